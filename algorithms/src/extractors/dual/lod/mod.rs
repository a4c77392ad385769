//! Levels of detail for the dual engine (surface nets, dual contouring): chunks meshed at full,
//! half, quarter (and coarser) resolution meet without cracks by octree dual contouring's rule
//! (Ju, Losasso, Schaefer and Warren 2002, "Dual Contouring of Hermite Data", section 3.2): every
//! *minimal* edge with a sign change, one that contains no edge of a smaller cell around it, gets
//! the polygon joining the vertices of the cells around it. Chunks at one level are a uniform grid
//! of cells, so inside a chunk this is the engine's quad per crossing edge; where a chunk meets a
//! finer one, the minimal edges on the seam are the finer chunk's edges, each surrounded by two
//! fine cells and one or two coarse ones: halves of a coarse edge get a quad, the finer edges
//! crossing a coarse face from its centre get a triangle (the coarse cell twice around them).
//! Gildea's chunked dual contouring seams and Lengyel's 2010 Transvoxel thesis (section 4.2)
//! describe the same octree view of chunk seams.
//!
//! The finer samples on a coarser chunk's boundary are restricted first
//! ([`crate::chunks::lod`]: linear on a coarse edge, bilinear on a coarse face, an ambiguous
//! face's interior kept outside), so a fine edge on a coarse face crosses only where the coarse
//! face's contour passes: a half of a coarse edge crosses when that edge does, and a fine edge
//! from a coarse face's centre to the midpoint of its edge `E` crosses on the coarse segment
//! through `E` (an ambiguous face has two segments, one per inside corner, and the midpoint of `E`
//! is inside with `E`'s inside corner) or, when `E` does not cross, on the face's only segment.
//! So each fine crossing names one piece of the coarse cell, and the polygons around every
//! vertex close into one fan. Faces between chunks of different levels keep their inside corners
//! apart (never joined, whatever the ring rule says inside a chunk), as the restriction assumes;
//! with every chunk at one level the result is the engine's own mesh (tested, smoothing
//! included). Smoothing runs once on the stitched net, each vertex kept in its own cell.

mod fans;
mod pinch;

use super::boundary::{boundary_split, SPLIT};
use super::cells::{place, split_least_folded, Tables};
use super::smoothing::{build_adjacency, smooth_within, SmoothBuffers};
use super::{DualEngine, Placement, Smoothing};
use crate::chunks::lod::DualLevels;
// Their home is chunks::lod now; named here too, where they were first public.
pub use crate::chunks::lod::{DualLodCounts, LodGrid};
use crate::geometry::trilinear_gradient;
use crate::mesh::TriMesh;
use crate::tables::marching_cubes::{face_edges, opposite_face, Case, CORNERS, EDGES, FACES, RING_FACES};
use glam::Vec3;
use rayon::prelude::*;

const NONE: u32 = u32::MAX;

/// One chunk's cells at its level: the first vertex of each surface cell, its table code, and its
/// vertices (sample index coordinates) with their cells' corners.
#[derive(Default)]
struct ChunkCells {
    first: Vec<u32>,
    codes: Vec<u16>,
    positions: Vec<Vec3>,
    corners: Vec<[u32; 3]>,
}

/// One chunk's polygons.
#[derive(Default)]
struct ChunkPolygons {
    triangles: Vec<[u32; 3]>,
    /// The triangles of polygons between levels (indices into `triangles`).
    seam_triangles: Vec<u32>,
    links: Vec<(u32, u32)>,
    /// With fans: the polygons themselves, triangulated once every vertex is placed.
    fans: Vec<fans::FanPolygon>,
    seam_polygons: usize,
    unmatched: usize,
}

/// A cell: its lower corner (sample indices) and side (samples).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Cell {
    corner: [usize; 3],
    side: usize,
}

struct Lod<'a> {
    g: LodGrid<'a>,
    tables: Tables,
    placement: Placement,
    /// Intersection-free fans ([`fans`]) instead of the engine's split quads.
    fans: bool,
}

impl Lod<'_> {
    fn value(&self, c: [usize; 3]) -> f32 {
        self.g.values[self.g.grid.index(c[0], c[1], c[2])]
    }

    fn inside(&self, c: [usize; 3]) -> bool {
        self.value(c) < self.g.iso
    }

    fn chunk_flat(&self, id: [usize; 3]) -> usize {
        id[0] + self.g.counts[0] * (id[1] + self.g.counts[1] * id[2])
    }

    /// The chunk (flat index) and level of a cell's lower corner.
    fn chunk_of(&self, corner: [usize; 3]) -> (usize, u8) {
        let k = self.chunk_flat(corner.map(|c| c / self.g.chunk));
        (k, self.g.levels[k])
    }

    fn cell_values(&self, cell: Cell) -> [f32; 8] {
        CORNERS.map(|o| self.value([0, 1, 2].map(|a| cell.corner[a] + cell.side * o[a] as usize)))
    }

    fn case_of(&self, cell: Cell) -> u8 {
        self.cell_values(cell).iter().enumerate().fold(0u8, |case, (bit, &v)| case | u8::from(v < self.g.iso) << bit)
    }

    /// The neighbour of `cell` across face `f`, when it lies in the grid.
    fn across(&self, cell: Cell, f: usize) -> Option<Cell> {
        let d = FACES[f].1;
        let mut corner = cell.corner;
        for a in 0..3 {
            let c = corner[a] as isize + d[a] as isize * cell.side as isize;
            if c < 0 || c as usize + cell.side > self.g.grid.dims[a] - 1 {
                return None;
            }
            corner[a] = c as usize;
        }
        Some(Cell { corner, side: cell.side })
    }

    /// The engine's ring rule ([`super::cells`]' `joined_faces`) among cells of one level; a face
    /// toward a chunk of another level is never joined.
    fn joined_faces(&self, case: u8, cell: Cell, level: u8) -> u8 {
        let rings = RING_FACES[case as usize];
        (0..6).filter(|&f| rings >> f & 1 == 1).fold(0u8, |joins, f| {
            let Some(n) = self.across(cell, f) else { return joins };
            if self.chunk_of(n.corner).1 != level {
                return joins;
            }
            joins | u8::from(RING_FACES[self.case_of(n) as usize] >> opposite_face(f) & 1 == 1) << f
        })
    }

    /// The cube edges of `cell` on the grid's boundary (bit `e`), as the engine's
    /// `boundary_edges`.
    fn boundary_mask(&self, cell: Cell) -> u16 {
        (0..6)
            .filter(|&f| {
                let d = FACES[f].1;
                let a = (0..3).find(|&a| d[a] != 0).expect("a face has a normal axis");
                if d[a] < 0 {
                    cell.corner[a] == 0
                } else {
                    cell.corner[a] + cell.side == self.g.grid.dims[a] - 1
                }
            })
            .fold(0u16, |m, f| m | self.tables.face_edges[f])
    }

    fn entry(&self, code: u16) -> &'static Case {
        self.tables.entry(code)
    }

    /// The piece (vertex offset in the cell) that edge `e` of a cell with table `code` belongs
    /// to, or `None` (the edge does not cross, or has no quad on the grid's boundary).
    fn piece(&self, cell: Cell, code: u16, e: usize) -> Option<u32> {
        let entry = self.entry(code);
        let piece = if code & SPLIT == 0 {
            entry.edge_polygon[e]
        } else {
            boundary_split(entry, self.boundary_mask(cell)).map_or(entry.edge_polygon[e], |s| s.edge_piece[e])
        };
        (piece != u8::MAX).then_some(u32::from(piece))
    }

    /// Chunk `k`'s cells at its level: case, joined faces, the grid boundary's split, and a
    /// vertex per piece placed as the engine places it.
    /// Whether chunk `k`'s samples at its level (its closed box) lie on both sides of the
    /// iso-value: otherwise it has no surface cell and no crossing edge.
    fn has_surface(&self, k: usize) -> bool {
        let side = 1usize << self.g.levels[k];
        let counts = self.g.counts;
        let id = [k % counts[0], (k / counts[0]) % counts[1], k / (counts[0] * counts[1])];
        let k0 = id.map(|c| c * self.g.chunk);
        let first = self.inside(k0);
        let m = self.g.chunk / side;
        (0..=m).any(|l| {
            (0..=m).any(|j| (0..=m).any(|i| self.inside([k0[0] + side * i, k0[1] + side * j, k0[2] + side * l]) != first))
        })
    }

    fn chunk_cells(&self, k: usize) -> ChunkCells {
        let level = self.g.levels[k];
        let side = 1usize << level;
        let m = self.g.chunk / side;
        let id = [k % self.g.counts[0], (k / self.g.counts[0]) % self.g.counts[1], k / (self.g.counts[0] * self.g.counts[1])];
        let k0 = id.map(|c| c * self.g.chunk);
        let mut out = ChunkCells { first: vec![NONE; m * m * m], codes: vec![0; m * m * m], ..Default::default() };
        if !self.has_surface(k) {
            return out;
        }
        let h = self.g.grid.spacing;
        for (local, (i, j, l)) in (0..m).flat_map(|l| (0..m).flat_map(move |j| (0..m).map(move |i| (i, j, l)))).enumerate() {
            let cell = Cell { corner: [k0[0] + side * i, k0[1] + side * j, k0[2] + side * l], side };
            let v = self.cell_values(cell);
            let case = v.iter().enumerate().fold(0u8, |case, (bit, &x)| case | u8::from(x < self.g.iso) << bit);
            if case == 0 || case == 255 {
                continue;
            }
            let mut code = u16::from(case) << 6 | u16::from(self.joined_faces(case, cell, level));
            let entry = self.entry(code);
            let crossing = |e: usize| {
                let (a, b) = EDGES[e];
                let (va, vb) = (v[a as usize], v[b as usize]);
                self.tables.edge_start[e] + self.tables.edge_step[e] * ((self.g.iso - va) / (vb - va))
            };
            let corner = Vec3::new(cell.corner[0] as f32, cell.corner[1] as f32, cell.corner[2] as f32);
            let min_world = self.g.grid.origin + corner * h;
            out.first[local] = out.positions.len() as u32;
            let mut push = |edges: u16| {
                let local = place(self.placement, self.g.field, side as f32 * h, edges, &v, min_world, &crossing);
                out.positions.push(corner + local * side as f32);
                out.corners.push(cell.corner.map(|c| c as u32));
            };
            let boundary = self.boundary_mask(cell);
            match (boundary != 0).then(|| boundary_split(entry, boundary)).flatten() {
                Some(split) => {
                    code |= SPLIT;
                    for p in 0..split.count as usize {
                        push(split.placed_from[p]);
                    }
                }
                None => {
                    for p in 0..entry.polygons {
                        push((0..12).filter(|&e| entry.edge_polygon[e] == p).fold(0u16, |mask, e| mask | 1 << e));
                    }
                }
            }
            out.codes[local] = code;
        }
        out
    }

    /// The vertex of the cell around a minimal edge (axis `a`, lower end `p`, `side` samples
    /// long) that contains the probe point `probe2` (doubled sample coordinates), or `None` when
    /// that cell has no piece for the crossing. `cells[k]`, `offsets[k]`: chunk `k`'s cells and
    /// its first vertex in the whole mesh.
    fn vertex_around(
        &self,
        (a, p, side): (usize, [usize; 3], usize),
        probe2: [usize; 3],
        cells: &[ChunkCells],
        offsets: &[u32],
    ) -> Option<u32> {
        let (k, level) = self.chunk_of(probe2.map(|c| c / 2));
        let s = 1usize << level;
        let cell = Cell { corner: probe2.map(|c| c / (2 * s) * s), side: s };
        let m = self.g.chunk / s;
        let k0 = cell.corner.map(|c| c / self.g.chunk * self.g.chunk);
        let local = [0, 1, 2].map(|d| (cell.corner[d] - k0[d]) / s);
        let index = local[0] + m * (local[1] + m * local[2]);
        let chunk = &cells[k];
        let first = chunk.first[index];
        if first == NONE {
            return None;
        }
        let code = chunk.codes[index];
        // Offsets of the edge's lower end in the cell, in units of the edge's length.
        let r = [0, 1, 2].map(|d| (p[d] - cell.corner[d]) / side);
        let e = if s == side {
            local_edge(a, r)
        } else {
            // One level coarser: the edge is half of a coarse edge, or runs from a coarse face's
            // centre to the midpoint of the face's edge `E` (module doc).
            let (b, c) = ((a + 1) % 3, (a + 2) % 3);
            match (r[b] % 2, r[c] % 2) {
                (0, 0) => local_edge(a, [0, 1, 2].map(|d| if d == a { 0 } else { r[d] / 2 })),
                (1, 0) | (0, 1) => {
                    let (along, normal) = if r[b] % 2 == 1 { (b, c) } else { (c, b) };
                    let big = local_edge(
                        along,
                        [0, 1, 2].map(|d| {
                            if d == along {
                                0
                            } else if d == a {
                                r[a]
                            } else {
                                r[d] / 2
                            }
                        }),
                    );
                    let entry = self.entry(code);
                    if entry.edge_mask >> big & 1 == 1 {
                        big
                    } else {
                        let f = face_index(normal, r[normal] / 2);
                        face_edges(f).into_iter().map(usize::from).find(|&e| self.piece(cell, code, e).is_some())?
                    }
                }
                _ => return None,
            }
        };
        self.piece(cell, code, e).map(|piece| offsets[k] + first + piece)
    }

    /// Chunk `k`'s polygons: one per crossing minimal edge it owns (the lowest-numbered chunk of
    /// its level around the edge).
    fn chunk_polygons(&self, k: usize, cells: &[ChunkCells], offsets: &[u32], positions: &[Vec3], links: bool) -> ChunkPolygons {
        let level = self.g.levels[k];
        let side = 1usize << level;
        let m = self.g.chunk / side;
        let counts = self.g.counts;
        let id = [k % counts[0], (k / counts[0]) % counts[1], k / (counts[0] * counts[1])];
        let k0 = id.map(|c| c * self.g.chunk);
        let dims = self.g.grid.dims;
        let least_folded = matches!(self.placement, Placement::Qef { .. });
        let mut out = ChunkPolygons::default();
        if cells[k].positions.is_empty() && !self.has_surface(k) {
            return out;
        }
        for a in 0..3 {
            let (b, c) = ((a + 1) % 3, (a + 2) % 3);
            let range = |d: usize| if d == a { m } else { m + 1 };
            for t2 in 0..range(2) {
                for t1 in 0..range(1) {
                    for t0 in 0..range(0) {
                        let t = [t0, t1, t2];
                        let p = [0, 1, 2].map(|d| k0[d] + side * t[d]);
                        let mut q = p;
                        q[a] += side;
                        let first_inside = self.inside(p);
                        if first_inside == self.inside(q) {
                            continue;
                        }
                        // The four cells around the edge, counter-clockwise seen from +a: probe
                        // points half a sample off the edge's middle, in doubled coordinates.
                        let mut probes = [[0usize; 3]; 4];
                        let mut off_grid = false;
                        for (n, (db, dc)) in [(false, false), (true, false), (true, true), (false, true)].into_iter().enumerate()
                        {
                            let mut p2 = p.map(|x| 2 * x as isize);
                            p2[a] += side as isize;
                            p2[b] += if db { 1 } else { -1 };
                            p2[c] += if dc { 1 } else { -1 };
                            if (0..3).any(|d| p2[d] < 0 || p2[d] > 2 * (dims[d] as isize - 1)) {
                                off_grid = true;
                                break;
                            }
                            probes[n] = p2.map(|x| x as usize);
                        }
                        if off_grid {
                            continue;
                        }
                        let inside_chunk = (1..m).contains(&t[b]) && (1..m).contains(&t[c]);
                        let mut seam = false;
                        if !inside_chunk {
                            let around = probes.map(|p2| self.chunk_of(p2.map(|x| x / 2)));
                            if around.iter().any(|&(_, l)| l < level) {
                                continue; // the finer chunk's halves are the minimal edges
                            }
                            let owner = around.iter().filter(|&&(_, l)| l == level).map(|&(o, _)| o).min();
                            if owner != Some(k) {
                                continue;
                            }
                            seam = around.iter().any(|&(_, l)| l != level);
                        }
                        let mut ring = [0u32; 4];
                        let mut found = true;
                        for n in 0..4 {
                            match self.vertex_around((a, p, side), probes[n], cells, offsets) {
                                Some(v) => ring[n] = v,
                                None => found = false,
                            }
                        }
                        if !found {
                            out.unmatched += 1;
                            continue;
                        }
                        out.seam_polygons += usize::from(seam);
                        if self.fans {
                            let (distinct, n) = distinct_cells(ring);
                            if n < 3 {
                                out.unmatched += 1;
                                continue;
                            }
                            let mut cycle = distinct;
                            if !first_inside {
                                cycle[1..n].reverse();
                            }
                            let edge = fans::MinimalEdge { start: p, axis: a, len: side };
                            out.fans.push(fans::FanPolygon { ring: cycle, n: n as u8, edge, level });
                            if links {
                                out.links.extend((0..n).map(|k| (distinct[k], distinct[(k + 1) % n])));
                            }
                            continue;
                        }
                        let before = out.triangles.len() as u32;
                        self.emit(ring, !first_inside, least_folded, positions, links, &mut out);
                        if seam {
                            out.seam_triangles.extend(before..out.triangles.len() as u32);
                        }
                    }
                }
            }
        }
        out
    }

    /// The triangles of one polygon around an edge (its cells in counter-clockwise order seen
    /// from the edge's direction, a cell repeated where a coarse one spans two quadrants),
    /// wound the other way when `flip`; split as the engine splits its quads.
    fn emit(&self, ring: [u32; 4], flip: bool, least_folded: bool, positions: &[Vec3], links: bool, out: &mut ChunkPolygons) {
        let (distinct, n) = distinct_cells(ring);
        let oriented = |t: [u32; 3]| if flip { [t[0], t[2], t[1]] } else { t };
        match n {
            4 => {
                let [c00, c10, c11, c01] = ring;
                let at = |i: u32| positions[i as usize];
                let along_00_11 = if least_folded {
                    let p = ring.map(at);
                    split_least_folded(p, (p[2] - p[0]).cross(p[3] - p[1]))
                } else {
                    at(c00).distance_squared(at(c11)) <= at(c10).distance_squared(at(c01))
                };
                let (t0, t1) = if along_00_11 { ([c00, c10, c11], [c00, c11, c01]) } else { ([c10, c11, c01], [c10, c01, c00]) };
                out.triangles.push(oriented(t0));
                out.triangles.push(oriented(t1));
            }
            3 => out.triangles.push(oriented([distinct[0], distinct[1], distinct[2]])),
            _ => {
                out.unmatched += 1;
                return;
            }
        }
        if links {
            out.links.extend((0..n).map(|k| (distinct[k], distinct[(k + 1) % n])));
        }
    }
}

/// The distinct vertices of a ring around an edge (a coarse cell spanning two quadrants appears
/// twice in a row), in order, and how many.
fn distinct_cells(ring: [u32; 4]) -> ([u32; 4], usize) {
    let mut distinct = [0u32; 4];
    let mut n = 0;
    for k in 0..4 {
        if ring[k] != ring[(k + 3) % 4] {
            distinct[n] = ring[k];
            n += 1;
        }
    }
    (distinct, n)
}

/// The cube edge along axis `a` whose lower corner is at offset `r` (each 0 or 1) in the cell.
fn local_edge(a: usize, r: [usize; 3]) -> usize {
    (0..12)
        .find(|&e| {
            let (u, v) = EDGES[e];
            let (cu, cv) = (CORNERS[u as usize], CORNERS[v as usize]);
            let lower = if cu[a] < cv[a] { cu } else { cv };
            cu[a] != cv[a] && (0..3).all(|d| lower[d] as usize == r[d])
        })
        .expect("every axis and corner offset names a cube edge")
}

/// The cube face normal to axis `a` on side `high` (0 or 1).
fn face_index(a: usize, high: usize) -> usize {
    (0..6).find(|&f| FACES[f].1[a] == if high == 1 { 1 } else { -1 }).expect("six faces")
}

impl DualLevels for DualEngine {
    fn extract_lod(&self, g: LodGrid<'_>, out: &mut TriMesh, levels: Option<&mut Vec<u8>>) -> DualLodCounts {
        extract_lod(self, g, out, levels)
    }
}

/// Meshes the chunked grid `g` with `engine`'s placement and smoothing, each chunk at its level,
/// with polygons on every minimal edge (module doc). The mesh is in world coordinates; `levels`
/// (if given) receives each triangle's level (its owning chunk's).
pub fn extract_lod(engine: &DualEngine, g: LodGrid<'_>, out: &mut TriMesh, levels: Option<&mut Vec<u8>>) -> DualLodCounts {
    let lod = Lod { g, tables: Tables::get(), placement: engine.placement, fans: engine.intersection_free_lod };
    let total = g.levels.len();
    let cells: Vec<ChunkCells> = (0..total).into_par_iter().map(|k| lod.chunk_cells(k)).collect();
    let mut offsets = Vec::with_capacity(total);
    let mut next = 0u32;
    for c in &cells {
        offsets.push(next);
        next += c.positions.len() as u32;
    }
    out.positions.clear();
    out.normals.clear();
    out.triangles.clear();
    let mut corners: Vec<[u32; 3]> = Vec::with_capacity(next as usize);
    for c in &cells {
        out.positions.extend_from_slice(&c.positions);
        corners.extend_from_slice(&c.corners);
    }
    let smoothing = engine.options.smoothing != Smoothing::None && engine.options.iterations > 0;
    let polygons: Vec<ChunkPolygons> =
        (0..total).into_par_iter().map(|k| lod.chunk_polygons(k, &cells, &offsets, &out.positions, smoothing)).collect();
    let mut counts = DualLodCounts::default();
    let mut triangle_levels = Vec::new();
    let mut links = Vec::new();
    let mut seam_triangles = Vec::new();
    let mut fan_polygons = Vec::new();
    for (k, p) in polygons.iter().enumerate() {
        fan_polygons.extend_from_slice(&p.fans);
        let base = out.triangles.len() as u32;
        seam_triangles.extend(p.seam_triangles.iter().map(|&t| base + t));
        out.triangles.extend_from_slice(&p.triangles);
        triangle_levels.extend(std::iter::repeat_n(g.levels[k], p.triangles.len()));
        links.extend_from_slice(&p.links);
        counts.seam_polygons += p.seam_polygons;
        counts.unmatched += p.unmatched;
    }
    // Each vertex's cell side, from its chunk's level.
    let side_of = |corner: [u32; 3]| 1u32 << lod.chunk_of(corner.map(|c| c as usize)).1;
    if !lod.fans {
        counts.pinched = pinch::pinch(out, &mut corners, &seam_triangles, side_of, &mut links, smoothing);
    }
    if smoothing {
        let (mut start, mut adjacency) = (Vec::new(), Vec::new());
        build_adjacency(out.positions.len(), &links, &mut start, &mut adjacency);
        let bound = |i: usize| {
            let lo = Vec3::from(corners[i].map(|c| c as f32));
            (lo, lo + Vec3::splat(side_of(corners[i]) as f32))
        };
        smooth_within(&engine.options, &mut out.positions, (&start, &adjacency), &mut SmoothBuffers::default(), bound);
    }
    if lod.fans {
        counts.crossing_cells = fans::triangulate(&lod, &fan_polygons, out, &mut corners, side_of, &mut triangle_levels);
    }
    // Normals: the gradient of the vertex's cell's trilinear interpolant there, as the engine.
    let normals: Vec<Vec3> = out
        .positions
        .par_iter()
        .zip(corners.par_iter())
        .map(|(&p, &corner)| {
            let side = side_of(corner) as usize;
            let cell = Cell { corner: corner.map(|c| c as usize), side };
            let lo = Vec3::from(corner.map(|c| c as f32));
            trilinear_gradient(&lod.cell_values(cell), ((p - lo) / side as f32).clamp(Vec3::ZERO, Vec3::ONE)).normalize_or_zero()
        })
        .collect();
    out.normals = normals;
    for p in &mut out.positions {
        *p = g.grid.origin + *p * g.grid.spacing;
    }
    if let Some(l) = levels {
        *l = triangle_levels;
    }
    counts
}
