//! The page `report/peers.md`, rendered from the data file alone.

use super::data::{Data, Timing};
use super::{reading, wake};
use super::{Column, FSN, ISOSURFACE, LARGE, NAME, ONE, OUR_MC, OUR_MC_CLI, OUR_MC_CLI_SMALL_PAGES, OUR_SN, TWO, VTK_FE};
use crate::experiment::context::{Context, ExperimentError};
use crate::peers::Protocol;
use crate::report::markdown_table;

/// The page, from the data file alone.
pub(super) fn section(ctx: &Context) -> Result<String, ExperimentError> {
    let data: Data = ctx.read_data(NAME)?;
    Ok(page_body(&data))
}

pub(super) fn time_of<'a>(data: &'a Data, implementation: &str, protocol: Protocol, field: &str, n: usize) -> Option<&'a Timing> {
    data.timings.iter().find(|t| t.implementation == implementation && t.protocol == protocol && t.field == field && t.n == n)
}

/// "1 thread", "2 threads".
pub(super) fn threads_text(threads: usize) -> String {
    format!("{threads} thread{}", if threads == 1 { "" } else { "s" })
}

/// An implementation's label in the data: its name and threads.
pub(super) fn label(name: &str, threads: usize) -> String {
    format!("{name} ({})", threads_text(threads))
}

/// Ratio columns, one-shot; the first four also steady state.
pub(super) fn one_shot_ratios() -> Vec<Column> {
    let t = threads_text;
    vec![
        (format!("MC vs FlyingEdges, {}", t(ONE)), (OUR_MC, ONE), (VTK_FE, ONE)),
        (format!("MC vs FlyingEdges, {}", t(TWO)), (OUR_MC, TWO), (VTK_FE, TWO)),
        (format!("SN vs fast-surface-nets, {}", t(ONE)), (OUR_SN, ONE), (FSN, ONE)),
        (format!("SN ({}) vs fast-surface-nets", t(TWO)), (OUR_SN, TWO), (FSN, ONE)),
        ("MC vs skimage Lewiner".into(), (OUR_MC, ONE), ("skimage-lewiner", ONE)),
        ("MC vs vtkMarchingCubes".into(), (OUR_MC, ONE), ("vtk-marching-cubes", ONE)),
        ("MC vs libigl".into(), (OUR_MC, ONE), ("libigl", ONE)),
        ("MC vs isosurface crate".into(), (OUR_MC, ONE), (ISOSURFACE, ONE)),
    ]
}

/// The second thread's speed-up (one-shot): header, then two threads against one.
pub(super) fn scaling_columns() -> Vec<Column> {
    [("isolab MC", OUR_MC), ("isolab SN", OUR_SN), ("VTK FlyingEdges", VTK_FE)]
        .into_iter()
        .map(|(h, name)| (h.to_owned(), (name, TWO), (name, ONE)))
        .collect()
}

/// Our command line against the library (one-shot): header, then the library and the CLI.
pub(super) fn cli_columns() -> Vec<Column> {
    let t = threads_text;
    vec![
        (format!("CLI, {}", t(ONE)), (OUR_MC, ONE), (OUR_MC_CLI, ONE)),
        (format!("CLI, {}", t(TWO)), (OUR_MC, TWO), (OUR_MC_CLI, TWO)),
        (format!("CLI without huge pages, {}", t(ONE)), (OUR_MC, ONE), (OUR_MC_CLI_SMALL_PAGES, ONE)),
    ]
}

/// Peer median over ours with the range of the per-round ratios (runs of the same round paired),
/// or a dash.
pub(super) fn ratio(a: Option<&Timing>, b: Option<&Timing>) -> String {
    match (a, b) {
        (Some(a), Some(b)) => match crate::report::ratio_range(&a.ms.runs, &b.ms.runs) {
            Some((lo, hi)) if a.ms.runs.len() > 1 => format!("{:.2}× ({lo:.2}-{hi:.2})", b.ms.median / a.ms.median),
            _ => format!("{:.2}×", b.ms.median / a.ms.median),
        },
        _ => "-".into(),
    }
}

/// A ratio table over `grids` for `columns` under `protocol`.
pub(super) fn ratio_table(data: &Data, grids: &[(String, usize)], protocol: Protocol, columns: &[Column]) -> String {
    let body: Vec<Vec<String>> = grids
        .iter()
        .map(|(f, n)| {
            let t = |label: &str| time_of(data, label, protocol, f, *n);
            let mut row = vec![format!("{f} {n}³")];
            row.extend(columns.iter().map(|(_, ours, theirs)| ratio(t(&label(ours.0, ours.1)), t(&label(theirs.0, theirs.1)))));
            row
        })
        .collect();
    let mut header = vec!["grid"];
    header.extend(columns.iter().map(|c| c.0.as_str()));
    markdown_table(&header, &body)
}

/// Median (fastest-slowest) in ms, marked *wide* when its last round stayed wide.
pub(super) fn spread(t: &Timing) -> String {
    use crate::experiment::context::ms;
    format!("{} ({}-{}){}", ms(t.ms.median), ms(t.ms.min), ms(t.ms.max), if t.wide { " *wide*" } else { "" })
}

/// A times table under `protocol`: every implementation measured under it, median and spread.
pub(super) fn times_table(data: &Data, grids: &[(String, usize)], protocol: Protocol, with_floor: bool) -> String {
    let mut labels: Vec<&str> =
        data.timings.iter().filter(|t| t.protocol == protocol).map(|t| t.implementation.as_str()).collect();
    labels.sort_unstable();
    labels.dedup();
    let mut header = vec!["grid"];
    if with_floor {
        header.extend(["floor ms", "MC × floor"]);
    }
    header.extend(labels.iter().copied());
    let body: Vec<Vec<String>> = grids
        .iter()
        .map(|(f, n)| {
            let mut row = vec![format!("{f} {n}³")];
            if with_floor {
                let fl = data.floors.iter().find(|x| &x.field == f && x.n == *n);
                let floor = fl.map_or(f64::NAN, |x| x.read_ms + x.write_ms);
                let mc = time_of(data, &label(OUR_MC, TWO), protocol, f, *n).map_or(f64::NAN, |t| t.ms.median);
                row.extend([format!("{floor:.2}"), format!("{:.1}", mc / floor)]);
            }
            row.extend(labels.iter().map(|l| time_of(data, l, protocol, f, *n).map_or("-".into(), spread)));
            row
        })
        .collect();
    markdown_table(&header, &body)
}

pub(super) fn page_body(data: &Data) -> String {
    let mut md = String::from("## Against the peers, in one run (`peers`)\n\n");
    md.push_str(&format!(
        "Every implementation on the same sampled grid (built-in fields on their default domains, n samples a side), extraction \
         only, alternating, {} runs each per protocol{}, and again in rounds of as many for a cell whose last round's \
         slowest run took more than {}x its fastest, up to {} rounds (every run kept; a cell still that spread is marked \
         *wide*); Python peers read the very grid isolab sampled (`tests/reference/peers.py`). \
         **One-shot**: fresh output and fresh state every call, as a CLI user or a first library call meets it (ours: a new \
         extractor and a new `Extraction`; VTK: a new filter; `fast-surface-nets`: a new buffer), each freed when its call \
         returns (freeing it just before the next call instead would hand that call pages already touched). **Steady state**: the same \
         call repeated with what the implementation lets a caller keep (ours: extractor and output buffers; VTK: the same \
         filter, `Modified()` then `Update()`; `fast-surface-nets`: its buffer), after one unrecorded warm-up call. The slower \
         peers keep nothing between calls and run one-shot only. Ratios are peer median / our median under the same protocol \
         (above one means we are faster), with the range of the ratios of the runs of each round in brackets; the times tables give each median with its fastest and slowest run. \
         Our marching cubes makes no normals here, as VTK runs with ComputeNormalsOff and PyMCubes, libigl and the \
         `isosurface` crate make none; scikit-image's `marching_cubes` computes each vertex's normal and value inside its \
         timed call (it has no option to leave them out), so its times include work ours skips. Surface nets makes its usual normals, as `fast-surface-nets` does, and does not smooth, as no peer does. Threads: our one-thread runs are serial on the \
         experiment's own thread; {} Pool set-ups tried before (the caller as a pool thread, the caller left out, a new pool \
         per call, pinned threads) are described, with what they measured, in `experiments/src/peers/ours.rs`. Each one-shot output is freed when its call returns, so the allocator may hand the \
         next call pages already touched, on both sides; a process's very first call gets fresh pages from the kernel and costs \
         more. The criterion benches' one-shot follows this protocol (each output dropped right after its call: \
         `experiments/benches/protocol`). Peer versions: {}. Times are wall clock on a shared machine; compare ratios within this run.\n\n",
        data.repeats,
        data.idle_before_call_ms.map_or_else(String::new, |ms| format!(
            ", each call after {ms} ms idle (so that no call overlaps what the previous one, often in another process, still \
             does after it answered; every thread pool has then slept)"
        )),
        crate::report::WIDE,
        crate::report::MAX_ROUNDS,
        match data.two_threads_global {
            Some(true) => "our two-thread runs call from that thread on rayon's global pool of two threads, so the caller \
                           wakes both pool threads at once and sleeps until they are done, as VTK's caller does with its pool \
                           and as our command line does (`slabs::for_each_slab`).",
            Some(false) => "rayon's global pool did not have two threads, so our two-thread runs ran inside a two-thread pool \
                            of their own, where a working thread wakes the other.",
            None => "our two-thread runs shared one rayon pool whose threads were the experiment's thread and one more, so the \
                     calling thread worked while it woke the other.",
        },
        if data.versions.is_empty() {
            "none available".to_owned()
        } else {
            data.versions.iter().map(|(k, v)| format!("{k} {v}")).collect::<Vec<_>>().join(", ")
        }
    ));
    let mut grids: Vec<(String, usize)> = data.floors.iter().map(|f| (f.field.clone(), f.n)).collect();
    grids.dedup();
    md.push_str(&reading::reading(data, &grids));
    if !data.settings.is_empty() {
        let said: Vec<String> = data.settings.iter().map(|(label, s)| format!("{label}: {s}")).collect();
        md.push_str(&format!("Our extractors' settings in this run: {}.\n\n", said.join("; ")));
    }
    if !data.skipped.is_empty() {
        md.push_str("**Skipped peers:** ");
        md.push_str(&data.skipped.join("; "));
        md.push_str("\n\n");
    }
    md.push_str("### Ratios, one-shot (peer time / ours)\n\n");
    md.push_str(&ratio_table(data, &grids, Protocol::OneShot, &one_shot_ratios()));
    md.push_str("\n### Ratios, steady state (peer time / ours)\n\n");
    md.push_str(&ratio_table(data, &grids, Protocol::SteadyState, &one_shot_ratios()[..4]));
    md.push_str("\n### The second thread (one-shot: one-thread time / two-thread time)\n\n");
    md.push_str(&ratio_table(data, &grids, Protocol::OneShot, &scaling_columns()));
    md.push_str(&wake::section(&data.wake));
    md.push_str(&format!(
        "\n### Our command line against the library (one-shot: CLI time / library time)\n\n`isolab extract` run as a user runs it, \
         a new process a call on the very grid file the Python peers read, marching cubes without normals, its time the \
         `times_ms.extraction` it reports (`experiments/src/peers/cli.rs`); not at {}³, where the metrics every call computes \
         take longer than the rest of a grid's runs. A process's one extraction gets pages the kernel has never handed out; \
         the CLI therefore re-executes itself with huge pages for malloc (Linux with glibc; `ISOLAB_NO_HUGE_PAGES` turns that \
         off), and the last column shows it without them. Above one, the CLI is slower than the library's one-shot call in \
         this long-running process.\n\n",
        LARGE.0
    ));
    let cli_grids: Vec<(String, usize)> = grids.iter().filter(|(_, n)| *n != LARGE.0).cloned().collect();
    md.push_str(&ratio_table(data, &cli_grids, Protocol::OneShot, &cli_columns()));
    md.push_str("\n### Times, one-shot (ms: median (fastest-slowest)) and the memory floor\n\nThe floor is one streaming read of the grid plus one write of marching cubes' output bytes; `× floor` is our two-thread one-shot marching cubes over it. Triangle counts are in `data/peers.json`.\n\n");
    md.push_str(&times_table(data, &grids, Protocol::OneShot, true));
    md.push_str("\n### Times, steady state (ms: median (fastest-slowest))\n\n");
    md.push_str(&times_table(data, &grids, Protocol::SteadyState, false));
    md.push_str(
        "\n| | |\n|---|---|\n| ![sphere](figures/peers/time-sphere.png) | ![gyroid](figures/peers/time-gyroid.png) |\n| ![asteroid](figures/peers/time-asteroid.png) | ![terrain](figures/peers/time-terrain.png) |\n\n",
    );
    md.push_str("Regularised marching tetrahedra against `ferreus_rmt` is in the `costen_table` section (that peer samples the field itself, following the surface).\n");
    md
}
