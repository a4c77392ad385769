//! Meshes out as numpy arrays, and the scikit-image conventions the drop-in keeps: numpy index
//! order, its winding, a cell mask, and each vertex's `values` entry.

use glam::{DAffine3, Vec3};
use isolab_algorithms::{Grid, TriMesh};
use numpy::{PyArray1, PyArray2, PyArray3, PyArrayMethods};
use pyo3::prelude::*;
use rayon::prelude::*;

/// Positions and normals from isolab's (x, y, z) to numpy's (i, j, k) (a swap of x and z for a
/// C-ordered volume), positions scaled per numpy axis by `scale`, and every triangle's winding
/// reversed when `flip`. Normals are not rescaled, as scikit-image leaves them.
pub fn to_numpy_order(mesh: &mut TriMesh, layout: crate::arrays::Layout, scale: [f32; 3], flip: bool) {
    let scale = Vec3::from(scale);
    let swap = layout == crate::arrays::Layout::C;
    let reorder = |p: &mut Vec3| {
        if swap {
            *p = Vec3::new(p.z, p.y, p.x);
        }
    };
    mesh.positions.par_iter_mut().with_min_len(1 << 14).for_each(|p| {
        reorder(p);
        *p *= scale;
    });
    mesh.normals.par_iter_mut().with_min_len(1 << 14).for_each(reorder);
    if flip {
        mesh.triangles.par_iter_mut().with_min_len(1 << 14).for_each(|t| t.swap(1, 2));
    }
}

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
fn triangle_cell(mesh: &TriMesh, t: [u32; 3], grid: &Grid) -> [usize; 3] {
    let c = (mesh.positions[t[0] as usize] + mesh.positions[t[1] as usize] + mesh.positions[t[2] as usize]) / 3.0;
    let at = |v: f32, n: usize| {
        let below = if v.fract() == 0.0 { v - 1.0 } else { v.floor() };
        (below.max(0.0) as usize).min(n.saturating_sub(2))
    };
    [at(c.x, grid.dims[0]), at(c.y, grid.dims[1]), at(c.z, grid.dims[2])]
}

/// The largest cell range among the up to four cells around the lattice edge from `base` along
/// `axis`. The cells share columns (two samples along `axis`): the 3 x 3 columns around the edge
/// are each read once, 18 samples for the four cells' 32 corners.
fn edge_cells_range(values: &[f32], dims: [usize; 3], strides: [usize; 3], base: [usize; 3], axis: usize, iso: f32) -> f32 {
    let (u, w) = ((axis + 1) % 3, (axis + 2) % 3);
    let at = base[0] + strides[1] * base[1] + strides[2] * base[2];
    // columns[du][dw]: (min, max) of the column at base + (du - 1) e_u + (dw - 1) e_w.
    let mut columns = [[(f32::INFINITY, f32::NEG_INFINITY); 3]; 3];
    let inside = |coord: usize, d: usize, n: usize| coord + d >= 1 && coord + d < n + 1;
    for (du, row) in columns.iter_mut().enumerate() {
        if !inside(base[u], du, dims[u]) {
            continue;
        }
        for (dw, column) in row.iter_mut().enumerate() {
            if !inside(base[w], dw, dims[w]) {
                continue;
            }
            let i = at + du * strides[u] + dw * strides[w] - strides[u] - strides[w];
            let (a, b) = (values[i], values[i + strides[axis]]);
            *column = (a.min(b), a.max(b));
        }
    }
    let mut best = 0.0f32;
    for cu in 0..2 {
        for cw in 0..2 {
            // The cell whose lowest corner is base + (cu - 1) e_u + (cw - 1) e_w.
            if base[u] + cu < 1 || base[u] + cu >= dims[u] || base[w] + cw < 1 || base[w] + cw >= dims[w] {
                continue;
            }
            let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
            for column in [columns[cu][cw], columns[cu + 1][cw], columns[cu][cw + 1], columns[cu + 1][cw + 1]] {
                lo = lo.min(column.0);
                hi = hi.max(column.1);
            }
            best = best.max((hi - iso).max(0.0) - (lo - iso).min(0.0));
        }
    }
    best
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

/// scikit-image's `values`: for each vertex, the largest value range, `max(0, max - iso) -
/// min(0, min - iso)` over the eight corners, among the cells around it: the up to four cells
/// around its edge for a vertex on an edge (two integer coordinates), the up to eight cells
/// around its sample for a vertex at a sample. Symmetric in the sign of the values, so negated
/// samples give the volume's own ranges. With a mask, a vertex reads the cells whose triangles
/// use it (zero for a vertex no triangle uses).
pub fn cell_ranges(mesh: &TriMesh, grid: &Grid, values: &[f32], iso: f32, masked: bool) -> Vec<f32> {
    let [nx, ny, nz] = grid.dims;
    let cell_range = |[x, y, z]: [usize; 3]| {
        let (mut lo, mut hi) = (0.0f32, 0.0f32);
        for dz in 0..2 {
            for dy in 0..2 {
                let row = x + nx * ((y + dy) + ny * (z + dz));
                for v in &values[row..row + 2] {
                    lo = lo.min(v - iso);
                    hi = hi.max(v - iso);
                }
            }
        }
        hi - lo
    };
    let dims = [nx, ny, nz];
    let strides = [1, nx, nx * ny];
    // A vertex at a sample (its value at the iso-value) reads every cell around that sample, as
    // scikit-image does (tested on level sets, where such vertices occur).
    let sample_cells_range = |at: [usize; 3]| {
        let mut best = 0.0f32;
        for corner in 0..8 {
            let d = [corner & 1, (corner >> 1) & 1, (corner >> 2) & 1];
            if (0..3).all(|k| at[k] >= d[k] && at[k] - d[k] + 1 < dims[k]) {
                best = best.max(cell_range([at[0] - d[0], at[1] - d[1], at[2] - d[2]]));
            }
        }
        best
    };
    // NaN marks a vertex whose cells are found from its triangles.
    let mut out: Vec<f32> = mesh
        .positions
        .par_iter()
        .with_min_len(1 << 12)
        .map(|p| {
            let c = p.to_array();
            let axis = match c.map(|v| v.fract() != 0.0) {
                [true, false, false] => 0,
                [false, true, false] => 1,
                [false, false, true] => 2,
                [false, false, false] if !masked => return sample_cells_range(c.map(|v| v as usize)),
                _ => return f32::NAN,
            };
            if masked {
                return f32::NAN;
            }
            edge_cells_range(values, dims, strides, c.map(|v| v.floor() as usize), axis, iso)
        })
        .collect();
    if out.iter().any(|v| v.is_nan()) {
        let mut from_triangles = vec![0.0f32; out.len()];
        for &t in &mesh.triangles {
            if t.iter().any(|&v| out[v as usize].is_nan()) {
                let range = cell_range(triangle_cell(mesh, t, grid));
                for v in t {
                    let slot = &mut from_triangles[v as usize];
                    *slot = slot.max(range);
                }
            }
        }
        for (v, t) in out.iter_mut().zip(from_triangles) {
            if v.is_nan() {
                *v = t;
            }
        }
    }
    out
}
