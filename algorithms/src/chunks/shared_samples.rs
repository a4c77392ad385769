//! Samples shared between the blocks of a sparse extraction ([`super::sparse`]), each evaluated
//! once.
//!
//! A block reads its chunk's samples, the face layer it shares with the next block on each axis
//! and its extractor's apron: with 4-cell blocks, 125 samples of which only 64 are its own, so
//! sampling each block on its own evaluates a thin shell of blocks about twice (warp's
//! `sparse_marching_cubes` evaluates each grid point once). Here every sample has one owner, the
//! block whose *core* holds it (the block's chunk of samples, half-open, the last block on an
//! axis closed on the grid's last sample), and its value is kept with that core. A block is
//! *scheduled* by naming the samples of its box that no earlier block asked for; once they are
//! evaluated, it is *gathered* from the cores its box overlaps. The values are the ones a block
//! evaluated on its own would get (the same points, rounded to `f32` the same way), so meshes do
//! not change by a bit. Cores a later block cannot read are retired as the blocks' z layer
//! advances, so memory holds about three layers of kept blocks' cores, never the dense grid.

use super::sparse::SparseGrid;
use super::BlockBounds;
use rayon::prelude::*;
use rustc_hash::FxHashMap;

/// A value not asked for yet.
const UNKNOWN: f32 = f32::NAN;
/// A value asked for and not yet evaluated. The mark only keeps a sample from being asked for
/// twice, so an evaluated value that rounds to an infinite `f32` may share it.
const ASKED: f32 = f32::INFINITY;

/// The values of one block's core.
struct Core {
    id: [usize; 3],
    lo: [usize; 3],
    dims: [usize; 3],
    values: Vec<f32>,
}

impl Core {
    /// Where `sample` (inside the core) lies in its values.
    fn offset(&self, sample: [usize; 3]) -> usize {
        self.dims[0] * ((sample[1] - self.lo[1]) + self.dims[1] * (sample[2] - self.lo[2])) + sample[0] - self.lo[0]
    }
}

/// The cores of the blocks read so far, and the samples asked for and not yet evaluated.
pub(super) struct SharedSamples {
    dims: [usize; 3],
    chunk: usize,
    counts: [usize; 3],
    index: FxHashMap<[usize; 3], u32>,
    cores: Vec<Core>,
    free: Vec<u32>,
    /// Per sample asked for, in the order asked: its core and index in it.
    asked: Vec<(u32, usize)>,
    /// The spans of the blocks scheduled since the last gather, in order.
    spans: Vec<Span>,
    /// Per block scheduled since the last gather, where its spans start.
    blocks: Vec<(BlockBounds, usize)>,
}

/// The part of a block's box (samples `lo..hi` per axis) one core holds.
#[derive(Clone, Copy)]
struct Span {
    core: u32,
    lo: [usize; 3],
    hi: [usize; 3],
}

/// Where a block's scheduling started, to undo it ([`SharedSamples::undo`]).
#[derive(Clone, Copy)]
pub(super) struct Mark {
    asked: usize,
    spans: usize,
    blocks: usize,
}

impl SharedSamples {
    /// No sample known yet, for a grid of `dims` samples in blocks of `chunk` cells, `counts`
    /// blocks per axis.
    pub(super) fn new(dims: [usize; 3], chunk: usize, counts: [usize; 3]) -> SharedSamples {
        SharedSamples {
            dims,
            chunk,
            counts,
            index: FxHashMap::default(),
            cores: Vec::new(),
            free: Vec::new(),
            asked: Vec::new(),
            spans: Vec::new(),
            blocks: Vec::new(),
        }
    }

    /// The block whose core holds sample `i` along axis `a`.
    fn owner(&self, a: usize, i: usize) -> usize {
        (i / self.chunk).min(self.counts[a] - 1)
    }

    /// The samples of block `n`'s core along axis `a`: first, and one past the last.
    fn core_range(&self, a: usize, n: usize) -> (usize, usize) {
        let end = if n + 1 == self.counts[a] { self.dims[a] } else { (n + 1) * self.chunk };
        (n * self.chunk, end)
    }

    /// The core of block `id`, made empty (every value unknown) if no block has read it.
    fn core(&mut self, id: [usize; 3]) -> u32 {
        if let Some(&c) = self.index.get(&id) {
            return c;
        }
        let ranges = [0, 1, 2].map(|a| self.core_range(a, id[a]));
        let lo = ranges.map(|r| r.0);
        let dims = ranges.map(|r| r.1 - r.0);
        let len = dims.iter().product();
        let c = match self.free.pop() {
            Some(c) => {
                let core = &mut self.cores[c as usize];
                (core.id, core.lo, core.dims) = (id, lo, dims);
                core.values.clear();
                core.values.resize(len, UNKNOWN);
                c
            }
            None => {
                self.cores.push(Core { id, lo, dims, values: vec![UNKNOWN; len] });
                (self.cores.len() - 1) as u32
            }
        };
        self.index.insert(id, c);
        c
    }

    /// The cores block `b`'s box overlaps, with the part of the box in each, appended to
    /// `self.spans` (at most 27 when the apron is at most a chunk: a box is one chunk and twice
    /// the apron wide).
    fn overlaps(&mut self, b: &BlockBounds) {
        let first = [0, 1, 2].map(|a| self.owner(a, b.lo[a]));
        let last = [0, 1, 2].map(|a| self.owner(a, b.lo[a] + b.dims[a] - 1));
        for z in first[2]..=last[2] {
            for y in first[1]..=last[1] {
                for x in first[0]..=last[0] {
                    let id = [x, y, z];
                    let r = [0, 1, 2].map(|a| self.core_range(a, id[a]));
                    let lo = [0, 1, 2].map(|a| r[a].0.max(b.lo[a]));
                    let hi = [0, 1, 2].map(|a| r[a].1.min(b.lo[a] + b.dims[a]));
                    let core = self.core(id);
                    self.spans.push(Span { core, lo, hi });
                }
            }
        }
    }

    /// The value of `sample` if it is known (evaluated, or kept by [`SharedSamples::know`]).
    /// Not for a sample asked for and not yet evaluated: call it between a gather and the next
    /// schedule.
    pub(super) fn value(&self, sample: [usize; 3]) -> Option<f32> {
        let id = [0, 1, 2].map(|a| self.owner(a, sample[a]));
        let core = &self.cores[*self.index.get(&id)? as usize];
        let v = core.values[core.offset(sample)];
        (!v.is_nan()).then_some(v)
    }

    /// Keeps the value of `sample` evaluated elsewhere (the pruning's), unless the sample is
    /// already asked for or known: no block asks for it again.
    pub(super) fn know(&mut self, sample: [usize; 3], value: f32) {
        let id = [0, 1, 2].map(|a| self.owner(a, sample[a]));
        let c = self.core(id);
        let i = self.cores[c as usize].offset(sample);
        let v = &mut self.cores[c as usize].values[i];
        if v.is_nan() {
            *v = value;
        }
    }

    /// Where the next block's scheduling starts.
    pub(super) fn mark(&self) -> Mark {
        Mark { asked: self.asked.len(), spans: self.spans.len(), blocks: self.blocks.len() }
    }

    /// Samples asked for and not yet filled.
    pub(super) fn asked(&self) -> usize {
        self.asked.len()
    }

    /// Asks for the samples of block `b` no block has asked for yet; [`SharedSamples::points`]
    /// gives their points, in the order [`SharedSamples::fill`] takes their values.
    pub(super) fn schedule(&mut self, b: &BlockBounds) {
        let first = self.spans.len();
        self.blocks.push((*b, first));
        self.overlaps(b);
        for s in &self.spans[first..] {
            let core = &mut self.cores[s.core as usize];
            let n = s.hi[0] - s.lo[0];
            for z in s.lo[2]..s.hi[2] {
                for y in s.lo[1]..s.hi[1] {
                    let start = core.dims[0] * ((y - core.lo[1]) + core.dims[1] * (z - core.lo[2])) + s.lo[0] - core.lo[0];
                    for (i, v) in core.values[start..start + n].iter_mut().enumerate() {
                        if v.is_nan() {
                            *v = ASKED;
                            self.asked.push((s.core, start + i));
                        }
                    }
                }
            }
        }
    }

    /// The world points of the samples asked for, in order (`out` is overwritten; in parallel).
    pub(super) fn points(&self, grid: &SparseGrid, out: &mut Vec<[f64; 3]>) {
        self.asked
            .par_iter()
            .map(|&(c, i)| {
                let core = &self.cores[c as usize];
                let (x, yz) = (i % core.dims[0], i / core.dims[0]);
                let (y, z) = (yz % core.dims[1], yz / core.dims[1]);
                grid.point([core.lo[0] + x, core.lo[1] + y, core.lo[2] + z])
            })
            .collect_into_vec(out);
    }

    /// Undoes the scheduling since `mark` (a block left for the next batch).
    pub(super) fn undo(&mut self, mark: Mark) {
        for &(c, i) in &self.asked[mark.asked..] {
            self.cores[c as usize].values[i] = UNKNOWN;
        }
        self.asked.truncate(mark.asked);
        self.spans.truncate(mark.spans);
        self.blocks.truncate(mark.blocks);
    }

    /// Keeps the values of the samples asked for, in the order their points were pushed.
    pub(super) fn fill(&mut self, values: &[f64]) {
        debug_assert_eq!(values.len(), self.asked.len());
        for (&(c, i), &v) in self.asked.iter().zip(values) {
            self.cores[c as usize].values[i] = v as f32;
        }
        self.asked.clear();
    }

    /// The samples of the blocks scheduled since the last gather, each block's box x fastest,
    /// one after another (`out` is overwritten), with where each block's run starts; every one
    /// must have been filled. In parallel over the blocks.
    pub(super) fn gather(&mut self, out: &mut Vec<f32>, offsets: &mut Vec<usize>) {
        offsets.clear();
        let mut total = 0;
        for (b, _) in &self.blocks {
            offsets.push(total);
            total += b.dims.iter().product::<usize>();
        }
        out.clear();
        out.resize(total, UNKNOWN);
        let mut runs = Vec::with_capacity(self.blocks.len());
        let mut rest = &mut out[..];
        for (b, _) in &self.blocks {
            let (run, tail) = rest.split_at_mut(b.dims.iter().product());
            runs.push(run);
            rest = tail;
        }
        let (cores, spans, blocks) = (&self.cores, &self.spans, &self.blocks);
        runs.into_par_iter().enumerate().for_each(|(k, run)| {
            let (b, first) = blocks[k];
            let end = blocks.get(k + 1).map_or(spans.len(), |n| n.1);
            for s in &spans[first..end] {
                let core = &cores[s.core as usize];
                let n = s.hi[0] - s.lo[0];
                for z in s.lo[2]..s.hi[2] {
                    for y in s.lo[1]..s.hi[1] {
                        let from = core.dims[0] * ((y - core.lo[1]) + core.dims[1] * (z - core.lo[2])) + s.lo[0] - core.lo[0];
                        let to = (s.lo[0] - b.lo[0]) + b.dims[0] * ((y - b.lo[1]) + b.dims[1] * (z - b.lo[2]));
                        run[to..to + n].copy_from_slice(&core.values[from..from + n]);
                    }
                }
            }
        });
        self.spans.clear();
        self.blocks.clear();
    }

    /// Forgets the cores below sample layer `z` (no later block reads them).
    pub(super) fn retire_below(&mut self, z: usize) {
        let layer = self.owner(2, z);
        let cores = &self.cores;
        let free = &mut self.free;
        self.index.retain(|_, &mut c| {
            let keep = cores[c as usize].id[2] >= layer;
            if !keep {
                free.push(c);
            }
            keep
        });
    }

    /// Cores held.
    #[cfg(test)]
    fn held(&self) -> usize {
        self.index.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn block(plan_dims: [usize; 3], chunk: usize, apron: usize, id: [usize; 3]) -> BlockBounds {
        let lo = id.map(|i| (i * chunk).saturating_sub(apron));
        let dims = [0, 1, 2].map(|a| (id[a] * chunk + chunk + apron).min(plan_dims[a] - 1) - lo[a] + 1);
        BlockBounds { id, lo, dims }
    }

    #[test]
    fn every_sample_is_asked_for_once_and_every_block_gets_its_own_samples_back() {
        // 11 x 9 x 10 samples in blocks of 4 cells with an apron of 1: every block scheduled in
        // order, each gathered block holds the value of each of its samples' positions, and no
        // point is asked for twice; over all blocks, every sample is asked for exactly once.
        let dims = [11, 9, 10];
        let (chunk, apron) = (4, 1);
        let counts = dims.map(|d: usize| (d - 1).div_ceil(chunk));
        let grid = SparseGrid { origin: [0.0; 3], spacing: 1.0, dims };
        let value = |p: [f64; 3]| p[0] + 100.0 * p[1] + 10_000.0 * p[2];
        let mut shared = SharedSamples::new(dims, chunk, counts);
        let mut asked = std::collections::HashSet::new();
        for z in 0..counts[2] {
            for y in 0..counts[1] {
                for x in 0..counts[0] {
                    let b = block(dims, chunk, apron, [x, y, z]);
                    // Scheduling undone leaves nothing asked for.
                    let mark = shared.mark();
                    shared.schedule(&b);
                    shared.undo(mark);
                    assert_eq!(shared.asked(), 0);
                    shared.schedule(&b);
                    let mut points = Vec::new();
                    shared.points(&grid, &mut points);
                    for p in &points {
                        assert!(asked.insert(p.map(|v| v as usize)), "{p:?} asked for twice");
                    }
                    shared.fill(&points.iter().map(|&p| value(p)).collect::<Vec<_>>());
                    let (mut out, mut offsets) = (Vec::new(), Vec::new());
                    shared.gather(&mut out, &mut offsets);
                    assert_eq!(offsets, [0]);
                    let mut i = 0;
                    for sz in 0..b.dims[2] {
                        for sy in 0..b.dims[1] {
                            for sx in 0..b.dims[0] {
                                let p = grid.point([b.lo[0] + sx, b.lo[1] + sy, b.lo[2] + sz]);
                                assert_eq!(out[i], value(p) as f32, "block {:?} sample {:?}", b.id, [sx, sy, sz]);
                                i += 1;
                            }
                        }
                    }
                }
            }
            shared.retire_below(((z + 1) * chunk).saturating_sub(apron));
            // About three layers of cores at most.
            assert!(shared.held() <= 3 * counts[0] * counts[1], "{} cores held", shared.held());
        }
        assert_eq!(asked.len(), dims.iter().product::<usize>());
    }
}
