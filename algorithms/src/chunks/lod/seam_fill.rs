//! Filling a stitched seam polygon (the `lod` module doc's step 2): the coarse triangle's corners
//! off the seam and the fine boundary path that replaced its seam edge, filled by the
//! best-shaped candidate (every triangulation, and fans from a new vertex inside) whose triangles
//! cross nothing near them, by exact predicates.

use crate::geometry::all_triangulations;
use crate::predicates::{has_zero_area, indexed_triangles_intersect};
use glam::Vec3;
use rustc_hash::{FxHashMap, FxHashSet};
use std::collections::HashSet;

/// The triangles around the seams, bucketed by coarse cell, and every edge's uses: what a
/// stitched triangle's filling must not cross or duplicate.
pub(super) struct SeamNeighbourhood<'a> {
    positions: &'a [Vec3],
    /// Coarse cell side, in samples.
    s: usize,
    cells: FxHashMap<[i64; 3], Vec<[u32; 3]>>,
    /// Stitched triangles left as fans for want of a filling that crosses nothing.
    pub(super) unresolved: usize,
    /// Vertices added inside seam polygons (numbered after `positions`).
    pub(super) added: Vec<Vec3>,
}

impl<'a> SeamNeighbourhood<'a> {
    pub(super) fn new(positions: &'a [Vec3], s: usize) -> Self {
        SeamNeighbourhood { positions, s, cells: FxHashMap::default(), unresolved: 0, added: Vec::new() }
    }

    /// Takes in the kept `triangles` within a coarse cell of the `stitched` ones' cells (the only
    /// ones a filling can meet: it stays in its triangle's coarse cell).
    pub(super) fn bucket(&mut self, triangles: &[[u32; 3]], removed: &[bool], stitched: impl Iterator<Item = [u32; 3]>) {
        let mut wanted: FxHashSet<[i64; 3]> = FxHashSet::default();
        for t in stitched {
            let c = self.cell(t);
            wanted.extend((0..27).map(|k| [c[0] + k % 3 - 1, c[1] + (k / 3) % 3 - 1, c[2] + k / 9 - 1]));
        }
        for (t, _) in triangles.iter().zip(removed).filter(|(_, &r)| !r) {
            if wanted.contains(&self.cell(*t)) {
                self.add(*t);
            }
        }
    }

    fn at(&self, v: u32) -> Vec3 {
        let v = v as usize;
        self.positions.get(v).copied().unwrap_or_else(|| self.added[v - self.positions.len()])
    }

    fn cell(&self, t: [u32; 3]) -> [i64; 3] {
        self.cell_of(t.map(|v| self.at(v)))
    }

    fn cell_of(&self, p: [Vec3; 3]) -> [i64; 3] {
        // Index coordinates are not negative: truncation is the floor.
        let c = (p[0].as_dvec3() + p[1].as_dvec3() + p[2].as_dvec3()) * (1.0 / (3.0 * self.s as f64));
        [c.x as i64, c.y as i64, c.z as i64]
    }

    pub(super) fn add(&mut self, t: [u32; 3]) {
        self.cells.entry(self.cell(t)).or_default().push(t);
    }

    /// The filling of the cycle `ring` (the polygon's corners in winding order) with the
    /// largest smallest angle among those whose triangles have area, add no edge the mesh has,
    /// and cross neither each other nor a triangle within a coarse cell of them (exact
    /// predicates); `None` when no filling passes. Besides every triangulation of the ring, fans
    /// from a new vertex between the seam's part of the ring and its corners `off_seam`
    /// ([`STEINER_STEPS`]) are tried: the seam path runs close to the coarse edge it replaced,
    /// so a triangulation of the ring alone is thin.
    pub(super) fn best_fill(&mut self, ring: &[u32], off_seam: &[u32]) -> Option<Vec<[u32; 3]>> {
        let next_id = (self.positions.len() + self.added.len()) as u32;
        let mut fills: Vec<(Option<Vec3>, Vec<[u32; 3]>)> = all_triangulations(ring).into_iter().map(|f| (None, f)).collect();
        if !off_seam.is_empty() && off_seam.len() < ring.len() {
            let mean = |vs: &mut dyn Iterator<Item = u32>| {
                let (sum, n) = vs.fold((glam::DVec3::ZERO, 0.0), |(s, n), v| (s + self.at(v).as_dvec3(), n + 1.0));
                sum / n
            };
            let seam = mean(&mut ring.iter().copied().filter(|v| !off_seam.contains(v)));
            let off = mean(&mut off_seam.iter().copied());
            for &t in STEINER_STEPS {
                let p = seam.lerp(off, t).as_vec3();
                fills.push((Some(p), (0..ring.len()).map(|i| [next_id, ring[i], ring[(i + 1) % ring.len()]]).collect()));
            }
        }
        let mut scored: Vec<(f64, usize)> = fills
            .iter()
            .enumerate()
            .map(|(k, (steiner, f))| {
                let at = |v: u32| if v == next_id { steiner.unwrap_or(Vec3::ZERO) } else { self.at(v) };
                (smallest_angle_cosine(f, &at), k)
            })
            .collect();
        scored.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        let ring_edges: HashSet<(u32, u32)> =
            (0..ring.len()).map(|i| (ring[i].min(ring[(i + 1) % ring.len()]), ring[i].max(ring[(i + 1) % ring.len()]))).collect();
        let found = scored.into_iter().map(|(_, k)| k).find(|&k| {
            let (steiner, fill) = &fills[k];
            let at = |v: u32| if v == next_id { steiner.unwrap_or(Vec3::ZERO) } else { self.at(v) };
            if fill.iter().any(|t| has_zero_area(t.map(at))) {
                return false;
            }
            let meet = |a: [u32; 3], b: [u32; 3]| indexed_triangles_intersect(a, b, at);
            let bounds = |t: [u32; 3]| {
                let p = t.map(at);
                (p[0].min(p[1]).min(p[2]), p[0].max(p[1]).max(p[2]))
            };
            let apart_inside = (0..fill.len()).all(|i| fill[i + 1..].iter().all(|&b| !meet(fill[i], b)));
            if !apart_inside {
                return false;
            }
            // The triangles of the coarse cells the filling's box reaches, whose boxes meet it.
            let (lo, hi) =
                fill.iter().map(|&t| bounds(t)).fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(l, h), (a, b)| (l.min(a), h.max(b)));
            let side = self.s as f32;
            let (c0, c1) = ((lo / side).floor(), (hi / side).floor());
            let mut nearby: Vec<([u32; 3], Vec3, Vec3)> = Vec::new();
            for z in c0.z as i64..=c1.z as i64 {
                for y in c0.y as i64..=c1.y as i64 {
                    for x in c0.x as i64..=c1.x as i64 {
                        let Some(others) = self.cells.get(&[x, y, z]) else { continue };
                        for &o in others {
                            let (olo, ohi) = bounds(o);
                            if !(olo.cmpgt(hi).any() || ohi.cmplt(lo).any()) {
                                nearby.push((o, olo, ohi));
                            }
                        }
                    }
                }
            }
            // A new edge the mesh already has (its triangles share the edge's ends, so they are
            // near) would be held by more than two triangles.
            let has_edge = |a: u32, b: u32| nearby.iter().any(|(o, _, _)| o.contains(&a) && o.contains(&b));
            let new_edge_used = fill
                .iter()
                .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
                .any(|(a, b)| !ring_edges.contains(&(a.min(b), a.max(b))) && has_edge(a, b));
            !new_edge_used
                && fill.iter().all(|&t| {
                    let (tlo, thi) = bounds(t);
                    nearby.iter().all(|&(o, olo, ohi)| olo.cmpgt(thi).any() || ohi.cmplt(tlo).any() || !meet(t, o))
                })
        })?;
        let (steiner, fill) = fills.swap_remove(found);
        if let Some(p) = steiner {
            self.added.push(p);
        }
        Some(fill)
    }
}

/// Where a seam polygon's new vertex may sit, from the mean of its seam corners (0) to the mean
/// of its other corners (1).
const STEINER_STEPS: &[f64] = &[0.25, 0.4, 0.55];

/// The cosine of the smallest angle of a filling's triangles (the filling with the largest
/// smallest angle has the smallest such cosine; 1 for a triangle without area).
fn smallest_angle_cosine(fill: &[[u32; 3]], at: &impl Fn(u32) -> Vec3) -> f64 {
    let cosine = |a: glam::DVec3, b: glam::DVec3, c: glam::DVec3| {
        let (u, v) = (b - a, c - a);
        let l = (u.length_squared() * v.length_squared()).sqrt();
        if l == 0.0 {
            1.0
        } else {
            u.dot(v) / l
        }
    };
    fill.iter()
        .map(|t| {
            let [a, b, c] = t.map(|v| at(v).as_dvec3());
            cosine(a, b, c).max(cosine(b, c, a)).max(cosine(c, a, b))
        })
        .fold(f64::NEG_INFINITY, f64::max)
}
