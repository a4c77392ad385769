//! Exact geometric predicates on `f32` points: orientation signs (Shewchuk's adaptive
//! predicates, from the `robust` crate, on coordinates that are exact in `f64`), closed
//! segment-triangle and triangle-triangle intersection, and point-in-tetrahedron. Shared by the
//! self-intersection metric and by `bcc-sculpt`'s sculpting and collision tests, so the answers do
//! not depend on rounding.

use glam::{DVec3, Vec3};
use robust::{orient2d, orient3d, Coord, Coord3D};

/// `p` as an exact `f64` coordinate.
pub fn c3(p: Vec3) -> Coord3D<f64> {
    Coord3D { x: f64::from(p.x), y: f64::from(p.y), z: f64::from(p.z) }
}

/// Sign of the orientation of `d` against the plane `abc` (positive: `abcd` is positively oriented
/// in the sense of `orient3d`).
pub fn o3(a: Vec3, b: Vec3, c: Vec3, d: Vec3) -> i8 {
    let v = orient3d(c3(a), c3(b), c3(c), c3(d));
    (v > 0.0) as i8 - (v < 0.0) as i8
}

/// Drops the coordinate along `axis` for 2D tests in a plane.
fn c2(p: Vec3, axis: usize) -> Coord<f64> {
    let (u, v) = match axis {
        0 => (p.y, p.z),
        1 => (p.z, p.x),
        _ => (p.x, p.y),
    };
    Coord { x: f64::from(u), y: f64::from(v) }
}

/// Sign of the 2D orientation of `abc` with `axis` dropped.
pub fn o2(a: Vec3, b: Vec3, c: Vec3, axis: usize) -> i8 {
    let v = orient2d(c2(a, axis), c2(b, axis), c2(c, axis));
    (v > 0.0) as i8 - (v < 0.0) as i8
}

/// The axis a triangle's plane is least parallel to (the one to drop for 2D tests).
pub fn dominant_axis(t: &[Vec3; 3]) -> usize {
    let n: DVec3 = (t[1] - t[0]).as_dvec3().cross((t[2] - t[0]).as_dvec3()).abs();
    if n.x >= n.y && n.x >= n.z {
        0
    } else if n.y >= n.z {
        1
    } else {
        2
    }
}

/// All three signs non-negative, or all non-positive.
pub fn same_sign_or_zero(a: i8, b: i8, c: i8) -> bool {
    (a >= 0 && b >= 0 && c >= 0) || (a <= 0 && b <= 0 && c <= 0)
}

/// Closed 2D segment-segment intersection.
fn segments_meet_2d(p: Vec3, q: Vec3, a: Vec3, b: Vec3, axis: usize) -> bool {
    let (d1, d2) = (o2(a, b, p, axis), o2(a, b, q, axis));
    let (d3, d4) = (o2(p, q, a, axis), o2(p, q, b, axis));
    if d1 * d2 < 0 && d3 * d4 < 0 {
        return true;
    }
    let on = |x: Vec3, s: Vec3, e: Vec3| {
        let (cx, cs, ce) = (c2(x, axis), c2(s, axis), c2(e, axis));
        cx.x >= cs.x.min(ce.x) && cx.x <= cs.x.max(ce.x) && cx.y >= cs.y.min(ce.y) && cx.y <= cs.y.max(ce.y)
    };
    (d1 == 0 && on(p, a, b)) || (d2 == 0 && on(q, a, b)) || (d3 == 0 && on(a, p, q)) || (d4 == 0 && on(b, p, q))
}

/// Closed 2D point-in-triangle.
fn point_in_triangle_2d(p: Vec3, t: &[Vec3; 3], axis: usize) -> bool {
    same_sign_or_zero(o2(t[0], t[1], p, axis), o2(t[1], t[2], p, axis), o2(t[2], t[0], p, axis))
}

/// Whether the closed segment `pq` meets the closed triangle `t`.
pub fn segment_meets_triangle(p: Vec3, q: Vec3, t: &[Vec3; 3]) -> bool {
    let (s1, s2) = (o3(t[0], t[1], t[2], p), o3(t[0], t[1], t[2], q));
    if s1 == s2 && s1 != 0 {
        return false;
    }
    if s1 == 0 && s2 == 0 {
        let axis = dominant_axis(t);
        return point_in_triangle_2d(p, t, axis)
            || point_in_triangle_2d(q, t, axis)
            || (0..3).any(|k| segments_meet_2d(p, q, t[k], t[(k + 1) % 3], axis));
    }
    same_sign_or_zero(o3(p, q, t[0], t[1]), o3(p, q, t[1], t[2]), o3(p, q, t[2], t[0]))
}

/// Whether two closed triangles with no shared vertex meet.
pub fn triangles_meet(a: &[Vec3; 3], b: &[Vec3; 3]) -> bool {
    (0..3).any(|k| segment_meets_triangle(a[k], a[(k + 1) % 3], b))
        || (0..3).any(|k| segment_meets_triangle(b[k], b[(k + 1) % 3], a))
}

/// Triangles `(s, a, b)` and `(s, c, d)` sharing only vertex `s`: do they meet elsewhere?
fn meet_beyond_shared_vertex(s: Vec3, a: Vec3, b: Vec3, c: Vec3, d: Vec3) -> bool {
    let t1 = [s, a, b];
    let t2 = [s, c, d];
    if segment_meets_triangle(a, b, &t2) || segment_meets_triangle(c, d, &t1) {
        return true;
    }
    // An edge from s lying in the other triangle's plane and pointing into its wedge at s.
    let into_wedge = |x: Vec3, t: &[Vec3; 3], u: Vec3, v: Vec3| {
        if o3(t[0], t[1], t[2], x) != 0 {
            return false;
        }
        let axis = dominant_axis(t);
        let w = o2(s, u, v, axis);
        w != 0 && o2(s, u, x, axis) * w >= 0 && o2(s, x, v, axis) * w >= 0
    };
    into_wedge(a, &t2, c, d) || into_wedge(b, &t2, c, d) || into_wedge(c, &t1, a, b) || into_wedge(d, &t1, a, b)
}

/// Whether two non-degenerate triangles, given by vertex indices and a position for each index,
/// intersect beyond the vertices and edges they share (the rules of CGAL's
/// `Polygon_mesh_processing::self_intersections`): sharing an edge, only when they fold onto
/// each other; sharing a vertex, when either's opposite edge meets the other or an edge from the
/// shared vertex runs into the other in its plane; otherwise when they touch at all. Used by the
/// self-intersection metric; written without allocation, as a per-edit test (such as a safe
/// edge collapse checking its one-ring) would call it for every candidate pair.
pub fn indexed_triangles_intersect(ti: [u32; 3], tj: [u32; 3], position: impl Fn(u32) -> Vec3) -> bool {
    indexed_intersect(ti, tj, position, true)
}

/// [`indexed_triangles_intersect`], with the float filters or (for the tests) without.
fn indexed_intersect(ti: [u32; 3], tj: [u32; 3], position: impl Fn(u32) -> Vec3, filtered: bool) -> bool {
    let mut shared = [0u32; 3];
    let mut count = 0;
    for v in ti {
        if tj.contains(&v) {
            shared[count] = v;
            count += 1;
        }
    }
    let shared = &shared[..count];
    let p = &position;
    let other = |t: [u32; 3]| {
        let mut out = [0u32; 3];
        let mut n = 0;
        for v in t {
            if !shared.contains(&v) {
                out[n] = v;
                n += 1;
            }
        }
        out
    };
    if filtered && count < 3 {
        // The float filter settles most pairs without an exact predicate: the plane of one
        // strictly separating the other's unshared corners leaves only shared points in common
        // (and, sharing an edge, rules out the coplanar fold).
        let unshared = |t: [u32; 3]| other(t)[..3 - count].iter().map(|&v| p(v)).collect::<ArrayPoints>();
        if strictly_one_side(&ti.map(p), &unshared(tj)) || strictly_one_side(&tj.map(p), &unshared(ti)) {
            return false;
        }
        // Coplanar pairs (flat parts of CAD models) defeat the plane filter and make the exact
        // orientation tests prove a zero, their slowest case: a separating edge line in the
        // projection along the plane's dominant axis settles most of them.
        let axis = dominant_axis(&ti.map(p));
        if separated_in_projection(ti, tj, p, axis) || separated_in_projection(tj, ti, p, axis) {
            return false;
        }
    }
    match count {
        0 => triangles_meet(&ti.map(p), &tj.map(p)),
        1 => {
            let (a, b) = (other(ti), other(tj));
            meet_beyond_shared_vertex(p(shared[0]), p(a[0]), p(a[1]), p(b[0]), p(b[1]))
        }
        2 => {
            let (u, v) = (p(shared[0]), p(shared[1]));
            let (x, y) = (p(other(ti)[0]), p(other(tj)[0]));
            if o3(u, v, x, y) != 0 {
                return false;
            }
            let axis = dominant_axis(&[u, v, x]);
            o2(u, v, x, axis) * o2(u, v, y, axis) > 0
        }
        _ => true, // the same triangle twice
    }
}

/// Whether a triangle has no area, exactly (its corners' cross product in `f64`, where the
/// products of `f32` differences are exact enough to be zero only for collinear corners). The
/// self-intersection metric skips such triangles, and the safe edge collapse follows it.
pub fn has_zero_area(p: [Vec3; 3]) -> bool {
    (p[1] - p[0]).as_dvec3().cross((p[2] - p[0]).as_dvec3()).length_squared() == 0.0
}

/// Up to three points, without allocation.
#[derive(Default)]
struct ArrayPoints {
    points: [Vec3; 3],
    len: usize,
}

impl FromIterator<Vec3> for ArrayPoints {
    fn from_iter<I: IntoIterator<Item = Vec3>>(iter: I) -> Self {
        let mut out = ArrayPoints::default();
        for q in iter.into_iter().take(3) {
            out.points[out.len] = q;
            out.len += 1;
        }
        out
    }
}

/// Relative margin of [`PlaneFilter`]: far above the error of its `f64` arithmetic on `f32`
/// inputs (a few units of 1.1e-16), so a side it reports is the exact side.
const FILTER_MARGIN: f64 = 1e-10;

/// A float filter ahead of the exact predicates: the plane of a triangle, telling which side of it
/// a point lies on when the point is farther from it than `FILTER_MARGIN` of the largest value
/// the orientation determinant could take (so the exact sign is the one reported), and "not
/// settled" otherwise. A zero-area triangle settles nothing.
#[derive(Clone, Copy, Debug)]
pub struct PlaneFilter {
    origin: glam::DVec3,
    normal: glam::DVec3,
    scale: f64,
}

impl PlaneFilter {
    /// The filter of triangle `t`'s plane.
    pub fn of(t: &[Vec3; 3]) -> Self {
        let origin = t[0].as_dvec3();
        let (e1, e2) = (t[1].as_dvec3() - origin, t[2].as_dvec3() - origin);
        // |n . d| <= |e1| |e2| |d|: compared squared, with no square root.
        let scale = FILTER_MARGIN * FILTER_MARGIN * e1.length_squared() * e2.length_squared();
        PlaneFilter { origin, normal: e1.cross(e2), scale }
    }

    /// `1` or `-1`: the side `q` is on, as `o3` of the triangle's corners and `q` would say;
    /// `0`: not settled (near the plane, on it, or a zero-area triangle).
    pub fn side(&self, q: Vec3) -> i8 {
        let d = q.as_dvec3() - self.origin;
        let s = self.normal.dot(d);
        if s * s <= self.scale * d.length_squared() {
            0
        } else if s > 0.0 {
            1
        } else {
            -1
        }
    }
}

/// Whether every point of `others` lies strictly on one side of the plane of `t` (settled by
/// [`PlaneFilter`]); `false` means "not settled", never "they meet".
fn strictly_one_side(t: &[Vec3; 3], others: &ArrayPoints) -> bool {
    let plane = PlaneFilter::of(t);
    strictly_one_sign(others.points[..others.len].iter().map(|&q| plane.side(q)))
}

/// The side of `x` against the line `p -> q` in the plane with `axis` dropped (as [`o2`]), when a
/// float evaluation settles it with the margin of [`PlaneFilter`]; `0` when it does not.
fn side_2d(p: Vec3, q: Vec3, x: Vec3, axis: usize) -> i8 {
    let (a, b, c) = (c2(p, axis), c2(q, axis), c2(x, axis));
    let (ux, uy, vx, vy) = (b.x - a.x, b.y - a.y, c.x - a.x, c.y - a.y);
    let det = ux * vy - uy * vx;
    let margin = FILTER_MARGIN * FILTER_MARGIN * (ux * ux + uy * uy) * (vx * vx + vy * vy);
    if det * det <= margin {
        0
    } else if det > 0.0 {
        1
    } else {
        -1
    }
}

/// A float filter for indexed triangles: whether the line of some edge of `tx`, projected along
/// `axis`, has `tx`'s third corner strictly on one side and every corner of `ty` not on that edge
/// strictly on the other. Then the projections meet only at shared vertices, and so do the
/// triangles. `false` means "not settled".
fn separated_in_projection(tx: [u32; 3], ty: [u32; 3], position: impl Fn(u32) -> Vec3, axis: usize) -> bool {
    (0..3).any(|k| {
        let (i, j, r) = (tx[k], tx[(k + 1) % 3], tx[(k + 2) % 3]);
        let (p, q) = (position(i), position(j));
        let own = side_2d(p, q, position(r), axis);
        own != 0 && ty.iter().filter(|&&v| v != i && v != j).all(|&v| side_2d(p, q, position(v), axis) == -own)
    })
}

/// Whether the sides are all `1` or all `-1` (and there is at least one).
pub fn strictly_one_sign(sides: impl IntoIterator<Item = i8>) -> bool {
    let mut seen = 0u8;
    for s in sides {
        seen |= match s {
            1 => 1,
            -1 => 2,
            _ => return false,
        };
    }
    seen == 1 || seen == 2
}

/// Whether `p` lies in the closed tetrahedron `t` (any orientation).
pub fn point_in_tetrahedron(p: Vec3, t: &[Vec3; 4]) -> bool {
    let [a, b, c, d] = *t;
    let s = [o3(b, c, d, p), o3(a, d, c, p), o3(a, b, d, p), o3(a, c, b, p)];
    // Each face sees `p` on the same side as the opposite corner, which is -orient(abcd).
    let w = o3(a, b, c, d);
    w != 0 && s.iter().all(|&x| x == 0 || x == -w)
}

/// Whether the closed triangle `tri` and the closed tetrahedron `tet` share a point.
pub fn triangle_meets_tetrahedron(tri: &[Vec3; 3], tet: &[Vec3; 4]) -> bool {
    const EDGES: [(usize, usize); 6] = [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)];
    const FACES: [[usize; 3]; 4] = [[1, 2, 3], [0, 2, 3], [0, 1, 3], [0, 1, 2]];
    tri.iter().any(|&p| point_in_tetrahedron(p, tet))
        || EDGES.iter().any(|&(i, j)| segment_meets_triangle(tet[i], tet[j], tri))
        || FACES.iter().any(|f| {
            let face = f.map(|k| tet[k]);
            (0..3).any(|k| segment_meets_triangle(tri[k], tri[(k + 1) % 3], &face))
        })
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand_xoshiro::rand_core::{Rng, SeedableRng};

    /// The float filters never change an answer: random triangle pairs sharing 0, 1 or 2
    /// vertices, on a small integer lattice so that coplanar, collinear and touching cases (the
    /// ones near the filters' margins) are common, some lifted off the plane by a tiny amount.
    #[test]
    fn the_float_filters_agree_with_the_exact_tests() {
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(20261128);
        let coordinate = |rng: &mut rand_xoshiro::Xoshiro256PlusPlus| (rng.next_u32() % 5) as f32 - 2.0;
        let (mut settled, mut met) = (0, 0);
        for case in 0..200_000u32 {
            let flat = case % 2 == 0;
            let points: Vec<Vec3> = (0..6)
                .map(|_| {
                    let z = if flat { 0.0 } else { coordinate(&mut rng) };
                    let lift = if case % 7 == 0 { (rng.next_u32() % 3) as f32 * 1e-6 } else { 0.0 };
                    Vec3::new(coordinate(&mut rng), coordinate(&mut rng), z + lift)
                })
                .collect();
            let shared = (rng.next_u32() % 3) as usize;
            let ti = [0u32, 1, 2];
            let mut tj = [3u32, 4, 5];
            tj[..shared].copy_from_slice(&ti[..shared]);
            tj.rotate_left((rng.next_u32() % 3) as usize);
            let p = |v: u32| points[v as usize];
            let area = |t: [u32; 3]| (p(t[1]) - p(t[0])).cross(p(t[2]) - p(t[0])).length_squared();
            if area(ti) == 0.0 || area(tj) == 0.0 {
                continue;
            }
            let exact = indexed_intersect(ti, tj, p, false);
            assert_eq!(indexed_intersect(ti, tj, p, true), exact, "case {case}: {ti:?} {tj:?} at {points:?}");
            met += exact as u32;
            let plane = PlaneFilter::of(&ti.map(p));
            for &v in &tj {
                let side = plane.side(p(v));
                if side != 0 {
                    settled += 1;
                    assert_eq!(side, -o3(p(0), p(1), p(2), p(v)), "case {case}");
                }
            }
        }
        // Both answers and both kinds of filter outcome were exercised.
        assert!(met > 1000 && settled > 1000, "met {met}, settled {settled}");
    }

    #[test]
    fn points_and_triangles_against_a_tetrahedron() {
        let tet = [Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z];
        let mut flipped = tet;
        flipped.swap(0, 1);
        for t in [tet, flipped] {
            assert!(point_in_tetrahedron(Vec3::splat(0.1), &t));
            assert!(point_in_tetrahedron(Vec3::ZERO, &t), "closed: corners count");
            assert!(!point_in_tetrahedron(Vec3::splat(0.4), &t));
            // A triangle piercing two faces with no vertex inside and no tet edge through it.
            let finger = [Vec3::new(0.2, 0.2, -1.0), Vec3::new(0.25, 0.2, 2.0), Vec3::new(0.2, 0.25, 2.0)];
            assert!(triangle_meets_tetrahedron(&finger, &t));
            let away = [Vec3::new(2.0, 2.0, 2.0), Vec3::new(3.0, 2.0, 2.0), Vec3::new(2.0, 3.0, 2.0)];
            assert!(!triangle_meets_tetrahedron(&away, &t));
        }
    }
}
