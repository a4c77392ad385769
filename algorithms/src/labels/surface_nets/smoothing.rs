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
    // A cap's vertex (`split`) follows no neighbour: it keeps its place beside the rest of its
    // piece and moves with it, so the walls between them keep their shape.
    let around = followed_neighbours(net);
    let steps = std::array::from_fn(|n| relaxation / n as f32);
    let rule = Rule { around, cells: &net.cells, relaxation, steps, width: Vec3A::splat(1.0 - 2.0 * MARGIN) };
    // Both buffers end with the rows' padding vertex, at the origin.
    let mut even: Vec<Vec3A> = net.positions.iter().map(|&p| Vec3A::from(p)).chain([Vec3A::ZERO]).collect();
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
            let lo = box_low(net.cells[cap]);
            Vec3::from(p.clamp(lo, lo + rule.width))
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
    around: Around,
    /// Each vertex's cell.
    cells: &'a [[u32; 3]],
    relaxation: f32,
    /// `relaxation / n` for `n` neighbours up to a row's.
    steps: [f32; ROW + 1],
    width: Vec3A,
}

/// Neighbours a row of a vertex holds; most vertices of a net have three to six.
const ROW: usize = 6;

/// Each vertex's followed neighbours laid out for the passes: the first [`ROW`] in a row padded
/// with a vertex at the origin (index: the number of vertices), so a vertex's sum is one read of
/// the row without a loop; the rest (rare) in `more[more_start[v]..more_start[v + 1]]`.
struct Around {
    rows: Vec<[u32; ROW]>,
    count: Vec<u32>,
    more_start: Vec<u32>,
    more: Vec<u32>,
}

impl Around {
    /// `n` vertices without neighbours yet, rows padded with `pad`.
    fn empty(n: usize, pad: u32) -> Self {
        Self { rows: vec![[pad; ROW]; n], count: vec![0; n], more_start: vec![0; n + 1], more: Vec::new() }
    }

    /// Sets vertex `v`'s neighbours to `all`; vertices are set in increasing order.
    #[inline]
    fn set(&mut self, v: usize, all: &[u32]) {
        let k = all.len().min(ROW);
        self.rows[v][..k].copy_from_slice(&all[..k]);
        self.count[v] = all.len() as u32;
        self.more.extend_from_slice(&all[k..]);
        self.more_start[v + 1] = self.more.len() as u32;
    }

    /// Vertex `v`'s neighbours, in order.
    #[cfg(test)]
    fn of(&self, v: usize) -> Vec<u32> {
        let k = (self.count[v] as usize).min(ROW);
        let more = &self.more[self.more_start[v] as usize..self.more_start[v + 1] as usize];
        self.rows[v][..k].iter().chain(more).copied().collect()
    }
}

impl Rule<'_> {
    /// One pass over vertices `first..first + to.len()`, reading `from` (every vertex's positions
    /// after the previous pass, and the padding vertex); a vertex with no neighbour to follow is
    /// left as it is in `to`. The sum runs over the neighbours in order, then the padding (adding
    /// zeros), as a loop over the neighbours alone would.
    #[inline]
    fn pass(&self, from: &[Vec3A], to: &mut [Vec3A], first: usize) {
        let a = &self.around;
        let span = first..first + to.len();
        let (rows, counts, cells) = (&a.rows[span.clone()], &a.count[span.clone()], &self.cells[span]);
        for (i, (((m, row), &n), c)) in to.iter_mut().zip(rows).zip(counts).zip(cells).enumerate() {
            if n == 0 {
                continue;
            }
            let v = first + i;
            let mut sum = Vec3A::ZERO;
            for &w in row {
                sum += from[w as usize];
            }
            if n as usize > ROW {
                for &w in &a.more[a.more_start[v] as usize..a.more_start[v + 1] as usize] {
                    sum += from[w as usize];
                }
            }
            let step = if n as usize <= ROW { self.steps[n as usize] } else { self.relaxation / n as f32 };
            let lo = box_low(*c);
            *m = (from[v] * (1.0 - self.relaxation) + sum * step).clamp(lo, lo + self.width);
        }
    }
}

/// The low corner of the box of a vertex in cell `c`: [`MARGIN`] inside the cell.
#[inline]
fn box_low(c: [u32; 3]) -> Vec3A {
    Vec3A::new(c[0] as f32, c[1] as f32, c[2] as f32) + MARGIN
}

/// Vertices per parallel task of a pass.
const CHUNK: usize = 4096;

/// The passes one after the other, each over all vertices in parallel chunks; pass `k` reads
/// `even` and writes `odd` when `k` is odd, the other way round when it is even (the padding
/// vertex, last in both, is never written).
fn passes(rule: &Rule<'_>, even: &mut [Vec3A], odd: &mut [Vec3A], iterations: usize) {
    let n = even.len() - 1;
    for k in 1..=iterations {
        let (from, to) = if k % 2 == 1 { (&*even, &mut odd[..n]) } else { (&*odd, &mut even[..n]) };
        to.par_chunks_mut(CHUNK).enumerate().for_each(|(c, out)| rule.pass(from, out, c * CHUNK));
    }
}

/// Each vertex's net neighbours (the vertices it shares a quad side with) whose labels include
/// all of its own, each once, in the order the quads and then the walls name them; none for a
/// cap's vertex. The sweep makes quads in the same order over a block as over the whole map, so
/// a vertex's neighbours, and the sum of their positions, are the same wherever it is meshed
/// (`tests/tests/labels.rs` holds blocks to the whole map's positions bit for bit). Keeping
/// that order rather than sorting saves a sort per vertex. A vertex of two labels follows
/// every neighbour: each quad at it separates its two labels, and each corner of the quad has
/// them both.
///
/// Such a vertex also needs only the side after it in each quad: its quads are all in both its
/// labels' meshes, wound alike, and a label's mesh is closed, so each side at the vertex runs
/// out of it in as many quads as into it. That holds where all its quads are in the net: not in
/// the cells on the border of the net's box (a block's, or the map's with `border=open`), whose
/// vertices take both sides.
fn followed_neighbours(net: &Net) -> Around {
    let n = net.positions.len();
    let b = &net.cell_box;
    let inside = |c: [u32; 3]| (0..3).all(|a| c[a] > b[a].start && c[a] + 1 < b[a].end);
    let one_side: Vec<bool> = (0..n).map(|v| net.label_start[v + 1] - net.label_start[v] == 2 && inside(net.cells[v])).collect();
    // Every quad gives each of its corners the sides' other ends (a side shared by two or more
    // quads gives them more than once).
    let mut count = vec![0u32; n + 1];
    let mut tally = |v: u32| count[v as usize + 1] += 2 - u32::from(one_side[v as usize]);
    for q in &net.quads {
        q.iter().for_each(|&v| tally(v));
    }
    for t in &net.tris {
        t.iter().for_each(|&v| tally(v));
    }
    for i in 0..n {
        count[i + 1] += count[i];
    }
    let mut fill = count.clone();
    let mut all = vec![0u32; count[n] as usize];
    let mut give = |v: u32, before: u32, after: u32| {
        let v = v as usize;
        let at = fill[v] as usize;
        if one_side[v] {
            all[at] = after;
            fill[v] += 1;
        } else {
            all[at] = before;
            all[at + 1] = after;
            fill[v] += 2;
        }
    };
    for q in &net.quads {
        for k in 0..4 {
            give(q[k], q[(k + 3) % 4], q[(k + 1) % 4]);
        }
    }
    for t in &net.tris {
        for k in 0..3 {
            give(t[k], t[(k + 2) % 3], t[(k + 1) % 3]);
        }
    }
    let labels_of = |v: usize| &net.labels[net.label_start[v] as usize..net.label_start[v + 1] as usize];
    let mut out = Around::empty(n, n as u32);
    let mut caps = net.caps.iter().map(|c| c[0]).peekable();
    let mut kept = Vec::new();
    for v in 0..n {
        kept.clear();
        if caps.next_if_eq(&(v as u32)).is_none() {
            let around = &all[count[v] as usize..count[v + 1] as usize];
            let mine = labels_of(v);
            for (i, &w) in around.iter().enumerate() {
                if !around[..i].contains(&w) && (mine.len() == 2 || mine.iter().all(|l| labels_of(w as usize).contains(l))) {
                    kept.push(w);
                }
            }
        }
        out.set(v, &kept);
    }
    out
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
    fn followed_neighbours_are_those_the_rule_names_with_either_border() {
        let mut random = crate::random::Random::new(11);
        let dims = [6, 5, 4];
        let (mut two, mut more) = (0, 0);
        // Half the rounds with `border=open`: the net is open at its box, where a vertex of two
        // labels needs both sides of its quads.
        for round in 0..80 {
            let labels = 2 + round % 4;
            let map: Vec<u8> = (0..dims.iter().product()).map(|_| (random.next_u64() % labels) as u8).collect();
            let open = round % 8 >= 4;
            let cells = dims.map(|n| if open { 1..n } else { 0..n + 1 });
            let block = LabelBlock {
                samples: &map,
                window_lo: [0; 3],
                window_dims: dims,
                map_dims: dims,
                cells: cells.clone(),
                apron: 0,
            };
            let (net, _) = sweep::net(&block, &cells, sweep::Needs { labels: true, cells: true });
            let around = followed_neighbours(&net);
            for (v, expected) in by_the_rule(&net).iter().enumerate() {
                let expected = if net.caps.iter().any(|c| c[0] == v as u32) { Vec::new() } else { expected.clone() };
                // In the quads' order, each once: sorted, the rule's set.
                let mut got = around.of(v);
                got.sort_unstable();
                let named = got.len();
                got.dedup();
                assert_eq!(got.len(), named, "vertex {v} of round {round}: a neighbour named twice");
                assert_eq!(got, expected, "vertex {v} of round {round}");
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
