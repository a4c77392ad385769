//! The stencils of isosurface stuffing (Labelle & Shewchuk 2007, section 3, "Stencils", and its
//! parity rule): how one BCC tetrahedron whose vertices are signed after warping is filled.
//!
//! A vertex is negative (inside), zero (on the surface: a sample at the iso-value, or a vertex
//! warped onto a cut point) or positive (outside); an edge between a negative and a positive
//! vertex holds a cut point. The part of the tetrahedron on the negative side of its cut points
//! is one of six shapes, each cut into tetrahedra:
//!
//! | signs (+, -, 0) | region | tetrahedra |
//! |---|---|---|
//! | no +, some - | the whole tetrahedron | 1 |
//! | no - (four zeros too) | nothing | 0 |
//! | 1, 1, 2 | the negative vertex, both zeros, one cut | 1 |
//! | 2, 1, 1 | the negative vertex, the zero, two cuts | 1 |
//! | 3, 1, 0 | the negative vertex and its three cuts | 1 |
//! | 1, 2, 1 | a pyramid: the zero over a quadrilateral | 2 |
//! | 1, 3, 0 | a prism: three negatives, three cuts | 3 |
//! | 2, 2, 0 | a prism: the negative edge, four cuts | 3 |
//!
//! A quadrilateral lies in a face of the tetrahedron with two negative vertices `a`, `b` and a
//! positive one `t`, so the tetrahedron across that face splits it too: its diagonal must be
//! chosen from the face alone. Every BCC face has one long edge (between two corners or two
//! centres) and two short ones. When the long edge is `a`-`t` or `b`-`t`, the diagonal joins that
//! edge's cut point to the other lattice vertex. When the long edge is `a`-`b`, the paper's
//! parity rule decides ([`parity_diagonal_from`]): the diagonals alternate around each long edge,
//! so the two faces of one tetrahedron that hold its long edge always take compatible diagonals.
//! The prisms then split into three tetrahedra around a vertex incident to both diagonals of its
//! quadrilaterals ([`split_prism`]); the inner quadrilateral of the 2-2 prism lies on the cut
//! surface and takes whichever diagonal makes the split possible.

/// A vertex of a stencil tetrahedron: corner `i` of the lattice tetrahedron, or the cut point
/// on its edge `(i, j)` (`i < j`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Corner {
    /// Vertex `i` of the lattice tetrahedron (after warping).
    Vertex(u8),
    /// The cut point on the edge between vertices `i < j`.
    Cut(u8, u8),
}

/// The cut point on edge `(i, j)`, in either order.
fn cut(i: usize, j: usize) -> Corner {
    Corner::Cut(i.min(j) as u8, i.max(j) as u8)
}

fn vertex(i: usize) -> Corner {
    Corner::Vertex(i as u8)
}

/// What fills one lattice tetrahedron: up to three tetrahedra, each positively oriented (in the
/// lattice's frame: [`orient`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Fill {
    tets: [[Option<Corner>; 4]; 3],
    len: usize,
}

impl Fill {
    fn push(&mut self, t: [Corner; 4]) {
        self.tets[self.len] = t.map(Some);
        self.len += 1;
    }

    /// The tetrahedra.
    pub fn tets(&self) -> impl Iterator<Item = [Corner; 4]> + '_ {
        self.tets[..self.len].iter().map(|t| t.map(|c| c.expect("pushed whole")))
    }

    /// How many.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether it is empty.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }
}

/// Whether edge `(i, j)` of a tetrahedron with doubled lattice coordinates `d` is long: both
/// ends corners (even coordinates) or both centres (odd).
pub fn is_long(d: &[[i32; 3]; 4], i: usize, j: usize) -> bool {
    (d[i][0] - d[j][0]) % 2 == 0
}

/// The parity rule for a quadrilateral in face `(a, b, t)` whose long edge is `a`-`b` (both
/// negative, `t` positive): whether its diagonal joins `a` to the cut point on `b`-`t` (`true`)
/// or `b` to the cut point on `a`-`t` (`false`). The answer depends on the face only (swapping `a`
/// and `b` flips it, which names the same diagonal) and alternates between the faces around one
/// long edge, whose apexes differ in the sign of one coordinate across it; corner edges and centre
/// edges take opposite phases.
pub fn parity_diagonal_from(d: &[[i32; 3]; 4], a: usize, b: usize, t: usize) -> bool {
    let axis = (0..3).find(|&k| d[a][k] != d[b][k]).expect("a long edge runs along one axis");
    let (o1, o2) = ((axis + 1) % 3, (axis + 2) % 3);
    let count = u32::from(d[a][axis] > d[b][axis]) + u32::from(d[t][o1] < d[a][o1]) + u32::from(d[t][o2] < d[a][o2]);
    let corner_edge = u32::from(d[a][0].rem_euclid(2) == 0);
    (count + corner_edge) % 2 == 0
}

/// The diagonal of the quadrilateral in face `(a, b, t)` (`a`, `b` negative, `t` positive): the
/// lattice vertex it leaves from, and the far end's edge (whose cut point it reaches).
fn quad_diagonal(d: &[[i32; 3]; 4], a: usize, b: usize, t: usize) -> (usize, (usize, usize)) {
    // From b to the cut on a-t when a-t is the long edge, or by the parity rule when a-b is.
    let from_b = is_long(d, a, t) || (!is_long(d, b, t) && !parity_diagonal_from(d, a, b, t));
    if from_b {
        (b, (a, t))
    } else {
        (a, (b, t))
    }
}

/// A triangular prism `A0 A1 A2 / B0 B1 B2` (`Bi` above `Ai`) whose quadrilateral `(i, j)`,
/// `i < j`, is split by `Ai`-`Bj` when `diagonal[k]` is true and by `Aj`-`Bi` otherwise (`k`
/// indexes `(0, 1)`, `(0, 2)`, `(1, 2)`), cut into three tetrahedra; `None` when the diagonals
/// turn around the prism (no split without a new vertex).
pub fn split_prism(a: [Corner; 3], b: [Corner; 3], diagonal: [bool; 3]) -> Option<[[Corner; 4]; 3]> {
    // Whether the diagonal of quadrilateral {i, j} is A_i-B_j.
    let from_a = |i: usize, j: usize| {
        let k = match (i.min(j), i.max(j)) {
            (0, 1) => 0,
            (0, 2) => 1,
            _ => 2,
        };
        diagonal[k] == (i < j)
    };
    let pyramid = |k: usize, apex: Corner| {
        // The quadrilateral A_i A_j B_j B_i opposite k, split by its own diagonal, under an apex.
        let (i, j) = ((k + 1) % 3, (k + 2) % 3);
        if from_a(i, j) {
            [[apex, a[i], a[j], b[j]], [apex, a[i], b[j], b[i]]]
        } else {
            [[apex, a[j], a[i], b[i]], [apex, a[j], b[i], b[j]]]
        }
    };
    for k in 0..3 {
        let (i, j) = ((k + 1) % 3, (k + 2) % 3);
        if from_a(k, i) && from_a(k, j) {
            let [p, q] = pyramid(k, a[k]);
            return Some([[a[k], b[0], b[1], b[2]], p, q]);
        }
        if from_a(i, k) && from_a(j, k) {
            // Both quadrilaterals of B_k are split by diagonals reaching B_k.
            let [p, q] = pyramid(k, b[k]);
            return Some([[b[k], a[0], a[1], a[2]], p, q]);
        }
    }
    None
}

/// Fills a lattice tetrahedron with doubled coordinates `d` and signs `signs` (after warping).
/// A tetrahedron with no negative vertex is dropped, four zeros included (warping can bring four
/// vertices close to one plane; the bound holds because every kept tetrahedron has a negative
/// vertex or a cut point). Tetrahedra come unoriented: [`orient`] orders them.
pub fn fill(d: &[[i32; 3]; 4], signs: [i8; 4]) -> Fill {
    let mut out = Fill::default();
    // The vertices of each sign, in order (fixed arrays: this runs once per cut tetrahedron).
    let of = |s: i8| {
        let (mut v, mut n) = ([0usize; 4], 0);
        for i in (0..4).filter(|&i| signs[i] == s) {
            v[n] = i;
            n += 1;
        }
        (v, n)
    };
    let ((pos, np), (neg, nn), (zero, _)) = (of(1), of(-1), of(0));
    let all = [vertex(0), vertex(1), vertex(2), vertex(3)];
    match (np, nn) {
        (_, 0) => {}
        (0, _) => out.push(all),
        (1, 1) => {
            let (t, n) = (pos[0], neg[0]);
            out.push([vertex(n), vertex(zero[0]), vertex(zero[1]), cut(n, t)]);
        }
        (2, 1) => {
            let n = neg[0];
            out.push([vertex(n), vertex(zero[0]), cut(n, pos[0]), cut(n, pos[1])]);
        }
        (3, 1) => {
            let n = neg[0];
            out.push([vertex(n), cut(n, pos[0]), cut(n, pos[1]), cut(n, pos[2])]);
        }
        (1, 2) => {
            // The zero over the quadrilateral l, m, cut(m, t), cut(l, t).
            let (t, l, m, r) = (pos[0], neg[0], neg[1], zero[0]);
            let (from, (e0, e1)) = quad_diagonal(d, l, m, t);
            let other = if from == l { m } else { l };
            // Triangles of the quadrilateral: (from, other, cut(other, t)) and (from, cut(other, t), cut(from, t)).
            debug_assert_eq!((e0.min(e1), e0.max(e1)), (other.min(t), other.max(t)));
            out.push([vertex(r), vertex(from), vertex(other), cut(other, t)]);
            out.push([vertex(r), vertex(from), cut(other, t), cut(from, t)]);
        }
        (1, 3) => {
            let t = pos[0];
            let a = [neg[0], neg[1], neg[2]];
            let diagonal = [(0, 1), (0, 2), (1, 2)].map(|(i, j)| quad_diagonal(d, a[i], a[j], t).0 == a[i]);
            let prism = split_prism(a.map(vertex), a.map(|n| cut(n, t)), diagonal)
                .expect("the quadrilateral rules never turn around a prism");
            prism.into_iter().for_each(|tet| out.push(tet));
        }
        (2, 2) => {
            // Prism l, cut(l, t), cut(l, m) / r, cut(r, t), cut(r, m); its inner quadrilateral is
            // on the cut surface, free to take either diagonal.
            let ([t, m], [l, r]) = ([pos[0], pos[1]], [neg[0], neg[1]]);
            let a = [vertex(l), cut(l, t), cut(l, m)];
            let b = [vertex(r), cut(r, t), cut(r, m)];
            let face_t = quad_diagonal(d, l, r, t).0 == l;
            let face_m = quad_diagonal(d, l, r, m).0 == l;
            let prism = split_prism(a, b, [face_t, face_m, true])
                .or_else(|| split_prism(a, b, [face_t, face_m, false]))
                .expect("one inner diagonal always splits the prism");
            prism.into_iter().for_each(|tet| out.push(tet));
        }
        _ => unreachable!("four signs"),
    }
    out
}

/// Orders a stencil tetrahedron positively in the lattice's frame: its corners at their doubled
/// coordinates, its cut points at their edges' midpoints (the sign of a stencil tetrahedron's
/// volume does not depend on where its cut points sit inside their edges). Returns it unchanged
/// when its reference volume is zero (a flat stencil, which would be a bug: tested never).
pub fn orient(d: &[[i32; 3]; 4], tet: [Corner; 4]) -> [Corner; 4] {
    if reference_volume(d, tet) < 0 {
        [tet[0], tet[1], tet[3], tet[2]]
    } else {
        tet
    }
}

/// Six times the volume of `tet` at reference positions, in quadrupled lattice coordinates.
pub fn reference_volume(d: &[[i32; 3]; 4], tet: [Corner; 4]) -> i64 {
    let p = tet.map(|c| match c {
        Corner::Vertex(i) => d[i as usize].map(|x| 2 * i64::from(x)),
        Corner::Cut(i, j) => std::array::from_fn(|k| i64::from(d[i as usize][k]) + i64::from(d[j as usize][k])),
    });
    let e = |q: [i64; 3]| [q[0] - p[0][0], q[1] - p[0][1], q[2] - p[0][2]];
    let (u, v, w) = (e(p[1]), e(p[2]), e(p[3]));
    u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) + u[2] * (v[0] * w[1] - v[1] * w[0])
}
