//! A uniform grid of triangles for local geometric queries while a mesh is being edited (the safe
//! edge collapse asks, before each collapse, which live triangles lie near the triangles that
//! would move).
//!
//! The grid covers a fixed box: an edit that only moves vertices to midpoints of existing ones
//! stays inside the input's bounding box, and anything outside is clamped onto the border cells,
//! so a query never misses it. Entries carry the triangle's bounding box (a query filters on it
//! without touching the mesh) and its generation when filed: filing a triangle again (after it
//! moved) makes its older entries stale. A query ignores stale and dead entries, and compacts a
//! cell it reads once the cell has doubled since its last compaction (and holds more than
//! `COMPACT_AT` entries), so cells do not grow with the edits and compaction costs amortised
//! constant time per entry. A stale entry costs a comparison, never a wrong answer.

use glam::Vec3;

/// Cells in the grid at most (the cell size grows to keep to it).
const MAX_CELLS: usize = 1 << 21;

/// A triangle covering more cells than this is kept in a list every query reads instead.
const MAX_CELLS_PER_TRIANGLE: usize = 512;

/// A grid cell nothing was filed in.
const NO_CELL: u32 = u32::MAX;

/// A cell read by a query is compacted (stale and dead entries dropped) when it holds more than
/// this many entries and twice as many as after its last compaction.
const COMPACT_AT: usize = 16;

/// The entries of one cell.
#[derive(Clone, Debug, Default)]
struct Cell {
    entries: Vec<Entry>,
    /// Entries left by the last compaction.
    kept: usize,
}

/// One filing of a triangle: its box then, its id and generation.
#[derive(Clone, Copy, Debug)]
struct Entry {
    lo: Vec3,
    hi: Vec3,
    triangle: u32,
    generation: u32,
}

/// Triangles by the grid cells their bounding boxes overlap.
#[derive(Debug)]
pub struct TriangleGrid {
    origin: Vec3,
    inverse_size: f32,
    dims: [usize; 3],
    /// For each grid cell, its index in `cells`, or `NO_CELL` while nothing was filed there.
    slots: Vec<u32>,
    /// The cells anything was filed in.
    cells: Vec<Cell>,
    large: Cell,
    generation: Vec<u32>,
    stamp: Vec<u32>,
    round: u32,
}

impl TriangleGrid {
    /// An empty grid over `lo..=hi` with cells of about `size` (larger if the box would need more
    /// than `MAX_CELLS`) for triangle ids below `triangles`.
    pub fn new(lo: Vec3, hi: Vec3, size: f32, triangles: usize) -> Self {
        let extent = (hi - lo).max(Vec3::ZERO);
        let mut size = if size.is_finite() && size > 0.0 { size } else { extent.max_element().max(1.0) };
        let dims = |size: f32| (extent / size).to_array().map(|x| (x.floor() as usize).saturating_add(1).max(1));
        while dims(size).iter().product::<usize>() > MAX_CELLS {
            size *= 1.5;
        }
        let d = dims(size);
        TriangleGrid {
            origin: lo,
            inverse_size: 1.0 / size,
            dims: d,
            slots: vec![NO_CELL; d[0] * d[1] * d[2]],
            cells: Vec::new(),
            large: Cell::default(),
            generation: vec![0; triangles],
            stamp: vec![0; triangles],
            round: 0,
        }
    }

    /// The inclusive cell range of a box, clamped to the grid.
    fn range(&self, lo: Vec3, hi: Vec3) -> ([usize; 3], [usize; 3]) {
        let cell = |p: Vec3| {
            let c = ((p - self.origin) * self.inverse_size).to_array();
            [0, 1, 2].map(|k| {
                let x = c[k];
                // NaN and below-zero go to the first cell, beyond the grid to the last.
                if x.is_nan() || x < 0.0 {
                    0
                } else {
                    (x as usize).min(self.dims[k] - 1)
                }
            })
        };
        (cell(lo), cell(hi))
    }

    fn index(&self, x: usize, y: usize, z: usize) -> usize {
        (z * self.dims[1] + y) * self.dims[0] + x
    }

    /// Files triangle `t` with corners `p` (again, if it was filed before: older entries go stale).
    pub fn insert(&mut self, t: u32, p: [Vec3; 3]) {
        let g = &mut self.generation[t as usize];
        *g = g.wrapping_add(1);
        let (lo, hi) = (p[0].min(p[1]).min(p[2]), p[0].max(p[1]).max(p[2]));
        let entry = Entry { lo, hi, triangle: t, generation: *g };
        let (l, h) = self.range(lo, hi);
        if (0..3).map(|k| h[k] - l[k] + 1).product::<usize>() > MAX_CELLS_PER_TRIANGLE {
            self.large.entries.push(entry);
            return;
        }
        for z in l[2]..=h[2] {
            for y in l[1]..=h[1] {
                for x in l[0]..=h[0] {
                    let i = self.index(x, y, z);
                    if self.slots[i] == NO_CELL {
                        self.slots[i] = self.cells.len() as u32;
                        self.cells.push(Cell::default());
                    }
                    self.cells[self.slots[i] as usize].entries.push(entry);
                }
            }
        }
    }

    /// The live triangles (by `alive`) whose current boxes meet the closed box `lo..=hi` and are
    /// `wanted` (given the box: a finer filter than one box), each once, into `out` (cleared
    /// first).
    pub fn near(&mut self, lo: Vec3, hi: Vec3, alive: &[bool], wanted: impl Fn(Vec3, Vec3) -> bool, out: &mut Vec<u32>) {
        out.clear();
        self.round = self.round.wrapping_add(1);
        if self.round == 0 {
            self.stamp.fill(0);
            self.round = 1;
        }
        let (l, h) = self.range(lo, hi);
        let (generation, stamp, round) = (&self.generation, &mut self.stamp, self.round);
        let current = |e: &Entry| alive[e.triangle as usize] && generation[e.triangle as usize] == e.generation;
        let mut take = |cell: &mut Cell| {
            if cell.entries.len() > COMPACT_AT.max(2 * cell.kept) {
                cell.entries.retain(current);
                cell.kept = cell.entries.len();
            }
            for e in cell.entries.iter() {
                let t = e.triangle as usize;
                if e.lo.cmple(hi).all() && e.hi.cmpge(lo).all() && stamp[t] != round && current(e) && wanted(e.lo, e.hi) {
                    stamp[t] = round;
                    out.push(e.triangle);
                }
            }
        };
        take(&mut self.large);
        for z in l[2]..=h[2] {
            for y in l[1]..=h[1] {
                for x in l[0]..=h[0] {
                    let i = (z * self.dims[1] + y) * self.dims[0] + x;
                    if let Some(cell) = self.cells.get_mut(self.slots[i] as usize) {
                        take(cell);
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tri(c: Vec3) -> [Vec3; 3] {
        [c, c + Vec3::X * 0.1, c + Vec3::Y * 0.1]
    }

    #[test]
    fn finds_what_is_near_once_and_forgets_what_moved_or_died() {
        let mut g = TriangleGrid::new(Vec3::ZERO, Vec3::splat(10.0), 1.0, 4);
        g.insert(0, tri(Vec3::splat(1.0)));
        g.insert(1, tri(Vec3::splat(1.05)));
        g.insert(2, tri(Vec3::splat(8.0)));
        // One spanning the whole box lands in the list every query reads.
        g.insert(3, [Vec3::ZERO, Vec3::splat(10.0), Vec3::new(10.0, 0.0, 0.0)]);
        let mut alive = vec![true; 4];
        let mut out = Vec::new();
        g.near(Vec3::splat(0.9), Vec3::splat(1.3), &alive, |_, _| true, &mut out);
        out.sort_unstable();
        assert_eq!(out, [0, 1, 3]);
        // In the same cell but with a box the query misses.
        g.near(Vec3::splat(1.2), Vec3::splat(1.3), &alive, |_, _| true, &mut out);
        out.sort_unstable();
        assert_eq!(out, [3]);
        // Triangle 1 moves far away: it is no longer near, and is found where it now is.
        g.insert(1, tri(Vec3::splat(5.0)));
        g.near(Vec3::splat(0.9), Vec3::splat(1.3), &alive, |_, _| true, &mut out);
        out.sort_unstable();
        assert_eq!(out, [0, 3]);
        g.near(Vec3::splat(4.9), Vec3::splat(5.2), &alive, |_, _| true, &mut out);
        out.sort_unstable();
        assert_eq!(out, [1, 3]);
        alive[0] = false;
        g.near(Vec3::ZERO, Vec3::splat(10.0), &alive, |_, _| true, &mut out);
        out.sort_unstable();
        assert_eq!(out, [1, 2, 3]);
        // Outside the box is clamped onto the border, not lost.
        g.insert(2, tri(Vec3::splat(30.0)));
        g.near(Vec3::splat(9.9), Vec3::splat(40.0), &alive, |_, _| true, &mut out);
        out.sort_unstable();
        assert_eq!(out, [2, 3]);
        // Refiling many times does not grow a cell without bound.
        for _ in 0..1000 {
            g.insert(0, tri(Vec3::splat(1.0)));
            g.near(Vec3::splat(0.9), Vec3::splat(1.3), &alive, |_, _| true, &mut out);
        }
        assert!(g.cells.iter().map(|c| c.entries.len()).max().unwrap() <= COMPACT_AT + 1);
    }
}
