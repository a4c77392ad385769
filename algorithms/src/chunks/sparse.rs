//! A field meshed from evaluations near its surface only: the grid is split into the blocks of a
//! [`BlockPlan`], whole octants of blocks are ruled out from one evaluation at their centre, and
//! only the surviving blocks are sampled (each with its extractor's apron; a sample two blocks
//! read is evaluated once, [`super::shared_samples`]), meshed by
//! [`mesh_block_view`] and welded as they come, as [`weld_fragments`](super::weld_fragments) welds. Memory holds one
//! batch of samples, the samples of about three layers of kept blocks, the octree's leaves (16
//! bytes each), the mesh and the weld keys of two block layers, never the dense grid.
//!
//! **Certified pruning** ([`Pruning::Lipschitz`]), after libigl's Lipschitz octree (PRs #2488
//! and #2541) and warp's `sparse_marching_cubes`: a field with `|f(p) - f(q)| <= L |p - q|` has
//! the sign of `f(c) - iso` at every sample of a box of half diagonal `r` around `c` when
//! `|f(c) - iso| > L r`. Such a box is all outside or all inside, so a dense chunked extraction
//! would skip its blocks too, and the sparse mesh equals the dense one exactly (same vertices
//! in the same order, same triangles; tested). A small relative margin covers the rounding of
//! samples to `f32`.
//!
//! Below the blocks the test goes on where a bound is loose: a leaf of the octree (a block no
//! centre ruled out) is split in halves, and quarters, and dropped when every part is proven on
//! one side ([`refine_leaves`]). A Lipschitz bound far above the field's usual slope (the
//! asteroid's 9, from its noise's steepest octaves) keeps a shell of blocks several blocks
//! thick around the surface; its parts' smaller radii rule out most of that shell. At 1024³
//! from the CLI the asteroid's kept blocks fell from 1,553,590 to 776,988 and its evaluations
//! from 107 to 64 million; a signed distance (bound 1) gains a few percent. The halves' centres
//! of a 4-cell block are grid samples, and a kept block's are not evaluated again.
//!
//! **Heuristic pruning** ([`Pruning::SignChange`]), as occupancy networks' MISE refines: the
//! block corners are evaluated on a coarse grid, the blocks whose corners disagree in sign are
//! kept with their neighbours (`margin` blocks around them). It misses a surface part that lies
//! wholly inside the blocks it drops (a sphere smaller than a block between coarse samples, a
//! thin sheet that crosses no coarse edge twice ...): no certificate.
//!
//! [`Pruning::Dense`] samples every block, for comparison.
//!
//! **Why one file of about 950 lines.** The octree, its refinement and the sampling loop take
//! turns on one evaluator and one [`SharedSamples`]: the refinement runs between sampling groups
//! and hands its grid-sample values to the sampling, so their order is one contract read in one
//! place. A third of the file is tests. The refinement could move to a module of its own beside
//! `shared_samples`; not done yet.

use super::shared_samples::SharedSamples;
use super::{mesh_block_view_of, BlockBounds, BlockPlan, ChunkStats, Fragment, Welder};
use crate::extract::{ExtractError, Extraction, Extractor};
use crate::field::Field;
use crate::lattice::Grid;
use crate::samples::GridView;
use glam::Vec3;
use rayon::prelude::*;
use rustc_hash::FxHashMap;
use std::collections::VecDeque;
use std::sync::Arc;
use std::time::{Duration, Instant};

/// A field evaluated at batches of world points: `out` gets one value per point.
pub trait BatchEval {
    /// Evaluates `points`, writing `out` (cleared first). An error is passed back unchanged.
    fn eval(&mut self, points: &[[f64; 3]], out: &mut Vec<f64>) -> Result<(), EvalError>;

    /// The field evaluated and the dense grid whose samples the points are, when the evaluator
    /// is a field on a grid ([`GridFieldEval`]): extractors then read the field as they do when
    /// meshing the dense grid (gradients for normals and Hermite data), and the sparse mesh is
    /// the dense one. `None` (the default): they read the samples only.
    fn field_on_grid(&self) -> Option<(&Arc<dyn Field>, &Grid)> {
        None
    }
}

/// What a [`BatchEval`] may fail with, carried back to its caller unchanged.
pub type EvalError = Box<dyn std::error::Error + Send + Sync>;

/// A built-in or mesh field as a [`BatchEval`] (points rounded to `f32`, the field's type),
/// evaluated in parallel.
pub struct FieldEval<'a>(pub &'a dyn Field);

impl BatchEval for FieldEval<'_> {
    fn eval(&mut self, points: &[[f64; 3]], out: &mut Vec<f64>) -> Result<(), EvalError> {
        out.clear();
        points
            .par_iter()
            .map(|p| f64::from(self.0.value(Vec3::new(p[0] as f32, p[1] as f32, p[2] as f32))))
            .collect_into_vec(out);
        Ok(())
    }
}

/// A field evaluated where a dense [`Grid`]'s samples lie, bitwise: a point at a sample index
/// (within 10⁻⁶ of one) is evaluated at [`Grid::position`] of it, in `f32` as dense sampling
/// computes it, so sparse and dense meshes of the grid agree to the bit; any other point (an
/// octree centre) at the point rounded to `f32`. In parallel.
pub struct GridFieldEval {
    /// The field.
    pub field: Arc<dyn Field>,
    /// The dense grid the samples belong to.
    pub grid: Grid,
}

impl BatchEval for GridFieldEval {
    fn field_on_grid(&self) -> Option<(&Arc<dyn Field>, &Grid)> {
        Some((&self.field, &self.grid))
    }

    fn eval(&mut self, points: &[[f64; 3]], out: &mut Vec<f64>) -> Result<(), EvalError> {
        out.clear();
        let g = self.grid;
        let (origin, h) = (g.origin.to_array().map(f64::from), f64::from(g.spacing));
        points
            .par_iter()
            .map(|p| {
                let t = [0, 1, 2].map(|a| (p[a] - origin[a]) / h);
                let on_grid = t.iter().all(|&t| t >= -1e-6 && (t - t.round()).abs() < 1e-6);
                let at = if on_grid {
                    g.position(t[0].round() as usize, t[1].round() as usize, t[2].round() as usize)
                } else {
                    Vec3::new(p[0] as f32, p[1] as f32, p[2] as f32)
                };
                f64::from(self.field.value(at))
            })
            .collect_into_vec(out);
        Ok(())
    }
}

/// The grid a sparse extraction samples: sample `i` at `origin + i * spacing`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SparseGrid {
    /// The first sample's world position.
    pub origin: [f64; 3],
    /// Distance between samples along every axis.
    pub spacing: f64,
    /// Samples per axis.
    pub dims: [usize; 3],
}

impl SparseGrid {
    /// The grid with `resolution` samples along the longest side of the box `lo..hi`, the first
    /// on `lo`, the last along the longest side on `hi`; along a shorter side the samples that
    /// fit, rounded to the nearest (the last within half a spacing of the bound).
    pub fn from_bounds(lo: [f64; 3], hi: [f64; 3], resolution: usize) -> Result<SparseGrid, String> {
        if resolution < 2 {
            return Err(format!("resolution {resolution}: at least 2 samples are needed along the longest side"));
        }
        let extent = [hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]];
        if lo.iter().chain(&hi).any(|v| !v.is_finite()) || extent.iter().any(|&e| e.is_nan() || e <= 0.0) {
            return Err(format!("bounds {lo:?}..{hi:?}: every upper bound must be finite and above its lower bound"));
        }
        let longest = extent.iter().copied().fold(0.0, f64::max);
        let spacing = longest / (resolution - 1) as f64;
        let dims = extent.map(|e| ((e / spacing).round() as usize).max(1) + 1);
        Ok(SparseGrid { origin: lo, spacing, dims })
    }

    /// The grid of a dense [`Grid`]'s samples (its `f32` origin and spacing, widened).
    pub fn of(grid: &Grid) -> SparseGrid {
        SparseGrid { origin: grid.origin.to_array().map(f64::from), spacing: f64::from(grid.spacing), dims: grid.dims }
    }

    /// The world position of sample `i`.
    pub fn point(&self, i: [usize; 3]) -> [f64; 3] {
        [0, 1, 2].map(|a| self.origin[a] + i[a] as f64 * self.spacing)
    }
}

/// How blocks are ruled out before they are sampled.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Pruning {
    /// Certified by a Lipschitz bound of the field (world units).
    Lipschitz(f64),
    /// A heuristic: blocks whose corners on a coarse grid change sign, and `margin` blocks
    /// around them.
    SignChange {
        /// Blocks kept around each block that sees a sign change.
        margin: usize,
    },
    /// None: every block is sampled.
    Dense,
}

/// Settings of a sparse extraction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SparseOptions {
    /// Cells per block side.
    pub chunk: usize,
    /// Points per evaluation call, at most.
    pub batch: usize,
    /// How blocks are ruled out.
    pub pruning: Pruning,
}

impl SparseOptions {
    /// The block size sparse extraction uses unless told: 4 cells for a cell-local extractor
    /// (small blocks follow the surface closely, for a little more time in the octree; on the
    /// sphere at 1024³, from Python, 58x fewer evaluations than dense with shared samples
    /// evaluated once, 37x when each block evaluated its own), four
    /// times the apron, and at least 8, for one with an apron (a block reads its apron on every
    /// side, so small blocks would read mostly apron).
    pub fn default_chunk(extractor: &dyn Extractor) -> usize {
        match extractor.chunking() {
            crate::extract::Chunking::Apron(a) => (4 * a).max(8),
            _ => 4,
        }
    }
}

impl Default for SparseOptions {
    fn default() -> Self {
        SparseOptions { chunk: 16, batch: 1 << 16, pruning: Pruning::Dense }
    }
}

/// What a sparse extraction did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SparseStats {
    /// Points evaluated, in all.
    pub evaluations: u64,
    /// Of those, the points evaluated to rule blocks out (octree centres, coarse corners, the
    /// refinement's centres); the rest are grid samples, each evaluated once. A refinement centre
    /// that is a grid sample is not evaluated again.
    pub pruning_evaluations: u64,
    /// Of the pruning's, the points evaluated refining the octree's leaves below a block.
    pub refinement_evaluations: u64,
    /// Evaluation calls.
    pub batches: u64,
    /// Time inside the evaluation calls.
    pub eval_time: Duration,
    /// Time outside them (pruning, meshing, welding).
    pub other_time: Duration,
    /// Blocks of the plan.
    pub blocks: usize,
    /// Blocks sampled and meshed.
    pub sampled_blocks: usize,
    /// Points the dense grid has.
    pub dense_points: u64,
}

/// Why a sparse extraction failed.
#[derive(Debug, thiserror::Error)]
pub enum SparseError {
    /// The evaluation failed; its error, unchanged.
    #[error("the field's evaluation failed: {0}")]
    Eval(EvalError),
    /// The evaluation returned a wrong number of values or a non-finite one.
    #[error("batch {batch} (points in {lo:?}..{hi:?}): {reason}")]
    BadBatch {
        /// The batch's number, from 0.
        batch: u64,
        /// The smallest coordinates among its points.
        lo: [f64; 3],
        /// The largest.
        hi: [f64; 3],
        /// What is wrong.
        reason: String,
    },
    /// The grid or the extractor cannot mesh in blocks.
    #[error(transparent)]
    Extract(#[from] ExtractError),
}

/// Evaluates points in batches of at most `batch`, checking each batch's answer and counting.
struct Evaluator<'e> {
    eval: &'e mut dyn BatchEval,
    batch: usize,
    stats: SparseStats,
    buffer: Vec<f64>,
}

impl Evaluator<'_> {
    fn values(&mut self, points: &[[f64; 3]], out: &mut Vec<f64>) -> Result<(), SparseError> {
        out.clear();
        out.reserve(points.len());
        for part in points.chunks(self.batch.max(1)) {
            let number = self.stats.batches;
            self.stats.batches += 1;
            self.stats.evaluations += part.len() as u64;
            let t = Instant::now();
            let result = self.eval.eval(part, &mut self.buffer);
            self.stats.eval_time += t.elapsed();
            result.map_err(SparseError::Eval)?;
            let bad = |reason: String| {
                let lo = [0, 1, 2].map(|a| part.iter().map(|p| p[a]).fold(f64::INFINITY, f64::min));
                let hi = [0, 1, 2].map(|a| part.iter().map(|p| p[a]).fold(f64::NEG_INFINITY, f64::max));
                SparseError::BadBatch { batch: number, lo, hi, reason }
            };
            if self.buffer.len() != part.len() {
                return Err(bad(format!(
                    "{} points gave {} values; one value per point is needed",
                    part.len(),
                    self.buffer.len()
                )));
            }
            if let Some(i) = self.buffer.iter().position(|v| !v.is_finite()) {
                return Err(bad(format!("the value at point {:?} is {}; every value must be finite", part[i], self.buffer[i])));
            }
            out.extend_from_slice(&self.buffer);
        }
        Ok(())
    }
}

/// A box of blocks: block ids `lo..hi` per axis.
#[derive(Clone, Copy, Debug)]
struct Octant {
    lo: [usize; 3],
    hi: [usize; 3],
}

/// Meshes the field `eval` gives on `grid` with `extractor`, sampling only the blocks pruning
/// keeps, into `out` (positions in world units). With [`Pruning::Lipschitz`] holding for the
/// field (and [`Pruning::Dense`]), the mesh is exactly [`extract_chunked`](super::extract_chunked)'s of the dense grid in
/// blocks of `options.chunk`.
pub fn extract_sparse(
    extractor: &dyn Extractor,
    grid: &SparseGrid,
    iso: f32,
    options: &SparseOptions,
    eval: &mut dyn BatchEval,
    out: &mut Extraction,
) -> Result<SparseStats, SparseError> {
    let start = Instant::now();
    let plan = BlockPlan::new(extractor, grid.dims, options.chunk)?;
    let mut ev = Evaluator { eval, batch: options.batch, stats: SparseStats::default(), buffer: Vec::new() };
    ev.stats.blocks = plan.len();
    ev.stats.dense_points = grid.dims.iter().map(|&d| d as u64).product();
    let candidates = match options.pruning {
        Pruning::Dense => Candidates::listed(plan.blocks().map(|b| b.id).collect()),
        Pruning::Lipschitz(l) => Candidates::Leaves { leaves: lipschitz_leaves(&plan, grid, iso, l, &mut ev)?, next: 0, l },
        Pruning::SignChange { margin } => Candidates::listed(sign_change_blocks(&plan, grid, iso, margin, &mut ev)?),
    };
    ev.stats.pruning_evaluations = ev.stats.evaluations;
    // Each group's fragments are welded as they come, in the plan's order; a pruned block would
    // be skipped as all outside or all inside, which adds nothing to the weld. With blocks
    // thicker than twice their apron no vertex is made two block layers apart, so the weld keeps
    // the keys of two layers only.
    let field = ev.eval.field_on_grid().map(|(f, g)| (f.clone(), *g));
    let field = field.as_ref().map(|(f, g)| (f, g));
    let mut welder = Welder::new(out);
    let mut weld_stats = ChunkStats::default();
    let retire = plan.chunk > 2 * plan.apron;
    let (mut points, mut values, mut samples) = (Vec::new(), Vec::new(), Vec::<f32>::new());
    let mut shared = SharedSamples::new(grid.dims, plan.chunk, plan.counts);
    let mut kept = KeptBlocks { candidates, queue: VecDeque::new(), scratch: RefineScratch::default() };
    // Enough blocks queued for one batch of new samples, refined between groups (when no sample
    // is asked for and not evaluated).
    let enough = (2 * options.batch / plan.chunk.pow(3)).max(1);
    kept.refill(enough, &plan, grid, iso, &mut ev, &mut shared)?;
    let mut layer = kept.queue.front().map_or(0, |id| id[2]);
    let mut group: Vec<BlockBounds> = Vec::new();
    let mut offsets = Vec::new();
    while !kept.queue.is_empty() {
        // A group of blocks whose samples not yet evaluated make about one batch (at least one
        // block); a sample shared with an earlier block is evaluated once.
        group.clear();
        while let Some(b) = kept.queue.front().and_then(|&id| plan.block(id)) {
            let mark = shared.mark();
            shared.schedule(&b);
            if !group.is_empty() && shared.asked() > options.batch {
                shared.undo(mark);
                break;
            }
            group.push(b);
            kept.queue.pop_front();
        }
        ev.stats.sampled_blocks += group.len();
        check_output_memory(extractor, ev.stats.sampled_blocks, plan.chunk, out.memory_limit)?;
        shared.points(grid, &mut points);
        ev.values(&points, &mut values)?;
        shared.fill(&values);
        // The samples as the extractors read them, each block's run gathered from the cores it
        // overlaps; each block meshes its run where it lies.
        shared.gather(&mut samples, &mut offsets);
        kept.refill(enough, &plan, grid, iso, &mut ev, &mut shared)?;
        if let Some(next) = kept.queue.front() {
            shared.retire_below((next[2] * plan.chunk).saturating_sub(plan.apron));
        }
        let meshed: Vec<Result<Fragment, ExtractError>> = group
            .par_iter()
            .zip(&offsets)
            .map(|(b, &off)| {
                let view = GridView::contiguous(&samples[off..off + block_points(b)], b.dims)
                    .map_err(|e| ExtractError::BadInput { algorithm: extractor.name(), reason: e.to_string() })?;
                mesh_block_view_of(extractor, &plan, b.id, view.into(), iso, field)
            })
            .collect();
        for f in meshed {
            let f = f?;
            while retire && layer < f.id[2] {
                welder.retire();
                layer += 1;
            }
            welder.add(f.piece(), out, &mut weld_stats);
        }
    }
    welder.finish(out);
    to_world(grid, out);
    // As extract_chunked: a field with an analytic gradient gives the normals.
    super::field_normals(field.map(|(f, _)| f), out);
    out.finish_counts(0);
    let eval_time = ev.stats.eval_time;
    ev.stats.other_time = start.elapsed().saturating_sub(eval_time);
    Ok(ev.stats)
}

/// Bytes of surface a kept block is taken to add: a smooth surface crosses about `chunk²` of
/// its cells, each about one vertex (position and normal, 24 bytes) and two triangles (24),
/// weld keys aside. On the sphere at 2048³ (911,492 blocks of 4 cells) this estimates 668 MiB;
/// the CLI's run peaked at 660 MiB.
const SURFACE_BYTES_PER_BLOCK_FACE_CELL: u64 = 48;

/// Refuses a mesh the memory allowed cannot hold, before the samples of the blocks that would
/// pass the limit are evaluated (`kept` blocks so far).
fn check_output_memory(extractor: &dyn Extractor, kept: usize, chunk: usize, limit: Option<u64>) -> Result<(), SparseError> {
    let cells = kept as u64 * (chunk * chunk) as u64;
    let needed = cells * SURFACE_BYTES_PER_BLOCK_FACE_CELL;
    match limit {
        Some(limit) if needed > limit => Err(SparseError::Extract(ExtractError::OverMemory {
            algorithm: extractor.name(),
            needed,
            limit,
            vertices: cells as usize,
        })),
        _ => Ok(()),
    }
}

/// Samples a block reads.
fn block_points(b: &BlockBounds) -> usize {
    b.dims.iter().product()
}

/// Positions from sample indices to world units: `origin + index * spacing`, in `f32` as dense
/// chunked meshing computes it when the origin and spacing are `f32` values (a grid taken from a
/// [`Grid`]: the same bits), in `f64` otherwise (bounds given in `f64`).
fn to_world(grid: &SparseGrid, out: &mut Extraction) {
    let origin = grid.origin.map(|o| o as f32);
    let spacing = grid.spacing as f32;
    let single = (0..3).all(|a| f64::from(origin[a]) == grid.origin[a]) && f64::from(spacing) == grid.spacing;
    for p in &mut out.surface.positions {
        *p = if single {
            Vec3::from(origin) + *p * spacing
        } else {
            Vec3::new(
                (grid.origin[0] + f64::from(p.x) * grid.spacing) as f32,
                (grid.origin[1] + f64::from(p.y) * grid.spacing) as f32,
                (grid.origin[2] + f64::from(p.z) * grid.spacing) as f32,
            )
        };
    }
}

/// The samples an octant's blocks read: first and last sample index per axis.
fn octant_samples(plan: &BlockPlan, o: &Octant) -> ([usize; 3], [usize; 3]) {
    let (Some(first), Some(last)) = (plan.block(o.lo), plan.block([o.hi[0] - 1, o.hi[1] - 1, o.hi[2] - 1])) else {
        return ([0; 3], [0; 3]);
    };
    (first.lo, [0, 1, 2].map(|a| last.lo[a] + last.dims[a] - 1))
}

/// Whether a value `d = f(c) - iso` proves the box of half diagonal `r` one-sided for a field
/// of Lipschitz bound `l`: `|d| > l r`, with a margin for the rounding of samples to `f32`.
fn proves_one_side(d: f64, l: f64, r: f64, iso: f32) -> bool {
    let rounding = 1e-5 * (f64::from(iso).abs() + d.abs()) + f64::from(f32::MIN_POSITIVE);
    d.abs() > l * r * (1.0 + 1e-9) + rounding
}

/// An octree leaf: a block no centre's value ruled out, and the value at its box's centre (as
/// a sample keeps it, rounded to `f32`).
#[derive(Clone, Copy)]
struct Leaf {
    id: [u32; 3],
    value: f32,
}

/// The leaves of an octree over the blocks that no centre's value rules out, in the plan's
/// order, one level evaluated per batch run.
fn lipschitz_leaves(plan: &BlockPlan, grid: &SparseGrid, iso: f32, l: f64, ev: &mut Evaluator) -> Result<Vec<Leaf>, SparseError> {
    let mut leaves = Vec::new();
    let mut level = vec![Octant { lo: [0; 3], hi: plan.counts }];
    let (mut centres, mut values) = (Vec::new(), Vec::new());
    while !level.is_empty() {
        centres.clear();
        let mut radii = Vec::with_capacity(level.len());
        for o in &level {
            let (lo, hi) = octant_samples(plan, o);
            centres.push(box_centre(grid, lo, hi));
            radii.push(half_diagonal(grid, lo, hi));
        }
        ev.values(&centres, &mut values)?;
        let mut next = Vec::new();
        for ((o, &v), &r) in level.iter().zip(&values).zip(&radii) {
            if proves_one_side(v - f64::from(iso), l, r, iso) {
                continue;
            }
            if (0..3).any(|a| o.hi[a] - o.lo[a] > 1) {
                split(o, &mut next);
            } else {
                leaves.push(Leaf { id: o.lo.map(|i| i as u32), value: v as f32 });
            }
        }
        level = next;
    }
    leaves.sort_unstable_by_key(|leaf| [leaf.id[2], leaf.id[1], leaf.id[0]]);
    Ok(leaves)
}

/// The world position of the centre of the samples `lo..=hi`: a grid sample's own position
/// (bitwise [`SparseGrid::point`]) when every axis has an even sum.
fn box_centre(grid: &SparseGrid, lo: [usize; 3], hi: [usize; 3]) -> [f64; 3] {
    [0, 1, 2].map(|a| grid.origin[a] + (lo[a] + hi[a]) as f64 * 0.5 * grid.spacing)
}

/// Half the diagonal of the samples `lo..=hi`, in world units.
fn half_diagonal(grid: &SparseGrid, lo: [usize; 3], hi: [usize; 3]) -> f64 {
    let half = [0, 1, 2].map(|a| (hi[a] - lo[a]) as f64 * 0.5 * grid.spacing);
    (half[0] * half[0] + half[1] * half[1] + half[2] * half[2]).sqrt()
}

/// The blocks a pruning leaves to sample, in the plan's order.
enum Candidates {
    /// Blocks kept as they are (every block, or the sign-change heuristic's).
    Listed { ids: Vec<[usize; 3]>, next: usize },
    /// The Lipschitz octree's leaves, refined a group at a time ([`refine_leaves`]).
    Leaves { leaves: Vec<Leaf>, next: usize, l: f64 },
}

impl Candidates {
    fn listed(ids: Vec<[usize; 3]>) -> Candidates {
        Candidates::Listed { ids, next: 0 }
    }
}

/// The blocks to sample, in the plan's order: leaves are refined as the blocks before them are
/// sampled, so memory holds a few groups of leaves' refinement, not the whole octree's.
struct KeptBlocks {
    candidates: Candidates,
    queue: VecDeque<[usize; 3]>,
    scratch: RefineScratch,
}

impl KeptBlocks {
    /// Queues blocks until `enough` are queued or no candidate is left, refining leaves a group
    /// at a time. Called between groups only: no sample is then asked for and not evaluated.
    fn refill(
        &mut self,
        enough: usize,
        plan: &BlockPlan,
        grid: &SparseGrid,
        iso: f32,
        ev: &mut Evaluator,
        shared: &mut SharedSamples,
    ) -> Result<(), SparseError> {
        while self.queue.len() < enough {
            match &mut self.candidates {
                Candidates::Listed { ids, next } => {
                    let end = (*next + enough).min(ids.len());
                    if *next == end {
                        return Ok(());
                    }
                    self.queue.extend(&ids[*next..end]);
                    *next = end;
                }
                Candidates::Leaves { leaves, next, l } => {
                    let end = (*next + (ev.batch / 8).clamp(1, REFINED_AT_ONCE)).min(leaves.len());
                    if *next == end {
                        return Ok(());
                    }
                    refine_leaves(plan, grid, iso, *l, &leaves[*next..end], ev, shared, &mut self.queue, &mut self.scratch)?;
                    *next = end;
                }
            }
        }
        Ok(())
    }
}

/// A box of samples `lo..=hi` inside one leaf's block, with `d = f(centre) - iso`.
struct SubBox {
    leaf: usize,
    lo: [usize; 3],
    hi: [usize; 3],
    d: f64,
}

/// The buffers [`refine_leaves`] reuses from one group of leaves to the next.
#[derive(Default)]
struct RefineScratch {
    state: Vec<Refined>,
    known: Vec<(usize, [usize; 3], f32)>,
    nodes: Vec<SubBox>,
    children: Vec<SubBox>,
    centres: Vec<[f64; 3]>,
    values: Vec<Answer>,
    asked: Vec<(usize, Option<[usize; 3]>)>,
    answers: Vec<f64>,
    same: FxHashMap<[usize; 3], usize>,
}

/// A part's value: a sample's known value, or the `k`-th of the level's evaluations.
#[derive(Clone, Copy)]
enum Answer {
    Known(f32),
    Asked(usize),
}

/// What refining a leaf has shown: every part of its box proven on one side so far (`0` none
/// yet, `-1` inside, `1` outside), or the block is needed (a part cannot be proven one-sided,
/// or two parts lie on opposite sides).
#[derive(Clone, Copy, PartialEq)]
enum Refined {
    OneSide(i8),
    Needed,
}

/// Leaves refined in one group, at most: their first halves are one batch of `8 x` this (or
/// `batch`) points, and the group's buffers stay small.
const REFINED_AT_ONCE: usize = 4096;

/// Levels of halves a leaf's box is refined into, at most: a leaf costs at most 8 + 64
/// evaluations (for 4-cell blocks, down to boxes of one cell).
const REFINEMENT_LEVELS: usize = 2;

/// Refines `leaves`, pushing the blocks still needed onto `kept` in their order. A leaf's box is
/// split in halves along every axis at least two cells wide, and its halves are tested as the
/// octree tests blocks, for [`REFINEMENT_LEVELS`]; a block whose parts are all proven on the
/// same side is dropped, as a dense run skips it. A part is split only where its value could
/// prove its halves (`|d| > L r_half`); otherwise its block is kept at once. A centre on the
/// grid (the leaf's, and for 4-cell blocks its first halves') whose sample is known is not
/// evaluated, and one evaluated is kept for the sampling, which does not evaluate it again: for
/// the blocks kept, and with an apron (where a neighbour's box holds it) for all.
#[allow(clippy::too_many_arguments)]
fn refine_leaves(
    plan: &BlockPlan,
    grid: &SparseGrid,
    iso: f32,
    l: f64,
    leaves: &[Leaf],
    ev: &mut Evaluator,
    shared: &mut SharedSamples,
    kept: &mut VecDeque<[usize; 3]>,
    scratch: &mut RefineScratch,
) -> Result<(), SparseError> {
    let RefineScratch { state, known, nodes, children, centres, values, asked, answers, same } = scratch;
    state.clear();
    state.resize(leaves.len(), Refined::OneSide(0));
    known.clear();
    nodes.clear();
    same.clear();
    // Without an apron a centre inside one block's box is no other block's sample: none is known
    // before this block's refinement, and no two blocks share one.
    let shared_centres = plan.apron > 0;
    for (k, leaf) in leaves.iter().enumerate() {
        let Some(b) = plan.block(leaf.id.map(|i| i as usize)) else { continue };
        let hi = [0, 1, 2].map(|a| b.lo[a] + b.dims[a] - 1);
        if let Some(s) = grid_sample(b.lo, hi) {
            if plan.apron > 0 {
                shared.know(s, leaf.value);
            } else {
                known.push((k, s, leaf.value));
            }
        }
        nodes.push(SubBox { leaf: k, lo: b.lo, hi, d: f64::from(leaf.value) - f64::from(iso) });
    }
    for level in 1..=REFINEMENT_LEVELS + 1 {
        if level > REFINEMENT_LEVELS {
            for n in nodes.iter() {
                state[n.leaf] = Refined::Needed;
            }
            break;
        }
        children.clear();
        for n in nodes.iter() {
            if state[n.leaf] == Refined::Needed {
                continue;
            }
            let before = children.len();
            split_samples(n, children);
            let promising = children.get(before).is_some_and(|c| n.d.abs() > l * half_diagonal(grid, c.lo, c.hi));
            if !promising {
                children.truncate(before);
                state[n.leaf] = Refined::Needed;
            }
        }
        children.retain(|c| state[c.leaf] != Refined::Needed);
        if children.is_empty() {
            break;
        }
        // Centres whose sample is known take its value; the others are evaluated, a centre two
        // parts share (with an apron, neighbours' boxes overlap) once.
        values.clear();
        asked.clear();
        centres.clear();
        same.clear();
        for c in children.iter() {
            let sample = grid_sample(c.lo, c.hi);
            if shared_centres {
                if let Some(v) = sample.and_then(|s| shared.value(s)) {
                    values.push(Answer::Known(v));
                    continue;
                }
                if let Some(&k) = sample.and_then(|s| same.get(&s)) {
                    values.push(Answer::Asked(k));
                    continue;
                }
                if let Some(s) = sample {
                    same.insert(s, centres.len());
                }
            }
            values.push(Answer::Asked(centres.len()));
            asked.push((c.leaf, sample));
            centres.push(box_centre(grid, c.lo, c.hi));
        }
        let before = ev.stats.evaluations;
        ev.values(centres, answers)?;
        ev.stats.pruning_evaluations += ev.stats.evaluations - before;
        ev.stats.refinement_evaluations += ev.stats.evaluations - before;
        for (&(leaf, sample), &v) in asked.iter().zip(answers.iter()) {
            match sample {
                // With an apron another block's box may hold it: kept now, whatever this
                // leaf's fate. Without, only this block reads it: kept if the block is.
                Some(s) if shared_centres => shared.know(s, v as f32),
                Some(s) => known.push((leaf, s, v as f32)),
                None => {}
            }
        }
        nodes.clear();
        for (mut c, &v) in children.drain(..).zip(values.iter()) {
            let v = match v {
                Answer::Known(v) => f64::from(v),
                Answer::Asked(k) => answers[k],
            };
            c.d = v - f64::from(iso);
            if !proves_one_side(c.d, l, half_diagonal(grid, c.lo, c.hi), iso) {
                nodes.push(c);
                continue;
            }
            let side = if c.d > 0.0 { 1 } else { -1 };
            state[c.leaf] = match state[c.leaf] {
                Refined::OneSide(0) => Refined::OneSide(side),
                Refined::OneSide(s) if s == side => Refined::OneSide(s),
                _ => Refined::Needed,
            };
        }
    }
    for (leaf, s) in leaves.iter().zip(state.iter()) {
        if *s == Refined::Needed {
            kept.push_back(leaf.id.map(|i| i as usize));
        }
    }
    for &(k, sample, value) in known.iter() {
        if state[k] == Refined::Needed {
            shared.know(sample, value);
        }
    }
    Ok(())
}

/// The grid sample at the centre of the samples `lo..=hi`, if the centre is one.
fn grid_sample(lo: [usize; 3], hi: [usize; 3]) -> Option<[usize; 3]> {
    (0..3).all(|a| (lo[a] + hi[a]) % 2 == 0).then(|| [0, 1, 2].map(|a| (lo[a] + hi[a]) / 2))
}

/// The halves of a box of samples along every axis at least two cells wide (sharing the middle
/// plane, so together they hold every sample of the box); none when no axis is.
fn split_samples(b: &SubBox, out: &mut Vec<SubBox>) {
    if (0..3).all(|a| b.hi[a] - b.lo[a] < 2) {
        return;
    }
    let halves = |a: usize| {
        let (lo, hi) = (b.lo[a], b.hi[a]);
        let mid = lo + (hi - lo) / 2;
        if hi - lo >= 2 {
            [(lo, mid), (mid, hi)].into_iter().take(2)
        } else {
            [(lo, hi), (lo, hi)].into_iter().take(1)
        }
    };
    for (z0, z1) in halves(2) {
        for (y0, y1) in halves(1) {
            for (x0, x1) in halves(0) {
                out.push(SubBox { leaf: b.leaf, lo: [x0, y0, z0], hi: [x1, y1, z1], d: 0.0 });
            }
        }
    }
}

/// The eight (or fewer) halves of an octant.
fn split(o: &Octant, out: &mut Vec<Octant>) {
    let halves = |a: usize| {
        let mid = o.lo[a] + (o.hi[a] - o.lo[a]).div_ceil(2);
        if o.hi[a] - o.lo[a] > 1 {
            vec![(o.lo[a], mid), (mid, o.hi[a])]
        } else {
            vec![(o.lo[a], o.hi[a])]
        }
    };
    for &(z0, z1) in &halves(2) {
        for &(y0, y1) in &halves(1) {
            for &(x0, x1) in &halves(0) {
                out.push(Octant { lo: [x0, y0, z0], hi: [x1, y1, z1] });
            }
        }
    }
}

fn for_each_block(o: &Octant, mut f: impl FnMut([usize; 3])) {
    for z in o.lo[2]..o.hi[2] {
        for y in o.lo[1]..o.hi[1] {
            for x in o.lo[0]..o.hi[0] {
                f([x, y, z]);
            }
        }
    }
}

/// The blocks the sign-change heuristic keeps, in the plan's order: those whose corners on the
/// coarse grid of block corners disagree in sign, and `margin` blocks around each. The coarse
/// grid is evaluated one plane of corners at a time.
fn sign_change_blocks(
    plan: &BlockPlan,
    grid: &SparseGrid,
    iso: f32,
    margin: usize,
    ev: &mut Evaluator,
) -> Result<Vec<[usize; 3]>, SparseError> {
    // Block corners along an axis: chunk boundaries, and the grid's last sample.
    let coarse = |a: usize| -> Vec<usize> {
        let mut c: Vec<usize> = (0..plan.counts[a]).map(|b| b * plan.chunk).collect();
        c.push(grid.dims[a] - 1);
        c
    };
    let (cx, cy, cz) = (coarse(0), coarse(1), coarse(2));
    let counts = plan.counts;
    let plane = |k: usize, ev: &mut Evaluator| -> Result<Vec<bool>, SparseError> {
        let z = cz[k];
        let cx = &cx;
        let points: Vec<[f64; 3]> = cy.iter().flat_map(|&y| cx.iter().map(move |&x| grid.point([x, y, z]))).collect();
        let mut values = Vec::new();
        ev.values(&points, &mut values)?;
        Ok(values.iter().map(|&v| (v as f32) < iso).collect())
    };
    let mut changed = std::collections::BTreeSet::new();
    let mut below = plane(0, ev)?;
    for z in 0..counts[2] {
        let above = plane(z + 1, ev)?;
        for y in 0..counts[1] {
            for x in 0..counts[0] {
                let corner = |c: usize| {
                    let layer = if c >> 2 & 1 == 1 { &above } else { &below };
                    layer[x + (c & 1) + cx.len() * (y + (c >> 1 & 1))]
                };
                if (1..8).any(|c| corner(c) != corner(0)) {
                    let at = [x, y, z];
                    let o = Octant {
                        lo: at.map(|v| v.saturating_sub(margin)),
                        hi: [0, 1, 2].map(|a| (at[a] + margin + 1).min(counts[a])),
                    };
                    for_each_block(&o, |id| {
                        changed.insert([id[2], id[1], id[0]]);
                    });
                }
            }
        }
        below = above;
    }
    Ok(changed.into_iter().map(|[z, y, x]| [x, y, z]).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grids_from_bounds_put_the_first_and_last_samples_on_the_longest_side() {
        let g = SparseGrid::from_bounds([-1.0, -1.0, -0.5], [1.0, 1.0, 0.5], 65).unwrap();
        assert_eq!(g.dims, [65, 65, 33]);
        assert_eq!(g.point([64, 64, 32]), [1.0, 1.0, 0.5]);
        assert!(SparseGrid::from_bounds([0.0; 3], [1.0; 3], 1).is_err());
        assert!(SparseGrid::from_bounds([0.0; 3], [1.0, 0.0, 1.0], 8).is_err());
        assert!(SparseGrid::from_bounds([0.0; 3], [1.0, f64::NAN, 1.0], 8).is_err());
    }

    #[test]
    fn octants_split_into_halves_that_cover_them_once() {
        let mut out = Vec::new();
        split(&Octant { lo: [0, 0, 0], hi: [5, 1, 2] }, &mut out);
        assert_eq!(out.len(), 4);
        let mut seen = std::collections::HashSet::new();
        for o in &out {
            for_each_block(o, |id| assert!(seen.insert(id), "{id:?} twice"));
        }
        assert_eq!(seen.len(), 10);
    }

    /// `x - 5.2` at world points (Lipschitz 1).
    struct Plane;

    impl BatchEval for Plane {
        fn eval(&mut self, points: &[[f64; 3]], out: &mut Vec<f64>) -> Result<(), EvalError> {
            out.clear();
            out.extend(points.iter().map(|p| p[0] - 5.2));
            Ok(())
        }
    }

    #[test]
    fn refinement_drops_a_leaf_whose_halves_prove_one_side_and_keeps_its_grid_samples_values() {
        // Blocks of 4 cells on 13 x 9 x 9 samples, spacing 1: the surface x = 5.2 crosses the
        // blocks x = 1 only. The blocks x = 0 (centre value -3.2) are leaves the octree cannot
        // rule out (half diagonal 2√3 ≈ 3.46); the blocks x = 2 (4.8) it would rule out, and
        // are given as leaves anyway. Their halves (centres at x = 1, 3 or 9, 11; half
        // diagonal √3) prove them one-sided: dropped. The blocks x = 1 are kept, their
        // centre's value known to the sampling.
        let mc = crate::extractors::by_name("marching-cubes").expect("marching cubes");
        let plan = BlockPlan::new(mc.as_ref(), [13, 9, 9], 4).expect("plan");
        let grid = SparseGrid { origin: [0.0; 3], spacing: 1.0, dims: [13, 9, 9] };
        let mut plane = Plane;
        let mut ev = Evaluator { eval: &mut plane, batch: 64, stats: SparseStats::default(), buffer: Vec::new() };
        let mut shared = SharedSamples::new(grid.dims, plan.chunk, plan.counts);
        let leaves: Vec<Leaf> =
            plan.blocks().map(|b| Leaf { id: b.id.map(|i| i as u32), value: (b.lo[0] as f64 + 2.0 - 5.2) as f32 }).collect();
        let mut kept = VecDeque::new();
        refine_leaves(&plan, &grid, 0.0, 1.0, &leaves, &mut ev, &mut shared, &mut kept, &mut RefineScratch::default())
            .expect("refined");
        let kept: Vec<[usize; 3]> = kept.into_iter().collect();
        let expected: Vec<[usize; 3]> = plan.blocks().map(|b| b.id).filter(|id| id[0] == 1).collect();
        assert_eq!(kept, expected);
        // The kept blocks were not split (their centre's 0.8 cannot prove a half): only their
        // centre is known; the dropped blocks' halves cost 8 evaluations each.
        assert_eq!(ev.stats.refinement_evaluations, 8 * 8);
        for id in &kept {
            let b = plan.block(*id).expect("block");
            let centre = b.lo.map(|l| l + 2);
            assert_eq!(shared.value(centre), Some(0.8));
            assert_eq!(shared.value([centre[0] - 1, centre[1], centre[2]]), None);
        }
    }

    #[test]
    fn halves_hold_every_sample_of_their_box() {
        let b = SubBox { leaf: 0, lo: [0, 2, 4], hi: [5, 3, 6], d: 0.0 };
        let mut out = Vec::new();
        split_samples(&b, &mut out);
        assert_eq!(out.len(), 4, "x and z are split, y (one cell) is not");
        for x in 0..=5 {
            for y in 2..=3 {
                for z in 4..=6 {
                    assert!(out.iter().any(|c| (0..3).all(|a| c.lo[a] <= [x, y, z][a] && [x, y, z][a] <= c.hi[a])));
                }
            }
        }
        out.clear();
        split_samples(&SubBox { leaf: 0, lo: [0; 3], hi: [1; 3], d: 0.0 }, &mut out);
        assert!(out.is_empty(), "a one-cell box is not split");
    }

    #[test]
    fn the_certificate_needs_the_value_beyond_the_bound() {
        assert!(proves_one_side(1.01, 1.0, 1.0, 0.0));
        assert!(!proves_one_side(1.0, 1.0, 1.0, 0.0));
        assert!(!proves_one_side(-0.5, 1.0, 1.0, 0.0));
        assert!(proves_one_side(-2.0, 1.0, 1.0, 0.0));
    }
}
