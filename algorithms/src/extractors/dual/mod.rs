//! # The dual engine: surface nets and dual contouring
//!
//! What [`crate::extractors::surface_nets`] and [`crate::extractors::dual_contouring`] share:
//! every cell whose corners disagree gets one vertex per separate piece of surface in it (the
//! polygons of the cell's marching cubes case, [`crate::tables::marching_cubes`]), every crossing
//! lattice edge inside the grid a quad joining the vertices of its four cells, split along the
//! shorter diagonal (for dual contouring, the other one where the shorter folds the quad:
//! `cells::split_least_folded`) and wound so normals point toward increasing `f`. Only the vertex
//! [`Placement`] differs: the mass point of the piece's crossings (surface nets) or the minimum of
//! its quadric error ([`qef`], dual contouring). Cells are swept in layers along z, slabs of
//! layers in parallel ([`crate::sweep::slabs`]); each slab recomputes the cell layer below it, whose
//! vertices belong to the slab below, and refers to them by tagged indices resolved at the join,
//! so the mesh is the same on any number of threads. A fresh output without smoothing (one-shot)
//! skips the join, as flying edges does: every slab's output is counted from the sign bits first,
//! the output allocated once, and each slab writes its own piece of it (`Ctx::count`,
//! `Ctx::slab_into`). Optional constrained smoothing
//! ([`smoothing`]) moves vertices toward their net neighbours without leaving their cells.
//!
//! The front ends' module docs give the papers, guarantees and costs.

mod boundary;
mod cells;
mod intersection_free;
pub mod lod;
pub mod qef;
mod slab_out;
pub mod smoothing;

use cells::{Ctx, Tables};
use slab_out::{Piece, PieceTriangles, SlabCount};

pub use qef::solve_qef;

use crate::extract::{Chunking, ExtractError, Extraction};
use crate::geometry::trilinear_gradient;
use crate::lattice::Lattice;
use crate::mesh::TriMesh;
use crate::samples::Samples;
use crate::sweep::sign_rows::LayerSigns;
use crate::sweep::slabs::{
    for_each_slab, join_parts, mesh_pieces, slab_offsets, split_slab_time, Parallelism, ScratchPool, EXTERN,
};
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
    /// The intersection-free pass's buffers ([`DualEngine::extract_intersection_free`]).
    free_scratch: ScratchPool<intersection_free::Scratch>,
    /// Levels of detail by intersection-free fans ([`lod`]), as the intersection-free pass.
    intersection_free_lod: bool,
}

#[derive(Default)]
struct Scratch {
    /// Lower corner of each vertex's cell (the smoothing constraint).
    cell_min: Vec<Vec3>,
    /// Net edges (quad sides) as vertex pairs, then the adjacency in CSR form.
    links: Vec<(u32, u32)>,
    adjacency_start: Vec<u32>,
    adjacency: Vec<u32>,
    buffers: smoothing::SmoothBuffers,
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
            + 12 * self.cell_min.capacity()
            + 8 * self.links.capacity()
            + self.signs.capacity_bytes()
    }
}

impl Scratch {
    fn bytes(&self) -> usize {
        4 * (self.adjacency_start.capacity() + self.adjacency.capacity())
            + 12 * self.cell_min.capacity()
            + self.buffers.bytes()
            + 8 * self.links.capacity()
            + self.slabs.iter().map(Slab::bytes).sum::<usize>()
    }
}

impl DualEngine {
    /// The engine with `options` and a vertex `placement`, reporting as `name` in stats and errors.
    pub fn new(options: DualOptions, placement: Placement, name: &'static str) -> Self {
        Self {
            options,
            placement,
            name,
            scratch: ScratchPool::default(),
            free_scratch: ScratchPool::default(),
            intersection_free_lod: false,
        }
    }

    /// The engine whose levels of detail keep every triangle inside its cells, as
    /// [`DualEngine::extract_intersection_free_into`] does on one level.
    pub fn with_intersection_free_levels(mut self) -> Self {
        self.intersection_free_lod = true;
        self
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
    /// The one-shot parallel path without smoothing: counts each of the `slabs`' output
    /// ([`Ctx::count`]), sizes `surface` once, and has each slab write its piece of it
    /// ([`Ctx::slab_into`]).
    fn extract_into_pieces(
        &self,
        ctx: &Ctx,
        slabs: &mut [Slab],
        cell_layers: usize,
        surface: &mut TriMesh,
    ) -> Result<(), ExtractError> {
        let tasks = slabs.len();
        let bounds = |t: usize| (t * cell_layers / tasks, (t + 1) * cell_layers / tasks);
        let counts: Vec<(SlabCount, std::time::Duration)> = for_each_slab(slabs, |t, slab| {
            let start = Instant::now();
            let (z0, z1) = bounds(t);
            (ctx.count(z0, z1, slab), start.elapsed())
        });
        let offsets = slab_offsets(counts.iter().map(|(c, _)| c.vertices), self.name)?;
        let sizes: Vec<(usize, usize)> = counts.iter().map(|(c, _)| (c.vertices, c.triangles)).collect();
        let pieces = mesh_pieces(surface, &sizes, ctx.sweep_normals).into_iter().enumerate().map(|(t, piece)| Piece {
            positions: piece.positions,
            normals: piece.normals,
            vertices: 0,
            triangles: PieceTriangles {
                out: piece.triangles,
                written: 0,
                base: offsets[t] as u32,
                // The slab below's last cell layer, which this slab's ghost layer recomputes.
                below: if t > 0 { (offsets[t - 1] + counts[t - 1].0.last_layer_start) as u32 } else { 0 },
            },
        });
        let mut work: Vec<(&mut Slab, Piece)> = slabs.iter_mut().zip(pieces).collect();
        for_each_slab(&mut work, |t, (slab, piece)| {
            let (z0, z1) = bounds(t);
            ctx.slab_into(z0, z1, slab, piece);
            slab.vertex_time += counts[t].1;
            // A piece left partly unwritten would be a silently wrong mesh, so this is checked
            // always: the count and the sweep read the same sign bits and must agree.
            assert_eq!(
                (piece.vertices, piece.triangles.written),
                (counts[t].0.vertices, counts[t].0.triangles),
                "{}: slab {t} wrote other counts than it counted",
                self.name
            );
        });
        Ok(())
    }

    /// The name it reports as.
    pub fn name(&self) -> &'static str {
        self.name
    }

    /// Its placement and smoothing in words ([`crate::Extractor::settings`]).
    pub fn settings(&self) -> String {
        let placement = match self.placement {
            Placement::MassPoint => "vertices at the mass point of their crossings".to_string(),
            Placement::Qef { tolerance, clamp } => format!(
                "vertices at the quadric error minimum (SVD cut-off {tolerance}{})",
                if clamp { ", kept in the cell" } else { "" }
            ),
        };
        let o = &self.options;
        let smoothing = match o.smoothing {
            _ if o.iterations == 0 => "no smoothing".to_string(),
            Smoothing::None => "no smoothing".to_string(),
            Smoothing::Elastic => {
                format!("elastic smoothing, {} iterations (strength {}, decay {})", o.iterations, o.strength, o.decay)
            }
            Smoothing::Spring => {
                format!("spring-damper smoothing, {} iterations (stiffness {}, damping {})", o.iterations, o.stiffness, o.damping)
            }
            Smoothing::Implicit => format!("implicit smoothing, {} steps of {}", o.iterations, o.time_step),
        };
        format!("{placement}; {smoothing}")
    }

    /// A quad needs its edge's four cells, a cell's pieces depend on its face neighbours (ring
    /// faces), and each smoothing iteration reaches one cell further: `2 + iterations` samples.
    /// Implicit smoothing is a global solve, so chunked positions only approximate it (the
    /// topology is still exact).
    pub fn chunking(&self) -> Chunking {
        let smoothing = if self.options.smoothing == Smoothing::None { 0 } else { self.options.iterations };
        Chunking::Apron(2 + smoothing)
    }

    /// The sweep into `out` ([`crate::Extractor::extract_into`]: `out` arrives cleared); returns
    /// the scratch bytes it holds.
    pub fn extract_into(&self, samples: &Samples, out: &mut Extraction) -> Result<usize, ExtractError> {
        self.run(samples, out, None)
    }

    /// Extracts into `out` and then replaces each quad by triangles that each stay inside one
    /// cell (the engine's `intersection_free` pass, after Ju and Udeshi 2006): the mesh cannot cross itself.
    pub fn extract_intersection_free_into(&self, samples: &Samples, out: &mut Extraction) -> Result<usize, ExtractError> {
        let mut scratch = self.free_scratch.take();
        let mut engine_bytes = 0;
        let result = self.run(samples, out, Some(&mut scratch)).and_then(|bytes| {
            engine_bytes = bytes;
            let t = Instant::now();
            let Lattice::Cubic(grid) = *samples.lattice() else { unreachable!("run refuses other lattices") };
            let input = intersection_free::Input { values: samples.values(), grid, iso: samples.iso() };
            let origins = out.origins.wanted.then_some(&mut out.origins.vertices);
            let unresolved = intersection_free::triangulate(&input, &mut scratch, &mut out.surface, origins, self.name)?;
            if unresolved > 0 {
                out.stats.warnings.push(format!(
                    "{}: {unresolved} cells with two pieces of surface whose triangles cross (please report the input)",
                    self.name
                ));
            }
            out.stats.times.geometry += t.elapsed();
            Ok(())
        });
        let held = engine_bytes + scratch.bytes();
        self.free_scratch.give(scratch);
        result?;
        Ok(held)
    }

    /// The sweep behind [`DualEngine::extract_into`]; with `quads`, it also keeps each quad's
    /// cycle and each vertex's cell for [`intersection_free::triangulate`]. Returns the scratch
    /// bytes it holds.
    fn run(
        &self,
        samples: &Samples,
        out: &mut Extraction,
        quads: Option<&mut intersection_free::Scratch>,
    ) -> Result<usize, ExtractError> {
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
        let smoothing = self.options.smoothing != Smoothing::None && self.options.iterations > 0;
        let keep_quads = quads.is_some();
        let links = smoothing || keep_quads;
        let ctx = Ctx {
            values: samples.values(),
            grid,
            iso: samples.iso(),
            placement: self.placement,
            field,
            tables: Tables::get(),
            sweep_normals: !smoothing,
            keep_cell_min: smoothing || out.origins.wanted || keep_quads,
        };
        let cell_layers = nz - 1;
        let tasks = crate::sweep::slabs::task_count(self.options.parallelism, grid.cell_count(), cell_layers);
        while s.slabs.len() < tasks {
            s.slabs.push(Slab::default());
        }
        let slabs = &mut s.slabs[..tasks];
        let t_slabs = Instant::now();
        let mut joined = false;
        if tasks > 1 && out.surface.positions.capacity() == 0 && !smoothing && !ctx.keep_cell_min {
            // A fresh output (one-shot) without smoothing, in flying edges' order: count every
            // slab's output, allocate the output once, then let each slab write its own piece of
            // it. Every page of the output is touched once, by the thread that fills it, and no
            // slab buffers are filled and copied.
            self.extract_into_pieces(&ctx, slabs, cell_layers, &mut out.surface)?;
            joined = true;
        } else if tasks == 1 {
            std::mem::swap(&mut slabs[0].mesh, &mut out.surface);
            std::mem::swap(&mut slabs[0].cell_min, &mut s.cell_min);
            std::mem::swap(&mut slabs[0].links, &mut s.links);
            ctx.slab(0, cell_layers, links, &mut slabs[0]);
            std::mem::swap(&mut slabs[0].mesh, &mut out.surface);
            std::mem::swap(&mut slabs[0].cell_min, &mut s.cell_min);
            std::mem::swap(&mut slabs[0].links, &mut s.links);
        } else {
            for_each_slab(slabs, |t, slab| {
                ctx.slab(t * cell_layers / tasks, (t + 1) * cell_layers / tasks, links, slab);
            });
        }
        let slab_wall = t_slabs.elapsed();
        let t_join = Instant::now();
        if tasks > 1 && !joined {
            let offsets = slab_offsets(slabs.iter().map(|slab| slab.mesh.positions.len()), self.name)?;
            let slabs: &[Slab] = slabs;
            // Where slab `t`'s tagged indices point: the first vertex of the slab below's last layer.
            let below = |t: usize| if t > 0 { offsets[t - 1] as u32 + slabs[t - 1].last_layer_start } else { 0 };
            let copy = |_: usize, part: &[Vec3], piece: &mut [Vec3]| piece.copy_from_slice(part);
            join_parts(&mut out.surface.positions, &slabs.iter().map(|sl| &sl.mesh.positions[..]).collect::<Vec<_>>(), copy);
            join_parts(&mut out.surface.normals, &slabs.iter().map(|sl| &sl.mesh.normals[..]).collect::<Vec<_>>(), copy);
            join_parts(&mut s.cell_min, &slabs.iter().map(|sl| &sl.cell_min[..]).collect::<Vec<_>>(), copy);
            let triangles: Vec<&[[u32; 3]]> = slabs.iter().map(|sl| &sl.mesh.triangles[..]).collect();
            join_parts(&mut out.surface.triangles, &triangles, |t, part, piece| {
                let (offset, below) = (offsets[t] as u32, below(t));
                for (d, s) in piece.iter_mut().zip(part) {
                    // Element by element, not `s.map(..)`: see `slabs::join_parts`' callers.
                    d[0] = resolve(s[0], offset, below);
                    d[1] = resolve(s[1], offset, below);
                    d[2] = resolve(s[2], offset, below);
                }
            });
            let links: Vec<&[(u32, u32)]> = slabs.iter().map(|sl| &sl.links[..]).collect();
            join_parts(&mut s.links, &links, |t, part, piece| {
                let (offset, below) = (offsets[t] as u32, below(t));
                for (d, &(a, b)) in piece.iter_mut().zip(part) {
                    *d = (resolve(a, offset, below), resolve(b, offset, below));
                }
            });
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
        // vertex pass without smoothing; after it, where smoothing moved the vertices).
        let t_normals = Instant::now();
        if smoothing {
            let (values, cell_min) = (samples.values(), &s.cell_min);
            let positions = &out.surface.positions;
            out.surface.normals.clear();
            let inverse_spacing = 1.0 / grid.spacing;
            out.surface.normals.par_extend(
                positions.par_iter().zip(cell_min.par_iter()).with_min_len(crate::sweep::slabs::MIN_VERTICES_PER_TASK).map(
                    |(&p, &min)| {
                        // The cell's lower corner is a lattice point: nearest integer by truncation.
                        let cell = ((min - grid.origin) * inverse_spacing + Vec3::splat(0.5)).as_uvec3();
                        let i = grid.index(cell.x as usize, cell.y as usize, cell.z as usize);
                        let (sx, sxy) = (nx, nx * ny);
                        let idx = [i, i + 1, i + 1 + sx, i + sx, i + sxy, i + 1 + sxy, i + 1 + sx + sxy, i + sx + sxy];
                        trilinear_gradient(&crate::geometry::gather(values, &idx), (p - min) / grid.spacing).normalize_or_zero()
                    },
                ),
            );
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
        if let Some(quads) = quads {
            quads.swap_with(&mut s.links, &mut s.cell_min);
        }
        self.scratch.give(held);
        Ok(scratch)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fields;
    use crate::lattice::Grid;
    use crate::sweep::sign_rows::count_crossing_edges;

    fn samples(name: &str, n: usize) -> Samples<'static> {
        let f = fields::builtin(name, Default::default()).unwrap();
        Samples::sample_cubic(f.clone(), Grid::covering(&f.domain(), n).unwrap(), 0.0).unwrap()
    }

    #[test]
    fn a_fresh_output_is_sized_once_from_the_crossing_edges() {
        for (name, n) in [("sphere", 37), ("gyroid", 41), ("terrain", 33), ("asteroid", 29)] {
            let s = samples(name, n);
            for placement in [Placement::MassPoint, Placement::Qef { tolerance: 0.1, clamp: true }] {
                let engine = DualEngine::new(
                    DualOptions { parallelism: Parallelism::Serial, smoothing: Smoothing::None, ..Default::default() },
                    placement,
                    "surface-nets",
                );
                let mut out = Extraction::default();
                out.clear();
                engine.extract_into(&s, &mut out).unwrap();
                let dims = s.grid().dims;
                let edges = count_crossing_edges(&mut LayerSigns::default(), s.values(), dims, s.iso(), 0, dims[2] - 1, true);
                let (v, t) = (out.surface.positions.len(), out.surface.triangles.len());
                // Allocated once: the capacity is the reservation, so nothing grew by doubling.
                assert_eq!(out.surface.positions.capacity(), edges + edges / 8 + 64, "{name}: {v} vertices, {edges} edges");
                assert_eq!(out.surface.triangles.capacity(), 2 * edges + 64, "{name}: {t} triangles, {edges} edges");
            }
        }
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
            // Origins wanted: the cell corners are kept without smoothing too.
            out.origins.wanted = true;
            out.clear();
            sn.extract_into(&s, &mut out).unwrap();
            let scratch = sn.scratch.take();
            assert_eq!(scratch.cell_min.len(), out.surface.positions.len(), "{smoothing:?}");
            for (p, min) in out.surface.positions.iter().zip(&scratch.cell_min) {
                let d = (*p - *min) / h;
                assert!(d.min_element() >= -1e-4 && d.max_element() <= 1.0 + 1e-4, "{smoothing:?}: {p} outside cell at {min}");
            }
        }
    }
}
