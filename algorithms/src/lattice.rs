//! Sampling lattices: the cubic grid and the body-centred cubic (BCC) lattice.
//!
//! ## Index order
//! A [`Grid`] of `dims = [nx, ny, nz]` stores sample `(x, y, z)` at `x + nx * (y + ny * z)`: x
//! fastest, then y, then z (C order of a `[nz][ny][nx]` array, what VTK and numpy's `order='C'`
//! of shape `(nz, ny, nx)` expect). A BCC lattice is two interleaved cubic grids: its corner grid,
//! then its centre grid of `[nx-1, ny-1, nz-1]` samples offset by half a spacing in every axis,
//! stored one after the other in that order.

use crate::geometry::Aabb;
use glam::Vec3;

/// At most this many samples in one lattice, so vertex indices (up to three per sample) fit `u32`.
pub const MAX_SAMPLES: usize = 1 << 30;

/// At most this many samples in a grid sampled sparsely ([`Grid::sparse_covering`]): 2⁴⁰, about
/// 10240³; its mesh, not its samples, must fit in memory.
pub const MAX_SPARSE_SAMPLES: usize = 1 << 40;

/// A cubic grid with the same spacing on every axis.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Grid {
    /// Position of sample `(0, 0, 0)`.
    pub origin: Vec3,
    /// Distance between neighbouring samples.
    pub spacing: f32,
    /// Samples along x, y and z.
    pub dims: [usize; 3],
}

/// Errors choosing a lattice.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LatticeError {
    /// Fewer than two samples along a side.
    #[error("resolution {resolution} is too small: at least 2 samples per side are needed")]
    ResolutionTooSmall {
        /// The resolution asked for.
        resolution: usize,
    },
    /// More samples than the library supports.
    #[error("a {dims:?} lattice has {samples} samples, more than the {max} supported")]
    TooManySamples {
        /// Samples per axis.
        dims: [usize; 3],
        /// Total samples.
        samples: u128,
        /// The limit.
        max: usize,
    },
    /// The domain has a zero, negative or non-finite side.
    #[error("domain {min:?}..{max:?} has a degenerate or non-finite side")]
    BadDomain {
        /// Smallest corner.
        min: [f32; 3],
        /// Largest corner.
        max: [f32; 3],
    },
}

/// Where a vertex lies on a grid's lattice ([`Grid::place`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LatticePlace {
    /// On the edge between samples `lower` and `upper` (`upper` = `lower + {0,1}³`).
    Edge(usize, usize),
    /// On a sample (within rounding).
    Sample(usize),
    /// Inside a cell or a face, off every edge; or outside the grid.
    Elsewhere,
}

/// `c` rounded to the nearest integer when within float rounding of it.
fn snap_to_integer(c: f32) -> f32 {
    let r = c.round();
    if (c - r).abs() <= 1e-6 + 4.0 * f32::EPSILON * r.abs() {
        r
    } else {
        c
    }
}

impl Grid {
    /// The grid with `resolution` samples along the domain's longest side, the same spacing on the
    /// other sides (rounded up so the domain is covered), centred on the domain.
    pub fn covering(domain: &Aabb, resolution: usize) -> Result<Grid, LatticeError> {
        Self::covering_within(domain, resolution, MAX_SAMPLES as u128)
    }

    /// [`Grid::covering`] for a grid whose samples are never all held at once (sparse
    /// extraction samples blocks near the surface only: [`crate::chunks::extract_sparse`]): up
    /// to [`MAX_SPARSE_SAMPLES`] samples rather than [`MAX_SAMPLES`].
    pub fn sparse_covering(domain: &Aabb, resolution: usize) -> Result<Grid, LatticeError> {
        Self::covering_within(domain, resolution, MAX_SPARSE_SAMPLES as u128)
    }

    /// [`Grid::with_dims`] for a grid whose samples are never all held at once (see
    /// [`Grid::sparse_covering`]).
    pub fn sparse_with_dims(domain: &Aabb, dims: [usize; 3]) -> Result<Grid, LatticeError> {
        Self::with_dims_within(domain, dims, MAX_SPARSE_SAMPLES as u128)
    }

    fn covering_within(domain: &Aabb, resolution: usize, max: u128) -> Result<Grid, LatticeError> {
        if resolution < 2 {
            return Err(LatticeError::ResolutionTooSmall { resolution });
        }
        check_domain(domain)?;
        let extent = domain.extent();
        let spacing = extent.max_element() / (resolution - 1) as f32;
        let dims = [0, 1, 2].map(|a| {
            let cells = (extent[a] / spacing - 1e-3).ceil().max(1.0);
            cells as usize + 1
        });
        Self::centred(domain, spacing, dims, max)
    }

    /// The grid with exactly `dims` samples, spacing chosen so the domain fits, centred on it.
    pub fn with_dims(domain: &Aabb, dims: [usize; 3]) -> Result<Grid, LatticeError> {
        Self::with_dims_within(domain, dims, MAX_SAMPLES as u128)
    }

    fn with_dims_within(domain: &Aabb, dims: [usize; 3], max: u128) -> Result<Grid, LatticeError> {
        if let Some(&resolution) = dims.iter().find(|&&d| d < 2) {
            return Err(LatticeError::ResolutionTooSmall { resolution });
        }
        check_domain(domain)?;
        let extent = domain.extent();
        let spacing = (0..3).map(|a| extent[a] / (dims[a] - 1) as f32).fold(0.0, f32::max);
        Self::centred(domain, spacing, dims, max)
    }

    fn centred(domain: &Aabb, spacing: f32, dims: [usize; 3], max: u128) -> Result<Grid, LatticeError> {
        let samples = dims.iter().map(|&d| d as u128).product::<u128>();
        if samples > max {
            return Err(LatticeError::TooManySamples { dims, samples, max: max as usize });
        }
        let size = Vec3::new(dims[0] as f32 - 1.0, dims[1] as f32 - 1.0, dims[2] as f32 - 1.0) * spacing;
        Ok(Grid { origin: domain.centre() - size * 0.5, spacing, dims })
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.dims[0] * self.dims[1] * self.dims[2]
    }

    /// Whether the grid has no samples.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Number of cells (`(nx-1)(ny-1)(nz-1)`).
    pub fn cell_count(&self) -> usize {
        self.dims.iter().map(|&d| d.saturating_sub(1)).product()
    }

    /// Flat index of sample `(x, y, z)`: `x + nx * (y + ny * z)`.
    #[inline]
    pub fn index(&self, x: usize, y: usize, z: usize) -> usize {
        x + self.dims[0] * (y + self.dims[1] * z)
    }

    /// Index coordinates of the world point `p`, each snapped to the nearest integer when within
    /// float rounding of it (positions come back from world space with a few ulps of error).
    pub fn index_coords(&self, p: Vec3) -> [f32; 3] {
        std::array::from_fn(|a| snap_to_integer((p[a] - self.origin[a]) / self.spacing))
    }

    /// Where a vertex at `p` (world space) lies on the grid's lattice: on a sample, on an edge
    /// from a sample to a sample `+{0,1}³` (cube edges and the Kuhn split's diagonals: every
    /// fractional index coordinate the same fraction), or elsewhere (inside a cell or a face, or
    /// outside the grid).
    pub fn place(&self, p: Vec3) -> LatticePlace {
        self.place_of_index(self.index_coords(p))
    }

    /// [`Grid::place`] of a point given by its index coordinates `q`.
    pub fn place_of_index(&self, q: [f32; 3]) -> LatticePlace {
        if q.iter().enumerate().any(|(a, &c)| !(c >= 0.0 && c <= (self.dims[a] - 1) as f32)) {
            return LatticePlace::Elsewhere;
        }
        let lo = q.map(|c| c.floor() as usize);
        let hi = q.map(|c| c.ceil() as usize);
        let fractions: Vec<f32> = (0..3).filter(|&a| lo[a] != hi[a]).map(|a| q[a] - lo[a] as f32).collect();
        let (a, b) = (self.index(lo[0], lo[1], lo[2]), self.index(hi[0], hi[1], hi[2]));
        if fractions.is_empty() {
            LatticePlace::Sample(a)
        } else if fractions.iter().all(|f| (f - fractions[0]).abs() < 1e-3) {
            LatticePlace::Edge(a, b)
        } else {
            LatticePlace::Elsewhere
        }
    }

    /// Position of sample `(x, y, z)`.
    #[inline]
    pub fn position(&self, x: usize, y: usize, z: usize) -> Vec3 {
        self.origin + Vec3::new(x as f32, y as f32, z as f32) * self.spacing
    }

    /// The box spanned by the samples.
    pub fn bounds(&self) -> Aabb {
        let [nx, ny, nz] = self.dims;
        Aabb::new(self.origin, self.position(nx - 1, ny - 1, nz - 1))
    }

    /// The grid of cell centres (one fewer sample per axis, offset by half a spacing): the
    /// second half of a BCC lattice.
    pub fn centres(&self) -> Grid {
        Grid {
            origin: self.origin + Vec3::splat(0.5 * self.spacing),
            spacing: self.spacing,
            dims: self.dims.map(|d| d.saturating_sub(1)),
        }
    }
}

fn check_domain(domain: &Aabb) -> Result<(), LatticeError> {
    let e = domain.extent();
    if !(domain.min.is_finite() && domain.max.is_finite()) || e.min_element() <= 0.0 {
        return Err(LatticeError::BadDomain { min: domain.min.to_array(), max: domain.max.to_array() });
    }
    Ok(())
}

/// Where samples are taken.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Lattice {
    /// One cubic grid.
    Cubic(Grid),
    /// Body-centred cubic: the corner grid plus its cell centres ([`Grid::centres`]).
    Bcc(Grid),
}

impl Lattice {
    /// The corner grid.
    pub fn grid(&self) -> &Grid {
        match self {
            Lattice::Cubic(g) | Lattice::Bcc(g) => g,
        }
    }

    /// Total samples (both grids for BCC).
    pub fn sample_count(&self) -> usize {
        match self {
            Lattice::Cubic(g) => g.len(),
            Lattice::Bcc(g) => g.len() + g.centres().len(),
        }
    }

    /// Short name: `cubic` or `bcc`.
    pub fn kind(&self) -> &'static str {
        match self {
            Lattice::Cubic(_) => "cubic",
            Lattice::Bcc(_) => "bcc",
        }
    }

    /// Position of sample `i` in the flat value array.
    pub fn position_of(&self, i: usize) -> Vec3 {
        let (grid, i) = match self {
            Lattice::Cubic(g) => (*g, i),
            Lattice::Bcc(g) if i < g.len() => (*g, i),
            Lattice::Bcc(g) => (g.centres(), i - g.len()),
        };
        let [nx, ny, _] = grid.dims;
        grid.position(i % nx, (i / nx) % ny, i / (nx * ny))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn resolution_is_samples_along_the_longest_side() {
        let d = Aabb::new(Vec3::new(-0.5, -0.25, -0.5), Vec3::new(0.5, 0.25, 0.5));
        let g = Grid::covering(&d, 65).unwrap();
        assert_eq!(g.dims, [65, 33, 65]);
        assert!((g.spacing - 1.0 / 64.0).abs() < 1e-7);
        assert!((g.origin - d.min).length() < 1e-6);
        assert!(g.bounds().max.abs_diff_eq(d.max, 1e-6));
    }

    #[test]
    fn index_order_is_x_fastest() {
        let g = Grid { origin: Vec3::ZERO, spacing: 1.0, dims: [3, 4, 5] };
        assert_eq!(g.index(1, 0, 0), 1);
        assert_eq!(g.index(0, 1, 0), 3);
        assert_eq!(g.index(0, 0, 1), 12);
        let l = Lattice::Bcc(g);
        assert_eq!(l.sample_count(), 60 + 2 * 3 * 4);
        assert_eq!(l.position_of(60), Vec3::splat(0.5));
        assert_eq!(l.position_of(g.index(2, 3, 4)), Vec3::new(2.0, 3.0, 4.0));
    }

    #[test]
    fn impossible_resolutions_are_errors() {
        let d = Aabb::cube(0.5);
        assert_eq!(Grid::covering(&d, 1), Err(LatticeError::ResolutionTooSmall { resolution: 1 }));
        assert!(matches!(Grid::covering(&d, 5000), Err(LatticeError::TooManySamples { .. })));
        assert!(matches!(
            Grid::covering(&Aabb::new(Vec3::ZERO, Vec3::new(1.0, 0.0, 1.0)), 8),
            Err(LatticeError::BadDomain { .. })
        ));
    }
}
