//! The topology-safe collapse (`edge-collapse-safe`): shortest edge first, each collapse
//! checked against the link condition, normal flips and (optionally) the triangles near it; see
//! the parent module for the rules.

use super::rebuild;
use crate::mesh::TriMesh;
use crate::post::triangle_grid::TriangleGrid;
use crate::predicates::{has_zero_area, indexed_triangles_intersect, strictly_one_sign, PlaneFilter};
use glam::Vec3;
use petgraph::unionfind::UnionFind;
use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// A triangle whose doubled area is below this fraction of its longest edge squared (an altitude
/// under 5% of that edge) is a sliver: its normal is not held fixed by the flip tests.
const SLIVER: f32 = 0.05;

/// Closed parts with this many vertices or fewer are not simplified further.
pub const MIN_PART: usize = 8;

/// Shortest-first topology-safe collapse of edges shorter than `limit`, down to `target`
/// triangles if that is not zero. `min_cos`: cosine of the largest allowed normal turn;
/// `refuse_intersections`: test each collapse against the triangles near it and refuse those that
/// would make two triangles meet.
pub fn collapse_safe(mesh: &mut TriMesh, limit: f32, target: usize, min_cos: f32, refuse_intersections: bool) {
    let n = mesh.positions.len();
    let mut position = mesh.positions.clone();
    let mut tris = mesh.triangles.clone();
    let mut alive = vec![true; tris.len()];
    // Each triangle keeps its slot as its corners are relabelled, so its first normal stays
    // comparable: no sequence of collapses may turn a triangle to face away from where it began.
    let original: Vec<Vec3> = tris
        .iter()
        .map(|t| {
            let p = t.map(|w| position[w as usize]);
            (p[1] - p[0]).cross(p[2] - p[0])
        })
        .collect();
    let mut fan: Vec<Vec<u32>> = vec![Vec::new(); n];
    for (t, tri) in tris.iter().enumerate() {
        for &v in tri {
            fan[v as usize].push(t as u32);
        }
    }
    let mut removed = vec![false; n];
    let mut version = vec![0u32; n];
    // Vertices left in each connected part: parts of MIN_PART vertices or fewer are left alone,
    // so a one-cell blob keeps its shape instead of folding into an inside-out tetrahedron.
    let mut parts = UnionFind::<u32>::new(n);
    for t in &tris {
        for k in 0..3 {
            parts.union(t[k], t[(k + 1) % 3]);
        }
    }
    let part: Vec<u32> = (0..n as u32).map(|v| parts.find_mut(v)).collect();
    let mut part_size = vec![0usize; n];
    for &p in &part {
        part_size[p as usize] += 1;
    }
    // Boundary vertices: on an edge with one triangle (or on a non-manifold edge: left alone too).
    let mut boundary = vec![false; n];
    let mut all_edges: Vec<(u32, u32)> =
        tris.iter().flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])]).map(|(a, b)| (a.min(b), a.max(b))).collect();
    all_edges.sort_unstable();
    for group in all_edges.chunk_by(|x, y| x == y) {
        if group.len() != 2 {
            boundary[group[0].0 as usize] = true;
            boundary[group[0].1 as usize] = true;
        }
    }
    all_edges.dedup();
    let key = |d: f32| Reverse(d.to_bits());
    let mut heap: BinaryHeap<(Reverse<u32>, u32, u32, u32, u32)> = BinaryHeap::new();
    for &(a, b) in &all_edges {
        let d = position[a as usize].distance(position[b as usize]);
        if d < limit {
            heap.push((key(d), a, b, 0, 0));
        }
    }
    let mut live = tris.len();
    let mut grid = refuse_intersections.then(|| triangle_grid(&tris, &position, &all_edges));
    let mut scratch = FoldScratch::default();
    let mut neighbours_a = Vec::new();
    let mut neighbours_b = Vec::new();
    while let Some((_, a, b, va, vb)) = heap.pop() {
        if target > 0 && live <= target {
            break;
        }
        let (ai, bi) = (a as usize, b as usize);
        if removed[ai] || removed[bi] || version[ai] != va || version[bi] != vb {
            continue;
        }
        if boundary[ai] || boundary[bi] || part_size[part[ai] as usize] <= MIN_PART {
            continue;
        }
        // Triangles on the edge, and the link condition.
        let mut shared = [u32::MAX; 2];
        let mut count = 0;
        for &t in &fan[ai] {
            if alive[t as usize] && tris[t as usize].contains(&b) {
                if count < 2 {
                    shared[count] = t;
                }
                count += 1;
            }
        }
        if count != 2 {
            continue;
        }
        ring(ai, &fan, &tris, &alive, &mut neighbours_a);
        ring(bi, &fan, &tris, &alive, &mut neighbours_b);
        let common = neighbours_a.iter().filter(|w| neighbours_b.contains(w)).count();
        let opposite = shared.map(|t| tris[t as usize].iter().copied().find(|&w| w != a && w != b).unwrap_or(a));
        // Link condition: the endpoints share exactly the two opposite vertices.
        if common != 2 || opposite[0] == opposite[1] {
            continue;
        }
        let degree = |v: u32| fan[v as usize].iter().filter(|&&t| alive[t as usize]).count();
        if opposite.iter().any(|&o| degree(o) <= 3) {
            continue;
        }
        // Normals of the surviving triangles must not flip or turn too far.
        let target_position = 0.5 * (position[ai] + position[bi]);
        let turns_ok = [ai, bi].iter().all(|&v| {
            fan[v].iter().filter(|&&t| alive[t as usize] && !shared.contains(&t)).all(|&t| {
                let tri = tris[t as usize];
                let p = tri.map(|w| position[w as usize]);
                let q = tri.map(|w| if w == a || w == b { target_position } else { position[w as usize] });
                let n0 = (p[1] - p[0]).cross(p[2] - p[0]);
                let n1 = (q[1] - q[0]).cross(q[2] - q[0]);
                let (l0, l1) = (n0.length(), n1.length());
                // A sliver's normal says little: only its replacement's non-degeneracy counts.
                let longest =
                    (p[1] - p[0]).length_squared().max((p[2] - p[1]).length_squared()).max((p[0] - p[2]).length_squared());
                let sliver = l0 < SLIVER * longest;
                // A triangle that already has no area may keep none (its own zero-length
                // edge collapses in turn); any other must keep some.
                let keeps_area = l1 > 1e-12 * l0.max(1e-30) || l0 == 0.0;
                keeps_area && (sliver || (n0.dot(n1) >= min_cos * l0 * l1 && n1.dot(original[t as usize]) >= 0.0))
            })
        });
        if !turns_ok {
            continue;
        }
        let collapse = Collapse { a, b, to: target_position, shared };
        if let Some(grid) = grid.as_mut() {
            if collapse.makes_intersection(&tris, &alive, &position, &fan, grid, &mut scratch) {
                continue;
            }
        }
        // Collapse b into a.
        for &t in &shared {
            alive[t as usize] = false;
            live -= 1;
        }
        position[ai] = target_position;
        removed[bi] = true;
        part_size[part[ai] as usize] -= 1;
        let moved = std::mem::take(&mut fan[bi]);
        for &t in &moved {
            if !alive[t as usize] {
                continue;
            }
            for w in tris[t as usize].iter_mut() {
                if *w == b {
                    *w = a;
                }
            }
            fan[ai].push(t);
        }
        fan[ai].retain(|&t| alive[t as usize]);
        if let Some(grid) = grid.as_mut() {
            for &t in &fan[ai] {
                grid.insert(t, tris[t as usize].map(|w| position[w as usize]));
            }
        }
        version[ai] += 1;
        ring(ai, &fan, &tris, &alive, &mut neighbours_a);
        for &w in &neighbours_a {
            let d = position[ai].distance(position[w as usize]);
            if d < limit {
                let (x, y) = (a.min(w), a.max(w));
                heap.push((key(d), x, y, version[x as usize], version[y as usize]));
            }
        }
    }
    let map: Vec<u32> = (0..n as u32).collect();
    mesh.triangles = tris.iter().zip(&alive).filter(|(_, &live)| live).map(|(t, _)| *t).collect();
    rebuild(mesh, &position, &map);
}

/// The grid the intersection test reads: every triangle filed, cells about three mean edges (the
/// size of a moved fan; smaller cells measured slower, as each costs a lookup).
fn triangle_grid(tris: &[[u32; 3]], position: &[Vec3], edges: &[(u32, u32)]) -> TriangleGrid {
    let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    for p in position {
        (lo, hi) = (lo.min(*p), hi.max(*p));
    }
    let mean_edge =
        edges.iter().map(|&(x, y)| position[x as usize].distance(position[y as usize])).sum::<f32>() / edges.len().max(1) as f32;
    let mut grid = TriangleGrid::new(lo, hi, 3.0 * mean_edge, tris.len());
    for (t, tri) in tris.iter().enumerate() {
        grid.insert(t as u32, tri.map(|w| position[w as usize]));
    }
    grid
}

/// One proposed collapse: `b` merges into `a`, which moves to `to`; `shared` are the two triangles
/// on the edge, which die.
struct Collapse {
    a: u32,
    b: u32,
    to: Vec3,
    shared: [u32; 2],
}

/// Buffers [`Collapse::makes_intersection`] reuses.
#[derive(Default)]
struct FoldScratch {
    moved: Vec<Moved>,
    near: Vec<u32>,
    /// The corners of the moved triangles, each once: vertex and position after the collapse.
    points: Vec<(u32, Vec3)>,
    /// For each of `points`, its side of the candidate's plane (or [`SHARED`]).
    sides: Vec<i8>,
}

/// A surviving triangle of the two fans after the collapse.
struct Moved {
    /// Its vertices, `b` relabelled `a`.
    ids: [u32; 3],
    /// Its vertices before the collapse.
    before: [u32; 3],
    /// Its corners in [`FoldScratch::points`].
    corners: [u8; 3],
    bounds: (Vec3, Vec3),
}

impl Collapse {
    fn label(&self, w: u32) -> u32 {
        if w == self.b {
            self.a
        } else {
            w
        }
    }

    fn position_after(&self, position: &[Vec3], w: u32) -> Vec3 {
        if w == self.a || w == self.b {
            self.to
        } else {
            position[w as usize]
        }
    }

    /// Whether the collapse would make a surviving triangle of the two fans meet another live
    /// triangle beyond what they share where the two did not meet before, decided as the
    /// self-intersection metric decides it (exact predicates, zero-area triangles skipped): each
    /// moved triangle against the live triangles filed near the moved fan, and against the other
    /// moved triangles. So a collapse never adds a self-intersecting pair.
    fn makes_intersection(
        &self,
        tris: &[[u32; 3]],
        alive: &[bool],
        position: &[Vec3],
        fan: &[Vec<u32>],
        grid: &mut TriangleGrid,
        scratch: &mut FoldScratch,
    ) -> bool {
        let after = |w: u32| self.position_after(position, w);
        let now = |w: u32| position[w as usize];
        // A pair that meets after the collapse counts only if it did not meet before: an
        // intersection already there (such as two vertices of the input at one point) neither
        // blocks the edits around it nor can be added to.
        // (The metric skips zero-area triangles, so a pair with one had no meeting to keep.)
        let met_before = |x: [u32; 3], y: [u32; 3]| {
            !has_zero_area(x.map(now)) && !has_zero_area(y.map(now)) && indexed_triangles_intersect(x, y, now)
        };
        let new_meeting = |x: &Moved, y_after: [u32; 3], y_before: [u32; 3]| {
            indexed_triangles_intersect(x.ids, y_after, after) && !met_before(x.before, y_before)
        };
        let FoldScratch { moved, near, points, sides } = scratch;
        moved.clear();
        points.clear();
        for &t in [self.a, self.b].iter().flat_map(|&v| &fan[v as usize]) {
            if alive[t as usize] && !self.shared.contains(&t) {
                let ids = tris[t as usize].map(|w| self.label(w));
                let p = ids.map(after);
                if !has_zero_area(p) {
                    let corners = ids.map(|w| local_index(points, w, after(w)));
                    moved.push(Moved { ids, before: tris[t as usize], corners, bounds: bounds(p) });
                }
            }
        }
        let Some(all) = moved.iter().map(|m| m.bounds).reduce(|x, y| (x.0.min(y.0), x.1.max(y.1))) else {
            return false;
        };
        for (i, m) in moved.iter().enumerate() {
            for n in &moved[i + 1..] {
                if !apart(m.bounds, n.bounds) && new_meeting(m, n.ids, n.before) {
                    return true;
                }
            }
        }
        grid.near(all.0, all.1, alive, |lo, hi| moved.iter().any(|m| !apart(m.bounds, (lo, hi))), near);
        near.iter().any(|&u| {
            let other = tris[u as usize];
            // Triangles with a or b are the moved ones (checked above) or the two that die.
            if other.contains(&self.a) || other.contains(&self.b) {
                return false;
            }
            let q = other.map(|w| position[w as usize]);
            let box_u = bounds(q);
            let mut near_moved = moved.iter().filter(|m| !apart(m.bounds, box_u)).peekable();
            if near_moved.peek().is_none() || has_zero_area(q) {
                return false;
            }
            // Which side of u's plane each moved corner is on, once per candidate: most pairs are
            // settled by it without an exact predicate.
            let plane = PlaneFilter::of(&q);
            sides.clear();
            sides.extend(points.iter().map(|&(w, p)| if other.contains(&w) { SHARED } else { plane.side(p) }));
            near_moved.any(|m| {
                !strictly_one_sign(m.corners.iter().map(|&k| sides[k as usize]).filter(|&s| s != SHARED))
                    && new_meeting(m, other, other)
            })
        })
    }
}

/// A corner shared with the candidate triangle, in [`FoldScratch::sides`].
const SHARED: i8 = 2;

/// The index of vertex `w` in `points`, added at `p` if it is not there yet.
fn local_index(points: &mut Vec<(u32, Vec3)>, w: u32, p: Vec3) -> u8 {
    let k = points.iter().position(|&(v, _)| v == w).unwrap_or_else(|| {
        points.push((w, p));
        points.len() - 1
    });
    k as u8
}

/// A triangle's bounding box.
fn bounds(p: [Vec3; 3]) -> (Vec3, Vec3) {
    (p[0].min(p[1]).min(p[2]), p[0].max(p[1]).max(p[2]))
}

/// Whether two closed boxes are disjoint.
fn apart(x: (Vec3, Vec3), y: (Vec3, Vec3)) -> bool {
    x.0.cmpgt(y.1).any() || y.0.cmpgt(x.1).any()
}

/// The vertices sharing a live triangle with `v`, each once (fans are small: a linear test).
fn ring(v: usize, fan: &[Vec<u32>], tris: &[[u32; 3]], alive: &[bool], out: &mut Vec<u32>) {
    out.clear();
    for &t in &fan[v] {
        if alive[t as usize] {
            for &w in &tris[t as usize] {
                if w as usize != v && !out.contains(&w) {
                    out.push(w);
                }
            }
        }
    }
}
