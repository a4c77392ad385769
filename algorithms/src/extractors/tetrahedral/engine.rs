//! The two passes marching tetrahedra and RMT share (Costen 2026, Algorithms 2 and 3): the
//! vertex pass (each sample's nearby crossings, handed to a [`Clustering`]) and the geometry pass
//! (each tetrahedron's case), both in slabs of layers on rayon, joined in order.
//!
//! **Why one file of about 700 lines.** The two passes, their slab join and the driver share the
//! per-slab scratch (the vertex indices of two layers, the packed signs, the clustering's state);
//! split apart they would pass it through every signature. The geometry of a tetrahedron's case
//! (`geometry`), the guard (`repair`, `folds`) and the lattices (`topology`) are already rooms of
//! their own.

use super::{geometry_pass, topology, TetKind, TetTopology, DIRECTIONS};
use crate::extract::{ExtractError, Extraction};
use crate::field::Field;
use crate::geometry::edge_crossing_fraction;
use crate::lattice::{Grid, Lattice};
use crate::samples::Samples;
use crate::sweep::sign_rows::{classify_rows, range_mask, span, GridSigns, Row};
use glam::Vec3;
use rayon::prelude::*;
use std::time::Instant;

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
    pub(super) base: Vec<u32>,
    pub(super) slots: Vec<u64>,
    /// Samples with a sign change on one of their edges.
    pub(super) touch: Vec<bool>,
    /// Samples whose crossings must not merge (set by a repairing caller).
    pub(super) no_merge: Vec<bool>,
    /// The sample that made each vertex, how many crossings it merged, and the lowest of their
    /// directions (with the sample, a key for the vertex that does not depend on the lattice's
    /// extent).
    pub(super) owner: Vec<(u32, u8, u8)>,
    // Everything below is kept so that re-meshing a same-sized chunk allocates nothing.
    /// BCC: row summaries of both grids, and the rows around one row.
    pub(super) rows: Vec<Vec<Row>>,
    pub(super) near: Vec<Row>,
    /// Kuhn (cubic grids): every sample's sign, 64 to a word.
    pub(super) signs: GridSigns,
    /// The vertex pass's slabs: (grid, first layer, end layer).
    pub(super) slabs: Vec<(usize, usize, usize)>,
    /// The index layout of the last lattice meshed (rebuilt when the lattice's shape changes).
    pub(super) plan: Option<Plan>,
    /// The last geometry pass's surface anchors, in order: flat index and first triangle; valid
    /// once a geometry pass ran on the current samples.
    pub(super) anchors: Vec<(u32, u32)>,
    pub(super) anchors_valid: bool,
    /// A partial re-pass's spare triangle buffer and the anchors it re-emits.
    pub(super) next_triangles: Vec<[u32; 3]>,
    pub(super) affected: Vec<u32>,
    /// The samples one repair unmerged.
    pub(super) unmerged: Vec<usize>,
    /// The vertices of the triangles the last partial re-pass removed or made (with repeats);
    /// valid when `rewritten_valid` (a whole pass leaves it invalid).
    pub(super) rewritten: Vec<u32>,
    pub(super) rewritten_valid: bool,
}

/// What both passes derive from a lattice's shape alone: the grids' index layout, the rows a
/// sample's neighbours lie in, and the tetrahedra templates' index offsets from their anchor.
#[derive(Clone, Debug)]
pub(super) struct Plan {
    kind: TetKind,
    dims: [usize; 3],
    pub(super) layout: Layout,
    pub(super) row_offsets: [Vec<(bool, isize, isize)>; 2],
    pub(super) template_offsets: Vec<[(bool, isize); 4]>,
}

impl Plan {
    pub(super) fn new(lattice: &Lattice) -> Plan {
        let topo = topology(TetKind::of(lattice));
        let at = Addresser::new(lattice);
        let layout = Layout::new(&at, topo);
        let anchor_part = match topo.kind {
            TetKind::Bcc => &layout.parts[1],
            TetKind::Kuhn => &layout.parts[0],
        };
        let template_offsets = topo.templates.iter().map(|t| t.map(|d| anchor_part.offset_of(d))).collect();
        Plan { kind: topo.kind, dims: lattice.grid().dims, row_offsets: row_neighbours(topo), template_offsets, layout }
    }

    /// Whether this plan was made for a lattice of `lattice`'s kind and shape.
    pub(super) fn fits(&self, lattice: &Lattice) -> bool {
        self.kind == TetKind::of(lattice) && self.dims == lattice.grid().dims
    }
}

impl TetScratch {
    /// Bytes held.
    pub fn bytes(&self) -> usize {
        self.base.capacity() * 4
            + self.slots.capacity() * 8
            + self.touch.capacity()
            + self.no_merge.capacity()
            + self.owner.capacity() * 8
            + (self.rows.iter().map(Vec::capacity).sum::<usize>() + self.near.capacity()) * std::mem::size_of::<Row>()
            + self.signs.capacity_bytes()
            + self.anchors.capacity() * 8
            + self.next_triangles.capacity() * 12
            + self.affected.capacity() * 4
            + self.unmerged.capacity() * 8
            + self.rewritten.capacity() * 4
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

    /// Whether vertex `v` merged two or more crossings and stands (its sample not unmerged
    /// since): only those can be unmerged.
    pub fn is_merged(&self, v: u32) -> bool {
        self.owner.get(v as usize).is_some_and(|&(sample, members, _)| members >= 2 && !self.no_merge[sample as usize])
    }

    /// The vertices whose triangles the last repair's re-pass changed (removed or made, with
    /// repeats), or `None` when it ran the whole geometry pass (BCC lattices): elsewhere every
    /// vertex's triangles are as before the repair.
    pub fn rewritten_vertices(&self) -> Option<&[u32]> {
        self.rewritten_valid.then_some(&self.rewritten[..])
    }
}

/// Sample addressing in doubled coordinates.
pub(super) struct Addresser {
    pub(super) corners: Grid,
    pub(super) centres: Option<Grid>,
    /// Largest doubled coordinate on each axis.
    pub(super) max: [i32; 3],
}

impl Addresser {
    pub(super) fn new(lattice: &Lattice) -> Addresser {
        let corners = *lattice.grid();
        let centres = matches!(lattice, Lattice::Bcc(_)).then(|| corners.centres());
        Addresser { corners, centres, max: corners.dims.map(|n| 2 * (n as i32 - 1)) }
    }

    /// Flat index of the sample at doubled coordinates `q`, if the lattice has one there.
    #[inline]
    pub(super) fn index(&self, q: [i32; 3]) -> Option<usize> {
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
    pub(super) fn coords(&self, i: usize) -> [i32; 3] {
        let (g, i, odd) = match &self.centres {
            Some(c) if i >= self.corners.len() => (c, i - self.corners.len(), 1),
            _ => (&self.corners, i, 0),
        };
        let [nx, ny, _] = g.dims;
        [(i % nx) as i32 * 2 + odd, ((i / nx) % ny) as i32 * 2 + odd, (i / (nx * ny)) as i32 * 2 + odd]
    }

    pub(super) fn position(&self, q: [i32; 3]) -> Vec3 {
        self.corners.origin + Vec3::new(q[0] as f32, q[1] as f32, q[2] as f32) * (0.5 * self.corners.spacing)
    }
}

/// One of the lattice's cubic grids (corners, or BCC centres) and the constant index offsets of
/// the neighbours of its interior samples.
#[derive(Clone, Debug)]
pub(super) struct Part {
    /// 0 for corners, 1 for centres (added to doubled coordinates).
    pub(super) odd: i32,
    /// First flat index and samples per axis.
    pub(super) start: usize,
    pub(super) dims: [usize; 3],
    /// The other grid (BCC), or this one again.
    pub(super) cross_start: usize,
    pub(super) cross_dims: [usize; 3],
    /// Per direction: whether the neighbour is in the other grid, and its index offset from
    /// `(x, y, z)` in that grid's order.
    pub(super) offsets: [(bool, isize); DIRECTIONS],
}

impl Part {
    /// The grid and index offset of the sample at doubled offset `d` from one of this grid's
    /// samples, in the same form as [`Part::offsets`].
    pub(super) fn offset_of(&self, d: [i32; 3]) -> (bool, isize) {
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

#[derive(Clone, Debug)]
pub(super) struct Layout {
    pub(super) parts: Vec<Part>,
}

impl Layout {
    pub(super) fn new(at: &Addresser, topo: &TetTopology) -> Layout {
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
pub(super) fn row_neighbours(topo: &TetTopology) -> [Vec<(bool, isize, isize)>; 2] {
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
pub(super) fn owns(a: usize, va: f32, b: usize, vb: f32, iso: f32) -> bool {
    let (da, db) = ((va - iso).abs(), (vb - iso).abs());
    da < db || (da == db && a < b)
}

/// [`owns`] without a branch, for the vertex pass's inner loop.
#[inline]
fn owns_branchless(a: usize, va: f32, b: usize, vb: f32, iso: f32) -> bool {
    let (da, db) = ((va - iso).abs(), (vb - iso).abs());
    (da < db) | ((da == db) & (a < b))
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
pub(super) struct VertexPass<'a> {
    pub(super) values: &'a [f32],
    pub(super) iso: f32,
    pub(super) topo: &'a TetTopology,
    pub(super) at: &'a Addresser,
    pub(super) layout: &'a Layout,
    pub(super) rows: &'a [Vec<Row>],
    /// Kuhn: the grid's signs, which find the samples with a crossing 64 at a time (the rows
    /// above are then not used).
    pub(super) signs: Option<&'a GridSigns>,
    pub(super) row_offsets: &'a [Vec<(bool, isize, isize)>; 2],
    pub(super) steps: [Vec3; DIRECTIONS],
    pub(super) no_merge: &'a [bool],
    pub(super) clustering: &'a dyn Clustering,
    pub(super) field: Option<&'a dyn Field>,
}

impl VertexPass<'_> {
    /// The vertex pass (Algorithm 2) over sample layers `z0..z1` of grid `p`: flags the samples
    /// with a sign change on an edge (`touch`), and for each sample that owns crossings makes its
    /// vertices (one per island) at the end of `positions`/`owner` and records the first one's
    /// index (`base`, counted from `positions`' start) and each crossing's island (`slots`).
    /// `touch`, `base` and `slots` start at flat sample index `first`.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn slab(
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
        let sample_offsets = topo.directions.map(|d| d.map(|c| c as isize / 2));
        for z in z0..z1 {
            for y in 0..dy {
                // The samples of the row that may own a crossing, as words of bits: on a cubic
                // grid exactly those with a sign change on one of their 14 edges; on the BCC
                // lattice the x-range where the rows around may differ.
                let span_xs = match self.signs {
                    Some(_) => None,
                    None => {
                        near.clear();
                        for &(cross, oy, oz) in &self.row_offsets[part.odd as usize] {
                            let (g, dims) = if cross { (other, part.cross_dims) } else { (p, part.dims) };
                            let (ry, rz) = (y as isize + oy, z as isize + oz);
                            if ry >= 0 && rz >= 0 && (ry as usize) < dims[1] && (rz as usize) < dims[2] {
                                near.push(self.rows[g][ry as usize + dims[1] * rz as usize]);
                            }
                        }
                        let Some((lo, hi)) = span(near, dx.max(part.cross_dims[0])) else { continue };
                        Some((lo.saturating_sub(1), (hi + 1).min(dx - 1)))
                    }
                };
                let row_interior = (1..dy.saturating_sub(1)).contains(&y) && (1..dz.saturating_sub(1)).contains(&z);
                let row_same = part.start + dx * (y + dy * z);
                let row_cross = part.cross_start + part.cross_dims[0] * (y + part.cross_dims[1] * z);
                for w in 0..dx.div_ceil(64) {
                    // Cubic grid: per direction, the samples of the word whose neighbour that way
                    // has the other sign (none where it lies outside the grid).
                    let toward = self.signs.map(|signs| signs.changes_toward_each(y, z, &sample_offsets, w));
                    let mut m = match (toward, span_xs) {
                        (Some(toward), _) => toward.iter().fold(0, |m, &c| m | c),
                        (None, Some((lo, hi))) => range_mask(w, lo, hi),
                        (None, None) => 0,
                    };
                    while m != 0 {
                        let bit = m.trailing_zeros();
                        let x = 64 * w + bit as usize;
                        m &= m - 1;
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
                        let (mut nearby, mut changes) = (0u16, 0u16);
                        let neighbours: u16;
                        if let Some(toward) = &toward {
                            // The sign changes come from the sign bits; only the edges that change
                            // are read (a neighbour that exists is at the same index offset on
                            // the grid's boundary as inside it).
                            changes = toward.iter().enumerate().fold(0, |c, (k, &t)| c | ((t >> bit) as u16 & 1) << k);
                            let mut bits = changes;
                            while bits != 0 {
                                let k = bits.trailing_zeros() as usize;
                                bits &= bits - 1;
                                let j = (i as isize + part.offsets[k].1) as usize;
                                nearby |= u16::from(owns_branchless(i, vi, j, values[j], iso)) << k;
                            }
                            neighbours = if interior || nearby == 0 {
                                (1 << DIRECTIONS) - 1
                            } else {
                                (0..DIRECTIONS).fold(0, |n, k| n | u16::from(neighbour(k).is_some()) << k)
                            };
                        } else if interior {
                            // No branch on the signs: at surface samples they are unpredictable.
                            neighbours = (1 << DIRECTIONS) - 1;
                            let from = [i, row_cross + x];
                            for (k, &(cross, off)) in part.offsets.iter().enumerate() {
                                let j = (from[usize::from(cross)] as isize + off) as usize;
                                let vj = values[j];
                                let change = (vj < iso) != inside;
                                changes |= u16::from(change) << k;
                                nearby |= u16::from(change & owns_branchless(i, vi, j, vj, iso)) << k;
                            }
                        } else {
                            let present = (0..DIRECTIONS).fold(0u16, |n, k| n | u16::from(neighbour(k).is_some()) << k);
                            // On the border only the edges of the lattice's tetrahedra (a
                            // crossing on any other would be a vertex no triangle uses).
                            neighbours = topo.edges_in_tetrahedra(present);
                            for k in (0..DIRECTIONS).filter(|&k| neighbours >> k & 1 == 1) {
                                let Some(j) = neighbour(k) else { continue };
                                let vj = values[j];
                                if (vj < iso) != inside {
                                    changes |= 1 << k;
                                    if owns(i, vi, j, vj, iso) {
                                        nearby |= 1 << k;
                                    }
                                }
                            }
                        }
                        touch[i - first] = changes != 0;
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
                            star.crossings[k] = origin + self.steps[k] * edge_crossing_fraction(vi, vj, iso);
                        }
                        let islands = if self.no_merge[i] {
                            NoClustering.islands(&star, topo)
                        } else {
                            self.clustering.islands(&star, topo)
                        };
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
        }
        Ok(())
    }
}

/// Marching tetrahedra on `samples` (BCC lattice: [`TetKind::Bcc`]; cubic grid: [`TetKind::Kuhn`])
/// with the given clustering, into `out` (which arrives cleared: [`crate::Extractor::extract`]
/// clears it), without normals ([`compute_normals`]). Returns the geometry pass counts.
pub fn extract_tetrahedral(
    samples: &Samples,
    clustering: &dyn Clustering,
    scratch: &mut TetScratch,
    out: &mut Extraction,
) -> Result<TetCounts, ExtractError> {
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
    // Cleared: a reused scratch holds the previous call's repairs.
    if scratch.no_merge.len() < n {
        scratch.no_merge = vec![false; n];
    } else {
        scratch.no_merge[..n].fill(false);
    }
    scratch.owner.clear();
    scratch.anchors_valid = false;
    if !scratch.plan.as_ref().is_some_and(|p| p.fits(&lattice)) {
        scratch.plan = Some(Plan::new(&lattice));
    }
    let plan = scratch.plan.as_ref().expect("made above");
    let layout = &plan.layout;
    let half = 0.5 * at.corners.spacing;
    // Row summaries of both grids: a row whose neighbouring rows (in both grids) all share its
    // state has no crossing and is skipped without loading its neighbours.
    // Kuhn: every sample's sign instead (the samples with a crossing are found from them).
    let kuhn = topo.kind == TetKind::Kuhn;
    if kuhn {
        scratch.signs.classify(values, at.corners.dims, iso);
    } else {
        scratch.rows.resize_with(layout.parts.len(), Vec::new);
        for (part, r) in layout.parts.iter().zip(&mut scratch.rows) {
            let len = part.dims.iter().product::<usize>();
            classify_rows(&values[part.start..part.start + len], part.dims[0], iso, r);
        }
    }
    let pass = VertexPass {
        values,
        iso,
        topo,
        at: &at,
        layout,
        rows: &scratch.rows,
        signs: kuhn.then_some(&scratch.signs),
        row_offsets: &plan.row_offsets,
        steps: topo.directions.map(|d| Vec3::new(d[0] as f32, d[1] as f32, d[2] as f32) * half),
        no_merge: &scratch.no_merge,
        clustering,
        field,
    };
    // Slabs of sample layers, per grid, in index order: each writes its own samples' flags and
    // slots and makes its own vertices; joined in order, the result is the serial pass's.
    let layers: usize = layout.parts.iter().map(|p| p.dims[2]).sum();
    let tasks = crate::sweep::slabs::task_count(crate::sweep::slabs::Parallelism::Rayon, n, layers);
    let slabs = &mut scratch.slabs; // (part, z0, z1)
    slabs.clear();
    for (p, part) in layout.parts.iter().enumerate() {
        let per = tasks.div_ceil(layout.parts.len()).min(part.dims[2]).max(1);
        for k in 0..per {
            slabs.push((p, k * part.dims[2] / per, (k + 1) * part.dims[2] / per));
        }
    }
    if slabs.len() == 1 || tasks == 1 {
        let near = &mut scratch.near;
        let (touch, base, slots) = (&mut scratch.touch[..], &mut scratch.base[..], &mut scratch.slots[..]);
        for &(p, z0, z1) in slabs.iter() {
            pass.slab(p, z0, z1, 0, touch, base, slots, &mut out.surface.positions, &mut scratch.owner, near)?;
        }
    } else {
        // Disjoint sample ranges for the slabs.
        let mut work = Vec::with_capacity(slabs.len());
        let (mut touch, mut base, mut slots) = (&mut scratch.touch[..n], &mut scratch.base[..n], &mut scratch.slots[..n]);
        let mut at_index = 0usize;
        for &(p, z0, z1) in slabs.iter() {
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
    Ok(geometry_pass(samples, scratch, out))
}

/// The area-weighted vertex normals of `out`'s surface (section 3.1.2), timed as its normals
/// stage. Run by the extractors once their triangles are final.
pub fn compute_normals(out: &mut Extraction) {
    let t = Instant::now();
    out.surface.compute_face_weighted_normals();
    out.stats.times.normals = t.elapsed();
}
