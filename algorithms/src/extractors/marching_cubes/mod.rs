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
//! ([`crate::sweep::sign_rows::LayerSigns`]): uniform rows are skipped whole, crossing edges and surface
//! cells are found by word operations over 64 samples at a time, and only they are visited one by
//! one, while the layer's samples are still in cache. The volume is split into slabs
//! of cells along z meshed in parallel (rayon); vertices on a slab's bottom layer belong to the
//! slab below, so there are no duplicates. Into a fresh output (one-shot), the slabs work in
//! flying edges' order: each first counts the vertices and triangles it will make, from the sign
//! bits alone; the output is allocated once at its exact size; then each slab writes its own piece
//! of it, numbering its bottom layer's vertices from where the slab below's top layer starts. No
//! slab buffers, no copy, and every output page is touched once. Into a reused output (steady
//! state), each slab meshes into its own kept buffers, with tagged references to the slab below,
//! and the buffers are copied into the output in parallel: the samples are read once, which
//! costs less than a counting pass once the buffers are warm.
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
//! **Variant `marching-cubes-33`** (`FaceResolution::Trilinear`): the faces as the decider
//! variant, and inside each cell the tunnels of the trilinear interpolant (Chernyaev 1995,
//! "Marching cubes 33"; Lewiner et al. 2003, DOI 10.1080/10867651.2003.10487582): where two
//! regions of one sign that the faces keep apart join through the cell, their two polygons become
//! one tube. The interior test is exact, not Lewiner's one-slice test
//! ([`crate::tables::marching_cubes_33`]). Every cell's mesh then has the components and Euler
//! characteristic of the interpolant's level set in the cell (tested on all 256 patterns against
//! a fine sampling of the interpolant). Polygons of eight or more vertices, and the tubes whose
//! band would need a side on a cube face, are fanned around a vertex inside the cell at
//! Lewiner's weighted centre, as their tables do. A tube is the first of
//! several triangulations that does not cross itself at the cell's own vertices; where none
//! avoids it the first is kept, so it promises no freedom from self-intersections (the
//! `real_volumes` page counts them).
//!
//! **Non-guarantees.** By default the topology is that of the table's face rule, not of the
//! trilinear interpolant (use the decider variant for that); triangles may be arbitrarily thin. Samples
//! exactly at the iso-value would give coincident vertices; by default vertices keep 1e-4 of the
//! spacing from the edge ends instead ([`OnIsoSamples`]), so no triangle has zero area.
//!
//! **Samples where they lie.** The sweep is generic over the sample type and reads a
//! [`GridView`]: owned `f32` samples, or a caller's array borrowed in its own type (bool, 8- to
//! 32-bit integers, `f32`, `f64`) and memory order through its strides, each loop compiled for
//! each type ([`crate::samples::view`]). It checks that the samples are finite as it packs their
//! signs. A [`Frame`] writes the vertices in the caller's axis order and scale and winds the
//! triangles its way, and [`VertexValues`] gives each vertex a value (scikit-image's `values`:
//! an edge vertex's is raised by every surface cell around its edge as the cells are meshed), so
//! a caller that wants its arrays in another frame gets them written once (the Python package's
//! scikit-image drop-in).
//!
//! **Why one file of about 1100 lines.** The sweep's vertex pass, geometry pass, counting pass, slab
//! join, normals and values share one set of per-layer index arrays; split apart they would pass
//! those arrays through half a dozen signatures. It is one algorithm that reads best whole (the
//! frame and the cell ranges, which need none of them, are in `output.rs`).
//!
//! **Costs.** One read of every sample to pack its sign (on one thread into a fresh output, plus 32
//! sampled cell layers to estimate its size on grids of over 4 Mi samples; on the one-shot parallel
//! path two: the count and the sweep), then work proportional to the crossing edges and surface
//! cells; normals read ten samples a vertex, values eight a surface cell. Memory: five `nx * ny`
//! index layers and two layers of sign bits per slab task, plus the output.
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

use crate::extract::{Chunking, ExtractError, Extraction, Extractor, ExtractorInfo, Guarantees, LevelsOfDetail, SampleAccess};
use crate::geometry::trilinear_gradient;
use crate::lattice::{Grid, Lattice};
use crate::mesh::TriMesh;
use crate::samples::{GridView, Sample, SampleError, Samples};
use crate::sweep::sign_rows::{
    count_bits, count_crossing_edges_in, for_each_bit, for_each_surface_cell, layer_edge_words, span, z_edge_words, LayerSigns,
};
use crate::sweep::slabs::{
    for_each_slab, grow_zeroed, join_parts, mesh_pieces, resize_zeroed, slab_offsets, split_pieces, split_slab_time, Parallelism,
    ScratchPool, EXTERN,
};
use crate::tables::marching_cubes::{
    decider_joins_inside, Case, AMBIGUOUS_FACES, CORNERS, EDGES, FACES, FACE_CHOICE_TABLE, TABLE,
};
use crate::tables::marching_cubes_33;
use glam::Vec3;
use rayon::prelude::*;
use std::time::{Duration, Instant};

mod output;
use output::is_whole;
pub use output::{cell_range, cell_range_at, is_at_sample, larger, range_of_corners, sample_value, smaller, Frame, VertexValues};

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
    /// Interpolate exactly, as VTK and scikit-image do (for side-by-side equivalence tests). An
    /// ambiguous face whose outside corners are both at the iso-value then joins its inside
    /// corners (with the default face rule), so no two triangles lie back to back on the same
    /// three samples (tested on every pattern of a cell's corners at the iso-value).
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
    /// Follow the trilinear interpolant on the faces (the asymptotic decider) and inside the cell
    /// (its tunnels): marching cubes 33 ([`crate::tables::marching_cubes_33`]), the default of
    /// `marching-cubes-33`.
    Trilinear,
}

/// Options for [`MarchingCubes`].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct McOptions {
    /// Vertex normals (default [`NormalSource::Auto`]).
    pub normals: NormalSource,
    /// Parallelism (default [`Parallelism::Rayon`]).
    pub parallelism: Parallelism,
    /// Samples exactly at the iso-value (default [`OnIsoSamples::Separate`]).
    pub on_iso: OnIsoSamples,
    /// Ambiguous faces (default [`FaceResolution::SeparateInside`]).
    pub faces: FaceResolution,
    /// The frame vertices are written in (default: the lattice's own).
    pub frame: Frame,
    /// A value per vertex (default none).
    pub values: VertexValues,
}

/// One line for listings.
pub const DESCRIPTION: &str = "Lorensen & Cline 1987: 256-case cube table, one vertex per crossing edge, linear interpolation";

/// Options by name: `normals` (auto, field, samples, faces, none), `parallelism` (rayon, serial),
/// `on-iso` (separate, exact), `faces` (separate: ambiguous faces separate the inside corners;
/// decider: the asymptotic decider, `marching-cubes-decider`'s default; trilinear: faces and
/// tunnels as the trilinear interpolant has them, `marching-cubes-33`'s default).
pub const OPTION_NAMES: &[&str] = &["normals", "parallelism", "on-iso", "faces"];

/// Lorensen & Cline 1987: the 256-case cube table, one vertex per crossing edge.
pub const INFO: ExtractorInfo = ExtractorInfo {
    name: "marching-cubes",
    description: DESCRIPTION,
    options: OPTION_NAMES,
    make: from_options,
    guarantees: Guarantees {
        cubic: true,
        bcc: false,
        closed: true,
        manifold: true,
        outward: true,
        intersection_free: true,
        trilinear_topology: false,
        keeps_small_parts: true,
        dihedral: None,
    },
    samples: SampleAccess::Borrowed,
};

/// Nielson & Hamann 1991: marching cubes whose ambiguous faces follow the trilinear interpolant.
pub const DECIDER_INFO: ExtractorInfo = ExtractorInfo {
    name: "marching-cubes-decider",
    description: DECIDER_DESCRIPTION,
    options: OPTION_NAMES,
    make: decider_from_options,
    guarantees: Guarantees {
        cubic: true,
        bcc: false,
        closed: true,
        manifold: true,
        outward: true,
        intersection_free: true,
        trilinear_topology: false,
        keeps_small_parts: true,
        dihedral: None,
    },
    samples: SampleAccess::Borrowed,
};

/// Chernyaev 1995 (marching cubes 33): every cell meshed with the topology of the trilinear
/// interpolant's level set, face and interior ambiguities resolved exactly.
pub const MC33_INFO: ExtractorInfo = ExtractorInfo {
    name: "marching-cubes-33",
    description: MC33_DESCRIPTION,
    options: OPTION_NAMES,
    make: mc33_from_options,
    guarantees: Guarantees {
        cubic: true,
        bcc: false,
        closed: true,
        manifold: true,
        outward: true,
        intersection_free: true,
        trilinear_topology: true,
        keeps_small_parts: true,
        dihedral: None,
    },
    samples: SampleAccess::Borrowed,
};

/// One line for listings of marching cubes 33.
pub const MC33_DESCRIPTION: &str =
    "marching cubes 33 (Chernyaev 1995, Lewiner et al. 2003): each cell follows the trilinear interpolant's topology, tunnels included";

/// Builds marching cubes 33 (`marching-cubes-33`) from named options.
pub fn mc33_from_options(options: &crate::options::Options) -> Result<Box<dyn Extractor>, crate::options::OptionError> {
    build(options, MC33_INFO.name, FaceResolution::Trilinear)
}

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
    let parallelism = r.parallelism(Parallelism::Rayon)?;
    let on_iso =
        r.choice("on-iso", OnIsoSamples::Separate, &[("separate", OnIsoSamples::Separate), ("exact", OnIsoSamples::Exact)])?;
    let faces = r.choice(
        "faces",
        default_faces,
        &[
            ("separate", FaceResolution::SeparateInside),
            ("decider", FaceResolution::AsymptoticDecider),
            ("trilinear", FaceResolution::Trilinear),
        ],
    )?;
    r.finish()?;
    Ok(Box::new(MarchingCubes::new(McOptions { normals, parallelism, on_iso, faces, ..McOptions::default() })))
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
    /// The slab's own output, when slabs are joined afterwards (a reused output).
    mesh: TriMesh,
    /// The slab's own vertex values, likewise.
    values: Vec<f32>,
    vertex_time: Duration,
    geometry_time: Duration,
    active_cells: usize,
}

impl Scratch {
    fn prepare(&mut self, layer: usize) {
        for b in [&mut self.x_lo, &mut self.y_lo, &mut self.x_hi, &mut self.y_hi, &mut self.z_mid] {
            grow_zeroed(b, layer);
        }
        self.vertex_time = Duration::ZERO;
        self.geometry_time = Duration::ZERO;
        self.active_cells = 0;
    }

    fn bytes(&self) -> usize {
        4 * (self.x_lo.capacity() + self.y_lo.capacity() + self.x_hi.capacity() + self.y_hi.capacity() + self.z_mid.capacity())
            + self.signs.capacity_bytes()
            + self.mesh.capacity_bytes()
            + 4 * self.values.capacity()
    }
}

/// Who makes the x/y-edge vertices of a slab's bottom layer.
#[derive(Clone, Copy, Debug)]
enum Bottom {
    /// This slab (the first).
    Make,
    /// The slab below, whose top layer's vertices are numbered from this global index onward
    /// (slabs writing into pieces of one output).
    Numbered(u32),
    /// The slab below, referred to by tagged indices `EXTERN | (2 * (x + nx * y) + axis)` that
    /// the join resolves (slabs writing into their own meshes).
    Tagged,
}

/// Where a slab task writes its vertices and triangles: the output mesh itself (one slab), or
/// its own pieces of the output, counted beforehand (parallel slabs).
trait Sink {
    /// Adds a vertex (and its normal and value, when made) and returns its global index.
    fn vertex(&mut self, p: Vec3, normal: Option<Vec3>, value: Option<f32>) -> u32;
    /// Adds a triangle of global indices.
    fn triangle(&mut self, t: [u32; 3]);
    /// Raises the value of vertex `id` to `value` if it is below, when the vertex is this
    /// sink's own (not one of the slab below's, which that slab made exact).
    fn raise(&mut self, id: u32, value: f32);
}

/// A mesh and its vertex values that grow as the sweep makes them.
struct Grow<'a> {
    mesh: &'a mut TriMesh,
    values: &'a mut Vec<f32>,
}

impl Sink for Grow<'_> {
    #[inline(always)]
    fn vertex(&mut self, p: Vec3, normal: Option<Vec3>, value: Option<f32>) -> u32 {
        let index = self.mesh.positions.len() as u32;
        self.mesh.positions.push(p);
        if let Some(n) = normal {
            self.mesh.normals.push(n);
        }
        if let Some(v) = value {
            self.values.push(v);
        }
        index
    }

    #[inline(always)]
    fn triangle(&mut self, t: [u32; 3]) {
        self.mesh.triangles.push(t);
    }

    #[inline(always)]
    fn raise(&mut self, id: u32, value: f32) {
        // Tagged indices name the slab below's vertices.
        if id & EXTERN == 0 {
            let slot = &mut self.values[id as usize];
            *slot = larger(*slot, value);
        }
    }
}

/// One slab's pieces of the output, sized by [`Ctx::count`]; its vertices are numbered from
/// `base`.
struct Pieces<'a> {
    positions: &'a mut [Vec3],
    /// Empty when no normals are made.
    normals: &'a mut [Vec3],
    /// Empty when no vertex values are made.
    values: &'a mut [f32],
    triangles: &'a mut [[u32; 3]],
    base: u32,
    vertices: usize,
    triangles_written: usize,
}

impl Sink for Pieces<'_> {
    #[inline(always)]
    fn vertex(&mut self, p: Vec3, normal: Option<Vec3>, value: Option<f32>) -> u32 {
        let i = self.vertices;
        self.positions[i] = p;
        if let Some(n) = normal {
            self.normals[i] = n;
        }
        if let Some(v) = value {
            self.values[i] = v;
        }
        self.vertices += 1;
        self.base + i as u32
    }

    #[inline(always)]
    fn triangle(&mut self, t: [u32; 3]) {
        self.triangles[self.triangles_written] = t;
        self.triangles_written += 1;
    }

    #[inline(always)]
    fn raise(&mut self, id: u32, value: f32) {
        // Indices below `base` are the slab below's.
        if let Some(slot) = self.values.get_mut(id.wrapping_sub(self.base) as usize) {
            *slot = larger(*slot, value);
        }
    }
}

/// What one slab will write (from [`Ctx::count`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
struct SlabCount {
    vertices: usize,
    triangles: usize,
    /// Vertices the slab writes before its top layer's x- and y-edge vertices (the slab above
    /// numbers its bottom layer from there).
    before_top: usize,
}

/// Read-only inputs of a slab task: the samples where they lie, in their own type `T`.
struct Ctx<'a, T> {
    values: GridView<'a, T>,
    grid: Grid,
    iso: f32,
    sample_normals: bool,
    /// Clamp of the interpolation parameter to `[t_min, 1 - t_min]`.
    t_min: f32,
    /// How ambiguous faces (and, for marching cubes 33, cell interiors) are resolved.
    faces: FaceResolution,
    /// The frame vertices are written in.
    frame: Frame,
    /// Whether each vertex gets its [`VertexValues::CellRange`].
    cell_ranges: bool,
    /// Element offsets of a cell's eight corners (marching cubes' corner order) from its first.
    corner_offsets: [isize; 8],
}

impl<'a, T: Sample> Ctx<'a, T> {
    fn new(values: GridView<'a, T>, grid: Grid, iso: f32, sample_normals: bool, t_min: f32, options: &McOptions) -> Self {
        let [sx, sy, sz] = values.strides();
        Ctx {
            values,
            grid,
            iso,
            sample_normals,
            t_min,
            faces: options.faces,
            frame: options.frame,
            cell_ranges: options.values == VertexValues::CellRange,
            corner_offsets: [0, sx, sx + sy, sy, sz, sx + sz, sx + sy + sz, sy + sz],
        }
    }

    /// Gradient of the samples at grid point `c` (central differences, one-sided at the
    /// boundary), whose element is `at`.
    #[inline(always)]
    fn sample_gradient(&self, c: [usize; 3], at: usize) -> Vec3 {
        let dims = self.grid.dims;
        let s = self.values.strides();
        if (0..3).all(|a| c[a] > 0 && c[a] + 1 < dims[a]) {
            // Inside the grid: a central difference along each axis.
            let diff = |a: usize| {
                (self.values.read(at.wrapping_add_signed(s[a])) - self.values.read(at.wrapping_add_signed(-s[a]))) / 2.0
            };
            return Vec3::new(diff(0), diff(1), diff(2));
        }
        let mut out = [0.0f32; 3];
        for a in 0..3 {
            let (mut lo, mut hi) = (at, at);
            let mut steps = 0.0f32;
            if c[a] > 0 {
                lo = lo.wrapping_add_signed(-s[a]);
                steps += 1.0;
            }
            if c[a] + 1 < dims[a] {
                hi = hi.wrapping_add_signed(s[a]);
                steps += 1.0;
            }
            out[a] = (self.values.read(hi) - self.values.read(lo)) / steps;
        }
        Vec3::from(out)
    }

    /// Creates the vertex on the edge from sample `a` to the next sample along `axis`.
    #[inline(always)]
    fn push_vertex<const AXIS: usize>(&self, sink: &mut impl Sink, a: [usize; 3], exact: bool) -> u32 {
        let axis = AXIS;
        let g = &self.grid;
        let i = self.values.offset(a[0], a[1], a[2]);
        let stride = self.values.strides()[axis];
        let (va, vb) = (self.values.read(i), self.values.read(i.wrapping_add_signed(stride)));
        let t = ((self.iso - va) / (vb - va)).clamp(self.t_min, 1.0 - self.t_min);
        let mut p = g.position(a[0], a[1], a[2]);
        p[axis] += t * g.spacing;
        let normal = self.sample_normals.then(|| self.vertex_normal::<AXIS>(a, i, [va, vb], t));
        let value = self.cell_ranges.then(|| {
            if exact || is_whole(a[axis] as f32 + t) {
                cell_range_at(&self.values, a, axis, t, self.iso)
            } else {
                // Raised to the largest range of the cells around the edge as they are meshed.
                0.0
            }
        });
        sink.vertex(self.frame.place(p), normal, value)
    }

    /// The unit normal of the vertex at `t` along the edge from sample `a` (element `i`) along
    /// `axis`, whose ends hold `ends`: the samples' gradients at the edge's ends (central
    /// differences), interpolated. Away from the grid's boundary the gradients' reads are the
    /// four columns of two samples beside the edge and the samples beyond its ends.
    #[inline(always)]
    fn vertex_normal<const AXIS: usize>(&self, a: [usize; 3], i: usize, ends: [f32; 2], t: f32) -> Vec3 {
        let dims = self.grid.dims;
        let axis = AXIS;
        let (u, w) = ((axis + 1) % 3, (axis + 2) % 3);
        let inner =
            a[u] >= 1 && a[u] + 1 < dims[u] && a[w] >= 1 && a[w] + 1 < dims[w] && a[axis] >= 1 && a[axis] + 2 < dims[axis];
        if !inner {
            return self.boundary_normal(a, axis, i, t);
        }
        let s = self.values.strides();
        let (sa, su, sw) = (s[axis], s[u], s[w]);
        let v = &self.values;
        let read2 = |k: usize| [v.read(k), v.read(k.wrapping_add_signed(sa))];
        let (u_lo, u_hi) = (read2(i.wrapping_add_signed(-su)), read2(i.wrapping_add_signed(su)));
        let (w_lo, w_hi) = (read2(i.wrapping_add_signed(-sw)), read2(i.wrapping_add_signed(sw)));
        let before = v.read(i.wrapping_add_signed(-sa));
        let beyond = v.read(i.wrapping_add_signed(2 * sa));
        let ga = along::<AXIS>((ends[1] - before) / 2.0, (u_hi[0] - u_lo[0]) / 2.0, (w_hi[0] - w_lo[0]) / 2.0);
        let gb = along::<AXIS>((beyond - ends[0]) / 2.0, (u_hi[1] - u_lo[1]) / 2.0, (w_hi[1] - w_lo[1]) / 2.0);
        self.frame.turn(ga.lerp(gb, t).normalize_or_zero())
    }

    /// [`Ctx::vertex_normal`] of an edge at the grid's boundary (one-sided differences there).
    #[inline(never)]
    fn boundary_normal(&self, a: [usize; 3], axis: usize, i: usize, t: f32) -> Vec3 {
        let mut b = a;
        b[axis] += 1;
        let ga = self.sample_gradient(a, i);
        let gb = self.sample_gradient(b, i.wrapping_add_signed(self.values.strides()[axis]));
        self.frame.turn(ga.lerp(gb, t).normalize_or_zero())
    }

    /// Vertices on the x- and y-edges of sample layer `z`.
    fn layer_vertices(&self, signs: &LayerSigns, z: usize, top: bool, xs: &mut [u32], ys: &mut [u32], sink: &mut impl Sink) {
        let nx = self.grid.dims[0];
        layer_edge_words(signs, self.grid.dims, z, |y, axis, lo, hi, word| {
            let ids = if axis == 0 { &mut *xs } else { &mut *ys };
            if axis == 0 {
                for_each_bit(lo, hi, word, |x| ids[x + nx * y] = self.push_vertex::<0>(sink, [x, y, z], top));
            } else {
                for_each_bit(lo, hi, word, |x| ids[x + nx * y] = self.push_vertex::<1>(sink, [x, y, z], top));
            }
        });
    }

    /// The indices of the x- and y-edge vertices of sample layer `z` that the slab below made
    /// (its top layer): numbered from `first` in the order [`Ctx::layer_vertices`] creates them,
    /// or tagged for the join when `first` is `None`.
    fn number_layer(&self, signs: &LayerSigns, z: usize, first: Option<u32>, xs: &mut [u32], ys: &mut [u32]) {
        let nx = self.grid.dims[0];
        let mut next = first.unwrap_or(0);
        layer_edge_words(signs, self.grid.dims, z, |y, axis, lo, hi, word| {
            let ids = if axis == 0 { &mut *xs } else { &mut *ys };
            for_each_bit(lo, hi, word, |x| {
                let i = x + nx * y;
                ids[i] = match first {
                    Some(_) => {
                        next += 1;
                        next - 1
                    }
                    None => EXTERN | (2 * i as u32 + axis as u32),
                };
            });
        });
    }

    /// Vertices on the z-edges between sample layers `z` and `z + 1`.
    fn z_vertices(&self, signs: &LayerSigns, z: usize, zs: &mut [u32], sink: &mut impl Sink) {
        let nx = self.grid.dims[0];
        z_edge_words(signs, self.grid.dims, z, |y, _, lo, hi, word| {
            for_each_bit(lo, hi, word, |x| zs[x + nx * y] = self.push_vertex::<2>(sink, [x, y, z], false));
        });
    }

    /// Calls `visit(x, y, case, corners)` for every cell between sample layers `z` and `z + 1`
    /// that the surface crosses, with its table case and its corners' sample indices.
    #[inline(always)]
    fn for_each_surface_cell(&self, signs: &LayerSigns, z: usize, mut visit: impl FnMut(usize, usize, usize, [usize; 8])) {
        let [nx, ny, _] = self.grid.dims;
        let sx = self.values.strides()[0];
        for y in 0..ny - 1 {
            let rows = [signs.row(y, z), signs.row(y + 1, z), signs.row(y, z + 1), signs.row(y + 1, z + 1)];
            let Some((lo, hi)) = span(&rows, nx) else { continue };
            let base = self.values.offset(0, y, z);
            let bits = [signs.bits(y, z), signs.bits(y + 1, z), signs.bits(y, z + 1), signs.bits(y + 1, z + 1)];
            for_each_surface_cell(bits, lo.saturating_sub(1), hi.min(nx - 2), |x, case| {
                let i = base.wrapping_add_signed(x as isize * sx);
                let corners = self.corner_offsets.map(|d| i.wrapping_add_signed(d));
                visit(x, y, case as usize, corners);
            });
        }
    }

    /// The table entry of a surface cell: the default table's, or with the decider, the one for
    /// the ambiguous faces whose inside corners the trilinear interpolant joins.
    #[inline(always)]
    fn entry(&self, case: usize, corners: &[usize; 8], cell: [usize; 3]) -> &'static Case {
        self.cell_entry(case, corners, cell).0
    }

    /// [`Ctx::entry`], with marching cubes 33's tube vertex where it is not Lewiner's centre
    /// ([`marching_cubes_33::CellEntry`]).
    #[inline(always)]
    fn cell_entry(&self, case: usize, corners: &[usize; 8], cell: [usize; 3]) -> marching_cubes_33::CellEntry {
        let ambiguous = AMBIGUOUS_FACES[case];
        if self.faces == FaceResolution::SeparateInside {
            if ambiguous == 0 || self.t_min > 0.0 {
                return (&TABLE[case], None);
            }
            return (self.tie_entry(case, ambiguous, corners), None);
        }
        if ambiguous == 0 && (self.faces != FaceResolution::Trilinear || !marching_cubes_33::may_tunnel(case as u8)) {
            return (&TABLE[case], None);
        }
        let g = corners.map(|k| f64::from(self.values.read(k)) - f64::from(self.iso));
        let mut joins = 0usize;
        for (f, (cycle, _)) in FACES.iter().enumerate() {
            if ambiguous >> f & 1 == 1 {
                joins |= usize::from(decider_joins_inside(cycle.map(|k| g[k as usize]))) << f;
            }
        }
        if self.faces == FaceResolution::Trilinear {
            return marching_cubes_33::entry(
                case as u8,
                joins as u8,
                &g,
                &marching_cubes_33::CellFrame { grid: self.grid, cell },
            );
        }
        (&FACE_CHOICE_TABLE[case * 64 + joins], None)
    }

    /// The default table's entry, except on an ambiguous face with a corner at the iso-value
    /// (interpolated exactly, `on-iso=exact`), which the asymptotic decider resolves. Separated
    /// there, the inside corners would leave the outside a passage of no thickness through a
    /// corner at the level: two triangles on the same three vertices, back to back (the
    /// duplicate faces scikit-image's classic table makes, its issue #8109; where both outside
    /// corners are at the level, the decider always joins). Both cells of a face decide from its
    /// four values, so the surface stays closed. `tests/tests/ties.rs` holds every pattern of
    /// corners at the level to no duplicate face.
    #[cold]
    fn tie_entry(&self, case: usize, ambiguous: u8, corners: &[usize; 8]) -> &'static Case {
        let mut joins = 0usize;
        for (f, (cycle, _)) in FACES.iter().enumerate() {
            let v = cycle.map(|k| f64::from(self.values.read(corners[k as usize])) - f64::from(self.iso));
            let any_at_iso = v.contains(&0.0);
            joins |= usize::from(ambiguous >> f & 1 == 1 && any_at_iso && decider_joins_inside(v)) << f;
        }
        &FACE_CHOICE_TABLE[case * 64 + joins]
    }

    /// Triangles of the cells between sample layers `z` and `z + 1`, connecting the vertices in
    /// the scratch's index layers. Returns the number of surface cells.
    fn cells(&self, signs: &LayerSigns, z: usize, s: &Scratch, sink: &mut impl Sink) -> usize {
        let nx = self.grid.dims[0];
        let mut active = 0;
        self.for_each_surface_cell(signs, z, |x, y, case, corners| {
            active += 1;
            let (entry, placed) = self.cell_entry(case, &corners, [x, y, z]);
            let e = x + nx * y;
            let mut ids = [0u32; 16];
            let mut mask = entry.edge_mask;
            while mask != 0 {
                let edge = mask.trailing_zeros() as usize;
                mask &= mask - 1;
                ids[edge] = match edge {
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
                self.interior_vertices(entry, placed, &corners, [x, y, z], &mut ids, sink);
            }
            if self.cell_ranges {
                // The cell's range raises its edges' vertices' values (every cell around a
                // crossing edge is a surface cell, so each edge vertex sees all of its cells).
                let range = range_of_corners(&corners.map(|k| self.values.read(k)), self.iso);
                let mut edges = entry.edge_mask & 0xFFF;
                while edges != 0 {
                    let edge = edges.trailing_zeros() as usize;
                    edges &= edges - 1;
                    sink.raise(ids[edge], range);
                }
            }
            for t in entry.triangles() {
                // Element by element: `t.map(..)` builds the triple on the stack and reads it back
                // wider than it was written (a store-forwarding stall per triangle).
                sink.triangle(self.frame.wind([ids[t[0] as usize], ids[t[1] as usize], ids[t[2] as usize]]));
            }
        });
        active
    }

    /// Vertices inside the cell for the polygons the table fans around one (joined ambiguous
    /// faces only): the mean of the polygon's edge crossings, stored in `ids[12 + polygon]`; for
    /// marching cubes 33, Lewiner et al.'s centre ([`marching_cubes_33::lewiner_centre`]), or
    /// where the cell's tube `placed` its own (a slot past the polygons: a waist ring's).
    fn interior_vertices(
        &self,
        entry: &Case,
        placed: Option<marching_cubes_33::Placed>,
        corners: &[usize; 8],
        cell: [usize; 3],
        ids: &mut [u32; 16],
        sink: &mut impl Sink,
    ) {
        let values = corners.map(|i| self.values.read(i));
        for piece in 0..4u8 {
            if entry.interior >> piece & 1 == 0 {
                continue;
            }
            let local = if let Some(p) = placed.filter(|p| p.mask >> piece & 1 == 1) {
                p.at[usize::from(piece)]
            } else if self.faces == FaceResolution::Trilinear {
                marching_cubes_33::lewiner_centre(values.map(|v| v - self.iso))
            } else {
                self.crossings_mean(entry, piece, &values)
            };
            let normal = self.sample_normals.then(|| self.frame.turn(trilinear_gradient(&values, local).normalize_or_zero()));
            // A vertex inside the cell: its own cell's range.
            let value = self.cell_ranges.then(|| cell_range(&self.values, cell, self.iso));
            let p = self.grid.position(cell[0], cell[1], cell[2]) + local * self.grid.spacing;
            ids[12 + piece as usize] = sink.vertex(self.frame.place(p), normal, value);
        }
    }

    /// The mean of the edge crossings of polygon `piece` of `entry`, in cell-local coordinates.
    fn crossings_mean(&self, entry: &Case, piece: u8, values: &[f32; 8]) -> Vec3 {
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
        sum / n
    }

    /// Interior vertices a cell's entry makes ([`Ctx::interior_vertices`]).
    fn interior_count(entry: &Case) -> usize {
        entry.interior.count_ones() as usize
    }

    /// What [`Ctx::slab`] will write for cell layers `z0..z1`, from the sign bits alone (and the
    /// decider's face values): the first pass of the parallel path, so every slab can then write
    /// straight into its own piece of an output allocated once, as flying edges does. `bottom`:
    /// the slab makes its bottom layer's x/y-edge vertices (the first slab).
    fn count(&self, z0: usize, z1: usize, bottom: bool, signs: &mut LayerSigns) -> SlabCount {
        let dims = self.grid.dims;
        // Every layer's signs are kept for the sweep that follows, which reads them instead of
        // the samples.
        signs.reset_span(dims[0], dims[1], z0, z1);
        signs.classify_view(&self.values, self.iso, z0);
        let layer_edges = |signs: &LayerSigns, z: usize| {
            let mut n = 0;
            layer_edge_words(signs, dims, z, |_, _, lo, hi, word| n += count_bits(lo, hi, word));
            n
        };
        let mut vertices = if bottom { layer_edges(signs, z0) } else { 0 };
        let (mut before_top, mut triangles) = (0, 0);
        for z in z0..z1 {
            signs.classify_view(&self.values, self.iso, z + 1);
            z_edge_words(signs, dims, z, |_, _, lo, hi, word| vertices += count_bits(lo, hi, word));
            if z + 1 == z1 {
                before_top = vertices;
            }
            vertices += layer_edges(signs, z + 1);
            self.for_each_surface_cell(signs, z, |x, y, case, corners| {
                let entry = self.entry(case, &corners, [x, y, z]);
                triangles += entry.triangles().len();
                if entry.interior != 0 {
                    vertices += Self::interior_count(entry);
                }
            });
        }
        SlabCount { vertices, triangles, before_top }
    }

    /// Meshes cell layers `z0..z1` into `sink`; `bottom` says who makes the bottom layer's
    /// x/y-edge vertices. Afterwards `s.x_lo`/`s.y_lo` hold the vertex indices of the top layer.
    fn slab(&self, z0: usize, z1: usize, bottom: Bottom, s: &mut Scratch, sink: &mut impl Sink) {
        let [nx, ny, _] = self.grid.dims;
        s.prepare(nx * ny);
        let mut signs = std::mem::take(&mut s.signs);
        let start = Instant::now();
        if !signs.holds_span(z0, z1) {
            signs.reset(nx, ny);
        }
        signs.classify_view(&self.values, self.iso, z0);
        match bottom {
            Bottom::Make => self.layer_vertices(&signs, z0, false, &mut s.x_lo, &mut s.y_lo, sink),
            Bottom::Numbered(first) => self.number_layer(&signs, z0, Some(first), &mut s.x_lo, &mut s.y_lo),
            Bottom::Tagged => self.number_layer(&signs, z0, None, &mut s.x_lo, &mut s.y_lo),
        }
        s.vertex_time += start.elapsed();
        let reads_ahead = self.sample_normals || self.cell_ranges;
        for z in z0..z1 {
            let t0 = Instant::now();
            if reads_ahead && z + 2 < self.grid.dims[2] {
                // Normals and values read a layer beyond the one classified next.
                self.values.touch_layer(z + 2);
            }
            signs.classify_view(&self.values, self.iso, z + 1);
            self.z_vertices(&signs, z, &mut s.z_mid, sink);
            // The slab's top layer's vertices have cells above that the slab above meshes:
            // their values are made whole here.
            self.layer_vertices(&signs, z + 1, z + 1 == z1, &mut s.x_hi, &mut s.y_hi, sink);
            let t1 = Instant::now();
            s.active_cells += self.cells(&signs, z, s, sink);
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
fn reserve_for(out: &mut Extraction, vertices: usize, normals: bool, values: bool) {
    let positions = vertices + vertices / 64 + 16;
    out.surface.positions.reserve_exact(positions);
    if normals {
        out.surface.normals.reserve_exact(positions);
    }
    if values {
        out.vertex_values.reserve_exact(positions);
    }
    out.surface.triangles.reserve_exact(2 * vertices + vertices / 8 + 64);
}

/// The vector whose component `AXIS` is `a`, the next (cyclically) `b`, the one after `c`.
#[inline(always)]
fn along<const AXIS: usize>(a: f32, b: f32, c: f32) -> Vec3 {
    match AXIS {
        0 => Vec3::new(a, b, c),
        1 => Vec3::new(c, a, b),
        _ => Vec3::new(b, c, a),
    }
}

/// The crossing edges of a grid (marching cubes' vertices): counted on grids of up to
/// [`COUNT_ALL_SAMPLES`] samples, else estimated from [`ESTIMATE_LAYERS`] cell layers spread
/// evenly through the grid, scaled to all of them.
fn estimate_crossing_edges<T: Sample>(signs: &mut LayerSigns, values: &GridView<'_, T>, iso: f32) -> usize {
    let [nx, ny, nz] = values.dims();
    let layers = nz - 1;
    if nx * ny * nz <= COUNT_ALL_SAMPLES || layers <= 2 * ESTIMATE_LAYERS {
        return count_crossing_edges_in(signs, values, iso, 0, layers, true);
    }
    let counted: usize = (0..ESTIMATE_LAYERS)
        .map(|k| {
            // The middle cell layer of stratum k: its z-edges and its top layer's x- and y-edges.
            let z = (2 * k + 1) * layers / (2 * ESTIMATE_LAYERS);
            count_crossing_edges_in(signs, values, iso, z, z + 1, false)
        })
        .sum();
    counted * layers / ESTIMATE_LAYERS
}

/// Grids of up to this many samples have their crossing edges counted, not estimated, before a
/// fresh output is reserved (a pass over 16 MB of float samples, which caches hold).
const COUNT_ALL_SAMPLES: usize = 1 << 22;

/// Cell layers counted to estimate a larger grid's crossing edges.
const ESTIMATE_LAYERS: usize = 32;

/// Copies the slabs' meshes (and vertex values) into `out` in parallel, resolving each slab's
/// tagged references to the slab below's top layer.
fn join_slab_meshes(
    scratches: &[Scratch],
    normals: bool,
    values: bool,
    out: &mut Extraction,
    algorithm: &'static str,
) -> Result<(), ExtractError> {
    let offsets = slab_offsets(scratches.iter().map(|s| s.mesh.positions.len()), algorithm)?;
    let copy = |_: usize, part: &[Vec3], piece: &mut [Vec3]| piece.copy_from_slice(part);
    let surface = &mut out.surface;
    join_parts(&mut surface.positions, &scratches.iter().map(|s| &s.mesh.positions[..]).collect::<Vec<_>>(), copy);
    if normals {
        join_parts(&mut surface.normals, &scratches.iter().map(|s| &s.mesh.normals[..]).collect::<Vec<_>>(), copy);
    }
    if values {
        let parts = scratches.iter().map(|s| &s.values[..]).collect::<Vec<_>>();
        join_parts(&mut out.vertex_values, &parts, |_, part, piece| piece.copy_from_slice(part));
    }
    let triangles: Vec<&[[u32; 3]]> = scratches.iter().map(|s| &s.mesh.triangles[..]).collect();
    join_parts(&mut surface.triangles, &triangles, |t, part, piece| {
        let offset = offsets[t] as u32;
        // A tagged index names an x- (even) or y-edge (odd) of the slab below's top layer.
        let resolve = |i: u32| {
            if i & EXTERN == 0 {
                return i + offset;
            }
            let key = (i & !EXTERN) as usize;
            let below = &scratches[t - 1];
            let local = if key % 2 == 0 { below.x_lo[key / 2] } else { below.y_lo[key / 2] };
            local + offsets[t - 1] as u32
        };
        for (d, s) in piece.iter_mut().zip(part) {
            // Element by element, not `s.map(..)`: see `Ctx::cells`.
            d[0] = resolve(s[0]);
            d[1] = resolve(s[1]);
            d[2] = resolve(s[2]);
        }
    });
    Ok(())
}

impl Extractor for MarchingCubes {
    fn info(&self) -> &'static ExtractorInfo {
        match self.options.faces {
            FaceResolution::SeparateInside => &INFO,
            FaceResolution::AsymptoticDecider => &DECIDER_INFO,
            FaceResolution::Trilinear => &MC33_INFO,
        }
    }

    fn chunking(&self) -> Chunking {
        Chunking::CellLocal
    }

    fn settings(&self) -> String {
        let faces = match self.options.faces {
            FaceResolution::SeparateInside => "ambiguous faces keep their inside corners apart",
            FaceResolution::AsymptoticDecider => "ambiguous faces by the asymptotic decider",
            FaceResolution::Trilinear => "faces and cell interiors by the trilinear interpolant (marching cubes 33)",
        };
        let on_iso = match self.options.on_iso {
            OnIsoSamples::Separate => "vertices kept off samples at the iso-value",
            OnIsoSamples::Exact => "exact interpolation at samples on the iso-value",
        };
        format!("{faces}; {on_iso}")
    }

    fn levels_of_detail(&self) -> LevelsOfDetail<'_> {
        match (self.options.faces, self.options.on_iso) {
            (FaceResolution::SeparateInside, OnIsoSamples::Separate) => LevelsOfDetail::Stitched,
            (FaceResolution::SeparateInside, OnIsoSamples::Exact) => {
                LevelsOfDetail::Unsupported("on-iso=exact puts vertices on samples, where the stitching cannot tell levels apart")
            }
            _ => LevelsOfDetail::Unsupported(
                "its ambiguous faces follow the interpolant, which the seam restriction (inside corners kept apart) does not reproduce",
            ),
        }
    }

    fn extract_into(&self, samples: &Samples, out: &mut Extraction) -> Result<usize, ExtractError> {
        let Lattice::Cubic(grid) = *samples.lattice() else {
            return Err(ExtractError::UnsupportedLattice {
                algorithm: self.name(),
                lattice: samples.lattice().kind(),
                supported: "cubic",
            });
        };
        crate::with_view!(samples.view(), values => self.extract_view(values, samples, grid, out))
    }
}

impl MarchingCubes {
    /// Fails with [`ExtractError::OverMemory`] when a fresh output of `vertices` and `triangles`
    /// (with normals and values as asked), plus the sweep's per-layer scratch, would take more
    /// than `limit` ([`Extraction::memory_limit`]).
    fn check_memory(
        &self,
        limit: Option<u64>,
        vertices: usize,
        triangles: usize,
        grid: &Grid,
        normals: bool,
        values: bool,
    ) -> Result<(), ExtractError> {
        let Some(limit) = limit else { return Ok(()) };
        let per_vertex = 12 + if normals { 12 } else { 0 } + if values { 4 } else { 0 };
        let [nx, ny, _] = grid.dims;
        let tasks = crate::sweep::slabs::task_count(self.options.parallelism, grid.cell_count(), grid.dims[2] - 1);
        // Five index layers of u32 and two layers of sign bits with their row summaries per task.
        let scratch = tasks * nx * ny * 21;
        let needed = (vertices * per_vertex + triangles * 12 + scratch) as u64;
        if needed > limit {
            return Err(ExtractError::OverMemory { algorithm: self.name(), needed, limit, vertices });
        }
        Ok(())
    }

    /// [`Extractor::extract_into`] on the samples where they lie, compiled for their type.
    fn extract_view<T: Sample>(
        &self,
        values: GridView<'_, T>,
        samples: &Samples,
        grid: Grid,
        out: &mut Extraction,
    ) -> Result<usize, ExtractError> {
        let nz = grid.dims[2];
        let framed = self.options.frame != Frame::default();
        if !self.options.frame.is_valid() {
            return Err(ExtractError::BadInput {
                algorithm: self.name(),
                reason: format!("frame axes {:?} are not a permutation of 0, 1, 2", self.options.frame.axes),
            });
        }
        // The field's gradient is taken at a vertex's lattice position, which a frame moves.
        let field = samples.field().filter(|f| match self.options.normals {
            NormalSource::Auto => f.has_analytic_gradient() && !framed,
            NormalSource::FieldGradient => !framed,
            _ => false,
        });
        let sample_normals = field.is_none() && matches!(self.options.normals, NormalSource::Auto | NormalSource::SampleGradient);
        let cell_ranges = self.options.values == VertexValues::CellRange;

        let start = Instant::now();
        let mut held = self.scratch.take();
        let pool = &mut held;
        let t_min = match self.options.on_iso {
            OnIsoSamples::Separate => MIN_EDGE_FRACTION,
            OnIsoSamples::Exact => 0.0,
        };
        let ctx = Ctx::new(values, grid, samples.iso(), sample_normals, t_min, &self.options);
        let setup_time = start.elapsed();
        let slab_cells = nz - 1;
        let tasks = crate::sweep::slabs::task_count(self.options.parallelism, grid.cell_count(), slab_cells);
        while pool.len() < tasks {
            pool.push(Scratch::default());
        }
        let scratches = &mut pool[..tasks];

        let t_slabs = Instant::now();
        let mut allocation_time = Duration::ZERO;
        if tasks == 1 {
            let s = &mut scratches[0];
            if out.surface.positions.capacity() == 0 {
                // A fresh output (one-shot): reserve for the vertices estimated from a sample of
                // the layers, so the vectors rarely grow (a growth copies them), without a
                // counting pass over every sample (which, on a volume larger than the caches,
                // costs as much as the sweep's own read).
                let vertices = estimate_crossing_edges(&mut s.signs, &ctx.values, ctx.iso);
                self.check_memory(out.memory_limit, vertices, 2 * vertices, &grid, sample_normals, cell_ranges)?;
                reserve_for(out, vertices + vertices / 8, sample_normals, cell_ranges);
            }
            ctx.slab(0, slab_cells, Bottom::Make, s, &mut Grow { mesh: &mut out.surface, values: &mut out.vertex_values });
            if out.surface.positions.len() >= EXTERN as usize {
                return Err(ExtractError::TooLarge { algorithm: self.name(), vertices: out.surface.positions.len() });
            }
        } else if out.surface.positions.capacity() > 0 {
            // A reused output (steady state): each slab meshes into its own kept buffers, which
            // are then copied into the output in parallel. This reads the samples once; counting
            // first would read them twice, which costs more than the copy once the buffers are warm.
            for_each_slab(scratches, |t, s| {
                s.mesh.clear();
                s.values.clear();
                let (mut mesh, mut values) = (std::mem::take(&mut s.mesh), std::mem::take(&mut s.values));
                let bottom = if t == 0 { Bottom::Make } else { Bottom::Tagged };
                let mut sink = Grow { mesh: &mut mesh, values: &mut values };
                ctx.slab(t * slab_cells / tasks, (t + 1) * slab_cells / tasks, bottom, s, &mut sink);
                (s.mesh, s.values) = (mesh, values);
            });
            let t_join = Instant::now();
            join_slab_meshes(scratches, sample_normals, cell_ranges, out, self.name())?;
            allocation_time = t_join.elapsed();
        } else {
            // A fresh output (one-shot), in flying edges' order: count every slab's output,
            // allocate the output once, then let each slab write its own piece of it. Every page
            // of the output is touched once, and no slab buffers are allocated and copied.
            let bounds = |t: usize| (t * slab_cells / tasks, (t + 1) * slab_cells / tasks);
            let counts: Vec<(SlabCount, Duration)> = for_each_slab(scratches, |t, s| {
                let start = Instant::now();
                let (z0, z1) = bounds(t);
                (ctx.count(z0, z1, t == 0, &mut s.signs), start.elapsed())
            });
            let offsets = slab_offsets(counts.iter().map(|(c, _)| c.vertices), self.name())?;
            let (vertices, triangles) = counts.iter().fold((0, 0), |(v, t), (c, _)| (v + c.vertices, t + c.triangles));
            if let Err(e) = self.check_memory(out.memory_limit, vertices, triangles, &grid, sample_normals, cell_ranges) {
                self.scratch.give(held);
                return Err(e);
            }
            let t_allocate = Instant::now();
            let sizes: Vec<(usize, usize)> = counts.iter().map(|(c, _)| (c.vertices, c.triangles)).collect();
            let value_counts = sizes.iter().map(|c| if cell_ranges { c.0 } else { 0 });
            resize_zeroed(&mut out.vertex_values, value_counts.clone().sum());
            let value_pieces = split_pieces(&mut out.vertex_values, value_counts);
            let sinks: Vec<Pieces> = mesh_pieces(&mut out.surface, &sizes, sample_normals)
                .into_iter()
                .zip(value_pieces)
                .enumerate()
                .map(|(t, (piece, values))| Pieces {
                    positions: piece.positions,
                    normals: piece.normals,
                    values,
                    triangles: piece.triangles,
                    base: offsets[t] as u32,
                    vertices: 0,
                    triangles_written: 0,
                })
                .collect();
            allocation_time = t_allocate.elapsed();
            let mut work: Vec<(&mut Scratch, Pieces)> = scratches.iter_mut().zip(sinks).collect();
            for_each_slab(&mut work, |t, (s, sink)| {
                let (z0, z1) = bounds(t);
                let bottom =
                    if t == 0 { Bottom::Make } else { Bottom::Numbered((offsets[t - 1] + counts[t - 1].0.before_top) as u32) };
                ctx.slab(z0, z1, bottom, s, sink);
                s.vertex_time += counts[t].1;
                // The count and the sweep read the same sign bits, so they agree; a piece left
                // partly unwritten would be a silently wrong mesh, so this is checked always.
                assert_eq!(
                    (sink.vertices, sink.triangles_written),
                    (counts[t].0.vertices, counts[t].0.triangles),
                    "marching cubes: slab {t} wrote other counts than it counted"
                );
            });
        }
        if let Some((y, z)) = scratches.iter().filter_map(|s| s.signs.non_finite()).min_by_key(|&(y, z)| (z, y)) {
            let found = (0..grid.dims[0]).map(|x| [x, y, z]).find(|&[x, y, z]| !ctx.values.at(x, y, z).is_finite());
            let [x, y, z] = found.unwrap_or([0, y, z]);
            self.scratch.give(held);
            return Err(ExtractError::Samples(SampleError::NonFinite {
                field: "values".to_owned(),
                position: grid.position(x, y, z).to_array(),
                index: grid.index(x, y, z),
                value: ctx.values.at(x, y, z),
            }));
        }
        let slab_wall = t_slabs.elapsed() - allocation_time;
        let (cpu_v, cpu_g) =
            scratches.iter().fold((0.0, 0.0), |(v, g), s| (v + s.vertex_time.as_secs_f64(), g + s.geometry_time.as_secs_f64()));
        let join_time = allocation_time;
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
        Ok(scratch_bytes)
    }
}

#[cfg(test)]
mod tests;
