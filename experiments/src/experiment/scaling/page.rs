//! The page `report/scaling.md`, rendered from the data file alone.

use super::data::{Data, Row};
use super::{
    CELLS_SLOPE_FROM, MAX_REPEATS, NAME, SECOND_THREAD_EXTRACTORS, SECOND_THREAD_GRID, SECOND_THREAD_TARGET, SINGLE_RUN_FROM,
    SLOPE_FROM, SURFACE_SLOPE_FROM,
};
use crate::experiment::context::{Context, ExperimentError};
use crate::report::{log_slope, markdown_table};

/// The page, from the data file alone.
pub(super) fn section(ctx: &Context) -> Result<String, ExperimentError> {
    let data: Data = ctx.read_data(NAME)?;
    Ok(page_body(ctx, &data))
}

pub(super) fn algorithms(data: &Data) -> Vec<String> {
    let mut names: Vec<String> = Vec::new();
    for r in &data.rows {
        if !names.contains(&r.algorithm) {
            names.push(r.algorithm.clone());
        }
    }
    names
}

/// The second thread's gain for the extractors the issue sets a target for, both protocols.
pub(super) fn second_thread(data: &Data) -> String {
    let mut parts = Vec::new();
    for name in SECOND_THREAD_EXTRACTORS {
        let Some(r) = data.rows.iter().find(|r| r.algorithm == name && r.n == SECOND_THREAD_GRID) else { continue };
        let gain = |ms: &[f64]| (ms.len() > 1 && ms[1] > 0.0).then(|| ms[0] / ms[1]);
        let show = |g: Option<f64>| {
            g.map_or("-".into(), |g| format!("{g:.2}×{}", if g >= SECOND_THREAD_TARGET { "" } else { " (missed)" }))
        };
        parts.push(format!("`{name}` one-shot {}, steady state {}", show(gain(&r.one_shot_ms)), show(gain(&r.ms))));
    }
    if parts.is_empty() {
        return String::new();
    }
    format!("The second thread at {SECOND_THREAD_GRID}³ (target: at least {SECOND_THREAD_TARGET}×): {}.", parts.join("; "))
}

/// The slope of log time against log cells of `name` on thread count number `k` (steady state).
pub(super) fn slope(data: &Data, name: &str, k: usize) -> Option<f64> {
    let pts: Vec<(f64, f64)> =
        data.rows.iter().filter(|r| r.algorithm == name && r.n >= SLOPE_FROM).map(|r| (r.cells as f64, r.ms[k])).collect();
    log_slope(&pts)
}

/// The page's opening reading: what drives each extractor's time (its one-thread slope), the
/// fastest on the largest grid, and the second thread's target.
pub(super) fn reading(data: &Data) -> String {
    let names = algorithms(data);
    if names.is_empty() {
        return String::new();
    }
    let mut bands: [Vec<String>; 3] = Default::default();
    for name in &names {
        let Some(s) = slope(data, name, 0) else { continue };
        let band = if s >= CELLS_SLOPE_FROM {
            0
        } else if s >= SURFACE_SLOPE_FROM {
            1
        } else {
            2
        };
        bands[band].push(format!("{name} {s:.2}"));
    }
    let mut lines = vec![format!(
        "One-thread slopes of log time against log cells: with the cells (from {CELLS_SLOPE_FROM}): {}; with the surface \
         ({SURFACE_SLOPE_FROM} to {CELLS_SLOPE_FROM}): {}; hardly driven by the grid: {}.",
        crate::report::listed(&bands[0]),
        crate::report::listed(&bands[1]),
        crate::report::listed(&bands[2])
    )];
    let largest = data.rows.iter().map(|r| r.n).max().unwrap_or(0);
    for (k, t) in data.threads.iter().enumerate() {
        let mut at: Vec<&Row> = data.rows.iter().filter(|r| r.n == largest && r.ms.len() > k).collect();
        at.sort_by(|a, b| a.ms[k].total_cmp(&b.ms[k]));
        if let (Some(first), Some(last)) = (at.first(), at.last()) {
            lines.push(format!(
                "At {largest}³ on {t} thread{}, steady state: fastest {} ({} ms), slowest {} ({} ms).",
                if *t == 1 { "" } else { "s" },
                first.algorithm,
                crate::experiment::context::ms(first.ms[k]),
                last.algorithm,
                crate::experiment::context::ms(last.ms[k])
            ));
        }
    }
    let second = second_thread(data);
    if !second.is_empty() {
        lines.push(second);
    }
    format!("**Reading.** {}\n\n", lines.join(" "))
}

pub(super) fn mib(bytes: usize) -> String {
    format!("{:.1}", bytes as f64 / (1024.0 * 1024.0))
}

pub(super) fn page_body(ctx: &Context, data: &Data) -> String {
    let threads = &data.threads;
    let mut md = String::from("## Scaling with the grid and the threads (`scaling`)\n\n");
    md.push_str(&format!(
        "Every extractor on the built-in `{}` sampled on cubic grids of n³ samples (extraction only, the samples shared), on {} \
         threads{}, alternating; medians of up to {MAX_REPEATS} runs per protocol (one from {SINGLE_RUN_FROM}³ on); slopes and plots use \
         the steady-state medians. *× floor* is the one-thread \
         time over this machine's memory floor for the grid and that extractor's output (one streaming read of the samples plus \
         one write of the output bytes, measured in the same run). *Peak* is the heap the extraction added at its highest, \
         counted by a global allocator on a fresh extractor and output; *grid + output* is the least any extractor must hold \
         (the samples are already there, so a ratio near one means the output is nearly all it keeps). Times are wall clock on a \
         shared machine.\n\n",
        data.field,
        threads.iter().map(|t| t.to_string()).collect::<Vec<_>>().join(" and "),
        match data.global_pool_threads {
            Some(g) => format!(
                " ({}{g} from the experiment's own thread on rayon's global pool of {g}, so the slab phases wake every pool thread \
                 at once, as the command line and `peers` call)",
                threads.iter().filter(|&&t| t != g).map(|t| format!("{t} inside a rayon pool of {t}; ")).collect::<String>()
            ),
            None => " (rayon limited to each count by a pool of that size)".to_owned(),
        },
    ));
    md.push_str(&reading(data));
    md.push_str(&crate::experiment::context::options_as_run(&data.settings));
    // Slopes.
    md.push_str(&format!("### Slopes of log time against log cells ({SLOPE_FROM}³ and up)\n\n"));
    let mut slopes = Vec::new();
    for name in algorithms(data) {
        let mut row = vec![name.clone()];
        for k in 0..threads.len() {
            row.push(slope(data, &name, k).map_or("-".into(), |s| format!("{s:.2}")));
        }
        let largest = data.rows.iter().filter(|r| r.algorithm == name).map(|r| r.n).max().unwrap_or(0);
        row.push(format!("{largest}³"));
        slopes.push(row);
    }
    let mut header: Vec<String> = vec!["extractor".into()];
    header.extend(threads.iter().map(|t| format!("slope, {t} thread{}", if *t == 1 { "" } else { "s" })));
    header.push("largest grid".into());
    let header_refs: Vec<&str> = header.iter().map(|s| s.as_str()).collect();
    md.push_str(&markdown_table(&header_refs, &slopes));
    md.push_str(
        "\nA slope near 1 means the time grows with the cells (the scan over every cell dominates), near 2/3 with the surface \
         (the sphere's area grows as cells^(2/3)), lower still a cost the grid hardly drives (`bcc-sculpt`'s lattice has a fixed number of cells along the \
         surface's longest side; a finer grid only refines the marching cubes surface it sculpts to).\n\n",
    );
    for &t in threads {
        md.push_str(&format!(
            "![time against cells, {t} thread{}]({})\n\n",
            if t == 1 { "" } else { "s" },
            ctx.link(&ctx.report_dir.join("figures").join(NAME).join(format!("time-{t}-threads.png")))
        ));
    }
    md.push_str("### Every run\n\n");
    md.push_str(
        "Median (fastest-slowest) per protocol. **One-shot**: a new extractor and a new output every call, as a CLI user or a \
         first library call meets it. **Steady state**: the same extractor and output kept between calls (buffers reused), as \
         a game re-meshing a chunk meets it. The speed-up is one-thread time over two-thread time within a protocol.\n\n",
    );
    let cell = |m: f64, s: Option<&[f64; 2]>| match s {
        Some([lo, hi]) => format!(
            "{} ({}-{})",
            crate::experiment::context::ms(m),
            crate::experiment::context::ms(*lo),
            crate::experiment::context::ms(*hi)
        ),
        None => crate::experiment::context::ms(m),
    };
    let speed_up = |ms: &[f64]| if ms.len() > 1 && ms[1] > 0.0 { format!("{:.2}×", ms[0] / ms[1]) } else { "-".into() };
    let body: Vec<Vec<String>> = data
        .rows
        .iter()
        .map(|r| {
            let mut row = vec![r.algorithm.clone(), format!("{}³", r.n)];
            row.extend(
                (0..threads.len()).map(|k| r.one_shot_ms.get(k).map_or("-".into(), |&m| cell(m, r.one_shot_spread.get(k)))),
            );
            row.extend(r.ms.iter().enumerate().map(|(k, &m)| cell(m, r.spread.get(k))));
            row.push(speed_up(&r.one_shot_ms));
            row.push(speed_up(&r.ms));
            row.push(format!("{:.3}", r.floor_ms));
            row.push(format!("{:.1}", r.ms[0] / r.floor_ms));
            row.push(if r.tetrahedra > 0 { format!("{} tets", r.tetrahedra) } else { r.triangles.to_string() });
            row.push(format!("{} + {}", mib(r.grid_bytes), mib(r.output_bytes)));
            row.push(r.peak_bytes.map_or("-".into(), mib));
            row.push(r.peak_bytes.map_or("-".into(), |p| {
                format!("{:.2}", (r.grid_bytes + p) as f64 / (r.grid_bytes + r.output_bytes).max(1) as f64)
            }));
            row
        })
        .collect();
    let plural = |t: &usize| if *t == 1 { "" } else { "s" };
    let mut header: Vec<String> = vec!["extractor".into(), "grid".into()];
    let first = threads.first().copied().unwrap_or(1);
    header.extend(threads.iter().map(|t| format!("one-shot ms, {t} thread{}", plural(t))));
    header.extend(threads.iter().map(|t| format!("steady ms, {t} thread{}", plural(t))));
    header.extend(
        [
            "speed-up, one-shot",
            "speed-up, steady",
            "floor ms",
            &format!("× floor (steady, {first} thread{})", plural(&first)),
            "triangles",
            "grid + output MiB",
            "peak MiB",
            "(grid + peak) / (grid + output)",
        ]
        .map(String::from),
    );
    let header_refs: Vec<&str> = header.iter().map(|s| s.as_str()).collect();
    md.push_str(&markdown_table(&header_refs, &body));
    if !data.skipped.is_empty() {
        md.push_str("\n**Not run:** ");
        md.push_str(&data.skipped.join("; "));
        md.push('\n');
    }
    md
}
