//! One cell of a label map: which of its twelve edges separate two labels, and how those
//! crossing edges group into pieces of interface, each piece one vertex of the net.
//!
//! A cell is the cube between eight samples, corner `i` at offset `(i & 1, i >> 1 & 1, i >> 2 & 1)`.
//! Each crossing edge carries one sheet of interface through the cell (a quarter of the quad
//! dual to the edge). Sheets meet where they pass through a cell face: all crossing edges of a
//! face meet at one point of that face, except on a face whose diagonal corners agree (`a, b, a,
//! b` or `a, x, a, y`), where two points are needed, one around each cut-off corner:
//! - `a, x, a, y` (`x ≠ y`): `a` is joined across the face (the only choice that keeps `x`'s and
//!   `y`'s sheets whole);
//! - `a, b, a, b`: the larger label's diagonal is joined ([`larger_label_flips`]), unless that
//!   makes a ring of interface through the face in both cells ([`is_ring_face`]), when the other
//!   is. The rule reads the face's own labels and the two cells around it, so both cells decide
//!   alike.
//!
//! The pieces of a cell are the connected components of its crossing edges under "meet at a face
//! point"; with two labels they are marching cubes' polygons (one vertex per piece is what keeps
//! surface nets manifold, as in `extractors::surface_nets`), and with more labels a piece holds
//! the junctions of three or more labels that pass through the cell (Frisken 2022, §3).

/// The twelve edges of a cell as corner pairs: axis `d`'s four edges are `4d..4d + 4`, in
/// increasing order of their lower corner.
pub const EDGES: [(u8, u8); 12] = edges();

const fn edges() -> [(u8, u8); 12] {
    let mut out = [(0u8, 0u8); 12];
    let mut d = 0;
    while d < 3 {
        let bit = 1u8 << d;
        let mut k = 0;
        let mut i = 0u8;
        while i < 8 {
            if i & bit == 0 {
                out[d * 4 + k] = (i, i | bit);
                k += 1;
            }
            i += 1;
        }
        d += 1;
    }
    out
}

/// The cell edge along axis `d` whose lower corner is `corner` (which must not have bit `d`).
pub const fn edge_index(d: usize, corner: u8) -> usize {
    // Rank of `corner` among the corners without bit d: drop bit d and read the two others.
    let low = corner & ((1 << d) - 1);
    let high = (corner >> (d + 1)) << d;
    d * 4 + (low | high) as usize
}

/// The six faces: for each, its four corners in cyclic order starting from the corner with the
/// smallest coordinates (axes `u < v` other than the face's normal axis), and the edge between
/// each corner and the next.
pub const FACES: [Face; 6] = faces();

/// A cell face.
#[derive(Clone, Copy, Debug)]
pub struct Face {
    /// Corners in cyclic order, the first with the smallest coordinates.
    pub corners: [u8; 4],
    /// `edges[k]` joins `corners[k]` and `corners[(k + 1) % 4]`.
    pub edges: [u8; 4],
}

const fn faces() -> [Face; 6] {
    let mut out = [Face { corners: [0; 4], edges: [0; 4] }; 6];
    let mut d = 0;
    while d < 3 {
        let (u, v) = if d == 0 {
            (1, 2)
        } else if d == 1 {
            (0, 2)
        } else {
            (0, 1)
        };
        let mut side = 0;
        while side < 2 {
            let base = (side as u8) << d;
            let corners = [base, base | 1 << u, base | 1 << u | 1 << v, base | 1 << v];
            let mut edges = [0u8; 4];
            let mut k = 0;
            while k < 4 {
                let (a, b) = (corners[k], corners[(k + 1) % 4]);
                let (lo, hi) = if a < b { (a, b) } else { (b, a) };
                let axis = if hi ^ lo == 1 {
                    0
                } else if hi ^ lo == 2 {
                    1
                } else {
                    2
                };
                edges[k] = edge_index(axis, lo) as u8;
                k += 1;
            }
            out[d * 2 + side] = Face { corners, edges };
            side += 1;
        }
        d += 1;
    }
    out
}

/// Marks an edge that does not cross.
pub const NONE: u8 = u8::MAX;

/// The pieces of one cell: for every edge, the piece it belongs to ([`NONE`] when its two
/// labels agree), and how many pieces there are.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CellPieces {
    /// Piece of each edge, numbered in order of their first edge.
    pub piece: [u8; 12],
    /// Number of pieces (0 for a cell of one label).
    pub count: u8,
}

/// The face points of one face: groups of its edge slots (`k` is the edge `edges[k]`) that meet
/// at one point. At most two groups; `len[g]` slots of `slots[g]` are used.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FacePoints {
    /// Slots of each group.
    pub slots: [[u8; 4]; 2],
    /// Slots used in each group (0 when the group is absent).
    pub len: [u8; 2],
}

/// How the crossing edges of a face with corner labels `l` (in the face's cyclic order) meet: one
/// point, or two on the faces whose diagonal corners agree (see the module doc). `flip` joins the
/// other diagonal of an `a, b, a, b` face (the ring rule of [`cell_pieces`]); it changes no other
/// face.
pub fn face_points<T: PartialEq>(l: [T; 4], flip: bool) -> FacePoints {
    let crossing = [l[0] != l[1], l[1] != l[2], l[2] != l[3], l[3] != l[0]];
    if crossing.iter().all(|&c| c) {
        if flip && l[0] == l[2] && l[1] == l[3] {
            return FacePoints { slots: [[3, 0, 0, 0], [1, 2, 0, 0]], len: [2, 2] };
        }
        // Joined diagonal 0-2 cuts off corners 1 (slots 0, 1) and 3 (slots 2, 3); joined 1-3
        // cuts off 0 (slots 3, 0) and 2 (slots 1, 2).
        if l[0] == l[2] {
            return FacePoints { slots: [[0, 1, 0, 0], [2, 3, 0, 0]], len: [2, 2] };
        }
        if l[1] == l[3] {
            return FacePoints { slots: [[3, 0, 0, 0], [1, 2, 0, 0]], len: [2, 2] };
        }
    }
    let mut one = [0u8; 4];
    let mut n = 0;
    for (k, &c) in crossing.iter().enumerate() {
        if c {
            one[n] = k as u8;
            n += 1;
        }
    }
    FacePoints { slots: [one, [0; 4]], len: [n as u8, 0] }
}

/// The faces of a cell (bit `f` for face `f`) that are `a, b, a, b` faces whose larger label sits
/// on the diagonal through corners 1 and 3: [`cell_pieces`] joins the larger label's diagonal of
/// such a face by default, a rule of the face's own labels, so both cells sharing it decide alike
/// (and, with two labels in a cell, alike on all its faces, as marching cubes' sign rule does).
pub fn larger_label_flips<T: super::Label>(labels: &[T; 8]) -> u8 {
    let mut flips = 0;
    let mut faces = checkered_faces(labels);
    while faces != 0 {
        let f = faces.trailing_zeros() as usize;
        faces &= faces - 1;
        let c = FACES[f].corners;
        if labels[c[1] as usize].id() > labels[c[0] as usize].id() {
            flips |= 1 << f;
        }
    }
    flips
}

/// The `a, b, a, b` faces of a cell (bit `f` for face `f`): the only ones the face rule and the
/// ring rule decide.
#[inline]
pub fn checkered_faces<T: PartialEq + Copy>(labels: &[T; 8]) -> u8 {
    let mut out = 0;
    for (f, face) in FACES.iter().enumerate() {
        let [a, b, c, d] = face.corners;
        let (a, b, c, d) = (labels[a as usize], labels[b as usize], labels[c as usize], labels[d as usize]);
        if a == c && b == d && a != b {
            out |= 1 << f;
        }
    }
    out
}

/// Whether face `f` of a cell is an `a, b, a, b` face whose two face points fall in one piece of
/// `pieces` (a ring of interface through the face: if the cell across the face has the same ring,
/// the quads of the face's four edges would share one net edge).
pub fn is_ring_face<T: PartialEq + Copy>(labels: &[T; 8], pieces: &CellPieces, f: usize) -> bool {
    let face = &FACES[f];
    let l = face.corners.map(|c| labels[c as usize]);
    l[0] == l[2] && l[1] == l[3] && l[0] != l[1] && pieces.piece[face.edges[0] as usize] == pieces.piece[face.edges[2] as usize]
}

/// The pieces of a cell with corner labels `labels` (corner `i` at offset bits `i`); bit `f` of
/// `flips` joins the other diagonal of face `f` when it is an `a, b, a, b` face. The engine flips
/// a face that is a ring ([`is_ring_face`]) in both cells sharing it, as surface nets do with the
/// marching cubes table's ring faces.
pub fn cell_pieces<T: PartialEq + Copy>(labels: &[T; 8], flips: u8) -> CellPieces {
    let mut parent: [u8; 12] = std::array::from_fn(|e| e as u8);
    fn find(parent: &mut [u8; 12], mut e: u8) -> u8 {
        while parent[e as usize] != e {
            let up = parent[parent[e as usize] as usize];
            parent[e as usize] = up;
            e = up;
        }
        e
    }
    for (f, face) in FACES.iter().enumerate() {
        let points = face_points(face.corners.map(|c| labels[c as usize]), flips >> f & 1 == 1);
        for g in 0..2 {
            let slots = &points.slots[g][..points.len[g] as usize];
            if let Some((&first, rest)) = slots.split_first() {
                let a = find(&mut parent, face.edges[first as usize]);
                for &s in rest {
                    let b = find(&mut parent, face.edges[s as usize]);
                    parent[b as usize] = a;
                }
            }
        }
    }
    let mut piece = [NONE; 12];
    let mut root_piece = [NONE; 12];
    let mut count = 0u8;
    for (e, &(a, b)) in EDGES.iter().enumerate() {
        if labels[a as usize] == labels[b as usize] {
            continue;
        }
        let r = find(&mut parent, e as u8) as usize;
        if root_piece[r] == NONE {
            root_piece[r] = count;
            count += 1;
        }
        piece[e] = root_piece[r];
    }
    CellPieces { piece, count }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn edges_and_faces_are_the_cube() {
        for (e, &(a, b)) in EDGES.iter().enumerate() {
            let d = (b ^ a).trailing_zeros() as usize;
            assert_eq!((b ^ a).count_ones(), 1);
            assert_eq!(edge_index(d, a), e);
        }
        let mut uses = [0; 12];
        for f in &FACES {
            for k in 0..4 {
                let (a, b) = EDGES[f.edges[k] as usize];
                let (p, q) = (f.corners[k], f.corners[(k + 1) % 4]);
                assert!((a, b) == (p, q) || (a, b) == (q, p), "face edge {k} of {f:?}");
                uses[f.edges[k] as usize] += 1;
            }
            assert!(f.corners.iter().all(|&c| c & f.corners[0] == f.corners[0]), "first corner is the smallest: {f:?}");
        }
        assert!(uses.iter().all(|&u| u == 2), "every edge bounds two faces: {uses:?}");
    }

    #[test]
    fn two_labels_give_marching_cubes_pieces() {
        // One corner apart: one piece of three edges; two opposite corners: two pieces.
        let one = cell_pieces(&[1, 0, 0, 0, 0, 0, 0, 0], 0);
        assert_eq!(one.count, 1);
        assert_eq!(one.piece.iter().filter(|&&p| p != NONE).count(), 3);
        let two = cell_pieces(&[1, 0, 0, 0, 0, 0, 0, 1], 0);
        assert_eq!(two.count, 2);
        // A uniform cell has none; a half-split cell one piece of four edges.
        assert_eq!(cell_pieces(&[3; 8], 0).count, 0);
        let half = cell_pieces(&[1, 1, 1, 1, 2, 2, 2, 2], 0);
        assert_eq!((half.count, half.piece.iter().filter(|&&p| p != NONE).count()), (1, 4));
    }

    #[test]
    fn a_face_with_agreeing_diagonal_has_two_points() {
        assert_eq!(face_points([1, 2, 1, 2], false).len, [2, 2]);
        assert_eq!(face_points([1, 2, 1, 3], false).slots[0][..2], [0, 1]);
        assert_eq!(face_points([2, 1, 3, 1], false).slots[0][..2], [3, 0]);
        assert_eq!(face_points([1, 2, 3, 4], false).len, [4, 0]);
        assert_eq!(face_points([1, 1, 2, 3], false).len, [3, 0]);
    }
}
