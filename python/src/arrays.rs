//! numpy arrays in, where they are copied: a 3-D array of any numeric dtype converted into
//! isolab's float32 samples (read in place in whichever memory order it has, C: the last axis is
//! isolab's x; Fortran: the first is; a strided view, or every `step`-th sample, through its
//! strides), for what cannot read an array where it lies ([`crate::views`]); mesh arrays as
//! meshes.

use glam::{DAffine3, DMat3, DVec3, Vec3};
use isolab_algorithms::{TetMesh, TriMesh};
use numpy::ndarray::{ArrayViewD, Slice};
use numpy::{PyArrayDyn, PyArrayMethods, PyUntypedArray, PyUntypedArrayMethods};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use rayon::prelude::*;

/// Which numpy axis is isolab's x (the fastest in memory).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Layout {
    /// The last axis is x: isolab's (x, y, z) are numpy's (k, j, i).
    C,
    /// The first axis is x: isolab's (x, y, z) are numpy's (i, j, k).
    Fortran,
}

/// A volume as isolab's samples.
pub struct VolumeArray {
    /// `sign * value`, x fastest.
    pub values: Vec<f32>,
    /// Samples along isolab's x, y, z.
    pub dims: [usize; 3],
    /// Which numpy axis is x.
    pub layout: Layout,
    /// The array's dtype name.
    pub dtype: &'static str,
}

/// A number numpy stores that isolab reads as a float32 sample.
trait Sample: numpy::Element + Copy + Send + Sync {
    const NAME: &'static str;
    fn to_f32(self) -> f32;
}

macro_rules! numeric_sample {
    ($($t:ty => $name:literal),*) => {$(
        impl Sample for $t {
            const NAME: &'static str = $name;
            fn to_f32(self) -> f32 {
                self as f32
            }
        }
    )*};
}
numeric_sample!(u8 => "uint8", i8 => "int8", u16 => "uint16", i16 => "int16", u32 => "uint32", i32 => "int32",
    u64 => "uint64", i64 => "int64", f32 => "float32", f64 => "float64");

impl Sample for bool {
    const NAME: &'static str = "bool";
    fn to_f32(self) -> f32 {
        f32::from(u8::from(self))
    }
}

/// Reads a 3-D array of any supported dtype (bool, u8-u64, i8-i64, f32, f64), every `step`-th
/// sample along each axis, times `sign`. The GIL is released while the values are converted,
/// on `pool` when given.
pub fn read_volume(
    py: Python<'_>,
    array: &Bound<'_, PyUntypedArray>,
    step: usize,
    sign: f32,
    pool: Option<&rayon::ThreadPool>,
) -> PyResult<VolumeArray> {
    if array.ndim() != 3 {
        return Err(PyValueError::new_err(format!("the volume must be a 3-D array; this one has {} dimensions", array.ndim())));
    }
    if array.shape().iter().any(|&n| n < 2) {
        return Err(PyValueError::new_err(format!("the volume must be at least 2x2x2; its shape is {:?}", array.shape())));
    }
    if step == 0 {
        return Err(PyValueError::new_err("step_size must be at least one."));
    }
    macro_rules! try_types {
        ($($t:ty),*) => {$(
            if let Ok(a) = array.downcast::<PyArrayDyn<$t>>() {
                return read_typed::<$t>(py, a, step, sign, pool);
            }
        )*};
    }
    try_types!(f32, f64, u8, i8, u16, i16, u32, i32, u64, i64, bool);
    Err(PyTypeError::new_err(format!("unsupported dtype {}: give bool, an integer or a float array", array.dtype())))
}

fn read_typed<T: Sample>(
    py: Python<'_>,
    array: &Bound<'_, PyArrayDyn<T>>,
    step: usize,
    sign: f32,
    pool: Option<&rayon::ThreadPool>,
) -> PyResult<VolumeArray> {
    let readonly = array.try_readonly().map_err(|e| PyValueError::new_err(format!("the volume cannot be read: {e}")))?;
    let shape = [array.shape()[0], array.shape()[1], array.shape()[2]];
    let fortran = !array.is_c_contiguous() && array.is_fortran_contiguous();
    let contiguous = if step == 1 { readonly.as_slice().ok() } else { None };
    let (values, dims, layout) = if let Some(slice) = contiguous {
        let values = py.allow_threads(|| crate::pools::install(pool, || convert(slice, sign)));
        if fortran {
            (values, shape, Layout::Fortran)
        } else {
            (values, [shape[2], shape[1], shape[0]], Layout::C)
        }
    } else {
        let view: ArrayViewD<'_, T> = readonly.as_array();
        let every = view.slice_each_axis(|_| Slice::new(0, None, step as isize));
        let m = [every.shape()[0], every.shape()[1], every.shape()[2]];
        let values: Vec<f32> = py.allow_threads(|| every.iter().map(|&x| sign * x.to_f32()).collect());
        (values, [m[2], m[1], m[0]], Layout::C)
    };
    if dims.iter().any(|&n| n < 2) {
        return Err(PyValueError::new_err(format!(
            "step_size {step} leaves fewer than 2 samples along an axis of a {shape:?} volume"
        )));
    }
    Ok(VolumeArray { values, dims, layout, dtype: T::NAME })
}

/// Samples per task of the conversion pass.
const CHUNK: usize = 1 << 16;

/// `sign * x` as float32 for every sample, in one parallel pass over the array.
fn convert<T: Sample>(slice: &[T], sign: f32) -> Vec<f32> {
    // Zeroed memory comes from fresh pages: no pass of its own before the conversion writes it.
    let mut values = vec![0.0f32; slice.len()];
    values.par_chunks_mut(CHUNK).zip(slice.par_chunks(CHUNK)).for_each(|(out, input)| {
        for (o, &x) in out.iter_mut().zip(input) {
            *o = sign * x.to_f32();
        }
    });
    values
}

/// A boolean mask of the volume's shape, read as the volume was (every `step`-th sample, in
/// isolab's x-fastest order for `layout`).
pub fn read_mask(
    py: Python<'_>,
    mask: &Bound<'_, PyUntypedArray>,
    step: usize,
    layout: Layout,
    pool: Option<&rayon::ThreadPool>,
) -> PyResult<Vec<bool>> {
    let mask = mask.downcast::<PyArrayDyn<bool>>().map_err(|_| PyTypeError::new_err("mask must be a boolean array"))?;
    let readonly = mask.try_readonly().map_err(|e| PyValueError::new_err(format!("the mask cannot be read: {e}")))?;
    let view = readonly.as_array();
    let every = view.slice_each_axis(|_| Slice::new(0, None, step as isize));
    let out: Vec<bool> = py.allow_threads(|| {
        crate::pools::install(pool, || match layout {
            Layout::C => every.iter().copied().collect(),
            Layout::Fortran => every.t().iter().copied().collect(),
        })
    });
    Ok(out)
}

/// The map from isolab's sample index (x, y, z) to the world: numpy's index (i, j, k) through
/// `affine` (identity when absent), after the axis swap a C-ordered array needs.
pub fn index_to_world(affine: Option<[[f64; 4]; 4]>, layout: Layout) -> Result<DAffine3, String> {
    let a = affine.unwrap_or([[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]]);
    if a[3] != [0.0, 0.0, 0.0, 1.0] {
        return Err(format!("affine's last row is {:?}; an index-to-world affine's is [0, 0, 0, 1]", a[3]));
    }
    let column = |c: usize| DVec3::new(a[0][c], a[1][c], a[2][c]);
    let ijk = DAffine3 { matrix3: DMat3::from_cols(column(0), column(1), column(2)), translation: column(3) };
    Ok(match layout {
        Layout::Fortran => ijk,
        // x is k and z is i.
        Layout::C => ijk * DAffine3 { matrix3: DMat3::from_cols(DVec3::Z, DVec3::Y, DVec3::X), translation: DVec3::ZERO },
    })
}

/// An N x 3 array of positions (any float dtype) as vectors.
fn vec3s(array: &Bound<'_, PyAny>, what: &str) -> PyResult<Vec<Vec3>> {
    let a: Vec<[f32; 3]> = numpy_rows(array, what)?;
    Ok(a.into_iter().map(Vec3::from).collect())
}

fn numpy_rows<const N: usize>(array: &Bound<'_, PyAny>, what: &str) -> PyResult<Vec<[f32; N]>> {
    let np = array.py().import("numpy")?;
    let a = np.call_method1("ascontiguousarray", (array, "float32"))?;
    let a = a.downcast::<PyArrayDyn<f32>>()?;
    let ro = a.readonly();
    let shape = ro.shape();
    if shape.len() != 2 || shape[1] != N {
        return Err(PyValueError::new_err(format!("{what} must be an N x {N} array; its shape is {shape:?}")));
    }
    let flat = ro.as_slice().map_err(|e| PyValueError::new_err(e.to_string()))?;
    Ok(flat.chunks_exact(N).map(|c| std::array::from_fn(|i| c[i])).collect())
}

fn index_rows<const N: usize>(array: &Bound<'_, PyAny>, what: &str, vertices: usize) -> PyResult<Vec<[u32; N]>> {
    let np = array.py().import("numpy")?;
    let a = np.call_method1("ascontiguousarray", (array, "int64"))?;
    let a = a.downcast::<PyArrayDyn<i64>>()?;
    let ro = a.readonly();
    let shape = ro.shape();
    if shape.len() != 2 || shape[1] != N {
        return Err(PyValueError::new_err(format!("{what} must be an M x {N} array of indices; its shape is {shape:?}")));
    }
    let flat = ro.as_slice().map_err(|e| PyValueError::new_err(e.to_string()))?;
    if let Some((at, &bad)) = flat.iter().enumerate().find(|(_, &i)| i < 0 || i as usize >= vertices) {
        return Err(PyValueError::new_err(format!(
            "{what}: index {bad} in row {} is not one of the {vertices} vertices",
            at / N
        )));
    }
    Ok(flat.chunks_exact(N).map(|c| std::array::from_fn(|i| c[i] as u32)).collect())
}

/// A triangle mesh from `vertices` (N x 3), `faces` (M x 3) and optional `normals` (N x 3).
pub fn tri_mesh(vertices: &Bound<'_, PyAny>, faces: &Bound<'_, PyAny>, normals: Option<&Bound<'_, PyAny>>) -> PyResult<TriMesh> {
    let positions = vec3s(vertices, "vertices")?;
    let triangles = index_rows::<3>(faces, "faces", positions.len())?;
    let normals = match normals.filter(|n| !n.is_none()) {
        Some(n) => vec3s(n, "normals")?,
        None => Vec::new(),
    };
    if !normals.is_empty() && normals.len() != positions.len() {
        return Err(PyValueError::new_err(format!("{} normals for {} vertices", normals.len(), positions.len())));
    }
    Ok(TriMesh { positions, normals, triangles })
}

/// A tetrahedral mesh from `vertices` (N x 3) and `tetrahedra` (K x 4).
pub fn tet_mesh(vertices: &Bound<'_, PyAny>, tetrahedra: &Bound<'_, PyAny>) -> PyResult<TetMesh> {
    let positions = vec3s(vertices, "tet_vertices")?;
    let tetrahedra = index_rows::<4>(tetrahedra, "tetrahedra", positions.len())?;
    Ok(TetMesh { positions, tetrahedra })
}
