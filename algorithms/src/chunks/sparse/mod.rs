//! A field meshed from evaluations near its surface only: the grid is split into the blocks of a
//! [`BlockPlan`], whole octants of blocks are ruled out from one evaluation at their centre, and
//! only the surviving blocks are sampled (each with its extractor's apron; a sample two blocks
//! read is evaluated once, [`super::shared_samples`]), meshed by
//! [`mesh_block_view`] and welded as they come, as [`weld_fragments`](super::weld_fragments) welds. Memory holds two
//! groups of samples (the group meshed and the next, sampled beside it), the samples of about
//! three layers of kept blocks, the octree's leaves (16
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
//! one side ([`refine::refine_leaves`]). A Lipschitz bound far above the field's usual slope (the
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
//! **The rooms.** This module holds the API, the evaluator every evaluation goes through and the
//! sampling loop; [`octree`] rules blocks out (the Lipschitz octree and the sign-change
//! heuristic) and [`refine`] tests the octree's leaves below the blocks, between sampling
//! groups. The order in which the refinement and the sampling take turns on the one evaluator
//! and one [`SharedSamples`] is the contract the two share: it is stated at
//! [`refine::KeptBlocks::refill`].

mod octree;
mod refine;

use super::shared_samples::SharedSamples;
use super::{mesh_block_view_of, BlockBounds, BlockPlan, ChunkStats, Fragment, Welder};
use crate::extract::{ExtractError, Extraction, Extractor};
use crate::field::Field;
use crate::lattice::Grid;
use crate::samples::GridView;
use glam::Vec3;
use octree::{lipschitz_leaves, sign_change_blocks};
use rayon::prelude::*;
use refine::{Candidates, KeptBlocks};
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

/// Meshes the field `eval` gives on `grid` with `extractor`, sampling only the blocks pruning
/// keeps, into `out` (positions in world units). With [`Pruning::Lipschitz`] holding for the
/// field (and [`Pruning::Dense`]), the mesh is exactly [`extract_chunked`](super::extract_chunked)'s of the dense grid in
/// blocks of `options.chunk`. On an error `out` holds no mesh.
pub fn extract_sparse(
    extractor: &dyn Extractor,
    grid: &SparseGrid,
    iso: f32,
    options: &SparseOptions,
    eval: &mut dyn BatchEval,
    out: &mut Extraction,
) -> Result<SparseStats, SparseError> {
    let result = extract_sparse_into(extractor, grid, iso, options, eval, out);
    if result.is_err() {
        // The groups meshed before the error would be a part of the mesh, read as the whole.
        drop(std::mem::take(&mut out.surface));
    }
    result
}

fn extract_sparse_into(
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
    let mut weld =
        LayerWeld { welder: Welder::new(out), stats: ChunkStats::default(), retire: plan.chunk > 2 * plan.apron, layer: None };
    let limit = out.memory_limit;
    let mut shared = SharedSamples::new(grid.dims, plan.chunk, plan.counts);
    let mut kept = KeptBlocks::new(candidates);
    // Enough blocks queued for one batch of new samples, refined between groups (when no sample
    // is asked for and not evaluated).
    let enough = (2 * options.batch / plan.chunk.pow(3)).max(1);
    kept.refill(enough, &plan, grid, iso, &mut ev, &mut shared)?;
    let mut sampler = Sampler {
        plan: &plan,
        grid,
        iso,
        batch: options.batch,
        enough,
        extractor,
        limit,
        ev,
        shared,
        kept,
        points: Vec::new(),
        values: Vec::new(),
    };
    let (mut current, mut next) = (SampledGroup::default(), SampledGroup::default());
    let mut more = sampler.next_group(&mut current)?;
    while more {
        // The group sampled is meshed on the pool while this thread samples the next one: a
        // callable that holds one core (a Python function under its lock) runs beside the
        // meshing instead of before it.
        let mut meshed = Vec::new();
        let sampled = rayon::in_place_scope(|s| {
            let (current, meshed, plan) = (&current, &mut meshed, &plan);
            s.spawn(move |_| *meshed = current.mesh(extractor, plan, iso, field));
            sampler.next_group(&mut next)
        });
        weld.add(meshed, out)?;
        more = sampled?;
        std::mem::swap(&mut current, &mut next);
    }
    let mut ev = sampler.ev;
    weld.welder.finish(out);
    to_world(grid, out);
    // As extract_chunked: a field with an analytic gradient gives the normals.
    super::field_normals(field.map(|(f, _)| f), out);
    out.finish_counts(0);
    let eval_time = ev.stats.eval_time;
    ev.stats.other_time = start.elapsed().saturating_sub(eval_time);
    Ok(ev.stats)
}

/// A group of kept blocks with their samples, gathered as the extractors read them: each
/// block's run, from its offset.
#[derive(Default)]
struct SampledGroup {
    blocks: Vec<BlockBounds>,
    samples: Vec<f32>,
    offsets: Vec<usize>,
}

impl SampledGroup {
    /// Each block meshed where its run lies, in the group's order.
    fn mesh(
        &self,
        extractor: &dyn Extractor,
        plan: &BlockPlan,
        iso: f32,
        field: Option<(&Arc<dyn Field>, &Grid)>,
    ) -> Vec<Result<Fragment, ExtractError>> {
        self.blocks
            .par_iter()
            .zip(&self.offsets)
            .map(|(b, &off)| {
                let view = GridView::contiguous(&self.samples[off..off + block_points(b)], b.dims)
                    .map_err(|e| ExtractError::BadInput { algorithm: extractor.name(), reason: e.to_string() })?;
                mesh_block_view_of(extractor, plan, b.id, view.into(), iso, field)
            })
            .collect()
    }
}

/// What takes the kept blocks a group at a time: schedules their samples, evaluates the ones no
/// earlier block asked for, gathers each block's run and refines the next leaves.
struct Sampler<'a, 'e> {
    plan: &'a BlockPlan,
    grid: &'a SparseGrid,
    iso: f32,
    batch: usize,
    enough: usize,
    extractor: &'a dyn Extractor,
    limit: Option<u64>,
    ev: Evaluator<'e>,
    shared: SharedSamples,
    kept: KeptBlocks,
    points: Vec<[f64; 3]>,
    values: Vec<f64>,
}

impl Sampler<'_, '_> {
    /// Samples the next group into `group`: blocks whose samples not yet evaluated make about
    /// one batch (at least one block; a sample shared with an earlier block is evaluated once).
    /// `false` when no block is left.
    fn next_group(&mut self, group: &mut SampledGroup) -> Result<bool, SparseError> {
        group.blocks.clear();
        let shared = &mut self.shared;
        while let Some(b) = self.kept.queue.front().and_then(|&id| self.plan.block(id)) {
            let mark = shared.mark();
            shared.schedule(&b);
            if !group.blocks.is_empty() && shared.asked() > self.batch {
                shared.undo(mark);
                break;
            }
            group.blocks.push(b);
            self.kept.queue.pop_front();
        }
        if group.blocks.is_empty() {
            return Ok(false);
        }
        self.ev.stats.sampled_blocks += group.blocks.len();
        check_output_memory(self.extractor, self.ev.stats.sampled_blocks, self.plan.chunk, self.limit)?;
        shared.points(self.grid, &mut self.points);
        self.ev.values(&self.points, &mut self.values)?;
        shared.fill(&self.values);
        shared.gather(&mut group.samples, &mut group.offsets);
        self.kept.refill(self.enough, self.plan, self.grid, self.iso, &mut self.ev, shared)?;
        if let Some(next) = self.kept.queue.front() {
            shared.retire_below((next[2] * self.plan.chunk).saturating_sub(self.plan.apron));
        }
        Ok(true)
    }
}

/// The weld of the fragments as they come, in the plan's order, retiring the keys of a block
/// layer no later fragment can share (when `retire`: blocks thicker than twice their apron).
struct LayerWeld {
    welder: Welder,
    stats: ChunkStats,
    retire: bool,
    /// The block layer of the last fragment added.
    layer: Option<usize>,
}

impl LayerWeld {
    fn add(&mut self, fragments: Vec<Result<Fragment, ExtractError>>, out: &mut Extraction) -> Result<(), ExtractError> {
        for f in fragments {
            let f = f?;
            let layer = self.layer.get_or_insert(f.id[2]);
            while self.retire && *layer < f.id[2] {
                self.welder.retire();
                *layer += 1;
            }
            self.welder.add(f.piece(), out, &mut self.stats);
        }
        Ok(())
    }
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
}
