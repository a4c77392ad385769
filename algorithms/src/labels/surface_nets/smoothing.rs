//! Frisken's constrained smoothing of the multi-label net (the module doc of
//! [`super`]): each vertex moves toward the mean of its net neighbours whose labels include all
//! of its own, and never out of its cell (kept [`MARGIN`] inside).

use super::Net;
use glam::{Vec3, Vec3A};
use rayon::prelude::*;

/// Frisken's constrained smoothing (module doc): Jacobi passes over the net's quad sides, each a
/// dense sweep over the vertices in SIMD-width positions (a vertex with no neighbour to follow
/// keeps its place in both buffers).
pub(super) fn smooth(net: &mut Net, iterations: usize, relaxation: f32) {
    let (start, next) = followed_neighbours(net);
    // Per vertex: the step toward its neighbours' sum (`relaxation / count`, 0 for a fixed
    // vertex) and the low corner of the box it stays in.
    let steps: Vec<f32> = start.windows(2).map(|w| if w[1] > w[0] { relaxation / (w[1] - w[0]) as f32 } else { 0.0 }).collect();
    let lows: Vec<Vec3A> = net.cells.iter().map(|c| Vec3A::new(c[0] as f32, c[1] as f32, c[2] as f32) + MARGIN).collect();
    let mut positions: Vec<Vec3A> = net.positions.iter().map(|&p| Vec3A::from(p)).collect();
    let mut moved = positions.clone();
    let keep = 1.0 - relaxation;
    let width = Vec3A::splat(1.0 - 2.0 * MARGIN);
    for _ in 0..iterations {
        let from = &positions;
        moved.par_chunks_mut(CHUNK).enumerate().for_each(|(c, out)| {
            for (i, m) in out.iter_mut().enumerate() {
                let v = c * CHUNK + i;
                let step = steps[v];
                if step == 0.0 {
                    continue;
                }
                let mut sum = Vec3A::ZERO;
                for &w in &next[start[v] as usize..start[v + 1] as usize] {
                    sum += from[w as usize];
                }
                let lo = lows[v];
                *m = (from[v] * keep + sum * step).clamp(lo, lo + width);
            }
        });
        std::mem::swap(&mut positions, &mut moved);
    }
    for (p, q) in net.positions.iter_mut().zip(&positions) {
        *p = Vec3::from(*q);
    }
}

/// Vertices per parallel task of a smoothing pass.
const CHUNK: usize = 4096;

/// Each vertex's net neighbours (the vertices it shares a quad side with) whose labels include
/// all of its own, compressed: `next[start[v]..start[v + 1]]`.
fn followed_neighbours(net: &Net) -> (Vec<u32>, Vec<u32>) {
    let n = net.positions.len();
    // Every quad gives each of its corners its two sides' other ends; duplicates (a side shared
    // by two or more quads) are removed per vertex.
    let mut count = vec![0u32; n + 1];
    for q in &net.quads {
        for &v in q {
            count[v as usize + 1] += 2;
        }
    }
    for i in 0..n {
        count[i + 1] += count[i];
    }
    let mut fill = count.clone();
    let mut all = vec![0u32; count[n] as usize];
    for q in &net.quads {
        for k in 0..4 {
            let v = q[k] as usize;
            all[fill[v] as usize] = q[(k + 3) % 4];
            all[fill[v] as usize + 1] = q[(k + 1) % 4];
            fill[v] += 2;
        }
    }
    let labels_of = |v: usize| &net.labels[net.label_start[v] as usize..net.label_start[v + 1] as usize];
    let mut start = vec![0u32; n + 1];
    let mut next = Vec::with_capacity(all.len() / 2);
    for v in 0..n {
        let around = &mut all[count[v] as usize..count[v + 1] as usize];
        around.sort_unstable();
        let mine = labels_of(v);
        let mut last = u32::MAX;
        for &w in around.iter() {
            if w != last && mine.iter().all(|l| labels_of(w as usize).contains(l)) {
                next.push(w);
            }
            last = w;
        }
        start[v + 1] = next.len() as u32;
    }
    (start, next)
}

/// How far smoothing keeps a vertex from its cell's faces, in samples: a label of one sample has
/// a vertex in each of the eight cells around it, and without the margin they can all reach the
/// sample and turn the label inside out.
const MARGIN: f32 = 0.1;
