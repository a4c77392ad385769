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

mod data;
mod page;

use super::context::{Context, Experiment, ExperimentError};
use crate::figures::plot::{self, Scale, Series, Style, XyPlot};
use crate::peers::cli::Cli;
use crate::peers::fast_surface_nets::FastSurfaceNets;
use crate::peers::isosurface_crate::IsosurfaceCrate;
use crate::peers::ours::Ours;
use crate::peers::python::{PythonPeer, PythonServer};
use crate::peers::{Job, Peer, PeerError, Protocol};
use crate::report::{median, Spread, MAX_ROUNDS};
use data::Data;
pub use data::{Floor, Timing};
use isolab_algorithms::{fields, Grid, Samples};
use page::label;
use page::{one_shot_ratios, scaling_columns, time_of};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Duration;

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
/// runs with ComputeNormalsOff and PyMCubes, libigl and the `isosurface` crate make none
/// (scikit-image computes normals and values in its call, which the page says); surface nets without
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

/// Whether a cell's last round of `repeats` runs was wide ([`crate::report::WIDE`]).
fn last_round_wide(times: &[f64], repeats: usize) -> bool {
    repeats > 1 && times.len() >= repeats && Spread::of(times[times.len() - repeats..].to_vec()).is_wide()
}

impl Experiment for Peers {
    fn name(&self) -> &'static str {
        NAME
    }

    fn question(&self) -> &'static str {
        "How fast are our extractors against the peer libraries on the same grids, one-shot and steady state?"
    }

    fn peers(&self) -> &'static [&'static str] {
        &["fast-surface-nets", "isosurface crate", "VTK", "scikit-image", "PyMCubes", "libigl", "numpy"]
    }

    fn run(&self, ctx: &Context) -> Result<(), ExperimentError> {
        let root = crate::provenance::root();
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
        let sizes = ctx.sizes(&SIZES);
        let mut grids: Vec<(&str, usize)> = FIELDS.iter().flat_map(|&f| sizes.iter().map(move |&n| (f, n))).collect();
        if !ctx.quick {
            grids.extend(LARGE.1.iter().map(|&f| (f, LARGE.0)));
        }
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
            // Rounds of `repeats`; after each, only the cells whose last round was wide run again,
            // up to MAX_ROUNDS rounds (every run kept).
            let mut again: Option<Vec<(usize, Protocol)>> = None;
            for round in 0..repeats * MAX_ROUNDS {
                if round > 0 && round % repeats == 0 {
                    let wide: Vec<(usize, Protocol)> =
                        runs.iter().filter(|(_, (times, _, _))| last_round_wide(times, repeats)).map(|(cell, _)| *cell).collect();
                    if wide.is_empty() {
                        break;
                    }
                    again = Some(wide);
                }
                for protocol in PROTOCOLS {
                    for (k, e) in entries.iter_mut().enumerate() {
                        if failed[k] || (large && e.slow) || (protocol == Protocol::SteadyState && !e.steady) {
                            continue;
                        }
                        if again.as_ref().is_some_and(|cells| !cells.contains(&(k, protocol))) {
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
                    wide: last_round_wide(&times, repeats),
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
        page::section(ctx)
    }
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
            .map(|label| Series {
                label: (*label).to_owned(),
                color: crate::figures::color_of(label),
                points: one_shot()
                    .filter(|t| t.implementation == *label)
                    .map(|t| (((t.n - 1) as f64).powi(3), t.ms.median))
                    .collect(),
                ranges: one_shot().filter(|t| t.implementation == *label).map(|t| (t.ms.min, t.ms.max)).collect(),
            })
            .collect();
        let chart = XyPlot {
            title: format!("One-shot extraction time against cells, {field}"),
            x_label: "cells".into(),
            y_label: "ms (median; bars: fastest to slowest run)".into(),
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

/// A ratio column: header, then (name, threads) of ours and of the peer.
type Column = (String, (&'static str, usize), (&'static str, usize));
