//! The steps of `isolab.dask.mesh_labels(..., format="neuroglancer")`, one Dask task each: a
//! block's level-0 box, a coarser box from its children, a batch of unsharded segments, a shard,
//! and the `info`. The engine is `isolab_pipeline::neuroglancer`; every step reads and writes
//! files under the output folder (the box files in its `.isolab-work`), so a task's result is
//! only a small index, and a rerun resumes.

use std::collections::BTreeMap;
use std::path::PathBuf;

use isolab_algorithms::labels::{LabelBlockPlan, LabelExtractor};
use isolab_io::neuroglancer::ShardingSpec;
use isolab_pipeline::neuroglancer::{self as ngp, BoxIndex, Layout, NgError, SegmentFragments};
use numpy::PyUntypedArray;
use pyo3::exceptions::{PyOSError, PyValueError};
use pyo3::prelude::*;

use crate::blocks::check_block;
use crate::blocks::labels::{block_values, extractor};
use crate::{pools, value_error};

/// The octree a job writes: `(algorithm, options, dims (x, y, z), chunk, lods, bits)`.
type Job = (String, Option<BTreeMap<String, String>>, [usize; 3], usize, usize, u32);

fn ng_error(e: NgError) -> PyErr {
    match e {
        NgError::Io(_) | NgError::File { .. } => PyOSError::new_err(e.to_string()),
        _ => PyValueError::new_err(e.to_string()),
    }
}

fn layout_of(job: &Job) -> PyResult<(Box<dyn LabelExtractor>, LabelBlockPlan, Layout)> {
    let e = extractor(&job.0, job.1.clone())?;
    let plan = LabelBlockPlan::new(e.as_ref(), job.2, job.3).map_err(value_error)?;
    let layout = Layout::new(&plan, job.4, job.5).map_err(PyValueError::new_err)?;
    Ok((e, plan, layout))
}

fn index_rows(i: BoxIndex) -> Vec<(u32, u32, u64)> {
    i.labels
}

/// A block's window (a C-ordered integer array of the samples `plan.widened(MARGIN).block(id)`
/// reads) as label values, labels outside `select` as background; an error names a wrong shape.
fn block_samples(
    plan: &LabelBlockPlan,
    block: &Bound<'_, PyUntypedArray>,
    id: [usize; 3],
    select: Option<&[u32]>,
) -> PyResult<isolab_algorithms::labels::LabelValues> {
    let bounds = plan
        .widened(ngp::MARGIN)
        .block(id)
        .ok_or_else(|| PyValueError::new_err(format!("block {id:?} is outside the plan's {:?} blocks", plan.counts)))?;
    check_block(block, id, bounds.dims, "labels")?;
    let values = block_values(block)?;
    Ok(match select {
        Some(s) => {
            let mut keep = s.to_vec();
            keep.sort_unstable();
            values.as_slice().keep_only(&keep)
        }
        None => values,
    })
}

/// The plan: `(counts per level, [(id, lo, dims), ...])`, each block's window the samples its
/// level-0 task reads (its cells, the extractor's apron and the one-cell margin).
#[pyfunction]
#[allow(clippy::type_complexity)]
pub fn ng_plan(job: Job) -> PyResult<(Vec<[usize; 3]>, Vec<([usize; 3], [usize; 3], [usize; 3])>)> {
    let (_, plan, layout) = layout_of(&job)?;
    let wide = plan.widened(ngp::MARGIN);
    let counts = (0..layout.lods).map(|l| layout.counts_at(l)).collect();
    Ok((counts, wide.blocks().map(|b| (b.id, b.lo, b.dims)).collect()))
}

/// A block's level-0 box (the block's window as a C-ordered integer array, labels outside
/// `select` as background): `[(label, triangles, bytes), ...]`.
#[pyfunction]
#[pyo3(signature = (job, block, id, work, select=None, threads=1))]
pub fn ng_level0(
    py: Python<'_>,
    job: Job,
    block: &Bound<'_, PyUntypedArray>,
    id: [usize; 3],
    work: PathBuf,
    select: Option<Vec<u32>>,
    threads: Option<usize>,
) -> PyResult<Vec<(u32, u32, u64)>> {
    let (e, plan, layout) = layout_of(&job)?;
    let values = block_samples(&plan, block, id, select.as_deref())?;
    let pool = pools::pool(threads)?;
    py.allow_threads(|| {
        pools::install(pool.as_deref(), || {
            let samples = values.as_slice();
            ngp::level0_box(e.as_ref(), &plan, &layout, id, samples, &work)
        })
    })
    .map(index_rows)
    .map_err(ng_error)
}

/// Box `position` at `level` from its children's: `[(label, triangles, bytes), ...]`, its
/// labels simplified and encoded on `threads` threads.
#[pyfunction]
#[pyo3(signature = (job, level, position, work, threads=1))]
pub fn ng_coarser(
    py: Python<'_>,
    job: Job,
    level: usize,
    position: [u32; 3],
    work: PathBuf,
    threads: Option<usize>,
) -> PyResult<Vec<(u32, u32, u64)>> {
    let (_, _, layout) = layout_of(&job)?;
    if level == 0 || level >= layout.lods {
        return Err(PyValueError::new_err(format!("level {level} is not a coarser level of {} levels", layout.lods)));
    }
    let pool = pools::pool(threads)?;
    py.allow_threads(|| pools::install(pool.as_deref(), || ngp::coarser_box(&layout, level, position, &work)))
        .map(index_rows)
        .map_err(ng_error)
}

type Segments = BTreeMap<u32, Vec<(usize, [u32; 3], u64)>>;

/// Writes the unsharded files of `segments` (`{label: [(level, position, bytes), ...]}`).
#[pyfunction]
pub fn ng_segments(py: Python<'_>, job: Job, work: PathBuf, out: PathBuf, segments: Segments) -> PyResult<()> {
    let (_, _, layout) = layout_of(&job)?;
    let segments: BTreeMap<u32, SegmentFragments> = segments;
    py.allow_threads(|| ngp::write_segments(&layout, &work, &out, &segments)).map_err(ng_error)
}

/// The sharding for `count` segments: `(minishard_bits, shard_bits)`.
#[pyfunction]
pub fn ng_sharding(count: usize) -> (u32, u32) {
    let s = ShardingSpec::for_segments(count);
    (s.minishard_bits, s.shard_bits)
}

/// The shard of each label under the sharding for `count` segments.
#[pyfunction]
pub fn ng_shard_of(count: usize, labels: Vec<u32>) -> Vec<u64> {
    let s = ShardingSpec::for_segments(count);
    labels.into_iter().map(|l| s.shard(u64::from(l))).collect()
}

/// Writes shard `shard` (of the sharding for `count` segments) holding `segments`.
#[pyfunction]
pub fn ng_shard(
    py: Python<'_>,
    job: Job,
    work: PathBuf,
    out: PathBuf,
    count: usize,
    shard: u64,
    segments: Segments,
) -> PyResult<()> {
    let (_, _, layout) = layout_of(&job)?;
    let spec = ShardingSpec::for_segments(count);
    py.allow_threads(|| ngp::write_shard(&layout, &spec, shard, &work, &out, &segments)).map_err(ng_error)
}

/// Writes the `info` (`transform`: 12 numbers, stored model to model, row-major; `sharded`
/// with the segment count; `names` for segment properties).
#[pyfunction]
#[pyo3(signature = (job, out, transform, sharded_count=None, names=None))]
pub fn ng_info(
    job: Job,
    out: PathBuf,
    transform: [f64; 12],
    sharded_count: Option<usize>,
    names: Option<Vec<(u64, String)>>,
) -> PyResult<()> {
    let (_, _, layout) = layout_of(&job)?;
    let sharding = sharded_count.map(ShardingSpec::for_segments);
    ngp::write_info(&layout, &out, transform, sharding, &names.unwrap_or_default()).map_err(ng_error)
}

/// The index of box `position` at `level` if its file is whole (a rerun skips it), else `None`.
#[pyfunction]
pub fn ng_box_index(work: PathBuf, level: usize, position: [u32; 3]) -> Option<Vec<(u32, u32, u64)>> {
    ngp::boxfile::read_index_if_complete(&ngp::box_path(&work, level, position)).map(index_rows)
}

/// The legacy format: block `id`'s fragments (its window as for `ng_level0`) written into `out`
/// in model coordinates (`transform`): `[(label, triangles), ...]`.
#[pyfunction]
#[pyo3(signature = (job, block, id, out, transform, select=None, threads=1))]
#[allow(clippy::too_many_arguments)]
pub fn ng_legacy_block(
    py: Python<'_>,
    job: Job,
    block: &Bound<'_, PyUntypedArray>,
    id: [usize; 3],
    out: PathBuf,
    transform: [f64; 12],
    select: Option<Vec<u32>>,
    threads: Option<usize>,
) -> PyResult<Vec<(u32, u32)>> {
    let (e, plan, _) = layout_of(&job)?;
    let values = block_samples(&plan, block, id, select.as_deref())?;
    let pool = pools::pool(threads)?;
    py.allow_threads(|| {
        pools::install(pool.as_deref(), || {
            let samples = values.as_slice();
            ngp::legacy_block(e.as_ref(), &plan, id, samples, transform, &out)
        })
    })
    .map_err(ng_error)
}

/// The legacy format's `<label>:0` files (`{label: [position, ...]}`) and `info`.
#[pyfunction]
pub fn ng_legacy_manifests(out: PathBuf, segments: BTreeMap<u32, Vec<[u32; 3]>>) -> PyResult<()> {
    ngp::write_legacy_manifests(&out, &segments).map_err(ng_error)
}

/// Draco-encodes one fragment as the writer does (`positions`: N x 3 integers in `[0, 2^bits)`,
/// `triangles`: M x 3): the bytes, for measuring the encoder against others.
#[pyfunction]
pub fn ng_encode_fragment<'py>(
    py: Python<'py>,
    positions: numpy::PyReadonlyArray2<'py, i32>,
    triangles: numpy::PyReadonlyArray2<'py, u32>,
) -> PyResult<Bound<'py, pyo3::types::PyBytes>> {
    let p = positions.as_array();
    let t = triangles.as_array();
    if p.ncols() != 3 || t.ncols() != 3 {
        return Err(PyValueError::new_err("positions and triangles must be N x 3 and M x 3"));
    }
    let p: Vec<[i32; 3]> = p.rows().into_iter().map(|r| [r[0], r[1], r[2]]).collect();
    let t: Vec<[u32; 3]> = t.rows().into_iter().map(|r| [r[0], r[1], r[2]]).collect();
    if t.iter().flatten().any(|&v| v as usize >= p.len()) {
        return Err(PyValueError::new_err("a triangle names a vertex the positions do not have"));
    }
    let bytes = py.allow_threads(|| isolab_io::neuroglancer::encode_fragment(&p, &t)).map_err(PyValueError::new_err)?;
    Ok(pyo3::types::PyBytes::new(py, &bytes))
}
