//! Slabs: what the grid extractors share to mesh layers of cells in parallel, public so that a
//! new extractor can use them. A volume is cut along z into slabs of cell layers, each meshed by
//! one rayon task into its own buffers; a slab's vertices on its bottom layer belong to the slab
//! below, and indices to them are tagged ([`EXTERN`]) until the slabs are joined in order
//! ([`slab_offsets`], [`join_parts`]), or, when every slab's output was counted first, each writes
//! its own piece of one output sized once ([`resize_zeroed`], [`split_pieces`]). The result is
//! the same mesh on any number of threads. [`ScratchPool`]
//! gives concurrent callers (chunks meshed in parallel) their own reusable buffers;
//! [`split_slab_time`] turns a parallel phase's wall time into the vertex and geometry stage
//! times the reports show.

use crate::extract::ExtractError;
use rayon::prelude::*;
use std::time::Duration;

/// Whether slabs run in parallel.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Parallelism {
    /// Slabs in parallel on the rayon pool (one slab for small grids).
    #[default]
    Rayon,
    /// One slab, on the calling thread.
    Serial,
}

/// Set on a slab-local vertex index that refers to the slab below until the slabs are joined.
pub const EXTERN: u32 = 1 << 31;

/// Cells per slab task below which the whole grid is one slab.
const MIN_CELLS_PER_SLAB: usize = 32 * 32 * 32;

/// Elements per rayon task in per-vertex passes (smoothing, normals): below it a pass runs as
/// one task on the calling thread, since waking a second thread for a few thousand vertices
/// costs more than it saves (a dirty terrain chunk has about three thousand).
pub const MIN_VERTICES_PER_TASK: usize = 8192;

/// How many slabs to cut `layers` cell layers of `cells` cells into: one when serial or small,
/// otherwise up to four per rayon thread.
pub fn task_count(parallelism: Parallelism, cells: usize, layers: usize) -> usize {
    match parallelism {
        Parallelism::Serial => 1,
        Parallelism::Rayon => (cells / MIN_CELLS_PER_SLAB).clamp(1, 4 * rayon::current_num_threads()).min(layers).max(1),
    }
}

/// The first global vertex index of each slab when slabs of `counts` vertices are joined in
/// order, and the total last; more vertices than untagged indices can hold is an error naming
/// `algorithm`.
pub fn slab_offsets(counts: impl Iterator<Item = usize>, algorithm: &'static str) -> Result<Vec<usize>, ExtractError> {
    let mut offsets = vec![0usize];
    for n in counts {
        offsets.push(offsets[offsets.len() - 1] + n);
    }
    let total = offsets[offsets.len() - 1];
    if total >= EXTERN as usize {
        return Err(ExtractError::TooLarge { algorithm, vertices: total });
    }
    Ok(offsets)
}

/// Splits a parallel slab phase's wall time between the vertex and the geometry pass in
/// proportion to the CPU time each took across tasks (`cpu_vertex`, `cpu_geometry`, seconds);
/// the join's time goes to the geometry pass. Returns (vertex, geometry).
pub fn split_slab_time(slab_wall: Duration, join: Duration, cpu_vertex: f64, cpu_geometry: f64) -> (Duration, Duration) {
    let share = if cpu_vertex + cpu_geometry > 0.0 { cpu_vertex / (cpu_vertex + cpu_geometry) } else { 0.5 };
    (slab_wall.mul_f64(share), slab_wall.mul_f64(1.0 - share) + join)
}

/// Grows `buffer` to at least `len` elements of `T::default()`. A new buffer is allocated zeroed
/// (`vec![0; len]`, which the allocator serves with untouched zero pages), not filled: a slab's per-layer index
/// arrays are written only where the surface passes, so a one-shot call touches only those pages
/// instead of zero-filling every slab's arrays.
pub fn grow_zeroed<T: Copy + Default>(buffer: &mut Vec<T>, len: usize) {
    if buffer.len() >= len {
        return;
    }
    if buffer.capacity() == 0 {
        // For integers, `vec![0; n]` is `alloc_zeroed` (calloc): fresh zero pages, not a fill.
        *buffer = vec![T::default(); len];
    } else {
        buffer.resize(len, T::default());
    }
}

/// Makes `dst` `len` zeroes long, ready to be cut into pieces that rayon tasks fill. A fresh
/// `dst` (too little capacity) is allocated zeroed, which the allocator serves with untouched zero
/// pages, so the tasks' writes are the output's first and only touch, made on every thread; a
/// reused one is zero-filled in parallel.
pub fn resize_zeroed<T: bytemuck::Zeroable + Copy + Send + Sync>(dst: &mut Vec<T>, len: usize) {
    dst.clear();
    if dst.capacity() < len {
        *dst = bytemuck::allocation::zeroed_vec(len);
    } else {
        dst.par_extend(rayon::iter::repeat_n(T::zeroed(), len).with_min_len(JOIN_MIN_LEN));
    }
}

/// Cuts `slice` into consecutive pieces of `lens` elements (the rest, if any, is left out).
pub fn split_pieces<T>(slice: &mut [T], lens: impl IntoIterator<Item = usize>) -> Vec<&mut [T]> {
    let mut rest = slice;
    lens.into_iter()
        .map(|n| {
            let (piece, tail) = std::mem::take(&mut rest).split_at_mut(n);
            rest = tail;
            piece
        })
        .collect()
}

/// Joins slab parts into `dst` (cleared first) in parallel: `dst` is sized to the parts' total
/// ([`resize_zeroed`]), cut into one piece per part, and `fill(t, part, piece)` writes part `t`
/// into its piece on a rayon task (a copy, or a copy that resolves indices).
pub fn join_parts<T, F>(dst: &mut Vec<T>, parts: &[&[T]], fill: F)
where
    T: bytemuck::Zeroable + Copy + Send + Sync,
    F: Fn(usize, &[T], &mut [T]) + Sync,
{
    resize_zeroed(dst, parts.iter().map(|p| p.len()).sum());
    let pieces = split_pieces(dst, parts.iter().map(|p| p.len()));
    pieces.into_par_iter().zip(parts.par_iter()).enumerate().for_each(|(t, (piece, part))| fill(t, part, piece));
}

/// Elements a parallel fill task writes at least (keeps rayon's splitting coarse).
const JOIN_MIN_LEN: usize = 1 << 14;

/// Scratch buffers for concurrent calls of one extractor (chunks meshed in parallel): each call
/// takes a set (a new one when all are in use) and gives it back, so calls never wait on each
/// other's buffers and, once the pool holds a set per concurrent caller, re-meshing allocates
/// nothing. (A lock held across the whole call would serialize parallel chunk meshing.)
#[derive(Default)]
pub struct ScratchPool<T>(std::sync::Mutex<Vec<T>>);

impl<T: Default> ScratchPool<T> {
    /// A free set of buffers, or a new one.
    pub fn take(&self) -> T {
        self.0.lock().unwrap_or_else(|e| e.into_inner()).pop().unwrap_or_default()
    }

    /// Returns a set for the next call.
    pub fn give(&self, scratch: T) {
        self.0.lock().unwrap_or_else(|e| e.into_inner()).push(scratch);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn offsets_accumulate_and_refuse_overflow() {
        assert_eq!(slab_offsets([3, 0, 5].into_iter(), "x").unwrap(), vec![0, 3, 3, 8]);
        let e = slab_offsets([EXTERN as usize - 1, 1].into_iter(), "x").unwrap_err();
        assert!(matches!(e, ExtractError::TooLarge { vertices, .. } if vertices == EXTERN as usize));
        assert_eq!(task_count(Parallelism::Serial, 1 << 30, 100), 1);
        assert_eq!(task_count(Parallelism::Rayon, 10, 100), 1);
    }

    #[test]
    fn parts_join_in_order_into_fresh_and_reused_outputs() {
        let parts: [&[u32]; 4] = [&[1, 2, 3], &[], &[4], &[5, 6]];
        // Fresh (no capacity: zeroed allocation), then reused (capacity kept: parallel fill).
        let mut dst = Vec::new();
        for round in 0..2 {
            join_parts(&mut dst, &parts, |t, part, piece| {
                for (d, s) in piece.iter_mut().zip(part) {
                    *d = s + 10 * t as u32;
                }
            });
            assert_eq!(dst, vec![1, 2, 3, 24, 35, 36], "round {round}");
        }
        let mut longer = vec![7u32; 9];
        resize_zeroed(&mut longer, 5);
        assert_eq!(longer, vec![0; 5]);
        let mut data = [0u8, 1, 2, 3, 4, 5];
        let pieces = split_pieces(&mut data, [2, 0, 3]);
        assert_eq!(pieces.iter().map(|p| p.to_vec()).collect::<Vec<_>>(), vec![vec![0, 1], vec![], vec![2, 3, 4]]);
    }

    #[test]
    fn slab_time_splits_by_cpu_share() {
        let (v, g) = split_slab_time(Duration::from_millis(100), Duration::from_millis(10), 3.0, 1.0);
        assert_eq!((v, g), (Duration::from_millis(75), Duration::from_millis(35)));
        let (v, g) = split_slab_time(Duration::from_millis(10), Duration::ZERO, 0.0, 0.0);
        assert_eq!(v, g);
    }
}
