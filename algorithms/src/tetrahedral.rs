//! # Tetrahedral lattices and the marching tetrahedra engine
//!
//! **Papers:** A. Payne and A. W. Toga, "Surface mapping brain function on 3D models", IEEE CG&A
//! 10(5), 1990 (marching tetrahedra); G. M. Treece, R. W. Prager and A. H. Gee, "Regularised
//! marching tetrahedra: improved iso-surface extraction", Computers & Graphics 23(4), 1999; and the
//! specification `../shared/papers/costen-2026-rmt-terrain.txt` (sections 2.3, 3.1.2, 3.1.3,
//! Algorithms 2 and 3, Figs. 7, 17-19).
//!
//! Two ways to fill space with tetrahedra, both with **14 neighbours per sample** (so per-edge
//! flags fit 16 bits and every sample's star is 24 tetrahedra whose link is a triangulated sphere
//! of 14 vertices, 36 edges and 24 triangles):
//! - [`TetKind::Bcc`] on a [`Lattice::Bcc`]: the body-centred cubic lattice (the paper's "BCDL").
//!   Each tetrahedron joins two neighbouring cell centres (a long edge of the centre grid) and a
//!   corner-grid edge of the face between them (a long edge of the corner grid), so it has two long
//!   edges (length h) and four short ones (h√3/2), dihedral angles of 60 and 90 degrees, and every
//!   tetrahedron is congruent. Twelve tetrahedra per cell (24 touch a cell, each shared by two).
//! - [`TetKind::Kuhn`] on a [`Lattice::Cubic`]: six congruent tetrahedra around each cube's main
//!   diagonal from `(0,0,0)` to `(1,1,1)`, cut in the same direction on opposite faces (the
//!   Kuhn / Freudenthal split, the paper's Fig. 19 "simple cubic"), so neighbouring cubes agree
//!   on every face without mirroring.
//!
//! Coordinates are **doubled**: a corner sample `(x, y, z)` sits at `(2x, 2y, 2z)`, a BCC centre
//! at `(2x+1, 2y+1, 2z+1)`, so both lattices share one integer frame and one direction table.
//!
//! ## The engine
//! [`extract_tetrahedral`] runs the paper's two passes for marching tetrahedra and for
//! regularised marching tetrahedra (which differ only in their [`Clustering`]):
//! - **vertex pass** (Algorithm 2): every sample collects the crossings on its 14 edges that lie
//!   nearer to it than to the other end (its *nearby intersections*; ties go to the lower sample
//!   index, so every crossing has exactly one owner), hands them to the clustering, and stores a
//!   base vertex index plus a 4-bit vertex slot per edge (14 bytes per sample, against the
//!   paper's 58: a 16-bit flag word and a 32-bit index per edge);
//! - **geometry pass** (Algorithm 3): every tetrahedron with a sign change looks up its case in
//!   the 16-case table ([`MT_TABLE`]) and emits one triangle or a quad split along its shorter
//!   diagonal, wound outward. Triangles with a repeated vertex (collapsed by clustering) are
//!   discarded and counted. A merged quad whose opposite corners coincide is split along them, so
//!   both halves vanish instead of leaving two back-to-back triangles.
//!
//! Vertex normals are the area-weighted mean of the incident triangle normals (section 3.1.2).
//! Groups of tetrahedra whose samples all share a sign are skipped from their signs alone (the
//! paper skips a cube when its centre has no flags, which misses tetrahedra whose crossings are
//! all owned by corners; this test cannot).
//!
//! **Guarantees.** Without clustering the surface is closed where it stays inside the lattice,
//! manifold and outward-wound (the tests run all 16 sign patterns of a tetrahedron, every pattern
//! of a sample's star, random fields and the closed built-in fields). With clustering see
//! [`crate::extractors::regularised_marching_tetrahedra`].
//!
//! **Costs.** Each pass reads every sample and its 14 neighbours once: O(samples). Serial, as the
//! paper's (its section 3.1.4 parallelises sampling only, which [`Samples`] does).

use crate::extract::{ExtractError, Extraction};
use crate::field::Field;
use crate::lattice::{Grid, Lattice};
use crate::samples::Samples;
use crate::sign_rows::{classify_rows, span, Row};
use glam::Vec3;
use rayon::prelude::*;
use std::sync::LazyLock;
use std::time::Instant;

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

fn sub(a: [i32; 3], b: [i32; 3]) -> [i32; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn orientation(t: &[[i32; 3]; 4]) -> i64 {
    let [a, b, c] = [sub(t[1], t[0]), sub(t[2], t[0]), sub(t[3], t[0])].map(|v| v.map(i64::from));
    a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) + a[2] * (b[0] * c[1] - b[1] * c[0])
}

impl TetTopology {
    fn new(kind: TetKind) -> TetTopology {
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
}

/// One marching tetrahedra case for a positively oriented tetrahedron: the crossing edges of its
/// polygon in cyclic order, wound counter-clockwise seen from outside (`f > iso`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MtCase {
    /// 0 (no surface), 3 (a triangle) or 4 (a quad).
    pub count: u8,
    /// Local vertex pairs `(inside, outside)` of the crossing edges.
    pub edges: [(u8, u8); 4],
}

/// The 16-case marching tetrahedra table, indexed by the inside mask (bit `i`: vertex `i` has
/// `f < iso`), generated from the geometry of a reference tetrahedron.
pub static MT_TABLE: LazyLock<[MtCase; 16]> = LazyLock::new(|| std::array::from_fn(|c| mt_case(c as u8)));

fn mt_case(case: u8) -> MtCase {
    let inside: Vec<u8> = (0..4).filter(|i| case >> i & 1 == 1).collect();
    let outside: Vec<u8> = (0..4).filter(|i| case >> i & 1 == 0).collect();
    let mut edges = [(0u8, 0u8); 4];
    let count = match (inside.len(), outside.len()) {
        (1, 3) => {
            for (k, &o) in outside.iter().enumerate() {
                edges[k] = (inside[0], o);
            }
            3
        }
        (3, 1) => {
            for (k, &i) in inside.iter().enumerate() {
                edges[k] = (i, outside[0]);
            }
            3
        }
        (2, 2) => {
            let ([i, j], [k, l]) = ([inside[0], inside[1]], [outside[0], outside[1]]);
            edges = [(i, k), (j, k), (j, l), (i, l)];
            4
        }
        _ => 0,
    };
    if count > 0 {
        // Reference tetrahedron (positive orientation); flip the cycle if it faces inward.
        let p = [Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z];
        let mid = |(a, b): (u8, u8)| 0.5 * (p[a as usize] + p[b as usize]);
        let centroid = |s: &[u8]| s.iter().map(|&i| p[i as usize]).sum::<Vec3>() / s.len() as f32;
        let n = (mid(edges[1]) - mid(edges[0])).cross(mid(edges[2]) - mid(edges[0]));
        if n.dot(centroid(&outside) - centroid(&inside)) < 0.0 {
            edges[..count as usize].reverse();
        }
    }
    MtCase { count, edges }
}

/// The crossings one sample owns, as a clustering policy sees them.
#[derive(Clone, Copy, Debug)]
pub struct Star {
    /// Bit `k`: the crossing on edge `k` is nearer this sample than the neighbour.
    pub nearby: u16,
    /// Bit `k`: neighbour `k` exists (all 14 away from the lattice boundary).
    pub neighbours: u16,
    /// Crossing positions (valid where `nearby` is set).
    pub crossings: [Vec3; DIRECTIONS],
}

/// Which of a sample's nearby crossings become one vertex.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Islands {
    /// Number of vertices made.
    pub count: u8,
    /// Vertex slot (`0..count`) of each nearby crossing's edge.
    pub slot: [u8; DIRECTIONS],
}

/// How a sample's nearby crossings are grouped into vertices.
pub trait Clustering: Sync {
    /// Groups the nearby crossings of one sample; `topology` gives the star's adjacency.
    fn islands(&self, star: &Star, topology: &TetTopology) -> Islands;

    /// Final position of a vertex merged from `members` crossings with mean `mean`, on the level
    /// set `iso` of `field` when the samples carry one; `spacing` is the grid spacing.
    fn place(&self, mean: Vec3, _members: u32, _field: Option<&dyn Field>, _iso: f32, _spacing: f32) -> Vec3 {
        mean
    }
}

/// One vertex per crossing (plain marching tetrahedra).
pub struct NoClustering;

impl Clustering for NoClustering {
    fn islands(&self, star: &Star, _: &TetTopology) -> Islands {
        let mut slot = [u8::MAX; DIRECTIONS];
        let mut count = 0;
        for (k, s) in slot.iter_mut().enumerate() {
            if star.nearby >> k & 1 == 1 {
                *s = count;
                count += 1;
            }
        }
        Islands { count, slot }
    }
}

/// Per-sample vertex bookkeeping, reusable between runs.
#[derive(Clone, Debug, Default)]
pub struct TetScratch {
    base: Vec<u32>,
    slots: Vec<u64>,
    /// Samples with a sign change on one of their edges.
    touch: Vec<bool>,
    /// Samples whose crossings must not merge (set by a repairing caller).
    no_merge: Vec<bool>,
    /// The sample that made each vertex, how many crossings it merged, and the lowest of their
    /// directions (with the sample, a key for the vertex that does not depend on the lattice's
    /// extent).
    owner: Vec<(u32, u8, u8)>,
}

impl TetScratch {
    /// Bytes held.
    pub fn bytes(&self) -> usize {
        self.base.capacity() * 4
            + self.slots.capacity() * 8
            + self.touch.capacity()
            + self.no_merge.capacity()
            + self.owner.capacity() * 8
    }

    /// Fills `origins` with each vertex's owning sample and the lowest direction of its crossings
    /// (`grid` is the corner grid of a cubic lattice); vertices from index `repaired_from` on were
    /// made by repairs and are tagged apart.
    pub fn fill_origins(&self, grid: &Grid, repaired_from: usize, origins: &mut crate::extract::Origins) {
        let owners = self.owner.iter().enumerate().map(|(v, &(s, _, k))| {
            let tag = if v >= repaired_from { DIRECTIONS as u32 } else { 0 };
            (s as usize, u32::from(k) + tag)
        });
        origins.fill_with_ordinals(grid, owners);
    }

    /// Samples currently forbidden to merge.
    pub fn unmerged_samples(&self) -> usize {
        self.no_merge.iter().filter(|&&b| b).count()
    }
}

/// Sample addressing in doubled coordinates.
struct Addresser {
    corners: Grid,
    centres: Option<Grid>,
    /// Largest doubled coordinate on each axis.
    max: [i32; 3],
}

impl Addresser {
    fn new(lattice: &Lattice) -> Addresser {
        let corners = *lattice.grid();
        let centres = matches!(lattice, Lattice::Bcc(_)).then(|| corners.centres());
        Addresser { corners, centres, max: corners.dims.map(|n| 2 * (n as i32 - 1)) }
    }

    /// Flat index of the sample at doubled coordinates `q`, if the lattice has one there.
    #[inline]
    fn index(&self, q: [i32; 3]) -> Option<usize> {
        if (0..3).any(|k| q[k] < 0 || q[k] > self.max[k]) {
            return None;
        }
        if q[0] & 1 == 0 {
            Some(self.corners.index((q[0] / 2) as usize, (q[1] / 2) as usize, (q[2] / 2) as usize))
        } else {
            let c = self.centres.as_ref()?;
            Some(self.corners.len() + c.index((q[0] / 2) as usize, (q[1] / 2) as usize, (q[2] / 2) as usize))
        }
    }

    /// Doubled coordinates of flat sample `i`.
    fn coords(&self, i: usize) -> [i32; 3] {
        let (g, i, odd) = match &self.centres {
            Some(c) if i >= self.corners.len() => (c, i - self.corners.len(), 1),
            _ => (&self.corners, i, 0),
        };
        let [nx, ny, _] = g.dims;
        [(i % nx) as i32 * 2 + odd, ((i / nx) % ny) as i32 * 2 + odd, (i / (nx * ny)) as i32 * 2 + odd]
    }

    fn position(&self, q: [i32; 3]) -> Vec3 {
        self.corners.origin + Vec3::new(q[0] as f32, q[1] as f32, q[2] as f32) * (0.5 * self.corners.spacing)
    }
}

/// One of the lattice's cubic grids (corners, or BCC centres) and the constant index offsets of
/// the neighbours of its interior samples.
struct Part {
    /// 0 for corners, 1 for centres (added to doubled coordinates).
    odd: i32,
    /// First flat index and samples per axis.
    start: usize,
    dims: [usize; 3],
    /// The other grid (BCC), or this one again.
    cross_start: usize,
    cross_dims: [usize; 3],
    /// Per direction: whether the neighbour is in the other grid, and its index offset from
    /// `(x, y, z)` in that grid's order.
    offsets: [(bool, isize); DIRECTIONS],
}

impl Part {
    /// The grid and index offset of the sample at doubled offset `d` from one of this grid's
    /// samples, in the same form as [`Part::offsets`].
    fn offset_of(&self, d: [i32; 3]) -> (bool, isize) {
        let cross = d[0] & 1 != 0;
        let shift = |c: i32| {
            if !cross {
                c / 2
            } else if self.odd == 0 {
                (c - 1) / 2
            } else {
                (c + 1) / 2
            }
        };
        let (a, b, c) = (shift(d[0]) as isize, shift(d[1]) as isize, shift(d[2]) as isize);
        let gd = if cross { self.cross_dims } else { self.dims };
        (cross, a + gd[0] as isize * (b + gd[1] as isize * c))
    }
}

struct Layout {
    parts: Vec<Part>,
}

impl Layout {
    fn new(at: &Addresser, topo: &TetTopology) -> Layout {
        let mut grids = vec![(0, 0usize, at.corners.dims)];
        if let Some(c) = &at.centres {
            grids.push((1, at.corners.len(), c.dims));
        }
        let parts = grids
            .iter()
            .map(|&(odd, start, dims)| {
                let other = grids.iter().find(|g| g.0 != odd).copied().unwrap_or((odd, start, dims));
                let mut part =
                    Part { odd, start, dims, cross_start: other.1, cross_dims: other.2, offsets: [(false, 0); DIRECTIONS] };
                part.offsets = topo.directions.map(|d| part.offset_of(d));
                part
            })
            .collect();
        Layout { parts }
    }
}

/// For samples of each parity (corners 0, BCC centres 1): the rows their neighbours lie in, as
/// (in the other grid?, y offset, z offset) of grid row indices, the sample's own row included.
fn row_neighbours(topo: &TetTopology) -> [Vec<(bool, isize, isize)>; 2] {
    std::array::from_fn(|odd| {
        let mut out = vec![(false, 0, 0)];
        for d in topo.directions {
            let cross = d[0] & 1 != 0;
            let shift = |c: i32| -> isize {
                (if !cross {
                    c / 2
                } else if odd == 0 {
                    (c - 1) / 2
                } else {
                    (c + 1) / 2
                }) as isize
            };
            let r = (cross, shift(d[1]), shift(d[2]));
            if !out.contains(&r) {
                out.push(r);
            }
        }
        out
    })
}

/// Whether the crossing on edge `(a, b)` belongs to `a`: it lies nearer `a` (ties: lower index).
#[inline]
fn owns(a: usize, va: f32, b: usize, vb: f32, iso: f32) -> bool {
    let (da, db) = ((va - iso).abs(), (vb - iso).abs());
    da < db || (da == db && a < b)
}

/// Tetrahedra in the lattice: six per cube (Kuhn); four per pair of neighbouring cell centres
/// (BCC, about twelve per cell).
pub fn tetrahedron_count(lattice: &Lattice) -> usize {
    let cells = lattice.grid().dims.map(|d| d.saturating_sub(1));
    match lattice {
        Lattice::Cubic(_) => 6 * cells.iter().product::<usize>(),
        Lattice::Bcc(_) => {
            let [a, b, c] = cells;
            4 * (a.saturating_sub(1) * b * c + a * b.saturating_sub(1) * c + a * b * c.saturating_sub(1))
        }
    }
}

/// Counts of the geometry pass.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TetCounts {
    /// Tetrahedra with a sign change (the paper's N_tetrahedra).
    pub active: usize,
    /// Tetrahedra in the lattice.
    pub total: usize,
    /// Triangles dropped for a repeated vertex.
    pub discarded: usize,
}

/// One slab's vertices and their owners, as the vertex pass made them.
type SlabVertices = (Vec<Vec3>, Vec<(u32, u8, u8)>);

/// What the vertex pass reads: everything but the per-sample outputs.
struct VertexPass<'a> {
    values: &'a [f32],
    iso: f32,
    topo: &'a TetTopology,
    at: &'a Addresser,
    layout: &'a Layout,
    rows: &'a [Vec<Row>],
    row_offsets: [Vec<(bool, isize, isize)>; 2],
    steps: [Vec3; DIRECTIONS],
    no_merge: &'a [bool],
    clustering: &'a dyn Clustering,
    field: Option<&'a dyn Field>,
}

impl VertexPass<'_> {
    /// The vertex pass (Algorithm 2) over sample layers `z0..z1` of grid `p`: flags the samples
    /// with a sign change on an edge (`touch`), and for each sample that owns crossings makes its
    /// vertices (one per island) at the end of `positions`/`owner` and records the first one's
    /// index (`base`, counted from `positions`' start) and each crossing's island (`slots`).
    /// `touch`, `base` and `slots` start at flat sample index `first`.
    #[allow(clippy::too_many_arguments)]
    fn slab(
        &self,
        p: usize,
        z0: usize,
        z1: usize,
        first: usize,
        touch: &mut [bool],
        base: &mut [u32],
        slots: &mut [u64],
        positions: &mut Vec<Vec3>,
        owner: &mut Vec<(u32, u8, u8)>,
        near: &mut Vec<Row>,
    ) -> Result<(), ExtractError> {
        let (values, iso, topo, at) = (self.values, self.iso, self.topo, self.at);
        let layout = self.layout;
        let part = &layout.parts[p];
        let [dx, dy, dz] = part.dims;
        let other = if layout.parts.len() > 1 { 1 - p } else { p };
        for z in z0..z1 {
            for y in 0..dy {
                near.clear();
                for &(cross, oy, oz) in &self.row_offsets[part.odd as usize] {
                    let (g, dims) = if cross { (other, part.cross_dims) } else { (p, part.dims) };
                    let (ry, rz) = (y as isize + oy, z as isize + oz);
                    if ry >= 0 && rz >= 0 && (ry as usize) < dims[1] && (rz as usize) < dims[2] {
                        near.push(self.rows[g][ry as usize + dims[1] * rz as usize]);
                    }
                }
                let Some((lo, hi)) = span(near, dx.max(part.cross_dims[0])) else { continue };
                let row_interior = (1..dy.saturating_sub(1)).contains(&y) && (1..dz.saturating_sub(1)).contains(&z);
                let row_same = part.start + dx * (y + dy * z);
                let row_cross = part.cross_start + part.cross_dims[0] * (y + part.cross_dims[1] * z);
                for x in lo.saturating_sub(1)..(hi + 2).min(dx) {
                    let i = row_same + x;
                    let vi = values[i];
                    let inside = vi < iso;
                    let interior = row_interior && x >= 1 && x + 1 < dx;
                    let q = [2 * x as i32 + part.odd, 2 * y as i32 + part.odd, 2 * z as i32 + part.odd];
                    let neighbour = |k: usize| -> Option<usize> {
                        if interior {
                            let (cross, off) = part.offsets[k];
                            Some(((if cross { row_cross + x } else { i }) as isize + off) as usize)
                        } else {
                            let d = topo.directions[k];
                            at.index([q[0] + d[0], q[1] + d[1], q[2] + d[2]])
                        }
                    };
                    // First the flags only; positions for the rare samples that own a crossing.
                    let (mut nearby, mut neighbours, mut touched) = (0u16, 0u16, false);
                    for k in 0..DIRECTIONS {
                        let Some(j) = neighbour(k) else { continue };
                        neighbours |= 1 << k;
                        let vj = values[j];
                        if (vj < iso) != inside {
                            touched = true;
                            if owns(i, vi, j, vj, iso) {
                                nearby |= 1 << k;
                            }
                        }
                    }
                    touch[i - first] = touched;
                    if nearby == 0 {
                        continue;
                    }
                    let mut star = Star { nearby, neighbours, crossings: [Vec3::ZERO; DIRECTIONS] };
                    let origin = at.position(q);
                    let mut bits = nearby;
                    while bits != 0 {
                        let k = bits.trailing_zeros() as usize;
                        bits &= bits - 1;
                        let vj = values[neighbour(k).expect("flagged neighbours exist")];
                        star.crossings[k] = origin + self.steps[k] * ((iso - vi) / (vj - vi));
                    }
                    let islands =
                        if self.no_merge[i] { NoClustering.islands(&star, topo) } else { self.clustering.islands(&star, topo) };
                    let start = positions.len();
                    if start + islands.count as usize > u32::MAX as usize {
                        return Err(ExtractError::TooLarge {
                            algorithm: "marching tetrahedra",
                            vertices: start + islands.count as usize,
                        });
                    }
                    base[i - first] = start as u32;
                    let mut sums = [Vec3::ZERO; DIRECTIONS];
                    let mut members = [0u32; DIRECTIONS];
                    let mut packed = 0u64;
                    let mut bits = star.nearby;
                    while bits != 0 {
                        let k = bits.trailing_zeros() as usize;
                        bits &= bits - 1;
                        let s = islands.slot[k];
                        sums[s as usize] += star.crossings[k];
                        members[s as usize] += 1;
                        packed |= u64::from(s) << (4 * k);
                    }
                    slots[i - first] = packed;
                    let mut lowest = [u8::MAX; DIRECTIONS];
                    for k in (0..DIRECTIONS).rev().filter(|&k| star.nearby >> k & 1 == 1) {
                        lowest[islands.slot[k] as usize] = k as u8;
                    }
                    for s in 0..islands.count as usize {
                        let mean = sums[s] / members[s] as f32;
                        positions.push(self.clustering.place(mean, members[s], self.field, iso, at.corners.spacing));
                        owner.push((i as u32, members[s].min(255) as u8, lowest[s]));
                    }
                }
            }
        }
        Ok(())
    }
}

/// Marching tetrahedra on `samples` (BCC lattice: [`TetKind::Bcc`]; cubic grid: [`TetKind::Kuhn`])
/// with the given clustering, into `out`. Returns the geometry pass counts.
pub fn extract_tetrahedral(
    samples: &Samples,
    clustering: &dyn Clustering,
    scratch: &mut TetScratch,
    out: &mut Extraction,
) -> Result<TetCounts, ExtractError> {
    out.clear();
    out.stats.times.sampling = samples.sampling_time();
    let lattice = *samples.lattice();
    let topo = topology(TetKind::of(&lattice));
    let at = Addresser::new(&lattice);
    let values = samples.values();
    let iso = samples.iso();
    let field = samples.field().map(|f| f.as_ref() as &dyn Field);

    // Vertex pass.
    let t = Instant::now();
    let n = values.len();
    // Base and slots are read only for samples that own a crossing, which this pass writes, so a
    // reused scratch is not cleared; a new one is allocated zeroed (the OS maps zero pages lazily,
    // so only pages near the surface are ever touched).
    if scratch.base.len() < n {
        scratch.base = vec![0; n];
        scratch.slots = vec![0; n];
    }
    if scratch.touch.len() < n {
        scratch.touch = vec![false; n];
    } else {
        scratch.touch[..n].fill(false);
    }
    if scratch.no_merge.len() < n {
        scratch.no_merge = vec![false; n];
    }
    scratch.owner.clear();
    let layout = Layout::new(&at, topo);
    let half = 0.5 * at.corners.spacing;
    // Row summaries of both grids: a row whose neighbouring rows (in both grids) all share its
    // state has no crossing and is skipped without loading its neighbours.
    let mut rows: Vec<Vec<Row>> = Vec::with_capacity(layout.parts.len());
    for part in &layout.parts {
        let mut r = Vec::new();
        let len = part.dims.iter().product::<usize>();
        classify_rows(&values[part.start..part.start + len], part.dims[0], iso, &mut r);
        rows.push(r);
    }
    let pass = VertexPass {
        values,
        iso,
        topo,
        at: &at,
        layout: &layout,
        rows: &rows,
        row_offsets: row_neighbours(topo),
        steps: topo.directions.map(|d| Vec3::new(d[0] as f32, d[1] as f32, d[2] as f32) * half),
        no_merge: &scratch.no_merge,
        clustering,
        field,
    };
    // Slabs of sample layers, per grid, in index order: each writes its own samples' flags and
    // slots and makes its own vertices; joined in order, the result is the serial pass's.
    let layers: usize = layout.parts.iter().map(|p| p.dims[2]).sum();
    let tasks = crate::slabs::task_count(crate::slabs::Parallelism::Rayon, n, layers);
    let mut slabs: Vec<(usize, usize, usize)> = Vec::new(); // (part, z0, z1)
    for (p, part) in layout.parts.iter().enumerate() {
        let per = tasks.div_ceil(layout.parts.len()).min(part.dims[2]).max(1);
        for k in 0..per {
            slabs.push((p, k * part.dims[2] / per, (k + 1) * part.dims[2] / per));
        }
    }
    if slabs.len() == 1 || tasks == 1 {
        let mut near = Vec::with_capacity(16);
        let (touch, base, slots) = (&mut scratch.touch[..], &mut scratch.base[..], &mut scratch.slots[..]);
        for &(p, z0, z1) in &slabs {
            pass.slab(p, z0, z1, 0, touch, base, slots, &mut out.surface.positions, &mut scratch.owner, &mut near)?;
        }
    } else {
        // Disjoint sample ranges for the slabs.
        let mut work = Vec::with_capacity(slabs.len());
        let (mut touch, mut base, mut slots) = (&mut scratch.touch[..n], &mut scratch.base[..n], &mut scratch.slots[..n]);
        let mut at_index = 0usize;
        for &(p, z0, z1) in &slabs {
            let part = &layout.parts[p];
            let first = part.start + part.dims[0] * part.dims[1] * z0;
            let last = part.start + part.dims[0] * part.dims[1] * z1;
            let skip = first - at_index;
            let (t, rest_t) = std::mem::take(&mut touch)[skip..].split_at_mut(last - first);
            let (b, rest_b) = std::mem::take(&mut base)[skip..].split_at_mut(last - first);
            let (s, rest_s) = std::mem::take(&mut slots)[skip..].split_at_mut(last - first);
            (touch, base, slots) = (rest_t, rest_b, rest_s);
            at_index = last;
            work.push(((p, z0, z1, first), t, b, s));
        }
        let made: Vec<Result<SlabVertices, ExtractError>> = work
            .into_par_iter()
            .map(|((p, z0, z1, first), t, b, s)| {
                let (mut positions, mut owner, mut near) = (Vec::new(), Vec::new(), Vec::with_capacity(16));
                pass.slab(p, z0, z1, first, t, b, s, &mut positions, &mut owner, &mut near)?;
                Ok((positions, owner))
            })
            .collect();
        for result in made {
            let (positions, owner) = result?;
            let offset = out.surface.positions.len();
            if offset + positions.len() > u32::MAX as usize {
                return Err(ExtractError::TooLarge { algorithm: "marching tetrahedra", vertices: offset + positions.len() });
            }
            // Each sample's vertices are consecutive: its base is its first one's index.
            let mut previous = u32::MAX;
            for (k, &(sample, _, _)) in owner.iter().enumerate() {
                if sample != previous {
                    scratch.base[sample as usize] = (offset + k) as u32;
                    previous = sample;
                }
            }
            out.surface.positions.extend_from_slice(&positions);
            scratch.owner.extend_from_slice(&owner);
        }
    }
    out.stats.times.vertex = t.elapsed();

    out.stats.times.vertex = t.elapsed();
    let counts = geometry_pass(samples, scratch, out);
    let t = Instant::now();
    out.surface.compute_face_weighted_normals();
    out.stats.times.normals = t.elapsed();
    Ok(counts)
}

/// The geometry pass (Algorithm 3) over the vertex indices in `scratch`, replacing
/// `out.surface.triangles`; sets the geometry time and the counts in `out.stats`.
pub fn geometry_pass(samples: &Samples, scratch: &TetScratch, out: &mut Extraction) -> TetCounts {
    let lattice = *samples.lattice();
    let topo = topology(TetKind::of(&lattice));
    let at = Addresser::new(&lattice);
    let layout = Layout::new(&at, topo);
    let values = samples.values();
    let iso = samples.iso();
    out.surface.triangles.clear();
    let t = Instant::now();
    let mut counts = TetCounts::default();
    let vertex_of = |a: usize, va: f32, b: usize, vb: f32, dir_ab: u8| -> u32 {
        let (o, k) = if owns(a, va, b, vb, iso) { (a, dir_ab) } else { (b, dir_ab ^ 1) };
        scratch.base[o] + ((scratch.slots[o] >> (4 * k)) & 0xf) as u32
    };
    // Anchors: BCC cell centres (every tetrahedron around a centre contains it), or cubes' low
    // corners (every Kuhn tetrahedron of a cube contains it). An anchor with no sign change on
    // its edges has no surface in any of its tetrahedra.
    let anchor_part = match topo.kind {
        TetKind::Bcc => &layout.parts[1],
        TetKind::Kuhn => &layout.parts[0],
    };
    let anchor_dims = match topo.kind {
        TetKind::Bcc => anchor_part.dims,
        TetKind::Kuhn => anchor_part.dims.map(|d| d - 1),
    };
    counts.total = match topo.kind {
        TetKind::Bcc => {
            let d = anchor_dims;
            4 * ((d[0].saturating_sub(1)) * d[1] * d[2]
                + d[0] * d[1].saturating_sub(1) * d[2]
                + d[0] * d[1] * d[2].saturating_sub(1))
        }
        TetKind::Kuhn => 6 * anchor_dims.iter().product::<usize>(),
    };
    let template_offsets: Vec<[(bool, isize); 4]> = topo.templates.iter().map(|t| t.map(|d| anchor_part.offset_of(d))).collect();
    let positions = &out.surface.positions;
    let [ax, ay, az] = anchor_dims;
    let [dx, dy, _] = anchor_part.dims;
    // The triangles of anchor layers `z0..z1`, in order, and their counts.
    let layers = |z0: usize, z1: usize, triangles: &mut Vec<[u32; 3]>, counts: &mut TetCounts| {
        for z in z0..z1 {
            for y in 0..ay {
                let row_same = anchor_part.start + dx * (y + dy * z);
                let row_cross = anchor_part.cross_start + anchor_part.cross_dims[0] * (y + anchor_part.cross_dims[1] * z);
                // BCC: every template exists when the anchor's +x, +y, +z neighbours do.
                let row_full = topo.kind == TetKind::Kuhn || (y + 1 < ay && z + 1 < az);
                for x in 0..ax {
                    let i = row_same + x;
                    if !scratch.touch[i] {
                        continue;
                    }
                    let full = row_full && (topo.kind == TetKind::Kuhn || x + 1 < ax);
                    let q = [2 * x as i32 + anchor_part.odd, 2 * y as i32 + anchor_part.odd, 2 * z as i32 + anchor_part.odd];
                    for (t, offsets) in template_offsets.iter().enumerate() {
                        let idx = if full {
                            offsets.map(|(cross, off)| ((if cross { row_cross + x } else { i }) as isize + off) as usize)
                        } else {
                            let template = &topo.templates[t];
                            let mut idx = [0usize; 4];
                            let mut valid = true;
                            for (v, d) in idx.iter_mut().zip(template) {
                                match at.index([q[0] + d[0], q[1] + d[1], q[2] + d[2]]) {
                                    Some(j) => *v = j,
                                    None => valid = false,
                                }
                            }
                            if !valid {
                                continue;
                            }
                            idx
                        };
                        let v = idx.map(|i| values[i]);
                        let case = usize::from(v[0] < iso)
                            | usize::from(v[1] < iso) << 1
                            | usize::from(v[2] < iso) << 2
                            | usize::from(v[3] < iso) << 3;
                        let entry = &MT_TABLE[case];
                        if entry.count == 0 {
                            continue;
                        }
                        counts.active += 1;
                        let dirs = &topo.edge_directions[t];
                        let mut ids = [0u32; 4];
                        for (k, &(a, b)) in entry.edges[..entry.count as usize].iter().enumerate() {
                            let (a, b) = (a as usize, b as usize);
                            ids[k] = vertex_of(idx[a], v[a], idx[b], v[b], dirs[a][b]);
                        }
                        if entry.count == 3 {
                            push_triangle([ids[0], ids[1], ids[2]], triangles, &mut counts.discarded);
                        } else {
                            let [a, b, c, d] = ids;
                            let along_ac = if a == c {
                                true
                            } else if b == d {
                                false
                            } else {
                                let p = |i: u32| positions[i as usize];
                                p(a).distance_squared(p(c)) <= p(b).distance_squared(p(d))
                            };
                            let halves = if along_ac { [[a, b, c], [a, c, d]] } else { [[a, b, d], [b, c, d]] };
                            for h in halves {
                                push_triangle(h, triangles, &mut counts.discarded);
                            }
                        }
                    }
                }
            }
        }
    };
    let mut triangles = std::mem::take(&mut out.surface.triangles);
    let tasks = crate::slabs::task_count(crate::slabs::Parallelism::Rayon, ax * ay * az, az);
    if tasks <= 1 {
        layers(0, az, &mut triangles, &mut counts);
    } else {
        // Slabs of anchor layers, joined in order: the serial pass's triangles.
        let slabs: Vec<(Vec<[u32; 3]>, TetCounts)> = (0..tasks)
            .into_par_iter()
            .map(|k| {
                let (mut part, mut c) = (Vec::new(), TetCounts::default());
                layers(k * az / tasks, (k + 1) * az / tasks, &mut part, &mut c);
                (part, c)
            })
            .collect();
        for (part, c) in slabs {
            triangles.extend_from_slice(&part);
            counts.active += c.active;
            counts.discarded += c.discarded;
        }
    }
    out.surface.triangles = triangles;
    out.stats.times.geometry = t.elapsed();
    out.stats.discarded_triangles = counts.discarded;
    out.stats.active_cells = counts.active;
    counts
}

/// Forbids merging at the samples that made the merged vertices among `vertices`, gives each of
/// their crossings its own new vertex, and runs the geometry pass again. Returns whether anything
/// changed. The old merged vertices stay in `out.surface.positions`, unreferenced, until
/// [`finish_repair`].
pub fn unmerge_and_regenerate(samples: &Samples, scratch: &mut TetScratch, out: &mut Extraction, vertices: &[u32]) -> bool {
    let lattice = *samples.lattice();
    let topo = topology(TetKind::of(&lattice));
    let at = Addresser::new(&lattice);
    let values = samples.values();
    let iso = samples.iso();
    let mut changed = false;
    for &v in vertices {
        let Some(&(sample, members, _)) = scratch.owner.get(v as usize) else { continue };
        let i = sample as usize;
        if members < 2 || scratch.no_merge[i] {
            continue;
        }
        scratch.no_merge[i] = true;
        changed = true;
        let q = at.coords(i);
        let (vi, base) = (values[i], out.surface.positions.len() as u32);
        let mut packed = 0u64;
        let mut slot = 0u64;
        for (k, d) in topo.directions.iter().enumerate() {
            let Some(j) = at.index([q[0] + d[0], q[1] + d[1], q[2] + d[2]]) else { continue };
            let vj = values[j];
            if (vj < iso) != (vi < iso) && owns(i, vi, j, vj, iso) {
                let step = Vec3::new(d[0] as f32, d[1] as f32, d[2] as f32) * (0.5 * at.corners.spacing);
                out.surface.positions.push(at.position(q) + step * ((iso - vi) / (vj - vi)));
                scratch.owner.push((sample, 1, k as u8));
                packed |= slot << (4 * k);
                slot += 1;
            }
        }
        scratch.base[i] = base;
        scratch.slots[i] = packed;
    }
    if changed {
        let time = out.stats.times.geometry;
        geometry_pass(samples, scratch, out);
        out.stats.times.geometry += time;
    }
    changed
}

/// After repairs: drops vertices no triangle uses (renumbering the rest in order) and
/// recomputes the normals.
pub fn finish_repair(out: &mut Extraction) {
    let t = Instant::now();
    let mesh = &mut out.surface;
    let mut used = vec![u32::MAX; mesh.positions.len()];
    for t in &mesh.triangles {
        for &v in t {
            used[v as usize] = 0;
        }
    }
    let mut next = 0u32;
    for (v, u) in used.iter_mut().enumerate() {
        if *u == 0 {
            *u = next;
            mesh.positions[next as usize] = mesh.positions[v];
            next += 1;
        }
    }
    mesh.positions.truncate(next as usize);
    let origins = &mut out.origins.vertices;
    if origins.len() == used.len() {
        for (v, &u) in used.iter().enumerate() {
            if u != u32::MAX {
                origins[u as usize] = origins[v];
            }
        }
        origins.truncate(next as usize);
    }
    for t in &mut mesh.triangles {
        *t = t.map(|v| used[v as usize]);
    }
    mesh.compute_face_weighted_normals();
    out.stats.times.normals = t.elapsed();
}

#[inline]
fn push_triangle(t: [u32; 3], triangles: &mut Vec<[u32; 3]>, discarded: &mut usize) {
    if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
        *discarded += 1;
    } else {
        triangles.push(t);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_star_is_a_sphere_of_24_tetrahedra() {
        for kind in [TetKind::Bcc, TetKind::Kuhn] {
            let t = topology(kind);
            // Link of a vertex: 14 vertices, 36 edges, 24 triangles (Euler 2).
            let edges: u32 = t.adjacency.iter().map(|a| a.count_ones()).sum::<u32>() / 2;
            assert_eq!(edges, 36, "{kind:?}");
            // Tetrahedra per sample: four vertices each, over the samples per anchor cell.
            let samples_per_cell = if kind == TetKind::Bcc { 2 } else { 1 };
            assert_eq!(t.templates.len() * 4 / samples_per_cell, 24, "{kind:?}");
            for a in t.adjacency {
                assert!(a.count_ones() >= 4);
            }
            for k in 0..DIRECTIONS {
                for j in 0..DIRECTIONS {
                    assert_eq!(t.adjacency[k] >> j & 1, t.adjacency[j] >> k & 1, "symmetric");
                }
                assert_eq!(t.adjacency[k] >> (k ^ 1) & 1, 0, "opposite neighbours are never adjacent");
            }
        }
    }

    #[test]
    fn templates_are_positive_and_congruent() {
        for kind in [TetKind::Bcc, TetKind::Kuhn] {
            let t = topology(kind);
            let volumes: Vec<i64> = t.templates.iter().map(orientation).collect();
            assert!(volumes.iter().all(|&v| v == volumes[0] && v > 0), "{kind:?} {volumes:?}");
        }
    }

    #[test]
    fn bcc_dihedral_angles_are_60_and_90_degrees() {
        let t = &topology(TetKind::Bcc).templates[0];
        let p = t.map(|q| Vec3::new(q[0] as f32, q[1] as f32, q[2] as f32));
        let mut angles = Vec::new();
        for i in 0..4 {
            for j in i + 1..4 {
                let others: Vec<usize> = (0..4).filter(|&k| k != i && k != j).collect();
                let e = (p[j] - p[i]).normalize();
                let perp = |k: usize| {
                    let v = p[k] - p[i];
                    (v - e * v.dot(e)).normalize()
                };
                angles.push(perp(others[0]).dot(perp(others[1])).clamp(-1.0, 1.0).acos().to_degrees());
            }
        }
        angles.sort_by(f32::total_cmp);
        for (a, want) in angles.iter().zip([60.0, 60.0, 60.0, 60.0, 90.0, 90.0]) {
            assert!((a - want).abs() < 1e-3, "{angles:?}");
        }
    }

    #[test]
    fn the_table_has_one_triangle_or_one_quad_per_mixed_case() {
        for (c, e) in MT_TABLE.iter().enumerate() {
            let inside = (c as u32).count_ones();
            let want = match inside {
                0 | 4 => 0,
                1 | 3 => 3,
                _ => 4,
            };
            assert_eq!(e.count, want, "case {c}");
            for &(a, b) in &e.edges[..e.count as usize] {
                assert!(c >> a & 1 == 1 && c >> b & 1 == 0, "case {c}: edges run inside to outside");
            }
        }
    }
}
