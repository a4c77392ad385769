//! The octree's leaves tested below the blocks ([`refine_leaves`]): a leaf's box is split in
//! halves and quarters, each part tested as the octree tests blocks with its smaller half
//! diagonal, and a block whose parts all prove the same side is dropped, as a dense run skips
//! it. A Lipschitz bound far above the field's usual slope (the asteroid's 9) otherwise keeps a
//! shell of blocks several blocks thick. Leaves are refined a group at a time between sampling
//! groups ([`KeptBlocks::refill`]), and the grid samples refinement evaluates are handed to the
//! sampling ([`SharedSamples::know`]) so that none is evaluated twice.

use super::octree::{box_centre, half_diagonal, proves_one_side, Leaf};
use super::{Evaluator, SparseError, SparseGrid};
use crate::chunks::shared_samples::SharedSamples;
use crate::chunks::BlockPlan;
use rustc_hash::FxHashMap;
use std::collections::VecDeque;

/// The blocks a pruning leaves to sample, in the plan's order.
pub(super) enum Candidates {
    /// Blocks kept as they are (every block, or the sign-change heuristic's).
    Listed { ids: Vec<[usize; 3]>, next: usize },
    /// The Lipschitz octree's leaves, refined a group at a time ([`refine_leaves`]).
    Leaves { leaves: Vec<Leaf>, next: usize, l: f64 },
}

impl Candidates {
    pub(super) fn listed(ids: Vec<[usize; 3]>) -> Candidates {
        Candidates::Listed { ids, next: 0 }
    }
}

/// The blocks to sample, in the plan's order: leaves are refined as the blocks before them are
/// sampled, so memory holds a few groups of leaves' refinement, not the whole octree's.
pub(super) struct KeptBlocks {
    candidates: Candidates,
    pub(super) queue: VecDeque<[usize; 3]>,
    scratch: RefineScratch,
}

impl KeptBlocks {
    /// Nothing queued yet: the blocks come from `candidates` as [`KeptBlocks::refill`] asks.
    pub(super) fn new(candidates: Candidates) -> KeptBlocks {
        KeptBlocks { candidates, queue: VecDeque::new(), scratch: RefineScratch::default() }
    }

    /// Queues blocks until `enough` are queued or no candidate is left, refining leaves a group
    /// at a time. Called between groups only: no sample is then asked for and not evaluated.
    pub(super) fn refill(
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

#[cfg(test)]
mod tests {
    use super::super::{BatchEval, EvalError, SparseStats};
    use super::*;

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
}
