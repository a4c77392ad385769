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
//! **The floor of any block size** (`floor::cell_floor`): at the reading's size, the corners of
//! the cells whose centre's value the bound cannot rule out, which a test cell by cell would
//! still evaluate; the blocks' evaluations are read against it.
//!
//! **From Python** (`functions/bench.py`, in the reference environment with this commit's
//! package): numpy callables (a sphere and a small MLP signed distance whose bound comes from its
//! layers' spectral norms) meshed by `isolab.extract(fn, ...)`, warp's `sparse_marching_cubes` on
//! the CPU, scikit-image on the dense grid and PyMCubes' `marching_cubes_func`, each run a fresh
//! process (one-shot), alternating.

mod data;
mod floor;
mod page;

use super::context::{load_object, Context, Experiment, ExperimentError};
use crate::alloc_meter;
use data::{Data, Equality, Floor, PythonSide, Row};
use isolab_algorithms::chunks::{extract_sparse, GridFieldEval, Pruning, SparseGrid, SparseOptions, SparseStats};
use isolab_algorithms::{extractors, Chunking, Extraction, Extractor, Field, Grid, Lattice, Samples};
use std::sync::Arc;
use std::time::Instant;

/// The experiment.
pub struct Functions;

const NAME: &str = "functions";

/// Fields and the largest grid each is meshed on (samples per side).
const FIELDS: [(&str, usize); 5] = [("sphere", 2048), ("torus", 2048), ("asteroid", 1024), ("gyroid", 512), ("spot", 512)];

/// Samples per side, up to each field's largest.
const SIZES: [usize; 4] = [256, 512, 1024, 2048];

/// A quick run's one size, for the sparse runs and the equality checks alike (a mesh field's
/// dense mode at the smallest full size asks millions of exact distances).
const QUICK_SIZES: [usize; 1] = [128];

/// Dense runs up to this size (a 1024³ grid is 4 GiB of samples).
const DENSE_UP_TO: usize = 512;

/// Every chunking extractor's certified mesh is checked against its dense mode at these sizes (a
/// mesh field's dense mode asks the exact distance at every sample: at the first size only, and
/// marching cubes at the others).
const EQUALITY_AT: [usize; 2] = [256, 512];

/// The size whose evaluation ratios the reading quotes (the issue's: at least [`FEWER_TARGET`]
/// times fewer there).
const READ_AT: usize = 1024;

/// The target: evaluations at least this many times fewer than dense at [`READ_AT`].
const FEWER_TARGET: f64 = 30.0;

/// The largest grid, and the bound on it: seconds and MiB.
const LARGEST: usize = 2048;

const BOUND_S: f64 = 60.0;

const BOUND_MIB: f64 = 2048.0;

/// Points per evaluation call.
const BATCH: usize = 1 << 18;

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
        pruning_evaluations: Some(stats.pruning_evaluations),
        refinement_evaluations: Some(stats.refinement_evaluations),
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
        pruning_evaluations: None,
        refinement_evaluations: None,
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

/// The cell-by-cell floor of `field` at `n` samples a side, on the sparse runs' grid.
fn floor_row(field: &Arc<dyn Field>, n: usize) -> Result<Floor, ExperimentError> {
    let grid = grid_of(field.as_ref(), n)?;
    let l = field.lipschitz().ok_or_else(|| failed(field.name().to_owned(), "no Lipschitz bound"))?;
    let (cells, samples) = floor::cell_floor(field.as_ref(), &grid, l);
    Ok(Floor { field: field.name().to_owned(), n, lipschitz: l, cells, samples, dense_points: grid.len() as u64 })
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

    fn peers(&self) -> &'static [&'static str] {
        &["PyMCubes", "scikit-image", "libigl", "warp", "numpy"]
    }

    fn run(&self, ctx: &Context) -> Result<(), ExperimentError> {
        let mc = extractors::by_name("marching-cubes").ok_or_else(|| failed("marching-cubes".into(), "not registered"))?;
        let chunking: Vec<Box<dyn Extractor>> =
            extractors::registry().into_iter().filter(|e| e.chunking() != Chunking::Unsupported).collect();
        let bar = ctx.bar(NAME, FIELDS.len() as u64);
        let (mut rows, mut equal, mut floors) = (Vec::new(), Vec::new(), Vec::new());
        for (name, largest) in FIELDS {
            let field = load_object(name)?;
            for &n in ctx.pick(&SIZES[..], &QUICK_SIZES).iter().filter(|&&n| n <= largest) {
                // Alternating: the dense run first, then the sparse one, on the same grid.
                if n <= DENSE_UP_TO {
                    rows.push(dense_row(&field, n, mc.as_ref())?);
                }
                rows.push(sparse_row(&field, n, mc.as_ref())?);
                if ctx.pick(&[READ_AT][..], &QUICK_SIZES[..]).contains(&n) {
                    floors.push(floor_row(&field, n)?);
                }
            }
            // A mesh field's dense mode asks the exact distance at every sample (no narrow band):
            // every extractor at the smallest size, marching cubes above it.
            let expensive = field.surface_mesh().is_some();
            for &n in ctx.pick(&EQUALITY_AT[..], &QUICK_SIZES).iter().filter(|&&n| n <= largest) {
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
        ctx.write_data(NAME, &Data { rows, equality: equal, floors, python, python_missing })
    }

    fn section(&self, ctx: &Context) -> Result<String, ExperimentError> {
        page::section(ctx)
    }
}

/// Grid sizes of the Python side; PyMCubes calls Python once per point, so it runs at the
/// smallest only, and the dense grid is sampled up to [`DENSE_UP_TO`].
const PYTHON_SIZES: [usize; 5] = [64, 256, 512, 1024, 2048];

const PYMCUBES_UP_TO: usize = 64;

/// Rounds per cell up to this size (alternating order), one above.
const PYTHON_REPEAT_UP_TO: usize = 256;

/// Runs `functions/bench.py` in the reference environment with this commit's package installed.
fn python_side(ctx: &Context) -> Result<PythonSide, String> {
    use crate::peers::python;
    let root = crate::provenance::root();
    let py = python::reference_python(&root)?;
    python::install_package(&py, &root)?;
    let script = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("src/experiment/functions/bench.py");
    let sizes: Vec<String> = ctx.sizes(&PYTHON_SIZES).iter().map(usize::to_string).collect();
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
        "--wide",
        &crate::report::WIDE.to_string(),
        "--max-blocks",
        &crate::report::MAX_ROUNDS.to_string(),
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    python::run_script(&py, &script, &args, &[])
}
