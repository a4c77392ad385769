//! What the cubic-grid extractors share to mesh slabs of cell layers in parallel: the tag on
//! indices that point into the slab below (resolved when the slabs are joined) and how many slabs
//! to cut.

use crate::extractors::marching_cubes::Parallelism;

/// Set on a slab-local vertex index that refers to the slab below until the slabs are joined.
pub(crate) const EXTERN: u32 = 1 << 31;

/// Cells per slab task below which the whole grid is one slab.
const MIN_CELLS_PER_SLAB: usize = 32 * 32 * 32;

/// How many slabs to cut `layers` cell layers of `cells` cells into: one when serial or small,
/// otherwise up to four per rayon thread.
pub(crate) fn task_count(parallelism: Parallelism, cells: usize, layers: usize) -> usize {
    match parallelism {
        Parallelism::Serial => 1,
        Parallelism::Rayon => (cells / MIN_CELLS_PER_SLAB).clamp(1, 4 * rayon::current_num_threads()).min(layers).max(1),
    }
}
