//! A sample's side without a winding number per sample: row crossings counted against the
//! mesh and the caps (cones) that close its holes, decided exactly where they can be and left to
//! the winding number where they cannot (see the parent module's "Sampling a grid").

use crate::bvh::{TriangleBvh, WindingInterval};
use crate::geometry::Aabb;
use crate::lattice::Grid;
use glam::Vec3;
use std::ops::Range;

/// Whether a winding-number interval is certainly inside (`|w| >= 1/2` everywhere), certainly
/// outside, or neither (`None`).
pub(super) fn inside(w: &crate::bvh::WindingInterval) -> Option<bool> {
    let (low, high) = (w.centre - w.error, w.centre + w.error);
    if low >= 0.5 || high <= -0.5 {
        Some(true)
    } else if low > -0.5 && high < 0.5 {
        Some(false)
    } else {
        None
    }
}

/// Whether a sample whose side [`BandFill::sided`] decided is inside (`caps`: the caps' winding
/// interval over its box, when the box has [`Side::NearCaps`] samples).
pub(super) fn is_inside(side: Side, caps: Option<WindingInterval>) -> bool {
    match side {
        Side::Inside => true,
        Side::NearCaps(n) => caps.and_then(|c| side_from_caps(n, c.centre, c.error)).unwrap_or(false),
        Side::Outside | Side::Unknown => false,
    }
}

/// Whether a sample whose mesh and caps wind `n` times around it (row crossings' count), where
/// the caps' own winding number is within `error` of `caps`, is inside: the mesh's own winding
/// number is `n` less the caps', inside where its magnitude is at least 1/2. Decided only when
/// every value in the interval keeps [`CAP_WINDING_BOUND`] clear of 1/2 (room for the error of
/// the mesh's fast winding number, which the field's sign follows); `None` otherwise.
pub(super) fn side_from_caps(n: i32, caps: f64, error: f64) -> Option<bool> {
    let (low, high) = (f64::from(n) - caps - error, f64::from(n) - caps + error);
    let margin = CAP_WINDING_BOUND;
    if low >= 0.5 + margin || high <= -0.5 - margin {
        Some(true)
    } else if low >= -0.5 + margin && high <= 0.5 - margin {
        Some(false)
    } else {
        None
    }
}

/// A sample's side, as row crossings tell it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Side {
    Inside,
    Outside,
    /// A cap is near (its winding number may exceed [`CAP_WINDING_BOUND`]): mesh and caps wind
    /// this many times around the sample, and the side comes from the caps' winding number over
    /// the sample's box ([`side_from_caps`]).
    NearCaps(i32),
    /// The row touches an edge or a vertex of a triangle's projection, or a crossing lies within
    /// [`CROSSING_TOLERANCE`] of the sample: the sample's side comes from the winding number.
    Unknown,
}

/// How near a crossing (in grid spacings) makes a sample ask its own winding number instead.
pub const CROSSING_TOLERANCE: f64 = 1e-4;

/// Largest bound on the caps' winding number at a sample whose side row crossings give alone:
/// the mesh's winding number is then within this of the crossings' integer, far from 1/2.
/// Nearer the caps, the caps' winding interval over a box must keep the mesh's this far from 1/2.
pub const CAP_WINDING_BOUND: f64 = 0.25;

/// Cones closing an open mesh: one per connected piece of its boundary (the edges its triangles
/// leave uncancelled, with multiplicity), from the piece's centroid. The mesh and its caps have
/// no boundary, so their winding number `n` is an integer that row crossings count; the mesh's
/// own is `n - w_caps`.
#[derive(Clone, Debug, Default)]
pub(super) struct Caps {
    /// The cones' triangles, wound so that they cancel the mesh's boundary.
    pub(super) triangles: Vec<[Vec3; 3]>,
    /// The same triangles in a hierarchy, for their winding interval over a box (none for a
    /// closed mesh).
    pub(super) bvh: Option<TriangleBvh>,
    /// Per cone: its apex, the largest distance from the apex to its rim, and its area.
    pub(super) cones: Vec<(Vec3, f32, f64)>,
}

impl Caps {
    /// The caps of `soup` (the triangles as the field keeps them). Corners are told apart by
    /// position, not by index: a seam whose two sides repeat the same positions under different
    /// indices (the Utah teapot's patches) cancels like a shared edge, since the winding number
    /// depends on the geometry alone. Capping such a seam would put a cone through the solid,
    /// near which every sample needs its own winding number.
    pub(super) fn closing(soup: &[[Vec3; 3]]) -> Self {
        let mut net: std::collections::HashMap<(u32, u32), i32> = std::collections::HashMap::new();
        let mut position_ids: std::collections::HashMap<[u32; 3], u32> = std::collections::HashMap::new();
        let mut at: Vec<Vec3> = Vec::new();
        for corners in soup {
            // `+ 0.0` makes -0.0 and 0.0 one position.
            let [a, b, c] = corners.map(|p| {
                *position_ids.entry((p + Vec3::ZERO).to_array().map(f32::to_bits)).or_insert_with(|| {
                    at.push(p);
                    (at.len() - 1) as u32
                })
            });
            for (u, v) in [(a, b), (b, c), (c, a)] {
                if u != v {
                    *net.entry((u.min(v), u.max(v))).or_default() += if u < v { 1 } else { -1 };
                }
            }
        }
        let mut edges: Vec<(u32, u32, u32)> = net
            .into_iter()
            .filter(|&(_, n)| n != 0)
            .map(|((u, v), n)| if n > 0 { (u, v, n as u32) } else { (v, u, n.unsigned_abs()) })
            .collect();
        if edges.is_empty() {
            return Self::default();
        }
        edges.sort_unstable();
        let mut ids: Vec<u32> = edges.iter().flat_map(|&(u, v, _)| [u, v]).collect();
        ids.sort_unstable();
        ids.dedup();
        let local = |v: u32| ids.binary_search(&v).unwrap_or(0);
        let mut pieces = petgraph::unionfind::UnionFind::<usize>::new(ids.len());
        for &(u, v, _) in &edges {
            pieces.union(local(u), local(v));
        }
        let mut caps = Self::default();
        let mut roots: Vec<usize> = (0..ids.len()).map(|i| pieces.find(i)).collect();
        roots.sort_unstable();
        roots.dedup();
        for root in roots {
            let rim: Vec<Vec3> = ids.iter().filter(|&&v| pieces.find(local(v)) == root).map(|&v| at[v as usize]).collect();
            let apex = (rim.iter().map(|p| p.as_dvec3()).sum::<glam::DVec3>() / rim.len() as f64).as_vec3();
            let radius = rim.iter().map(|p| p.distance(apex)).fold(0.0, f32::max);
            let mut area = 0.0;
            for &(u, v, n) in edges.iter().filter(|e| pieces.find(local(e.0)) == root) {
                let t = [apex, at[v as usize], at[u as usize]];
                area += f64::from(n) * 0.5 * (t[1] - t[0]).as_dvec3().cross((t[2] - t[0]).as_dvec3()).length();
                caps.triangles.extend(std::iter::repeat_n(t, n as usize));
            }
            caps.cones.push((apex, radius, area));
        }
        caps.bvh = Some(TriangleBvh::new(caps.triangles.clone()));
        caps
    }

    /// A bound on the caps' winding number at `p` (a triangle's solid angle is at most its area
    /// over the squared distance), infinite within a cone's ball.
    pub(super) fn winding_bound(&self, p: Vec3) -> f64 {
        self.cones
            .iter()
            .map(|&(apex, radius, area)| {
                let gap = f64::from(p.distance(apex)) - f64::from(radius);
                if gap > 0.0 {
                    area / (4.0 * std::f64::consts::PI * gap * gap)
                } else {
                    f64::INFINITY
                }
            })
            .sum()
    }
}

/// The side of every sample of the z-layers `layers` of `grid` (slab order), by counting
/// crossings along each x-row. The mesh closed by its `caps` has an integer winding number `n`,
/// 0 far out along the row and changing by one at each crossing (up where the triangle faces
/// away from +x, down where it faces +x); the mesh's own winding number is `n` less the caps',
/// so where the caps' is bounded by [`CAP_WINDING_BOUND`] (everywhere, for a closed mesh) a
/// sample is inside exactly where `n` is nonzero. Whether a row meets a triangle is decided with
/// exact orientation tests in the row's (y, z) plane; a row through a projected edge or vertex,
/// or along a triangle seen edge-on, leaves its samples [`Side::Unknown`], as does a crossing
/// within [`CROSSING_TOLERANCE`] of a sample, or a cap nearby. The sides agree with the fast
/// winding number's `|w| >= 1/2` (tested on every sample of the shipped models).
pub(super) fn crossing_signs(bvh: &TriangleBvh, caps: &Caps, grid: &Grid, layers: Range<usize>) -> Vec<Side> {
    use crate::predicates::o2;
    let [nx, ny, _] = grid.dims;
    let rows = ny * layers.len();
    let mut sides = vec![Side::Outside; nx * rows];
    if rows == 0 || nx == 0 {
        return sides;
    }
    let (first, last) = (grid.position(0, 0, layers.start), grid.position(0, ny - 1, layers.end - 1));
    let query = Aabb::new(Vec3::new(f32::MIN, first.y, first.z), Vec3::new(f32::MAX, last.y, last.z));
    let mut unsure = vec![false; rows];
    let mut crossings: Vec<(u32, f64, i8)> = Vec::new();
    let index_range = |lo: f32, hi: f32, origin: f32, count: usize| {
        let from = ((lo - origin) / grid.spacing).floor() - 1.0;
        let to = ((hi - origin) / grid.spacing).ceil() + 1.0;
        (from.max(0.0) as usize)..((to.max(-1.0) + 1.0) as usize).min(count)
    };
    let mut cross = |t: &[Vec3; 3]| {
        let [a, b, c] = *t;
        let facing = o2(a, b, c, 0);
        let (lo, hi) = (a.min(b).min(c), a.max(b).max(c));
        let js = index_range(lo.y, hi.y, grid.origin.y, ny);
        let ks = index_range(lo.z, hi.z, grid.origin.z, grid.dims[2]);
        for k in ks.start.max(layers.start)..ks.end.min(layers.end) {
            for j in js.clone() {
                let row = (k - layers.start) * ny + j;
                let r = grid.position(0, j, k);
                let e = [o2(a, b, r, 0), o2(b, c, r, 0), o2(c, a, r, 0)];
                if facing == 0 {
                    // Seen edge-on: only a row on its projected segment is in doubt.
                    if e == [0, 0, 0] && (lo.y..=hi.y).contains(&r.y) && (lo.z..=hi.z).contains(&r.z) {
                        unsure[row] = true;
                    }
                    continue;
                }
                if e.iter().all(|&s| s == facing) {
                    match crossing_x(t, r) {
                        Some(x) => crossings.push((row as u32, x, -facing)),
                        None => unsure[row] = true,
                    }
                } else if e.iter().all(|&s| s == facing || s == 0) {
                    unsure[row] = true;
                }
            }
        }
    };
    bvh.for_each_overlapping(&query, |_, t| cross(t));
    caps.triangles.iter().for_each(&mut cross);
    crossings.sort_unstable_by(|p, q| p.0.cmp(&q.0).then(p.1.total_cmp(&q.1)));
    let tolerance = CROSSING_TOLERANCE * f64::from(grid.spacing);
    let mut next = 0;
    for (row, unsure) in unsure.iter().enumerate() {
        let end = next + crossings[next..].iter().take_while(|c| c.0 as usize == row).count();
        let here = &crossings[next..end];
        next = end;
        let out = &mut sides[row * nx..(row + 1) * nx];
        if *unsure {
            out.fill(Side::Unknown);
            continue;
        }
        let (j, k) = (row % ny, layers.start + row / ny);
        let (mut winding, mut c) = (0i32, 0);
        for (i, side) in out.iter_mut().enumerate() {
            let p = grid.position(i, j, k);
            let x = f64::from(p.x);
            while c < here.len() && here[c].1 < x - tolerance {
                winding += i32::from(here[c].2);
                c += 1;
            }
            let on_a_crossing = c < here.len() && here[c].1 <= x + tolerance;
            *side = if on_a_crossing {
                Side::Unknown
            } else if !caps.cones.is_empty() && caps.winding_bound(p) >= CAP_WINDING_BOUND {
                Side::NearCaps(winding)
            } else if winding != 0 {
                Side::Inside
            } else {
                Side::Outside
            };
        }
    }
    sides
}

/// Where the x-parallel line through `r` (its y and z) meets the plane of triangle `t`, whose
/// projection onto (y, z) it crosses; `None` when that projection is so thin against its
/// coordinates that `f64` rounding of the barycentric weights (products of coordinate
/// differences) could move the answer by more than about 1e-9 of the triangle: the row then
/// takes its samples' winding numbers.
pub(super) fn crossing_x(t: &[Vec3; 3], r: Vec3) -> Option<f64> {
    let [a, b, c] = t.map(|v| v.as_dvec3());
    let (py, pz) = (f64::from(r.y), f64::from(r.z));
    let products = |u: glam::DVec3, v: glam::DVec3| ((u.y - py) * (v.z - pz), (u.z - pz) * (v.y - py));
    let pairs = [products(b, c), products(c, a), products(a, b)];
    let [wa, wb, wc] = pairs.map(|(p, q)| p - q);
    let magnitude: f64 = pairs.iter().map(|(p, q)| p.abs() + q.abs()).sum();
    let sum = wa + wb + wc;
    let x = (wa * a.x + wb * b.x + wc * c.x) / sum;
    (sum.abs() > 1e-6 * magnitude && x.is_finite()).then_some(x)
}
