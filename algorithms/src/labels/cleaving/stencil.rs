//! One lattice tetrahedron cleaved into the tetrahedra of its labels: a pure function of the
//! tetrahedron's four corners (key, position, label) and its edges' cut parameters.
//!
//! The pieces are the dual cells of the corners in the tetrahedron's barycentric subdivision,
//! moved onto the cut points: each face is split by the segments where its labels meet (one
//! between its two cut points when it has two labels, three from its face point to its cut points
//! when it has three), each piece of a face takes its corner's label, and the tetrahedron is the
//! cone from one apex (the mean of its cut and face points) over its faces' pieces. A face's split
//! reads only the face (its corners in key order, its cut points), so the two tetrahedra that share
//! a face split it alike, and the cone tetrahedra conform across it.

use glam::DVec3;

/// A corner of a lattice tetrahedron: its point key, position and label.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Corner {
    /// The vertex's weld key.
    pub key: u128,
    /// Its position.
    pub at: DVec3,
    /// Its label.
    pub label: u32,
}

/// A point of the output before it has an index: its weld key and position.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Point {
    /// Names the point alike in every tetrahedron (and block) that makes it.
    pub key: u128,
    /// Where it is.
    pub at: DVec3,
}

/// The keys of the points a tetrahedron may make beyond its corners.
#[derive(Clone, Copy, Debug, Default)]
pub struct Keys {
    /// The cut point of each edge of [`EDGES`].
    pub edges: [u128; 6],
    /// The face point of the face opposite each corner.
    pub faces: [u128; 4],
    /// The apex.
    pub apex: u128,
}

/// Where a tetrahedron's pieces go.
pub trait Sink {
    /// A tetrahedron of label `label`, positively oriented.
    fn tetrahedron(&mut self, points: [Point; 4], label: u32);
    /// An interface triangle between `pair[0]` and `pair[1]` (`pair[0] > pair[1]`), its normal
    /// pointing from `pair[0]` into `pair[1]`.
    fn triangle(&mut self, points: [Point; 3], pair: [u32; 2]);
}

/// The six edges of a tetrahedron as corner slots, the cut parameter of each measured from its
/// first slot.
pub const EDGES: [(usize, usize); 6] = [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)];

/// The edge of [`EDGES`] between slots `i` and `j`.
fn edge_of(i: usize, j: usize) -> usize {
    let (i, j) = (i.min(j), i.max(j));
    EDGES.iter().position(|&e| e == (i, j)).unwrap_or(0)
}

/// Six times the signed volume of `a b c d`.
fn volume6(a: DVec3, b: DVec3, c: DVec3, d: DVec3) -> f64 {
    (b - a).dot((c - a).cross(d - a))
}

/// The smallest angle of a triangle, as its cosine's complement (larger is better): the largest
/// cosine among its three angles, negated.
fn smallest_angle_score(p: [DVec3; 3]) -> f64 {
    (0..3)
        .map(|k| {
            let (u, v) = (p[(k + 1) % 3] - p[k], p[(k + 2) % 3] - p[k]);
            let c = u.dot(v) / (u.length() * v.length());
            if c.is_finite() {
                -c
            } else {
                -1.0
            }
        })
        .fold(f64::INFINITY, f64::min)
}

/// Slots of a tetrahedron's point table: its corners `0..4`, the cut point of edge `e` at
/// `CUT + e`, the face point of the face opposite corner `k` at `FACE + k`, the apex at `APEX`
/// and the two sides' apexes of a two-label tetrahedron at `SIDE + side`.
const CUT: u8 = 4;
const FACE: u8 = 10;
const APEX: u8 = 14;
const SIDE: u8 = 15;

/// A face's pieces (triangles as point slots, with the corner whose label they take) and the
/// segments where two labels meet (with the corner whose piece lies on each side).
#[derive(Clone, Copy, Default)]
struct FacePieces {
    triangles: [([u8; 3], u8); 6],
    n_triangles: usize,
    segments: [([u8; 2], u8, u8); 3],
    n_segments: usize,
}

impl FacePieces {
    fn triangle(&mut self, t: [u8; 3], slot: u8) {
        self.triangles[self.n_triangles] = (t, slot);
        self.n_triangles += 1;
    }
    fn segment(&mut self, s: [u8; 2], near: u8, far: u8) {
        self.segments[self.n_segments] = (s, near, far);
        self.n_segments += 1;
    }
    fn triangles(&self) -> &[([u8; 3], u8)] {
        &self.triangles[..self.n_triangles]
    }
}

impl Default for Point {
    fn default() -> Self {
        Self { key: 0, at: DVec3::ZERO }
    }
}

/// The slot of the cut point on the edge between corners `i` and `j`.
fn cut_slot(i: u8, j: u8) -> u8 {
    CUT + edge_of(usize::from(i), usize::from(j)) as u8
}

/// Cleaves one lattice tetrahedron (corners in any order; `t[e]` the cut parameter of edge
/// `EDGES[e]` from its first slot, read only where its corners' labels differ, clamped to
/// `[alpha, 1 - alpha]`) into `sink`. Label `0` (the background) gets no tetrahedra; its
/// interfaces with other labels are made.
pub fn cleave(corners: &[Corner; 4], t: &[f64; 6], alpha: f64, keys: &Keys, sink: &mut impl Sink) {
    let l = corners.map(|c| c.label);
    let mut pts = [Point::default(); 17];
    for (i, c) in corners.iter().enumerate() {
        pts[i] = Point { key: c.key, at: c.at };
    }
    if l.iter().all(|&x| x == l[0]) {
        if l[0] != 0 {
            let mut p = [pts[0], pts[1], pts[2], pts[3]];
            if volume6(p[0].at, p[1].at, p[2].at, p[3].at) < 0.0 {
                p.swap(2, 3);
            }
            sink.tetrahedron(p, l[0]);
        }
        return;
    }
    let (mut apex_sum, mut apex_n) = (DVec3::ZERO, 0.0);
    for (e, &(i, j)) in EDGES.iter().enumerate() {
        if l[i] != l[j] {
            let s = t[e].clamp(alpha, 1.0 - alpha);
            let at = corners[i].at * (1.0 - s) + corners[j].at * s;
            pts[usize::from(CUT) + e] = Point { key: keys.edges[e], at };
            apex_sum += at;
            apex_n += 1.0;
        }
    }
    let lab = |i: u8| l[usize::from(i)];
    let mut faces = [FacePieces::default(); 4];
    for (k, pieces) in faces.iter_mut().enumerate() {
        let mut s: [u8; 3] = [[1, 2, 3], [0, 2, 3], [0, 1, 3], [0, 1, 2]][k];
        s.sort_unstable_by_key(|&i| corners[usize::from(i)].key);
        let [a, b, c] = s;
        if lab(a) == lab(b) && lab(b) == lab(c) {
            pieces.triangle([a, b, c], a);
        } else if lab(a) != lab(b) && lab(b) != lab(c) && lab(a) != lab(c) {
            let f = FACE + k as u8;
            let at =
                (pts[usize::from(cut_slot(a, b))].at + pts[usize::from(cut_slot(b, c))].at + pts[usize::from(cut_slot(a, c))].at)
                    / 3.0;
            pts[usize::from(f)] = Point { key: keys.faces[k], at };
            apex_sum += at;
            apex_n += 1.0;
            for (x, y) in [(a, b), (b, c), (a, c)] {
                let e = cut_slot(x, y);
                pieces.triangle([x, e, f], x);
                pieces.triangle([y, e, f], y);
                pieces.segment([f, e], x, y);
            }
        } else {
            // Two labels: the lone corner's triangle and the quadrilateral of the other two, split
            // by the diagonal whose triangles' smallest angle is larger.
            let (lone, p, q) = if lab(b) == lab(c) {
                (a, b, c)
            } else if lab(a) == lab(c) {
                (b, a, c)
            } else {
                (c, a, b)
            };
            let (ep, eq) = (cut_slot(lone, p), cut_slot(lone, q));
            pieces.triangle([lone, ep, eq], lone);
            pieces.segment([ep, eq], lone, p);
            let through_p = [[p, q, eq], [p, eq, ep]];
            let through_q = [[p, q, ep], [q, eq, ep]];
            let score = |tris: &[[u8; 3]; 2]| {
                tris.iter().map(|t| smallest_angle_score(t.map(|x| pts[usize::from(x)].at))).fold(f64::INFINITY, f64::min)
            };
            let chosen = if score(&through_q) > score(&through_p) { through_q } else { through_p };
            pieces.triangle(chosen[0], p);
            pieces.triangle(chosen[1], p);
        }
    }
    let distinct = {
        let mut d = l;
        d.sort_unstable();
        1 + d.windows(2).filter(|w| w[0] != w[1]).count()
    };
    if distinct == 2 && two_labels(&l, &mut pts, &faces, keys, sink) {
        return;
    }
    pts[usize::from(APEX)] = Point { key: keys.apex, at: apex_sum / apex_n };
    cone(&l, &pts, &faces, sink);
}

/// A tetrahedron of three or four labels (or two, where [`two_labels`] cannot): the cone from
/// the apex over every face piece, the interfaces the cone over the faces' segments.
fn cone(l: &[u32; 4], pts: &[Point; 17], faces: &[FacePieces; 4], sink: &mut impl Sink) {
    let apex = pts[usize::from(APEX)];
    let at = |i: u8| pts[usize::from(i)];
    for pieces in faces {
        for &(tri, slot) in pieces.triangles() {
            if l[usize::from(slot)] == 0 {
                continue;
            }
            let mut p = [apex, at(tri[0]), at(tri[1]), at(tri[2])];
            if volume6(p[0].at, p[1].at, p[2].at, p[3].at) < 0.0 {
                p.swap(2, 3);
            }
            sink.tetrahedron(p, l[usize::from(slot)]);
        }
        for &(seg, near, far) in &pieces.segments[..pieces.n_segments] {
            let (ln, lf) = (l[usize::from(near)], l[usize::from(far)]);
            let mut tri = [apex, at(seg[0]), at(seg[1])];
            // `near`'s corner lies on its own side of the triangle (it is a corner of the cone
            // tetrahedron on that side).
            let near_side = volume6(tri[0].at, tri[1].at, tri[2].at, at(near).at);
            // The normal points away from the larger label: the larger one's corner is behind.
            if (near_side > 0.0) == (ln > lf) {
                tri.swap(1, 2);
            }
            sink.triangle(tri, [ln.max(lf), ln.min(lf)]);
        }
    }
}

/// The outward-wound face piece `tri`: wound away from the corner opposite the face.
fn outward(pts: &[Point; 17], tri: [u8; 3], opposite: DVec3) -> [u8; 3] {
    let [a, b, c] = tri.map(|i| pts[usize::from(i)].at);
    if volume6(a, b, c, opposite) > 0.0 {
        [tri[0], tri[2], tri[1]]
    } else {
        tri
    }
}

/// A tetrahedron of two labels: the interface is the polygon of its cut points (a triangle, or a
/// quadrilateral split by the diagonal whose triangles' smallest angle is larger), and each
/// label's side is one tetrahedron when it has four points, or else the cone from the best of
/// its candidate apexes (the mean of its points, each of its corners) over its boundary. Returns
/// `false`, emitting nothing, when every candidate of a side would invert a tetrahedron (the
/// caller then cones the whole tetrahedron from one apex).
fn two_labels(l: &[u32; 4], pts: &mut [Point; 17], faces: &[FacePieces; 4], keys: &Keys, sink: &mut impl Sink) -> bool {
    let low = l.iter().copied().min().unwrap_or(0);
    let high = l.iter().copied().max().unwrap_or(0);
    let side_of = |slot: u8| usize::from(l[usize::from(slot)] == high);
    let mut lows = [0u8; 3];
    let mut highs = [0u8; 3];
    let (mut nl, mut nh) = (0, 0);
    for i in 0..4u8 {
        if l[usize::from(i)] == low {
            lows[nl] = i;
            nl += 1;
        } else {
            highs[nh] = i;
            nh += 1;
        }
    }
    let at = |pts: &[Point; 17], i: u8| pts[usize::from(i)].at;
    let mut interface = [[0u8; 3]; 2];
    let n_interface = if nl == 1 || nh == 1 {
        let (lone, rest) = if nl == 1 { (lows[0], highs) } else { (highs[0], lows) };
        interface[0] = [cut_slot(lone, rest[0]), cut_slot(lone, rest[1]), cut_slot(lone, rest[2])];
        1
    } else {
        let (a, c) = (lows[0], lows[1]);
        let (b, d) = (highs[0], highs[1]);
        let quad = [cut_slot(a, b), cut_slot(a, d), cut_slot(c, d), cut_slot(c, b)];
        let split = |k: usize| [[quad[k], quad[(k + 1) % 4], quad[(k + 2) % 4]], [quad[k], quad[(k + 2) % 4], quad[(k + 3) % 4]]];
        let score =
            |tris: &[[u8; 3]; 2]| tris.iter().map(|t| smallest_angle_score(t.map(|x| at(pts, x)))).fold(f64::INFINITY, f64::min);
        // Split alike whatever the corners' order: ties go to the split at the smallest key.
        let first = (0..4).min_by_key(|&k| pts[usize::from(quad[k])].key).unwrap_or(0);
        let (s0, s1) = (split(first), split((first + 1) % 4));
        interface = if score(&s1) > score(&s0) { s1 } else { s0 };
        2
    };
    let low_corner = at(pts, lows[0]);
    for tri in &mut interface[..n_interface] {
        // Normal from the high side into the low: the low corner in front of it.
        let [a, b, c] = tri.map(|i| at(pts, i));
        if volume6(a, b, c, low_corner) < 0.0 {
            tri.swap(1, 2);
        }
    }
    // Each side's boundary, wound outward from it, and the points it uses (a mask of slots).
    let mut bounds = [[[0u8; 3]; 16]; 2];
    let mut n_bounds = [0usize; 2];
    let mut used = [0u32; 2];
    let mut push = |side: usize, tri: [u8; 3]| {
        bounds[side][n_bounds[side]] = tri;
        n_bounds[side] += 1;
        for i in tri {
            used[side] |= 1 << i;
        }
    };
    for (k, pieces) in faces.iter().enumerate() {
        for &(tri, slot) in pieces.triangles() {
            push(side_of(slot), outward(pts, tri, at(pts, k as u8)));
        }
    }
    for tri in &interface[..n_interface] {
        push(0, [tri[0], tri[2], tri[1]]);
        push(1, *tri);
    }
    let mut out = [[[0u8; 4]; 16]; 2];
    let mut n_out = [0usize; 2];
    for side in 0..2 {
        let bounds = &bounds[side][..n_bounds[side]];
        if used[side].count_ones() == 4 {
            let mut p = [0u8; 4];
            let mut n = 0;
            for i in 0..17u8 {
                if used[side] & 1 << i != 0 {
                    p[n] = i;
                    n += 1;
                }
            }
            if volume6(at(pts, p[0]), at(pts, p[1]), at(pts, p[2]), at(pts, p[3])) < 0.0 {
                p.swap(2, 3);
            }
            out[side][0] = p;
            n_out[side] = 1;
            continue;
        }
        let centre = (0..17u8).filter(|&i| used[side] & 1 << i != 0).map(|i| at(pts, i)).sum::<DVec3>()
            / f64::from(used[side].count_ones());
        let mid = SIDE + side as u8;
        pts[usize::from(mid)] = Point { key: keys.apex | (side as u128) << 23, at: centre };
        // Candidate apexes: the mean, and each corner of the side; the one whose worst
        // tetrahedron is best.
        let mut best = 1e-9;
        let corners_of_side = (0..4u8).filter(|&i| side_of(i) == side);
        for apex in std::iter::once(mid).chain(corners_of_side) {
            let mut tets = [[0u8; 4]; 16];
            let mut n = 0;
            let mut worst = f64::INFINITY;
            for tri in bounds {
                if tri.contains(&apex) {
                    continue;
                }
                // Outward triangles seen from inside: the apex behind each.
                let p = [apex, tri[0], tri[2], tri[1]];
                let q = p.map(|i| at(pts, i));
                if volume6(q[0], q[1], q[2], q[3]) <= 0.0 {
                    worst = f64::NEG_INFINITY;
                    break;
                }
                worst = worst.min(shape(q));
                tets[n] = p;
                n += 1;
            }
            if worst > best {
                best = worst;
                out[side] = tets;
                n_out[side] = n;
            }
        }
        if n_out[side] == 0 {
            return false;
        }
    }
    for side in 0..2 {
        let label = if side == 1 { high } else { low };
        if label != 0 {
            for t in &out[side][..n_out[side]] {
                sink.tetrahedron(t.map(|i| pts[usize::from(i)]), label);
            }
        }
    }
    for tri in &interface[..n_interface] {
        sink.triangle(tri.map(|i| pts[usize::from(i)]), [high, low]);
    }
    true
}

/// A tetrahedron's shape as the smallest sine of its six dihedral angles (so its worst angle's
/// distance from flat, 0° or 180°): `sin θ = 3 V |e| / (2 A₁ A₂)` at edge `e` between faces of
/// areas `A₁` and `A₂`.
pub(crate) fn shape(p: [DVec3; 4]) -> f64 {
    const PAIRS: [(usize, usize, usize, usize); 6] =
        [(0, 1, 2, 3), (0, 2, 1, 3), (0, 3, 1, 2), (1, 2, 0, 3), (1, 3, 0, 2), (2, 3, 0, 1)];
    // Twice the area of the face opposite each corner; with them and six times the volume,
    // 3 V |e| / (2 A_k A_l) is v6 |e| / (a_k a_l), the faces through edge ij being those
    // opposite k and l.
    let area2 = |a: usize, b: usize, c: usize| (p[b] - p[a]).cross(p[c] - p[a]).length();
    let faces = [area2(1, 2, 3), area2(0, 2, 3), area2(0, 1, 3), area2(0, 1, 2)];
    let v6 = volume6(p[0], p[1], p[2], p[3]).abs();
    PAIRS
        .iter()
        .map(|&(i, j, k, l)| {
            let s = v6 * (p[j] - p[i]).length() / (faces[k] * faces[l]);
            if s.is_finite() {
                s
            } else {
                0.0
            }
        })
        .fold(f64::INFINITY, f64::min)
}
