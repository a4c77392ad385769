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
