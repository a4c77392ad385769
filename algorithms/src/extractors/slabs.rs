//! What the cubic-grid extractors share to mesh slabs of cell layers in parallel: the tag on
//! indices that point into the slab below (resolved when the slabs are joined), how many slabs
//! to cut, and a pool of scratch buffers for concurrent calls.

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

/// Scratch buffers for concurrent calls of one extractor (chunks meshed in parallel): each call
/// takes a set (a new one when all are in use) and gives it back, so calls never wait on each
/// other's buffers and, once the pool holds a set per concurrent caller, re-meshing allocates
/// nothing. (A lock held across the whole call would serialize parallel chunk meshing.)
#[derive(Default)]
pub(crate) struct ScratchPool<T>(std::sync::Mutex<Vec<T>>);

impl<T: Default> ScratchPool<T> {
    /// A free set of buffers, or a new one.
    pub(crate) fn take(&self) -> T {
        self.0.lock().unwrap_or_else(|e| e.into_inner()).pop().unwrap_or_default()
    }

    /// Returns a set for the next call.
    pub(crate) fn give(&self, scratch: T) {
        self.0.lock().unwrap_or_else(|e| e.into_inner()).push(scratch);
    }
}
