//! The `python_users` page's targets, worded from its data: `isolab.marching_cubes` (all four
//! arrays) against VTK's zero-copy flying edges without normals and scikit-image's Lorensen on the
//! inputs users bring, on one and two threads, beside the floor (one read of the array, one write
//! of our output); and each call's peak memory above the input.

use super::{find, label, spread, Data, OURS};
use crate::report::{markdown_table, ms};

/// The peer our time must be `VTK_TARGET` times below.
pub(super) const VTK: &str = "VTK flying edges";
/// See [`VTK`].
pub(super) const VTK_TARGET: f64 = 1.5;
/// The peer our time must be `SKIMAGE_TARGET` times below (it has one thread to give: our two
/// threads are held to its one).
pub(super) const SKIMAGE: &str = "skimage lorensen";
/// See [`SKIMAGE`].
pub(super) const SKIMAGE_TARGET: f64 = 5.0;
/// The input whose peak memory is held to its output plus [`PEAK_SHARE`] of the input.
pub(super) const PEAK_INPUT: &str = "gyroid uint8";
/// See [`PEAK_INPUT`].
pub(super) const PEAK_SHARE: f64 = 0.25;

/// The inputs the targets are set on, (input, n), those run.
fn target_inputs(data: &Data) -> Vec<(String, usize)> {
    const SET: [(&str, Option<usize>); 4] =
        [("gyroid", Some(256)), ("gyroid", Some(512)), ("MNI152 T1", None), ("MNI152 T1 stored", None)];
    let mut out: Vec<(String, usize)> = super::inputs(data)
        .into_iter()
        .filter(|(input, n)| SET.iter().any(|(i, size)| i == input && size.is_none_or(|s| s == *n)))
        .collect();
    out.extend(super::inputs(data).into_iter().filter(|(input, _)| input == PEAK_INPUT));
    out
}

/// One input on some threads: our median and the peers', ms.
struct Cell {
    input: String,
    n: usize,
    threads: usize,
    ours: f64,
    vtk: Option<f64>,
    skimage: Option<f64>,
    /// The peers' ratios round by round, where their calls and ours ran in the same rounds.
    vtk_range: Option<(f64, f64)>,
    skimage_range: Option<(f64, f64)>,
    floor: Option<f64>,
}

impl Cell {
    fn vtk_ratio(&self) -> Option<f64> {
        self.vtk.map(|v| v / self.ours)
    }

    fn skimage_ratio(&self) -> Option<f64> {
        self.skimage.map(|s| s / self.ours)
    }
}

fn cells(data: &Data) -> Vec<Cell> {
    let mut out = Vec::new();
    for (input, n) in target_inputs(data) {
        for threads in super::THREADS {
            let Some(ours) = find(data, "default", OURS, &input, n, threads) else { continue };
            let median = |name: &str, t: usize| find(data, "default", name, &input, n, t).map(|r| spread(r).median);
            // Calls of one round are paired; scikit-image runs in the one-thread rounds only.
            let range = |name: &str| {
                let theirs = find(data, "default", name, &input, n, threads)?;
                crate::report::ratio_range(&ours.ms, &theirs.ms)
            };
            let floor = data.floors.iter().find(|f| f.input == input && f.n == n).map(|f| f.read_ms + f.write_ms);
            out.push(Cell {
                input: input.clone(),
                n,
                threads,
                ours: spread(ours).median,
                vtk: median(VTK, threads),
                skimage: median(SKIMAGE, super::THREADS[0]),
                vtk_range: range(VTK),
                skimage_range: if threads == super::THREADS[0] { range(SKIMAGE) } else { None },
                floor,
            });
        }
    }
    out
}

/// `" (1.40–1.80× round by round)"`, or empty without paired rounds.
fn round_by_round(range: Option<(f64, f64)>) -> String {
    range.map_or(String::new(), |(lo, hi)| format!(" ({lo:.2}–{hi:.2}× round by round)"))
}

fn verdict(ratio: Option<f64>, range: Option<(f64, f64)>, target: f64) -> String {
    match ratio {
        Some(r) if r >= target => format!("{r:.2}× (met){}", round_by_round(range)),
        Some(r) => format!("{r:.2}× (missed){}", round_by_round(range)),
        None => "not run".into(),
    }
}

/// The targets table: every input and thread count, ours against the two peers and the floor.
pub(super) fn table(data: &Data) -> String {
    let rows: Vec<Vec<String>> = cells(data)
        .iter()
        .map(|c| {
            vec![
                label(&c.input, c.n, data),
                c.threads.to_string(),
                ms(c.ours),
                c.vtk.map_or("–".into(), ms),
                verdict(c.vtk_ratio(), c.vtk_range, VTK_TARGET),
                c.skimage.map_or("–".into(), ms),
                verdict(c.skimage_ratio(), c.skimage_range, SKIMAGE_TARGET),
                c.floor.map_or("–".into(), ms),
                c.floor.map_or("–".into(), |f| format!("{:.1}", c.ours / f)),
            ]
        })
        .collect();
    let vtk_header = format!("{VTK} ÷ ours (target {VTK_TARGET}×)");
    let skimage_header = format!("{SKIMAGE} ÷ ours (target {SKIMAGE_TARGET}×)");
    markdown_table(
        &[
            "input",
            "threads",
            "ours, ms",
            "VTK flying edges, ms",
            &vtk_header,
            "skimage lorensen (one thread), ms",
            &skimage_header,
            "floor, ms",
            "ours ÷ floor",
        ],
        &rows,
    )
}

/// The sentence on the targets: how many cells met each, and the ones missed with their ratio.
pub(super) fn reading(data: &Data) -> Option<String> {
    let cells = cells(data);
    if cells.is_empty() {
        return None;
    }
    let missed = |ratio: fn(&Cell) -> Option<f64>, range: fn(&Cell) -> Option<(f64, f64)>, target: f64| {
        let mut met = 0;
        let mut missed = Vec::new();
        for c in &cells {
            match ratio(c) {
                Some(r) if r >= target => met += 1,
                Some(r) => missed.push(format!(
                    "{} on {} thread{} ({r:.2}×{})",
                    label(&c.input, c.n, data),
                    c.threads,
                    plural(c.threads),
                    range(c).map_or(String::new(), |(lo, hi)| format!(", {lo:.2}–{hi:.2}× round by round"))
                )),
                None => {}
            }
        }
        (met, missed)
    };
    let (vtk_met, vtk_missed) = missed(Cell::vtk_ratio, |c| c.vtk_range, VTK_TARGET);
    let (sk_met, sk_missed) = missed(Cell::skimage_ratio, |c| c.skimage_range, SKIMAGE_TARGET);
    let count = |f: fn(&Cell) -> Option<f64>| cells.iter().filter(|c| f(c).is_some()).count();
    Some(format!(
        "Targets: `isolab.marching_cubes` returning all four arrays at least {VTK_TARGET}× faster than {VTK} (no normals) in \
         {vtk_met} of {} cells (input and threads), missed in {}; at least {SKIMAGE_TARGET}× faster than {SKIMAGE} in {sk_met} \
         of {}, missed in {}.",
        count(Cell::vtk_ratio),
        crate::report::listed_or(&vtk_missed, "none"),
        count(Cell::skimage_ratio),
        crate::report::listed_or(&sk_missed, "none"),
    ))
}

fn plural(n: usize) -> &'static str {
    if n == 1 {
        ""
    } else {
        "s"
    }
}

fn mib(bytes: i64) -> String {
    format!("{:.1}", bytes as f64 / (1u64 << 20) as f64)
}

/// Each call's peak memory above the input, beside its output.
pub(super) fn peaks_table(data: &Data) -> String {
    let rows: Vec<Vec<String>> = data
        .peaks
        .iter()
        .map(|p| {
            vec![
                label(&p.input, p.n, data),
                p.implementation.clone(),
                mib(p.input_bytes),
                mib(p.output_bytes),
                mib(p.peak_bytes),
                format!("{:.0}%", 100.0 * (p.peak_bytes - p.output_bytes) as f64 / p.input_bytes as f64),
            ]
        })
        .collect();
    markdown_table(
        &[
            "input",
            "implementation",
            "input, MiB",
            "arrays returned, MiB",
            "peak above the input, MiB",
            "(peak − returned) ÷ input",
        ],
        &rows,
    )
}

/// The sentence on our peak on the uint8 volume against its target.
pub(super) fn peak_reading(data: &Data) -> Option<String> {
    let p = data.peaks.iter().find(|p| p.implementation == OURS && p.input == PEAK_INPUT)?;
    let beyond = (p.peak_bytes - p.output_bytes) as f64 / p.input_bytes as f64;
    Some(format!(
        "On {}, one call of ours peaks {} MiB above the input: the {} MiB it returns plus {:.0}% of the input's {} MiB (target: at \
         most {:.0}%, {}).",
        label(&p.input, p.n, data),
        mib(p.peak_bytes),
        mib(p.output_bytes),
        100.0 * beyond,
        mib(p.input_bytes),
        100.0 * PEAK_SHARE,
        if beyond <= PEAK_SHARE { "met" } else { "missed" }
    ))
}

#[cfg(test)]
mod tests {
    use super::super::data::{Floor, Peak};
    use super::super::tests::{data, row};
    use super::*;

    #[test]
    fn the_target_reading_counts_and_names_the_cells() {
        let mut d = data(vec![
            row(OURS, "gyroid", 256, 1, 100.0),
            row(OURS, "gyroid", 256, 2, 60.0),
            row(VTK, "gyroid", 256, 1, 160.0),
            row(VTK, "gyroid", 256, 2, 80.0),
            row(SKIMAGE, "gyroid", 256, 1, 600.0),
        ]);
        d.floors = vec![Floor {
            input: "gyroid".into(),
            n: 256,
            output_bytes: 0,
            read_ms: 5.0,
            write_ms: 5.0,
            first_touch_write_ms: 9.0,
        }];
        let r = reading(&d).unwrap();
        assert!(r.contains("faster than VTK flying edges (no normals) in 1 of 2 cells"), "{r}");
        assert!(r.contains("missed in gyroid 256 on 2 threads (1.33×, 1.33–1.33× round by round)"), "{r}");
        assert!(r.contains("faster than skimage lorensen in 2 of 2, missed in none"), "{r}");
        let t = table(&d);
        assert!(
            t.contains("| 1.60× (met) (1.60–1.60× round by round) |")
                && t.contains("| 1.33× (missed) (1.33–1.33× round by round) |")
                && t.contains("| 10.0 |"),
            "{t}"
        );
        // scikit-image ran in the one-thread rounds only: no range against our two-thread calls.
        assert!(t.contains("| 6.00× (met) (6.00–6.00× round by round) |") && t.contains("| 10.00× (met) |"), "{t}");
        d.rows[1].ms = vec![40.0];
        assert!(reading(&d).unwrap().contains("in 2 of 2 cells (input and threads), missed in none"));
    }

    #[test]
    fn the_peak_reading_holds_the_uint8_call_to_its_target() {
        let mut d = data(Vec::new());
        let mib = 1i64 << 20;
        d.peaks = vec![Peak {
            implementation: OURS.into(),
            input: PEAK_INPUT.into(),
            n: 512,
            peak_bytes: 220 * mib,
            output_bytes: 200 * mib,
            input_bytes: 128 * mib,
        }];
        let r = peak_reading(&d).unwrap();
        assert!(r.contains("plus 16% of the input's 128.0 MiB (target: at most 25%, met)"), "{r}");
        d.peaks[0].peak_bytes = 240 * mib;
        assert!(peak_reading(&d).unwrap().contains("31% of the input's 128.0 MiB (target: at most 25%, missed)"));
    }
}
