//! Frisken's constrained smoothing of the multi-label net (the module doc of
//! [`super`]): each vertex moves toward the mean of its net neighbours whose labels include all
//! of its own, and never out of its cell (kept [`MARGIN`] inside).

use super::Net;
use glam::Vec3;
use rayon::prelude::*;

/// Frisken's constrained smoothing (module doc): Jacobi passes over the net's quad sides.
pub(super) fn smooth(net: &mut Net, iterations: usize, relaxation: f32) {
    let (start, next) = followed_neighbours(net);
    // Only vertices with a neighbour to follow move; the others keep their place in both buffers.
    let movable: Vec<u32> = (0..net.positions.len() as u32).filter(|&v| start[v as usize + 1] > start[v as usize]).collect();
    let lows: Vec<Vec3> = movable
        .iter()
        .map(|&v| {
            let c = net.cells[v as usize];
            Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32) + MARGIN
        })
        .collect();
    let mut moved = net.positions.clone();
    let mut updates = vec![Vec3::ZERO; movable.len()];
    for _ in 0..iterations {
        let positions = &net.positions;
        updates.par_chunks_mut(4096).zip(movable.par_chunks(4096)).zip(lows.par_chunks(4096)).for_each(|((out, vs), lows)| {
            for ((m, &v), &lo) in out.iter_mut().zip(vs).zip(lows) {
                let around = &next[start[v as usize] as usize..start[v as usize + 1] as usize];
                let mut sum = Vec3::ZERO;
                for &w in around {
                    sum += positions[w as usize];
                }
                let x = positions[v as usize];
                let mean = sum / around.len() as f32;
                *m = (x + relaxation * (mean - x)).clamp(lo, lo + (1.0 - 2.0 * MARGIN));
            }
        });
        for (&v, &u) in movable.iter().zip(&updates) {
            moved[v as usize] = u;
        }
        std::mem::swap(&mut net.positions, &mut moved);
        // `moved` now holds the previous positions: the fixed vertices are the same in both.
    }
}

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
