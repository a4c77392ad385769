//! One slab's sweep of the dual engine: each surface cell's pieces and their vertices (mass point
//! or quadric minimum), each crossing edge's quad, two cell layers of vertex indices at a time,
//! and the cube tables it reads.

use super::boundary::{boundary_split, BoundaryPieces, SPLIT};
use super::slab_out::{Piece, SlabCount, SweepOut, TriangleOut};
use super::{qef, Placement, Slab};
use crate::geometry::trilinear_gradient;
use crate::lattice::Grid;
use crate::sweep::sign_rows::{count_crossing_edges, for_each_bit, for_each_surface_cell, next_bits, span, LayerSigns};
use crate::sweep::slabs::EXTERN;
use crate::tables::marching_cubes::{
    face_edges, opposite_face, Case, CORNERS, EDGES, FACES, FACE_CHOICE_TABLE, RING_FACES, TABLE,
};
use glam::Vec3;
use std::time::Instant;

pub(super) struct Ctx<'a> {
    pub(super) values: &'a [f32],
    pub(super) grid: Grid,
    pub(super) iso: f32,
    pub(super) placement: Placement,
    pub(super) field: Option<&'a dyn crate::field::Field>,
    pub(super) tables: Tables,
    /// Whether the sweep computes vertex normals (not when smoothing moves the vertices: their
    /// normals are computed once, after it).
    pub(super) sweep_normals: bool,
    /// Whether each vertex's cell corner is kept (`cell_min`): smoothing clamps to the cell and
    /// chunked meshing names the owner cell; otherwise it is not written at all, a fifth less
    /// output to write (and, on parallel slabs, to copy).
    pub(super) keep_cell_min: bool,
}

impl Ctx<'_> {
    #[inline]
    pub(super) fn inside(&self, i: usize) -> bool {
        self.values[i] < self.iso
    }

    /// The sign case of cell `(x, y, z)` (bit `c` set: table corner `c` inside).
    pub(super) fn cell_case(&self, x: usize, y: usize, z: usize) -> u8 {
        let [nx, ny, _] = self.grid.dims;
        let i = self.grid.index(x, y, z);
        CORNERS.iter().enumerate().fold(0u8, |case, (bit, c)| {
            let k = i + c[0] as usize + nx * (c[1] as usize + ny * c[2] as usize);
            case | u8::from(self.inside(k)) << bit
        })
    }

    /// The faces of cell `(x, y, z)` whose inside corners are joined: the ring faces
    /// ([`RING_FACES`]) that are ring faces of the neighbouring cell too. Both cells of a face
    /// compute the same answer.
    pub(super) fn joined_faces(&self, case: u8, x: usize, y: usize, z: usize) -> u8 {
        let rings = self.tables.rings[case as usize];
        if rings == 0 {
            return 0;
        }
        let cells = self.grid.dims.map(|n| n as isize - 1);
        (0..6).filter(|&f| rings >> f & 1 == 1).fold(0u8, |joins, f| {
            let d = FACES[f].1;
            let n = [x as isize + d[0] as isize, y as isize + d[1] as isize, z as isize + d[2] as isize];
            if (0..3).any(|k| n[k] < 0 || n[k] >= cells[k]) {
                return joins;
            }
            let other = self.cell_case(n[0] as usize, n[1] as usize, n[2] as usize);
            joins | u8::from(self.tables.rings[other as usize] >> opposite_face(f) & 1 == 1) << f
        })
    }

    /// Vertices of the surface cells in cell layer `z`: one per separate piece of surface in the
    /// cell (the polygons of its marching cubes case), at the mean of that piece's edge crossings.
    /// `base` gets each cell's first vertex index and `cases` its [`Tables::entry`] code; `cell_min`,
    /// when given, each vertex's cell corner (the ghost layer below a slab needs none).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn cell_vertices(
        &self,
        signs: &LayerSigns,
        z: usize,
        tag: u32,
        base: &mut [u32],
        cases: &mut [u16],
        mesh: &mut impl SweepOut,
        mut cell_min: Option<&mut Vec<Vec3>>,
    ) {
        let [nx, ny, _] = self.grid.dims;
        let (sx, sxy) = (nx, nx * ny);
        let first_normal = mesh.vertex_count();
        self.for_each_surface_cell_of_layer(signs, z, |x, y, i, case| {
            let idx = [i, i + 1, i + 1 + sx, i + sx, i + sxy, i + 1 + sxy, i + 1 + sx + sxy, i + sx + sxy];
            let v = crate::geometry::gather(self.values, &idx);
            let c = x + (nx - 1) * y;
            let code = u16::from(case) << 6 | u16::from(self.joined_faces(case, x, y, z));
            cases[c] = code;
            let entry = self.tables.entry(code);
            // Crossing of edge `e`, in the cell's unit cube.
            let crossing = |e: usize| {
                let (a, b) = EDGES[e];
                let (va, vb) = (v[a as usize], v[b as usize]);
                self.tables.edge_start[e] + self.tables.edge_step[e] * ((self.iso - va) / (vb - va))
            };
            let mut sums = [Vec3::ZERO; 4];
            let mut counts = [0.0f32; 4];
            let mut mask = entry.edge_mask;
            if entry.polygons == 1 {
                // Most cells: one piece, summed in registers (the same sum, in the same order).
                counts[0] = mask.count_ones() as f32;
                while mask != 0 {
                    sums[0] += crossing(mask.trailing_zeros() as usize);
                    mask &= mask - 1;
                }
            }
            while mask != 0 {
                let e = mask.trailing_zeros() as usize;
                mask &= mask - 1;
                let piece = entry.edge_polygon[e] as usize;
                sums[piece] += crossing(e);
                counts[piece] += 1.0;
            }
            let min = self.grid.position(x, y, z);
            base[c] = tag | mesh.vertex_count() as u32;
            if let Some(split) = self.boundary_split(entry, x, y, z) {
                // A piece the domain boundary cuts into separate fans: a vertex per fan.
                cases[c] = code | SPLIT;
                for p in 0..split.count as usize {
                    let local = self.place(split.placed_from[p], &v, min, &crossing);
                    let normal = self.sweep_normals.then(|| trilinear_gradient(&v, local.clamp(Vec3::ZERO, Vec3::ONE)));
                    mesh.push_vertex(min + local * self.grid.spacing, normal);
                    if let Some(cell_min) = cell_min.as_deref_mut() {
                        cell_min.push(min);
                    }
                }
                return;
            }
            for p in 0..entry.polygons as usize {
                let local = match self.placement {
                    Placement::Qef { .. } => {
                        let edges = (0..12).filter(|&e| entry.edge_polygon[e] as usize == p).fold(0u16, |m, e| m | 1 << e);
                        self.place(edges, &v, min, &crossing)
                    }
                    Placement::MassPoint => sums[p] / counts[p],
                };
                let normal = self.sweep_normals.then(|| trilinear_gradient(&v, local.clamp(Vec3::ZERO, Vec3::ONE)));
                mesh.push_vertex(min + local * self.grid.spacing, normal);
                if let Some(cell_min) = cell_min.as_deref_mut() {
                    cell_min.push(min);
                }
            }
        });
        crate::geometry::normalize_all(mesh.normals_from(first_normal));
    }

    /// Where the vertex of the piece whose crossings are the edges in mask `edges` goes, in the
    /// cell's unit cube (`v`: its corner values, `min`: its lower corner, `crossing`: each edge's
    /// crossing in the unit cube).
    fn place(&self, edges: u16, v: &[f32; 8], min: Vec3, crossing: &impl Fn(usize) -> Vec3) -> Vec3 {
        place(self.placement, self.field, self.grid.spacing, edges, v, min, crossing)
    }

    /// The cube edges of cell `(x, y, z)` that lie on the domain boundary (bit `e`): they have
    /// no quad, as one of their four cells is missing. Zero for cells inside.
    #[inline]
    pub(super) fn boundary_edges(&self, x: usize, y: usize, z: usize) -> u16 {
        let [nx, ny, nz] = self.grid.dims;
        if x != 0 && y != 0 && z != 0 && x + 2 != nx && y + 2 != ny && z + 2 != nz {
            return 0;
        }
        let at = [(z == 0), (z + 2 == nz), (y == 0), (y + 2 == ny), (x == 0), (x + 2 == nx)];
        (0..6).filter(|&f| at[f]).fold(0u16, |mask, f| mask | self.tables.face_edges[f])
    }

    /// The split of `entry`'s pieces in cell `(x, y, z)` by the domain boundary, when it splits
    /// one ([`boundary_split`]).
    #[inline]
    fn boundary_split(&self, entry: &Case, x: usize, y: usize, z: usize) -> Option<BoundaryPieces> {
        match self.boundary_edges(x, y, z) {
            0 => None,
            edges => boundary_split(entry, edges),
        }
    }

    /// Calls `visit(x, y, i, case)` for every cell of cell layer `z` whose corners disagree (`i`:
    /// the sample index of its lower corner), in the order the sweep numbers their vertices.
    #[inline(always)]
    fn for_each_surface_cell_of_layer(&self, signs: &LayerSigns, z: usize, mut visit: impl FnMut(usize, usize, usize, u8)) {
        let [nx, ny, _] = self.grid.dims;
        for y in 0..ny - 1 {
            let rows = [signs.row(y, z), signs.row(y + 1, z), signs.row(y, z + 1), signs.row(y + 1, z + 1)];
            let Some((lo, hi)) = span(&rows, nx) else { continue };
            let start = self.grid.index(0, y, z);
            let bits = [signs.bits(y, z), signs.bits(y + 1, z), signs.bits(y, z + 1), signs.bits(y + 1, z + 1)];
            for_each_surface_cell(bits, lo.saturating_sub(1), hi.min(nx - 2), |x, case| visit(x, y, start + x, case));
        }
    }

    /// The vertices [`Ctx::cell_vertices`] makes in cell layer `z`: one per piece of surface of
    /// every surface cell, from the sign bits alone.
    fn count_cell_vertices(&self, signs: &LayerSigns, z: usize) -> usize {
        let mut n = 0;
        self.for_each_surface_cell_of_layer(signs, z, |x, y, _, case| {
            let code = u16::from(case) << 6 | u16::from(self.joined_faces(case, x, y, z));
            let entry = self.tables.entry(code);
            n += match self.boundary_split(entry, x, y, z) {
                Some(split) => split.count as usize,
                None => entry.polygons as usize,
            };
        });
        n
    }

    /// Quads for the crossing edges whose four cells lie in cell layers `z - 1` (`prev`) and `z`
    /// (`cur`): x- and y-edges of sample layer `z` (when `z > 0`) and z-edges from sample layer `z`.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn quads(
        &self,
        signs: &LayerSigns,
        z: usize,
        prev: (&[u32], &[u16]),
        cur: (&[u32], &[u16]),
        ghost: &[Vec3],
        mesh: &mut impl SweepOut,
        links: Option<&mut Vec<(u32, u32)>>,
    ) {
        let cx = self.grid.dims[0] - 1;
        let tables = self.tables;
        // The vertex of the piece of surface that crosses local edge `e` of a cell.
        // (`lz`: the layer's z, for the rare cells the domain boundary splits.)
        let cell = |layer: (&[u32], &[u16]), lz: usize, x: usize, y: usize, e: usize| {
            piece_vertex(tables, layer, x + cx * y, e, || self.boundary_edges(x, y, lz))
        };
        let (positions, triangles) = mesh.positions_and_triangles();
        let at = |i: u32| if i & EXTERN == 0 { positions[i as usize] } else { ghost[(i & !EXTERN) as usize] };
        let mut links = links;
        let least_folded = matches!(self.placement, Placement::Qef { .. });
        self.for_each_quad(signs, z, |edge, x, y, flip| {
            let [c00, c10, c11, c01] = match edge {
                QuadEdge::Z => {
                    [cell(cur, z, x - 1, y - 1, 10), cell(cur, z, x, y - 1, 11), cell(cur, z, x, y, 8), cell(cur, z, x - 1, y, 9)]
                }
                QuadEdge::X => {
                    let below = z - 1;
                    [cell(prev, below, x, y - 1, 6), cell(prev, below, x, y, 4), cell(cur, z, x, y, 0), cell(cur, z, x, y - 1, 2)]
                }
                QuadEdge::Y => {
                    let below = z - 1;
                    [cell(prev, below, x - 1, y, 5), cell(cur, z, x - 1, y, 1), cell(cur, z, x, y, 3), cell(prev, below, x, y, 7)]
                }
            };
            let along_00_11 = if least_folded {
                let p = [c00, c10, c11, c01].map(at);
                split_least_folded(p, (p[2] - p[0]).cross(p[3] - p[1]))
            } else {
                at(c00).distance_squared(at(c11)) <= at(c10).distance_squared(at(c01))
            };
            let (t0, t1) = if along_00_11 { ([c00, c10, c11], [c00, c11, c01]) } else { ([c10, c11, c01], [c10, c01, c00]) };
            for t in [t0, t1] {
                triangles.push_triangle(if flip { [t[0], t[2], t[1]] } else { t });
            }
            if let Some(links) = links.as_deref_mut() {
                links.extend([(c00, c10), (c10, c11), (c11, c01), (c01, c00)]);
            }
        });
    }

    /// The triangles [`Ctx::quads`] makes for cell layer `z`: two per quad.
    fn count_quad_triangles(&self, signs: &LayerSigns, z: usize) -> usize {
        let mut n = 0;
        self.for_each_quad(signs, z, |_, _, _, _| n += 2);
        n
    }

    /// Calls `visit(edge, x, y, flip)` for every crossing edge whose quad [`Ctx::quads`] makes
    /// for cell layer `z`, in its order: the edge from sample `(x, y, z)` along `edge`, wound the
    /// other way when `flip` (its first sample is outside).
    #[inline(always)]
    fn for_each_quad(&self, signs: &LayerSigns, z: usize, mut visit: impl FnMut(QuadEdge, usize, usize, bool)) {
        let [nx, ny, nz] = self.grid.dims;
        let bit = |row: &[u64], x: usize| row[x / 64] >> (x % 64) & 1 == 1;
        for y in 0..ny {
            let here = signs.bits(y, z);
            // z-edges (x, y, z)-(x, y, z+1): cells (x-1..x, y-1..y) of layer z.
            if z + 1 < nz && y >= 1 && y + 1 < ny {
                if let Some((lo, hi)) = span(&[signs.row(y, z), signs.row(y, z + 1)], nx) {
                    let above = signs.bits(y, z + 1);
                    for_each_bit(lo.max(1), hi.min(nx - 2), |w| here[w] ^ above[w], |x| visit(QuadEdge::Z, x, y, !bit(here, x)));
                }
            }
            if z == 0 || z + 1 >= nz {
                continue;
            }
            // x-edges (x, y, z)-(x+1, y, z): cells (x, y-1..y) of layers z-1 and z.
            let row = signs.row(y, z);
            if y >= 1 && y + 1 < ny && !row.is_uniform() {
                let (lo, hi) = ((row.first as usize).saturating_sub(1), (row.last as usize).min(nx - 2));
                for_each_bit(lo, hi, |w| here[w] ^ next_bits(here, w), |x| visit(QuadEdge::X, x, y, !bit(here, x)));
            }
            // y-edges (x, y, z)-(x, y+1, z): cells (x-1..x, y) of layers z-1 and z.
            if y + 1 < ny {
                if let Some((lo, hi)) = span(&[row, signs.row(y + 1, z)], nx) {
                    let next = signs.bits(y + 1, z);
                    for_each_bit(lo.max(1), hi.min(nx - 2), |w| here[w] ^ next[w], |x| visit(QuadEdge::Y, x, y, !bit(here, x)));
                }
            }
        }
    }
}

/// Where the vertex of the piece whose crossings are the edges in mask `edges` goes, in the unit
/// cube of a cell of side `spacing` whose lower corner is `min` (world) and corner values `v`
/// (`crossing`: each edge's crossing in the unit cube): the mass point of the crossings, or the
/// minimum of their quadric error with the field's normals there ([`qef::solve_qef`]).
pub(super) fn place(
    placement: Placement,
    field: Option<&dyn crate::field::Field>,
    spacing: f32,
    edges: u16,
    v: &[f32; 8],
    min: Vec3,
    crossing: &impl Fn(usize) -> Vec3,
) -> Vec3 {
    match placement {
        Placement::Qef { tolerance, clamp } => {
            let mut pts = [Vec3::ZERO; 12];
            let mut nrm = [Vec3::ZERO; 12];
            let mut k = 0;
            for e in (0..12).filter(|&e| edges >> e & 1 == 1) {
                let q = crossing(e);
                pts[k] = q;
                // The field's gradient where the samples carry it, else the cell's trilinear
                // interpolant's (Hermite data from samples).
                let g = match field {
                    Some(field) => field.gradient(min + q * spacing),
                    None => trilinear_gradient(v, q),
                };
                nrm[k] = g.normalize_or_zero();
                k += 1;
            }
            let x = qef::solve_qef(&pts[..k], &nrm[..k], tolerance);
            if clamp {
                x.clamp(Vec3::ZERO, Vec3::ONE)
            } else {
                x
            }
        }
        Placement::MassPoint => {
            let (sum, n) =
                (0..12).filter(|&e| edges >> e & 1 == 1).fold((Vec3::ZERO, 0.0f32), |(s, n), e| (s + crossing(e), n + 1.0));
            sum / n
        }
    }
}

/// The vertex of the piece of surface that crosses local edge `e` of cell `c` in `layer` (first
/// vertex indices, cell codes). Inlined by force: called from one closure in four places, it was
/// not, and the whole sweep took a sixth longer.
#[inline(always)]
fn piece_vertex(tables: Tables, layer: (&[u32], &[u16]), c: usize, e: usize, boundary_edges: impl FnOnce() -> u16) -> u32 {
    let code = layer.1[c];
    let entry = tables.entry(code);
    let piece = if code & SPLIT == 0 {
        entry.edge_polygon[e]
    } else {
        // Rare: a cell on the domain boundary whose piece the boundary splits.
        boundary_split(entry, boundary_edges()).map_or(entry.edge_polygon[e], |split| split.edge_piece[e])
    };
    layer.0[c] + u32::from(piece)
}

/// The lattice axis of a crossing edge whose quad the sweep makes.
#[derive(Clone, Copy)]
pub(super) enum QuadEdge {
    X,
    Y,
    Z,
}

impl Ctx<'_> {
    /// Meshes cell layers `z0..z1` into `s.mesh`, referring to the layer below `z0` (owned by the
    /// slab below) through `EXTERN`-tagged indices into a recomputed ghost layer.
    pub(super) fn slab(&self, z0: usize, z1: usize, links: bool, s: &mut Slab) {
        let mut mesh = std::mem::take(&mut s.mesh);
        mesh.clear();
        if mesh.positions.capacity() == 0 {
            // A fresh output (one-shot): size it once from the crossing edges instead of growing
            // by doubling. A closed quad mesh has about as many vertices as quads, one quad per
            // interior crossing edge; capacity never written is never touched.
            let dims = self.grid.dims;
            let edges = count_crossing_edges(&mut s.signs, self.values, dims, self.iso, z0, z1, true);
            let vertices = edges + edges / 8 + 64;
            mesh.positions.reserve_exact(vertices);
            mesh.normals.reserve_exact(vertices);
            if self.keep_cell_min {
                s.cell_min.reserve_exact(vertices);
            }
            mesh.triangles.reserve_exact(2 * edges + 64);
        }
        self.sweep(z0, z1, links, s, &mut mesh);
        s.mesh = mesh;
    }

    /// Meshes cell layers `z0..z1` straight into `piece`, its part of the output, sized by
    /// [`Ctx::count`]: indices come out global, those to the layer below `z0` resolved to the
    /// slab below's piece. No cell corners or links (the path without smoothing).
    pub(super) fn slab_into(&self, z0: usize, z1: usize, s: &mut Slab, piece: &mut Piece) {
        debug_assert!(!self.keep_cell_min);
        self.sweep(z0, z1, false, s, piece);
    }

    /// What [`Ctx::slab_into`] writes for cell layers `z0..z1`, from the sign bits alone (and
    /// the neighbour cases of the rare cells with joined faces).
    pub(super) fn count(&self, z0: usize, z1: usize, s: &mut Slab) -> SlabCount {
        let (values, dims, iso) = (self.values, self.grid.dims, self.iso);
        let signs = &mut s.signs;
        signs.reset(dims[0], dims[1]);
        let mut count = SlabCount::default();
        for z in z0..z1 {
            signs.classify(values, dims, iso, z);
            signs.classify(values, dims, iso, z + 1);
            count.last_layer_start = count.vertices;
            count.vertices += self.count_cell_vertices(signs, z);
            count.triangles += self.count_quad_triangles(signs, z);
        }
        count
    }

    /// The sweep of [`Ctx::slab`] and [`Ctx::slab_into`] into `out`.
    fn sweep(&self, z0: usize, z1: usize, links: bool, s: &mut Slab, out: &mut impl SweepOut) {
        let [nx, ny, _] = self.grid.dims;
        let layer = (nx - 1) * (ny - 1);
        for b in [&mut s.prev, &mut s.cur] {
            crate::sweep::slabs::grow_zeroed(b, layer);
        }
        for b in [&mut s.prev_case, &mut s.cur_case] {
            crate::sweep::slabs::grow_zeroed(b, layer);
        }
        s.ghost.clear();
        s.cell_min.clear();
        s.links.clear();
        s.vertex_time = std::time::Duration::ZERO;
        s.geometry_time = std::time::Duration::ZERO;
        let mut signs = std::mem::take(&mut s.signs);
        let (values, dims, iso) = (self.values, self.grid.dims, self.iso);
        signs.reset(nx, ny);
        if z0 > 0 {
            let t = Instant::now();
            signs.classify(values, dims, iso, z0 - 1);
            signs.classify(values, dims, iso, z0);
            self.cell_vertices(&signs, z0 - 1, EXTERN, &mut s.prev, &mut s.prev_case, &mut s.ghost, None);
            s.vertex_time += t.elapsed();
        }
        for z in z0..z1 {
            let a = Instant::now();
            signs.classify(values, dims, iso, z);
            signs.classify(values, dims, iso, z + 1);
            s.last_layer_start = out.vertex_count() as u32;
            let cell_min = self.keep_cell_min.then_some(&mut s.cell_min);
            self.cell_vertices(&signs, z, 0, &mut s.cur, &mut s.cur_case, out, cell_min);
            let b = Instant::now();
            let link_buffer = links.then_some(&mut s.links);
            self.quads(&signs, z, (&s.prev, &s.prev_case), (&s.cur, &s.cur_case), &s.ghost.positions, out, link_buffer);
            s.geometry_time += b.elapsed();
            s.vertex_time += b - a;
            std::mem::swap(&mut s.prev, &mut s.cur);
            std::mem::swap(&mut s.prev_case, &mut s.cur_case);
        }
        s.signs = signs;
    }
}

/// The cube tables, dereferenced once per pass instead of once per lookup.
#[derive(Clone, Copy)]
pub(super) struct Tables {
    pub(super) default: &'static [Case; 256],
    pub(super) rings: &'static [u8; 256],
    /// Each cube edge's first corner and the step to its second, in the unit cube.
    pub(super) edge_start: [Vec3; 12],
    pub(super) edge_step: [Vec3; 12],
    /// The cube edges on each face (bit `e`).
    pub(super) face_edges: [u16; 6],
}

impl Tables {
    pub(super) fn get() -> Tables {
        let corner = |c: u8| Vec3::from(CORNERS[c as usize].map(f32::from));
        Tables {
            default: &TABLE,
            rings: &RING_FACES,
            edge_start: EDGES.map(|(a, _)| corner(a)),
            edge_step: EDGES.map(|(a, b)| corner(b) - corner(a)),
            face_edges: std::array::from_fn(|f| face_edges(f).iter().fold(0u16, |m, &e| m | 1 << e)),
        }
    }

    /// The table entry for a cell code `case << 6 | joined faces`: the default table unless a
    /// face is joined (rare: only at faces wrapped on both sides).
    #[inline]
    pub(super) fn entry(&self, code: u16) -> &'static Case {
        let code = code & !SPLIT;
        if code & 63 == 0 {
            &self.default[(code >> 6) as usize]
        } else {
            &FACE_CHOICE_TABLE[code as usize]
        }
    }
}

/// Cosine of the largest turn of a triangle from its quad's mean normal that the shorter
/// diagonal may keep (60 degrees).
const FOLD_COS: f32 = 0.5;

/// Which diagonal to split the quad `p` (corners in order) along, for vertices that sit on
/// features (dual contouring): `true` for `p[0]-p[2]`. The shorter diagonal, unless one of its
/// triangles turns more than 60 degrees away from `expected` (the quad's mean normal, its vector
/// area) and the other split's worse triangle turns less: a quad whose feature-placed vertices
/// fold it is then split where it does not turn back on itself. On the shipped models and
/// built-in fields this removed most of dual contouring's self-intersections (the tests hold the
/// shipped models at none) and left the 768 cube-pattern cases as they were.
pub(super) fn split_least_folded(p: [Vec3; 4], expected: Vec3) -> bool {
    let facing = |a: Vec3, b: Vec3, c: Vec3| {
        let n = (b - a).cross(c - a);
        let l = n.length() * expected.length();
        if l > 0.0 {
            n.dot(expected) / l
        } else {
            0.0
        }
    };
    let first = facing(p[0], p[1], p[2]).min(facing(p[0], p[2], p[3]));
    let second = facing(p[1], p[2], p[3]).min(facing(p[1], p[3], p[0]));
    let shorter = p[0].distance_squared(p[2]) <= p[1].distance_squared(p[3]);
    let (kept, other) = if shorter { (first, second) } else { (second, first) };
    if kept > FOLD_COS || other <= kept + 1e-4 {
        shorter
    } else {
        !shorter
    }
}
