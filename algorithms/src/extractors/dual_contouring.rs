//! # Dual contouring, and manifold dual contouring
//!
//! Two registered extractors on one dual engine ([`crate::extractors::dual`]): `dual-contouring`
//! ([`DualContouring`], [`INFO`]) and its intersection-free mode `manifold-dual-contouring`
//! ([`ManifoldDualContouring`], [`MANIFOLD_INFO`]; its section below). They share the vertices
//! and the options' reading, and differ in how each quad becomes triangles.
//!
//! **Paper:** T. Ju, F. Losasso, S. Schaefer and J. Warren, "Dual contouring of Hermite data",
//! SIGGRAPH 2002, DOI 10.1145/566654.566586.
//!
//! **Summary.** The dual structure of [`crate::extractors::dual`] (a vertex per piece of surface in each
//! cell, a quad per crossing edge, split along the shorter diagonal unless that folds the quad:
//! a triangle turned more than 60 degrees from the quad's mean normal), with each vertex placed by
//! minimising the quadric error function of the cell's Hermite data ([`crate::extractors::dual::solve_qef`]): for every edge crossing `p_i`
//! with unit normal `n_i` (the field's gradient, analytic where the field has one; for raw samples
//! with no field, such as edited terrain, the gradient of the cell's trilinear interpolant at the
//! crossing, as game engines estimate normals from their voxels), minimise
//! `Σ (n_i · (x - p_i))²`. The 3x3 system is solved around the mass point `m` (the mean of the
//! crossings) with a truncated SVD (nalgebra): singular values below `svd-tolerance` times the
//! largest are dropped, so flat and ridge-like cells stay near `m` along their free directions
//! while corners snap to the planes' intersection. With `clamp` (default), the vertex is kept in
//! its cell.
//!
//! **Guarantees.** Sharp edges and corners are reproduced where the field's gradients describe
//! them (the `csg` corners land within a few thousandths of the spacing). Closed where it stays
//! inside the grid, consistently wound; one vertex per piece of surface avoids the classic
//! two-sheets-in-a-cell non-manifold vertex.
//!
//! **Non-guarantees.** DC is known to self-intersect where a vertex placed at a feature folds
//! its quads over its neighbours', and clamping can crease the surface. Choosing the diagonal
//! that does not fold removed these on the shipped models (a test holds them at none at 64) but
//! not everywhere: noisy fields (the asteroid, the terrain) keep some, where vertices of
//! neighbouring quads cross rather than one quad folding. The report counts self-intersections
//! and non-manifold edges per field. The manifold mode keeps these
//! vertices and triangulates each quad inside its cells instead, which cannot cross.
//!
//! **Costs.** The surface nets passes, plus one gradient evaluation per edge crossing (for mesh
//! fields without an analytic gradient that is six distance queries) and a 3x3 SVD per vertex.
//!
//! ```
//! use isolab_algorithms::{extractors::DualContouring, fields, Extraction, Extractor, Grid, Samples};
//! let csg = fields::builtin("csg", Default::default()).unwrap();
//! let samples = Samples::sample_cubic(csg.clone(), Grid::covering(&csg.domain(), 32).unwrap(), 0.0).unwrap();
//! let mut out = Extraction::default();
//! DualContouring::default().extract(&samples, &mut out).unwrap();
//! // A vertex sits on the box's corner (-0.25, -0.25, -0.25).
//! let corner = isolab_algorithms::Vec3::splat(-0.25);
//! let nearest = out.surface.positions.iter().map(|p| p.distance(corner)).fold(f32::INFINITY, f32::min);
//! assert!(nearest < 0.05 * samples.grid().spacing);
//! ```
//!
//! ## Manifold mode: manifold, intersection-free dual contouring
//!
//! **Papers:** S. Schaefer, T. Ju and J. Warren, "Manifold dual contouring", IEEE TVCG 13(3),
//! 2007, DOI 10.1109/TVCG.2007.1012 (a vertex per component of the cell's surface); T. Ju and
//! T. Udeshi, "Intersection-free contouring on an octree grid", Pacific Graphics 2006 (triangles
//! enclosed in non-overlapping cells).
//!
//! **Summary.** Dual contouring's vertices: one per separate piece of
//! surface in each cell (the marching cubes polygons of its case, which on a uniform grid is
//! what manifold dual contouring's vertex clustering starts from; without an octree there is
//! nothing to simplify, so its manifold test has nothing to decide), each at the minimum of its
//! piece's quadric error, kept strictly inside its cell. The quads are then triangulated so that
//! no triangle leaves its cell or the pair of cells it spans ([`crate::extractors::dual`]'s
//! intersection-free pass): each quad becomes a fan around its edge's crossing point, and a quad
//! side whose segment does not pierce the two cells' shared face where the surface may cross it
//! is broken at a face point (the face's own quadric minimum, so a sharp edge through the face
//! stays sharp).
//!
//! **Guarantees.** Free of self-intersections by construction (the argument is in the pass's
//! module doc; the contract and exhaustive tests check it with the exact predicate). Closed where
//! the surface stays inside the grid, manifold, wound outward, as dual contouring. Sharp corners
//! as dual contouring (the `csg` corners within 0.05 spacings).
//!
//! **Non-guarantees.** A cell with several pieces of surface tests its pieces' cones against
//! each other and falls back to centroids where they cross; a crossing left after that is
//! reported as a warning (none has been seen).
//!
//! **Chunks.** Seam-exact like dual contouring, with one sample more of apron: the edge points
//! are owned by their edge's lower sample and the face points by their face's lower corner
//! ([`crate::Origins`]), so chunks weld every vertex by lattice key, and re-meshing a chunk
//! allocates nothing once the pass's buffers have grown.
//!
//! **Costs.** Dual contouring's sweep, then per quad an edge point and four to eight triangles
//! instead of two (about twice the triangles), a sort of the quad sides, and a face point where
//! a side does not pierce its face.
//!
//! ```
//! use isolab_algorithms::{extractors::ManifoldDualContouring, fields, Extraction, Extractor, Grid, Samples};
//! let csg = fields::builtin("csg", Default::default()).unwrap();
//! let samples = Samples::sample_cubic(csg.clone(), Grid::covering(&csg.domain(), 32).unwrap(), 0.0).unwrap();
//! let mut out = Extraction::default();
//! ManifoldDualContouring::default().extract(&samples, &mut out).unwrap();
//! let corner = isolab_algorithms::Vec3::splat(-0.25);
//! let nearest = out.surface.positions.iter().map(|p| p.distance(corner)).fold(f32::INFINITY, f32::min);
//! assert!(nearest < 0.05 * samples.grid().spacing);
//! assert!(out.stats.warnings.is_empty());
//! ```
//!
//! The two modes share this file: they are one algorithm's two triangulations, and kept apart
//! their options, registry entries and constructors were near-copies.

use crate::extract::{Chunking, ExtractError, Extraction, Extractor, ExtractorInfo, Guarantees, LevelsOfDetail};
use crate::extractors::dual::{DualEngine, DualOptions, Placement, Smoothing};
use crate::options::{OptionError, Options};
use crate::samples::Samples;
use crate::sweep::slabs::Parallelism;

/// One line for listings.
pub const DESCRIPTION: &str =
    "Ju et al. 2002: dual vertices at the minimum of each cell's quadric error (Hermite data, truncated SVD)";

/// One line for listings, of the manifold mode.
pub const MANIFOLD_DESCRIPTION: &str =
    "Schaefer et al. 2007 and Ju & Udeshi 2006: dual contouring with every triangle kept in its cells (no self-intersections)";

/// Option names for [`from_options`].
pub const OPTION_NAMES: &[&str] = &["svd-tolerance", "clamp", "parallelism"];

/// Option names for [`manifold_from_options`] (its vertices are always kept in their cells).
pub const MANIFOLD_OPTION_NAMES: &[&str] = &["svd-tolerance", "parallelism"];

/// Why both modes copy their samples.
const SAMPLES: crate::extract::SampleAccess = crate::extract::SampleAccess::Copies(
    "the dual engine reads f32 samples by flat index (its QEF gathers and gradients); not yet ported to typed views",
);

/// What both modes promise but freedom from self-intersections.
const GUARANTEES: Guarantees = Guarantees {
    cubic: true,
    bcc: false,
    closed: true,
    manifold: true,
    outward: true,
    intersection_free: false,
    trilinear_topology: false,
    keeps_small_parts: true,
    dihedral: None,
};

/// Ju et al. 2002: the dual structure with vertices at the minimum of the quadric error.
pub const INFO: ExtractorInfo = ExtractorInfo {
    name: "dual-contouring",
    description: DESCRIPTION,
    options: OPTION_NAMES,
    make: from_options,
    guarantees: GUARANTEES,
    samples: SAMPLES,
};

/// Manifold dual contouring with intersection-free triangles.
pub const MANIFOLD_INFO: ExtractorInfo = ExtractorInfo {
    name: "manifold-dual-contouring",
    description: MANIFOLD_DESCRIPTION,
    options: MANIFOLD_OPTION_NAMES,
    make: manifold_from_options,
    guarantees: Guarantees { intersection_free: true, ..GUARANTEES },
    samples: SAMPLES,
};

/// Options for [`DualContouring`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DcOptions {
    /// Singular values below this fraction of the largest are dropped (default 0.1, as Ju et al.).
    pub svd_tolerance: f32,
    /// Keep each vertex inside its cell (default true).
    pub clamp: bool,
    /// Slabs in parallel (default) or serial.
    pub parallelism: Parallelism,
}

impl Default for DcOptions {
    fn default() -> Self {
        Self { svd_tolerance: 0.1, clamp: true, parallelism: Parallelism::Rayon }
    }
}

/// Options for [`ManifoldDualContouring`]: dual contouring's, its vertices always clamped.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MdcOptions {
    /// Singular values below this fraction of the largest are dropped (default 0.1, as dual contouring).
    pub svd_tolerance: f32,
    /// Slabs in parallel (default) or serial.
    pub parallelism: Parallelism,
}

impl Default for MdcOptions {
    fn default() -> Self {
        let d = DcOptions::default();
        Self { svd_tolerance: d.svd_tolerance, parallelism: d.parallelism }
    }
}

/// Reads both modes' options (`clamp` only where `names` has it) and checks none is left over.
fn read_options(options: &Options, info: &ExtractorInfo) -> Result<DcOptions, OptionError> {
    let d = DcOptions::default();
    let mut r = options.reader(info.name, info.options);
    let clamp =
        if info.options.contains(&"clamp") { r.choice("clamp", d.clamp, &[("true", true), ("false", false)])? } else { true };
    let o = DcOptions {
        svd_tolerance: r.number("svd-tolerance", d.svd_tolerance, 0.0, 1.0)?,
        clamp,
        parallelism: r.parallelism(d.parallelism)?,
    };
    r.finish()?;
    Ok(o)
}

/// The dual engine both modes run: no smoothing, vertices at their quadric minimum.
fn engine(o: DcOptions, name: &'static str) -> DualEngine {
    let sn = DualOptions { smoothing: Smoothing::None, iterations: 0, parallelism: o.parallelism, ..Default::default() };
    DualEngine::new(sn, Placement::Qef { tolerance: o.svd_tolerance, clamp: o.clamp }, name)
}

/// Builds dual contouring from named options.
pub fn from_options(options: &Options) -> Result<Box<dyn Extractor>, OptionError> {
    Ok(Box::new(DualContouring::new(read_options(options, &INFO)?)))
}

/// Builds manifold dual contouring from named options.
pub fn manifold_from_options(options: &Options) -> Result<Box<dyn Extractor>, OptionError> {
    let o = read_options(options, &MANIFOLD_INFO)?;
    Ok(Box::new(ManifoldDualContouring::new(MdcOptions { svd_tolerance: o.svd_tolerance, parallelism: o.parallelism })))
}

/// Dual contouring on a cubic grid (normals from the field when the samples carry it, from the
/// samples otherwise).
pub struct DualContouring {
    /// The options.
    pub options: DcOptions,
    engine: DualEngine,
}

impl Default for DualContouring {
    fn default() -> Self {
        Self::new(DcOptions::default())
    }
}

impl DualContouring {
    /// Dual contouring with `options`.
    pub fn new(options: DcOptions) -> Self {
        Self { options, engine: engine(options, INFO.name) }
    }
}

impl Extractor for DualContouring {
    fn info(&self) -> &'static ExtractorInfo {
        &INFO
    }

    fn settings(&self) -> String {
        self.engine.settings()
    }

    fn chunking(&self) -> Chunking {
        self.engine.chunking()
    }

    fn levels_of_detail(&self) -> LevelsOfDetail<'_> {
        LevelsOfDetail::Dual(&self.engine)
    }

    fn extract_into(&self, samples: &Samples, out: &mut Extraction) -> Result<usize, ExtractError> {
        self.engine.extract_into(samples, out)
    }
}

/// Manifold dual contouring on a cubic grid, free of self-intersections.
pub struct ManifoldDualContouring {
    /// The options.
    pub options: MdcOptions,
    engine: DualEngine,
}

impl Default for ManifoldDualContouring {
    fn default() -> Self {
        Self::new(MdcOptions::default())
    }
}

impl ManifoldDualContouring {
    /// The extractor with `options`.
    pub fn new(options: MdcOptions) -> Self {
        let o = DcOptions { svd_tolerance: options.svd_tolerance, clamp: true, parallelism: options.parallelism };
        Self { options, engine: engine(o, MANIFOLD_INFO.name).with_intersection_free_levels() }
    }
}

impl Extractor for ManifoldDualContouring {
    fn info(&self) -> &'static ExtractorInfo {
        &MANIFOLD_INFO
    }

    fn levels_of_detail(&self) -> LevelsOfDetail<'_> {
        LevelsOfDetail::Dual(&self.engine)
    }

    fn settings(&self) -> String {
        self.engine.settings()
    }

    /// Dual contouring's apron and one cell more: a kept triangle's sides need both of their
    /// quads, and a cell's face points the quads around its faces.
    fn chunking(&self) -> Chunking {
        match self.engine.chunking() {
            Chunking::Apron(a) => Chunking::Apron(a + 1),
            other => other,
        }
    }

    fn extract_into(&self, samples: &Samples, out: &mut Extraction) -> Result<usize, ExtractError> {
        self.engine.extract_intersection_free_into(samples, out)
    }
}
