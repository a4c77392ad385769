//! numpy arrays read where they lie: a 3-D array of bool, 8- to 32-bit integers, float32 or
//! float64 as an [`AnyView`] over its own memory, in its own type, whatever its memory order or
//! strides (C order, Fortran order, every `step`-th sample, a reversed axis, a block of a larger
//! array). isolab's x is the array's axis with the smaller stride of its first and last, so rows
//! are read in memory order.
//!
//! A view that is not contiguous is read through the contiguous array it was cut from (its
//! `base`, found by walking the chain of bases); only an array none of whose bases holds its
//! memory contiguously in its own dtype is copied (`None` from [`borrow`]: the caller converts).

use crate::arrays::Layout;
use isolab_algorithms::samples::{AnyView, GridView, Sample};
use numpy::{Element, PyArrayDyn, PyArrayMethods, PyReadonlyArrayDyn, PyUntypedArray, PyUntypedArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

/// A volume's samples where they lie, and which numpy axis is isolab's x.
pub struct Borrowed<'a> {
    /// The view, isolab's (x, y, z) being numpy's (k, j, i) for [`Layout::C`], (i, j, k) for
    /// [`Layout::Fortran`]; every `step`-th sample.
    pub view: AnyView<'a>,
    /// Which numpy axis is x.
    pub layout: Layout,
}

/// Runs `f` on the array's samples where they lie (every `step`-th along each axis), or returns
/// `Ok(None)` when it is not 3-D or its dtype or memory cannot be read in place (the caller
/// copies, or raises). The GIL is
/// held while `f` builds its call; `f` may release it.
pub fn with_borrowed<R>(
    array: &Bound<'_, PyUntypedArray>,
    step: usize,
    f: impl FnOnce(Borrowed<'_>) -> PyResult<R>,
) -> PyResult<Option<R>> {
    macro_rules! try_types {
        ($($t:ty),*) => {$(
            if let Ok(a) = array.downcast::<PyArrayDyn<$t>>() {
                return with_typed::<$t, R>(a, step, f);
            }
        )*};
    }
    try_types!(f32, f64, u8, i8, u16, i16, u32, i32, bool);
    Ok(None)
}

fn with_typed<T: Sample + Element, R>(
    array: &Bound<'_, PyArrayDyn<T>>,
    step: usize,
    f: impl FnOnce(Borrowed<'_>) -> PyResult<R>,
) -> PyResult<Option<R>> {
    if array.ndim() != 3 {
        return Ok(None); // not a volume: the caller's conversion names what is wrong
    }
    let Some((holder, origin)) = memory_of(array)? else { return Ok(None) };
    let data = holder.as_slice().map_err(|e| PyValueError::new_err(format!("the volume cannot be read: {e}")))?;
    let shape = array.shape();
    let size = std::mem::size_of::<T>() as isize;
    let bytes = array.strides();
    if bytes.iter().any(|s| s % size != 0) {
        return Ok(None);
    }
    let strides = [bytes[0] / size, bytes[1] / size, bytes[2] / size];
    // x is the axis of the smaller stride of the first and last (C order: the last).
    let layout = if strides[0].abs() < strides[2].abs() { Layout::Fortran } else { Layout::C };
    let (dims, strides) = match layout {
        Layout::C => ([shape[2], shape[1], shape[0]], [strides[2], strides[1], strides[0]]),
        Layout::Fortran => ([shape[0], shape[1], shape[2]], strides),
    };
    let view = GridView::strided(data, dims, origin, strides)
        .map_err(|e| PyValueError::new_err(format!("the volume's memory cannot be read: {e}")))?;
    let view = view.every(step).ok_or_else(|| PyValueError::new_err("step_size must be at least one."))?;
    f(Borrowed { view: view.into(), layout }).map(Some)
}

/// The contiguous array holding `array`'s memory (itself, or the first of its bases that is
/// contiguous in the same dtype) and the element where `array`'s first sample is; `None` when
/// there is none.
fn memory_of<'py, T: Element>(array: &Bound<'py, PyArrayDyn<T>>) -> PyResult<Option<(PyReadonlyArrayDyn<'py, T>, usize)>> {
    let start = array.data() as usize;
    let mut candidate = array.clone();
    for _ in 0..64 {
        if candidate.is_contiguous() {
            let base = candidate.data() as usize;
            let size = std::mem::size_of::<T>();
            if start < base || (start - base) % size != 0 {
                return Ok(None);
            }
            let readonly =
                candidate.try_readonly().map_err(|e| PyValueError::new_err(format!("the volume cannot be read: {e}")))?;
            return Ok(Some((readonly, (start - base) / size)));
        }
        let base = candidate.getattr("base")?;
        match base.downcast_into::<PyArrayDyn<T>>() {
            Ok(b) => candidate = b,
            Err(_) => return Ok(None),
        }
    }
    Ok(None)
}
