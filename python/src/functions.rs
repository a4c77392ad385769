//! `isolab.extract` on a callable: the field a Python function gives, evaluated in batches of
//! world points only near its surface ([`chunks::extract_sparse`]: certified by a Lipschitz
//! bound, or the sign-change heuristic, or dense for comparison), meshed and welded in Rust with
//! the GIL released; the GIL is taken back only to call the function.
//!
//! The function is the package's wrapper around the user's callable (`isolab._batch_caller`),
//! which converts what the callable returns (numpy, `__array__`, DLPack) to a float64 vector
//! and raises `ValueError` naming the batch for a wrong length, dtype or a non-finite value.
//! An exception the callable raises comes back to Python unchanged.

use crate::{out, pools, value_error, Run};
use isolab_algorithms::chunks::{self, BatchEval, EvalError, Pruning, SparseError, SparseGrid, SparseOptions, SparseStats};
use isolab_algorithms::Extraction;
use numpy::{PyArray1, PyArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::collections::BTreeMap;

/// The wrapped Python callable as a [`BatchEval`].
struct PyEval {
    call: Py<PyAny>,
}

impl BatchEval for PyEval {
    fn eval(&mut self, points: &[[f64; 3]], out: &mut Vec<f64>) -> Result<(), EvalError> {
        Python::with_gil(|py| -> PyResult<()> {
            let flat = PyArray1::from_slice(py, points.as_flattened());
            let array = flat.reshape([points.len(), 3])?;
            let values = self.call.call1(py, (array,))?;
            let values = values.downcast_bound::<PyArray1<f64>>(py)?.try_readonly()?;
            out.clear();
            out.extend_from_slice(values.as_slice()?);
            Ok(())
        })
        .map_err(|e| Box::new(e) as EvalError)
    }
}

/// What the call asks for (`isolab.extract`'s arguments of the same names).
pub struct FunctionCall {
    /// The level; inside is below it.
    pub level: f32,
    /// The extractor's name.
    pub algorithm: String,
    /// Its options, as the CLI's `--set NAME=VALUE`.
    pub options: Option<BTreeMap<String, String>>,
    /// The grid's box: its lowest and highest corners.
    pub bounds: ([f64; 3], [f64; 3]),
    /// Samples along the box's longest side.
    pub resolution: usize,
    /// A Lipschitz bound of the field, which certifies the pruning.
    pub lipschitz: Option<f64>,
    /// `false`: every sample evaluated.
    pub sparse: bool,
    /// Points per call of the function, at most.
    pub batch: usize,
    /// Cells per block side (`None`: [`SparseOptions::default_chunk`]).
    pub chunk: Option<usize>,
    /// Threads for the meshing (`None`: the global pool).
    pub threads: Option<usize>,
}

/// Meshes `call`'s field from the wrapped callable `function`; returns the parts of an
/// `isolab.Mesh`.
pub fn extract_function<'py>(py: Python<'py>, function: Py<PyAny>, call: FunctionCall) -> PyResult<Bound<'py, PyDict>> {
    let grid = SparseGrid::from_bounds(call.bounds.0, call.bounds.1, call.resolution).map_err(value_error)?;
    if call.batch == 0 {
        return Err(PyValueError::new_err("batch must be at least 1 point"));
    }
    if let Some(l) = call.lipschitz {
        if !(l.is_finite() && l > 0.0) {
            return Err(PyValueError::new_err(format!("lipschitz must be a positive finite bound, not {l}")));
        }
    }
    let pruning = match (call.sparse, call.lipschitz) {
        (false, _) => Pruning::Dense,
        (true, Some(l)) => Pruning::Lipschitz(l),
        (true, None) => Pruning::SignChange { margin: 1 },
    };
    let extractor = crate::blocks::volume::extractor(&call.algorithm, call.options.clone(), call.threads == Some(1))?;
    let chunk = call.chunk.unwrap_or_else(|| SparseOptions::default_chunk(extractor.as_ref()));
    let options = SparseOptions { chunk, batch: call.batch, pruning };
    let pool = pools::pool(call.threads)?;
    let mut eval = PyEval { call: function };
    let mut mesh = Extraction::default();
    let result = py.allow_threads(|| {
        pools::install(pool.as_deref(), || {
            chunks::extract_sparse(extractor.as_ref(), &grid, call.level, &options, &mut eval, &mut mesh)
        })
    });
    let stats = result.map_err(sparse_error)?;
    let d = PyDict::new(py);
    let report = report_json(&call, &grid, chunk, pruning, &stats, &mesh);
    let surface = std::mem::take(&mut mesh.surface);
    d.set_item("vertices", out::vec3_array(py, surface.positions)?)?;
    d.set_item("faces", out::faces_array(py, surface.triangles)?)?;
    d.set_item("normals", out::vec3_array(py, surface.normals)?)?;
    d.set_item("warnings", Vec::<String>::new())?;
    d.set_item("notes", Vec::<String>::new())?;
    d.set_item("run", Run::without_truth(report))?;
    Ok(d)
}

/// The Python exception for a failed sparse extraction: the callable's own exception unchanged,
/// `ValueError` for a wrong answer (naming the batch) or settings the blocks cannot take.
fn sparse_error(e: SparseError) -> PyErr {
    match e {
        SparseError::Eval(inner) => match inner.downcast::<PyErr>() {
            Ok(py_err) => *py_err,
            Err(other) => PyValueError::new_err(other.to_string()),
        },
        other => PyValueError::new_err(other.to_string()),
    }
}

/// `mesh.stats` of a function's extraction.
fn report_json(
    call: &FunctionCall,
    grid: &SparseGrid,
    chunk: usize,
    pruning: Pruning,
    stats: &SparseStats,
    mesh: &Extraction,
) -> String {
    let mode = match pruning {
        Pruning::Lipschitz(_) => "certified (Lipschitz)",
        Pruning::SignChange { .. } => "heuristic (sign change on the block corners, one block of margin)",
        Pruning::Dense => "dense",
    };
    serde_json::json!({
        "algorithm": call.algorithm,
        "input": "function",
        "level": call.level,
        "mode": mode,
        "lipschitz": call.lipschitz,
        "dims": grid.dims,
        "spacing": grid.spacing,
        "origin": grid.origin,
        "chunk": chunk,
        "evaluations": stats.evaluations,
        "pruning_evaluations": stats.pruning_evaluations,
        "refinement_evaluations": stats.refinement_evaluations,
        "dense_points": stats.dense_points,
        "batches": stats.batches,
        "blocks": stats.blocks,
        "sampled_blocks": stats.sampled_blocks,
        "function_ms": stats.eval_time.as_secs_f64() * 1e3,
        "other_ms": stats.other_time.as_secs_f64() * 1e3,
        "vertices": mesh.surface.positions.len(),
        "triangles": mesh.surface.triangles.len(),
    })
    .to_string()
}
