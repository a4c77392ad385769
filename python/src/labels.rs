//! `isolab.mesh_labels`: a label map (a numpy array of integer labels, read in place when it is
//! uint8, uint16 or uint32 and contiguous; or a volume file) to one mesh per label through the
//! pipeline's label run, the one `isolab labels` runs.

use std::collections::BTreeMap;

use isolab_pipeline::labels::{self, LabelConfig, LabelInput, LabelOutcome, LabelSamples, LabelValues, LabelVolume};
use numpy::{PyArrayDyn, PyArrayMethods, PyUntypedArray, PyUntypedArrayMethods};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::arrays::{self, Layout};
use crate::{out, pools, run_error, value_error, Run};

/// Meshes a label map: `data` is a 3-D integer (or bool) array, or a path to a volume file.
/// Returns a dict with each label's vertices and faces (world coordinates), the interface
/// surface with its label pairs, per-label metrics as JSON, notes and the missing labels.
#[pyfunction]
#[allow(clippy::too_many_arguments)]
#[pyo3(signature = (data, affine, select, algorithm, options, threads))]
pub fn mesh_labels<'py>(
    py: Python<'py>,
    data: &Bound<'py, PyAny>,
    affine: Option<[[f64; 4]; 4]>,
    select: Option<Vec<u32>>,
    algorithm: String,
    options: Option<BTreeMap<String, String>>,
    threads: Option<usize>,
) -> PyResult<Bound<'py, PyDict>> {
    let config = LabelConfig { algorithm, options: crate::options_from(options), select, space: Default::default() };
    let pool = pools::pool(threads)?;
    let outcome = if let Ok(array) = data.downcast::<PyUntypedArray>() {
        mesh_array(py, array, affine, &config, pool.as_deref())?
    } else {
        let path: std::path::PathBuf = data.extract()?;
        py.allow_threads(|| {
            pools::install(pool.as_deref(), || {
                let volume = LabelVolume::read(&path, None)?;
                labels::mesh_labels(&volume, &config)
            })
        })
        .map_err(run_error)?
    };
    to_python(py, outcome, &config.algorithm)
}

fn mesh_array(
    py: Python<'_>,
    array: &Bound<'_, PyUntypedArray>,
    affine: Option<[[f64; 4]; 4]>,
    config: &LabelConfig,
    pool: Option<&rayon::ThreadPool>,
) -> PyResult<LabelOutcome> {
    if array.ndim() != 3 {
        return Err(PyValueError::new_err(format!(
            "the label map must be a 3-D array; this one has {} dimensions",
            array.ndim()
        )));
    }
    let shape = [array.shape()[0], array.shape()[1], array.shape()[2]];
    let fortran = !array.is_c_contiguous() && array.is_fortran_contiguous();
    let contiguous = array.is_c_contiguous() || fortran;
    let (dims, layout) = if fortran { (shape, Layout::Fortran) } else { ([shape[2], shape[1], shape[0]], Layout::C) };
    let to_world = arrays::index_to_world(affine, layout).map_err(value_error)?;
    macro_rules! borrowed {
        ($($t:ty => $v:ident),*) => {$(
            if let Ok(a) = array.downcast::<PyArrayDyn<$t>>() {
                if contiguous {
                    let ro = a.try_readonly().map_err(|e| PyValueError::new_err(format!("the label map cannot be read: {e}")))?;
                    let slice = ro.as_slice().map_err(value_error)?;
                    return run(py, LabelSamples::$v(slice), dims, to_world, config, pool);
                }
                let ro = a.try_readonly().map_err(|e| PyValueError::new_err(format!("the label map cannot be read: {e}")))?;
                let values: Vec<u32> = ro.as_array().iter().map(|&v| u32::from(v)).collect();
                return run(py, LabelValues::narrowest(values).as_slice(), dims, to_world, config, pool);
            }
        )*};
    }
    borrowed!(u8 => U8, u16 => U16, u32 => U32);
    // Other integer types: every value must be a label (0 to 2^32 - 1); C order when copied.
    macro_rules! converted {
        ($($t:ty),*) => {$(
            if let Ok(a) = array.downcast::<PyArrayDyn<$t>>() {
                let ro = a.try_readonly().map_err(|e| PyValueError::new_err(format!("the label map cannot be read: {e}")))?;
                // Memory order when contiguous (as `dims` and `layout` say), else C order.
                let (values, dims, layout) = match ro.as_slice() {
                    Ok(slice) => (to_labels(slice.iter().copied())?, dims, layout),
                    Err(_) => (to_labels(ro.as_array().iter().copied())?, [shape[2], shape[1], shape[0]], Layout::C),
                };
                let to_world = arrays::index_to_world(affine, layout).map_err(value_error)?;
                return run(py, LabelValues::narrowest(values).as_slice(), dims, to_world, config, pool);
            }
        )*};
    }
    converted!(i8, i16, i32, i64, u64);
    if let Ok(a) = array.downcast::<PyArrayDyn<bool>>() {
        let ro = a.try_readonly().map_err(|e| PyValueError::new_err(format!("the label map cannot be read: {e}")))?;
        let values: Vec<u8> = ro.as_array().iter().map(|&b| u8::from(b)).collect();
        let to_world = arrays::index_to_world(affine, Layout::C).map_err(value_error)?;
        return run(py, LabelSamples::U8(&values), [shape[2], shape[1], shape[0]], to_world, config, pool);
    }
    Err(PyTypeError::new_err(not_labels_message(&array.dtype().to_string())))
}

/// Why an array of `dtype` is not a label map, with what to do.
pub(crate) fn not_labels_message(dtype: &str) -> String {
    format!(
        "a label map holds integer labels, but this array's dtype is {dtype}: an intensity volume is meshed at a level \
         with isolab.extract or isolab.marching_cubes; labels stored as floats convert with .astype(np.uint16)"
    )
}

/// Integers as labels: each from 0 to 2^32 - 1, or an error naming the first that is not.
pub(crate) fn to_labels<T: Copy + std::fmt::Display>(values: impl Iterator<Item = T>) -> PyResult<Vec<u32>>
where
    u32: TryFrom<T>,
{
    values
        .enumerate()
        .map(|(i, v)| {
            u32::try_from(v).map_err(|_| {
                PyValueError::new_err(format!(
                    "labels are whole numbers from 0 to 4294967295, but sample {i} (in memory order) is {v}"
                ))
            })
        })
        .collect()
}

fn run(
    py: Python<'_>,
    values: LabelSamples<'_>,
    dims: [usize; 3],
    index_to_world: glam::DAffine3,
    config: &LabelConfig,
    pool: Option<&rayon::ThreadPool>,
) -> PyResult<LabelOutcome> {
    let input = LabelInput { name: "array", dims, values, index_to_world, anatomical: false };
    py.allow_threads(|| pools::install(pool, || labels::mesh_label_input(input, config))).map_err(run_error)
}

/// The outcome as Python objects; no mesh metric is computed (`Mesh.metrics()` measures on
/// demand): each mesh's stats are its label, counts and the triangles it shares with each
/// neighbour.
pub(crate) fn to_python<'py>(py: Python<'py>, outcome: LabelOutcome, algorithm: &str) -> PyResult<Bound<'py, PyDict>> {
    let neighbours = labels::neighbours(&outcome.surface);
    let d = PyDict::new(py);
    let meshes = PyDict::new(py);
    for (label, mesh) in outcome.meshes {
        let one = PyDict::new(py);
        let report = serde_json::json!({
            "algorithm": algorithm,
            "label": label,
            "samples": outcome.counts.get(&label).copied().unwrap_or(0),
            "vertices": mesh.positions.len(),
            "triangles": mesh.triangles.len(),
            "neighbours": neighbours.get(&label).cloned().unwrap_or_default(),
        });
        one.set_item("vertices", out::vec3_array(py, mesh.positions)?)?;
        one.set_item("faces", out::faces_array(py, mesh.triangles)?)?;
        one.set_item("run", Run::without_truth(report.to_string()))?;
        meshes.set_item(label, one)?;
    }
    d.set_item("meshes", meshes)?;
    let surface = outcome.surface;
    d.set_item("vertices", out::vec3_array(py, surface.mesh.positions)?)?;
    d.set_item("faces", out::faces_array(py, surface.mesh.triangles)?)?;
    d.set_item("pairs", out::u32_rows(py, surface.pairs)?)?;
    d.set_item("tetrahedra", out::quads_array(py, &surface.tetrahedra)?)?;
    d.set_item("tetrahedron_labels", numpy::PyArray1::from_vec(py, surface.tetrahedron_labels))?;
    d.set_item("missing", outcome.missing)?;
    d.set_item("notes", outcome.notes)?;
    d.set_item("extract_ms", outcome.extract_ms)?;
    d.set_item("space", outcome.space_tag)?;
    Ok(d)
}
