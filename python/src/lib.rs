//! # isolab's native Python module (`isolab._isolab`)
//!
//! What the `isolab` package (`python/python/isolab/__init__.py`, which holds the signatures,
//! argument checks and docstrings users read) calls: numpy arrays in (`arrays`), the one run of
//! `isolab-pipeline` or a lean marching cubes for the scikit-image drop-in, meshes out as numpy
//! arrays (`out`), blocks of a volume for `isolab.dask` (`blocks`), metrics, files. Every call releases the GIL while it works and runs on the
//! global rayon pool or, with `threads=N`, on a kept pool of N threads.
//!
//! Errors are the pipeline's messages (the CLI prints the same), raised as `ValueError` (bad
//! names, options or data), `OSError` (files) or `MemoryError`; nothing here panics on user input.

use isolab_algorithms::{extractors, fields as builtin_fields, Options, TetMesh};
use isolab_io::volume::Inside;
use isolab_pipeline::{measure, run, run_input, Input, LatticeKind, Measure, RunConfig, RunError, Truth};
use numpy::PyUntypedArray;
use pyo3::exceptions::{PyMemoryError, PyOSError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::collections::BTreeMap;

/// Every allocation the extension makes (the meshes it hands to numpy among them, freed by it
/// again when numpy drops them) goes through mimalloc: measured on the MNI tissue map, glibc's
/// malloc gave each call's large buffers back to the system and faulted them in again on the
/// next call.
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

mod arrays;
mod blocks;
mod drop_in;
mod functions;
mod labels;
mod neuroglancer;
mod out;
mod pools;
mod views;

use arrays::{read_volume, VolumeArray};

/// A pipeline error as the Python exception a user expects, with the CLI's message.
pub(crate) fn run_error(e: RunError) -> PyErr {
    match e {
        RunError::Io(isolab_io::IoError::UnknownFormat { .. }) => PyValueError::new_err(e.to_string()),
        RunError::Io(_) => PyOSError::new_err(e.to_string()),
        RunError::OutOfMemory { .. } | RunError::Extract(isolab_algorithms::ExtractError::OverMemory { .. }) => {
            PyMemoryError::new_err(e.to_string())
        }
        _ => PyValueError::new_err(e.to_string()),
    }
}

pub(crate) fn value_error(e: impl std::fmt::Display) -> PyErr {
    PyValueError::new_err(e.to_string())
}

/// The registered extractors, post-processes and label extractors, with their options and
/// guarantees, as the JSON of `isolab_pipeline::registry::listing` (what `isolab list` prints).
#[pyfunction]
fn algorithms() -> PyResult<String> {
    serde_json::to_string(&isolab_pipeline::registry::listing()).map_err(value_error)
}

/// The built-in fields: `(name, description)`.
#[pyfunction]
fn fields() -> Vec<(&'static str, &'static str)> {
    isolab_pipeline::registry::field_listing().into_iter().map(|f| (f.name, f.description)).collect()
}

/// `parallelism=serial` for an extractor that has the option (what `threads=1` means).
pub(crate) fn serial_where_possible(options: &mut Options, algorithm: &str) {
    if extractors::INFOS.iter().any(|e| e.name == algorithm && e.options.contains(&"parallelism")) {
        options.set("parallelism", "serial");
    }
}

/// Options from a `{name: value}` mapping (values as the CLI's `--set NAME=VALUE` text).
pub(crate) fn options_from(options: Option<BTreeMap<String, String>>) -> Options {
    let mut o = Options::new();
    for (k, v) in options.unwrap_or_default() {
        o.set(&k, &v);
    }
    o
}

/// The scikit-image-compatible marching cubes core ([`drop_in`]): the volume meshed where it
/// lies by `marching-cubes` with `faces` (separate, trilinear) and `on_iso` (exact, separate).
/// Returns vertices in numpy index order times `spacing * step`, faces wound as scikit-image
/// winds them (`ascent` reverses), unit normals toward decreasing values, and each vertex's value
/// ([`isolab_algorithms::extractors::marching_cubes::VertexValues::CellRange`]).
#[pyfunction]
#[allow(clippy::too_many_arguments)]
#[pyo3(signature = (volume, level, spacing, step, faces, on_iso, ascent, allow_degenerate, mask, threads, memory_limit))]
fn marching_cubes<'py>(
    py: Python<'py>,
    volume: &Bound<'py, PyUntypedArray>,
    level: Option<f64>,
    spacing: [f64; 3],
    step: usize,
    faces: &str,
    on_iso: &str,
    ascent: bool,
    allow_degenerate: bool,
    mask: Option<&Bound<'py, PyUntypedArray>>,
    threads: Option<usize>,
    memory_limit: Option<u64>,
) -> PyResult<Bound<'py, PyDict>> {
    use isolab_algorithms::extractors::marching_cubes::{FaceResolution, OnIsoSamples};
    let faces = match faces {
        "separate" => FaceResolution::SeparateInside,
        "decider" => FaceResolution::AsymptoticDecider,
        "trilinear" => FaceResolution::Trilinear,
        other => return Err(value_error(format!("faces must be separate, decider or trilinear, not {other:?}"))),
    };
    let on_iso = match on_iso {
        "exact" => OnIsoSamples::Exact,
        "separate" => OnIsoSamples::Separate,
        other => return Err(value_error(format!("on_iso must be exact or separate, not {other:?}"))),
    };
    let call = drop_in::Call { level, spacing, step, faces, on_iso, ascent, allow_degenerate, threads, memory_limit };
    drop_in::marching_cubes(py, volume, mask, &call)
}

/// A finished run, kept for its true surface (what `Mesh.metrics()` measures against) and its
/// JSON report.
#[pyclass(module = "isolab._isolab", frozen)]
pub(crate) struct Run {
    truth: Option<Truth>,
    report: String,
}

impl Run {
    /// A run with no true surface to measure against (a welded mesh of blocks).
    pub(crate) fn without_truth(report: String) -> Run {
        Run { truth: None, report }
    }
}

#[pymethods]
impl Run {
    /// The run's JSON report (the CLI's, without mesh metrics).
    fn report(&self) -> &str {
        &self.report
    }
}

/// Runs an extractor on a numpy array (`data`: meshed on its own grid, placed by `affine`, a
/// 4 x 4 index-to-world matrix in numpy index order) or on what a string names (a built-in
/// field sampled at `resolution` or `dims`, or a mesh or volume file), through the CLI's
/// pipeline. Returns the meshes as arrays and the run.
#[pyfunction]
#[allow(clippy::too_many_arguments)]
#[pyo3(signature = (data, level, algorithm, affine, inside, options, post, threads, resolution, dims, lattice, seed, chunk, materials))]
fn extract<'py>(
    py: Python<'py>,
    data: &Bound<'py, PyAny>,
    level: Option<f64>,
    algorithm: String,
    affine: Option<[[f64; 4]; 4]>,
    inside: Option<String>,
    options: Option<BTreeMap<String, String>>,
    post: Vec<String>,
    threads: Option<usize>,
    resolution: Option<usize>,
    dims: Option<[usize; 3]>,
    lattice: Option<String>,
    seed: Option<i32>,
    chunk: Option<usize>,
    materials: bool,
) -> PyResult<Bound<'py, PyDict>> {
    let inside = inside.map(|word| word.parse::<Inside>()).transpose().map_err(value_error)?;
    let lattice = lattice.map(|word| word.parse::<LatticeKind>()).transpose().map_err(value_error)?;
    let mut config = RunConfig::builder(&algorithm, "")
        .resolution(resolution)
        .dims(dims)
        .lattice(lattice.unwrap_or_default())
        .iso(level.map(|l| l as f32))
        .inside(inside)
        .seed(seed)
        .post(post)
        .options(options.unwrap_or_default())
        .chunk(chunk)
        .materials(materials)
        .build();
    if threads == Some(1) {
        serial_where_possible(&mut config.options, &algorithm);
    }
    let pool = pools::pool(threads)?;
    let outcome = if let Ok(array) = data.downcast::<PyUntypedArray>() {
        // An array's iso-value is 0 unless given (not the Otsu threshold a scan file gets).
        config.iso = Some(config.iso.unwrap_or(0.0));
        // One copy at most: in the array's own dtype for an extractor that reads samples in
        // place (the samples share it), as float32 for one that needs them so.
        let in_place = extractors::INFOS
            .iter()
            .any(|i| i.name == config.algorithm && i.samples == isolab_algorithms::extract::SampleAccess::Borrowed);
        let typed = if in_place {
            views::with_borrowed(array, 1, |b| {
                let (dims, dtype) = (b.view.dims(), b.view.dtype());
                Ok((py.allow_threads(|| b.view.to_stored()), dims, b.layout, dtype))
            })?
        } else {
            None
        };
        let (values, dims, layout, dtype) = match typed {
            Some(t) => t,
            None => {
                let VolumeArray { values, dims, layout, dtype } = read_volume(py, array, 1, 1.0, pool.as_deref())?;
                (values.into(), dims, layout, dtype)
            }
        };
        let to_world = arrays::index_to_world(affine, layout).map_err(value_error)?;
        py.allow_threads(|| {
            pools::install(pool.as_deref(), || {
                let v = builtin_fields::Volume::stored("array", dims, values, to_world).map_err(|e| run_error(e.into()))?;
                run_input(&config, Input::from_volume(v, "numpy", dtype, Inside::Below)).map_err(run_error)
            })
        })?
    } else {
        // A built-in or mesh field above 512³ samples is sampled near its surface where its
        // Lipschitz bound certifies the same mesh (`isolab_pipeline::sparse`, the builder's
        // default), as on the CLI.
        config.field = data.extract::<String>().or_else(|_| data.str().map(|s| s.to_string()))?;
        py.allow_threads(|| pools::install(pool.as_deref(), || run(&config).map_err(run_error)))?
    };
    let d = PyDict::new(py);
    let mut outcome = outcome;
    let surface = std::mem::take(&mut outcome.extraction.surface);
    d.set_item("vertices", out::vec3_array(py, surface.positions)?)?;
    d.set_item("faces", out::faces_array(py, surface.triangles)?)?;
    d.set_item("normals", out::vec3_array(py, surface.normals)?)?;
    if !outcome.vertex_materials.is_empty() {
        d.set_item("materials", numpy::PyArray1::from_slice(py, &outcome.vertex_materials))?;
    }
    let volume = std::mem::take(&mut outcome.extraction.volume);
    if !volume.tetrahedra.is_empty() {
        d.set_item("tet_vertices", out::vec3_array(py, volume.positions)?)?;
        d.set_item("tetrahedra", out::quads_array(py, &volume.tetrahedra)?)?;
    }
    d.set_item("space", outcome.space_tag)?;
    d.set_item("warnings", outcome.report.warnings.clone())?;
    d.set_item("notes", outcome.notes.clone())?;
    let report = serde_json::to_string(&outcome.report).map_err(value_error)?;
    d.set_item("run", Run { truth: outcome.truth, report })?;
    Ok(d)
}

/// Meshes the field a wrapped Python callable gives (`isolab.extract(fn, ...)`): samples at
/// `bounds.0 + index * h`, `resolution` along the longest side, evaluated in batches of at most
/// `batch` points only in the blocks of `chunk` cells that pruning keeps (a `lipschitz` bound
/// certifies; without one, the sign-change heuristic; every block with `sparse=False`).
#[pyfunction]
#[pyo3(signature = (function, level, algorithm, bounds, resolution, lipschitz, sparse, batch, chunk, options, threads))]
#[allow(clippy::too_many_arguments)]
fn extract_function<'py>(
    py: Python<'py>,
    function: Py<PyAny>,
    level: f64,
    algorithm: String,
    bounds: ([f64; 3], [f64; 3]),
    resolution: usize,
    lipschitz: Option<f64>,
    sparse: bool,
    batch: usize,
    chunk: Option<usize>,
    options: Option<BTreeMap<String, String>>,
    threads: Option<usize>,
) -> PyResult<Bound<'py, PyDict>> {
    let call = functions::FunctionCall {
        level: level as f32,
        algorithm,
        options,
        bounds,
        resolution,
        lipschitz,
        sparse,
        batch,
        chunk,
        threads,
    };
    functions::extract_function(py, function, call)
}

/// The CLI's metrics of a mesh given as arrays, as JSON: every measure, the exact
/// self-intersection test only with `self_intersections`; against `run`'s true surface when
/// given (distance of vertices to it, normal deviation), with the tetrahedra's measures when
/// `tetrahedra` are given.
#[pyfunction]
#[pyo3(signature = (vertices, faces, normals=None, tet_vertices=None, tetrahedra=None, run=None, self_intersections=true, threads=None))]
#[allow(clippy::too_many_arguments)]
fn metrics(
    py: Python<'_>,
    vertices: &Bound<'_, PyAny>,
    faces: &Bound<'_, PyAny>,
    normals: Option<&Bound<'_, PyAny>>,
    tet_vertices: Option<&Bound<'_, PyAny>>,
    tetrahedra: Option<&Bound<'_, PyAny>>,
    run: Option<&Bound<'_, Run>>,
    self_intersections: bool,
    threads: Option<usize>,
) -> PyResult<String> {
    let surface = arrays::tri_mesh(vertices, faces, normals)?;
    let volume = match (tet_vertices, tetrahedra) {
        (Some(v), Some(t)) => arrays::tet_mesh(v, t)?,
        _ => TetMesh::default(),
    };
    let truth = run.and_then(|r| r.get().truth.clone());
    let pool = pools::pool(threads)?;
    let which = if self_intersections { Measure::All } else { Measure::Metrics };
    let (m, v) = py.allow_threads(|| pools::install(pool.as_deref(), || measure(&surface, &volume, truth.as_ref(), which)));
    let mut json = serde_json::to_value(m).map_err(value_error)?;
    if let (Some(v), Some(obj)) = (v, json.as_object_mut()) {
        if let Ok(serde_json::Value::Object(extra)) = serde_json::to_value(v) {
            obj.extend(extra);
        }
    }
    serde_json::to_string(&json).map_err(value_error)
}

/// Writes a mesh given as arrays as the CLI writes a run's ([`isolab_pipeline::files::write_meshes`]):
/// in the format `path`'s extension names (`.obj`, `.ply`, `.stl`, `.glb`, `.gltf`),
/// atomically, each vertex coloured by its material when `materials` are given, tagged with
/// `space`; tetrahedra, when given, beside it as `.vtk`.
#[pyfunction]
#[pyo3(signature = (path, vertices, faces, normals=None, materials=None, tet_vertices=None, tetrahedra=None, space=None))]
#[allow(clippy::too_many_arguments)]
fn save(
    py: Python<'_>,
    path: std::path::PathBuf,
    vertices: &Bound<'_, PyAny>,
    faces: &Bound<'_, PyAny>,
    normals: Option<&Bound<'_, PyAny>>,
    materials: Option<Vec<u8>>,
    tet_vertices: Option<&Bound<'_, PyAny>>,
    tetrahedra: Option<&Bound<'_, PyAny>>,
    space: Option<String>,
) -> PyResult<()> {
    let surface = arrays::tri_mesh(vertices, faces, normals)?;
    let volume = match (tet_vertices, tetrahedra) {
        (Some(v), Some(t)) => arrays::tet_mesh(v, t)?,
        _ => TetMesh::default(),
    };
    let materials = materials.unwrap_or_default();
    if !materials.is_empty() && materials.len() != surface.positions.len() {
        return Err(value_error(format!(
            "materials: {} values for {} vertices (one per vertex)",
            materials.len(),
            surface.positions.len()
        )));
    }
    py.allow_threads(|| isolab_pipeline::files::write_meshes(&path, &surface, &volume, &materials, space.as_deref()))
        .map_err(run_error)
}

/// Writes labelled tetrahedra (a label map's, from `lattice-cleaving`) as `isolab labels -o`
/// writes them, by `path`'s extension: `.vtk` (a `label` cell array) or `.msh` (Gmsh 2.2, a
/// physical volume per label), atomically.
#[pyfunction]
#[pyo3(signature = (path, vertices, tetrahedra, labels, space=None))]
fn save_tetrahedra(
    py: Python<'_>,
    path: std::path::PathBuf,
    vertices: &Bound<'_, PyAny>,
    tetrahedra: &Bound<'_, PyAny>,
    labels: Vec<u32>,
    space: Option<String>,
) -> PyResult<()> {
    let mesh = arrays::tet_mesh(vertices, tetrahedra)?;
    if labels.len() != mesh.tetrahedra.len() {
        return Err(value_error(format!("{} labels for {} tetrahedra (one each)", labels.len(), mesh.tetrahedra.len())));
    }
    let written =
        py.allow_threads(|| isolab_io::write_labelled_tets(&path, &mesh.positions, &mesh.tetrahedra, &labels, space.as_deref()));
    written.map_err(|e| match &e {
        isolab_io::IoError::Write { source, .. } if source.kind() == std::io::ErrorKind::InvalidInput => value_error(e),
        _ => run_error(e.into()),
    })
}

/// Reads a volume file as `("volume", array, affine)` (the array in numpy index order `[i, j,
/// k]`, Fortran-ordered over isolab's own buffer, no copy; the 4 x 4 index-to-world affine, RAS
/// for anatomical files) or a mesh file as `("mesh", vertices, faces)`: whichever the file
/// holds, decided as the CLI decides it ([`isolab_pipeline::files::read_file`]).
#[pyfunction]
fn load<'py>(py: Python<'py>, path: std::path::PathBuf) -> PyResult<Bound<'py, pyo3::types::PyTuple>> {
    use isolab_pipeline::files::{read_file, FileContents};
    let contents = py.allow_threads(|| read_file(&path, Default::default(), isolab_io::Coordinates::Any)).map_err(run_error)?;
    match contents {
        FileContents::Volume(file) => {
            let volume = &file.volume;
            let array = out::fortran_volume(py, volume.values_f32().into_owned(), volume.dims)?;
            let affine = out::affine_rows(&volume.index_to_world);
            ("volume", array, affine).into_pyobject(py)
        }
        FileContents::Mesh(mesh, _) => {
            ("mesh", out::vec3_array(py, mesh.positions)?, out::faces_array(py, mesh.triangles)?).into_pyobject(py)
        }
    }
}

/// The native module.
#[pymodule]
fn _isolab(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(algorithms, m)?)?;
    m.add_function(wrap_pyfunction!(fields, m)?)?;
    m.add_function(wrap_pyfunction!(marching_cubes, m)?)?;
    m.add_function(wrap_pyfunction!(extract, m)?)?;
    m.add_function(wrap_pyfunction!(extract_function, m)?)?;
    m.add_function(wrap_pyfunction!(metrics, m)?)?;
    m.add_function(wrap_pyfunction!(save, m)?)?;
    m.add_function(wrap_pyfunction!(save_tetrahedra, m)?)?;
    m.add_function(wrap_pyfunction!(load, m)?)?;
    m.add_function(wrap_pyfunction!(labels::mesh_labels, m)?)?;
    m.add_function(wrap_pyfunction!(blocks::volume::block_plan, m)?)?;
    m.add_function(wrap_pyfunction!(blocks::volume::mesh_block, m)?)?;
    m.add_function(wrap_pyfunction!(blocks::volume::weld_fragments, m)?)?;
    m.add_function(wrap_pyfunction!(blocks::volume::field_block, m)?)?;
    m.add_function(wrap_pyfunction!(blocks::volume::skipped_fragment, m)?)?;
    m.add_function(wrap_pyfunction!(blocks::labels::label_block_plan, m)?)?;
    m.add_function(wrap_pyfunction!(blocks::labels::mesh_label_block, m)?)?;
    m.add_function(wrap_pyfunction!(blocks::labels::weld_label_fragments, m)?)?;
    m.add_function(wrap_pyfunction!(neuroglancer::ng_plan, m)?)?;
    m.add_function(wrap_pyfunction!(neuroglancer::ng_level0, m)?)?;
    m.add_function(wrap_pyfunction!(neuroglancer::ng_coarser, m)?)?;
    m.add_function(wrap_pyfunction!(neuroglancer::ng_segments, m)?)?;
    m.add_function(wrap_pyfunction!(neuroglancer::ng_sharding, m)?)?;
    m.add_function(wrap_pyfunction!(neuroglancer::ng_shard_of, m)?)?;
    m.add_function(wrap_pyfunction!(neuroglancer::ng_shard, m)?)?;
    m.add_function(wrap_pyfunction!(neuroglancer::ng_info, m)?)?;
    m.add_function(wrap_pyfunction!(neuroglancer::ng_box_index, m)?)?;
    m.add_function(wrap_pyfunction!(neuroglancer::ng_legacy_block, m)?)?;
    m.add_function(wrap_pyfunction!(neuroglancer::ng_legacy_manifests, m)?)?;
    m.add_function(wrap_pyfunction!(neuroglancer::ng_encode_fragment, m)?)?;
    m.add_class::<Run>()?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
