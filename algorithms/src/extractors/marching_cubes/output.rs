//! What marching cubes writes besides its mesh in the lattice's own coordinates, for callers
//! that want their arrays as they use them (the Python package's scikit-image drop-in): the frame
//! the vertices are written in ([`Frame`]) and a value per vertex ([`VertexValues`]), both made
//! as each vertex is made, so the output is written once.

use crate::samples::{GridView, Sample};
use glam::Vec3;

/// The frame marching cubes writes its vertices in: output axis `k` is the lattice's axis
/// `axes[k]`, positions scaled by `scale[k]` along it; normals are permuted and not scaled (as
/// scikit-image leaves them); `flip` reverses every triangle's winding. The default is the
/// lattice's own frame, which changes nothing.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    /// Which lattice axis each output axis is.
    pub axes: [usize; 3],
    /// Scale of each output axis.
    pub scale: [f32; 3],
    /// Reverse every triangle (`[a, b, c]` written `[a, c, b]`).
    pub flip: bool,
}

impl Default for Frame {
    fn default() -> Self {
        Frame { axes: [0, 1, 2], scale: [1.0; 3], flip: false }
    }
}

impl Frame {
    /// A position in the frame.
    #[inline(always)]
    pub fn place(&self, p: Vec3) -> Vec3 {
        let [a, b, c] = self.axes;
        Vec3::new(component(p, a) * self.scale[0], component(p, b) * self.scale[1], component(p, c) * self.scale[2])
    }

    /// A direction in the frame (permuted only).
    #[inline(always)]
    pub fn turn(&self, n: Vec3) -> Vec3 {
        let [a, b, c] = self.axes;
        Vec3::new(component(n, a), component(n, b), component(n, c))
    }

    /// A triangle wound as the frame winds.
    #[inline(always)]
    pub fn wind(&self, t: [u32; 3]) -> [u32; 3] {
        if self.flip {
            [t[0], t[2], t[1]]
        } else {
            t
        }
    }

    /// Whether `axes` is a permutation of the three axes.
    pub fn is_valid(&self) -> bool {
        let mut seen = [false; 3];
        self.axes.iter().all(|&a| a < 3 && !std::mem::replace(&mut seen[a], true))
    }
}

/// Component `k` of `v` by selection, not by an index into memory (a vector built from indexed
/// stores and read back whole stalls the store buffer).
#[inline(always)]
fn component(v: Vec3, k: usize) -> f32 {
    if k == 0 {
        v.x
    } else if k == 1 {
        v.y
    } else {
        v.z
    }
}

/// A value per vertex, written to [`crate::Extraction::vertex_values`] as the vertex is made.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum VertexValues {
    /// None (default).
    #[default]
    None,
    /// scikit-image's `values`: the largest value range, `max(0, max - iso) - min(0, min -
    /// iso)`, over the eight corners of each cell around the vertex: the up to four cells around
    /// its lattice edge, or the up to eight around its sample for a vertex that lies on one (its
    /// position rounds to the sample). Symmetric in the sign of the samples, so a negated view
    /// gives the volume's own ranges.
    CellRange,
}

/// [`VertexValues::CellRange`] of the vertex at `t` along the lattice edge from sample `a` along
/// `axis`, in a grid of samples at integer coordinates: the four cells around the edge, or the
/// eight around the sample its position rounds to ([`is_at_sample`]).
#[inline]
pub fn cell_range_at<T: Sample>(values: &GridView<'_, T>, a: [usize; 3], axis: usize, t: f32, iso: f32) -> f32 {
    match is_at_sample(a, axis, t) {
        None => edge_cells_range(values, a, axis, iso),
        Some(at) => sample_cells_range(values, at, iso),
    }
}

/// The sample the vertex at `t` along the edge from `a` along `axis` lies on (its coordinate
/// `a[axis] + t` rounds to a whole number), if any.
#[inline(always)]
pub fn is_at_sample(a: [usize; 3], axis: usize, t: f32) -> Option<[usize; 3]> {
    let c = a[axis] as f32 + t;
    is_whole(c).then(|| {
        let mut at = a;
        at[axis] = c as usize;
        at
    })
}

/// [`VertexValues::CellRange`] of a vertex at a sample: the cells around it.
pub fn sample_value<T: Sample>(values: &GridView<'_, T>, at: [usize; 3], iso: f32) -> f32 {
    sample_cells_range(values, at, iso)
}

/// The value range of the cell whose lowest corner is `cell`.
#[inline]
pub fn cell_range<T: Sample>(values: &GridView<'_, T>, cell: [usize; 3], iso: f32) -> f32 {
    let [sx, sy, sz] = values.strides();
    let base = values.offset(cell[0], cell[1], cell[2]);
    let corners = [0, sx, sy, sx + sy, sz, sx + sz, sy + sz, sx + sy + sz].map(|d| values.read(base.wrapping_add_signed(d)));
    range_of_corners(&corners, iso)
}

/// `max(0, max - iso) - min(0, min - iso)` over a cell's eight corner values.
#[inline(always)]
pub fn range_of_corners(corners: &[f32; 8], iso: f32) -> f32 {
    let (mut lo, mut hi) = (corners[0], corners[0]);
    for &v in &corners[1..] {
        lo = smaller(lo, v);
        hi = larger(hi, v);
    }
    larger(hi - iso, 0.0) - smaller(lo - iso, 0.0)
}

/// The largest cell range among the up to eight cells around sample `at`.
fn sample_cells_range<T: Sample>(values: &GridView<'_, T>, at: [usize; 3], iso: f32) -> f32 {
    let dims = values.dims();
    let mut best = 0.0f32;
    for corner in 0..8 {
        let d = [corner & 1, (corner >> 1) & 1, (corner >> 2) & 1];
        if (0..3).all(|k| at[k] >= d[k] && at[k] - d[k] + 1 < dims[k]) {
            best = larger(best, cell_range(values, [at[0] - d[0], at[1] - d[1], at[2] - d[2]], iso));
        }
    }
    best
}

/// The largest cell range among the up to four cells around the lattice edge from `base` along
/// `axis`. The cells share columns (two samples along `axis`): the 3 x 3 columns around the edge
/// are each read once, 18 samples for the four cells' 32 corners.
#[inline]
fn edge_cells_range<T: Sample>(values: &GridView<'_, T>, base: [usize; 3], axis: usize, iso: f32) -> f32 {
    let dims = values.dims();
    let strides = values.strides();
    let (u, w) = ((axis + 1) % 3, (axis + 2) % 3);
    let at = values.offset(base[0], base[1], base[2]);
    if base[u] >= 1 && base[u] + 1 < dims[u] && base[w] >= 1 && base[w] + 1 < dims[w] {
        return inner_edge_cells_range(values, at, [strides[axis], strides[u], strides[w]], iso);
    }
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
            let i = at.wrapping_add_signed((du as isize - 1) * strides[u] + (dw as isize - 1) * strides[w]);
            let (a, b) = (values.read(i), values.read(i.wrapping_add_signed(strides[axis])));
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

/// [`edge_cells_range`] of an edge with all four cells around it: the edge's first sample at
/// element `at`, `strides` along the edge and the two other axes.
#[inline(always)]
fn inner_edge_cells_range<T: Sample>(values: &GridView<'_, T>, at: usize, strides: [isize; 3], iso: f32) -> f32 {
    let [along, su, sw] = strides;
    let columns: [[[f32; 2]; 3]; 3] = std::array::from_fn(|du| {
        std::array::from_fn(|dw| {
            let i = at.wrapping_add_signed((du as isize - 1) * su + (dw as isize - 1) * sw);
            [values.read(i), values.read(i.wrapping_add_signed(along))]
        })
    });
    edge_range_of_columns(&columns, iso)
}

/// The largest range of the four cells around an edge, from the 3 x 3 columns of two samples
/// around it (`columns[du][dw]`: the edge's two samples moved by `du - 1` and `dw - 1` along the
/// other two axes).
#[inline(always)]
fn edge_range_of_columns(columns: &[[[f32; 2]; 3]; 3], iso: f32) -> f32 {
    let (mut lo, mut hi) = ([[0.0f32; 3]; 3], [[0.0f32; 3]; 3]);
    for du in 0..3 {
        for dw in 0..3 {
            let [a, b] = columns[du][dw];
            lo[du][dw] = smaller(a, b);
            hi[du][dw] = larger(a, b);
        }
    }
    let mut best = 0.0f32;
    for cu in 0..2 {
        for cw in 0..2 {
            let l = smaller(smaller(lo[cu][cw], lo[cu + 1][cw]), smaller(lo[cu][cw + 1], lo[cu + 1][cw + 1]));
            let h = larger(larger(hi[cu][cw], hi[cu + 1][cw]), larger(hi[cu][cw + 1], hi[cu + 1][cw + 1]));
            best = larger(best, larger(h - iso, 0.0) - smaller(l - iso, 0.0));
        }
    }
    best
}

/// The smaller of two finite samples (one compare: `f32::min`'s NaN rules cost several
/// instructions, and samples are finite).
#[inline(always)]
pub fn smaller(a: f32, b: f32) -> f32 {
    if a < b {
        a
    } else {
        b
    }
}

/// The larger of two finite samples (see [`smaller`]).
#[inline(always)]
pub fn larger(a: f32, b: f32) -> f32 {
    if a > b {
        a
    } else {
        b
    }
}

/// Whether a non-negative lattice coordinate below 2^32 is a whole number (`fract() == 0`
/// without a call to `truncf`).
#[inline(always)]
pub(super) fn is_whole(c: f32) -> bool {
    (c as u64) as f32 == c
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_permute_scale_and_wind() {
        let f = Frame { axes: [2, 1, 0], scale: [2.0, 1.0, 0.5], flip: true };
        assert!(f.is_valid());
        assert_eq!(f.place(Vec3::new(1.0, 2.0, 3.0)), Vec3::new(6.0, 2.0, 0.5));
        assert_eq!(f.turn(Vec3::new(1.0, 2.0, 3.0)), Vec3::new(3.0, 2.0, 1.0));
        assert_eq!(f.wind([1, 2, 3]), [1, 3, 2]);
        assert!(!Frame { axes: [0, 0, 1], ..f }.is_valid());
        let id = Frame::default();
        assert_eq!(id.place(Vec3::new(0.1, -2.5, 7.0)), Vec3::new(0.1, -2.5, 7.0));
    }

    #[test]
    fn an_edges_range_is_the_largest_of_its_cells() {
        // 3 x 3 x 3 samples; the x-edge from (0, 1, 1) has four cells around it.
        let data: Vec<f32> = (0..27).map(|i| ((i * 7) % 10) as f32 - 4.5).collect();
        let v = GridView::contiguous(&data, [3, 3, 3]).unwrap();
        let iso = 0.25;
        let cells = [[0, 0, 0], [0, 1, 0], [0, 0, 1], [0, 1, 1]];
        let expected = cells.iter().map(|&c| cell_range(&v, c, iso)).fold(0.0f32, f32::max);
        assert_eq!(cell_range_at(&v, [0, 1, 1], 0, 0.5, iso), expected);
        // At the sample (1, 1, 1): all eight cells.
        let all = (0..8).map(|k| cell_range(&v, [k & 1, (k >> 1) & 1, (k >> 2) & 1], iso)).fold(0.0f32, f32::max);
        assert_eq!(cell_range_at(&v, [0, 1, 1], 0, 1.0, iso), all);
    }
}
