//! The page's opening reading, worded from the rows: the speed target met and missed, who leaves
//! no gap between labels, who is manifold everywhere, the fastest on each input, and what the
//! peers' outputs show that nobody explained.

use super::{against_target, find, inputs, spread, Data, Row, TARGET, TARGETS, THREADS};
use crate::report::listed as list;

/// Three to six lines that say what the rows show (empty without rows).
pub(super) fn reading(data: &Data) -> String {
    if data.rows.is_empty() {
        return String::new();
    }
    let inputs = inputs(data);
    let checked: Vec<&Row> = data.rows.iter().filter(|r| r.threads == THREADS[0]).collect();
    let implementations = crate::report::first_seen(checked.iter().map(|r| r.implementation.as_str()));
    let of = |name: &str| checked.iter().copied().filter(move |r| r.implementation == name).collect::<Vec<_>>();
    let mut lines = Vec::new();
    // The speed target.
    let (mut met, mut missed) = (Vec::new(), Vec::new());
    for input in &inputs {
        for (peer, ours) in TARGETS {
            let (Some(p), Some(o)) = (find(data, peer, input, 1), find(data, ours, input, 1)) else { continue };
            let r = spread(p).median / spread(o).median;
            let said = format!("{peer} on {input} ({}×)", against_target(r));
            if r >= TARGET {
                met.push(said);
            } else {
                missed.push(said);
            }
        }
    }
    if !met.is_empty() || !missed.is_empty() {
        lines.push(format!(
            "The speed target ({TARGET}× on one thread) is met against {} and missed against {}.",
            list(&met),
            list(&missed)
        ));
    }
    // Gaps and overlaps.
    let gap_free: Vec<&str> = implementations
        .iter()
        .copied()
        .filter(|&name| {
            let rows = of(name);
            !rows.is_empty() && rows.iter().all(|r| r.unmatched_interface_triangles == Some(0))
        })
        .collect();
    lines.push(format!("No unmatched interface triangle on any input: {}.", list(&gap_free)));
    // Manifold meshes.
    let manifold: Vec<&str> =
        implementations.iter().copied().filter(|&name| of(name).iter().all(|r| r.labels_manifold == Some(r.labels))).collect();
    let pinched: Vec<String> = implementations
        .iter()
        .filter(|name| !manifold.contains(name))
        .map(|name| {
            let most = of(name).iter().filter_map(|r| r.non_manifold).max().unwrap_or(0);
            format!("{name} (up to {most} non-manifold edges and vertices on one input)")
        })
        .collect();
    lines.push(format!("Every label's mesh manifold on every input: {}; not: {}.", list(&manifold), pinched.join(", ")));
    // The fastest on each input, one thread.
    let fastest: Vec<String> = inputs
        .iter()
        .filter_map(|input| {
            let best =
                checked.iter().filter(|r| &r.input == input).min_by(|a, b| spread(a).median.total_cmp(&spread(b).median))?;
            Some(format!("{input}: {} ({})", best.implementation, crate::report::ms(spread(best).median)))
        })
        .collect();
    lines.push(format!("Fastest on one thread, median ms: {}.", fastest.join("; ")));
    // Open meshes and zero-area triangles, which no implementation here explains.
    let defects: Vec<String> = checked
        .iter()
        .filter(|r| r.labels_closed.is_some_and(|c| c < r.labels) || r.degenerate_triangles.is_some_and(|d| d > 0))
        .map(|r| {
            format!(
                "{} on {} ({} of {} labels closed, {} zero-area triangles)",
                r.implementation,
                r.input,
                r.labels_closed.unwrap_or(0),
                r.labels,
                r.degenerate_triangles.unwrap_or(0)
            )
        })
        .collect();
    if !defects.is_empty() {
        lines.push(format!("Open label meshes or zero-area triangles, unexplained: {}.", defects.join("; ")));
    }
    format!("**Reading.** {}\n\n", lines.join(" "))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(implementation: &str, input: &str, ms: f64, unmatched: usize, manifold: usize, closed: usize) -> Row {
        Row {
            implementation: implementation.into(),
            input: input.into(),
            threads: 1,
            ms: vec![ms],
            core_ms: None,
            blocks: None,
            wide: None,
            labels: 3,
            triangles: 100,
            labels_closed: Some(closed),
            labels_manifold: Some(manifold),
            non_manifold: Some(if manifold == 3 { 0 } else { 7 }),
            degenerate_triangles: Some(0),
            min_angle_deg: None,
            mean_radius_ratio: None,
            interface_triangles: Some(50),
            unmatched_interface_triangles: Some(unmatched),
        }
    }

    fn data(rows: Vec<Row>) -> Data {
        Data {
            repeats: 1,
            versions: Default::default(),
            notes: Vec::new(),
            inputs: Vec::new(),
            rows,
            pictures: false,
            drawn: Vec::new(),
        }
    }

    #[test]
    fn the_reading_follows_the_rows() {
        let rows = vec![
            row("isolab surface-nets", "m", 100.0, 0, 2, 3),
            row("isolab surface-nets unsmoothed", "m", 40.0, 0, 2, 3),
            row("VTK SurfaceNets3D", "m", 200.0, 4, 1, 1),
            row("zmesh", "m", 50.0, 9, 3, 3),
        ];
        let r = reading(&data(rows.clone()));
        assert!(r.contains("met against VTK SurfaceNets3D on m (2.00×) and missed against zmesh on m (1.25×)"), "{r}");
        assert!(
            r.contains("No unmatched interface triangle on any input: isolab surface-nets, isolab surface-nets unsmoothed."),
            "{r}"
        );
        assert!(r.contains("manifold on every input: zmesh; not: isolab surface-nets (up to 7"), "{r}");
        assert!(r.contains("m: isolab surface-nets unsmoothed (40"), "{r}");
        assert!(r.contains("unexplained: VTK SurfaceNets3D on m (1 of 3 labels closed"), "{r}");
        // Faster zmesh, slower ours: the verdicts turn.
        let mut turned = rows;
        turned[1].ms = vec![20.0];
        turned[2].ms = vec![120.0];
        let r = reading(&data(turned));
        assert!(r.contains("met against zmesh on m (2.50×) and missed against VTK SurfaceNets3D on m (1.20×)"), "{r}");
        assert_eq!(reading(&data(Vec::new())), "");
        // A miss that two decimals would round up to the target shows a third.
        assert_eq!(
            (against_target(1.497), against_target(1.5), against_target(1.42)),
            ("1.497".into(), "1.50".into(), "1.42".into())
        );
    }

    #[test]
    fn the_target_sentences_give_the_meshing_step_where_both_have_one() {
        let mut rows = vec![
            row("isolab surface-nets", "m", 100.0, 0, 2, 3),
            row("isolab surface-nets unsmoothed", "m", 40.0, 0, 2, 3),
            row("VTK SurfaceNets3D", "m", 120.0, 4, 1, 1),
            row("zmesh", "m", 80.0, 9, 3, 3),
        ];
        rows[0].core_ms = Some(vec![50.0, 60.0, 70.0]);
        rows[2].core_ms = Some(vec![90.0]);
        let s = super::super::page::target_sentences(&data(rows.clone())).join(" ");
        assert!(
            s.contains(
                "VTK SurfaceNets3D takes 1.20× (1.20–1.20× round by round) the time of `isolab surface-nets` (missed), its meshing step alone 1.50× ours;"
            ),
            "{s}"
        );
        // zmesh's row has a meshing step, ours unsmoothed none: the verdict alone.
        assert!(
            s.contains("zmesh takes 2.00× (2.00–2.00× round by round) the time of `isolab surface-nets unsmoothed` (met)."),
            "{s}"
        );
        // Round by round: the calls of one round paired, both ends from the same rounds.
        let mut paired = rows.clone();
        paired[1].ms = vec![40.0, 50.0, 30.0];
        paired[3].ms = vec![80.0, 75.0, 90.0];
        let s = super::super::page::target_sentences(&data(paired)).join(" ");
        assert!(s.contains("zmesh takes 2.00× (1.50–3.00× round by round)"), "{s}");
        rows[0].core_ms = None;
        let s = super::super::page::target_sentences(&data(rows)).join(" ");
        assert!(!s.contains("meshing step"), "{s}");
    }
}
