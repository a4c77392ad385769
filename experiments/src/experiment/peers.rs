//! `peers`: our extractors and the peer implementations on the same sampled grids in one run,
//! alternating, medians of repeated runs, extraction only (sampling excluded for everyone):
//! - in process: `fast-surface-nets` (its buffer reused, as a game engine would) and the
//!   `isosurface` crate's marching cubes (which samples a `Source` itself: ours reads the stored
//!   grid, so its time includes that lookup; cubic grids only, and it also meshes one layer of
//!   cells past the far faces, which a closed surface inside the grid never reaches);
//! - through one Python subprocess (`tests/reference/peers.py`, in the pinned virtual environment
//!   `tests/reference/run.sh setup` creates) reading the very grid we sampled: VTK's
//!   vtkFlyingEdges3D on one and two threads, vtkMarchingCubes, scikit-image (Lorensen, Lewiner),
//!   PyMCubes, libigl. A peer that is not installed is skipped with a note in the report.
//!
//! Also measured: the memory floor (one streaming read of the grid plus writing the output's
//! bytes) and every extractor as a multiple of it; thread scaling (one thread against rayon's
//! pool); time against cells on a log-log plot.

use super::context::{Context, Experiment, ExperimentError};
use crate::figures::plot::{self, Scale, Series, Style, XyPlot};
use crate::report::{markdown_table, median};
use fast_surface_nets::ndshape::RuntimeShape;
use fast_surface_nets::{surface_nets, SurfaceNetsBuffer};
use isolab_algorithms::extractors::marching_cubes::{McOptions, NormalSource};
use isolab_algorithms::extractors::surface_nets::{Smoothing, SnOptions, SurfaceNets};
use isolab_algorithms::extractors::MarchingCubes;
use isolab_algorithms::slabs::Parallelism;
use isolab_algorithms::{fields, Extraction, Extractor, Grid, Samples};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::io::{BufRead, BufReader, Write};
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdin, ChildStdout, Command, Stdio};
use std::time::{Duration, Instant};

/// The experiment.
pub struct Peers;

/// The stored grid as the `isosurface` crate's `Source`: it asks for values at `(x, y, z)` in the
/// unit cube in steps of `1 / (n - 1)`; past the far faces (where it also looks) the grid is
/// outside.
struct GridSource<'a> {
    values: &'a [f32],
    n: usize,
}

impl isosurface::source::Source for GridSource<'_> {
    fn sample(&self, x: f32, y: f32, z: f32) -> f32 {
        let last = (self.n - 1) as f32;
        let index = |c: f32| (c * last).round() as usize;
        let (i, j, k) = (index(x), index(y), index(z));
        if i >= self.n || j >= self.n || k >= self.n {
            return 1.0;
        }
        self.values[i + self.n * (j + self.n * k)]
    }
}

const NAME: &str = "peers";
const FIELDS: [&str; 4] = ["sphere", "gyroid", "asteroid", "terrain"];
const SIZES: [usize; 3] = [64, 128, 256];
/// 512^3 for the fast implementations only, on every field (the slow peers take seconds a run).
const LARGE: (usize, [&str; 4]) = (512, FIELDS);
const SLOW_PEERS: [&str; 5] = ["vtk-marching-cubes", "skimage-lorensen", "skimage-lewiner", "pymcubes", "libigl"];

/// One implementation on one grid.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Timing {
    /// Implementation label.
    pub implementation: String,
    /// Field.
    pub field: String,
    /// Samples along each side.
    pub n: usize,
    /// Median extraction time, ms.
    pub ms: f64,
    /// Vertices and triangles of its output.
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
}

/// The Python peer server.
pub(crate) struct PythonPeers {
    child: Child,
    stdin: ChildStdin,
    stdout: BufReader<ChildStdout>,
}

impl PythonPeers {
    /// Starts `peers.py` in the reference environment, creating it when missing.
    pub(crate) fn start(root: &Path) -> Result<(PythonPeers, serde_json::Value), String> {
        let python = root.join("tests/reference/.venv/bin/python");
        if !python.exists() {
            let status = Command::new("bash")
                .arg(root.join("tests/reference/run.sh"))
                .arg("setup")
                .status()
                .map_err(|e| format!("cannot run tests/reference/run.sh setup: {e}"))?;
            if !status.success() {
                return Err("tests/reference/run.sh setup failed (no Python peers)".into());
            }
        }
        let mut child = Command::new(&python)
            .arg(root.join("tests/reference/peers.py"))
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .spawn()
            .map_err(|e| format!("cannot start {}: {e}", python.display()))?;
        let stdin = child.stdin.take().ok_or("no stdin")?;
        let mut stdout = BufReader::new(child.stdout.take().ok_or("no stdout")?);
        let mut line = String::new();
        stdout.read_line(&mut line).map_err(|e| e.to_string())?;
        let hello: serde_json::Value = serde_json::from_str(&line).map_err(|e| format!("peers.py said {line:?}: {e}"))?;
        Ok((PythonPeers { child, stdin, stdout }, hello))
    }

    /// One timed run: (ms, vertices, triangles).
    fn run(&mut self, raw: &Path, peer: &str, threads: usize) -> Result<(f64, usize, usize), String> {
        self.request(&serde_json::json!({"raw": raw, "peer": peer, "threads": threads}))
    }

    /// pymeshlab's quadric edge collapse of `mesh` to `target` faces into `out`: (ms, vertices,
    /// triangles).
    pub(crate) fn decimate(&mut self, mesh: &Path, target: usize, out: &Path) -> Result<(f64, usize, usize), String> {
        self.request(&serde_json::json!({"peer": "pymeshlab-quadric", "mesh": mesh, "target": target, "out": out}))
    }

    /// Sends one request line and reads its answer: (ms, vertices, triangles), or the peer's error.
    pub(crate) fn request(&mut self, request: &serde_json::Value) -> Result<(f64, usize, usize), String> {
        writeln!(self.stdin, "{request}").map_err(|e| e.to_string())?;
        self.stdin.flush().map_err(|e| e.to_string())?;
        let mut line = String::new();
        self.stdout.read_line(&mut line).map_err(|e| e.to_string())?;
        let v: serde_json::Value = serde_json::from_str(&line).map_err(|e| format!("{line:?}: {e}"))?;
        if let Some(e) = v.get("error") {
            return Err(e.to_string());
        }
        let n = |k: &str| v[k].as_u64().unwrap_or(0) as usize;
        Ok((v["ms"].as_f64().unwrap_or(f64::NAN), n("vertices"), n("triangles")))
    }
}

impl Drop for PythonPeers {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// Times one of our extractors once.
fn ours(e: &dyn Extractor, s: &Samples, out: &mut Extraction) -> Result<Duration, ExperimentError> {
    e.extract(s, out)?;
    Ok(out.stats.times.extraction())
}

/// The memory floor: one read of every sample (a sum the optimiser cannot drop) and one write of
/// `bytes` (filling a buffer allocated beforehand).
pub(crate) fn floor(values: &[f32], bytes: usize) -> (Duration, Duration) {
    // Eight independent lanes so the sum is limited by memory, not by the adder's latency.
    let t = Instant::now();
    let mut lanes = [0.0f32; 8];
    let chunks = values.chunks_exact(8);
    let rest: f32 = chunks.remainder().iter().sum();
    for c in chunks {
        for (l, v) in lanes.iter_mut().zip(c) {
            *l += v;
        }
    }
    let read = t.elapsed();
    std::hint::black_box((lanes, rest));
    // The buffer is touched once first: page faults are an allocator's cost, not the floor's.
    let mut buffer = vec![0u8; bytes];
    buffer.iter_mut().for_each(|b| *b = 2);
    std::hint::black_box(&buffer);
    let t = Instant::now();
    buffer.iter_mut().for_each(|b| *b = 1);
    let write = t.elapsed();
    std::hint::black_box(&buffer);
    (read, write)
}

impl Experiment for Peers {
    fn name(&self) -> &'static str {
        NAME
    }

    fn run(&self, ctx: &Context) -> Result<(), ExperimentError> {
        let root = ctx.report_dir.join("..");
        let repeats = ctx.repeats.min(3);
        let mut versions = BTreeMap::new();
        let mut skipped = Vec::new();
        let mut python = match PythonPeers::start(&root) {
            Ok((p, hello)) => {
                for (k, v) in hello["available"].as_object().into_iter().flatten() {
                    versions.insert(k.clone(), v.as_str().unwrap_or("installed").to_owned());
                }
                for (k, v) in hello["errors"].as_object().into_iter().flatten() {
                    skipped.push(format!("{k}: {v}"));
                }
                Some(p)
            }
            Err(e) => {
                skipped.push(format!("all Python peers: {e}"));
                None
            }
        };
        let tmp = std::env::temp_dir().join(format!("isolab-peers-{}", std::process::id()));
        std::fs::create_dir_all(&tmp).map_err(|source| crate::io::IoError::Write { path: tmp.clone(), source })?;
        let mut grids: Vec<(&str, usize)> = FIELDS.iter().flat_map(|&f| SIZES.iter().map(move |&n| (f, n))).collect();
        grids.extend(LARGE.1.iter().map(|&f| (f, LARGE.0)));
        let bar = ctx.bar(NAME, grids.len() as u64);
        // No normals, as the Python side runs VTK (ComputeNormalsOff) and the other peers make none.
        let mc = MarchingCubes::new(McOptions { normals: NormalSource::None, ..Default::default() });
        let mc1 =
            MarchingCubes::new(McOptions { normals: NormalSource::None, parallelism: Parallelism::Serial, ..Default::default() });
        let sn = SurfaceNets::new(SnOptions { smoothing: Smoothing::None, ..Default::default() });
        let sn1 =
            SurfaceNets::new(SnOptions { smoothing: Smoothing::None, parallelism: Parallelism::Serial, ..Default::default() });
        let mut timings = Vec::new();
        let mut floors = Vec::new();
        for (field_name, n) in grids {
            let field = fields::builtin(field_name, Default::default())?;
            let grid = Grid::covering(&field.domain(), n)?;
            let samples = Samples::sample_cubic(field, grid, 0.0)?;
            // A file per grid: the Python side caches the grid it read last by path.
            let raw: PathBuf = tmp.join(format!("{field_name}-{n}.raw"));
            crate::io::write_samples(&raw, &samples, None)?;
            let large = n == LARGE.0;
            let mut runs: BTreeMap<String, (Vec<Duration>, usize, usize)> = BTreeMap::new();
            let mut record = |label: &str, t: Duration, v: usize, f: usize| {
                let e = runs.entry(label.to_owned()).or_insert_with(|| (Vec::new(), v, f));
                e.0.push(t);
            };
            let [nx, ny, nz] = grid.dims.map(|d| d as u32);
            let shape = RuntimeShape::<u32, 3>::new([nx, ny, nz]);
            let mut fsn = SurfaceNetsBuffer::default();
            let mut out = Extraction::default();
            let mut reads = Vec::new();
            let mut writes = Vec::new();
            for _ in 0..repeats {
                for (label, e) in [
                    ("isolab marching-cubes (2 threads)", &mc as &dyn Extractor),
                    ("isolab marching-cubes (1 thread)", &mc1),
                    ("isolab surface-nets (2 threads)", &sn),
                    ("isolab surface-nets (1 thread)", &sn1),
                ] {
                    let t = ours(e, &samples, &mut out)?;
                    record(label, t, out.surface.positions.len(), out.surface.triangles.len());
                    if label.starts_with("isolab marching-cubes (2") {
                        let bytes = out.surface.positions.len() * 12 + out.surface.triangles.len() * 12;
                        let (r, w) = floor(samples.values(), bytes);
                        reads.push(r);
                        writes.push(w);
                    }
                }
                let t = Instant::now();
                surface_nets(samples.values(), &shape, [0; 3], [nx - 1, ny - 1, nz - 1], &mut fsn);
                record("fast-surface-nets (1 thread)", t.elapsed(), fsn.positions.len(), fsn.indices.len() / 3);
                if nx == ny && ny == nz {
                    let source = GridSource { values: samples.values(), n: nx as usize };
                    let (mut vertices, mut indices) = (Vec::new(), Vec::new());
                    let t = Instant::now();
                    isosurface::marching_cubes::MarchingCubes::new(nx as usize).extract(&source, &mut vertices, &mut indices);
                    record("isosurface crate (1 thread)", t.elapsed(), vertices.len() / 3, indices.len() / 3);
                } else {
                    let note = format!(
                        "isosurface crate on {field_name}: the field's grids are not n³ (the crate meshes n³ grids only)"
                    );
                    if !skipped.contains(&note) {
                        skipped.push(note);
                    }
                }
                if let Some(py) = python.as_mut() {
                    let mut peers: Vec<(&str, usize, String)> = vec![
                        ("vtk-flying-edges", 1, "VTK vtkFlyingEdges3D (1 thread)".into()),
                        ("vtk-flying-edges", 2, "VTK vtkFlyingEdges3D (2 threads)".into()),
                    ];
                    if !large {
                        peers.extend(SLOW_PEERS.iter().map(|&p| (p, 1, format!("{p} (1 thread)"))));
                    }
                    for (peer, threads, label) in peers {
                        match py.run(&raw, peer, threads) {
                            Ok((ms, v, f)) => record(&label, Duration::from_secs_f64(ms / 1e3), v, f),
                            Err(e) => {
                                let note = format!("{peer}: {e}");
                                if !skipped.contains(&note) {
                                    skipped.push(note);
                                }
                            }
                        }
                    }
                }
            }
            for (label, (times, v, f)) in runs {
                timings.push(Timing {
                    implementation: label,
                    field: field_name.into(),
                    n,
                    ms: median(times).as_secs_f64() * 1e3,
                    vertices: v,
                    triangles: f,
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
        drop(python);
        let _ = std::fs::remove_dir_all(&tmp);
        bar.finish();
        let data = Data { repeats, timings, floors, versions, skipped };
        charts(&ctx.figure_dir(NAME)?, &data)?;
        ctx.write_data(NAME, &data)
    }

    fn section(&self, ctx: &Context) -> Result<String, ExperimentError> {
        let data: Data = ctx.read_data(NAME)?;
        Ok(section(&data))
    }
}

fn time_of<'a>(data: &'a Data, implementation: &str, field: &str, n: usize) -> Option<&'a Timing> {
    data.timings.iter().find(|t| t.implementation == implementation && t.field == field && t.n == n)
}

fn charts(dir: &Path, data: &Data) -> Result<(), ExperimentError> {
    for field in FIELDS {
        let mut labels: Vec<&str> = data.timings.iter().filter(|t| t.field == field).map(|t| t.implementation.as_str()).collect();
        labels.sort_unstable();
        labels.dedup();
        let series = labels
            .iter()
            .enumerate()
            .map(|(k, label)| Series {
                label: (*label).to_owned(),
                color: crate::figures::PALETTE[k % crate::figures::PALETTE.len()],
                points: data
                    .timings
                    .iter()
                    .filter(|t| t.field == field && t.implementation == *label)
                    .map(|t| (((t.n - 1) as f64).powi(3), t.ms))
                    .collect(),
            })
            .collect();
        let chart = XyPlot {
            title: format!("Extraction time against cells, {field}"),
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

fn section(data: &Data) -> String {
    let mut md = String::from("## Against the peers, in one run (`peers`)\n\n");
    md.push_str(&format!(
        "Every implementation on the same sampled grid (built-in fields on their default domains, n samples a side), extraction \
         only, alternating, median of {} runs each; Python peers read the very grid isolab sampled (`tests/reference/peers.py`). \
         Our marching cubes makes no normals here, as VTK runs with ComputeNormalsOff and the other marching cubes peers make \
         none; surface nets makes its usual normals, as `fast-surface-nets` does. Peer versions: {}. Times are wall clock on a shared 2-core machine; compare ratios within this run.\n\n",
        data.repeats,
        if data.versions.is_empty() {
            "none available".to_owned()
        } else {
            data.versions.iter().map(|(k, v)| format!("{k} {v}")).collect::<Vec<_>>().join(", ")
        }
    ));
    if !data.skipped.is_empty() {
        md.push_str("**Skipped peers:** ");
        md.push_str(&data.skipped.join("; "));
        md.push_str("\n\n");
    }
    let mut grids: Vec<(String, usize)> = data.floors.iter().map(|f| (f.field.clone(), f.n)).collect();
    grids.dedup();
    let ratio = |a: Option<&Timing>, b: Option<&Timing>| match (a, b) {
        (Some(a), Some(b)) => format!("{:.2}×", b.ms / a.ms),
        _ => "-".into(),
    };
    md.push_str("### Ratios (peer time / ours: above 1 means we are faster)\n\n");
    let body: Vec<Vec<String>> = grids
        .iter()
        .map(|(f, n)| {
            let t = |label: &str| time_of(data, label, f, *n);
            vec![
                format!("{f} {n}³"),
                ratio(t("isolab marching-cubes (1 thread)"), t("VTK vtkFlyingEdges3D (1 thread)")),
                ratio(t("isolab marching-cubes (2 threads)"), t("VTK vtkFlyingEdges3D (2 threads)")),
                ratio(t("isolab surface-nets (1 thread)"), t("fast-surface-nets (1 thread)")),
                ratio(t("isolab surface-nets (2 threads)"), t("fast-surface-nets (1 thread)")),
                ratio(t("isolab marching-cubes (1 thread)"), t("skimage-lewiner (1 thread)")),
                ratio(t("isolab marching-cubes (1 thread)"), t("vtk-marching-cubes (1 thread)")),
                ratio(t("isolab marching-cubes (1 thread)"), t("isosurface crate (1 thread)")),
            ]
        })
        .collect();
    md.push_str(&markdown_table(
        &[
            "grid",
            "MC vs FlyingEdges, 1 thread",
            "MC vs FlyingEdges, 2 threads",
            "SN vs fast-surface-nets, 1 thread",
            "SN (2 threads) vs fast-surface-nets",
            "MC vs skimage Lewiner",
            "MC vs vtkMarchingCubes",
            "MC vs isosurface crate",
        ],
        &body,
    ));
    md.push_str("\n### Times (ms, median) and the memory floor\n\nThe floor is one streaming read of the grid plus one write of marching cubes' output bytes; `× floor` is our two-thread marching cubes over it. Triangle counts in parentheses.\n\n");
    let mut labels: Vec<&str> = data.timings.iter().map(|t| t.implementation.as_str()).collect();
    labels.sort_unstable();
    labels.dedup();
    let mut header = vec!["grid", "floor ms", "MC × floor"];
    header.extend(labels.iter().copied());
    let body: Vec<Vec<String>> = grids
        .iter()
        .map(|(f, n)| {
            let fl = data.floors.iter().find(|x| &x.field == f && x.n == *n);
            let floor = fl.map_or(f64::NAN, |x| x.read_ms + x.write_ms);
            let mc = time_of(data, "isolab marching-cubes (2 threads)", f, *n).map_or(f64::NAN, |t| t.ms);
            let mut row = vec![format!("{f} {n}³"), format!("{floor:.2}"), format!("{:.1}", mc / floor)];
            row.extend(labels.iter().map(|l| {
                time_of(data, l, f, *n).map_or("-".into(), |t| format!("{} ({})", super::context::ms(t.ms), t.triangles))
            }));
            row
        })
        .collect();
    md.push_str(&markdown_table(&header, &body));
    md.push_str(
        "\n| | |\n|---|---|\n| ![sphere](figures/peers/time-sphere.png) | ![gyroid](figures/peers/time-gyroid.png) |\n| ![asteroid](figures/peers/time-asteroid.png) | ![terrain](figures/peers/time-terrain.png) |\n\n",
    );
    md.push_str("Regularised marching tetrahedra against `ferreus_rmt` is in the `costen_table` section (that peer samples the field itself, following the surface).\n");
    md
}
