//! Slabs: what the grid extractors share to mesh layers of cells in parallel, public so that a
//! new extractor can use them. A volume is cut along z into slabs of cell layers, each meshed by
//! one rayon task into its own buffers; a slab's vertices on its bottom layer belong to the slab
//! below, and indices to them are tagged ([`EXTERN`]) until the slabs are joined in order
//! ([`slab_offsets`], [`join_parts`]), or, when every slab's output was counted first, each writes
//! its own piece of one output sized once ([`mesh_pieces`]). The result is
//! the same mesh on any number of threads. [`ScratchPool`]
//! gives concurrent callers (chunks meshed in parallel) their own reusable buffers;
//! [`split_slab_time`] turns a parallel phase's wall time into the vertex and geometry stage
//! times the reports show.

use crate::extract::ExtractError;
use crate::mesh::TriMesh;
use glam::Vec3;
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
/// otherwise up to four per thread of the pool the slabs run on.
pub fn task_count(parallelism: Parallelism, cells: usize, layers: usize) -> usize {
    match parallelism {
        Parallelism::Serial => 1,
        Parallelism::Rayon => (cells / MIN_CELLS_PER_SLAB).clamp(1, 4 * slab_threads()).min(layers).max(1),
    }
}

thread_local! {
    /// The pool [`on_pool`] named for slab tasks started from this (non-pool) thread.
    static SLAB_POOL: std::cell::RefCell<Option<std::sync::Arc<rayon::ThreadPool>>> = const { std::cell::RefCell::new(None) };
}

/// Runs `f` on the calling thread, with the slab tasks it starts ([`for_each_slab`]) broadcast
/// to `pool`'s threads as they are to the global pool's from outside any pool: the caller sleeps
/// while every thread of the pool starts at once. (`pool.install(f)` would run `f` on a thread
/// of the pool, from where slab tasks are handed out by work stealing, which wakes the other
/// threads one at a time; see [`for_each_slab`].) Other parallel work inside `f` runs on the
/// global pool. `None` runs `f` as it is.
pub fn on_pool<R>(pool: Option<&std::sync::Arc<rayon::ThreadPool>>, f: impl FnOnce() -> R) -> R {
    let Some(pool) = pool else { return f() };
    let previous = SLAB_POOL.with(|p| p.replace(Some(pool.clone())));
    // Restored even if `f` unwinds.
    struct Restore(Option<std::sync::Arc<rayon::ThreadPool>>);
    impl Drop for Restore {
        fn drop(&mut self) {
            let previous = self.0.take();
            SLAB_POOL.with(|p| *p.borrow_mut() = previous);
        }
    }
    let _restore = Restore(previous);
    f()
}

/// The pool [`on_pool`] set for this thread, outside any pool.
fn slab_pool() -> Option<std::sync::Arc<rayon::ThreadPool>> {
    if rayon::current_thread_index().is_some() {
        return None;
    }
    SLAB_POOL.with(|p| p.borrow().clone())
}

/// The threads slab tasks started here run on.
fn slab_threads() -> usize {
    slab_pool().map_or_else(rayon::current_num_threads, |p| p.current_num_threads())
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

/// One slab's piece of a mesh output sized once ([`mesh_pieces`]).
pub struct MeshPiece<'a> {
    /// The slab's vertex positions.
    pub positions: &'a mut [Vec3],
    /// Its normals; empty when the output has none.
    pub normals: &'a mut [Vec3],
    /// Its triangles.
    pub triangles: &'a mut [[u32; 3]],
}

/// Sizes `mesh` once for slabs that make `counts` (vertices, triangles) each, with a normal per
/// vertex when `normals` ([`resize_zeroed`]), and cuts it into one piece per slab, in order: the
/// output of the count-then-write path, where every slab fills its own piece.
pub fn mesh_pieces<'a>(mesh: &'a mut TriMesh, counts: &[(usize, usize)], normals: bool) -> Vec<MeshPiece<'a>> {
    let vertices: usize = counts.iter().map(|c| c.0).sum();
    resize_zeroed(&mut mesh.positions, vertices);
    resize_zeroed(&mut mesh.normals, if normals { vertices } else { 0 });
    resize_zeroed(&mut mesh.triangles, counts.iter().map(|c| c.1).sum());
    let normal_counts = counts.iter().map(|c| if normals { c.0 } else { 0 });
    split_pieces(&mut mesh.positions, counts.iter().map(|c| c.0))
        .into_iter()
        .zip(split_pieces(&mut mesh.normals, normal_counts))
        .zip(split_pieces(&mut mesh.triangles, counts.iter().map(|c| c.1)))
        .map(|((positions, normals), triangles)| MeshPiece { positions, normals, triangles })
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
    let mut pieces = split_pieces(dst, parts.iter().map(|p| p.len()));
    for_each_slab(&mut pieces, |t, piece| fill(t, parts[t], piece));
}

/// Elements a parallel fill task writes at least (keeps rayon's splitting coarse).
const JOIN_MIN_LEN: usize = 1 << 14;

/// Runs `task(t, &mut items[t])` for every item on the rayon pool and returns the results in
/// item order.
///
/// Called from outside any rayon pool (a program's own thread on the global pool, as the command
/// line calls), the caller wakes every thread of the pool at once ([`rayon::broadcast`]) and
/// sleeps until they are done, as VTK's SMP back end does. Each thread takes its own run of
/// consecutive items first, then items left in the others' runs, from the last back. Called from
/// a pool thread (chunks meshed in parallel, or a pool that counts its caller as one of its
/// threads) it is a parallel iterator and rayon's work stealing, which wakes threads one at a
/// time from a working thread.
///
/// Why the broadcast: on the machine the report runs on, a thread woken by a thread that keeps
/// working lands on its waker's CPU and waits there until the scheduler moves it, often a
/// millisecond or more; threads woken by a caller that then sleeps start on both CPUs within
/// tens of microseconds. Measured in a side harness, one-shot marching cubes on two threads after
/// 5 ms idle, medians of 15: gyroid 64³ 1.75 ms from outside against 2.86 ms from a pool thread
/// (serial 2.42). Why the runs: handing items out in turn (0, 1, 2, ... to whichever thread
/// is free) made the sweep of the 256³ gyroid slower than one run per thread (calls of 40 ms
/// against 31 ms), for reasons not found.
pub fn for_each_slab<S, R, F>(items: &mut [S], task: F) -> Vec<R>
where
    S: Send,
    R: Send,
    F: Fn(usize, &mut S) -> R + Sync,
{
    use std::sync::atomic::{AtomicBool, Ordering};
    use std::sync::Mutex;
    let pool = slab_pool();
    if items.len() < 2 || slab_threads() < 2 || rayon::current_thread_index().is_some() {
        return match pool {
            Some(pool) => pool.install(|| items.par_iter_mut().enumerate().map(|(t, item)| task(t, item)).collect()),
            None => items.par_iter_mut().enumerate().map(|(t, item)| task(t, item)).collect(),
        };
    }
    let count = items.len();
    let cells: Vec<Mutex<&mut S>> = items.iter_mut().map(Mutex::new).collect();
    let claimed: Vec<AtomicBool> = (0..count).map(|_| AtomicBool::new(false)).collect();
    let each = |ctx: rayon::BroadcastContext<'_>| {
        let own = ctx.index() * count / ctx.num_threads()..(ctx.index() + 1) * count / ctx.num_threads();
        let others = (0..count).rev().filter(|t| !own.contains(t));
        let mut done = Vec::new();
        for t in own.clone().chain(others) {
            if !claimed[t].swap(true, Ordering::Relaxed) {
                let mut item = cells[t].lock().unwrap_or_else(|e| e.into_inner());
                done.push((t, task(t, &mut item)));
            }
        }
        done
    };
    let per_thread: Vec<Vec<(usize, R)>> = match pool {
        Some(pool) => pool.broadcast(each),
        None => rayon::broadcast(each),
    };
    let mut results: Vec<(usize, R)> = per_thread.into_iter().flatten().collect();
    results.sort_unstable_by_key(|(t, _)| *t);
    results.into_iter().map(|(_, r)| r).collect()
}

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

    /// Every item once, results in item order, from outside a pool (the broadcast) and from
    /// inside one (the parallel iterator), on pools of one to three threads.
    #[test]
    fn every_slab_runs_once_and_results_come_in_order() {
        for threads in 1..=3 {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            for count in [0, 1, 2, 3, 7, 8, 33] {
                let check = |items: &mut Vec<u32>| {
                    let results = for_each_slab(items, |t, item| {
                        *item += 1;
                        (t, rayon::current_thread_index())
                    });
                    assert_eq!(results.iter().map(|r| r.0).collect::<Vec<_>>(), (0..count).collect::<Vec<_>>());
                    assert!(items.iter().all(|&v| v == 1), "{threads} threads, {count} items: {items:?}");
                    results
                };
                // From a thread in no pool: the global pool (broadcast when it has two threads or more).
                let outside = check(&mut vec![0u32; count]);
                assert!(outside.iter().all(|r| r.1.is_some() || rayon::current_num_threads() < 2 || count < 2));
                // From inside `pool`.
                let inside = pool.install(|| check(&mut vec![0u32; count]));
                assert!(inside.iter().all(|r| r.1.is_some_and(|k| k < threads)));
                // From outside, on `pool` (its threads, never the caller's).
                let pool = std::sync::Arc::new(rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap());
                let on = on_pool(Some(&pool), || check(&mut vec![0u32; count]));
                assert!(on.iter().all(|r| r.1.is_some_and(|k| k < threads)), "{threads} threads, {count} items");
                assert_eq!(on_pool(Some(&pool), || task_count(Parallelism::Rayon, 1 << 30, 1000)), 4 * threads);
            }
        }
    }

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
    fn mesh_pieces_cut_one_output_sized_once() {
        let mut mesh = TriMesh::default();
        for normals in [true, false] {
            let pieces = mesh_pieces(&mut mesh, &[(2, 1), (0, 0), (3, 4)], normals);
            let sizes: Vec<_> = pieces.iter().map(|p| (p.positions.len(), p.normals.len(), p.triangles.len())).collect();
            let n = |k: usize| if normals { k } else { 0 };
            assert_eq!(sizes, vec![(2, n(2), 1), (0, 0, 0), (3, n(3), 4)]);
            assert_eq!((mesh.positions.len(), mesh.normals.len(), mesh.triangles.len()), (5, n(5), 5));
        }
    }

    #[test]
    fn slab_time_splits_by_cpu_share() {
        let (v, g) = split_slab_time(Duration::from_millis(100), Duration::from_millis(10), 3.0, 1.0);
        assert_eq!((v, g), (Duration::from_millis(75), Duration::from_millis(35)));
        let (v, g) = split_slab_time(Duration::from_millis(10), Duration::ZERO, 0.0, 0.0);
        assert_eq!(v, g);
    }
}
