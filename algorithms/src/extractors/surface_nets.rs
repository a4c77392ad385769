//! # Surface nets
//!
//! **Papers:** S. F. F. Gibson, "Constrained elastic surface nets: generating smooth surfaces from
//! binary segmented data", MICCAI 1998, DOI 10.1007/BFb0056277; the terrain use and its smoothing
//! variants follow the blog post `../shared/papers/blog-surface-nets-terrain.txt` (linear
//! relaxation with decaying strength, an explicit spring-damper, an implicit solve).
//!
//! **Summary.** Every cell whose corners disagree gets one vertex per separate piece of surface in
//! it, at the mean of that piece's edge crossings (linear interpolation). The pieces are the
//! polygons of the cell's marching cubes case ([`crate::tables::marching_cubes`]); Gibson's
//! original puts one vertex in every cell, which pinches two sheets sharing a cell into a
//! non-manifold vertex: one vertex per piece keeps the net manifold. Every crossing lattice edge inside the grid gets one quad
//! joining the vertices of its four cells, split along its shorter diagonal and wound so normals
//! point toward increasing `f`. Cells are swept in layers along z with two layers of vertex
//! indices, so memory is two cell layers plus the output. Optional smoothing moves each vertex
//! toward its net neighbours (the quads' sides) but never out of its own cell (Gibson's constraint):
//! - [`Smoothing::Elastic`]: `x += λ_k (mean − x)`, `λ_k = strength · decay^k` (the post found a
//!   decaying strength necessary so detail survives a few iterations);
//! - [`Smoothing::Spring`]: the post's explicit method: springs to the neighbours' mean with a
//!   stiffness, a damping on the velocity, a unit time step;
//! - [`Smoothing::Implicit`]: backward Euler on the net's graph Laplacian, `(I + t L) x' = x`,
//!   solved per coordinate by Jacobi-preconditioned conjugate gradients (the matrix is symmetric
//!   positive definite), then clamped to the cells.
//!
//! **Guarantees.** Every vertex lies in its cell, before and after smoothing. Quads never cross the
//! lattice boundary, so the mesh is open where the surface leaves the grid. Consistent outward
//! winding.
//!
//! **Guarantees (topology).** Because each piece of surface has its own vertex and the cube table
//! resolves ambiguous faces alike in both cells, the net is closed (where it stays inside the
//! grid) and consistently wound. One configuration of the plain table would still pinch: a piece
//! of surface that wraps an outside passage across an ambiguous face (the face's inside corners
//! joined through the cell's other faces) on *both* sides of the face gives a two-vertex tube, and
//! the four quads of the face's edges share one net edge. Such a face
//! ([`crate::tables::marching_cubes::RING_FACES`] in both cells) is resolved the other way in both
//! cells (its inside corners joined), which splits the passage into two pieces per cell and
//! changes no other face (the joined corners were already connected). Tests: all 256 cube
//! patterns, all 4096 patterns of two cells sharing a face, random smooth and white-noise fields,
//! the built-in closed fields. Slabs of cell layers run in parallel and join into exactly the mesh
//! one slab would give.
//!
//! **Non-guarantees.** Smoothing shrinks convex shapes (reported as volume change), and spring or
//! implicit smoothing can fold a one-sample feature flat. Vertices at the mean of their crossings
//! never leave their cell, but adjacent quads can still intersect on rough fields (the report
//! counts self-intersections).
//!
//! Vertex normals are the gradient of the cell's trilinear interpolant at the vertex (no field
//! evaluation, as game engines and `fast-surface-nets` do).
//!
//! **Costs.** One read of every sample to pack its sign, layer by layer as the sweep reaches it
//! ([`crate::sign_rows::LayerSigns`]: surface cells and crossing edges are found 64 samples at a
//! time), then work proportional to surface cells; smoothing is
//! `iterations` passes over the vertices (implicit: a conjugate-gradient solve per iteration).
//!
//! ```
//! use isolab_algorithms::{extractors::SurfaceNets, fields, Extraction, Extractor, Grid, Samples};
//! let sphere = fields::builtin("sphere", Default::default()).unwrap();
//! let samples = Samples::sample_cubic(sphere.clone(), Grid::covering(&sphere.domain(), 32).unwrap(), 0.0).unwrap();
//! let mut out = Extraction::default();
//! SurfaceNets::default().extract(&samples, &mut out).unwrap();
//! // Vertices stay within one cell diagonal of the sphere.
//! let h = samples.grid().spacing;
//! assert!(out.surface.positions.iter().all(|p| (p.length() - 0.4).abs() < 1.8 * h));
//! ```

use crate::extract::{Chunking, ExtractError, Extraction, Extractor};
use crate::extractors::marching_cubes::Parallelism;
use crate::extractors::slabs::{ScratchPool, EXTERN};
use crate::geometry::trilinear_gradient;
use crate::lattice::{Grid, Lattice};
use crate::mesh::TriMesh;
use crate::options::{OptionError, Options};
use crate::samples::Samples;
use crate::sign_rows::{for_each_bit, for_each_surface_cell, next_bits, span, LayerSigns};
use crate::tables::marching_cubes::{opposite_face, Case, CORNERS, EDGES, FACES, FACE_CHOICE_TABLE, RING_FACES, TABLE};
use glam::Vec3;
use rayon::prelude::*;
use std::time::Instant;

/// One line for listings.
pub const DESCRIPTION: &str =
    "Gibson 1998: one vertex per surface cell (mean of its edge crossings), a quad per crossing edge; constrained smoothing";

/// How vertices are smoothed after placement.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Smoothing {
    /// Vertices stay at the mean of their cell's edge crossings.
    None,
    /// Constrained elastic relaxation with decaying strength (Gibson 1998; the post's "linear").
    Elastic,
    /// The post's explicit spring-damper, constrained to the cells.
    Spring,
    /// Backward Euler on the graph Laplacian, solved by conjugate gradients, then constrained.
    Implicit,
}

/// Options for [`SurfaceNets`]. Defaults are the best-looking setting found on the built-in
/// fields (see the `surface_nets_smoothing` experiment): elastic, 4 iterations.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SnOptions {
    /// Smoothing method.
    pub smoothing: Smoothing,
    /// Smoothing iterations (implicit: time steps).
    pub iterations: usize,
    /// Elastic: first step's fraction of the way to the neighbours' mean, in (0, 1].
    pub strength: f32,
    /// Elastic: factor applied to the strength after each iteration, in (0, 1].
    pub decay: f32,
    /// Spring: stiffness, in (0, 1].
    pub stiffness: f32,
    /// Spring: velocity damping per step, in [0, 1].
    pub damping: f32,
    /// Implicit: diffusion time per step, in (0, 100].
    pub time_step: f32,
    /// Slabs of cell layers in parallel, or one on the calling thread.
    pub parallelism: Parallelism,
}

impl Default for SnOptions {
    fn default() -> Self {
        Self {
            smoothing: Smoothing::Elastic,
            iterations: 4,
            strength: 0.6,
            decay: 0.75,
            stiffness: 0.5,
            damping: 0.4,
            time_step: 1.0,
            parallelism: Parallelism::Rayon,
        }
    }
}

/// Option names for [`from_options`].
pub const OPTION_NAMES: &[&str] =
    &["smoothing", "iterations", "strength", "decay", "stiffness", "damping", "time-step", "parallelism"];

/// Builds surface nets from named options.
pub fn from_options(options: &Options) -> Result<Box<dyn Extractor>, OptionError> {
    let d = SnOptions::default();
    let mut r = options.reader("surface-nets", OPTION_NAMES);
    let smoothing = r.choice(
        "smoothing",
        d.smoothing,
        &[
            ("none", Smoothing::None),
            ("elastic", Smoothing::Elastic),
            ("spring", Smoothing::Spring),
            ("implicit", Smoothing::Implicit),
        ],
    )?;
    let o = SnOptions {
        smoothing,
        iterations: r.count("iterations", d.iterations, 10_000)?,
        strength: r.number("strength", d.strength, 1e-6, 1.0)?,
        decay: r.number("decay", d.decay, 1e-6, 1.0)?,
        stiffness: r.number("stiffness", d.stiffness, 1e-6, 1.0)?,
        damping: r.number("damping", d.damping, 0.0, 1.0)?,
        time_step: r.number("time-step", d.time_step, 1e-6, 100.0)?,
        parallelism: r.choice("parallelism", d.parallelism, &[("rayon", Parallelism::Rayon), ("serial", Parallelism::Serial)])?,
    };
    r.finish()?;
    Ok(Box::new(SurfaceNets::new(o)))
}

/// Where a dual vertex goes inside its cell.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum Placement {
    /// The mean of its piece's edge crossings (surface nets).
    #[default]
    MassPoint,
    /// The minimum of the quadric error of its crossings and the field's normals there
    /// ([`crate::extractors::dual_contouring`]); needs samples that carry their field.
    Qef {
        /// Relative singular value cut-off of the truncated SVD.
        tolerance: f32,
        /// Keep the vertex inside its cell.
        clamp: bool,
    },
}

/// Surface nets on a cubic grid. Keeps its scratch buffers between calls.
#[derive(Default)]
pub struct SurfaceNets {
    /// The options.
    pub options: SnOptions,
    placement: Placement,
    label: Option<&'static str>,
    scratch: ScratchPool<Scratch>,
}

#[derive(Default)]
struct Scratch {
    /// Lower corner of each vertex's cell (the smoothing constraint).
    cell_min: Vec<Vec3>,
    /// Net edges (quad sides) as vertex pairs, then the adjacency in CSR form.
    links: Vec<(u32, u32)>,
    adjacency_start: Vec<u32>,
    adjacency: Vec<u32>,
    work: Vec<Vec3>,
    velocity: Vec<Vec3>,
    velocity_next: Vec<Vec3>,
    /// One per slab task.
    slabs: Vec<Slab>,
}

/// A slab of cell layers meshed on its own.
#[derive(Default)]
struct Slab {
    /// First vertex index and sign case of each cell in the previous and current cell layers.
    prev: Vec<u32>,
    cur: Vec<u32>,
    prev_case: Vec<u16>,
    cur_case: Vec<u16>,
    mesh: TriMesh,
    cell_min: Vec<Vec3>,
    links: Vec<(u32, u32)>,
    /// The slab below's last cell layer, recomputed here so quads can refer to it.
    ghost: TriMesh,
    ghost_min: Vec<Vec3>,
    /// The sign bits of the two sample layers the sweep is between.
    signs: LayerSigns,
    /// Index of the first vertex of this slab's last cell layer.
    last_layer_start: u32,
    vertex_time: std::time::Duration,
    geometry_time: std::time::Duration,
}

impl Slab {
    fn bytes(&self) -> usize {
        4 * (self.prev.capacity() + self.cur.capacity())
            + self.prev_case.capacity()
            + self.cur_case.capacity()
            + self.mesh.capacity_bytes()
            + self.ghost.capacity_bytes()
            + 12 * (self.cell_min.capacity() + self.ghost_min.capacity())
            + 8 * self.links.capacity()
            + self.signs.capacity_bytes()
    }
}

impl Scratch {
    fn bytes(&self) -> usize {
        4 * (self.adjacency_start.capacity() + self.adjacency.capacity())
            + 12 * (self.cell_min.capacity() + self.work.capacity() + self.velocity.capacity() + self.velocity_next.capacity())
            + 8 * self.links.capacity()
            + self.slabs.iter().map(Slab::bytes).sum::<usize>()
    }
}

impl SurfaceNets {
    /// Surface nets with `options`.
    pub fn new(options: SnOptions) -> Self {
        Self { options, placement: Placement::MassPoint, label: None, scratch: ScratchPool::default() }
    }

    /// The dual engine with another vertex placement, reporting as `label` (dual contouring).
    pub fn with_placement(options: SnOptions, placement: Placement, label: &'static str) -> Self {
        Self { options, placement, label: Some(label), scratch: ScratchPool::default() }
    }
}

struct Ctx<'a> {
    values: &'a [f32],
    grid: Grid,
    iso: f32,
    placement: Placement,
    field: Option<&'a dyn crate::field::Field>,
    tables: Tables,
}

impl Ctx<'_> {
    #[inline]
    fn inside(&self, i: usize) -> bool {
        self.values[i] < self.iso
    }

    /// The sign case of cell `(x, y, z)` (bit `c` set: table corner `c` inside).
    fn cell_case(&self, x: usize, y: usize, z: usize) -> u8 {
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
    fn joined_faces(&self, case: u8, x: usize, y: usize, z: usize) -> u8 {
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
    /// `base` gets each cell's first vertex index and `cases` its [`Tables::entry`] code.
    #[allow(clippy::too_many_arguments)]
    fn cell_vertices(
        &self,
        signs: &LayerSigns,
        z: usize,
        tag: u32,
        base: &mut [u32],
        cases: &mut [u16],
        mesh: &mut TriMesh,
        cell_min: &mut Vec<Vec3>,
    ) {
        let [nx, ny, _] = self.grid.dims;
        let (sx, sxy) = (nx, nx * ny);
        for y in 0..ny - 1 {
            let rows = [signs.row(y, z), signs.row(y + 1, z), signs.row(y, z + 1), signs.row(y + 1, z + 1)];
            let Some((lo, hi)) = span(&rows, nx) else { continue };
            let start = self.grid.index(0, y, z);
            let bits = [signs.bits(y, z), signs.bits(y + 1, z), signs.bits(y, z + 1), signs.bits(y + 1, z + 1)];
            for_each_surface_cell(bits, lo.saturating_sub(1), hi.min(nx - 2), |x, case| {
                let i = start + x;
                let idx = [i, i + 1, i + 1 + sx, i + sx, i + sxy, i + 1 + sxy, i + 1 + sx + sxy, i + sx + sxy];
                let v = idx.map(|k| self.values[k]);
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
                while mask != 0 {
                    let e = mask.trailing_zeros() as usize;
                    mask &= mask - 1;
                    let piece = entry.edge_polygon[e] as usize;
                    sums[piece] += crossing(e);
                    counts[piece] += 1.0;
                }
                let min = self.grid.position(x, y, z);
                base[c] = tag | mesh.positions.len() as u32;
                for p in 0..entry.polygons as usize {
                    let local = match self.placement {
                        Placement::Qef { tolerance, clamp } => {
                            let mut pts = [Vec3::ZERO; 12];
                            let mut nrm = [Vec3::ZERO; 12];
                            let mut k = 0;
                            for e in (0..12).filter(|&e| entry.edge_polygon[e] as usize == p) {
                                let q = crossing(e);
                                pts[k] = q;
                                // The field's gradient where the samples carry it, else the
                                // cell's trilinear interpolant's (Hermite data from samples).
                                let g = match self.field {
                                    Some(field) => field.gradient(min + q * self.grid.spacing),
                                    None => trilinear_gradient(&v, q),
                                };
                                nrm[k] = g.normalize_or_zero();
                                k += 1;
                            }
                            let x = crate::extractors::dual_contouring::solve_qef(&pts[..k], &nrm[..k], tolerance);
                            if clamp {
                                x.clamp(Vec3::ZERO, Vec3::ONE)
                            } else {
                                x
                            }
                        }
                        Placement::MassPoint => sums[p] / counts[p],
                    };
                    mesh.positions.push(min + local * self.grid.spacing);
                    mesh.normals.push(trilinear_gradient(&v, local.clamp(Vec3::ZERO, Vec3::ONE)).normalize_or_zero());
                    cell_min.push(min);
                }
            });
        }
    }

    /// Quads for the crossing edges whose four cells lie in cell layers `z - 1` (`prev`) and `z`
    /// (`cur`): x- and y-edges of sample layer `z` (when `z > 0`) and z-edges from sample layer `z`.
    #[allow(clippy::too_many_arguments)]
    fn quads(
        &self,
        signs: &LayerSigns,
        z: usize,
        prev: (&[u32], &[u16]),
        cur: (&[u32], &[u16]),
        ghost: &[Vec3],
        mesh: &mut TriMesh,
        links: Option<&mut Vec<(u32, u32)>>,
    ) {
        let [nx, ny, _] = self.grid.dims;
        let cx = nx - 1;
        let tables = self.tables;
        // The vertex of the piece of surface that crosses local edge `e` of a cell.
        let cell = |layer: (&[u32], &[u16]), x: usize, y: usize, e: usize| {
            let c = x + cx * y;
            layer.0[c] + u32::from(tables.entry(layer.1[c]).edge_polygon[e])
        };
        let positions = &mesh.positions;
        let at = |i: u32| if i & EXTERN == 0 { positions[i as usize] } else { ghost[(i & !EXTERN) as usize] };
        let mut links = links;
        let mut emit = |c: [u32; 4], flip: bool, triangles: &mut Vec<[u32; 3]>| {
            let [c00, c10, c11, c01] = c;
            let d0 = at(c00).distance_squared(at(c11));
            let d1 = at(c10).distance_squared(at(c01));
            let (t0, t1) = if d0 <= d1 { ([c00, c10, c11], [c00, c11, c01]) } else { ([c10, c11, c01], [c10, c01, c00]) };
            for t in [t0, t1] {
                triangles.push(if flip { [t[0], t[2], t[1]] } else { t });
            }
            if let Some(links) = links.as_deref_mut() {
                links.extend([(c00, c10), (c10, c11), (c11, c01), (c01, c00)]);
            }
        };
        let mut triangles = std::mem::take(&mut mesh.triangles);
        let bit = |row: &[u64], x: usize| row[x / 64] >> (x % 64) & 1 == 1;
        for y in 0..ny {
            let here = signs.bits(y, z);
            // z-edges (x, y, z)-(x, y, z+1): cells (x-1..x, y-1..y) of layer z.
            if z + 1 < self.grid.dims[2] && y >= 1 && y + 1 < ny {
                if let Some((lo, hi)) = span(&[signs.row(y, z), signs.row(y, z + 1)], nx) {
                    let above = signs.bits(y, z + 1);
                    for_each_bit(
                        lo.max(1),
                        hi.min(nx - 2),
                        |w| here[w] ^ above[w],
                        |x| {
                            let c = [
                                cell(cur, x - 1, y - 1, 10),
                                cell(cur, x, y - 1, 11),
                                cell(cur, x, y, 8),
                                cell(cur, x - 1, y, 9),
                            ];
                            emit(c, !bit(here, x), &mut triangles);
                        },
                    );
                }
            }
            if z == 0 || z + 1 >= self.grid.dims[2] {
                continue;
            }
            // x-edges (x, y, z)-(x+1, y, z): cells (x, y-1..y) of layers z-1 and z.
            let row = signs.row(y, z);
            if y >= 1 && y + 1 < ny && !row.is_uniform() {
                let (lo, hi) = ((row.first as usize).saturating_sub(1), (row.last as usize).min(nx - 2));
                for_each_bit(
                    lo,
                    hi,
                    |w| here[w] ^ next_bits(here, w),
                    |x| {
                        let c = [cell(prev, x, y - 1, 6), cell(prev, x, y, 4), cell(cur, x, y, 0), cell(cur, x, y - 1, 2)];
                        emit(c, !bit(here, x), &mut triangles);
                    },
                );
            }
            // y-edges (x, y, z)-(x, y+1, z): cells (x-1..x, y) of layers z-1 and z.
            if y + 1 < ny {
                if let Some((lo, hi)) = span(&[row, signs.row(y + 1, z)], nx) {
                    let next = signs.bits(y + 1, z);
                    for_each_bit(
                        lo.max(1),
                        hi.min(nx - 2),
                        |w| here[w] ^ next[w],
                        |x| {
                            let c = [cell(prev, x - 1, y, 5), cell(cur, x - 1, y, 1), cell(cur, x, y, 3), cell(prev, x, y, 7)];
                            emit(c, !bit(here, x), &mut triangles);
                        },
                    );
                }
            }
        }
        mesh.triangles = triangles;
    }
}

impl Ctx<'_> {
    /// Meshes cell layers `z0..z1` into `s.mesh`, referring to the layer below `z0` (owned by the
    /// slab below) through `EXTERN`-tagged indices into a recomputed ghost layer.
    fn slab(&self, z0: usize, z1: usize, links: bool, s: &mut Slab) {
        let [nx, ny, _] = self.grid.dims;
        let layer = (nx - 1) * (ny - 1);
        for b in [&mut s.prev, &mut s.cur] {
            if b.len() < layer {
                b.resize(layer, 0);
            }
        }
        for b in [&mut s.prev_case, &mut s.cur_case] {
            if b.len() < layer {
                b.resize(layer, 0);
            }
        }
        s.mesh.clear();
        s.ghost.clear();
        s.cell_min.clear();
        s.ghost_min.clear();
        s.links.clear();
        s.vertex_time = std::time::Duration::ZERO;
        s.geometry_time = std::time::Duration::ZERO;
        let mut signs = std::mem::take(&mut s.signs);
        signs.reset(nx, ny);
        let (values, dims, iso) = (self.values, self.grid.dims, self.iso);
        if z0 > 0 {
            let t = Instant::now();
            signs.classify(values, dims, iso, z0 - 1);
            signs.classify(values, dims, iso, z0);
            self.cell_vertices(&signs, z0 - 1, EXTERN, &mut s.prev, &mut s.prev_case, &mut s.ghost, &mut s.ghost_min);
            s.vertex_time += t.elapsed();
        }
        for z in z0..z1 {
            let a = Instant::now();
            signs.classify(values, dims, iso, z);
            signs.classify(values, dims, iso, z + 1);
            s.last_layer_start = s.mesh.positions.len() as u32;
            self.cell_vertices(&signs, z, 0, &mut s.cur, &mut s.cur_case, &mut s.mesh, &mut s.cell_min);
            let b = Instant::now();
            let link_buffer = links.then_some(&mut s.links);
            self.quads(&signs, z, (&s.prev, &s.prev_case), (&s.cur, &s.cur_case), &s.ghost.positions, &mut s.mesh, link_buffer);
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
struct Tables {
    default: &'static [Case; 256],
    rings: &'static [u8; 256],
    /// Each cube edge's first corner and the step to its second, in the unit cube.
    edge_start: [Vec3; 12],
    edge_step: [Vec3; 12],
}

impl Tables {
    fn get() -> Tables {
        let corner = |c: u8| Vec3::from(CORNERS[c as usize].map(f32::from));
        Tables {
            default: &TABLE,
            rings: &RING_FACES,
            edge_start: EDGES.map(|(a, _)| corner(a)),
            edge_step: EDGES.map(|(a, b)| corner(b) - corner(a)),
        }
    }

    /// The table entry for a cell code `case << 6 | joined faces`: the default table unless a
    /// face is joined (rare: only at faces wrapped on both sides).
    #[inline]
    fn entry(&self, code: u16) -> &'static Case {
        if code & 63 == 0 {
            &self.default[(code >> 6) as usize]
        } else {
            &FACE_CHOICE_TABLE[code as usize]
        }
    }
}

/// Resolves a slab-local index: tagged ones name the slab below's last layer.
#[inline]
fn resolve(i: u32, offset: u32, below: u32) -> u32 {
    if i & EXTERN == 0 {
        i + offset
    } else {
        below + (i & !EXTERN)
    }
}

/// Builds the net's adjacency (CSR) from the quad sides: a counting pass over both directions
/// of every side (each side comes from two quads), then each vertex's short list sorted and
/// deduplicated in place. Linear in the sides, and no buffer besides the reused ones, so
/// steady-state re-meshing does not allocate.
fn build_adjacency(n: usize, links: &[(u32, u32)], start: &mut Vec<u32>, adjacency: &mut Vec<u32>) {
    start.clear();
    start.resize(n + 1, 0);
    for &(a, b) in links.iter() {
        start[a as usize + 1] += 1;
        start[b as usize + 1] += 1;
    }
    for i in 0..n {
        start[i + 1] += start[i];
    }
    adjacency.clear();
    adjacency.resize(start[n] as usize, 0);
    // Fill with start[i] as vertex i's cursor (it ends at start[i + 1]), then shift back.
    for &(a, b) in links.iter() {
        adjacency[start[a as usize] as usize] = b;
        start[a as usize] += 1;
        adjacency[start[b as usize] as usize] = a;
        start[b as usize] += 1;
    }
    for i in (1..=n).rev() {
        start[i] = start[i - 1];
    }
    start[0] = 0;
    // Sort and deduplicate each vertex's list, compacting towards the front.
    let mut write = 0usize;
    for i in 0..n {
        let (lo, hi) = (start[i] as usize, start[i + 1] as usize);
        adjacency[lo..hi].sort_unstable();
        start[i] = write as u32;
        let mut last = u32::MAX;
        for k in lo..hi {
            let j = adjacency[k];
            if j != last {
                adjacency[write] = j;
                write += 1;
                last = j;
            }
        }
    }
    start[n] = write as u32;
    adjacency.truncate(write);
}

fn neighbour_mean(i: usize, x: &[Vec3], start: &[u32], adjacency: &[u32]) -> Option<Vec3> {
    let nbrs = &adjacency[start[i] as usize..start[i + 1] as usize];
    (!nbrs.is_empty()).then(|| nbrs.iter().map(|&j| x[j as usize]).sum::<Vec3>() / nbrs.len() as f32)
}

fn clamp_to_cell(p: Vec3, min: Vec3, h: f32) -> Vec3 {
    p.clamp(min, min + Vec3::splat(h))
}

impl SurfaceNets {
    fn smooth(&self, s: &mut Scratch, positions: &mut [Vec3], h: f32) {
        let o = &self.options;
        let n = positions.len();
        let (start, adjacency, cell_min) = (&s.adjacency_start, &s.adjacency, &s.cell_min);
        match o.smoothing {
            Smoothing::None => {}
            Smoothing::Elastic => {
                let mut strength = o.strength;
                for _ in 0..o.iterations {
                    s.work.clear();
                    s.work.par_extend((0..n).into_par_iter().map(|i| {
                        let p = positions[i];
                        let target = neighbour_mean(i, positions, start, adjacency).unwrap_or(p);
                        clamp_to_cell(p + (target - p) * strength, cell_min[i], h)
                    }));
                    positions.copy_from_slice(&s.work);
                    strength *= o.decay;
                }
            }
            Smoothing::Spring => {
                s.velocity.clear();
                s.velocity.resize(n, Vec3::ZERO);
                for _ in 0..o.iterations {
                    s.work.resize(n, Vec3::ZERO);
                    s.velocity_next.resize(n, Vec3::ZERO);
                    let velocity = &s.velocity;
                    s.work.par_iter_mut().zip(s.velocity_next.par_iter_mut()).enumerate().for_each(|(i, (next_p, next_v))| {
                        let p = positions[i];
                        let target = neighbour_mean(i, positions, start, adjacency).unwrap_or(p);
                        let v = velocity[i] * (1.0 - o.damping) + (target - p) * o.stiffness;
                        let moved = p + v;
                        let clamped = clamp_to_cell(moved, cell_min[i], h);
                        // A wall stops motion into it (no bounce).
                        *next_v = Vec3::select(moved.cmpne(clamped), Vec3::ZERO, v);
                        *next_p = clamped;
                    });
                    positions.copy_from_slice(&s.work);
                    std::mem::swap(&mut s.velocity, &mut s.velocity_next);
                }
            }
            Smoothing::Implicit => {
                for _ in 0..o.iterations {
                    let solved = implicit_step(positions, start, adjacency, o.time_step);
                    for (i, p) in solved.into_iter().enumerate() {
                        positions[i] = clamp_to_cell(p, cell_min[i], h);
                    }
                }
            }
        }
    }
}

/// One backward-Euler step of graph diffusion: solves `(I + t L) x' = x` with `L = D - A`.
fn implicit_step(x: &[Vec3], start: &[u32], adjacency: &[u32], t: f32) -> Vec<Vec3> {
    let n = x.len();
    let degree: Vec<f32> = (0..n).map(|i| (start[i + 1] - start[i]) as f32).collect();
    let apply = |v: &[Vec3], out: &mut Vec<Vec3>| {
        out.clear();
        out.par_extend((0..n).into_par_iter().map(|i| {
            let nbrs = &adjacency[start[i] as usize..start[i + 1] as usize];
            let sum: Vec3 = nbrs.iter().map(|&j| v[j as usize]).sum();
            v[i] * (1.0 + t * degree[i]) - sum * t
        }));
    };
    // Jacobi-preconditioned conjugate gradients, the three coordinates at once.
    let precond: Vec<f32> = degree.iter().map(|d| 1.0 / (1.0 + t * d)).collect();
    let mut sol: Vec<Vec3> = x.to_vec();
    let mut ax = Vec::with_capacity(n);
    apply(&sol, &mut ax);
    let mut r: Vec<Vec3> = x.iter().zip(&ax).map(|(b, a)| *b - *a).collect();
    let mut z: Vec<Vec3> = r.iter().zip(&precond).map(|(r, m)| *r * *m).collect();
    let mut p = z.clone();
    let dot = |a: &[Vec3], b: &[Vec3]| a.iter().zip(b).fold(Vec3::ZERO, |acc, (u, v)| acc + *u * *v);
    let mut rz = dot(&r, &z);
    let norm_b = dot(x, x).max(Vec3::splat(1e-30));
    let mut ap = Vec::with_capacity(n);
    for _ in 0..500 {
        if (dot(&r, &r) / norm_b).max_element() < 1e-12 {
            break;
        }
        apply(&p, &mut ap);
        let pap = dot(&p, &ap);
        let alpha = Vec3::select(pap.cmpgt(Vec3::ZERO), rz / pap, Vec3::ZERO);
        for i in 0..n {
            sol[i] += p[i] * alpha;
            r[i] -= ap[i] * alpha;
            z[i] = r[i] * precond[i];
        }
        let rz_new = dot(&r, &z);
        let beta = Vec3::select(rz.cmpgt(Vec3::ZERO), rz_new / rz, Vec3::ZERO);
        for i in 0..n {
            p[i] = z[i] + p[i] * beta;
        }
        rz = rz_new;
    }
    sol
}

impl Extractor for SurfaceNets {
    fn name(&self) -> &'static str {
        self.label.unwrap_or("surface-nets")
    }

    fn description(&self) -> &'static str {
        DESCRIPTION
    }

    /// A quad needs its edge's four cells, a cell's pieces depend on its face neighbours (ring
    /// faces), and each smoothing iteration reaches one cell further: `2 + iterations` samples.
    /// Implicit smoothing is a global solve, so chunked positions only approximate it (the
    /// topology is still exact).
    fn chunking(&self) -> Chunking {
        let smoothing = if self.options.smoothing == Smoothing::None { 0 } else { self.options.iterations };
        Chunking::Apron(2 + smoothing)
    }

    fn extract(&self, samples: &Samples, out: &mut Extraction) -> Result<(), ExtractError> {
        out.clear();
        out.stats.times.sampling = samples.sampling_time();
        let Lattice::Cubic(grid) = *samples.lattice() else {
            return Err(ExtractError::UnsupportedLattice {
                algorithm: "surface-nets",
                lattice: samples.lattice().kind(),
                supported: "cubic",
            });
        };
        let [nx, ny, nz] = grid.dims;
        let mut held = self.scratch.take();
        let s = &mut held;
        let field = samples.field().map(|f| f.as_ref());
        let ctx =
            Ctx { values: samples.values(), grid, iso: samples.iso(), placement: self.placement, field, tables: Tables::get() };
        let smoothing = self.options.smoothing != Smoothing::None && self.options.iterations > 0;
        let cell_layers = nz - 1;
        let tasks = crate::extractors::slabs::task_count(self.options.parallelism, grid.cell_count(), cell_layers);
        while s.slabs.len() < tasks {
            s.slabs.push(Slab::default());
        }
        let slabs = &mut s.slabs[..tasks];
        let t_slabs = Instant::now();
        if tasks == 1 {
            std::mem::swap(&mut slabs[0].mesh, &mut out.surface);
            std::mem::swap(&mut slabs[0].cell_min, &mut s.cell_min);
            std::mem::swap(&mut slabs[0].links, &mut s.links);
            ctx.slab(0, cell_layers, smoothing, &mut slabs[0]);
            std::mem::swap(&mut slabs[0].mesh, &mut out.surface);
            std::mem::swap(&mut slabs[0].cell_min, &mut s.cell_min);
            std::mem::swap(&mut slabs[0].links, &mut s.links);
        } else {
            slabs.par_iter_mut().enumerate().for_each(|(t, slab)| {
                ctx.slab(t * cell_layers / tasks, (t + 1) * cell_layers / tasks, smoothing, slab);
            });
        }
        let slab_wall = t_slabs.elapsed();
        let t_join = Instant::now();
        if tasks > 1 {
            let mut offsets = Vec::with_capacity(tasks + 1);
            offsets.push(0usize);
            for slab in slabs.iter() {
                offsets.push(offsets[offsets.len() - 1] + slab.mesh.positions.len());
            }
            if offsets[tasks] >= EXTERN as usize {
                return Err(ExtractError::TooLarge { algorithm: "surface-nets", vertices: offsets[tasks] });
            }
            s.cell_min.clear();
            s.links.clear();
            for (t, slab) in slabs.iter().enumerate() {
                let offset = offsets[t] as u32;
                let below = if t > 0 { offsets[t - 1] as u32 + slabs[t - 1].last_layer_start } else { 0 };
                out.surface.positions.extend_from_slice(&slab.mesh.positions);
                out.surface.normals.extend_from_slice(&slab.mesh.normals);
                out.surface.triangles.extend(slab.mesh.triangles.iter().map(|tri| tri.map(|i| resolve(i, offset, below))));
                s.cell_min.extend_from_slice(&slab.cell_min);
                s.links.extend(slab.links.iter().map(|&(a, b)| (resolve(a, offset, below), resolve(b, offset, below))));
            }
        } else if out.surface.positions.len() >= EXTERN as usize {
            return Err(ExtractError::TooLarge { algorithm: "surface-nets", vertices: out.surface.positions.len() });
        }
        let join_time = t_join.elapsed();
        let (cpu_v, cpu_g) =
            slabs.iter().fold((0.0, 0.0), |(v, g), sl| (v + sl.vertex_time.as_secs_f64(), g + sl.geometry_time.as_secs_f64()));
        let share = if cpu_v + cpu_g > 0.0 { cpu_v / (cpu_v + cpu_g) } else { 0.5 };
        let vertex_time = slab_wall.mul_f64(share);
        let geometry_time = slab_wall.mul_f64(1.0 - share) + join_time;
        out.stats.times.vertex = vertex_time;
        out.stats.times.geometry = geometry_time;
        out.stats.active_cells = out.surface.positions.len();

        let t_smooth = Instant::now();
        if smoothing {
            build_adjacency(out.surface.positions.len(), &s.links, &mut s.adjacency_start, &mut s.adjacency);
            self.smooth(s, &mut out.surface.positions, grid.spacing);
        }
        out.stats.times.smoothing = t_smooth.elapsed();

        // Normals: the gradient of the cell's trilinear interpolant at the vertex (computed in the
        // vertex pass; recomputed where smoothing moved the vertex).
        let t_normals = Instant::now();
        if smoothing {
            let (values, cell_min) = (samples.values(), &s.cell_min);
            let positions = &out.surface.positions;
            out.surface.normals.clear();
            out.surface.normals.par_extend(positions.par_iter().zip(cell_min.par_iter()).map(|(&p, &min)| {
                let cell = ((min - grid.origin) / grid.spacing).round();
                let i = grid.index(cell.x as usize, cell.y as usize, cell.z as usize);
                let (sx, sxy) = (nx, nx * ny);
                let idx = [i, i + 1, i + 1 + sx, i + sx, i + sxy, i + 1 + sxy, i + 1 + sx + sxy, i + sx + sxy];
                trilinear_gradient(&idx.map(|k| values[k]), (p - min) / grid.spacing).normalize_or_zero()
            }));
        }
        out.stats.times.normals = t_normals.elapsed();
        if out.origins.wanted {
            let cell_of = |min: &Vec3| {
                let c = ((*min - grid.origin) / grid.spacing).round();
                (grid.index(c.x as usize, c.y as usize, c.z as usize), 0)
            };
            out.origins.fill_from_owners(&grid, s.cell_min.iter().map(cell_of));
        }
        let scratch = s.bytes();
        self.scratch.give(held);
        out.finish_counts(scratch);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fields;

    fn samples(name: &str, n: usize) -> Samples {
        let f = fields::builtin(name, Default::default()).unwrap();
        Samples::sample_cubic(f.clone(), Grid::covering(&f.domain(), n).unwrap(), 0.0).unwrap()
    }

    #[test]
    fn every_smoothing_keeps_vertices_in_their_cells() {
        let s = samples("asteroid", 24);
        let h = s.grid().spacing;
        for smoothing in [Smoothing::None, Smoothing::Elastic, Smoothing::Spring, Smoothing::Implicit] {
            let sn = SurfaceNets::new(SnOptions { smoothing, iterations: 6, ..Default::default() });
            let mut out = Extraction::default();
            sn.extract(&s, &mut out).unwrap();
            let scratch = sn.scratch.take();
            for (p, min) in out.surface.positions.iter().zip(&scratch.cell_min) {
                let d = (*p - *min) / h;
                assert!(d.min_element() >= -1e-4 && d.max_element() <= 1.0 + 1e-4, "{smoothing:?}: {p} outside cell at {min}");
            }
        }
    }

    #[test]
    fn bad_options_name_the_option() {
        let mut o = Options::new();
        o.set("iterations", "-1");
        assert!(from_options(&o).err().unwrap().to_string().contains("'iterations'"));
        let mut o = Options::new();
        o.set("damping", "1.5");
        assert!(from_options(&o).err().unwrap().to_string().contains("'damping'"));
        let mut o = Options::new();
        o.set("smoothing", "bilateral");
        assert!(from_options(&o).err().unwrap().to_string().contains("none, elastic, spring, implicit"));
    }
}
