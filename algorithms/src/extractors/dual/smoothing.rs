//! Constrained smoothing of the dual net (surface nets' `smoothing` option): the net's adjacency
//! from the quads' sides, then each vertex moved toward its neighbours' mean but never out of
//! its cell (Gibson 1998's constraint): elastic relaxation with decaying strength, the blog
//! post's explicit spring-damper, or backward Euler on the graph Laplacian solved by
//! Jacobi-preconditioned conjugate gradients.

use super::{DualEngine, DualOptions, Scratch, Smoothing};
use crate::sweep::slabs::MIN_VERTICES_PER_TASK;
use glam::Vec3;
use rayon::prelude::*;

/// Builds the net's adjacency (CSR) from the quad sides: a counting pass over both directions
/// of every side (each side comes from two quads), then each vertex's short list sorted and
/// deduplicated in place. Linear in the sides, and no buffer besides the reused ones, so
/// steady-state re-meshing does not allocate.
pub(super) fn build_adjacency(n: usize, links: &[(u32, u32)], start: &mut Vec<u32>, adjacency: &mut Vec<u32>) {
    start.clear();
    start.resize(n + 1, 0);
    for &(a, b) in links.iter() {
        start[a as usize + 1] += 1;
        start[b as usize + 1] += 1;
    }
    for i in 0..n {
        start[i + 1] += start[i];
    }
    adjacency.clear();
    adjacency.resize(start[n] as usize, 0);
    // Fill with start[i] as vertex i's cursor (it ends at start[i + 1]), then shift back.
    for &(a, b) in links.iter() {
        adjacency[start[a as usize] as usize] = b;
        start[a as usize] += 1;
        adjacency[start[b as usize] as usize] = a;
        start[b as usize] += 1;
    }
    for i in (1..=n).rev() {
        start[i] = start[i - 1];
    }
    start[0] = 0;
    // Sort and deduplicate each vertex's list, compacting towards the front.
    let mut write = 0usize;
    for i in 0..n {
        let (lo, hi) = (start[i] as usize, start[i + 1] as usize);
        adjacency[lo..hi].sort_unstable();
        start[i] = write as u32;
        let mut last = u32::MAX;
        for k in lo..hi {
            let j = adjacency[k];
            if j != last {
                adjacency[write] = j;
                write += 1;
                last = j;
            }
        }
    }
    start[n] = write as u32;
    adjacency.truncate(write);
}

fn neighbour_mean(i: usize, x: &[Vec3], start: &[u32], adjacency: &[u32]) -> Option<Vec3> {
    let nbrs = &adjacency[start[i] as usize..start[i + 1] as usize];
    (!nbrs.is_empty()).then(|| nbrs.iter().map(|&j| x[j as usize]).sum::<Vec3>() / nbrs.len() as f32)
}

/// The buffers [`smooth_within`] works in, kept between calls.
#[derive(Default)]
pub(super) struct SmoothBuffers {
    pub(super) work: Vec<Vec3>,
    pub(super) velocity: Vec<Vec3>,
    pub(super) velocity_next: Vec<Vec3>,
}

impl SmoothBuffers {
    pub(super) fn bytes(&self) -> usize {
        12 * (self.work.capacity() + self.velocity.capacity() + self.velocity_next.capacity())
    }
}

impl DualEngine {
    pub(super) fn smooth(&self, s: &mut Scratch, positions: &mut [Vec3], h: f32) {
        let cell_min = &s.cell_min;
        let bound = |i: usize| (cell_min[i], cell_min[i] + Vec3::splat(h));
        smooth_within(&self.options, positions, (&s.adjacency_start, &s.adjacency), &mut s.buffers, bound);
    }
}

/// Moves each vertex toward its neighbours' mean (adjacency in CSR form: `start`, `adjacency`)
/// by `o`'s method, never out of its box `bound(i)` (lower and upper corner): the constrained
/// smoothing of the dual net, for cells of one size (the engine) or several (levels of detail).
pub(super) fn smooth_within(
    o: &DualOptions,
    positions: &mut [Vec3],
    (start, adjacency): (&[u32], &[u32]),
    b: &mut SmoothBuffers,
    bound: impl Fn(usize) -> (Vec3, Vec3) + Sync,
) {
    let n = positions.len();
    let clamp = |p: Vec3, i: usize| {
        let (lo, hi) = bound(i);
        p.clamp(lo, hi)
    };
    match o.smoothing {
        Smoothing::None => {}
        Smoothing::Elastic => {
            let mut strength = o.strength;
            for _ in 0..o.iterations {
                b.work.clear();
                b.work.par_extend((0..n).into_par_iter().with_min_len(MIN_VERTICES_PER_TASK).map(|i| {
                    let p = positions[i];
                    let target = neighbour_mean(i, positions, start, adjacency).unwrap_or(p);
                    clamp(p + (target - p) * strength, i)
                }));
                positions.copy_from_slice(&b.work);
                strength *= o.decay;
            }
        }
        Smoothing::Spring => {
            b.velocity.clear();
            b.velocity.resize(n, Vec3::ZERO);
            for _ in 0..o.iterations {
                b.work.resize(n, Vec3::ZERO);
                b.velocity_next.resize(n, Vec3::ZERO);
                let velocity = &b.velocity;
                b.work
                    .par_iter_mut()
                    .zip(b.velocity_next.par_iter_mut())
                    .enumerate()
                    .with_min_len(MIN_VERTICES_PER_TASK)
                    .for_each(|(i, (next_p, next_v))| {
                        let p = positions[i];
                        let target = neighbour_mean(i, positions, start, adjacency).unwrap_or(p);
                        let v = velocity[i] * (1.0 - o.damping) + (target - p) * o.stiffness;
                        let moved = p + v;
                        let clamped = clamp(moved, i);
                        // A wall stops motion into it (no bounce).
                        *next_v = Vec3::select(moved.cmpne(clamped), Vec3::ZERO, v);
                        *next_p = clamped;
                    });
                positions.copy_from_slice(&b.work);
                std::mem::swap(&mut b.velocity, &mut b.velocity_next);
            }
        }
        Smoothing::Implicit => {
            for _ in 0..o.iterations {
                let solved = implicit_step(positions, start, adjacency, o.time_step);
                for (i, p) in solved.into_iter().enumerate() {
                    positions[i] = clamp(p, i);
                }
            }
        }
    }
}

/// One backward-Euler step of graph diffusion: solves `(I + t L) x' = x` with `L = D - A`.
fn implicit_step(x: &[Vec3], start: &[u32], adjacency: &[u32], t: f32) -> Vec<Vec3> {
    let n = x.len();
    let degree: Vec<f32> = (0..n).map(|i| (start[i + 1] - start[i]) as f32).collect();
    let apply = |v: &[Vec3], out: &mut Vec<Vec3>| {
        out.clear();
        out.par_extend((0..n).into_par_iter().map(|i| {
            let nbrs = &adjacency[start[i] as usize..start[i + 1] as usize];
            let sum: Vec3 = nbrs.iter().map(|&j| v[j as usize]).sum();
            v[i] * (1.0 + t * degree[i]) - sum * t
        }));
    };
    // Jacobi-preconditioned conjugate gradients, the three coordinates at once.
    let precond: Vec<f32> = degree.iter().map(|d| 1.0 / (1.0 + t * d)).collect();
    let mut sol: Vec<Vec3> = x.to_vec();
    let mut ax = Vec::with_capacity(n);
    apply(&sol, &mut ax);
    let mut r: Vec<Vec3> = x.iter().zip(&ax).map(|(b, a)| *b - *a).collect();
    let mut z: Vec<Vec3> = r.iter().zip(&precond).map(|(r, m)| *r * *m).collect();
    let mut p = z.clone();
    let dot = |a: &[Vec3], b: &[Vec3]| a.iter().zip(b).fold(Vec3::ZERO, |acc, (u, v)| acc + *u * *v);
    let mut rz = dot(&r, &z);
    let norm_b = dot(x, x).max(Vec3::splat(1e-30));
    let mut ap = Vec::with_capacity(n);
    for _ in 0..500 {
        if (dot(&r, &r) / norm_b).max_element() < 1e-12 {
            break;
        }
        apply(&p, &mut ap);
        let pap = dot(&p, &ap);
        let alpha = Vec3::select(pap.cmpgt(Vec3::ZERO), rz / pap, Vec3::ZERO);
        for i in 0..n {
            sol[i] += p[i] * alpha;
            r[i] -= ap[i] * alpha;
            z[i] = r[i] * precond[i];
        }
        let rz_new = dot(&r, &z);
        let beta = Vec3::select(rz.cmpgt(Vec3::ZERO), rz_new / rz, Vec3::ZERO);
        for i in 0..n {
            p[i] = z[i] + p[i] * beta;
        }
        rz = rz_new;
    }
    sol
}
