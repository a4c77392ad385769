//! `functions`: meshes from functions evaluated near their surface only (issue 60). Each field is
//! meshed by marching cubes on grids of 256³ to 2048³ samples through
//! [`extract_sparse`] with its own Lipschitz bound
//! (certified pruning, blocks of [`SparseOptions::default_chunk`] cells), and, where the grid
//! fits, densely: the field sampled on the whole grid and meshed in one call, as a user without
//! sparse extraction would. Reported per run: evaluations against the dense grid's points, wall
//! time, time inside the field's evaluations, peak heap ([`crate::alloc_meter`]) and triangles;
//! the slope of log evaluations and log time against log n (n² for a surface, n³ for the grid).
//!
//! **Identical to dense.** At 256³ every extractor that meshes in blocks, and at 512³ marching
//! cubes, meshes each field twice through the same blocks: certified, and with every block
//! sampled ([`Pruning::Dense`]); the page reports whether vertices, triangles and normals are the
//! same bits.
//!
//! Fields: the built-in signed distances `sphere` and `torus`, the `asteroid` (its bound from a
//! measured noise gradient bound: [`isolab_algorithms::fields::NOISE_GRADIENT_BOUND_3D`]), the
//! `gyroid` (not a distance; bound `k √6`) and the shipped `spot` model's signed distance
//! (closed, so 1-Lipschitz).
//!
//! **From Python** (`functions_peers.py`, in the reference environment with this commit's
//! package): numpy callables (a sphere and a small MLP signed distance whose bound comes from its
//! layers' spectral norms) meshed by `isolab.extract(fn, ...)`, warp's `sparse_marching_cubes` on
//! the CPU, scikit-image on the dense grid and PyMCubes' `marching_cubes_func`, each run a fresh
//! process (one-shot), alternating.

use super::context::{load_object, Context, Experiment, ExperimentError};
use crate::alloc_meter;
use crate::report::{log_slope, markdown_table};
use isolab_algorithms::chunks::{extract_sparse, GridFieldEval, Pruning, SparseGrid, SparseOptions, SparseStats};
use isolab_algorithms::{extractors, Chunking, Extraction, Extractor, Field, Grid, Lattice, Samples};
use serde::{Deserialize, Serialize};
use std::sync::Arc;
use std::time::Instant;

/// The experiment.
pub struct Functions;

const NAME: &str = "functions";
/// Fields and the largest grid each is meshed on (samples per side).
const FIELDS: [(&str, usize); 5] = [("sphere", 2048), ("torus", 2048), ("asteroid", 1024), ("gyroid", 512), ("spot", 512)];
/// Samples per side, up to each field's largest.
const SIZES: [usize; 4] = [256, 512, 1024, 2048];
/// Dense runs up to this size (a 1024³ grid is 4 GiB of samples).
const DENSE_UP_TO: usize = 512;
/// Every chunking extractor's certified mesh is checked against its dense mode at these sizes (a
/// mesh field's dense mode asks the exact distance at every sample: at the first size only, and
/// marching cubes at the others).
const EQUALITY_AT: [usize; 2] = [256, 512];
/// The size whose evaluation ratios the reading quotes (the issue's: at least 30x fewer there).
const READ_AT: usize = 1024;
/// The largest grid, and the bound on it: seconds and MiB.
const LARGEST: usize = 2048;
const BOUND_S: f64 = 60.0;
const BOUND_MIB: f64 = 2048.0;
/// Points per evaluation call.
const BATCH: usize = 1 << 18;

/// One run.
#[derive(Clone, Debug, Serialize, Deserialize)]
struct Row {
    field: String,
    n: usize,
    /// `sparse` or `dense`.
    mode: String,
    lipschitz: Option<f64>,
    chunk: Option<usize>,
    evaluations: u64,
    dense_points: u64,
    batches: u64,
    sampled_blocks: Option<usize>,
    blocks: Option<usize>,
    wall_ms: f64,
    eval_ms: f64,
    peak_mib: Option<f64>,
    triangles: usize,
}

/// A certified extraction compared with the same blocks all sampled.
#[derive(Clone, Debug, Serialize, Deserialize)]
struct Equality {
    field: String,
    n: usize,
    algorithm: String,
    same_vertices: bool,
    same_triangles: bool,
    same_normals: bool,
    triangles: usize,
    evaluations: u64,
    dense_evaluations: u64,
}

/// One fresh-process run of `functions_peers.py`.
#[derive(Clone, Debug, Serialize, Deserialize)]
struct PeerRun {
    #[serde(default)]
    seconds: Option<f64>,
    #[serde(default)]
    faces: Option<usize>,
    #[serde(default)]
    evaluations: Option<u64>,
    #[serde(default)]
    calls: Option<u64>,
    #[serde(default)]
    lipschitz: Option<f64>,
    #[serde(default)]
    peak_mib: Option<f64>,
    #[serde(default)]
    error: Option<String>,
}

/// One implementation on one callable and grid.
#[derive(Clone, Debug, Serialize, Deserialize)]
struct PeerRow {
    callable: String,
    n: usize,
    implementation: String,
    runs: Vec<PeerRun>,
}

/// What `functions_peers.py` wrote.
#[derive(Clone, Debug, Serialize, Deserialize)]
struct PythonSide {
    versions: std::collections::BTreeMap<String, Option<String>>,
    rows: Vec<PeerRow>,
    #[serde(default)]
    notes: Vec<String>,
    /// Each callable's definition, as the script states it.
    #[serde(default)]
    callables: std::collections::BTreeMap<String, String>,
}

#[derive(Serialize, Deserialize)]
struct Data {
    rows: Vec<Row>,
    equality: Vec<Equality>,
    /// The Python callables and peers; `None` where the reference environment could not be made.
    #[serde(default)]
    python: Option<PythonSide>,
    /// Why the Python side is missing, when it is.
    #[serde(default)]
    python_missing: Option<String>,
}

fn failed(what: String, e: impl std::fmt::Display) -> ExperimentError {
    ExperimentError::Failed { what, reason: e.to_string() }
}

/// The dense grid of `n` samples along the field's longest side.
fn grid_of(field: &dyn Field, n: usize) -> Result<Grid, ExperimentError> {
    Ok(Grid::sparse_covering(&field.domain(), n)?)
}

/// A sparse extraction of `field` on `grid` with `pruning`.
fn sparse(
    extractor: &dyn Extractor,
    field: &Arc<dyn Field>,
    grid: &Grid,
    pruning: Pruning,
) -> Result<(Extraction, SparseStats), ExperimentError> {
    let options = SparseOptions { chunk: SparseOptions::default_chunk(extractor), batch: BATCH, pruning };
    let mut out = Extraction::default();
    let mut eval = GridFieldEval { field: field.clone(), grid: *grid };
    let stats = extract_sparse(extractor, &SparseGrid::of(grid), 0.0, &options, &mut eval, &mut out)
        .map_err(|e| failed(format!("{} on {} at {}", extractor.name(), field.name(), grid.dims[0]), e))?;
    Ok((out, stats))
}

fn mib(bytes: Option<usize>) -> Option<f64> {
    bytes.map(|b| b as f64 / (1u64 << 20) as f64)
}

fn sparse_row(field: &Arc<dyn Field>, n: usize, mc: &dyn Extractor) -> Result<Row, ExperimentError> {
    let grid = grid_of(field.as_ref(), n)?;
    let l = field.lipschitz().ok_or_else(|| failed(field.name().to_owned(), "no Lipschitz bound"))?;
    let start = Instant::now();
    let (result, peak) = alloc_meter::peak_since(|| sparse(mc, field, &grid, Pruning::Lipschitz(l)));
    let wall = start.elapsed();
    let (out, stats) = result?;
    Ok(Row {
        field: field.name().to_owned(),
        n,
        mode: "sparse".into(),
        lipschitz: Some(l),
        chunk: Some(SparseOptions::default_chunk(mc)),
        evaluations: stats.evaluations,
        dense_points: stats.dense_points,
        batches: stats.batches,
        sampled_blocks: Some(stats.sampled_blocks),
        blocks: Some(stats.blocks),
        wall_ms: wall.as_secs_f64() * 1e3,
        eval_ms: stats.eval_time.as_secs_f64() * 1e3,
        peak_mib: mib(peak),
        triangles: out.surface.triangles.len(),
    })
}

fn dense_row(field: &Arc<dyn Field>, n: usize, mc: &dyn Extractor) -> Result<Row, ExperimentError> {
    let grid = Grid::covering(&field.domain(), n)?;
    let start = Instant::now();
    let (result, peak) = alloc_meter::peak_since(|| -> Result<(Extraction, f64), ExperimentError> {
        let t = Instant::now();
        let samples = Samples::sample(field.clone(), Lattice::Cubic(grid), 0.0)?;
        let eval_ms = t.elapsed().as_secs_f64() * 1e3;
        let mut out = Extraction::default();
        mc.extract(&samples, &mut out)?;
        Ok((out, eval_ms))
    });
    let wall = start.elapsed();
    let (out, eval_ms) = result?;
    let points = grid.len() as u64;
    Ok(Row {
        field: field.name().to_owned(),
        n,
        mode: "dense".into(),
        lipschitz: None,
        chunk: None,
        evaluations: points,
        dense_points: points,
        batches: 1,
        sampled_blocks: None,
        blocks: None,
        wall_ms: wall.as_secs_f64() * 1e3,
        eval_ms,
        peak_mib: mib(peak),
        triangles: out.surface.triangles.len(),
    })
}

fn equality(field: &Arc<dyn Field>, n: usize, e: &dyn Extractor) -> Result<Equality, ExperimentError> {
    let grid = grid_of(field.as_ref(), n)?;
    let l = field.lipschitz().ok_or_else(|| failed(field.name().to_owned(), "no Lipschitz bound"))?;
    let (certified, stats) = sparse(e, field, &grid, Pruning::Lipschitz(l))?;
    let (dense, dense_stats) = sparse(e, field, &grid, Pruning::Dense)?;
    Ok(Equality {
        field: field.name().to_owned(),
        n,
        algorithm: e.name().to_owned(),
        same_vertices: certified.surface.positions == dense.surface.positions,
        same_triangles: certified.surface.triangles == dense.surface.triangles,
        same_normals: certified.surface.normals == dense.surface.normals,
        triangles: dense.surface.triangles.len(),
        evaluations: stats.evaluations,
        dense_evaluations: dense_stats.evaluations,
    })
}

impl Experiment for Functions {
    fn name(&self) -> &'static str {
        NAME
    }

    fn question(&self) -> &'static str {
        "How few evaluations does a function need when only its surface is sampled, and is the mesh still the dense one?"
    }

    fn run(&self, ctx: &Context) -> Result<(), ExperimentError> {
        let mc = extractors::by_name("marching-cubes").ok_or_else(|| failed("marching-cubes".into(), "not registered"))?;
        let chunking: Vec<Box<dyn Extractor>> =
            extractors::registry().into_iter().filter(|e| e.chunking() != Chunking::Unsupported).collect();
        let bar = ctx.bar(NAME, FIELDS.len() as u64);
        let (mut rows, mut equal) = (Vec::new(), Vec::new());
        for (name, largest) in FIELDS {
            let field = load_object(name)?;
            for &n in SIZES.iter().filter(|&&n| n <= largest) {
                // Alternating: the dense run first, then the sparse one, on the same grid.
                if n <= DENSE_UP_TO {
                    rows.push(dense_row(&field, n, mc.as_ref())?);
                }
                rows.push(sparse_row(&field, n, mc.as_ref())?);
            }
            // A mesh field's dense mode asks the exact distance at every sample (no narrow band):
            // every extractor at the smallest size, marching cubes above it.
            let expensive = field.surface_mesh().is_some();
            for &n in EQUALITY_AT.iter().filter(|&&n| n <= largest) {
                let all = !expensive || n == EQUALITY_AT[0];
                for e in chunking.iter().filter(|e| all || e.name() == mc.name()) {
                    equal.push(equality(&field, n, e.as_ref())?);
                }
            }
            bar.inc(1);
        }
        bar.finish_and_clear();
        let (python, python_missing) = match python_side(ctx) {
            Ok(side) => (Some(side), None),
            Err(e) => (None, Some(e)),
        };
        ctx.write_data(NAME, &Data { rows, equality: equal, python, python_missing })
    }

    fn section(&self, ctx: &Context) -> Result<String, ExperimentError> {
        let data: Data = ctx.read_data(NAME)?;
        let mut s = String::from("## Meshes from functions (`functions`)\n\n");
        s.push_str(&format!(
            "Marching cubes of a field evaluated only in the blocks its Lipschitz bound cannot rule out (sparse), and of \
                 the whole grid (dense, up to {DENSE_UP_TO}³). Evaluations count every point the field was asked for, octree \
                 centres included; peak is the heap the run added. One run per cell, in one process.\n\n"
        ));
        s.push_str(&reading(&data));
        let rows: Vec<Vec<String>> = data
            .rows
            .iter()
            .map(|r| {
                vec![
                    format!("`{}`", r.field),
                    format!("{}³", r.n),
                    r.mode.clone(),
                    r.lipschitz.map_or("—".into(), |l| format!("{l:.2}")),
                    format!("{:.1} M", r.evaluations as f64 / 1e6),
                    format!("{:.1}x", r.dense_points as f64 / r.evaluations.max(1) as f64),
                    format!("{:.0}", r.wall_ms),
                    format!("{:.0}", r.eval_ms),
                    r.peak_mib.map_or("—".into(), |m| format!("{m:.0}")),
                    r.triangles.to_string(),
                ]
            })
            .collect();
        s.push_str(&markdown_table(
            &[
                "field",
                "grid",
                "mode",
                "L",
                "evaluations",
                "fewer than dense",
                "wall ms",
                "in the field ms",
                "peak MiB",
                "triangles",
            ],
            &rows,
        ));
        s.push_str("\n### Growth with n\n\n");
        s.push_str(
            "Slope of log evaluations and log wall time against log n over each field's sparse runs (a surface grows as n², \
             the grid as n³).\n\n",
        );
        s.push_str(&markdown_table(&["field", "sizes", "evaluations slope", "time slope"], &growth(&data.rows)));
        s.push_str("\n### Identical to dense\n\n");
        s.push_str(
            "Each extractor that meshes in blocks, certified against every block sampled (the same blocks, the same \
             welding): whether vertices, triangles and normals are the same bits. A mesh field's dense mode asks \
             the exact distance at every sample, so past the smallest size only marching cubes is compared on it; the \
             blocks, aprons and welding are the same for every field.\n\n",
        );
        let eq: Vec<Vec<String>> = data
            .equality
            .iter()
            .map(|e| {
                let yes = |b: bool| if b { "same" } else { "**differ**" }.to_owned();
                vec![
                    format!("`{}`", e.field),
                    format!("{}³", e.n),
                    format!("`{}`", e.algorithm),
                    yes(e.same_vertices),
                    yes(e.same_triangles),
                    yes(e.same_normals),
                    e.triangles.to_string(),
                    format!("{:.1}x", e.dense_evaluations as f64 / e.evaluations.max(1) as f64),
                ]
            })
            .collect();
        s.push_str(&markdown_table(
            &["field", "grid", "extractor", "vertices", "triangles", "normals", "triangle count", "fewer evaluations"],
            &eq,
        ));
        s.push_str(&python_section(&data));
        Ok(s)
    }
}

/// Grid sizes of the Python side; PyMCubes calls Python once per point, so it runs at the
/// smallest only, and the dense grid is sampled up to [`DENSE_UP_TO`].
const PYTHON_SIZES: [usize; 5] = [64, 256, 512, 1024, 2048];
const PYMCUBES_UP_TO: usize = 64;
/// Rounds per cell up to this size (alternating order), one above.
const PYTHON_REPEAT_UP_TO: usize = 256;

/// Runs `functions_peers.py` in the reference environment with this commit's package installed.
fn python_side(ctx: &Context) -> Result<PythonSide, String> {
    use crate::peers::python;
    let root = ctx.report_dir.join("..");
    let py = python::reference_python(&root)?;
    python::install_package(&py, &root)?;
    let script = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("src/experiment/functions_peers.py");
    let sizes: Vec<String> = PYTHON_SIZES.iter().map(usize::to_string).collect();
    let args: Vec<String> = [
        "--sizes",
        &sizes.join(","),
        "--repeats",
        &ctx.repeats.clamp(1, 3).to_string(),
        "--repeat-up-to",
        &PYTHON_REPEAT_UP_TO.to_string(),
        "--dense-up-to",
        &DENSE_UP_TO.to_string(),
        "--pymcubes-up-to",
        &PYMCUBES_UP_TO.to_string(),
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    python::run_script(&py, &script, &args, &[])
}

/// The Python side's table: per callable, grid and implementation, the median call time with its
/// range, evaluations, peak RSS of its process and faces, and each time as a multiple of isolab's.
fn python_section(data: &Data) -> String {
    let Some(side) = &data.python else {
        return format!(
            "\n### From Python\n\nNot run: {}\n",
            data.python_missing.as_deref().unwrap_or("no reference environment")
        );
    };
    let mut s = String::from("\n### From Python, against the peers\n\n");
    s.push_str(
        "Each implementation meshes the same numpy callable on the same bounds and grid, one fresh process per run \
         (one-shot: the time is the call's, after the imports; the peak is the process's RSS), rounds alternating. \
         isolab and warp prune with the callable's Lipschitz bound; scikit-image samples the dense grid; PyMCubes calls \
         the function once per point. The callables:\n\n",
    );
    for (name, what) in &side.callables {
        s.push_str(&format!("- `{name}`: {what}\n"));
    }
    s.push('\n');
    let versions: Vec<String> = side.versions.iter().map(|(k, v)| format!("{k} {}", v.as_deref().unwrap_or("missing"))).collect();
    s.push_str(&format!("Versions: {}. {}\n\n", versions.join(", "), side.notes.join(" ")));
    let median_of = |r: &PeerRow| {
        let secs: Vec<f64> = r.runs.iter().filter_map(|x| x.seconds).collect();
        (!secs.is_empty()).then(|| crate::report::Spread::of(secs))
    };
    let mut rows = Vec::new();
    for r in &side.rows {
        let ours =
            side.rows.iter().find(|o| o.callable == r.callable && o.n == r.n && o.implementation == "isolab").and_then(median_of);
        let spread = median_of(r);
        let first = r.runs.iter().find(|x| x.error.is_none());
        let peak = r.runs.iter().filter_map(|x| x.peak_mib).fold(f64::NAN, f64::max);
        rows.push(vec![
            format!("`{}`", r.callable),
            format!("{}³", r.n),
            r.implementation.clone(),
            spread.as_ref().map_or_else(
                || r.runs.iter().find_map(|x| x.error.clone()).unwrap_or_default(),
                |sp| format!("{:.3} [{:.3}–{:.3}] ×{}", sp.median, sp.min, sp.max, r.runs.len()),
            ),
            match (&spread, &ours) {
                (Some(sp), Some(o)) if o.median > 0.0 => format!("{:.2}x", sp.median / o.median),
                _ => "–".into(),
            },
            first.and_then(|x| x.evaluations).map_or("–".into(), |e| format!("{:.2} M", e as f64 / 1e6)),
            if peak.is_finite() { format!("{peak:.0}") } else { "–".into() },
            first.and_then(|x| x.faces).map_or("–".into(), |f| f.to_string()),
        ]);
    }
    s.push_str(&markdown_table(
        &["callable", "grid", "implementation", "seconds, median [range] ×runs", "÷ isolab", "evaluations", "peak MiB", "faces"],
        &rows,
    ));
    s
}

/// Per field: the log-log slope of sparse evaluations and wall time against n.
fn growth(rows: &[Row]) -> Vec<Vec<String>> {
    let mut out = Vec::new();
    for (name, _) in FIELDS {
        let sparse: Vec<&Row> = rows.iter().filter(|r| r.field == name && r.mode == "sparse").collect();
        if sparse.len() < 2 {
            continue;
        }
        let slope = |y: &dyn Fn(&Row) -> f64| {
            let pts: Vec<(f64, f64)> = sparse.iter().map(|r| (r.n as f64, y(r))).collect();
            log_slope(&pts).unwrap_or(f64::NAN)
        };
        out.push(vec![
            format!("`{name}`"),
            format!("{}³–{}³", sparse[0].n, sparse[sparse.len() - 1].n),
            format!("{:.2}", slope(&|r| r.evaluations as f64)),
            format!("{:.2}", slope(&|r| r.wall_ms)),
        ]);
    }
    out
}

/// The page's reading, from the data: the evaluation ratios at [`READ_AT`], the [`LARGEST`] runs
/// against the bound, and how many comparisons were equal.
fn reading(data: &Data) -> String {
    let mut s = String::new();
    let at_read: Vec<String> = data
        .rows
        .iter()
        .filter(|r| r.mode == "sparse" && r.n == READ_AT)
        .map(|r| format!("`{}` {:.1}x", r.field, r.dense_points as f64 / r.evaluations.max(1) as f64))
        .collect();
    if !at_read.is_empty() {
        s.push_str(&format!(
            "**Reading.** At {READ_AT}³, sparse extraction evaluated fewer points than the dense grid has: {}. ",
            at_read.join(", ")
        ));
    }
    let big: Vec<String> = data
        .rows
        .iter()
        .filter(|r| r.mode == "sparse" && r.n == LARGEST)
        .map(|r| {
            let within = r.wall_ms <= BOUND_S * 1e3 && r.peak_mib.is_some_and(|m| m <= BOUND_MIB);
            format!(
                "`{}` in {:.1} s and {} ({} the issue's bound of {BOUND_S} s and {BOUND_MIB} MiB)",
                r.field,
                r.wall_ms / 1e3,
                r.peak_mib.map_or("unmeasured peak".into(), |m| format!("{m:.0} MiB peak")),
                if within { "within" } else { "**outside**" }
            )
        })
        .collect();
    if !big.is_empty() {
        s.push_str(&format!("At {LARGEST}³: {}. ", big.join("; ")));
    }
    let same = data.equality.iter().filter(|e| e.same_vertices && e.same_triangles && e.same_normals).count();
    s.push_str(&format!("{same} of {} certified meshes are the dense mesh bit for bit.\n\n", data.equality.len()));
    s
}
