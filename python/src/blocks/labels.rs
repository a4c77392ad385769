//! Blocks of a label map (the driver is [`super`]): the plan, one block's labels to a fragment
//! (its interface triangles in the map's sample indices, their label pairs, each vertex's weld
//! key and the block's own label counts), and the weld into the per-label meshes
//! `isolab.mesh_labels` returns. The engine is `isolab_algorithms::labels::blocks`, whose weld
//! equals the whole map's surface.

use std::collections::BTreeMap;

use isolab_algorithms::labels::blocks;
use isolab_algorithms::labels::{LabelBlockPlan, LabelExtractor, LabelFragment, LabelSamples, LabelValues};
use isolab_algorithms::TriMesh;
use isolab_pipeline::labels::{self, LabelConfig, LabelOutcome};
use numpy::{PyArrayDyn, PyArrayMethods, PyUntypedArray, PyUntypedArrayMethods};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use super::{check_block, field, keys_array, keys_from, rows, PlanListing};
use crate::arrays::{self, Layout};
use crate::{out, pools, run_error, value_error};

pub(crate) fn extractor(algorithm: &str, options: Option<BTreeMap<String, String>>) -> PyResult<Box<dyn LabelExtractor>> {
    let config = LabelConfig { algorithm: algorithm.to_owned(), options: crate::options_from(options), ..LabelConfig::default() };
    labels::build(&config).map_err(run_error)
}

fn plan_for(e: &dyn LabelExtractor, dims: [usize; 3], chunk: usize) -> PyResult<LabelBlockPlan> {
    LabelBlockPlan::new(e, dims, chunk).map_err(value_error)
}

/// The blocks of a label map of `dims` samples (isolab's x, y, z) for `algorithm` at `chunk`
/// cells: `(counts, apron, [(id, lo, dims), ...])` in weld order.
#[pyfunction]
#[pyo3(signature = (algorithm, options, dims, chunk))]
pub fn label_block_plan(
    algorithm: &str,
    options: Option<BTreeMap<String, String>>,
    dims: [usize; 3],
    chunk: usize,
) -> PyResult<PlanListing> {
    let e = extractor(algorithm, options)?;
    let plan = plan_for(e.as_ref(), dims, chunk)?;
    Ok((plan.counts, plan.apron, plan.blocks().map(|b| (b.id, b.lo, b.dims)).collect()))
}

/// A C-ordered block of labels as values: uint8, uint16 and uint32 copied as they are, other
/// integers and bool converted (each a label from 0 to 2^32 - 1), floats refused.
pub(crate) fn block_values(block: &Bound<'_, PyUntypedArray>) -> PyResult<LabelValues> {
    let unreadable = |e: numpy::BorrowError| PyValueError::new_err(format!("the block cannot be read: {e}"));
    macro_rules! same {
        ($($t:ty => $v:ident),*) => {$(
            if let Ok(a) = block.downcast::<PyArrayDyn<$t>>() {
                return Ok(LabelValues::$v(a.try_readonly().map_err(unreadable)?.as_array().iter().copied().collect()));
            }
        )*};
    }
    same!(u8 => U8, u16 => U16, u32 => U32);
    macro_rules! converted {
        ($($t:ty),*) => {$(
            if let Ok(a) = block.downcast::<PyArrayDyn<$t>>() {
                let ro = a.try_readonly().map_err(unreadable)?;
                return Ok(LabelValues::narrowest(crate::labels::to_labels(ro.as_array().iter().copied())?));
            }
        )*};
    }
    converted!(i8, i16, i32, i64, u64);
    if let Ok(a) = block.downcast::<PyArrayDyn<bool>>() {
        return Ok(LabelValues::U8(a.try_readonly().map_err(unreadable)?.as_array().iter().map(|&b| u8::from(b)).collect()));
    }
    Err(PyTypeError::new_err(crate::labels::not_labels_message(&block.dtype().to_string())))
}

/// Meshes one block (a C-ordered 3-D array of the labels `label_block_plan` named for `id`) of a
/// label map of `dims` samples; labels outside `select` (when given) count as background.
/// Returns the fragment as arrays: `positions` (sample indices, x y z), `triangles`, `pairs`
/// (M x 2 uint32), `keys` (N x 2 uint64: the low and high halves of each vertex's weld key), and
/// `id`, `active_cells` and `counts` (each label's samples among those the block owns, before the
/// selection).
#[pyfunction]
#[allow(clippy::too_many_arguments)]
#[pyo3(signature = (block, algorithm, options, dims, chunk, id, select=None, threads=1))]
pub fn mesh_label_block<'py>(
    py: Python<'py>,
    block: &Bound<'py, PyUntypedArray>,
    algorithm: &str,
    options: Option<BTreeMap<String, String>>,
    dims: [usize; 3],
    chunk: usize,
    id: [usize; 3],
    select: Option<Vec<u32>>,
    threads: Option<usize>,
) -> PyResult<Bound<'py, PyDict>> {
    let e = extractor(algorithm, options)?;
    let plan = plan_for(e.as_ref(), dims, chunk)?;
    let bounds = plan
        .block(id)
        .ok_or_else(|| PyValueError::new_err(format!("block {id:?} is outside the plan's {:?} blocks", plan.counts)))?;
    check_block(block, id, bounds.dims, "labels")?;
    let values = block_values(block)?;
    let pool = pools::pool(threads)?;
    let (fragment, counts) = py
        .allow_threads(|| {
            pools::install(pool.as_deref(), || {
                let counts = bounds.owned_counts(values.as_slice());
                let (keep, _) = labels::selection(select.as_deref(), &counts);
                let selected = keep.map(|keep| values.as_slice().keep_only(&keep));
                let samples: LabelSamples<'_> = selected.as_ref().unwrap_or(&values).as_slice();
                let mut fragment = LabelFragment::default();
                blocks::mesh_label_block(e.as_ref(), &plan, id, samples, &mut fragment).map(|()| (fragment, counts))
            })
        })
        .map_err(value_error)?;
    fragment_dict(py, fragment, counts)
}

fn fragment_dict(py: Python<'_>, f: LabelFragment, counts: BTreeMap<u32, usize>) -> PyResult<Bound<'_, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("id", f.id)?;
    d.set_item("active_cells", f.surface.active_cells)?;
    d.set_item("counts", counts)?;
    d.set_item("keys", keys_array(py, f.keys.iter().copied())?)?;
    let TriMesh { positions, triangles, .. } = f.surface.mesh;
    d.set_item("positions", out::vec3_array(py, positions)?)?;
    d.set_item("triangles", out::u32_rows(py, triangles)?)?;
    d.set_item("pairs", out::u32_rows(py, f.surface.pairs)?)?;
    d.set_item("tetrahedra", out::u32_rows(py, f.surface.tetrahedra)?)?;
    d.set_item("tetrahedron_labels", numpy::PyArray1::from_vec(py, f.surface.tetrahedron_labels))?;
    Ok(d)
}

/// A fragment dict (as `mesh_label_block` made it, or as loaded back from a file) as a
/// `LabelFragment` and its counts.
fn fragment_from(d: &Bound<'_, PyDict>) -> PyResult<(LabelFragment, BTreeMap<u32, usize>)> {
    let item = |k: &str| field(d, k, "label fragment");
    let mut fragment = LabelFragment { id: item("id")?.extract()?, ..LabelFragment::default() };
    fragment.surface.mesh = arrays::tri_mesh(&item("positions")?, &item("triangles")?, None)?;
    fragment.surface.pairs = rows::<u32, 2>(&item("pairs")?, "pairs", "uint32")?;
    fragment.surface.active_cells = item("active_cells")?.extract()?;
    fragment.keys = keys_from(&item("keys")?)?;
    // Tetrahedra (lattice cleaving's), absent from fragments of surface extractors' older files.
    if let (Some(tets), Some(labels)) = (d.get_item("tetrahedra")?, d.get_item("tetrahedron_labels")?) {
        fragment.surface.tetrahedra = rows::<u32, 4>(&tets, "tetrahedra", "uint32")?;
        fragment.surface.tetrahedron_labels = labels.extract()?;
        let n = fragment.surface.mesh.positions.len() as u32;
        if fragment.surface.tetrahedron_labels.len() != fragment.surface.tetrahedra.len()
            || fragment.surface.tetrahedra.iter().flatten().any(|&v| v >= n)
        {
            return Err(PyValueError::new_err(format!(
                "label fragment {:?}: {} tetrahedra with {} labels over {n} vertices",
                fragment.id,
                fragment.surface.tetrahedra.len(),
                fragment.surface.tetrahedron_labels.len()
            )));
        }
    }
    let (n, t) = (fragment.surface.mesh.positions.len(), fragment.surface.mesh.triangles.len());
    if fragment.keys.len() != n || fragment.surface.pairs.len() != t {
        return Err(PyValueError::new_err(format!(
            "label fragment {:?}: {n} vertices with {} keys, {t} triangles with {} label pairs",
            fragment.id,
            fragment.keys.len(),
            fragment.surface.pairs.len()
        )));
    }
    Ok((fragment, item("counts")?.extract()?))
}

/// Welds label fragments (in `label_block_plan`'s order) into what `isolab.mesh_labels` returns:
/// each label's mesh and the interface surface, placed by `affine` (numpy index to world, 4 x 4;
/// identity when `None`), the labels of `select` that no block has as `missing`.
#[pyfunction]
#[pyo3(signature = (fragments, affine, select, algorithm))]
pub fn weld_label_fragments<'py>(
    py: Python<'py>,
    fragments: Vec<Bound<'py, PyDict>>,
    affine: Option<[[f64; 4]; 4]>,
    select: Option<Vec<u32>>,
    algorithm: &str,
) -> PyResult<Bound<'py, PyDict>> {
    let parts: Vec<(LabelFragment, BTreeMap<u32, usize>)> = fragments.iter().map(fragment_from).collect::<PyResult<_>>()?;
    let to_world = arrays::index_to_world(affine, Layout::C).map_err(value_error)?;
    let outcome = py.allow_threads(|| {
        let start = std::time::Instant::now();
        let mut counts = BTreeMap::new();
        for (l, n) in parts.iter().flat_map(|(_, c)| c) {
            *counts.entry(*l).or_insert(0) += n;
        }
        let surface = blocks::weld_label_fragments(parts.iter().map(|(f, _)| f));
        let (_, missing) = labels::selection(select.as_deref(), &counts);
        let notes = if missing.is_empty() {
            Vec::new()
        } else {
            vec![format!("label(s) {missing:?} do not occur in the label map: no mesh for them")]
        };
        let extract_ms = start.elapsed().as_secs_f64() * 1e3;
        labels::outcome(surface, to_world, None, LabelOutcome { missing, notes, extract_ms, counts, ..LabelOutcome::default() })
    });
    crate::labels::to_python(py, outcome, algorithm)
}
