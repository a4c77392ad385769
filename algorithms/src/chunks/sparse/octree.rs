//! Blocks ruled out before any is sampled: the Lipschitz octree ([`lipschitz_leaves`], after
//! libigl's PRs #2488 and #2541 and warp's `sparse_marching_cubes`: an octant of blocks whose
//! centre value exceeds the bound times its half diagonal is dropped whole) and the sign-change
//! heuristic ([`sign_change_blocks`], as occupancy networks' MISE). The certificate's test
//! itself is [`proves_one_side`].

use super::{Evaluator, SparseError, SparseGrid};
use crate::chunks::BlockPlan;

/// A box of blocks: block ids `lo..hi` per axis.
#[derive(Clone, Copy, Debug)]
struct Octant {
    lo: [usize; 3],
    hi: [usize; 3],
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
pub(super) fn proves_one_side(d: f64, l: f64, r: f64, iso: f32) -> bool {
    let rounding = 1e-5 * (f64::from(iso).abs() + d.abs()) + f64::from(f32::MIN_POSITIVE);
    d.abs() > l * r * (1.0 + 1e-9) + rounding
}

/// An octree leaf: a block no centre's value ruled out, and the value at its box's centre (as
/// a sample keeps it, rounded to `f32`).
#[derive(Clone, Copy)]
pub(super) struct Leaf {
    pub(super) id: [u32; 3],
    pub(super) value: f32,
}

/// The leaves of an octree over the blocks that no centre's value rules out, in the plan's
/// order, one level evaluated per batch run.
pub(super) fn lipschitz_leaves(
    plan: &BlockPlan,
    grid: &SparseGrid,
    iso: f32,
    l: f64,
    ev: &mut Evaluator,
) -> Result<Vec<Leaf>, SparseError> {
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
pub(super) fn box_centre(grid: &SparseGrid, lo: [usize; 3], hi: [usize; 3]) -> [f64; 3] {
    [0, 1, 2].map(|a| grid.origin[a] + (lo[a] + hi[a]) as f64 * 0.5 * grid.spacing)
}

/// Half the diagonal of the samples `lo..=hi`, in world units.
pub(super) fn half_diagonal(grid: &SparseGrid, lo: [usize; 3], hi: [usize; 3]) -> f64 {
    let half = [0, 1, 2].map(|a| (hi[a] - lo[a]) as f64 * 0.5 * grid.spacing);
    (half[0] * half[0] + half[1] * half[1] + half[2] * half[2]).sqrt()
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
pub(super) fn sign_change_blocks(
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

    #[test]
    fn the_certificate_needs_the_value_beyond_the_bound() {
        assert!(proves_one_side(1.01, 1.0, 1.0, 0.0));
        assert!(!proves_one_side(1.0, 1.0, 1.0, 0.0));
        assert!(!proves_one_side(-0.5, 1.0, 1.0, 0.0));
        assert!(proves_one_side(-2.0, 1.0, 1.0, 0.0));
    }
}
