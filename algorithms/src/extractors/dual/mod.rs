//! # The dual engine: surface nets and dual contouring
//!
//! What [`crate::extractors::surface_nets`] and [`crate::extractors::dual_contouring`] share:
//! every cell whose corners disagree gets one vertex per separate piece of surface in it (the
//! polygons of the cell's marching cubes case, [`crate::tables::marching_cubes`]), every crossing
//! lattice edge inside the grid a quad joining the vertices of its four cells, split along the
//! shorter diagonal and wound so normals point toward increasing `f`. Only the vertex
//! [`Placement`] differs: the mass point of the piece's crossings (surface nets) or the minimum of
//! its quadric error ([`qef`], dual contouring). Cells are swept in layers along z, slabs of
//! layers in parallel ([`crate::slabs`]); each slab recomputes the cell layer below it, whose
//! vertices belong to the slab below, and refers to them by tagged indices resolved at the join,
//! so the mesh is the same on any number of threads. Optional constrained smoothing
//! ([`smoothing`]) moves vertices toward their net neighbours without leaving their cells.
//!
//! The front ends' module docs give the papers, guarantees and costs.

pub mod qef;
pub mod smoothing;

pub use qef::solve_qef;

use crate::extract::{Chunking, ExtractError, Extraction};
use crate::geometry::trilinear_gradient;
use crate::lattice::{Grid, Lattice};
use crate::mesh::TriMesh;
use crate::samples::Samples;
use crate::sign_rows::{for_each_bit, for_each_surface_cell, next_bits, span, LayerSigns};
use crate::slabs::{slab_offsets, split_slab_time, Parallelism, ScratchPool, EXTERN};
use crate::tables::marching_cubes::{opposite_face, Case, CORNERS, EDGES, FACES, FACE_CHOICE_TABLE, RING_FACES, TABLE};
use glam::Vec3;
use rayon::prelude::*;
use smoothing::build_adjacency;
use std::time::Instant;

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

/// Options of the dual engine (surface nets' options; dual contouring runs without smoothing).
/// Defaults are the best-looking setting found on the built-in fields (see the
/// `surface_nets_smoothing` experiment): elastic, 4 iterations.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DualOptions {
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

impl Default for DualOptions {
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

/// Where a dual vertex goes inside its cell.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum Placement {
    /// The mean of its piece's edge crossings (surface nets).
    #[default]
    MassPoint,
    /// The minimum of the quadric error of its crossings and the field's normals there
    /// ([`qef::solve_qef`], dual contouring); the field's gradients when the samples carry their
    /// field, else the trilinear interpolant's.
    Qef {
        /// Relative singular value cut-off of the truncated SVD.
        tolerance: f32,
        /// Keep the vertex inside its cell.
        clamp: bool,
    },
}

/// The dual engine on a cubic grid, reporting as `name`. Keeps its scratch buffers between calls.
pub struct DualEngine {
    /// The options.
    pub options: DualOptions,
    placement: Placement,
    name: &'static str,
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

impl DualEngine {
    /// The engine with `options` and a vertex `placement`, reporting as `name` in stats and errors.
    pub fn new(options: DualOptions, placement: Placement, name: &'static str) -> Self {
        Self { options, placement, name, scratch: ScratchPool::default() }
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
                            let x = qef::solve_qef(&pts[..k], &nrm[..k], tolerance);
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

impl DualEngine {
    /// The name it reports as.
    pub fn name(&self) -> &'static str {
        self.name
    }

    /// A quad needs its edge's four cells, a cell's pieces depend on its face neighbours (ring
    /// faces), and each smoothing iteration reaches one cell further: `2 + iterations` samples.
    /// Implicit smoothing is a global solve, so chunked positions only approximate it (the
    /// topology is still exact).
    pub fn chunking(&self) -> Chunking {
        let smoothing = if self.options.smoothing == Smoothing::None { 0 } else { self.options.iterations };
        Chunking::Apron(2 + smoothing)
    }

    /// Extracts into `out`, cleared first (the [`crate::Extractor`] contract).
    pub fn extract(&self, samples: &Samples, out: &mut Extraction) -> Result<(), ExtractError> {
        out.clear();
        out.stats.times.sampling = samples.sampling_time();
        let Lattice::Cubic(grid) = *samples.lattice() else {
            return Err(ExtractError::UnsupportedLattice {
                algorithm: self.name,
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
        let tasks = crate::slabs::task_count(self.options.parallelism, grid.cell_count(), cell_layers);
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
            let offsets = slab_offsets(slabs.iter().map(|slab| slab.mesh.positions.len()), self.name)?;
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
            return Err(ExtractError::TooLarge { algorithm: self.name, vertices: out.surface.positions.len() });
        }
        let join_time = t_join.elapsed();
        let (cpu_v, cpu_g) =
            slabs.iter().fold((0.0, 0.0), |(v, g), sl| (v + sl.vertex_time.as_secs_f64(), g + sl.geometry_time.as_secs_f64()));
        let (vertex_time, geometry_time) = split_slab_time(slab_wall, join_time, cpu_v, cpu_g);
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
            let sn = DualEngine::new(
                DualOptions { smoothing, iterations: 6, ..Default::default() },
                Placement::MassPoint,
                "surface-nets",
            );
            let mut out = Extraction::default();
            sn.extract(&s, &mut out).unwrap();
            let scratch = sn.scratch.take();
            for (p, min) in out.surface.positions.iter().zip(&scratch.cell_min) {
                let d = (*p - *min) / h;
                assert!(d.min_element() >= -1e-4 && d.max_element() <= 1.0 + 1e-4, "{smoothing:?}: {p} outside cell at {min}");
            }
        }
    }
}
