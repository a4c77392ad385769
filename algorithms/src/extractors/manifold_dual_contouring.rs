//! # Manifold, intersection-free dual contouring
//!
//! **Papers:** S. Schaefer, T. Ju and J. Warren, "Manifold dual contouring", IEEE TVCG 13(3),
//! 2007, DOI 10.1109/TVCG.2007.1012 (a vertex per component of the cell's surface); T. Ju and
//! T. Udeshi, "Intersection-free contouring on an octree grid", Pacific Graphics 2006 (triangles
//! enclosed in non-overlapping cells).
//!
//! **Summary.** [`crate::extractors::dual_contouring`]'s vertices: one per separate piece of
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

use crate::extract::{Chunking, ExtractError, Extraction, Extractor, ExtractorInfo, Guarantees, LevelsOfDetail};
use crate::extractors::dual::{DualEngine, DualOptions, Placement, Smoothing};
use crate::options::{OptionError, Options};
use crate::samples::Samples;

/// One line for listings.
pub const DESCRIPTION: &str =
    "Schaefer et al. 2007 and Ju & Udeshi 2006: dual contouring with every triangle kept in its cells (no self-intersections)";

/// Option names for [`from_options`].
pub const OPTION_NAMES: &[&str] = &["svd-tolerance", "parallelism"];

/// Manifold dual contouring with intersection-free triangles.
pub const INFO: ExtractorInfo = ExtractorInfo {
    name: "manifold-dual-contouring",
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
    samples: crate::extract::SampleAccess::Copies(
        "the dual engine reads f32 samples by flat index (its QEF gathers and gradients); not yet ported to typed views",
    ),
};

/// Options for [`ManifoldDualContouring`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MdcOptions {
    /// Singular values below this fraction of the largest are dropped (default 0.1, as dual contouring).
    pub svd_tolerance: f32,
    /// Slabs in parallel (default) or serial.
    pub parallelism: crate::sweep::slabs::Parallelism,
}

impl Default for MdcOptions {
    fn default() -> Self {
        Self { svd_tolerance: 0.1, parallelism: crate::sweep::slabs::Parallelism::Rayon }
    }
}

/// Builds the extractor from named options.
pub fn from_options(options: &Options) -> Result<Box<dyn Extractor>, OptionError> {
    use crate::sweep::slabs::Parallelism;
    let d = MdcOptions::default();
    let mut r = options.reader(INFO.name, OPTION_NAMES);
    let o = MdcOptions {
        svd_tolerance: r.number("svd-tolerance", d.svd_tolerance, 0.0, 1.0)?,
        parallelism: r.choice("parallelism", d.parallelism, &[("rayon", Parallelism::Rayon), ("serial", Parallelism::Serial)])?,
    };
    r.finish()?;
    Ok(Box::new(ManifoldDualContouring::new(o)))
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
        let sn =
            DualOptions { smoothing: Smoothing::None, iterations: 0, parallelism: options.parallelism, ..Default::default() };
        let placement = Placement::Qef { tolerance: options.svd_tolerance, clamp: true };
        Self { options, engine: DualEngine::new(sn, placement, INFO.name) }
    }
}

impl Extractor for ManifoldDualContouring {
    fn info(&self) -> &'static ExtractorInfo {
        &INFO
    }

    fn levels_of_detail(&self) -> LevelsOfDetail<'_> {
        LevelsOfDetail::Unsupported(
            "its triangles are fans around edge points kept inside cells, which a polygon on a seam between levels (spanning a fine and a coarse cell) is not",
        )
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
