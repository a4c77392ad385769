//! The two tetrahedral lattices in doubled integer coordinates: the body-centred cubic lattice
//! and Kuhn-split cubes, each sample's 14 neighbour directions and its star of 24 tetrahedra.

use crate::lattice::Lattice;
use std::sync::LazyLock;

/// Neighbours of every sample in both tetrahedral lattices.
pub const DIRECTIONS: usize = 14;

/// How space is cut into tetrahedra.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TetKind {
    /// Body-centred cubic: corner grid plus cell centres, 12 tetrahedra per cell.
    Bcc,
    /// Cubic grid, six tetrahedra around each cube's main diagonal.
    Kuhn,
}

impl TetKind {
    /// The decomposition used for a lattice: BCC lattices get [`TetKind::Bcc`], cubic grids
    /// [`TetKind::Kuhn`].
    pub fn of(lattice: &Lattice) -> TetKind {
        match lattice {
            Lattice::Bcc(_) => TetKind::Bcc,
            Lattice::Cubic(_) => TetKind::Kuhn,
        }
    }
}

/// The directions, tetrahedra and star adjacency of one tetrahedral lattice.
#[derive(Clone, Debug)]
pub struct TetTopology {
    /// Which lattice.
    pub kind: TetKind,
    /// Direction `k` to neighbour `k`, in doubled coordinates; `k ^ 1` is the opposite direction.
    pub directions: [[i32; 3]; DIRECTIONS],
    /// Bit `j` of `adjacency[k]`: neighbours `k` and `j` of a sample are joined by a lattice edge,
    /// so the sample and the two span a tetrahedron face (the edges of the star's link).
    pub adjacency: [u16; DIRECTIONS],
    /// The tetrahedra around one anchor (a BCC cell centre, or a cube's low corner), as doubled
    /// offsets from the anchor, each positively oriented.
    pub templates: Vec<[[i32; 3]; 4]>,
    /// For template `t`, the direction from its vertex `i` to its vertex `j`.
    pub edge_directions: Vec<[[u8; 4]; 4]>,
}

/// The two topologies, built once.
pub static BCC: LazyLock<TetTopology> = LazyLock::new(|| TetTopology::new(TetKind::Bcc));
/// The Kuhn topology, built once.
pub static KUHN: LazyLock<TetTopology> = LazyLock::new(|| TetTopology::new(TetKind::Kuhn));

/// The topology for `kind`.
pub fn topology(kind: TetKind) -> &'static TetTopology {
    match kind {
        TetKind::Bcc => &BCC,
        TetKind::Kuhn => &KUHN,
    }
}

pub(super) fn sub(a: [i32; 3], b: [i32; 3]) -> [i32; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

pub(super) fn orientation(t: &[[i32; 3]; 4]) -> i64 {
    let [a, b, c] = [sub(t[1], t[0]), sub(t[2], t[0]), sub(t[3], t[0])].map(|v| v.map(i64::from));
    a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) + a[2] * (b[0] * c[1] - b[1] * c[0])
}

impl TetTopology {
    pub(super) fn new(kind: TetKind) -> TetTopology {
        let mut directions = [[0i32; 3]; DIRECTIONS];
        let axes = [[2, 0, 0], [0, 2, 0], [0, 0, 2]];
        let diagonals: Vec<[i32; 3]> = match kind {
            // The eight half-diagonals to the neighbouring centres (or corners).
            TetKind::Bcc => vec![[1, 1, 1], [-1, 1, 1], [1, -1, 1], [1, 1, -1]],
            // Face diagonals and the main diagonal, all cut the same way.
            TetKind::Kuhn => vec![[2, 2, 0], [2, 0, 2], [0, 2, 2], [2, 2, 2]],
        };
        for (k, d) in axes.iter().chain(diagonals.iter()).enumerate() {
            directions[2 * k] = *d;
            directions[2 * k + 1] = d.map(|c| -c);
        }
        let mut templates = Vec::new();
        match kind {
            TetKind::Bcc => {
                // Anchor: a cell centre. Its neighbour across face `a` and that face's four corners.
                for a in 0..3 {
                    let (b, c) = ((a + 1) % 3, (a + 2) % 3);
                    let mut other = [0; 3];
                    other[a] = 2;
                    let corner = |sb: i32, sc: i32| {
                        let mut p = [0; 3];
                        p[a] = 1;
                        p[b] = sb;
                        p[c] = sc;
                        p
                    };
                    let ring = [corner(-1, -1), corner(1, -1), corner(1, 1), corner(-1, 1)];
                    for m in 0..4 {
                        templates.push([[0, 0, 0], other, ring[m], ring[(m + 1) % 4]]);
                    }
                }
            }
            TetKind::Kuhn => {
                for perm in [[0, 1, 2], [0, 2, 1], [1, 0, 2], [1, 2, 0], [2, 0, 1], [2, 1, 0]] {
                    let mut v1 = [0; 3];
                    v1[perm[0]] = 2;
                    let mut v2 = v1;
                    v2[perm[1]] = 2;
                    templates.push([[0, 0, 0], v1, v2, [2, 2, 2]]);
                }
            }
        }
        for t in &mut templates {
            if orientation(t) < 0 {
                t.swap(2, 3);
            }
        }
        let direction_of =
            |d: [i32; 3]| directions.iter().position(|&e| e == d).expect("tetrahedron edges are lattice edges") as u8;
        let edge_directions: Vec<[[u8; 4]; 4]> = templates
            .iter()
            .map(|t| {
                std::array::from_fn(|i| std::array::from_fn(|j| if i == j { u8::MAX } else { direction_of(sub(t[j], t[i])) }))
            })
            .collect();
        let mut adjacency = [0u16; DIRECTIONS];
        for e in &edge_directions {
            for p in 0..4 {
                for q in 0..4 {
                    for r in 0..4 {
                        if p != q && p != r && q != r {
                            adjacency[e[p][q] as usize] |= 1 << e[p][r];
                        }
                    }
                }
            }
        }
        TetTopology { kind, directions, adjacency, templates, edge_directions }
    }

    /// The neighbours among `present` (bit `k`: neighbour `k` exists) whose edge to the sample
    /// lies in a tetrahedron of the lattice: those with two present neighbours joined to it and
    /// to each other (a tetrahedron of the star). Inside the lattice that is every neighbour; on
    /// the BCC lattice's border it is not, as the tetrahedra there need the cell centres beyond
    /// it (a cube edge along an edge of the domain lies in none).
    pub fn edges_in_tetrahedra(&self, present: u16) -> u16 {
        (0..DIRECTIONS).filter(|&k| present >> k & 1 == 1).fold(0u16, |mask, k| {
            let around = self.adjacency[k] & present;
            let in_one = (0..DIRECTIONS).any(|j| around >> j & 1 == 1 && self.adjacency[j] & around != 0);
            mask | u16::from(in_one) << k
        })
    }
}
