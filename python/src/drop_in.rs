//! The scikit-image drop-in's core (`isolab.marching_cubes`): the caller's array meshed where it
//! lies, in its own type ([`crate::views`]), by `marching-cubes` reading the samples negated (the
//! object is above the level, inside is below in isolab), in one sweep that writes each vertex in
//! numpy's index order times `spacing * step`, its unit normal (central differences of the
//! samples, toward decreasing values) and scikit-image's `values` entry, and winds the triangles
//! as scikit-image does. The arrays Python receives are the sweep's own buffers (no copy).
//!
//! The level is compared as scikit-image compares it: a sample (as `float32`) is inside when it
//! is above the level as a `float64` (so a level between two `float32` values, or equal to
//! samples, keeps scikit-image's vertex set and tie handling). Its range check (a level outside
//! the data's range is a `ValueError`) is made only when the mesh comes out empty, since a level
//! outside the range meshes nothing: a call with a level reads the samples once.

use crate::arrays::{self, Layout};
use crate::views::Borrowed;
use crate::{out, pools};
use isolab_algorithms::extractors::marching_cubes::{
    cell_range, larger, sample_value, FaceResolution, Frame, MarchingCubes, McOptions, NormalSource, OnIsoSamples, VertexValues,
};
use isolab_algorithms::samples::{f32_at_or_below, AnyView, GridView, SampleError};
use isolab_algorithms::sweep::slabs::{self, Parallelism};
use isolab_algorithms::{ExtractError, Extraction, Extractor, Grid, Samples, TriMesh};
use numpy::{PyUntypedArray, PyUntypedArrayMethods};
use pyo3::exceptions::{PyMemoryError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::sync::Arc;

/// What `isolab.marching_cubes` asks of the core.
pub struct Call {
    /// The level in the volume's units (`None`: the middle of its range).
    pub level: Option<f64>,
    /// Voxel spacing along numpy's axes.
    pub spacing: [f64; 3],
    /// Every `step`-th sample.
    pub step: usize,
    /// `faces` of marching cubes (`separate` for lorensen, `trilinear` for lewiner).
    pub faces: FaceResolution,
    /// `on-iso` (`exact` for lorensen, `separate` for lewiner).
    pub on_iso: OnIsoSamples,
    /// scikit-image's `gradient_direction='ascent'`.
    pub ascent: bool,
    /// scikit-image's `allow_degenerate`: with `false`, samples at the level are interpolated
    /// exactly and [`merge_degenerate`] runs.
    pub allow_degenerate: bool,
    /// Threads (`None`: the global pool).
    pub threads: Option<usize>,
    /// Bytes the output may take (`None`: the memory available to the process).
    pub memory_limit: Option<u64>,
}

/// Meshes `volume` (with `mask`, when given) and returns scikit-image's four arrays.
pub fn marching_cubes<'py>(
    py: Python<'py>,
    volume: &Bound<'py, PyUntypedArray>,
    mask: Option<&Bound<'py, PyUntypedArray>>,
    call: &Call,
) -> PyResult<Bound<'py, PyDict>> {
    if call.step == 0 {
        return Err(PyValueError::new_err("step_size must be at least one."));
    }
    let pool = pools::pool(call.threads)?;
    let shape = volume.shape().to_vec();
    let borrowed = crate::views::with_borrowed(volume, call.step, |b| mesh_view(py, b, &shape, mask, call, pool.as_ref()))?;
    if let Some(d) = borrowed {
        return Ok(d);
    }
    // A dtype or memory that cannot be read in place (64-bit integers, a view of another
    // dtype's memory): converted once into float32 samples.
    let array = arrays::read_volume(py, volume, call.step, 1.0, pool.as_deref())?;
    let view = GridView::contiguous(&array.values, array.dims).map_err(crate::value_error)?;
    let b = Borrowed { view: view.into(), layout: array.layout };
    mesh_view(py, b, &shape, mask, call, pool.as_ref())
}

fn mesh_view<'py>(
    py: Python<'py>,
    b: Borrowed<'_>,
    shape: &[usize],
    mask: Option<&Bound<'py, PyUntypedArray>>,
    call: &Call,
    threads: Option<&Arc<rayon::ThreadPool>>,
) -> PyResult<Bound<'py, PyDict>> {
    let pool = threads.map(|p| p.as_ref());
    let Borrowed { view, layout, .. } = b;
    let step = call.step;
    let dims = view.dims();
    if dims.iter().any(|&n| n < 2) {
        return Err(PyValueError::new_err(format!(
            "step_size {step} leaves fewer than 2 samples along an axis of a {shape:?} volume"
        )));
    }
    let view = view.negated();
    let grid = Grid { origin: glam::Vec3::ZERO, spacing: 1.0, dims };
    let level = match call.level {
        Some(l) => l,
        None => {
            let r = py.allow_threads(|| pools::install(pool, || view.range()));
            if let Some((at, value)) = r.non_finite {
                return Err(non_finite(at, -value, layout, step));
            }
            // The volume's min and max are minus the negated view's max and min.
            f64::from(0.5f32 * (-r.max + -r.min))
        }
    };
    let mask = mask.map(|m| arrays::read_mask(py, m, step, layout, pool)).transpose()?;
    // Our winding turns toward decreasing values in isolab's (x, y, z); C order mirrors it into
    // numpy's (i, j, k), where scikit-image's descent winds toward increasing values.
    let flip = (layout == Layout::Fortran) != call.ascent;
    let axes = if layout == Layout::C { [2, 1, 0] } else { [0, 1, 2] };
    let scale = call.spacing.map(|s| (s * step as f64) as f32);
    let frame = Frame { axes, scale, flip };
    let options = McOptions {
        normals: NormalSource::SampleGradient,
        parallelism: if call.threads == Some(1) { Parallelism::Serial } else { Parallelism::Rayon },
        // Without degenerate triangles, coincident vertices are merged as scikit-image merges
        // them, which needs vertices exactly where scikit-image puts them.
        on_iso: if call.allow_degenerate { call.on_iso } else { OnIsoSamples::Exact },
        faces: call.faces,
        // With a mask, triangles are kept by cell in the lattice's frame, then placed.
        frame: if mask.is_some() { Frame::default() } else { frame },
        values: if mask.is_some() { VertexValues::None } else { VertexValues::CellRange },
    };
    let iso = -f32_at_or_below(level);
    let samples = Samples::borrowed(grid, view, iso).map_err(crate::value_error)?;
    let mc = MarchingCubes::new(options);
    // The slabs are broadcast to the pool's threads from this thread (see `slabs::on_pool`).
    let extracted = py.allow_threads(|| {
        let memory_limit = call.memory_limit.or_else(isolab_pipeline::available_memory);
        let mut extraction = Extraction { memory_limit, ..Extraction::default() };
        slabs::on_pool(threads, || mc.extract(&samples, &mut extraction))?;
        if let Some(mask) = mask.as_deref() {
            pools::install(pool, || masked(&mut extraction, &grid, view, iso, mask, frame));
        }
        if !call.allow_degenerate {
            merge_degenerate(&mut extraction);
        }
        Ok::<_, ExtractError>(extraction)
    });
    let extraction = match extracted {
        Ok(e) => e,
        Err(ExtractError::Samples(SampleError::NonFinite { index, value, .. })) => {
            let [nx, ny, _] = dims;
            return Err(non_finite([index % nx, index / nx % ny, index / (nx * ny)], -value, layout, step));
        }
        Err(e @ ExtractError::OverMemory { .. }) => return Err(PyMemoryError::new_err(e.to_string())),
        Err(e) => return Err(crate::value_error(e)),
    };
    if extraction.surface.positions.is_empty() && call.level.is_some() {
        // Nothing meshed: a level outside the data's range is scikit-image's ValueError.
        let r = py.allow_threads(|| pools::install(pool, || view.range()));
        let (min, max) = (f64::from(-r.max), f64::from(-r.min));
        if level < min || level > max {
            return Err(PyValueError::new_err("Surface level must be within volume data range."));
        }
    }
    let Extraction { surface, vertex_values, .. } = extraction;
    let d = PyDict::new(py);
    d.set_item("vertices", out::vec3_array(py, surface.positions)?)?;
    d.set_item("faces", out::faces_array(py, surface.triangles)?)?;
    d.set_item("normals", out::vec3_array(py, surface.normals)?)?;
    d.set_item("values", numpy::PyArray1::from_vec(py, vertex_values))?;
    Ok(d)
}

/// The error for a NaN or infinite sample at isolab's `(x, y, z)` of the stepped view.
fn non_finite(xyz: [usize; 3], value: f32, layout: Layout, step: usize) -> PyErr {
    let ijk = if layout == Layout::C { [xyz[2], xyz[1], xyz[0]] } else { xyz };
    let ijk = ijk.map(|i| i * step);
    PyValueError::new_err(format!(
        "volume{ijk:?} is {}: every sample must be finite",
        if value.is_nan() { "NaN" } else { "infinite" }
    ))
}

/// Keeps the triangles of the cells the mask keeps ([`out::keep_masked_cells`]), gives each
/// vertex the largest range of the cells whose triangles use it, then places the mesh in the
/// frame.
fn masked(extraction: &mut Extraction, grid: &Grid, view: AnyView<'_>, iso: f32, mask: &[bool], frame: Frame) {
    let mesh = &mut extraction.surface;
    out::keep_masked_cells(mesh, grid, mask);
    let mut values = vec![0.0f32; mesh.positions.len()];
    isolab_algorithms::with_view!(view, v => {
        for &t in &mesh.triangles {
            let range = cell_range(&v, out::triangle_cell(mesh, t, grid), iso);
            for i in t {
                let slot = &mut values[i as usize];
                *slot = larger(*slot, range);
            }
        }
        // A vertex on a sample reads every cell around the sample, as unmasked.
        for (p, slot) in mesh.positions.iter().zip(&mut values) {
            if p.to_array().iter().all(|c| c.fract() == 0.0) {
                *slot = sample_value(&v, p.to_array().map(|c| c as usize), iso);
            }
        }
    });
    extraction.vertex_values = values;
    place(mesh, frame);
}

/// scikit-image's `allow_degenerate=False`: every triangle with two vertices at one position is
/// dropped and those vertices merged into the first of them (transitively, as scikit-image's
/// `remove_degenerate_faces` does); then the vertices no triangle uses are dropped too (which
/// scikit-image keeps), keeping the others' order, their normals and values with them.
fn merge_degenerate(extraction: &mut Extraction) {
    let mesh = &mut extraction.surface;
    let mut root: Vec<u32> = (0..mesh.positions.len() as u32).collect();
    fn find(root: &mut [u32], mut v: u32) -> u32 {
        while root[v as usize] != v {
            let up = root[root[v as usize] as usize];
            root[v as usize] = up;
            v = up;
        }
        v
    }
    let union = |root: &mut Vec<u32>, a: u32, b: u32| {
        let (ra, rb) = (find(root, a), find(root, b));
        let (keep, gone) = (ra.min(rb), ra.max(rb));
        root[gone as usize] = keep;
    };
    let p = &mesh.positions;
    mesh.triangles.retain(|&[a, b, c]| {
        let (pa, pb, pc) = (p[a as usize], p[b as usize], p[c as usize]);
        let degenerate = pa == pb || pa == pc || pb == pc;
        if pa == pb {
            union(&mut root, a, b);
        }
        if pa == pc {
            union(&mut root, a, c);
        }
        if pb == pc {
            union(&mut root, b, c);
        }
        !degenerate
    });
    for t in &mut mesh.triangles {
        *t = t.map(|v| find(&mut root, v));
    }
    // Renumber the vertices kept triangles use, in their order.
    let mut new_index = vec![u32::MAX; mesh.positions.len()];
    for t in &mesh.triangles {
        for &v in t {
            new_index[v as usize] = 0;
        }
    }
    for (next, slot) in new_index.iter_mut().filter(|s| **s == 0).enumerate() {
        *slot = next as u32;
    }
    fn keep_used<T: Copy>(items: &mut Vec<T>, new_index: &[u32]) {
        if items.len() == new_index.len() {
            *items = items.iter().zip(new_index).filter(|(_, &n)| n != u32::MAX).map(|(&x, _)| x).collect();
        }
    }
    keep_used(&mut mesh.positions, &new_index);
    keep_used(&mut mesh.normals, &new_index);
    keep_used(&mut extraction.vertex_values, &new_index);
    for t in &mut mesh.triangles {
        *t = t.map(|v| new_index[v as usize]);
    }
}

/// A mesh in the lattice's frame moved into `frame`.
fn place(mesh: &mut TriMesh, frame: Frame) {
    for p in &mut mesh.positions {
        *p = frame.place(*p);
    }
    for n in &mut mesh.normals {
        *n = frame.turn(*n);
    }
    for t in &mut mesh.triangles {
        *t = frame.wind(*t);
    }
}
