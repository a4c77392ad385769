//! The piece tables of the cell patterns a sweep meets ([`super::sweep`]): each pattern's
//! pieces ([`cell_pieces`]) with the default face rule or the ring rule's flips, its split
//! ([`split`]), and what the sweep reads of it per cell (its ring faces, its vertices' places and
//! labels), computed once per pattern and looked up by the pattern's canonical key.

use super::super::cell::{cell_pieces, is_ring_face, larger_label_flips, CellPieces, EDGES, NONE};
use super::super::Label;
use super::split::split;
use glam::Vec3;
use rustc_hash::FxHashMap;

/// The piece tables of the cell patterns met so far, by canonical pattern (each corner's label
/// replaced by the rank of its first occurrence: three bits a corner).
#[derive(Default)]
pub(super) struct PieceCache {
    index: FxHashMap<u32, u32>,
    pub pieces: Vec<CellPieces>,
    /// Per table: the table with its pinched labels split ([`split`]), or `u32::MAX`.
    pub split_of: Vec<u32>,
    /// Per table: per face, a corner of the label whose walls lie on it, or [`NONE`].
    pub walls: Vec<[u8; 6]>,
    /// Per table: per vertex, the rest's vertex a cap was split from, or [`NONE`].
    pub rests: Vec<[u8; 12]>,
    /// Per table: its faces that are rings ([`is_ring_face`]).
    pub rings: Vec<u8>,
    /// Per table: where its vertices' [`VertexPlace`]s start in `places` (and end: the next).
    place_start: Vec<u32>,
    places: Vec<VertexPlace>,
    /// Cells of two labels, by the corners holding the larger: their pieces with the default
    /// face rule and its flips ([`larger_label_flips`] is a function of that mask).
    two: Vec<(u32, u8)>,
}

/// Where a vertex of a cell's piece starts, and which labels it separates, from the cell's
/// pattern alone.
#[derive(Clone, Copy)]
pub(super) struct VertexPlace {
    /// The mean of its crossing edges' midpoints, from the cell's low corner.
    pub offset: Vec3,
    /// One corner of each label the piece separates (bit per corner).
    pub label_corners: u8,
}

/// The places of the vertices of `pieces` in a cell with corner labels `labels`.
fn vertex_places<'a, T: Label>(pieces: &'a CellPieces, labels: &'a [T; 8]) -> impl Iterator<Item = VertexPlace> + 'a {
    (0..pieces.count).map(move |piece| {
        let mut sum = Vec3::ZERO;
        let mut n = 0.0;
        let mut label_corners = 0u8;
        for (e, &(a, b)) in EDGES.iter().enumerate() {
            if pieces.piece[e] != piece {
                continue;
            }
            sum += (corner_offset(a) + corner_offset(b)) * 0.5;
            n += 1.0;
            for c in [a, b] {
                let seen = (0..8).any(|k| label_corners >> k & 1 == 1 && labels[k] == labels[c as usize]);
                if !seen {
                    label_corners |= 1 << c;
                }
            }
        }
        VertexPlace { offset: sum / n, label_corners }
    })
}

impl PieceCache {
    /// The pieces of a cell with the default face rule, and the rule's flips.
    #[inline]
    pub fn plain<T: Label>(&mut self, labels: &[T; 8]) -> (u32, u8) {
        let l0 = labels[0];
        let other = labels.iter().copied().find(|&l| l != l0).unwrap_or(l0);
        if labels.iter().all(|&l| l == l0 || l == other) {
            let hi = if other.id() > l0.id() { other } else { l0 };
            let mask = labels.iter().enumerate().fold(0usize, |m, (i, &l)| m | usize::from(l == hi) << i);
            if self.two.is_empty() {
                self.two = vec![(u32::MAX, 0); 256];
            }
            if self.two[mask].0 == u32::MAX {
                let flips = larger_label_flips(labels);
                self.two[mask] = (self.get(labels, flips), flips);
            }
            return self.two[mask];
        }
        let flips = larger_label_flips(labels);
        (self.get(labels, flips), flips)
    }

    pub fn get<T: Label>(&mut self, labels: &[T; 8], flips: u8) -> u32 {
        let mut firsts = [labels[0]; 8];
        let mut n = 1usize;
        let mut key = 0u32;
        for (i, &l) in labels.iter().enumerate().skip(1) {
            let rank = firsts[..n].iter().position(|&f| f == l).unwrap_or_else(|| {
                firsts[n] = l;
                n += 1;
                n - 1
            });
            key |= (rank as u32) << (3 * i);
        }
        key |= u32::from(flips) << 24;
        if let Some(&t) = self.index.get(&key) {
            return t;
        }
        let plain = cell_pieces(labels, flips);
        let at = self.pieces.len() as u32;
        self.index.insert(key, at);
        self.push_table(labels, plain, [NONE; 6], [NONE; 12]);
        if let Some(s) = split(labels, &plain, flips) {
            self.split_of[at as usize] = at + 1;
            self.push_table(labels, s.pieces, s.walls, s.rest);
        }
        at
    }

    /// Appends a table (`pieces` of a cell with corner labels `labels`, its walls and rests) and
    /// what the sweep reads of it per cell: its ring faces and its vertices' places.
    fn push_table<T: Label>(&mut self, labels: &[T; 8], pieces: CellPieces, walls: [u8; 6], rest: [u8; 12]) {
        self.pieces.push(pieces);
        self.walls.push(walls);
        self.rests.push(rest);
        self.split_of.push(u32::MAX);
        self.rings.push((0..6).fold(0, |m, f| m | u8::from(is_ring_face(labels, &pieces, f)) << f));
        if self.place_start.is_empty() {
            self.place_start.push(0);
        }
        self.places.extend(vertex_places(&pieces, labels));
        self.place_start.push(self.places.len() as u32);
    }

    /// The vertex places of table `t`.
    #[inline]
    pub fn places(&self, t: u32) -> &[VertexPlace] {
        &self.places[self.place_start[t as usize] as usize..self.place_start[t as usize + 1] as usize]
    }

    /// Whether table `t` is a split one (it has walls).
    pub fn has_walls(&self, t: u32) -> bool {
        self.walls[t as usize] != [NONE; 6]
    }
}

fn corner_offset(i: u8) -> Vec3 {
    Vec3::new(f32::from(i & 1), f32::from(i >> 1 & 1), f32::from(i >> 2 & 1))
}
