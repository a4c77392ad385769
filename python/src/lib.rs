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

use isolab_algorithms::{extractors, fields as builtin_fields, Options, TetMesh, TriMesh};
use isolab_io::volume::Inside;
use isolab_pipeline::{measure, run, run_input, Input, LatticeKind, Measure, RunConfig, RunError, Truth, VolumeGrid};
use numpy::PyUntypedArray;
use pyo3::exceptions::{PyMemoryError, PyOSError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::collections::BTreeMap;
use std::path::Path;

mod arrays;
mod blocks;
mod drop_in;
mod functions;
mod label_blocks;
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
/// guarantees.
#[pyfunction]
fn algorithms(py: Python<'_>) -> PyResult<Vec<Bound<'_, PyDict>>> {
    let mut out = Vec::new();
    for e in extractors::INFOS {
        let d = PyDict::new(py);
        d.set_item("name", e.name)?;
        d.set_item("kind", "extractor")?;
        d.set_item("description", e.description)?;
        d.set_item("options", e.options.to_vec())?;
        let g = PyDict::new(py);
        g.set_item("lattices", e.guarantees.lattices())?;
        g.set_item("closed", e.guarantees.closed)?;
        g.set_item("manifold", e.guarantees.manifold)?;
        g.set_item("outward", e.guarantees.outward)?;
        g.set_item("intersection_free", e.guarantees.intersection_free)?;
        g.set_item("trilinear_topology", e.guarantees.trilinear_topology)?;
        g.set_item("keeps_small_parts", e.guarantees.keeps_small_parts)?;
        // Volume extractors' dihedral interval in degrees, [min, max], or None.
        g.set_item("dihedral_degrees", e.guarantees.dihedral.map(|d| vec![d.min_degrees, d.max_degrees]))?;
        d.set_item("guarantees", g)?;
        // How it reads a numpy array: in place ("borrowed"), or "copies: REASON".
        d.set_item("samples", e.samples.describe())?;
        // How it meshes in blocks (isolab.dask, chunk=) with its default options.
        let chunking = extractors::build(e.name, &Options::new()).ok().flatten().map(|x| x.chunking());
        let (kind, apron) = match chunking {
            Some(isolab_algorithms::Chunking::CellLocal) => ("cell-local", 0),
            Some(isolab_algorithms::Chunking::Apron(a)) => ("apron", a),
            _ => ("unsupported", 0),
        };
        d.set_item("chunking", kind)?;
        d.set_item("apron", apron)?;
        out.push(d);
    }
    for p in isolab_algorithms::post::POST_INFOS {
        let d = PyDict::new(py);
        d.set_item("name", p.name)?;
        d.set_item("kind", "post-process")?;
        d.set_item("description", p.description)?;
        d.set_item("options", p.options.to_vec())?;
        let g = PyDict::new(py);
        g.set_item("keeps_closed_manifold", p.guarantees.keeps_closed_manifold)?;
        g.set_item("keeps_outward", p.guarantees.keeps_outward)?;
        g.set_item("adds_no_intersection", p.guarantees.adds_no_intersection)?;
        g.set_item("keeps_every_component", p.guarantees.keeps_every_component)?;
        d.set_item("guarantees", g)?;
        out.push(d);
    }
    for e in isolab_algorithms::labels::LABEL_INFOS {
        let d = PyDict::new(py);
        d.set_item("name", e.name)?;
        d.set_item("kind", "labels")?;
        d.set_item("description", e.description)?;
        d.set_item("options", e.options.to_vec())?;
        let g = PyDict::new(py);
        g.set_item("closed", e.guarantees.closed)?;
        g.set_item("manifold", e.guarantees.manifold)?;
        g.set_item("outward", e.guarantees.outward)?;
        d.set_item("guarantees", g)?;
        out.push(d);
    }
    Ok(out)
}

/// The display colour of every material id (what the CLI writes as vertex colours).
#[pyfunction]
fn material_colours() -> Vec<[u8; 3]> {
    (0..=255u8).map(isolab_algorithms::materials::colour).collect()
}

/// The built-in fields: `(name, description)`.
#[pyfunction]
fn fields() -> Vec<(&'static str, &'static str)> {
    builtin_fields::registry().iter().map(|f| (f.name, f.description)).collect()
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
    let inside = match inside.as_deref() {
        None => None,
        Some("below") => Some(Inside::Below),
        Some("above") => Some(Inside::Above),
        Some(other) => return Err(PyValueError::new_err(format!("inside '{other}': expected 'below' or 'above'"))),
    };
    let lattice = match lattice.as_deref() {
        None | Some("cubic") => LatticeKind::Cubic,
        Some("bcc") => LatticeKind::Bcc,
        Some(other) => return Err(PyValueError::new_err(format!("lattice '{other}': expected 'cubic' or 'bcc'"))),
    };
    let mut config = RunConfig::new(&algorithm, "", resolution.unwrap_or(64));
    config.dims = dims;
    config.lattice = lattice;
    config.iso = level.map(|l| l as f32);
    config.inside = inside;
    config.volume_grid = if resolution.is_some() || dims.is_some() { VolumeGrid::Resampled } else { VolumeGrid::Native };
    config.seed = seed.unwrap_or(builtin_fields::DEFAULT_SEED);
    config.post = post;
    config.options = options_from(options);
    config.chunk = chunk;
    config.materials = materials;
    config.measure = Measure::Counts;
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
        config.field = data.extract::<String>().or_else(|_| data.str().map(|s| s.to_string()))?;
        // A built-in or mesh field above 512³ samples is sampled near its surface where its
        // Lipschitz bound certifies the same mesh (`isolab_pipeline::sparse`), as on the CLI.
        config.sparse = isolab_pipeline::Sparse::Auto;
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

/// Writes a mesh given as arrays in the format `path`'s extension names (`.obj`, `.ply`,
/// `.stl`, `.glb`, `.gltf`), atomically; tetrahedra, when given, beside it as `.vtk`.
#[pyfunction]
#[pyo3(signature = (path, vertices, faces, normals=None, colours=None, tet_vertices=None, tetrahedra=None, space=None))]
#[allow(clippy::too_many_arguments)]
fn save(
    py: Python<'_>,
    path: std::path::PathBuf,
    vertices: &Bound<'_, PyAny>,
    faces: &Bound<'_, PyAny>,
    normals: Option<&Bound<'_, PyAny>>,
    colours: Option<Vec<[u8; 3]>>,
    tet_vertices: Option<&Bound<'_, PyAny>>,
    tetrahedra: Option<&Bound<'_, PyAny>>,
    space: Option<String>,
) -> PyResult<()> {
    let surface = arrays::tri_mesh(vertices, faces, normals)?;
    if isolab_io::MeshFormat::from_extension(&path).is_none() {
        return Err(run_error(isolab_io::IoError::UnknownFormat { path }.into()));
    }
    let volume = match (tet_vertices, tetrahedra) {
        (Some(v), Some(t)) => Some(arrays::tet_mesh(v, t)?),
        _ => None,
    };
    py.allow_threads(|| {
        let extras = isolab_io::MeshExtras { colours: colours.as_deref(), space: space.as_deref() };
        isolab_io::write_mesh_with(&path, &surface, extras)?;
        if let Some(volume) = volume.filter(|v| !v.tetrahedra.is_empty()) {
            isolab_io::write_vtk_tets(&isolab_io::tetrahedra_path(&path), &volume, space.as_deref())?;
        }
        Ok::<(), isolab_io::IoError>(())
    })
    .map_err(|e| run_error(e.into()))
}

/// Reads a volume file as `("volume", array, affine)` (the array in numpy index order `[i, j,
/// k]`, Fortran-ordered over isolab's own buffer, no copy; the 4 x 4 index-to-world affine, RAS
/// for anatomical files) or a mesh file as `("mesh", vertices, faces)`.
#[pyfunction]
fn load<'py>(py: Python<'py>, path: std::path::PathBuf) -> PyResult<Bound<'py, pyo3::types::PyTuple>> {
    let bytes = isolab_io::read_bytes(&path).map_err(|e| run_error(e.into()))?;
    if isolab_io::volume::detect(&path, &bytes).is_some() {
        let file = py
            .allow_threads(|| isolab_io::volume::read_volume_bytes(&bytes, &path, Default::default()))
            .map_err(|e| run_error(e.into()))?;
        let volume = &file.volume;
        let array = out::fortran_volume(py, volume.values_f32().into_owned(), volume.dims)?;
        let affine = out::affine_rows(&volume.index_to_world);
        return ("volume", array, affine).into_pyobject(py);
    }
    let mesh = py.allow_threads(|| read_mesh_bytes(&bytes, &path)).map_err(|e| run_error(e.into()))?;
    ("mesh", out::vec3_array(py, mesh.positions)?, out::faces_array(py, mesh.triangles)?).into_pyobject(py)
}

fn read_mesh_bytes(bytes: &[u8], path: &Path) -> Result<TriMesh, isolab_io::IoError> {
    match isolab_io::MeshFormat::detect(bytes, path) {
        isolab_io::MeshFormat::Glb | isolab_io::MeshFormat::Gltf => isolab_io::gltf::parse_gltf_beside(bytes, path),
        _ => isolab_io::parse_mesh(bytes, path, isolab_io::Coordinates::Any),
    }
}

/// The native module.
#[pymodule]
fn _isolab(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(algorithms, m)?)?;
    m.add_function(wrap_pyfunction!(fields, m)?)?;
    m.add_function(wrap_pyfunction!(material_colours, m)?)?;
    m.add_function(wrap_pyfunction!(marching_cubes, m)?)?;
    m.add_function(wrap_pyfunction!(extract, m)?)?;
    m.add_function(wrap_pyfunction!(extract_function, m)?)?;
    m.add_function(wrap_pyfunction!(metrics, m)?)?;
    m.add_function(wrap_pyfunction!(save, m)?)?;
    m.add_function(wrap_pyfunction!(load, m)?)?;
    m.add_function(wrap_pyfunction!(labels::mesh_labels, m)?)?;
    m.add_function(wrap_pyfunction!(blocks::block_plan, m)?)?;
    m.add_function(wrap_pyfunction!(blocks::mesh_block, m)?)?;
    m.add_function(wrap_pyfunction!(blocks::weld_fragments, m)?)?;
    m.add_function(wrap_pyfunction!(blocks::field_block, m)?)?;
    m.add_function(wrap_pyfunction!(blocks::skipped_fragment, m)?)?;
    m.add_function(wrap_pyfunction!(label_blocks::label_block_plan, m)?)?;
    m.add_function(wrap_pyfunction!(label_blocks::mesh_label_block, m)?)?;
    m.add_function(wrap_pyfunction!(label_blocks::weld_label_fragments, m)?)?;
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
