//! Pinched labels split apart: where one piece of a cell ([`super::super::cell`]) carries two
//! or more separate boundary loops of one label, that label's mesh would pinch at the piece's
//! one vertex. The piece is split instead: each loop of the label (a *cap*) gets its own vertex,
//! the piece's other crossing edges keep one vertex between them, and the gap this opens between
//! the sheets of the other labels is closed by *walls*: at each face point where a cap's sheets
//! meet other sheets, one triangle (or quad, when the cell across the face split the same label)
//! between the cap's vertex, the rest's vertex and the vertex across the face, an interface of
//! the two labels on either side of the split label there ([`walls_of_face`]).
//!
//! A split is local: a cell splits a piece when exactly one of its labels is pinched there (or,
//! with none pinched, to part a bridge) and every other label meets each cap along one run of
//! its rim (so the walls keep that label's mesh manifold too). The sweep leaves it whole when
//! the cell across a face of four labels with walls would put another label's walls there, or,
//! for a cell whose ring rule changed its faces (whose neighbours' splits their own patterns do
//! not tell), when it has walls on a face of four labels; across a face of three labels, two
//! splits of different labels meet at a tetrahedron given to the third label
//! ([`walls_of_face`]). Both rules read only the neighbours' own patterns, so a block meshes a
//! cell as the whole map does.

use super::super::cell::{face_points, CellPieces, EDGES, FACES, NONE};

/// A cell's pieces with its pinched labels split, and for each face, a corner holding the label
/// whose walls lie on that face ([`NONE`] for a face without walls).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Split {
    /// One vertex per cap and per rest of a split piece (the rest keeps the piece's number).
    pub pieces: CellPieces,
    /// Per face, a corner of the split label whose walls lie on it, or [`NONE`].
    pub walls: [u8; 6],
    /// Per vertex, the piece (the rest's vertex) a cap was split from, or [`NONE`].
    pub rest: [u8; 12],
}

/// The face points of a cell: per face, up to two groups of edge slots (see [`face_points`]).
fn groups<T: PartialEq + Copy>(labels: &[T; 8], flips: u8) -> Vec<(usize, Vec<u8>)> {
    let mut out = Vec::new();
    for (f, face) in FACES.iter().enumerate() {
        let points = face_points(face.corners.map(|c| labels[c as usize]), flips >> f & 1 == 1);
        for g in 0..2 {
            if points.len[g] > 0 {
                out.push((f, points.slots[g][..points.len[g] as usize].to_vec()));
            }
        }
    }
    out
}

/// Whether edge `e` of a cell has label `l` at one of its ends.
fn touches<T: PartialEq + Copy>(labels: &[T; 8], e: usize, l: T) -> bool {
    let (a, b) = EDGES[e];
    labels[a as usize] == l || labels[b as usize] == l
}

/// The sectors of a face point (slots `slots` of face `f`, in cyclic order): the corner between
/// each slot and the next.
fn sector_corners(f: usize, slots: &[u8]) -> Vec<u8> {
    slots.iter().map(|&k| FACES[f].corners[(k as usize + 1) % 4]).collect()
}

/// The split of a cell with corner labels `labels` and pieces `pieces` (made with `flips`), if
/// any of its pieces pinches a label (see the module doc).
pub fn split<T: PartialEq + Copy>(labels: &[T; 8], pieces: &CellPieces, flips: u8) -> Option<Split> {
    split_reporting(labels, pieces, flips).0
}

/// [`split`], and whether some piece still pinches a label or keeps a bridge after it (two
/// labels pinched in one piece, or a label meeting a cap along two runs): the cases the split
/// leaves as Frisken's net has them.
pub fn split_reporting<T: PartialEq + Copy>(labels: &[T; 8], pieces: &CellPieces, flips: u8) -> (Option<Split>, bool) {
    let points = groups(labels, flips);
    let mut unresolved = false;
    let mut out = *pieces;
    let mut walls = [NONE; 6];
    let mut rest = [NONE; 12];
    for p in 0..pieces.count {
        let edges: Vec<usize> = (0..12).filter(|&e| pieces.piece[e] == p).collect();
        let mut seen: Vec<T> = Vec::new();
        for &e in &edges {
            for c in [EDGES[e].0, EDGES[e].1] {
                if !seen.contains(&labels[c as usize]) {
                    seen.push(labels[c as usize]);
                }
            }
        }
        // The caps of each label: its edges in the piece joined where they share a face point.
        let pinched: Vec<(T, [u8; 12])> = seen
            .iter()
            .map(|&l| (l, caps(labels, &points, &edges, l)))
            .filter(|(_, c)| c.iter().any(|&c| c != NONE && c >= 1))
            .collect();
        // Two pinched labels leave the piece whole; with none, a bridge is split at its first
        // cut-off corner's label.
        if pinched.len() >= 2 {
            unresolved = true;
            continue;
        }
        let bridged = bridge_corner(labels, &points, pieces, p);
        let Some((l, caps)) = pinched.first().copied().or_else(|| {
            let l = labels[bridged? as usize];
            Some((l, caps(labels, &points, &edges, l)))
        }) else {
            continue;
        };
        let pinches = caps.iter().any(|&c| c != NONE && c >= 1);
        let Some(cap_walls) = cap_walls(labels, &points, &caps, l).filter(|_| edges.iter().any(|&e| caps[e] == NONE)) else {
            unresolved = true;
            continue;
        };
        let corner = (0..8u8).find(|&c| labels[c as usize] == l).unwrap_or(0);
        if cap_walls.iter().any(|&f| walls[f] != NONE && labels[walls[f] as usize] != l) {
            unresolved = true;
            continue;
        }
        // A pinched label split apart may leave a bridge of the piece in place.
        if pinches && bridged.is_some() {
            unresolved = true;
        }
        let first = out.count;
        let cap_count = caps.iter().filter(|&&c| c != NONE).max().map_or(0, |&m| m + 1);
        for (piece, &cap) in out.piece.iter_mut().zip(&caps) {
            if cap != NONE {
                *piece = first + cap;
            }
        }
        for r in &mut rest[first as usize..(first + cap_count) as usize] {
            *r = p;
        }
        out.count += cap_count;
        for f in cap_walls {
            walls[f] = corner;
        }
    }
    ((out.count > pieces.count).then_some(Split { pieces: out, walls, rest }), unresolved)
}

/// The first cut-off corner (the lower of its two) of a face of piece `p` whose diagonal
/// corners share a label `a` and whose other two differ (`a, x, a, y`), when both of the face's
/// points are in `p`: `a` is joined across the face, and if the cell across joins the two points
/// too, the quads of both points share one net edge (four of `a`'s triangles). Splitting the
/// corner's label off gives its point its own vertex.
fn bridge_corner<T: PartialEq + Copy>(labels: &[T; 8], points: &[(usize, Vec<u8>)], pieces: &CellPieces, p: u8) -> Option<u8> {
    for (f, face) in FACES.iter().enumerate() {
        let l = face.corners.map(|c| labels[c as usize]);
        let cut = if l[0] == l[2] && l[1] != l[3] && l[1] != l[0] && l[3] != l[0] {
            [face.corners[1], face.corners[3]]
        } else if l[1] == l[3] && l[0] != l[2] && l[0] != l[1] && l[2] != l[1] {
            [face.corners[0], face.corners[2]]
        } else {
            continue;
        };
        let mine =
            points.iter().filter(|(g, _)| *g == f).all(|(_, slots)| pieces.piece[face.edges[slots[0] as usize] as usize] == p);
        if mine {
            return cut.into_iter().min();
        }
    }
    None
}

/// The cap of each edge of `edges` that touches label `l` (numbered from 0; [`NONE`] elsewhere):
/// its edges joined where they meet at a face point.
fn caps<T: PartialEq + Copy>(labels: &[T; 8], points: &[(usize, Vec<u8>)], edges: &[usize], l: T) -> [u8; 12] {
    let mut parent: [u8; 12] = std::array::from_fn(|e| e as u8);
    fn find(parent: &mut [u8; 12], mut e: u8) -> u8 {
        while parent[e as usize] != e {
            e = parent[e as usize];
        }
        e
    }
    let mine = |e: usize| edges.contains(&e) && touches(labels, e, l);
    for (f, slots) in points {
        let of_l: Vec<usize> = slots.iter().map(|&k| FACES[*f].edges[k as usize] as usize).filter(|&e| mine(e)).collect();
        for w in of_l.windows(2) {
            let (a, b) = (find(&mut parent, w[0] as u8), find(&mut parent, w[1] as u8));
            parent[b as usize] = a;
        }
    }
    let mut cap = [NONE; 12];
    let mut of_root = [NONE; 12];
    let mut n = 0;
    for (e, cap) in cap.iter_mut().enumerate() {
        if mine(e) {
            let r = find(&mut parent, e as u8) as usize;
            if of_root[r] == NONE {
                of_root[r] = n;
                n += 1;
            }
            *cap = of_root[r];
        }
    }
    cap
}

/// The faces on which the caps of `l` (`caps`, as [`caps`] gives) get walls, or `None` when some
/// other label meets a cap along more than one run of its rim (its mesh would pinch on the edge
/// between the cap's vertex and the rest's).
fn cap_walls<T: PartialEq + Copy>(labels: &[T; 8], points: &[(usize, Vec<u8>)], caps: &[u8; 12], l: T) -> Option<Vec<usize>> {
    let mut faces = Vec::new();
    // Per cap, the labels flanking it at its walls, with their counts.
    let mut flanks: Vec<Vec<(T, u8)>> = vec![Vec::new(); 12];
    for (f, slots) in points {
        let edges: Vec<usize> = slots.iter().map(|&k| FACES[*f].edges[k as usize] as usize).collect();
        let capped: Vec<bool> = edges.iter().map(|&e| caps[e] != NONE).collect();
        if !capped.iter().any(|&c| c) || capped.iter().all(|&c| c) {
            continue;
        }
        let cap = edges.iter().map(|&e| caps[e]).find(|&c| c != NONE).unwrap_or(0) as usize;
        // The sector of `l` and the sectors before and after it.
        let sectors = sector_corners(*f, slots);
        let m = sectors.len();
        let at = sectors.iter().position(|&c| labels[c as usize] == l)?;
        for c in [sectors[(at + m - 1) % m], sectors[(at + 1) % m]] {
            let x = labels[c as usize];
            match flanks[cap].iter_mut().find(|(y, _)| *y == x) {
                Some((_, n)) => *n += 1,
                None => flanks[cap].push((x, 1)),
            }
        }
        faces.push(*f);
    }
    flanks.iter().all(|f| f.iter().all(|&(_, n)| n <= 2)).then_some(faces)
}

/// The walls on a face of a cell between this cell's vertices (`here[k]`, the vertex of the
/// face's edge slot `k`) and the cell across the face's (`there[k]`), with the face's corner
/// labels `l` in the face's cyclic order and its flip bit. For each face point whose sheets end
/// on two segments, one wall between the two sectors where they change; on three (two labels
/// split, one on each side), two walls around a tetrahedron given to the third label. Each is
/// given as the slot whose sheet it continues, the labels on its two sides, and its corners
/// (see [`Wall`]; the caller winds it).
pub fn walls_of_face<T: PartialEq + Copy>(l: [T; 4], flip: bool, here: [u32; 4], there: [u32; 4]) -> Vec<Wall<T>> {
    let points = face_points(l, flip);
    let mut out = Vec::new();
    for g in 0..2 {
        let slots = &points.slots[g][..points.len[g] as usize];
        let m = slots.len();
        let seg = |i: usize| (here[slots[i] as usize], there[slots[i] as usize]);
        let changes: Vec<usize> = (0..m).filter(|&i| seg(i) != seg((i + 1) % m)).collect();
        let corner = |i: usize| (slots[i] as usize + 1) % 4;
        let wall = |i: usize, z: T| {
            let (s1, n1) = seg(i);
            let (s2, n2) = seg((i + 1) % m);
            Wall { slot: slots[i] as usize, x: l[corner(i)], z, polygon: [s1, n1, n2, s2] }
        };
        match changes[..] {
            // One label split (on either side or both): the two sectors flanking it close on
            // one wall between them.
            [i, j] => out.push(wall(i, l[corner(j)])),
            // Two labels split, one on each side, at a point of three labels: the sheets end on
            // three segments around a tetrahedron, given to the label not split (the sector
            // whose two segments share no end); the other two sectors close against it.
            [_, _, _] => {
                let Some(&v) = changes.iter().find(|&&i| {
                    let (a, b) = (seg(i), seg((i + 1) % m));
                    a.0 != b.0 && a.1 != b.1
                }) else {
                    continue;
                };
                for &i in changes.iter().filter(|&&i| i != v) {
                    out.push(wall(i, l[corner(v)]));
                }
            }
            _ => {}
        }
    }
    out
}

/// One wall: see [`walls_of_face`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Wall<T> {
    /// The face slot whose sheet the wall continues.
    pub slot: usize,
    /// The label of the sector after that slot (the wall's polygon is wound for it).
    pub x: T,
    /// The label on the wall's other side.
    pub z: T,
    /// `[s1, n1, n2, s2]`: this cell's vertex of the slot, the vertex across the face, then the
    /// same two of the next slot; wound outward for `x` when `x`'s orientation of the slot's
    /// quad runs from `n1` to `s1`, reversed otherwise.
    pub polygon: [u32; 4],
}

#[cfg(test)]
mod tests {
    use super::super::super::cell::cell_pieces;
    use super::*;

    #[test]
    fn two_opposite_caps_of_one_label_split_and_a_plain_cell_does_not() {
        // Label 1 at corners 0 and 7, labels 2 and 3 between them: the piece holds both caps of
        // 1 (joined through the 2|3 sheets), so 1 pinches.
        let labels = [1u8, 3, 2, 3, 2, 2, 2, 1];
        let pieces = cell_pieces(&labels, 0);
        let s = split(&labels, &pieces, 0).expect("label 1 pinches");
        assert!(s.pieces.count >= pieces.count + 2, "{s:?} from {pieces:?}");
        // The six edges of the caps of 1 are on two new vertices, three each.
        let caps: Vec<u8> = (0..12).filter(|&e| touches(&labels, e, 1)).map(|e| s.pieces.piece[e]).collect();
        assert_eq!(caps.len(), 6);
        assert!(caps.iter().all(|&p| p >= pieces.count));
        // A cell of two labels never splits (marching cubes' pieces are manifold).
        let two = [1u8, 0, 0, 0, 0, 0, 0, 1];
        assert_eq!(split(&two, &cell_pieces(&two, 0), 0), None);
    }
}
