//! Blocks meshed one at a time, for `isolab.dask`: one driver for volumes ([`volume`]) and label
//! maps ([`labels`]). Each kind has the same four calls: the plan (which samples each block
//! reads, in weld order), one block's samples to a fragment of numpy arrays (its mesh in the
//! input's sample indices and each shareable vertex's integer weld key), the fragment back from
//! its arrays (as loaded from a file), and the weld of fragments into what the one-process call
//! returns. What both kinds do alike is here: the plan's listing, the block's shape check, the
//! weld keys as N x 2 `uint64` rows, and a fragment's fields. The engines are
//! `isolab_algorithms::chunks` and `isolab_algorithms::labels::blocks`, whose welds equal the
//! whole input's mesh.
//!
//! Axes: a block arrives as a C-ordered numpy array, so isolab's x is numpy's last axis, as for
//! any C-ordered array `isolab.extract` meshes; plans, ids and sample offsets here are in
//! isolab's (x, y, z). `python/python/isolab/dask.py` drives both kinds through one task.

pub mod labels;
pub mod volume;

use crate::value_error;
use numpy::{PyArray1, PyArray2, PyArrayDyn, PyArrayMethods, PyUntypedArray, PyUntypedArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// A plan as Python reads it: `(counts, apron, [(id, lo, dims), ...])` in weld order, all in
/// isolab's (x, y, z).
pub(crate) type PlanListing = ([usize; 3], usize, Vec<([usize; 3], [usize; 3], [usize; 3])>);

/// The error for a block of the wrong shape or memory order: `expected` in isolab's (x, y, z)
/// (`None`: the id is outside the plan), the shape as numpy gives it.
pub(crate) fn wrong_block(id: [usize; 3], expected: Option<[usize; 3]>, shape: &[usize], c_order: bool, what: &str) -> PyErr {
    let Some([x, y, z]) = expected else {
        return PyValueError::new_err(format!("block {id:?} is outside the plan"));
    };
    PyValueError::new_err(format!(
        "block {id:?}: expected a C-ordered array of {:?} {what} (numpy shape), got shape {shape:?}{}",
        [z, y, x],
        if c_order { "" } else { " not in C order" }
    ))
}

/// Refuses a block that is not a C-ordered array of `expected` samples (isolab's x, y, z).
pub(crate) fn check_block(block: &Bound<'_, PyUntypedArray>, id: [usize; 3], expected: [usize; 3], what: &str) -> PyResult<()> {
    let [x, y, z] = expected;
    if block.is_c_contiguous() && block.shape() == [z, y, x] {
        Ok(())
    } else {
        Err(wrong_block(id, Some(expected), block.shape(), block.is_c_contiguous(), what))
    }
}

/// Weld keys as an N x 2 `uint64` array: each key's low and high halves.
pub(crate) fn keys_array(py: Python<'_>, keys: impl ExactSizeIterator<Item = u128>) -> PyResult<Bound<'_, PyArray2<u64>>> {
    let n = keys.len();
    let halves: Vec<u64> = keys.flat_map(|k| [k as u64, (k >> 64) as u64]).collect();
    PyArray1::from_vec(py, halves).reshape([n, 2])
}

/// Weld keys back from their N x 2 rows.
pub(crate) fn keys_from(a: &Bound<'_, PyAny>) -> PyResult<Vec<u128>> {
    Ok(rows::<u64, 2>(a, "keys", "uint64")?.into_iter().map(|[lo, hi]| u128::from(lo) | u128::from(hi) << 64).collect())
}

/// An M x N array of numbers, converted to `dtype`, as rows.
pub(crate) fn rows<T: numpy::Element + Copy, const N: usize>(
    a: &Bound<'_, PyAny>,
    what: &str,
    dtype: &str,
) -> PyResult<Vec<[T; N]>> {
    let np = a.py().import("numpy")?;
    let a = np.call_method1("ascontiguousarray", (a, dtype))?;
    let a = a.downcast::<PyArrayDyn<T>>()?;
    let ro = a.readonly();
    let shape = ro.shape();
    if shape.len() != 2 || shape[1] != N {
        return Err(PyValueError::new_err(format!("fragment {what} must be an M x {N} array; its shape is {shape:?}")));
    }
    let flat = ro.as_slice().map_err(value_error)?;
    Ok(flat.chunks_exact(N).map(|c| std::array::from_fn(|i| c[i])).collect())
}

/// A fragment's field `key`, or an error naming it (`kind`: "fragment", "label fragment").
pub(crate) fn field<'py>(d: &Bound<'py, PyDict>, key: &str, kind: &str) -> PyResult<Bound<'py, PyAny>> {
    d.get_item(key)?.ok_or_else(|| PyValueError::new_err(format!("{kind} has no '{key}'")))
}
