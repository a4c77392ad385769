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
//! winding. Where the boundary cuts one piece's quads into separate fans (two sheets of the cut
//! surface touching in a boundary cell), the piece gets a vertex per fan, so no vertex is a
//! bow-tie there; a piece with no quad at all (a corner of the domain cut off) gets none
//! (`dual::cells::boundary_split`; the contract test's surfaces that leave the lattice).
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
//! The engine (cells, quads, slabs, smoothing) is [`crate::extractors::dual`], shared with dual
//! contouring; this file is surface nets' options and its place in the registry.
//!
//! **Costs.** One read of every sample to pack its sign, layer by layer as the sweep reaches it
//! ([`crate::sweep::sign_rows::LayerSigns`]: surface cells and crossing edges are found 64 samples at a
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

use crate::extract::{Chunking, ExtractError, Extraction, Extractor, ExtractorInfo, Guarantees, LevelsOfDetail};
use crate::extractors::dual::{DualEngine, Placement};
use crate::options::{OptionError, Options};
use crate::samples::Samples;

pub use crate::extractors::dual::{DualOptions as SnOptions, Smoothing};

/// One line for listings.
pub const DESCRIPTION: &str =
    "Gibson 1998: one vertex per piece of surface in each cell (mean of its edge crossings), a quad per crossing edge; constrained smoothing";

/// Option names for [`from_options`].
pub const OPTION_NAMES: &[&str] =
    &["smoothing", "iterations", "strength", "decay", "stiffness", "damping", "time-step", "parallelism"];

/// Gibson 1998: one vertex per piece of surface in each cell, quads across crossing edges,
/// constrained smoothing.
pub const INFO: ExtractorInfo = ExtractorInfo {
    name: "surface-nets",
    description: DESCRIPTION,
    options: OPTION_NAMES,
    make: from_options,
    guarantees: Guarantees {
        cubic: true,
        bcc: false,
        closed: true,
        manifold: true,
        outward: true,
        intersection_free: false,
        trilinear_topology: false,
        keeps_small_parts: true,
        dihedral: None,
    },
    samples: crate::extract::SampleAccess::Copies(
        "the dual engine reads f32 samples by flat index (its vertex placement and smoothing); not yet ported to typed views",
    ),
};

/// Builds surface nets from named options.
pub fn from_options(options: &Options) -> Result<Box<dyn Extractor>, OptionError> {
    let d = SnOptions::default();
    let mut r = options.reader(INFO.name, OPTION_NAMES);
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
        parallelism: r.parallelism(d.parallelism)?,
    };
    r.finish()?;
    Ok(Box::new(SurfaceNets::new(o)))
}

/// Surface nets on a cubic grid: the dual engine with vertices at the mass point of their
/// crossings. Keeps its scratch buffers between calls.
pub struct SurfaceNets {
    engine: DualEngine,
}

impl Default for SurfaceNets {
    fn default() -> Self {
        Self::new(SnOptions::default())
    }
}

impl SurfaceNets {
    /// Surface nets with `options`.
    pub fn new(options: SnOptions) -> Self {
        Self { engine: DualEngine::new(options, Placement::MassPoint, INFO.name) }
    }

    /// The options.
    pub fn options(&self) -> &SnOptions {
        &self.engine.options
    }
}

impl Extractor for SurfaceNets {
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

#[cfg(test)]
mod tests {
    use super::*;

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
