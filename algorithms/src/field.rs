//! The [`Field`] trait: a scalar function of space whose level set is the surface.

use crate::geometry::Aabb;
use crate::lattice::Grid;
use glam::Vec3;
use rayon::prelude::*;

/// The material id a field has where it says nothing else: 0, rock in `crate::materials`
/// (which depends on fields, not the other way round).
pub const DEFAULT_MATERIAL: u8 = 0;

/// Where every sample of a block lies, when a field can tell without sampling it
/// ([`Field::block_side`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BlockSide {
    /// Every sample's value is at least `iso` (nothing to mesh: an empty chunk).
    Outside,
    /// Every sample's value is below `iso` (a full chunk).
    Inside,
}

/// A scalar field `f: R^3 -> R`. Inside is `f < iso`.
///
/// Implementors give a value, a default domain and, where they know it, an analytic gradient;
/// otherwise the gradient falls back to central differences.
pub trait Field: Send + Sync {
    /// Stable name (the CLI's `--field` value for built-ins, the file stem for mesh fields).
    fn name(&self) -> &str;

    /// The field's value at `p`.
    fn value(&self, p: Vec3) -> f32;

    /// The default domain to sample.
    fn domain(&self) -> Aabb;

    /// Whether [`Field::gradient`] is analytic (true) or central differences (false).
    fn has_analytic_gradient(&self) -> bool {
        false
    }

    /// The gradient at `p`; the default is central differences with step
    /// [`Field::difference_step`].
    fn gradient(&self, p: Vec3) -> Vec3 {
        central_difference(self, p, self.difference_step())
    }

    /// Step used by central differences: 1e-3 of the domain's longest side.
    fn difference_step(&self) -> f32 {
        1e-3 * self.domain().longest_side()
    }

    /// Distance from `p` to the level set `iso`. The default is the first-order estimate
    /// `|f - iso| / |grad f|` (exact for signed distance fields); mesh fields give the exact
    /// distance to their triangles.
    fn distance_to_surface(&self, p: Vec3, iso: f32) -> f32 {
        let g = self.gradient(p).length();
        let d = (self.value(p) - iso).abs();
        if g > 0.0 {
            d / g
        } else {
            d
        }
    }

    /// The triangles whose level set this field is, when it is a mesh field (a surface `S` that
    /// algorithms like `bcc-sculpt` test against exactly).
    fn surface_mesh(&self) -> Option<&crate::bvh::TriangleBvh> {
        None
    }

    /// The material at `p` (an id of `materials::NAMES`); [`DEFAULT_MATERIAL`] (rock) unless the
    /// field says otherwise.
    fn material(&self, _p: Vec3) -> u8 {
        DEFAULT_MATERIAL
    }

    /// Fills `out` with the field's values at every sample of `grid` (x fastest, then y, then z)
    /// for a surface at `iso`. The default samples each z-slice as a block
    /// ([`sample_pointwise`], through [`Field::sample_block`]); a field that can do better for a
    /// whole grid overrides it, as mesh
    /// fields do (exact values only in a narrow band around the level set, a bound beyond).
    fn sample_grid(&self, grid: &Grid, iso: f32, out: &mut [f32]) {
        let _ = iso;
        sample_pointwise(self, grid, out);
    }

    /// Fills `out` with the values at the samples `lo ..= lo + dims - 1` of `grid` (x fastest,
    /// then y, then z), each bitwise equal to [`Field::value`] at `grid.position(..)`, so blocks
    /// that share samples agree on them. The default evaluates [`Field::value`] per sample; a
    /// field that shares work between samples overrides it (terrain computes its height field
    /// once per column).
    fn sample_block(&self, grid: &Grid, lo: [usize; 3], dims: [usize; 3], out: &mut [f32]) {
        let [nx, ny, nz] = dims;
        for z in 0..nz {
            for y in 0..ny {
                for x in 0..nx {
                    out[(z * ny + y) * nx + x] = self.value(grid.position(lo[0] + x, lo[1] + y, lo[2] + z));
                }
            }
        }
    }

    /// The side of `iso` every sample of the block `lo ..= lo + dims - 1` of `grid` lies on, when
    /// the field can prove it without sampling the block; `None` (the default) when it cannot.
    /// Streaming skips such chunks unsampled ([`crate::chunks::stream_chunked`]), so a wrong
    /// answer loses surface: only answer from a proven bound.
    fn block_side(&self, _grid: &Grid, _lo: [usize; 3], _dims: [usize; 3], _iso: f32) -> Option<BlockSide> {
        None
    }

    /// A bound `L` with `|f(p) - f(q)| <= L |p - q|` for all `p`, `q` (world units), when the
    /// field has one: 1 for a signed distance, computed from the frequencies for the gyroid and
    /// the noise fields. Sparse extraction ([`crate::chunks::extract_sparse`]) rules out a box
    /// of half diagonal `r` around `c` when `|f(c) - iso| > L r`, so a bound too small loses
    /// surface: only answer with one that holds. `None` (the default): no bound known.
    fn lipschitz(&self) -> Option<f64> {
        None
    }

    /// The analytic volume enclosed by the level set `iso` within the default domain, where known.
    fn analytic_volume(&self, _iso: f32) -> Option<f64> {
        None
    }

    /// The analytic area of the level set `iso`, where known.
    fn analytic_area(&self, _iso: f32) -> Option<f64> {
        None
    }
}

/// [`Field::value`] at every sample of `grid`, in parallel: each z-slice is one rayon task and
/// one [`Field::sample_block`] (bitwise the pointwise values).
pub fn sample_pointwise<F: Field + ?Sized>(field: &F, grid: &Grid, out: &mut [f32]) {
    let [nx, ny, _] = grid.dims;
    if nx == 0 || ny == 0 {
        return;
    }
    out.par_chunks_mut(nx * ny).enumerate().for_each(|(z, slice)| field.sample_block(grid, [0, 0, z], [nx, ny, 1], slice));
}

/// Central-difference gradient of any field.
pub fn central_difference<F: Field + ?Sized>(field: &F, p: Vec3, h: f32) -> Vec3 {
    let dx = Vec3::new(h, 0.0, 0.0);
    let dy = Vec3::new(0.0, h, 0.0);
    let dz = Vec3::new(0.0, 0.0, h);
    Vec3::new(
        field.value(p + dx) - field.value(p - dx),
        field.value(p + dy) - field.value(p - dy),
        field.value(p + dz) - field.value(p - dz),
    ) / (2.0 * h)
}

/// Errors building a field.
#[derive(Debug, thiserror::Error)]
pub enum FieldError {
    /// No built-in field has this name.
    #[error("unknown field '{name}'; valid fields: {valid}")]
    Unknown {
        /// The name asked for.
        name: String,
        /// Comma-separated valid names.
        valid: String,
    },
    /// A mesh given as a field has no triangles.
    #[error("mesh '{name}' has no triangles")]
    EmptyMesh {
        /// The mesh's name.
        name: String,
    },
    /// A triangle refers to a vertex that does not exist.
    #[error("mesh '{name}': triangle {triangle} refers to vertex {vertex}, but there are only {vertices} vertices")]
    BadIndex {
        /// The mesh's name.
        name: String,
        /// Triangle number (0-based).
        triangle: usize,
        /// The offending index.
        vertex: u32,
        /// How many vertices exist.
        vertices: usize,
    },
    /// A volume's values or geometry cannot be meshed (too few voxels, a non-finite voxel, a
    /// zero or non-finite spacing).
    #[error("volume '{name}': {reason}")]
    BadVolume {
        /// The volume's name.
        name: String,
        /// What is wrong.
        reason: String,
    },
    /// A vertex position is NaN or infinite.
    #[error("mesh '{name}': vertex {vertex} has a non-finite coordinate")]
    NonFiniteVertex {
        /// The mesh's name.
        name: String,
        /// Vertex number (0-based).
        vertex: usize,
    },
}
