//! The page's opening reading, worded from the timings: for each ratio column, the median ratio
//! over the grids, its range and the grids where the peer is faster; what the second thread gives
//! each implementation.

use super::{label, one_shot_ratios, scaling_columns, time_of, Column, Data};
use crate::peers::Protocol;
use crate::report::{listed_or, Spread};

/// A ratio column over `grids`: the median, fastest and slowest ratio (peer time over ours) and
/// the grids where it is below one, or `None` where no grid has both.
fn column(data: &Data, grids: &[(String, usize)], protocol: Protocol, c: &Column) -> Option<(Spread, Vec<String>)> {
    let (_, ours, theirs) = c;
    let mut ratios = Vec::new();
    let mut below = Vec::new();
    for (f, n) in grids {
        let t = |(name, threads): (&str, usize)| time_of(data, &label(name, threads), protocol, f, *n);
        let (Some(o), Some(p)) = (t(*ours), t(*theirs)) else { continue };
        let r = p.ms.median / o.ms.median;
        if r < 1.0 {
            below.push(format!("{f} {n}³"));
        }
        ratios.push(r);
    }
    (!ratios.is_empty()).then(|| (Spread::of(ratios), below))
}

fn said(s: &Spread) -> String {
    format!("{:.2}× ({:.2}–{:.2})", s.median, s.min, s.max)
}

/// Three to six lines: the fast peers' columns one-shot and steady, the slow peers' medians, and
/// the second thread (empty without timings).
pub(super) fn reading(data: &Data, grids: &[(String, usize)]) -> String {
    let columns = one_shot_ratios();
    let mut lines = Vec::new();
    for (protocol, name) in [(Protocol::OneShot, "one-shot"), (Protocol::SteadyState, "steady state")] {
        let parts: Vec<String> = columns[..4]
            .iter()
            .filter_map(|c| {
                let (s, below) = column(data, grids, protocol, c)?;
                Some(format!("{} {} (the peer faster on {})", c.0, said(&s), listed_or(&below, "no grid")))
            })
            .collect();
        if !parts.is_empty() {
            lines.push(format!("Peer time over ours, median (range) over the grids, {name}: {}.", parts.join("; ")));
        }
    }
    let slow: Vec<String> = columns[4..]
        .iter()
        .filter_map(|c| column(data, grids, Protocol::OneShot, c).map(|(s, _)| format!("{} {}", c.0, said(&s))))
        .collect();
    if !slow.is_empty() {
        lines.push(format!("The other peers, one-shot, one thread: {}.", slow.join("; ")));
    }
    let second: Vec<String> = scaling_columns()
        .iter()
        .filter_map(|c| {
            let (s, below) = column(data, grids, Protocol::OneShot, c)?;
            Some(format!("{} {} (slower with it on {})", c.0, said(&s), listed_or(&below, "no grid")))
        })
        .collect();
    if !second.is_empty() {
        lines.push(format!(
            "The second thread, one-thread time over two-thread time: {} (the pool's wake-up times are measured below).",
            second.join("; ")
        ));
    }
    if lines.is_empty() {
        return String::new();
    }
    format!("**Reading.** {}\n\n", lines.join(" "))
}

#[cfg(test)]
mod tests {
    use super::super::{Timing, OUR_MC, TWO, VTK_FE};
    use super::*;

    fn timing(implementation: &str, threads: usize, field: &str, ms: f64) -> Timing {
        Timing {
            implementation: label(implementation, threads),
            field: field.into(),
            n: 64,
            protocol: Protocol::OneShot,
            ms: Spread::of(vec![ms]),
            wide: false,
            vertices: 0,
            triangles: 0,
        }
    }

    #[test]
    fn the_reading_follows_the_timings() {
        let grids = vec![("a".to_owned(), 64), ("b".to_owned(), 64), ("c".to_owned(), 64)];
        let mut data: Data =
            serde_json::from_str(r#"{"repeats": 1, "timings": [], "floors": [], "versions": {}, "skipped": []}"#).unwrap();
        assert_eq!(reading(&data, &grids), "");
        // Ours 10 ms on one thread; VTK 30, 20 and 5: ratios 3, 2 and 0.5.
        for (f, vtk) in [("a", 30.0), ("b", 20.0), ("c", 5.0)] {
            data.timings.push(timing(OUR_MC, 1, f, 10.0));
            data.timings.push(timing(VTK_FE, 1, f, vtk));
            data.timings.push(timing(OUR_MC, TWO, f, 20.0));
        }
        let r = reading(&data, &grids);
        assert!(r.contains("MC vs FlyingEdges, 1 thread 2.00× (0.50–3.00) (the peer faster on c 64³)"), "{r}");
        // Our second thread: 10 ms alone, 20 ms with it: slower on every grid.
        assert!(r.contains("isolab MC 0.50× (0.50–0.50) (slower with it on a 64³, b 64³, c 64³)"), "{r}");
        assert!(!r.contains("steady state:"), "no steady-state timings, no steady-state line: {r}");
    }
}
