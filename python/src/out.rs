//! Meshes out as numpy arrays, and the scikit-image conventions the drop-in keeps: numpy index
//! order, its winding, a cell mask, and each vertex's `values` entry.

use glam::{DAffine3, Vec3};
use isolab_algorithms::{Grid, TriMesh};
use numpy::{PyArray1, PyArray2, PyArray3, PyArrayMethods};
use pyo3::prelude::*;

/// Vectors as an N x 3 float32 array over the same buffer (no copy).
pub fn vec3_array<'py>(py: Python<'py>, v: Vec<Vec3>) -> PyResult<Bound<'py, PyArray2<f32>>> {
    let n = v.len();
    let flat: Vec<f32> = bytemuck::allocation::try_cast_vec(v)
        .unwrap_or_else(|(_, v): (_, Vec<Vec3>)| v.iter().flat_map(|p| p.to_array()).collect());
    PyArray1::from_vec(py, flat).reshape([n, 3])
}

/// Triangles as an M x 3 int32 array (scikit-image's dtype) over the same buffer.
pub fn faces_array<'py>(py: Python<'py>, t: Vec<[u32; 3]>) -> PyResult<Bound<'py, PyArray2<i32>>> {
    let n = t.len();
    let flat: Vec<i32> = bytemuck::allocation::try_cast_vec(t)
        .unwrap_or_else(|(_, t): (_, Vec<[u32; 3]>)| t.iter().flat_map(|f| f.map(|i| i as i32)).collect());
    PyArray1::from_vec(py, flat).reshape([n, 3])
}

/// Rows of unsigned integers (triangles, label pairs) as an M x N uint32 array over the same
/// buffer.
pub fn u32_rows<const N: usize>(py: Python<'_>, rows: Vec<[u32; N]>) -> PyResult<Bound<'_, PyArray2<u32>>>
where
    [u32; N]: bytemuck::Pod,
{
    let m = rows.len();
    let flat: Vec<u32> = bytemuck::allocation::try_cast_vec(rows)
        .unwrap_or_else(|(_, rows): (_, Vec<[u32; N]>)| rows.iter().flatten().copied().collect());
    PyArray1::from_vec(py, flat).reshape([m, N])
}

/// Tetrahedra as a K x 4 int32 array.
pub fn quads_array<'py>(py: Python<'py>, t: &[[u32; 4]]) -> PyResult<Bound<'py, PyArray2<i32>>> {
    let flat: Vec<i32> = t.iter().flat_map(|f| f.map(|i| i as i32)).collect();
    PyArray1::from_vec(py, flat).reshape([t.len(), 4])
}

/// A volume's values (x fastest) as a numpy array of shape `dims` in Fortran order, over the
/// same buffer.
pub fn fortran_volume<'py>(py: Python<'py>, values: Vec<f32>, dims: [usize; 3]) -> PyResult<Bound<'py, PyArray3<f32>>> {
    PyArray1::from_vec(py, values).reshape_with_order(dims, numpy::npyffi::NPY_ORDER::NPY_FORTRANORDER)
}

/// An affine as the rows of its 4 x 4 matrix.
pub fn affine_rows(a: &DAffine3) -> [[f64; 4]; 4] {
    let m = a.matrix3;
    let t = a.translation;
    [
        [m.x_axis.x, m.y_axis.x, m.z_axis.x, t.x],
        [m.x_axis.y, m.y_axis.y, m.z_axis.y, t.y],
        [m.x_axis.z, m.y_axis.z, m.z_axis.z, t.z],
        [0.0, 0.0, 0.0, 1.0],
    ]
}

/// The cell of `grid` (sample index of its lowest corner) a marching cubes triangle lies in:
/// its vertices lie on the cell's edges or inside it, so its centroid is in the cell. A centroid
/// on a lattice plane is a triangle lying in a face of its cell, and isolab's tables draw those
/// only on a cell's upper faces (`isolab_algorithms::tables::marching_cubes`): its cell is the
/// one below the plane.
pub fn triangle_cell(mesh: &TriMesh, t: [u32; 3], grid: &Grid) -> [usize; 3] {
    let c = (mesh.positions[t[0] as usize] + mesh.positions[t[1] as usize] + mesh.positions[t[2] as usize]) / 3.0;
    let at = |v: f32, n: usize| {
        let below = if v.fract() == 0.0 { v - 1.0 } else { v.floor() };
        (below.max(0.0) as usize).min(n.saturating_sub(2))
    };
    [at(c.x, grid.dims[0]), at(c.y, grid.dims[1]), at(c.z, grid.dims[2])]
}

fn cell_index(cell: [usize; 3], grid: &Grid) -> usize {
    cell[0] + grid.dims[0] * (cell[1] + grid.dims[1] * cell[2])
}

/// Keeps the triangles of cells whose highest corner (largest index along every axis) the mask
/// keeps, the corner scikit-image reads the mask at, then drops the vertices no triangle uses,
/// keeping the others' order. Positions are in sample index coordinates.
pub fn keep_masked_cells(mesh: &mut TriMesh, grid: &Grid, mask: &[bool]) {
    let kept_cell = |t: [u32; 3]| mask[cell_index(triangle_cell(mesh, t, grid).map(|c| c + 1), grid)];
    let keep: Vec<[u32; 3]> = mesh.triangles.iter().copied().filter(|&t| kept_cell(t)).collect();
    let mut new_index = vec![u32::MAX; mesh.positions.len()];
    for t in &keep {
        for &v in t {
            new_index[v as usize] = 0;
        }
    }
    let mut next = 0u32;
    for slot in &mut new_index {
        if *slot == 0 {
            *slot = next;
            next += 1;
        }
    }
    let kept = |v: &[Vec3]| -> Vec<Vec3> { v.iter().zip(&new_index).filter(|(_, &i)| i != u32::MAX).map(|(p, _)| *p).collect() };
    mesh.positions = kept(&mesh.positions);
    if !mesh.normals.is_empty() {
        mesh.normals = kept(&mesh.normals);
    }
    mesh.triangles = keep.into_iter().map(|t| t.map(|v| new_index[v as usize])).collect();
}
