//! What [`super::extract_lod`] hands a dual method (surface nets, dual contouring) after the
//! restriction, and the trait such a method implements to mesh chunks at mixed levels
//! ([`crate::extractors::dual::lod`] is the dual engine's).

use crate::field::Field;
use crate::lattice::Grid;
use crate::mesh::TriMesh;

/// A chunked grid whose chunks have levels of detail, as [`super::extract_lod`] hands it to a
/// [`DualLevels`] method.
#[derive(Clone, Copy)]
pub struct LodGrid<'a> {
    /// The whole grid; positions are made in its sample indices and placed by it at the end.
    pub grid: Grid,
    /// The samples, finer ones on coarser chunks' boundaries restricted.
    pub values: &'a [f32],
    /// The iso-value (inside below).
    pub iso: f32,
    /// The field, for dual contouring's normals where the samples carry it.
    pub field: Option<&'a dyn Field>,
    /// Cells per chunk along each axis (at full resolution).
    pub chunk: usize,
    /// Chunks per axis.
    pub counts: [usize; 3],
    /// Each chunk's level (x fastest): its cells have `2^level` samples a side.
    pub levels: &'a [u8],
}

/// What a [`DualLevels`] method made besides the mesh.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct DualLodCounts {
    /// Polygons on minimal edges between chunks of different levels.
    pub seam_polygons: usize,
    /// Crossing minimal edges whose coarse cell had no piece to give (0 in every test; left open).
    pub unmatched: usize,
    /// Vertices split where a seam edge had four triangles (`pinch`: where two rings met).
    pub pinched: usize,
    /// Intersection-free levels (manifold dual contouring): cells with several pieces of surface
    /// whose triangles still cross after the fallback (0 in every test).
    pub crossing_cells: usize,
}

/// A dual method's own meshing of chunks at mixed levels (the dual engine's octree minimal
/// edges, [`crate::extractors::dual::lod`]), named by [`crate::LevelsOfDetail::Dual`]: after the
/// restriction, it meshes the whole grid at once.
pub trait DualLevels: Sync {
    /// Meshes `g` into `out` (cleared first); `levels`, if given, receives each triangle's level.
    fn extract_lod(&self, g: LodGrid<'_>, out: &mut TriMesh, levels: Option<&mut Vec<u8>>) -> DualLodCounts;
}
