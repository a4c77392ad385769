//! One block of a chunked volume meshed on its own, for a driver that runs the blocks elsewhere
//! (a Dask task on another machine, another process, a later run): [`BlockPlan`] says which
//! samples each block reads (its chunk plus the extractor's apron), [`mesh_block`] meshes one
//! block's samples into a [`Fragment`] (its mesh in the volume's index coordinates and a weld key
//! for each vertex another block can share), and [`weld_fragments`] joins fragments, in the
//! plan's order, into exactly the mesh [`extract_chunked`] makes of the whole volume in one
//! process (same vertices in the same order, same triangles; tested).
//!
//! Unlike [`extract_chunked`], a plan takes any volume size: the last block along an axis holds
//! the cells that remain (fewer than `chunk`).

use super::{apron_of, check_chunk_and_size, chunk_ids, weld, Block, ChunkSlot, ChunkState, ChunkStats, WeldPiece};
use crate::extract::{Chunking, ExtractError, Extraction, Extractor};
use crate::field::Field;
use crate::lattice::Grid;
use crate::mesh::TriMesh;
use crate::samples::{AnyView, GridView};
use glam::Vec3;
use std::sync::Arc;

/// The samples one block reads, in the volume's sample indices (x fastest).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BlockBounds {
    /// The chunk's index per axis.
    pub id: [usize; 3],
    /// First sample read per axis.
    pub lo: [usize; 3],
    /// Samples read per axis.
    pub dims: [usize; 3],
}

/// How a volume of `dims` samples splits into blocks of `chunk`³ cells for one extractor.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BlockPlan {
    /// Samples of the whole volume per axis.
    pub dims: [usize; 3],
    /// Cells per chunk along each axis (the last chunk on an axis may have fewer).
    pub chunk: usize,
    /// Blocks per axis.
    pub counts: [usize; 3],
    /// Samples each block reads beyond its chunk on every side (0 for cell-local extractors).
    pub apron: usize,
    chunking: Chunking,
}

impl BlockPlan {
    /// The plan for `extractor` on a volume of `dims` samples, or an error saying why it cannot
    /// mesh in blocks (an extractor that cannot chunk, a chunk under 2 cells, a volume under 2
    /// samples or above 2²⁴ on an axis: the checks [`chunk_counts`](super::chunk_counts) makes, without asking the
    /// chunk to divide the volume).
    pub fn new(extractor: &dyn Extractor, dims: [usize; 3], chunk: usize) -> Result<BlockPlan, ExtractError> {
        let algorithm = extractor.name();
        let chunking = extractor.chunking();
        if chunking == Chunking::Unsupported {
            return Err(ExtractError::BadInput {
                algorithm,
                reason: "it cannot mesh in blocks (its output is a volume or depends on the whole grid)".into(),
            });
        }
        check_chunk_and_size(dims, chunk, algorithm)?;
        if dims.iter().any(|&d| d < 2) {
            return Err(ExtractError::BadInput {
                algorithm,
                reason: format!("a volume of {}x{}x{} samples has no cells", dims[0], dims[1], dims[2]),
            });
        }
        let counts = dims.map(|d| (d - 1).div_ceil(chunk));
        Ok(BlockPlan { dims, chunk, counts, apron: apron_of(chunking), chunking })
    }

    /// Every block, in the order [`weld_fragments`] takes their fragments (x fastest).
    pub fn blocks(&self) -> impl Iterator<Item = BlockBounds> + '_ {
        chunk_ids(self.counts).map(|id| self.bounds(id))
    }

    /// Number of blocks.
    pub fn len(&self) -> usize {
        self.counts.iter().product()
    }

    /// Whether the plan has no blocks (never: a volume has at least one cell).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The block of chunk `id`, or `None` outside the plan.
    pub fn block(&self, id: [usize; 3]) -> Option<BlockBounds> {
        (0..3).all(|a| id[a] < self.counts[a]).then(|| self.bounds(id))
    }

    fn bounds(&self, id: [usize; 3]) -> BlockBounds {
        let b = self.inner(id);
        BlockBounds { id, lo: b.lo, dims: b.dims }
    }

    fn inner(&self, id: [usize; 3]) -> Block {
        Block::new(id, self.chunk, self.apron, self.dims)
    }
}

/// One meshed block: what a task hands back or stores.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Fragment {
    /// The chunk's index per axis.
    pub id: [usize; 3],
    /// Whether it was meshed or skipped as all outside or all inside.
    pub state: ChunkState,
    /// Its mesh, positions in the volume's sample index coordinates.
    pub surface: TriMesh,
    /// Per vertex: its weld key (the same in every block that makes the vertex), or `None` for a
    /// vertex no other block can make.
    pub keys: Vec<Option<u128>>,
    /// Cells the extractor found crossing the surface.
    pub active_cells: usize,
    /// Triangles the extractor discarded (degenerate).
    pub discarded_triangles: usize,
}

/// The block of chunk `id`, or an error naming it when it is outside the plan.
fn block_in(plan: &BlockPlan, id: [usize; 3], algorithm: &'static str) -> Result<BlockBounds, ExtractError> {
    plan.block(id).ok_or_else(|| ExtractError::BadInput {
        algorithm,
        reason: format!("block {id:?} is outside the plan's {:?} blocks", plan.counts),
    })
}

/// Meshes the block of chunk `id` from its samples (`plan.block(id)`'s `dims`, x fastest, inside
/// where a value is below `iso`). A sample count that does not match, a chunk outside the plan
/// or a non-finite sample is an error naming it.
pub fn mesh_block(
    extractor: &dyn Extractor,
    plan: &BlockPlan,
    id: [usize; 3],
    values: Vec<f32>,
    iso: f32,
) -> Result<Fragment, ExtractError> {
    let algorithm = extractor.name();
    let bad = |reason: String| ExtractError::BadInput { algorithm, reason };
    let bounds = block_in(plan, id, algorithm)?;
    let expected: usize = bounds.dims.iter().product();
    if values.len() != expected {
        return Err(bad(format!(
            "block {id:?} needs {}x{}x{} = {expected} samples (from sample {:?}); it was given {}",
            bounds.dims[0],
            bounds.dims[1],
            bounds.dims[2],
            bounds.lo,
            values.len()
        )));
    }
    let view = GridView::contiguous(&values, bounds.dims).map_err(|e| bad(e.to_string()))?;
    mesh_block_view(extractor, plan, id, view.into(), iso)
}

/// [`mesh_block`] of samples where they lie (a block of a caller's array, in its own type and
/// memory order, read with the view's sign), with no copy for an extractor that reads them in
/// place.
pub fn mesh_block_view(
    extractor: &dyn Extractor,
    plan: &BlockPlan,
    id: [usize; 3],
    values: AnyView<'_>,
    iso: f32,
) -> Result<Fragment, ExtractError> {
    mesh_block_view_of(extractor, plan, id, values, iso, None)
}

/// [`mesh_block_view`] of samples of a known field on the dense grid `world`: the extractor may
/// read the field (marching cubes its analytic gradient for normals, dual contouring its
/// gradient for Hermite data) as it does when the whole grid is meshed in chunks, so the
/// block's mesh is [`extract_chunked`](super::extract_chunked)'s.
pub fn mesh_block_view_of(
    extractor: &dyn Extractor,
    plan: &BlockPlan,
    id: [usize; 3],
    values: AnyView<'_>,
    iso: f32,
    field: Option<(&Arc<dyn Field>, &Grid)>,
) -> Result<Fragment, ExtractError> {
    let algorithm = extractor.name();
    let bad = |reason: String| ExtractError::BadInput { algorithm, reason };
    let bounds = block_in(plan, id, algorithm)?;
    if values.dims() != bounds.dims {
        let [x, y, z] = bounds.dims;
        return Err(bad(format!(
            "block {id:?} needs {x}x{y}x{z} samples (from sample {:?}); it was given {:?}",
            bounds.lo,
            values.dims()
        )));
    }
    let range = values.range();
    if let Some(([x, y, z], v)) = range.non_finite {
        let at = [bounds.lo[0] + x, bounds.lo[1] + y, bounds.lo[2] + z];
        return Err(bad(format!("sample {at:?} is {v}: every sample must be finite")));
    }
    let grid = Grid { origin: Vec3::ZERO, spacing: 1.0, dims: plan.dims };
    let mut slot = ChunkSlot::with_view(id, plan.inner(id), values, iso, field)
        .ok_or_else(|| bad(format!("block {id:?}: its samples do not fit its block")))?;
    slot.mesh_loaded(extractor, plan.chunking, &grid, range.min, range.max)?;
    let stats = &slot.mesh.stats;
    Ok(Fragment {
        id,
        state: slot.state,
        active_cells: stats.active_cells,
        discarded_triangles: stats.discarded_triangles,
        surface: std::mem::take(&mut slot.mesh.surface),
        keys: std::mem::take(&mut slot.keys),
    })
}

/// Welds fragments, given in the plan's block order, into `out` (cleared first): vertices with
/// the same key become one (the first fragment's position and normal kept), as
/// [`extract_chunked`](super::extract_chunked) welds its chunks.
pub fn weld_fragments<'a>(fragments: impl IntoIterator<Item = &'a Fragment>, out: &mut Extraction) -> ChunkStats {
    out.clear();
    let mut stats = ChunkStats::default();
    weld(fragments.into_iter().map(Fragment::piece), out, &mut stats);
    out.finish_counts(0);
    stats
}

impl Fragment {
    pub(super) fn piece(&self) -> WeldPiece<'_> {
        WeldPiece {
            state: self.state,
            surface: &self.surface,
            keys: &self.keys,
            active_cells: self.active_cells,
            discarded_triangles: self.discarded_triangles,
        }
    }
}
