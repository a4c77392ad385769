//! # Marching cubes
//!
//! **Paper:** W. E. Lorensen and H. E. Cline, "Marching cubes: a high resolution 3D surface
//! construction algorithm", SIGGRAPH 1987, DOI 10.1145/37402.37422. The row trimming follows the
//! idea of Schroeder, Maynard & Geveci, "Flying edges" (LDAV 2015, DOI 10.1109/LDAV.2015.7348069).
//!
//! **Summary.** Each cubic cell's eight corner signs index the 256-case table
//! ([`crate::tables::marching_cubes`]); its triangles connect vertices on crossing edges, placed
//! by linear interpolation. Every lattice edge gets at most one vertex, created once when its
//! layer is swept, and found again through per-layer index arrays (no hash map). As the sweep
//! reaches a sample layer it packs the layer's inside states into bits, 64 samples to a word, and
//! summarises each x-row (uniform, or the x-range where the sign changes)
//! ([`crate::sign_rows::LayerSigns`]): uniform rows are skipped whole, crossing edges and surface
//! cells are found by word operations over 64 samples at a time, and only they are visited one by
//! one, while the layer's samples are still in cache. The volume is split into slabs
//! of cells along z meshed in parallel (rayon); vertices on a slab's bottom layer belong to the
//! slab below and are patched in when the slabs are joined, so there are no duplicates.
//!
//! **Guarantees.** The table resolves every ambiguous face the same way in both cells sharing it
//! (the inside corners are separated), so for any finite samples the surface is closed wherever
//! it does not reach the lattice boundary, edge- and vertex-manifold, and consistently oriented
//! with normals toward increasing `f`. Output is identical whether run serially or in parallel.
//!
//! **Variant `marching-cubes-decider`** (`FaceResolution::AsymptoticDecider`): ambiguous faces follow
//! the trilinear interpolant (Nielson & Hamann 1991, "The asymptotic decider", DOI
//! 10.1109/VISUAL.1991.175782): the face's saddle value decides whether its inside corners join.
//! Both cells of a face decide from the same four values, so the surface stays closed and
//! manifold (tested on all 256 patterns among random neighbours). The tables for every choice of
//! joined faces are generated like the default one; a few joined polygons (9 of their vertices can
//! lie on faces pairwise) have no triangulation free of face diagonals and are fanned around a
//! vertex inside the cell instead. The interior ambiguity (MC33) is not resolved.
//!
//! **Non-guarantees.** By default the topology is that of the table's face rule, not of the
//! trilinear interpolant (use the decider variant for that); triangles may be arbitrarily thin. Samples
//! exactly at the iso-value would give coincident vertices; by default vertices keep 1e-4 of the
//! spacing from the edge ends instead ([`OnIsoSamples`]), so no triangle has zero area.
//!
//! **Why one file of about 650 lines.** The sweep's vertex pass, geometry pass, slab join and
//! normals share one set of per-layer index arrays; split apart they would pass those arrays
//! through half a dozen signatures. It is one algorithm that reads best whole.
//!
//! **Costs.** One read of every sample to pack its sign, then work proportional to the crossing
//! edges and surface cells. Memory: five `nx * ny` index layers and two layers of sign bits per
//! slab task, plus the output.
//!
//! ```
//! use isolab_algorithms::{extractors::MarchingCubes, fields, Extraction, Extractor, Grid, Samples};
//! let sphere = fields::builtin("sphere", Default::default()).unwrap();
//! let samples = Samples::sample_cubic(sphere.clone(), Grid::covering(&sphere.domain(), 40).unwrap(), 0.0).unwrap();
//! let mut out = Extraction::default();
//! MarchingCubes::default().extract(&samples, &mut out).unwrap();
//! // Every vertex lies close to the sphere of radius 0.4.
//! assert!(out.surface.positions.iter().all(|p| (p.length() - 0.4).abs() < 2e-3));
//! ```

use crate::extract::{Chunking, ExtractError, Extraction, Extractor, ExtractorInfo, Guarantees};
use crate::geometry::trilinear_gradient;
use crate::lattice::{Grid, Lattice};
use crate::mesh::TriMesh;
use crate::samples::Samples;
use crate::sign_rows::{
    count_crossing_edges, for_each_bit, for_each_surface_cell, layer_edge_words, span, z_edge_words, LayerSigns,
};
use crate::slabs::{grow_zeroed, slab_offsets, split_slab_time, Parallelism, ScratchPool, EXTERN};
use crate::tables::marching_cubes::{
    decider_joins_inside, Case, AMBIGUOUS_FACES, CORNERS, EDGES, FACES, FACE_CHOICE_TABLE, TABLE,
};
use glam::Vec3;
use rayon::prelude::*;
use std::time::{Duration, Instant};

/// Where vertex normals come from.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum NormalSource {
    /// The field's gradient when it is analytic, else [`NormalSource::SampleGradient`].
    #[default]
    Auto,
    /// The field's gradient (analytic or central differences of the field itself).
    FieldGradient,
    /// Central differences of the samples, interpolated along the edge (what VTK does).
    SampleGradient,
    /// Area-weighted mean of incident triangle normals.
    FaceAverage,
    /// No normals.
    None,
}

/// What to do with samples exactly at the iso-value.
///
/// Such a sample counts as outside, and every crossing edge that ends at it would put its vertex
/// exactly on it: several distinct vertices at one point, zero-area triangles, and triangles of
/// neighbouring cells touching there (self-intersections, as CGAL counts them). This happens on
/// real data: the gyroid is exactly zero on whole planes of grid points.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum OnIsoSamples {
    /// Keep every vertex at least [`MIN_EDGE_FRACTION`] of the spacing away from both ends of its
    /// edge, as if such samples were a hair above the iso-value (default).
    #[default]
    Separate,
    /// Interpolate exactly, as VTK and scikit-image do (for side-by-side equivalence tests).
    Exact,
}

/// Smallest distance of a vertex from an edge's ends, as a fraction of the spacing, under
/// [`OnIsoSamples::Separate`] (shared with the tetrahedral extractors).
pub use crate::geometry::MIN_EDGE_FRACTION;

/// How ambiguous faces (two diagonal corners inside, two outside) are resolved.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum FaceResolution {
    /// Always separate the inside corners (the default table: fast, closed, manifold).
    #[default]
    SeparateInside,
    /// Follow the trilinear interpolant on the face: the asymptotic decider (Nielson & Hamann
    /// 1991). Still closed and manifold; topologically faithful on every face (the cell interior
    /// ambiguity of MC33 is not resolved).
    AsymptoticDecider,
}

/// Options for [`MarchingCubes`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct McOptions {
    /// Vertex normals (default [`NormalSource::Auto`]).
    pub normals: NormalSource,
    /// Parallelism (default [`Parallelism::Rayon`]).
    pub parallelism: Parallelism,
    /// Samples exactly at the iso-value (default [`OnIsoSamples::Separate`]).
    pub on_iso: OnIsoSamples,
    /// Ambiguous faces (default [`FaceResolution::SeparateInside`]).
    pub faces: FaceResolution,
}

/// One line for listings.
pub const DESCRIPTION: &str = "Lorensen & Cline 1987: 256-case cube table, one vertex per crossing edge, linear interpolation";

/// Options by name: `normals` (auto, field, samples, faces, none), `parallelism` (rayon, serial),
/// `on-iso` (separate, exact).
pub const OPTION_NAMES: &[&str] = &["normals", "parallelism", "on-iso", "faces"];

/// Lorensen & Cline 1987: the 256-case cube table, one vertex per crossing edge.
pub const INFO: ExtractorInfo = ExtractorInfo {
    name: "marching-cubes",
    description: DESCRIPTION,
    options: OPTION_NAMES,
    make: from_options,
    guarantees: Guarantees { cubic: true, bcc: false, closed: true, manifold: true, outward: true, intersection_free: false },
};

/// Nielson & Hamann 1991: marching cubes whose ambiguous faces follow the trilinear interpolant.
pub const DECIDER_INFO: ExtractorInfo = ExtractorInfo {
    name: "marching-cubes-decider",
    description: DECIDER_DESCRIPTION,
    options: OPTION_NAMES,
    make: decider_from_options,
    guarantees: Guarantees { cubic: true, bcc: false, closed: true, manifold: true, outward: true, intersection_free: false },
};

/// Builds marching cubes from named options.
pub fn from_options(options: &crate::options::Options) -> Result<Box<dyn Extractor>, crate::options::OptionError> {
    build(options, INFO.name, FaceResolution::SeparateInside)
}

/// One line for listings of the asymptotic-decider variant.
pub const DECIDER_DESCRIPTION: &str =
    "marching cubes with ambiguous faces resolved by the asymptotic decider (Nielson & Hamann 1991)";

/// Builds the asymptotic-decider variant (`marching-cubes-decider`) from named options.
pub fn decider_from_options(options: &crate::options::Options) -> Result<Box<dyn Extractor>, crate::options::OptionError> {
    build(options, DECIDER_INFO.name, FaceResolution::AsymptoticDecider)
}

fn build(
    options: &crate::options::Options,
    name: &'static str,
    default_faces: FaceResolution,
) -> Result<Box<dyn Extractor>, crate::options::OptionError> {
    let mut r = options.reader(name, OPTION_NAMES);
    let normals = r.choice(
        "normals",
        NormalSource::Auto,
        &[
            ("auto", NormalSource::Auto),
            ("field", NormalSource::FieldGradient),
            ("samples", NormalSource::SampleGradient),
            ("faces", NormalSource::FaceAverage),
            ("none", NormalSource::None),
        ],
    )?;
    let parallelism =
        r.choice("parallelism", Parallelism::Rayon, &[("rayon", Parallelism::Rayon), ("serial", Parallelism::Serial)])?;
    let on_iso =
        r.choice("on-iso", OnIsoSamples::Separate, &[("separate", OnIsoSamples::Separate), ("exact", OnIsoSamples::Exact)])?;
    let faces = r.choice(
        "faces",
        default_faces,
        &[("separate", FaceResolution::SeparateInside), ("decider", FaceResolution::AsymptoticDecider)],
    )?;
    r.finish()?;
    Ok(Box::new(MarchingCubes::new(McOptions { normals, parallelism, on_iso, faces })))
}

/// Marching cubes on a cubic grid. Keeps its scratch buffers between calls, so re-meshing the same
/// size of grid allocates nothing once the output has grown.
#[derive(Default)]
pub struct MarchingCubes {
    /// The options.
    pub options: McOptions,
    /// One call's buffers: a scratch per slab task.
    scratch: ScratchPool<Vec<Scratch>>,
}

impl MarchingCubes {
    /// Marching cubes with `options`.
    pub fn new(options: McOptions) -> Self {
        Self { options, ..Self::default() }
    }
}

#[derive(Default)]
struct Scratch {
    x_lo: Vec<u32>,
    y_lo: Vec<u32>,
    x_hi: Vec<u32>,
    y_hi: Vec<u32>,
    z_mid: Vec<u32>,
    /// The sign bits of the two sample layers the sweep is between.
    signs: LayerSigns,
    mesh: TriMesh,
    vertex_time: Duration,
    geometry_time: Duration,
    active_cells: usize,
}

impl Scratch {
    fn prepare(&mut self, layer: usize) {
        for b in [&mut self.x_lo, &mut self.y_lo, &mut self.x_hi, &mut self.y_hi, &mut self.z_mid] {
            grow_zeroed(b, layer);
        }
        self.mesh.clear();
        self.vertex_time = Duration::ZERO;
        self.geometry_time = Duration::ZERO;
        self.active_cells = 0;
    }

    fn bytes(&self) -> usize {
        4 * (self.x_lo.capacity() + self.y_lo.capacity() + self.x_hi.capacity() + self.y_hi.capacity() + self.z_mid.capacity())
            + self.signs.capacity_bytes()
            + self.mesh.capacity_bytes()
    }
}

/// Read-only inputs of a slab task.
struct Ctx<'a> {
    values: &'a [f32],
    grid: Grid,
    iso: f32,
    sample_normals: bool,
    /// Clamp of the interpolation parameter to `[t_min, 1 - t_min]`.
    t_min: f32,
    /// Resolve ambiguous faces with the asymptotic decider.
    decider: bool,
}

impl Ctx<'_> {
    /// Gradient of the samples at grid point `(x, y, z)` (central differences, one-sided at
    /// the boundary).
    fn sample_gradient(&self, x: usize, y: usize, z: usize) -> Vec3 {
        let g = &self.grid;
        let c = [x, y, z];
        let mut out = [0.0f32; 3];
        for a in 0..3 {
            let (mut lo, mut hi) = (c, c);
            if c[a] > 0 {
                lo[a] -= 1;
            }
            if c[a] + 1 < g.dims[a] {
                hi[a] += 1;
            }
            let steps = (hi[a] - lo[a]) as f32;
            out[a] = (self.values[g.index(hi[0], hi[1], hi[2])] - self.values[g.index(lo[0], lo[1], lo[2])]) / steps;
        }
        Vec3::from(out)
    }

    /// Creates the vertex on the edge from sample `a` to the next sample along `axis`.
    #[inline(always)]
    fn push_vertex(&self, mesh: &mut TriMesh, a: [usize; 3], axis: usize) -> u32 {
        let g = &self.grid;
        let i = g.index(a[0], a[1], a[2]);
        let stride = [1, g.dims[0], g.dims[0] * g.dims[1]][axis];
        let (va, vb) = (self.values[i], self.values[i + stride]);
        let t = ((self.iso - va) / (vb - va)).clamp(self.t_min, 1.0 - self.t_min);
        let mut p = g.position(a[0], a[1], a[2]);
        p[axis] += t * g.spacing;
        let index = mesh.positions.len() as u32;
        mesh.positions.push(p);
        if self.sample_normals {
            let mut b = a;
            b[axis] += 1;
            let ga = self.sample_gradient(a[0], a[1], a[2]);
            let gb = self.sample_gradient(b[0], b[1], b[2]);
            mesh.normals.push(ga.lerp(gb, t).normalize_or_zero());
        }
        index
    }

    /// Vertices on the x- and y-edges of sample layer `z`.
    fn layer_vertices(&self, signs: &LayerSigns, z: usize, xs: &mut [u32], ys: &mut [u32], mesh: &mut TriMesh) {
        let nx = self.grid.dims[0];
        layer_edge_words(signs, self.grid.dims, z, |y, axis, lo, hi, word| {
            let ids = if axis == 0 { &mut *xs } else { &mut *ys };
            for_each_bit(lo, hi, word, |x| ids[x + nx * y] = self.push_vertex(mesh, [x, y, z], axis));
        });
    }

    /// Vertices on the z-edges between sample layers `z` and `z + 1`.
    fn z_vertices(&self, signs: &LayerSigns, z: usize, zs: &mut [u32], mesh: &mut TriMesh) {
        let nx = self.grid.dims[0];
        z_edge_words(signs, self.grid.dims, z, |y, axis, lo, hi, word| {
            for_each_bit(lo, hi, word, |x| zs[x + nx * y] = self.push_vertex(mesh, [x, y, z], axis));
        });
    }

    /// Triangles of the cells between sample layers `z` and `z + 1`. When `extern_bottom`, the
    /// bottom layer's x/y-edge vertices belong to the slab below and are written as tagged
    /// references `EXTERN | (2 * (x + nx * y) + axis)`.
    fn cells(&self, signs: &LayerSigns, z: usize, extern_bottom: bool, s: &mut Scratch) -> usize {
        let [nx, ny, _] = self.grid.dims;
        let layer = nx * ny;
        let mut active = 0;
        let tag = |i: usize, axis: u32| EXTERN | (2 * i as u32 + axis);
        for y in 0..ny - 1 {
            let rows = [signs.row(y, z), signs.row(y + 1, z), signs.row(y, z + 1), signs.row(y + 1, z + 1)];
            let Some((lo, hi)) = span(&rows, nx) else { continue };
            let base = self.grid.index(0, y, z);
            let bits = [signs.bits(y, z), signs.bits(y + 1, z), signs.bits(y, z + 1), signs.bits(y + 1, z + 1)];
            for_each_surface_cell(bits, lo.saturating_sub(1), hi.min(nx - 2), |x, case| {
                let case = case as usize;
                let i = base + x;
                let corners = [i, i + 1, i + 1 + nx, i + nx, i + layer, i + 1 + layer, i + 1 + nx + layer, i + nx + layer];
                active += 1;
                let ambiguous = if self.decider { AMBIGUOUS_FACES[case] } else { 0 };
                let entry = if ambiguous == 0 {
                    &TABLE[case]
                } else {
                    let mut joins = 0usize;
                    for (f, (cycle, _)) in FACES.iter().enumerate() {
                        if ambiguous >> f & 1 == 1 {
                            let v = cycle.map(|k| f64::from(self.values[corners[k as usize]]) - f64::from(self.iso));
                            joins |= usize::from(decider_joins_inside(v)) << f;
                        }
                    }
                    &FACE_CHOICE_TABLE[case * 64 + joins]
                };
                let e = x + nx * y;
                let mut ids = [0u32; 16];
                let mut mask = entry.edge_mask;
                while mask != 0 {
                    let edge = mask.trailing_zeros() as usize;
                    mask &= mask - 1;
                    ids[edge] = match edge {
                        0 if extern_bottom => tag(e, 0),
                        1 if extern_bottom => tag(e + 1, 1),
                        2 if extern_bottom => tag(e + nx, 0),
                        3 if extern_bottom => tag(e, 1),
                        0 => s.x_lo[e],
                        1 => s.y_lo[e + 1],
                        2 => s.x_lo[e + nx],
                        3 => s.y_lo[e],
                        4 => s.x_hi[e],
                        5 => s.y_hi[e + 1],
                        6 => s.x_hi[e + nx],
                        7 => s.y_hi[e],
                        8 => s.z_mid[e],
                        9 => s.z_mid[e + 1],
                        10 => s.z_mid[e + 1 + nx],
                        _ => s.z_mid[e + nx],
                    };
                }
                if entry.interior != 0 {
                    self.interior_vertices(entry, &corners, [x, y, z], &mut ids, &mut s.mesh);
                }
                for t in entry.triangles() {
                    s.mesh.triangles.push(t.map(|edge| ids[edge as usize]));
                }
            });
        }
        active
    }

    /// Vertices inside the cell for the polygons the table fans around one (joined ambiguous
    /// faces only): the mean of the polygon's edge crossings, stored in `ids[12 + polygon]`.
    fn interior_vertices(&self, entry: &Case, corners: &[usize; 8], cell: [usize; 3], ids: &mut [u32; 16], mesh: &mut TriMesh) {
        let values = corners.map(|i| self.values[i]);
        for piece in 0..entry.polygons {
            if entry.interior >> piece & 1 == 0 {
                continue;
            }
            let (mut sum, mut n) = (Vec3::ZERO, 0.0f32);
            for (edge, &(a, b)) in EDGES.iter().enumerate() {
                if entry.edge_polygon[edge] == piece {
                    let (va, vb) = (values[a as usize], values[b as usize]);
                    let t = ((self.iso - va) / (vb - va)).clamp(self.t_min, 1.0 - self.t_min);
                    let pa = Vec3::from(CORNERS[a as usize].map(f32::from));
                    let pb = Vec3::from(CORNERS[b as usize].map(f32::from));
                    sum += pa + (pb - pa) * t;
                    n += 1.0;
                }
            }
            let local = sum / n;
            ids[12 + piece as usize] = mesh.positions.len() as u32;
            mesh.positions.push(self.grid.position(cell[0], cell[1], cell[2]) + local * self.grid.spacing);
            if self.sample_normals {
                mesh.normals.push(trilinear_gradient(&values, local).normalize_or_zero());
            }
        }
    }

    /// Meshes cell slabs `z0..z1` into `s.mesh`; afterwards `s.x_lo`/`s.y_lo` hold the vertex
    /// indices of the top layer `z1`.
    fn slab(&self, z0: usize, z1: usize, extern_bottom: bool, s: &mut Scratch) {
        let [nx, ny, _] = self.grid.dims;
        s.prepare(nx * ny);
        let mut signs = std::mem::take(&mut s.signs);
        let start = Instant::now();
        if s.mesh.positions.capacity() == 0 {
            // A fresh output (one-shot): count the vertices and allocate once, instead of
            // growing the vectors by doubling, which copies them and touches twice the pages.
            let vertices = count_crossing_edges(&mut signs, self.values, self.grid.dims, self.iso, z0, z1, !extern_bottom);
            reserve_for(&mut s.mesh, vertices, self.sample_normals);
        }
        signs.reset(nx, ny);
        signs.classify(self.values, self.grid.dims, self.iso, z0);
        if !extern_bottom {
            self.layer_vertices(&signs, z0, &mut s.x_lo, &mut s.y_lo, &mut s.mesh);
        }
        s.vertex_time += start.elapsed();
        for z in z0..z1 {
            let t0 = Instant::now();
            signs.classify(self.values, self.grid.dims, self.iso, z + 1);
            self.z_vertices(&signs, z, &mut s.z_mid, &mut s.mesh);
            self.layer_vertices(&signs, z + 1, &mut s.x_hi, &mut s.y_hi, &mut s.mesh);
            let t1 = Instant::now();
            s.active_cells += self.cells(&signs, z, extern_bottom && z == z0, s);
            s.geometry_time += t1.elapsed();
            s.vertex_time += t1 - t0;
            std::mem::swap(&mut s.x_lo, &mut s.x_hi);
            std::mem::swap(&mut s.y_lo, &mut s.y_hi);
        }
        s.signs = signs;
    }
}

/// Reserves room for `vertices` vertices (a little more, for the decider's cell-interior
/// vertices) and the triangles they usually make: a closed surface of genus `g` has
/// `2 V + 4 (g - 1)` triangles, so `2 V` plus a margin for high genus (the gyroid); an open one
/// fewer. Capacity never written is never touched, so the margin costs no time.
fn reserve_for(mesh: &mut TriMesh, vertices: usize, normals: bool) {
    let positions = vertices + vertices / 64 + 16;
    mesh.positions.reserve_exact(positions);
    if normals {
        mesh.normals.reserve_exact(positions);
    }
    mesh.triangles.reserve_exact(2 * vertices + vertices / 8 + 64);
}

/// Elements a join task copies at least (keeps rayon's splitting coarse).
const JOIN_CHUNK: usize = 1 << 14;

/// Which slab an output element comes from, remembered between consecutive elements of one join
/// task (they are consecutive indices, so the slab changes rarely).
#[derive(Default)]
struct SlabCursor(usize);

impl SlabCursor {
    /// The slab `t` with `offsets[t] <= i < offsets[t + 1]`.
    #[inline]
    fn slab_of(&mut self, offsets: &[usize], i: usize) -> usize {
        if i < offsets[self.0] || i >= offsets[self.0 + 1] {
            self.0 = offsets.partition_point(|&o| o <= i) - 1;
        }
        self.0
    }
}

/// Resolves a slab-local index to a global one.
#[inline]
fn resolve(i: u32, offset: u32, below: Option<(&Scratch, u32)>) -> u32 {
    if i & EXTERN == 0 {
        return i + offset;
    }
    let key = (i & !EXTERN) as usize;
    let (prev, prev_offset) = below.expect("only slabs above the first have external references");
    let local = if key % 2 == 0 { prev.x_lo[key / 2] } else { prev.y_lo[key / 2] };
    local + prev_offset
}

impl Extractor for MarchingCubes {
    fn name(&self) -> &'static str {
        match self.options.faces {
            FaceResolution::SeparateInside => INFO.name,
            FaceResolution::AsymptoticDecider => DECIDER_INFO.name,
        }
    }

    fn chunking(&self) -> Chunking {
        Chunking::CellLocal
    }

    fn description(&self) -> &'static str {
        match self.options.faces {
            FaceResolution::SeparateInside => DESCRIPTION,
            FaceResolution::AsymptoticDecider => DECIDER_DESCRIPTION,
        }
    }

    fn extract(&self, samples: &Samples, out: &mut Extraction) -> Result<(), ExtractError> {
        out.clear();
        out.stats.times.sampling = samples.sampling_time();
        let Lattice::Cubic(grid) = *samples.lattice() else {
            return Err(ExtractError::UnsupportedLattice {
                algorithm: self.name(),
                lattice: samples.lattice().kind(),
                supported: "cubic",
            });
        };
        let nz = grid.dims[2];
        let field = samples.field().filter(|f| match self.options.normals {
            NormalSource::Auto => f.has_analytic_gradient(),
            NormalSource::FieldGradient => true,
            _ => false,
        });
        let sample_normals = field.is_none() && matches!(self.options.normals, NormalSource::Auto | NormalSource::SampleGradient);

        let start = Instant::now();
        let mut held = self.scratch.take();
        let pool = &mut held;
        let t_min = match self.options.on_iso {
            OnIsoSamples::Separate => MIN_EDGE_FRACTION,
            OnIsoSamples::Exact => 0.0,
        };
        let decider = self.options.faces == FaceResolution::AsymptoticDecider;
        let ctx = Ctx { values: samples.values(), grid, iso: samples.iso(), sample_normals, t_min, decider };
        let setup_time = start.elapsed();

        let slab_cells = nz - 1;
        let tasks = crate::slabs::task_count(self.options.parallelism, grid.cell_count(), slab_cells);
        while pool.len() < tasks {
            pool.push(Scratch::default());
        }
        let scratches = &mut pool[..tasks];

        let t_slabs = Instant::now();
        if tasks == 1 {
            std::mem::swap(&mut scratches[0].mesh, &mut out.surface);
            ctx.slab(0, slab_cells, false, &mut scratches[0]);
            std::mem::swap(&mut scratches[0].mesh, &mut out.surface);
        } else {
            scratches
                .par_iter_mut()
                .enumerate()
                .for_each(|(t, s)| ctx.slab(t * slab_cells / tasks, (t + 1) * slab_cells / tasks, t > 0, s));
        }
        let slab_wall = t_slabs.elapsed();

        let t_join = Instant::now();
        if tasks > 1 {
            let offsets = slab_offsets(scratches.iter().map(|s| s.mesh.positions.len()), self.name())?;
            // Written in parallel straight into the output's capacity (a fresh output's pages are
            // first touched here, by both threads, instead of by a serial fill).
            let surface = &mut out.surface;
            let total = offsets[tasks];
            let scratches: &[Scratch] = scratches;
            let tri_offsets: Vec<usize> = std::iter::once(0)
                .chain(scratches.iter().scan(0, |sum, s| {
                    *sum += s.mesh.triangles.len();
                    Some(*sum)
                }))
                .collect();
            surface.positions.par_extend((0..total).into_par_iter().with_min_len(JOIN_CHUNK).map_init(
                SlabCursor::default,
                |c, i| {
                    let t = c.slab_of(&offsets, i);
                    scratches[t].mesh.positions[i - offsets[t]]
                },
            ));
            if ctx.sample_normals {
                surface.normals.par_extend((0..total).into_par_iter().with_min_len(JOIN_CHUNK).map_init(
                    SlabCursor::default,
                    |c, i| {
                        let t = c.slab_of(&offsets, i);
                        scratches[t].mesh.normals[i - offsets[t]]
                    },
                ));
            }
            surface.triangles.par_extend((0..tri_offsets[tasks]).into_par_iter().with_min_len(JOIN_CHUNK).map_init(
                SlabCursor::default,
                |c, i| {
                    let t = c.slab_of(&tri_offsets, i);
                    let below = (t > 0).then(|| (&scratches[t - 1], offsets[t - 1] as u32));
                    scratches[t].mesh.triangles[i - tri_offsets[t]].map(|v| resolve(v, offsets[t] as u32, below))
                },
            ));
        } else if out.surface.positions.len() >= EXTERN as usize {
            return Err(ExtractError::TooLarge { algorithm: self.name(), vertices: out.surface.positions.len() });
        }
        let join_time = t_join.elapsed();

        let (cpu_v, cpu_g) =
            scratches.iter().fold((0.0, 0.0), |(v, g), s| (v + s.vertex_time.as_secs_f64(), g + s.geometry_time.as_secs_f64()));
        let (vertex_time, geometry_time) = split_slab_time(slab_wall, join_time, cpu_v, cpu_g);
        out.stats.times.vertex = setup_time + vertex_time;
        out.stats.times.geometry = geometry_time;
        out.stats.active_cells = scratches.iter().map(|s| s.active_cells).sum();

        let t_normals = Instant::now();
        match (field, self.options.normals) {
            (Some(f), _) => {
                let positions = &out.surface.positions;
                out.surface.normals.clear();
                out.surface.normals.par_extend(positions.par_iter().map(|&p| f.gradient(p).normalize_or_zero()));
            }
            (None, NormalSource::FaceAverage | NormalSource::FieldGradient) => out.surface.compute_face_weighted_normals(),
            (None, NormalSource::None) => out.surface.normals.clear(),
            _ => {}
        }
        out.stats.times.normals = t_normals.elapsed();
        let scratch_bytes = pool.iter().map(Scratch::bytes).sum::<usize>();
        self.scratch.give(held);
        out.finish_counts(scratch_bytes);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fields;

    fn sphere_samples(n: usize) -> Samples {
        let f = fields::builtin("sphere", Default::default()).unwrap();
        Samples::sample_cubic(f.clone(), Grid::covering(&f.domain(), n).unwrap(), 0.0).unwrap()
    }

    #[test]
    fn the_vertex_count_before_the_sweep_is_exact_and_a_fresh_output_never_grows() {
        for (name, n) in [("sphere", 37), ("gyroid", 41), ("terrain", 33), ("asteroid", 29)] {
            let f = fields::builtin(name, Default::default()).unwrap();
            let s = Samples::sample_cubic(f.clone(), Grid::covering(&f.domain(), n).unwrap(), 0.0).unwrap();
            let Lattice::Cubic(grid) = *s.lattice() else { unreachable!() };
            let ctx =
                Ctx { values: s.values(), grid, iso: s.iso(), sample_normals: false, t_min: MIN_EDGE_FRACTION, decider: false };
            let mut out = Extraction::default();
            let mc = MarchingCubes::new(McOptions {
                normals: NormalSource::None,
                parallelism: Parallelism::Serial,
                ..Default::default()
            });
            mc.extract(&s, &mut out).unwrap();
            let nz = grid.dims[2];
            let mut signs = LayerSigns::default();
            let count = |signs: &mut LayerSigns, z0, z1, bottom| {
                count_crossing_edges(signs, ctx.values, grid.dims, ctx.iso, z0, z1, bottom)
            };
            assert_eq!(count(&mut signs, 0, nz - 1, true), out.surface.positions.len(), "{name}");
            // Slabs: the bottom layer of a slab above the first is counted by the slab below.
            let mid = nz / 2;
            let split = count(&mut signs, 0, mid, true) + count(&mut signs, mid, nz - 1, false);
            assert_eq!(split, out.surface.positions.len(), "{name}, two slabs");
            // Allocated once: the capacity is the reservation, not a doubling.
            let v = out.surface.positions.len();
            assert_eq!(out.surface.positions.capacity(), v + v / 64 + 16, "{name}");
            assert!(out.surface.triangles.len() <= out.surface.triangles.capacity());
            assert_eq!(out.surface.triangles.capacity(), 2 * v + v / 8 + 64, "{name}: the triangles fit the estimate");
        }
    }

    #[test]
    fn serial_and_parallel_give_the_same_mesh() {
        let s = sphere_samples(90);
        let mut a = Extraction::default();
        let mut b = Extraction::default();
        MarchingCubes::new(McOptions { parallelism: Parallelism::Serial, ..Default::default() }).extract(&s, &mut a).unwrap();
        let par = MarchingCubes::default();
        par.extract(&s, &mut b).unwrap();
        assert_eq!(a.surface.positions.len(), b.surface.positions.len());
        assert_eq!(a.surface.triangles.len(), b.surface.triangles.len());
        // Same triangles as position triples (vertex order differs between runs).
        let key = |m: &TriMesh| {
            let mut v: Vec<[[u32; 3]; 3]> =
                m.triangles.iter().map(|t| t.map(|i| m.positions[i as usize].to_array().map(f32::to_bits))).collect();
            v.sort_unstable();
            v
        };
        assert_eq!(key(&a.surface), key(&b.surface));
    }

    #[test]
    fn bcc_samples_are_refused() {
        let f = fields::builtin("sphere", Default::default()).unwrap();
        let s = Samples::sample(f.clone(), Lattice::Bcc(Grid::covering(&f.domain(), 8).unwrap()), 0.0).unwrap();
        let err = MarchingCubes::default().extract(&s, &mut Extraction::default()).unwrap_err();
        assert!(err.to_string().contains("cubic"), "{err}");
    }

    #[test]
    fn reuse_keeps_buffers() {
        let s = sphere_samples(40);
        let mc = MarchingCubes::default();
        let mut out = Extraction::default();
        mc.extract(&s, &mut out).unwrap();
        let cap = out.surface.positions.capacity();
        let first = out.clone();
        mc.extract(&s, &mut out).unwrap();
        assert_eq!(out.surface, first.surface);
        assert_eq!(out.surface.positions.capacity(), cap);
    }
}
