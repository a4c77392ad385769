//! Blocks of a volume (the driver is [`super`]): the plan, one block's samples (any numeric
//! dtype, read where they lie when the extractor can) to a fragment (its mesh in the volume's
//! sample indices, each shareable vertex's weld key, and whether the block was meshed, empty or
//! full), and the weld into one mesh in world coordinates. The engine is
//! `isolab_algorithms::chunks` (`BlockPlan`, `mesh_block`, `weld_fragments`), whose weld equals
//! the one-process chunked extraction. Also the blocks of a built-in field's world
//! (`field_block`), which `isolab.dask.bake_world` samples.

use super::{field, keys_array, keys_from, wrong_block, PlanListing};
use crate::arrays::{self, Layout, VolumeArray};
use crate::{out, pools, run_error, value_error, views, Run};
use isolab_algorithms::chunks::{self, BlockPlan, ChunkState, Fragment};
use isolab_algorithms::{extractors, Extraction, Extractor, TriMesh};
use isolab_pipeline::RunError;
use numpy::{PyArray1, PyArrayMethods, PyUntypedArray, PyUntypedArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::collections::BTreeMap;

/// The extractor called `algorithm` with `options` (serial where it can be, with `serial`).
pub(crate) fn extractor(
    algorithm: &str,
    options: Option<BTreeMap<String, String>>,
    serial: bool,
) -> PyResult<Box<dyn Extractor>> {
    let mut options = crate::options_from(options);
    if serial {
        crate::serial_where_possible(&mut options, algorithm);
    }
    extractors::build(algorithm, &options)
        .map_err(value_error)?
        .ok_or_else(|| run_error(RunError::UnknownAlgorithm { name: algorithm.to_owned(), valid: extractors::names() }))
}

fn plan_for(extractor: &dyn Extractor, dims: [usize; 3], chunk: usize) -> PyResult<BlockPlan> {
    BlockPlan::new(extractor, dims, chunk).map_err(value_error)
}

/// The blocks of a volume of `dims` samples (isolab's x, y, z) for `algorithm` at `chunk` cells:
/// `(counts, apron, [(id, lo, dims), ...])` in weld order.
#[pyfunction]
#[pyo3(signature = (algorithm, options, dims, chunk))]
pub fn block_plan(
    algorithm: &str,
    options: Option<BTreeMap<String, String>>,
    dims: [usize; 3],
    chunk: usize,
) -> PyResult<PlanListing> {
    let e = extractor(algorithm, options, true)?;
    let plan = plan_for(e.as_ref(), dims, chunk)?;
    Ok((plan.counts, plan.apron, plan.blocks().map(|b| (b.id, b.lo, b.dims)).collect()))
}

/// Meshes one block (a C-ordered 3-D array of the samples `block_plan` named for `id`, any
/// numeric dtype) of a volume of `dims` samples. `above` makes values above `level` inside.
/// Returns the fragment as arrays: `positions` (sample indices, x y z), `normals`, `triangles`,
/// `keys` (N x 2 uint64: the low and high halves of each vertex's weld key), `keyed` (N bool),
/// `state`, `active_cells`, `discarded_triangles`.
#[pyfunction]
#[allow(clippy::too_many_arguments)]
#[pyo3(signature = (block, algorithm, options, dims, chunk, id, level, above, threads=1))]
pub fn mesh_block<'py>(
    py: Python<'py>,
    block: &Bound<'py, PyUntypedArray>,
    algorithm: &str,
    options: Option<BTreeMap<String, String>>,
    dims: [usize; 3],
    chunk: usize,
    id: [usize; 3],
    level: f64,
    above: bool,
    threads: Option<usize>,
) -> PyResult<Bound<'py, PyDict>> {
    let e = extractor(algorithm, options, threads == Some(1))?;
    let plan = plan_for(e.as_ref(), dims, chunk)?;
    let sign = if above { -1.0 } else { 1.0 };
    let pool = pools::pool(threads)?;
    let expected = plan.block(id).map(|b| b.dims);
    let wrong = |layout: Layout, dims: [usize; 3]| {
        (layout != Layout::C || Some(dims) != expected)
            .then(|| wrong_block(id, expected, block.shape(), layout == Layout::C, "samples"))
    };
    let iso = sign * level as f32;
    // The block where it lies, in its own dtype (no copy for an extractor that reads it in place).
    let borrowed = views::with_borrowed(block, 1, |b| {
        if let Some(err) = wrong(b.layout, b.view.dims()) {
            return Err(err);
        }
        let view = if above { b.view.negated() } else { b.view };
        py.allow_threads(|| {
            pools::install(pool.as_deref(), || chunks::mesh_block_view(e.as_ref(), &plan, id, view, iso).map_err(value_error))
        })
    })?;
    let fragment = match borrowed {
        Some(f) => f,
        None => {
            let VolumeArray { values, dims: block_dims, layout, .. } = arrays::read_volume(py, block, 1, sign, pool.as_deref())?;
            if let Some(err) = wrong(layout, block_dims) {
                return Err(err);
            }
            py.allow_threads(|| {
                pools::install(pool.as_deref(), || chunks::mesh_block(e.as_ref(), &plan, id, values, iso).map_err(value_error))
            })?
        }
    };
    fragment_dict(py, fragment)
}

fn state_name(state: ChunkState) -> &'static str {
    match state {
        ChunkState::Empty => "empty",
        ChunkState::Full => "full",
        ChunkState::Meshed => "meshed",
    }
}

fn fragment_dict(py: Python<'_>, f: Fragment) -> PyResult<Bound<'_, PyDict>> {
    let d = PyDict::new(py);
    let keyed: Vec<bool> = f.keys.iter().map(Option::is_some).collect();
    d.set_item("id", f.id)?;
    d.set_item("state", state_name(f.state))?;
    d.set_item("active_cells", f.active_cells)?;
    d.set_item("discarded_triangles", f.discarded_triangles)?;
    d.set_item("keys", keys_array(py, f.keys.iter().map(|k| k.unwrap_or(0)))?)?;
    d.set_item("keyed", PyArray1::from_vec(py, keyed))?;
    let TriMesh { positions, normals, triangles, .. } = f.surface;
    d.set_item("positions", out::vec3_array(py, positions)?)?;
    d.set_item("normals", out::vec3_array(py, normals)?)?;
    d.set_item("triangles", out::u32_rows(py, triangles)?)?;
    Ok(d)
}

/// A fragment dict (as `mesh_block` made it, or as loaded back from a file) as a `Fragment`.
fn fragment_from(d: &Bound<'_, PyDict>) -> PyResult<Fragment> {
    let item = |k: &str| field(d, k, "fragment");
    let state = match item("state")?.extract::<String>()?.as_str() {
        "empty" => ChunkState::Empty,
        "full" => ChunkState::Full,
        "meshed" => ChunkState::Meshed,
        other => return Err(PyValueError::new_err(format!("fragment state '{other}': expected meshed, empty or full"))),
    };
    let keys = keys_from(&item("keys")?)?;
    let keyed_array = item("keyed")?;
    let keyed = keyed_array.downcast::<PyArray1<bool>>().map_err(|_| PyValueError::new_err("fragment 'keyed' must be bool"))?;
    let keyed = keyed.readonly();
    let keyed = keyed.as_array();
    let normals = item("normals")?;
    let has_normals = normals.len()? > 0;
    let surface = arrays::tri_mesh(&item("positions")?, &item("triangles")?, has_normals.then_some(&normals))?;
    if keys.len() != surface.positions.len() || keyed.len() != surface.positions.len() {
        return Err(PyValueError::new_err(format!(
            "fragment has {} vertices but {} keys ({} keyed flags)",
            surface.positions.len(),
            keys.len(),
            keyed.len()
        )));
    }
    let keys = keys.into_iter().zip(keyed.iter()).map(|(k, &on)| on.then_some(k)).collect();
    Ok(Fragment {
        id: item("id")?.extract()?,
        state,
        surface,
        keys,
        active_cells: item("active_cells")?.extract()?,
        discarded_triangles: item("discarded_triangles")?.extract()?,
    })
}

/// Welds fragments (in `block_plan`'s order) into one mesh, placed by `affine` (numpy index to
/// world, 4 x 4; identity when `None`): the vertices, faces and normals as `extract` returns
/// them, and a run whose report holds the counts.
#[pyfunction]
#[pyo3(signature = (fragments, affine, report))]
pub fn weld_fragments<'py>(
    py: Python<'py>,
    fragments: Vec<Bound<'py, PyDict>>,
    affine: Option<[[f64; 4]; 4]>,
    report: &str,
) -> PyResult<Bound<'py, PyDict>> {
    let fragments: Vec<Fragment> = fragments.iter().map(fragment_from).collect::<PyResult<_>>()?;
    let to_world = arrays::index_to_world(affine, Layout::C).map_err(value_error)?;
    let (mesh, stats) = py.allow_threads(|| {
        let mut out = Extraction::default();
        let stats = chunks::weld_fragments(&fragments, &mut out);
        let mut mesh = std::mem::take(&mut out.surface);
        mesh.transform(&to_world);
        (mesh, stats)
    });
    let mut report: serde_json::Value = serde_json::from_str(report).map_err(value_error)?;
    report["vertices"] = mesh.positions.len().into();
    report["triangles"] = mesh.triangles.len().into();
    report["blocks"] = serde_json::json!({
        "meshed": stats.meshed, "empty": stats.empty, "full": stats.full, "welded_vertices": stats.welded,
    });
    let d = PyDict::new(py);
    d.set_item("vertices", out::vec3_array(py, mesh.positions)?)?;
    d.set_item("faces", out::faces_array(py, mesh.triangles)?)?;
    d.set_item("normals", out::vec3_array(py, mesh.normals)?)?;
    d.set_item("warnings", Vec::<String>::new())?;
    d.set_item("notes", Vec::<String>::new())?;
    d.set_item("run", Run::without_truth(report.to_string()))?;
    Ok(d)
}

/// The world grid `bake_world` meshes: `cells` cells of the built-in field, from its domain's
/// lowest corner, at the spacing that fits the domain's height in `cells[1]` cells (the grid of
/// the `large_world` experiment).
fn world_grid(field: &dyn isolab_algorithms::Field, cells: [usize; 3]) -> PyResult<isolab_algorithms::Grid> {
    if cells.contains(&0) {
        return Err(PyValueError::new_err(format!("size {cells:?}: a world needs at least one cell along each axis")));
    }
    let domain = field.domain();
    let spacing = (domain.max.y - domain.min.y) / cells[1] as f32;
    Ok(isolab_algorithms::Grid { origin: domain.min, spacing, dims: cells.map(|c| c + 1) })
}

/// One block of a built-in field's world (`cells` cells, see [`world_grid`]) sampled, or (with
/// `prove`) proven empty or full without sampling: `{"side": "mixed"|"empty"|"full", "values":
/// C-ordered float32 array of the block (numpy shape z, y, x) or None, "origin", "spacing"}`.
#[pyfunction]
#[pyo3(signature = (field, cells, lo, dims, seed=None, prove=true))]
pub fn field_block<'py>(
    py: Python<'py>,
    field: &str,
    cells: [usize; 3],
    lo: [usize; 3],
    dims: [usize; 3],
    seed: Option<i32>,
    prove: bool,
) -> PyResult<Bound<'py, PyDict>> {
    use isolab_algorithms::field::BlockSide;
    let params = isolab_algorithms::fields::FieldParams { seed: seed.unwrap_or(isolab_algorithms::fields::DEFAULT_SEED) };
    let f = isolab_algorithms::fields::builtin(field, params).map_err(value_error)?;
    let grid = world_grid(f.as_ref(), cells)?;
    if (0..3).any(|a| dims[a] == 0 || lo[a] + dims[a] > grid.dims[a]) {
        return Err(PyValueError::new_err(format!("block at {lo:?} of {dims:?} samples is outside the world's {:?}", grid.dims)));
    }
    let d = PyDict::new(py);
    d.set_item("origin", grid.origin.to_array())?;
    d.set_item("spacing", grid.spacing)?;
    let side = if prove { py.allow_threads(|| f.block_side(&grid, lo, dims, 0.0)) } else { None };
    match side {
        Some(BlockSide::Outside) => d.set_item("side", "empty")?,
        Some(BlockSide::Inside) => d.set_item("side", "full")?,
        None => {
            let mut values = vec![0.0f32; dims.iter().product()];
            py.allow_threads(|| f.sample_block(&grid, lo, dims, &mut values));
            d.set_item("side", "mixed")?;
            d.set_item("values", PyArray1::from_vec(py, values).reshape([dims[2], dims[1], dims[0]])?)?;
        }
    }
    if !d.contains("values")? {
        d.set_item("values", py.None())?;
    }
    Ok(d)
}

/// A fragment of a block proven empty or full: no mesh.
#[pyfunction]
pub fn skipped_fragment<'py>(py: Python<'py>, id: [usize; 3], full: bool) -> PyResult<Bound<'py, PyDict>> {
    let state = if full { ChunkState::Full } else { ChunkState::Empty };
    fragment_dict(py, Fragment { id, state, ..Default::default() })
}
