//! Frisken's constrained smoothing of the multi-label net (the module doc of
//! [`super`]): each vertex moves toward the mean of its net neighbours whose labels include all
//! of its own, and never out of its cell (kept [`MARGIN`] inside).

use super::Net;
use glam::{Vec3, Vec3A};
use rayon::prelude::*;

/// Frisken's constrained smoothing (module doc): `iterations` Jacobi passes over the vertices'
/// followed neighbours, in SIMD-width positions (a vertex with no neighbour to follow keeps its
/// place in both buffers).
pub(super) fn smooth(net: &mut Net, iterations: usize, relaxation: f32) {
    let (mut start, mut next) = followed_neighbours(net);
    // A cap's vertex (`split`) does not follow neighbours: it keeps its place beside the rest of
    // its piece and moves with it, so the walls between them keep their shape.
    if !net.caps.is_empty() {
        let mut kept = Vec::with_capacity(next.len());
        let mut from = 0;
        let mut caps = net.caps.iter().map(|c| c[0]).peekable();
        for v in 0..net.positions.len() {
            let around = &next[from..start[v + 1] as usize];
            from = start[v + 1] as usize;
            if caps.next_if_eq(&(v as u32)).is_none() {
                kept.extend_from_slice(around);
            }
            start[v + 1] = kept.len() as u32;
        }
        next = kept;
    }
    let rule = Rule {
        start: &start,
        next: &next,
        lows: net.cells.iter().map(|c| Vec3A::new(c[0] as f32, c[1] as f32, c[2] as f32) + MARGIN).collect(),
        relaxation,
        width: Vec3A::splat(1.0 - 2.0 * MARGIN),
    };
    let mut even: Vec<Vec3A> = net.positions.iter().map(|&p| Vec3A::from(p)).collect();
    let mut odd = even.clone();
    passes(&rule, &mut even, &mut odd, iterations);
    let last = if iterations % 2 == 0 { &even } else { &odd };
    // Caps move by their rest's move, from the places both had before smoothing.
    let moved: Vec<Vec3> = net
        .caps
        .iter()
        .map(|&[cap, rest]| {
            let (cap, rest) = (cap as usize, rest as usize);
            let p = Vec3A::from(net.positions[cap]) + last[rest] - Vec3A::from(net.positions[rest]);
            Vec3::from(p.clamp(rule.lows[cap], rule.lows[cap] + rule.width))
        })
        .collect();
    for (p, q) in net.positions.iter_mut().zip(last) {
        *p = Vec3::from(*q);
    }
    for (&[cap, _], &p) in net.caps.iter().zip(&moved) {
        net.positions[cap as usize] = p;
    }
}

/// One vertex's move: toward the mean of its followed neighbours, kept in its cell's box.
struct Rule<'a> {
    start: &'a [u32],
    next: &'a [u32],
    /// The low corner of each vertex's box.
    lows: Vec<Vec3A>,
    relaxation: f32,
    width: Vec3A,
}

impl Rule<'_> {
    /// One pass over vertices `first..first + to.len()`, reading `from` (every vertex's positions
    /// after the previous pass); a vertex with no neighbour to follow is left as it is in `to`.
    #[inline]
    fn pass(&self, from: &[Vec3A], to: &mut [Vec3A], first: usize) {
        for (i, m) in to.iter_mut().enumerate() {
            let v = first + i;
            let around = &self.next[self.start[v] as usize..self.start[v + 1] as usize];
            if around.is_empty() {
                continue;
            }
            let mut sum = Vec3A::ZERO;
            for &w in around {
                sum += from[w as usize];
            }
            let step = self.relaxation / around.len() as f32;
            let lo = self.lows[v];
            *m = (from[v] * (1.0 - self.relaxation) + sum * step).clamp(lo, lo + self.width);
        }
    }
}

/// Vertices per parallel task of a pass.
const CHUNK: usize = 4096;

/// The passes one after the other, each over all vertices in parallel chunks; pass `k` reads
/// `even` and writes `odd` when `k` is odd, the other way round when it is even.
fn passes(rule: &Rule<'_>, even: &mut [Vec3A], odd: &mut [Vec3A], iterations: usize) {
    for k in 1..=iterations {
        let (from, to) = if k % 2 == 1 { (&*even, &mut *odd) } else { (&*odd, &mut *even) };
        to.par_chunks_mut(CHUNK).enumerate().for_each(|(c, out)| rule.pass(from, out, c * CHUNK));
    }
}

/// Each vertex's net neighbours (the vertices it shares a quad side with) whose labels include
/// all of its own, compressed: `next[start[v]..start[v + 1]]`. A vertex of two labels follows
/// every neighbour: each quad at it separates its two labels, and each corner of the quad has
/// them both.
fn followed_neighbours(net: &Net) -> (Vec<u32>, Vec<u32>) {
    let n = net.positions.len();
    // Every quad gives each of its corners its two sides' other ends; duplicates (a side shared
    // by two or more quads) are removed per vertex.
    let mut count = vec![0u32; n + 1];
    for &v in net.quads.iter().flatten().chain(net.tris.iter().flatten()) {
        count[v as usize + 1] += 2;
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
    for t in &net.tris {
        for k in 0..3 {
            let v = t[k] as usize;
            all[fill[v] as usize] = t[(k + 2) % 3];
            all[fill[v] as usize + 1] = t[(k + 1) % 3];
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
            if w != last && (mine.len() == 2 || mine.iter().all(|l| labels_of(w as usize).contains(l))) {
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

#[cfg(test)]
mod tests {
    use super::super::super::blocks::LabelBlock;
    use super::super::sweep;
    use super::*;
    use std::collections::BTreeSet;

    /// Each vertex's followed neighbours by the rule as stated, with no shortcut: every vertex it
    /// shares a quad side with whose labels include all of its own.
    fn by_the_rule(net: &Net) -> Vec<Vec<u32>> {
        let mut around = vec![BTreeSet::new(); net.positions.len()];
        for q in &net.quads {
            for k in 0..4 {
                around[q[k] as usize].extend([q[(k + 1) % 4], q[(k + 3) % 4]]);
            }
        }
        for t in &net.tris {
            for k in 0..3 {
                around[t[k] as usize].extend([t[(k + 1) % 3], t[(k + 2) % 3]]);
            }
        }
        let labels_of = |v: usize| &net.labels[net.label_start[v] as usize..net.label_start[v + 1] as usize];
        around
            .iter()
            .enumerate()
            .map(|(v, ws)| {
                ws.iter().copied().filter(|&w| labels_of(v).iter().all(|l| labels_of(w as usize).contains(l))).collect()
            })
            .collect()
    }

    #[test]
    fn followed_neighbours_are_those_the_rule_names() {
        let mut random = crate::random::Random::new(11);
        let dims = [6, 5, 4];
        let (mut two, mut more) = (0, 0);
        for round in 0..40 {
            let labels = 2 + round % 4;
            let map: Vec<u8> = (0..dims.iter().product()).map(|_| (random.next_u64() % labels) as u8).collect();
            let cells = dims.map(|n| 0..n + 1);
            let block = LabelBlock {
                samples: &map,
                window_lo: [0; 3],
                window_dims: dims,
                map_dims: dims,
                cells: cells.clone(),
                apron: 0,
            };
            let (net, _) = sweep::net(&block, &cells);
            let (start, next) = followed_neighbours(&net);
            for (v, expected) in by_the_rule(&net).iter().enumerate() {
                assert_eq!(next[start[v] as usize..start[v + 1] as usize], expected[..], "vertex {v} of round {round}");
                if net.label_start[v + 1] - net.label_start[v] == 2 {
                    two += 1;
                } else {
                    more += 1;
                }
            }
        }
        // Both kinds of vertex were met: the shortcut's and the rule's.
        assert!(two > 100 && more > 100, "{two} two-label vertices, {more} with more labels");
    }
}
