//! Small geometric helpers shared by fields, lattices and extractors.

use glam::{DVec3, Vec3};

/// Polygons of at most this many corners are filled in every triangulation (429 for nine) by
/// the crate's polygon fillings (`all_triangulations`); longer ones as fans from each corner.
pub const ALL_TRIANGULATIONS_UP_TO: usize = 9;

/// An axis-aligned bounding box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    /// Smallest corner.
    pub min: Vec3,
    /// Largest corner.
    pub max: Vec3,
}

impl Aabb {
    /// A box from its two corners.
    pub const fn new(min: Vec3, max: Vec3) -> Self {
        Self { min, max }
    }

    /// The cube `[-h, h]^3`.
    pub fn cube(h: f32) -> Self {
        Self::new(Vec3::splat(-h), Vec3::splat(h))
    }

    /// The empty box (grows to fit the first point added).
    pub fn empty() -> Self {
        Self::new(Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY))
    }

    /// Grows the box to contain `p`.
    pub fn grow(&mut self, p: Vec3) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }

    /// The smallest box containing both.
    pub fn union(&self, other: &Aabb) -> Aabb {
        Aabb::new(self.min.min(other.min), self.max.max(other.max))
    }

    /// Side lengths.
    pub fn extent(&self) -> Vec3 {
        self.max - self.min
    }

    /// Centre point.
    pub fn centre(&self) -> Vec3 {
        (self.min + self.max) * 0.5
    }

    /// Longest side length.
    pub fn longest_side(&self) -> f32 {
        self.extent().max_element()
    }

    /// The box grown by `margin` on every side.
    pub fn expanded(&self, margin: f32) -> Aabb {
        Aabb::new(self.min - Vec3::splat(margin), self.max + Vec3::splat(margin))
    }

    /// Squared distance from `p` to the box (0 inside).
    pub fn distance_squared(&self, p: Vec3) -> f32 {
        let d = (self.min - p).max(p - self.max).max(Vec3::ZERO);
        d.length_squared()
    }

    /// Whether `p` lies in the closed box.
    pub fn contains(&self, p: Vec3) -> bool {
        p.cmpge(self.min).all() && p.cmple(self.max).all()
    }
}

/// Smallest distance of a vertex from the ends of its lattice edge, as a fraction of the edge:
/// far enough that `f32` positions stay distinct up to grids of about 10^4 samples per side. A
/// sample exactly at the iso-value would otherwise put the vertices of all its edges at one
/// point: distinct vertices there touch (self-intersections, as CGAL counts them) and make
/// zero-area triangles. The gyroid is exactly zero on whole planes of grid points.
pub const MIN_EDGE_FRACTION: f32 = 1e-4;

/// Where the iso-value crosses the edge from a sample valued `from` to one valued `to` (which
/// differ in sign about `iso`), as a fraction of the edge from `from`, kept
/// [`MIN_EDGE_FRACTION`] away from both ends.
pub fn edge_crossing_fraction(from: f32, to: f32, iso: f32) -> f32 {
    ((iso - from) / (to - from)).clamp(MIN_EDGE_FRACTION, 1.0 - MIN_EDGE_FRACTION)
}

/// The closest point to `p` on triangle `(a, b, c)` (Ericson, Real-Time Collision Detection, 5.1.5).
pub fn closest_point_on_triangle(p: Vec3, a: Vec3, b: Vec3, c: Vec3) -> Vec3 {
    let ab = b - a;
    let ac = c - a;
    let ap = p - a;
    let d1 = ab.dot(ap);
    let d2 = ac.dot(ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = p - b;
    let d3 = ab.dot(bp);
    let d4 = ac.dot(bp);
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return a + ab * v;
    }
    let cp = p - c;
    let d5 = ab.dot(cp);
    let d6 = ac.dot(cp);
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return a + ac * w;
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return b + (c - b) * w;
    }
    let denom = 1.0 / (va + vb + vc);
    let v = vb * denom;
    let w = vc * denom;
    a + ab * v + ac * w
}

/// Signed solid angle of triangle `(a, b, c)` seen from `p` (Van Oosterom & Strackee 1983),
/// positive when `p` is behind the counter-clockwise face. Summed over a closed outward mesh and
/// divided by 4π it is the winding number: 1 inside, 0 outside.
pub fn solid_angle(p: Vec3, a: Vec3, b: Vec3, c: Vec3) -> f64 {
    let a = (a - p).as_dvec3();
    let b = (b - p).as_dvec3();
    let c = (c - p).as_dvec3();
    let (la, lb, lc) = (a.length(), b.length(), c.length());
    let det = a.dot(b.cross(c));
    let den = la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb;
    2.0 * det.atan2(den)
}

/// `values` at the indices `idx` (a cell's or a tetrahedron's corner samples). Written as a loop
/// the compiler unrolls in place: `idx.map(|k| values[k])` compiled to an out-of-line call whose
/// result was read back wider than it was written, a store-forwarding stall that cost a third of
/// surface nets' normal pass on a terrain chunk.
#[inline(always)]
pub fn gather<const N: usize>(values: &[f32], idx: &[usize; N]) -> [f32; N] {
    let mut out = [0.0; N];
    for k in 0..N {
        out[k] = values[idx[k]];
    }
    out
}

/// Normalises `normals` in place (zero stays zero). Extractors store raw gradients in their
/// branchy cell loops and normalise them here, in a tight loop where the square roots and
/// divisions of successive vertices overlap: the same values as normalising each as it is made.
pub fn normalize_all(normals: &mut [Vec3]) {
    for n in normals {
        *n = n.normalize_or_zero();
    }
}

/// Gradient of the trilinear interpolant of a cell's corner values `c` (table corner order) at
/// local coordinates `q` in `[0, 1]^3`.
pub fn trilinear_gradient(c: &[f32; 8], q: Vec3) -> Vec3 {
    let (u, v, w) = (q.x, q.y, q.z);
    let (iu, iv, iw) = (1.0 - u, 1.0 - v, 1.0 - w);
    Vec3::new(
        iv * iw * (c[1] - c[0]) + v * iw * (c[2] - c[3]) + iv * w * (c[5] - c[4]) + v * w * (c[6] - c[7]),
        iu * iw * (c[3] - c[0]) + u * iw * (c[2] - c[1]) + iu * w * (c[7] - c[4]) + u * w * (c[6] - c[5]),
        iu * iv * (c[4] - c[0]) + u * iv * (c[5] - c[1]) + iu * v * (c[7] - c[3]) + u * v * (c[6] - c[2]),
    )
}

/// The six dihedral angles of a tetrahedron, degrees, in edge order 01, 02, 03, 12, 13, 23.
pub fn dihedral_angles(p: [Vec3; 4]) -> [f64; 6] {
    let p = p.map(|v| v.as_dvec3());
    const EDGES: [(usize, usize, usize, usize); 6] =
        [(0, 1, 2, 3), (0, 2, 1, 3), (0, 3, 1, 2), (1, 2, 0, 3), (1, 3, 0, 2), (2, 3, 0, 1)];
    EDGES.map(|(i, j, k, l)| {
        let e = (p[j] - p[i]).normalize_or_zero();
        let project = |v: DVec3| v - e * v.dot(e);
        let (u, w) = (project(p[k] - p[i]), project(p[l] - p[i]));
        let c = u.dot(w) / (u.length() * w.length());
        if c.is_finite() {
            c.clamp(-1.0, 1.0).acos().to_degrees()
        } else {
            0.0
        }
    })
}

/// Circumcentre of a tetrahedron (`None` when it is flat).
pub fn circumcentre(p: [DVec3; 4]) -> Option<DVec3> {
    let (u, v, w) = (p[1] - p[0], p[2] - p[0], p[3] - p[0]);
    let det = u.dot(v.cross(w));
    let c = (u.length_squared() * v.cross(w) + v.length_squared() * w.cross(u) + w.length_squared() * u.cross(v)) / (2.0 * det);
    (det != 0.0 && c.is_finite()).then(|| p[0] + c)
}

/// Every triangulation of a polygon (its corners in winding order, each triangle wound as the
/// polygon) up to
/// [`ALL_TRIANGULATIONS_UP_TO`] corners; fans from each corner beyond.
pub(crate) fn all_triangulations(ring: &[u32]) -> Vec<Vec<[u32; 3]>> {
    let n = ring.len();
    if n > ALL_TRIANGULATIONS_UP_TO {
        return (0..n)
            .map(|k| {
                let r: Vec<u32> = (0..n).map(|i| ring[(k + i) % n]).collect();
                (1..n - 1).map(|i| [r[0], r[i], r[i + 1]]).collect()
            })
            .collect();
    }
    fn between(ring: &[u32], i: usize, j: usize) -> Vec<Vec<[u32; 3]>> {
        if j - i < 2 {
            return vec![Vec::new()];
        }
        let mut out = Vec::new();
        for k in i + 1..j {
            for left in between(ring, i, k) {
                for right in between(ring, k, j) {
                    let mut t = vec![[ring[i], ring[k], ring[j]]];
                    t.extend(left.iter().copied());
                    t.extend(right.iter().copied());
                    out.push(t);
                }
            }
        }
        out
    }
    between(ring, 0, n - 1)
}

#[cfg(test)]
mod tests {
    #[test]
    fn every_triangulation_of_a_hexagon_is_listed_once() {
        let ring = [0, 1, 2, 3, 4, 5];
        let all = all_triangulations(&ring);
        assert_eq!(all.len(), 14, "Catalan(4)");
        let distinct: std::collections::HashSet<Vec<[u32; 3]>> = all
            .iter()
            .map(|t| {
                let mut k: Vec<[u32; 3]> = t
                    .iter()
                    .map(|&t| {
                        let mut k = t;
                        k.sort_unstable();
                        k
                    })
                    .collect();
                k.sort_unstable();
                k
            })
            .collect();
        assert_eq!(distinct.len(), 14);
        // Each winds as the loop: every loop edge appears in its forward direction.
        for t in &all {
            assert_eq!(t.len(), 4);
            let directed: std::collections::HashSet<(u32, u32)> =
                t.iter().flat_map(|&[a, b, c]| [(a, b), (b, c), (c, a)]).collect();
            assert!((0..6).all(|i| directed.contains(&(ring[i], ring[(i + 1) % 6]))), "{t:?}");
        }
    }

    use super::*;

    #[test]
    fn closest_point_regions() {
        let (a, b, c) = (Vec3::ZERO, Vec3::X, Vec3::Y);
        assert_eq!(closest_point_on_triangle(Vec3::new(-1.0, -1.0, 0.0), a, b, c), a);
        assert!(closest_point_on_triangle(Vec3::new(0.2, 0.2, 1.0), a, b, c).abs_diff_eq(Vec3::new(0.2, 0.2, 0.0), 1e-6));
        let p = closest_point_on_triangle(Vec3::new(1.0, 1.0, 0.0), a, b, c);
        assert!((p - Vec3::new(0.5, 0.5, 0.0)).length() < 1e-6);
    }

    #[test]
    fn winding_number_of_a_tetrahedron() {
        let v = [Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z];
        // Outward counter-clockwise faces.
        let faces = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];
        let w = |p: Vec3| -> f64 {
            faces.iter().map(|f| solid_angle(p, v[f[0]], v[f[1]], v[f[2]])).sum::<f64>() / (4.0 * std::f64::consts::PI)
        };
        assert!((w(Vec3::splat(0.1)) - 1.0).abs() < 1e-9);
        assert!(w(Vec3::splat(2.0)).abs() < 1e-9);
    }
}
