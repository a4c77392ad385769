//! A cell on the domain boundary whose piece of surface the boundary cuts into separate fans
//! gets a vertex per fan ([`boundary_split`]), so the open border has no bow-tie.

use crate::tables::marching_cubes::Case;

/// Cell-code flag: the domain boundary splits one of the cell's pieces ([`boundary_split`]).
pub(super) const SPLIT: u16 = 1 << 15;

/// A boundary cell's pieces once the domain boundary has cut them into fans.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct BoundaryPieces {
    /// Vertices the cell makes.
    pub(super) count: u8,
    /// The piece (vertex) of each crossing edge that has a quad; `u8::MAX` for the others.
    pub(super) edge_piece: [u8; 12],
    /// The crossings each piece's vertex is placed from: the edges of its fan and the boundary
    /// edge at either end of it.
    pub(super) placed_from: [u16; 12],
}

/// How the domain boundary splits the pieces of a cell with table entry `entry` whose edges in
/// `boundary_edges` lie on the boundary (they get no quad). A piece is one polygon of crossing
/// edges, its vertex shared by the quads of its edges; around the vertex those quads form one
/// fan per run of consecutive quad-bearing edges in the polygon. Two runs would be two fans
/// meeting only at the vertex (a bow-tie), so each run gets its own vertex, and a polygon with
/// no quad at all gets none (it would be an unused vertex). `None` when no piece is split or
/// dropped: the cell keeps the table's pieces.
pub(super) fn boundary_split(entry: &Case, boundary_edges: u16) -> Option<BoundaryPieces> {
    if entry.edge_mask & boundary_edges == 0 {
        return None;
    }
    let on_boundary = |e: u8| boundary_edges >> e & 1 == 1;
    let mut out = BoundaryPieces { count: 0, edge_piece: [u8::MAX; 12], placed_from: [0; 12] };
    let mut changed = false;
    for p in 0..entry.polygons {
        // The polygon's cycle, from its lowest edge.
        let start = (0..12u8).find(|&e| entry.edge_polygon[e as usize] == p)?;
        let (mut cycle, mut len) = ([0u8; 12], 0);
        let mut e = start;
        loop {
            cycle[len] = e;
            len += 1;
            e = entry.next[e as usize];
            if e == start || len == 12 {
                break;
            }
        }
        let cycle = &cycle[..len];
        let with_quads = cycle.iter().filter(|&&e| !on_boundary(e)).count();
        if with_quads == 0 {
            changed = true;
            continue;
        }
        if with_quads == len {
            let piece = out.count;
            out.count += 1;
            for &e in cycle {
                out.edge_piece[e as usize] = piece;
                out.placed_from[piece as usize] |= 1 << e;
            }
            continue;
        }
        // Walk the cycle from a quad-bearing edge that follows a boundary edge: the walk then
        // ends on a boundary edge, and every run lies whole inside it.
        let first = (0..len).find(|&k| !on_boundary(cycle[k]) && on_boundary(cycle[(k + len - 1) % len]))?;
        let at = |k: usize| cycle[(first + k) % len];
        let (mut k, mut runs) = (0, 0);
        while k < len {
            if on_boundary(at(k)) {
                k += 1;
                continue;
            }
            let piece = out.count;
            out.count += 1;
            runs += 1;
            let mut mask = 1u16 << at(k + len - 1);
            while !on_boundary(at(k)) {
                out.edge_piece[at(k) as usize] = piece;
                mask |= 1 << at(k);
                k += 1;
            }
            out.placed_from[piece as usize] = mask | 1 << at(k);
        }
        changed |= runs > 1;
    }
    changed.then_some(out)
}
