//! `peers`: our extractors and the peer implementations on the same sampled grids in one run,
//! alternating, extraction only (sampling excluded for everyone), under both protocols of
//! [`crate::peers::Protocol`]:
//! - *one-shot*: fresh output and fresh state per call (ours: a new extractor and
//!   `Extraction::default()`; VTK: a new filter; `fast-surface-nets`: a new buffer);
//! - *steady state*: the same call repeated with what the implementation lets a caller keep (ours:
//!   extractor and output; VTK: the filter, `Modified()` + `Update()`; `fast-surface-nets`: its
//!   buffer), after one unrecorded warm-up call.
//!
//! Peers ([`crate::peers`]): in process `fast-surface-nets` and the `isosurface` crate's marching
//! cubes; through `tests/reference/peers.py` (reading the very grid we sampled) VTK's
//! vtkFlyingEdges3D on one and two threads, vtkMarchingCubes, scikit-image (Lorensen, Lewiner),
//! PyMCubes, libigl. The slow peers keep no state, so they run one-shot only. A peer that is not
//! installed is skipped with a note in the report. Medians of `repeats` alternating runs and
//! their spread (fastest, slowest); ratios compare like with like (same protocol, same threads).
//!
//! Also measured: the memory floor (one streaming read of the grid plus writing the output's
//! bytes) and our two-thread marching cubes as a multiple of it; time against cells on a log-log
//! plot.

use super::context::{Context, Experiment, ExperimentError};
use crate::figures::plot::{self, Scale, Series, Style, XyPlot};
use crate::peers::cli::Cli;
use crate::peers::fast_surface_nets::FastSurfaceNets;
use crate::peers::isosurface_crate::IsosurfaceCrate;
use crate::peers::ours::Ours;
use crate::peers::python::{PythonPeer, PythonServer};
use crate::peers::{Job, Peer, PeerError, Protocol};
use crate::report::{markdown_table, median, Spread};
use isolab_algorithms::{fields, Grid, Samples};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Duration;
use wake::Wake;

mod reading;
mod wake;

/// The experiment.
pub struct Peers;

const NAME: &str = "peers";
const FIELDS: [&str; 4] = ["sphere", "gyroid", "asteroid", "terrain"];
const SIZES: [usize; 3] = [64, 128, 256];
/// 512^3 for the fast implementations only, on every field (the slow peers take seconds a run).
const LARGE: (usize, [&str; 4]) = (512, FIELDS);
const SLOW_PEERS: [&str; 5] = ["vtk-marching-cubes", "skimage-lorensen", "skimage-lewiner", "pymcubes", "libigl"];
const PROTOCOLS: [Protocol; 2] = [Protocol::OneShot, Protocol::SteadyState];

/// One implementation on one grid under one protocol.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Timing {
    /// Implementation label, threads included.
    pub implementation: String,
    /// Field.
    pub field: String,
    /// Samples along each side.
    pub n: usize,
    /// How it was timed.
    pub protocol: Protocol,
    /// Extraction time, ms: median and spread.
    pub ms: Spread,
    /// Vertices of its output.
    pub vertices: usize,
    /// Triangles.
    pub triangles: usize,
}

/// The memory floor of one grid.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Floor {
    /// Field.
    pub field: String,
    /// Samples along each side.
    pub n: usize,
    /// One streaming read of every sample, ms (median).
    pub read_ms: f64,
    /// Writing marching cubes' output bytes once, ms (median).
    pub write_ms: f64,
}

#[derive(Serialize, Deserialize)]
struct Data {
    repeats: usize,
    timings: Vec<Timing>,
    floors: Vec<Floor>,
    /// Peer package versions, or why a peer was skipped.
    versions: BTreeMap<String, String>,
    skipped: Vec<String>,
    /// How long our two-thread pool's second thread takes to start work after idling.
    #[serde(default)]
    wake: Vec<Wake>,
    /// Whether our two-thread runs called from the experiment's thread on rayon's global pool of
    /// two threads (absent from runs before they did; they used a pool counting the caller).
    #[serde(default)]
    two_threads_global: Option<bool>,
    /// Idle before each recorded call, ms (absent from runs before there was one).
    #[serde(default)]
    idle_before_call_ms: Option<u64>,
    /// Our extractors' settings as they ran (absent from runs before they were recorded).
    #[serde(default)]
    settings: Vec<(String, String)>,
}

/// One implementation as the run alternates them: its label, the peer, its threads, and whether
/// it runs under both protocols (else one-shot only).
struct Entry {
    label: String,
    peer: Box<dyn Peer>,
    threads: usize,
    steady: bool,
    slow: bool,
}

/// Our two extractors and the options they run with here: no normals for marching cubes, as VTK
/// runs with ComputeNormalsOff and the other marching cubes peers make none; surface nets without
/// smoothing, as `fast-surface-nets` and the other peers do not smooth (its usual normals kept).
const MC: &str = "marching-cubes";
const MC_OPTIONS: &[(&str, &str)] = &[("normals", "none")];
const SN: &str = "surface-nets";
const SN_OPTIONS: &[(&str, &str)] = &[("smoothing", "none")];

/// Our extractors' settings in words, as the run builds them.
fn our_settings() -> Vec<(String, String)> {
    [(OUR_MC, MC, MC_OPTIONS), (OUR_SN, SN, SN_OPTIONS)]
        .iter()
        .map(|(label, name, options)| ((*label).to_owned(), Ours::new(name, options).settings()))
        .collect()
}

/// Every implementation the run alternates, Python peers when the server started.
fn entries(python: Option<&std::rc::Rc<std::cell::RefCell<PythonServer>>>, root: &Path) -> Vec<Entry> {
    let entry = |name: &str, peer: Box<dyn Peer>, threads: usize, steady: bool, slow: bool| Entry {
        label: label(name, threads),
        peer,
        threads,
        steady,
        slow,
    };
    let mc = || Box::new(Ours::new(MC, MC_OPTIONS));
    let sn = || Box::new(Ours::new(SN, SN_OPTIONS));
    let mut list = vec![
        entry(OUR_MC, mc(), TWO, true, false),
        entry(OUR_MC, mc(), ONE, true, false),
        entry(OUR_SN, sn(), TWO, true, false),
        entry(OUR_SN, sn(), ONE, true, false),
        entry(FSN, Box::<FastSurfaceNets>::default(), ONE, true, false),
        entry(ISOSURFACE, Box::<IsosurfaceCrate>::default(), ONE, true, false),
    ];
    // Our command line as a user runs it, one process a call: one-shot only, and not at 512³,
    // where the metrics every `isolab extract` computes take longer than the rest of a grid's runs.
    let binary = crate::peers::cli::build(root);
    let cli = |huge_pages: bool| Box::new(Cli::new(binary.clone(), "marching-cubes", &[("normals", "none")], huge_pages));
    list.push(entry(OUR_MC_CLI, cli(true), ONE, false, true));
    list.push(entry(OUR_MC_CLI, cli(true), TWO, false, true));
    list.push(entry(OUR_MC_CLI_SMALL_PAGES, cli(false), ONE, false, true));
    if let Some(server) = python {
        for threads in [ONE, TWO] {
            list.push(entry(VTK_FE, Box::new(PythonPeer::new(server, "vtk-flying-edges")), threads, true, false));
        }
        for name in SLOW_PEERS {
            list.push(entry(name, Box::new(PythonPeer::new(server, name)), ONE, false, true));
        }
    }
    list
}

impl Experiment for Peers {
    fn name(&self) -> &'static str {
        NAME
    }

    fn question(&self) -> &'static str {
        "How fast are our extractors against the peer libraries on the same grids, one-shot and steady state?"
    }

    fn run(&self, ctx: &Context) -> Result<(), ExperimentError> {
        let root = ctx.report_dir.join("..");
        let repeats = ctx.repeats.max(1);
        let mut versions = BTreeMap::new();
        let mut skipped = Vec::new();
        let server = match PythonServer::start(&root) {
            Ok((server, hello)) => {
                for (k, v) in hello["available"].as_object().into_iter().flatten() {
                    versions.insert(k.clone(), v.as_str().unwrap_or("installed").to_owned());
                }
                for (k, v) in hello["errors"].as_object().into_iter().flatten() {
                    skipped.push(format!("{k}: {v}"));
                }
                Some(server)
            }
            Err(e) => {
                skipped.push(format!("all Python peers: {e}"));
                None
            }
        };
        // Before the grids, on the pool our two-thread runs use.
        let wake = wake::measure()?;
        let mut entries = entries(server.as_ref(), &root);
        let tmp = std::env::temp_dir().join(format!("isolab-peers-{}", std::process::id()));
        std::fs::create_dir_all(&tmp).map_err(|source| isolab_io::IoError::Write { path: tmp.clone(), source })?;
        let mut grids: Vec<(&str, usize)> = FIELDS.iter().flat_map(|&f| SIZES.iter().map(move |&n| (f, n))).collect();
        grids.extend(LARGE.1.iter().map(|&f| (f, LARGE.0)));
        let bar = ctx.bar(NAME, grids.len() as u64);
        let mut timings = Vec::new();
        let mut floors = Vec::new();
        let note = |skipped: &mut Vec<String>, e: PeerError, field: &str| {
            // A failure can depend on the grid (the isosurface crate meshes n³ grids only): name the field.
            let line = match &e {
                PeerError::Failed { .. } => format!("{e} ({field})"),
                PeerError::Unsupported { .. } => e.to_string(),
            };
            if !skipped.contains(&line) {
                skipped.push(line);
            }
        };
        for (field_name, n) in grids {
            let field = fields::builtin(field_name, Default::default())?;
            let grid = Grid::covering(&field.domain(), n)?;
            let samples = Samples::sample_cubic(field, grid, 0.0)?;
            // A file per grid: the Python side caches the grid it read last by path.
            let raw: PathBuf = tmp.join(format!("{field_name}-{n}.raw"));
            isolab_io::write_samples(&raw, &samples, None)?;
            let large = n == LARGE.0;
            let mut runs: BTreeMap<(usize, Protocol), (Vec<f64>, usize, usize)> = BTreeMap::new();
            let mut failed = vec![false; entries.len()];
            let (mut reads, mut writes) = (Vec::new(), Vec::new());
            // One unrecorded steady-state call each, so the recorded ones find their state kept.
            for (k, e) in entries.iter_mut().enumerate() {
                if e.steady && !(large && e.slow) {
                    let job = Job::Grid { samples: &samples, file: &raw, threads: e.threads };
                    if let Err(err) = e.peer.run(&job, Protocol::SteadyState) {
                        failed[k] = true;
                        note(&mut skipped, err, field_name);
                    }
                }
            }
            for _ in 0..repeats {
                for protocol in PROTOCOLS {
                    for (k, e) in entries.iter_mut().enumerate() {
                        if failed[k] || (large && e.slow) || (protocol == Protocol::SteadyState && !e.steady) {
                            continue;
                        }
                        let job = Job::Grid { samples: &samples, file: &raw, threads: e.threads };
                        std::thread::sleep(IDLE_BEFORE_CALL);
                        match e.peer.run(&job, protocol) {
                            Ok(run) => {
                                let slot = runs.entry((k, protocol)).or_insert_with(|| (Vec::new(), run.vertices, run.triangles));
                                slot.0.push(run.time.as_secs_f64() * 1e3);
                                if k == 0 && protocol == Protocol::OneShot {
                                    let (r, w) = crate::memory::floor(samples.values(), run.vertices * 12 + run.triangles * 12);
                                    reads.push(r);
                                    writes.push(w);
                                }
                            }
                            Err(err) => {
                                failed[k] = true;
                                note(&mut skipped, err, field_name);
                            }
                        }
                    }
                }
            }
            for ((k, protocol), (times, vertices, triangles)) in runs {
                timings.push(Timing {
                    implementation: entries[k].label.clone(),
                    field: field_name.into(),
                    n,
                    protocol,
                    ms: Spread::of(times),
                    vertices,
                    triangles,
                });
            }
            let _ = std::fs::remove_file(&raw);
            floors.push(Floor {
                field: field_name.into(),
                n,
                read_ms: median(reads).as_secs_f64() * 1e3,
                write_ms: median(writes).as_secs_f64() * 1e3,
            });
            bar.inc(1);
        }
        drop(entries);
        drop(server);
        let _ = std::fs::remove_dir_all(&tmp);
        bar.finish();
        let two_threads_global = Some(crate::peers::ours::caller_outside(TWO));
        let idle_before_call_ms = Some(IDLE_BEFORE_CALL.as_millis() as u64);
        let data = Data {
            repeats,
            timings,
            floors,
            versions,
            skipped,
            wake,
            two_threads_global,
            idle_before_call_ms,
            settings: our_settings(),
        };
        charts(&ctx.figure_dir(NAME)?, &data)?;
        ctx.write_data(NAME, &data)
    }

    fn section(&self, ctx: &Context) -> Result<String, ExperimentError> {
        let data: Data = ctx.read_data(NAME)?;
        Ok(section(&data))
    }
}

fn time_of<'a>(data: &'a Data, implementation: &str, protocol: Protocol, field: &str, n: usize) -> Option<&'a Timing> {
    data.timings.iter().find(|t| t.implementation == implementation && t.protocol == protocol && t.field == field && t.n == n)
}

fn charts(dir: &Path, data: &Data) -> Result<(), ExperimentError> {
    for field in FIELDS {
        // The CLI rows have a table of their own; drawn here they only crowd the legend.
        let one_shot = || {
            data.timings
                .iter()
                .filter(|t| t.field == field && t.protocol == Protocol::OneShot && !t.implementation.contains(CLI_MARK))
        };
        let mut labels: Vec<&str> = one_shot().map(|t| t.implementation.as_str()).collect();
        labels.sort_unstable();
        labels.dedup();
        let series = labels
            .iter()
            .enumerate()
            .map(|(k, label)| Series {
                label: (*label).to_owned(),
                color: crate::figures::series_color(k),
                points: one_shot()
                    .filter(|t| t.implementation == *label)
                    .map(|t| (((t.n - 1) as f64).powi(3), t.ms.median))
                    .collect(),
            })
            .collect();
        let chart = XyPlot {
            title: format!("One-shot extraction time against cells, {field}"),
            x_label: "cells".into(),
            y_label: "ms (median)".into(),
            x_scale: Scale::Log,
            y_scale: Scale::Log,
            style: Style::Lines,
            series,
        };
        plot::xy(&dir.join(format!("time-{field}")), &chart).map_err(ExperimentError::Figure)?;
    }
    Ok(())
}

/// The thread counts compared: one, and the second thread.
const ONE: usize = 1;
/// See [`ONE`].
const TWO: usize = 2;

/// Idle before every recorded call, so that no call overlaps what the previous implementation
/// (often in another process) still does after it answered. Without it, in a run cut to 64³ and
/// 128³, our two-thread marching cubes on the 128³ sphere took 2.37-2.48 ms in two runs and
/// 4.36-4.74 ms in three, right after the Python peers' calls; with it, four runs of five took
/// 1.88-1.97 ms. Every implementation waits the same, so each call finds the machine idle and
/// any thread pool asleep, as a one-shot call in a program mostly does.
const IDLE_BEFORE_CALL: Duration = Duration::from_millis(20);
const OUR_MC: &str = "isolab marching-cubes";
const OUR_SN: &str = "isolab surface-nets";
/// What every CLI row's label contains.
const CLI_MARK: &str = " CLI";
const OUR_MC_CLI: &str = "isolab marching-cubes CLI";
const OUR_MC_CLI_SMALL_PAGES: &str = "isolab marching-cubes CLI, no huge pages";
const VTK_FE: &str = "VTK vtkFlyingEdges3D";
const FSN: &str = "fast-surface-nets";
const ISOSURFACE: &str = "isosurface crate";

/// "1 thread", "2 threads".
fn threads_text(threads: usize) -> String {
    format!("{threads} thread{}", if threads == 1 { "" } else { "s" })
}

/// An implementation's label in the data: its name and threads.
fn label(name: &str, threads: usize) -> String {
    format!("{name} ({})", threads_text(threads))
}

/// A ratio column: header, then (name, threads) of ours and of the peer.
type Column = (String, (&'static str, usize), (&'static str, usize));

/// Ratio columns, one-shot; the first four also steady state.
fn one_shot_ratios() -> Vec<Column> {
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
fn scaling_columns() -> Vec<Column> {
    [("isolab MC", OUR_MC), ("isolab SN", OUR_SN), ("VTK FlyingEdges", VTK_FE)]
        .into_iter()
        .map(|(h, name)| (h.to_owned(), (name, TWO), (name, ONE)))
        .collect()
}

/// Our command line against the library (one-shot): header, then the library and the CLI.
fn cli_columns() -> Vec<Column> {
    let t = threads_text;
    vec![
        (format!("CLI, {}", t(ONE)), (OUR_MC, ONE), (OUR_MC_CLI, ONE)),
        (format!("CLI, {}", t(TWO)), (OUR_MC, TWO), (OUR_MC_CLI, TWO)),
        (format!("CLI without huge pages, {}", t(ONE)), (OUR_MC, ONE), (OUR_MC_CLI_SMALL_PAGES, ONE)),
    ]
}

/// Peer median over ours, or a dash.
fn ratio(a: Option<&Timing>, b: Option<&Timing>) -> String {
    match (a, b) {
        (Some(a), Some(b)) => format!("{:.2}×", b.ms.median / a.ms.median),
        _ => "-".into(),
    }
}

/// A ratio table over `grids` for `columns` under `protocol`.
fn ratio_table(data: &Data, grids: &[(String, usize)], protocol: Protocol, columns: &[Column]) -> String {
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

/// Median (fastest-slowest) in ms.
fn spread(t: &Timing) -> String {
    use super::context::ms;
    format!("{} ({}-{})", ms(t.ms.median), ms(t.ms.min), ms(t.ms.max))
}

/// A times table under `protocol`: every implementation measured under it, median and spread.
fn times_table(data: &Data, grids: &[(String, usize)], protocol: Protocol, with_floor: bool) -> String {
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

fn section(data: &Data) -> String {
    let mut md = String::from("## Against the peers, in one run (`peers`)\n\n");
    md.push_str(&format!(
        "Every implementation on the same sampled grid (built-in fields on their default domains, n samples a side), extraction \
         only, alternating, {} runs each per protocol{}; Python peers read the very grid isolab sampled (`tests/reference/peers.py`). \
         **One-shot**: fresh output and fresh state every call, as a CLI user or a first library call meets it (ours: a new \
         extractor and a new `Extraction`; VTK: a new filter; `fast-surface-nets`: a new buffer), each freed when its call \
         returns (freeing it just before the next call instead would hand that call pages already touched). **Steady state**: the same \
         call repeated with what the implementation lets a caller keep (ours: extractor and output buffers; VTK: the same \
         filter, `Modified()` then `Update()`; `fast-surface-nets`: its buffer), after one unrecorded warm-up call. The slower \
         peers keep nothing between calls and run one-shot only. Ratios are peer median / our median under the same protocol \
         (above one means we are faster); the times tables give each median with its fastest and slowest run. \
         Our marching cubes makes no normals here, as VTK runs with ComputeNormalsOff and the other marching cubes peers make \
         none; surface nets makes its usual normals, as `fast-surface-nets` does, and does not smooth, as no peer does. Threads: our one-thread runs are serial on the \
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
