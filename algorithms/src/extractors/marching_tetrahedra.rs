//! # Marching tetrahedra
//!
//! **Paper:** A. Payne and A. W. Toga, "Surface mapping brain function on 3D models", IEEE
//! Computer Graphics and Applications 10(5), 1990; the lattices and passes of
//! `../shared/papers/costen-2026-rmt-terrain.txt` sections 2.3 and 3.1 without clustering (the
//! paper's "unmerged" configurations `*_bu` and `*_su`).
//!
//! **Summary.** Space is cut into tetrahedra: on a BCC lattice (`--lattice bcc`) twelve per cell,
//! all congruent with dihedral angles of 60 and 90 degrees; on a cubic grid six per cube around
//! its main diagonal (the Kuhn split of the paper's Fig. 19). Each tetrahedron looks up its sign
//! pattern in the 16-case table and emits nothing, a triangle or a quad (split along its shorter
//! diagonal). One vertex per crossing lattice edge, at the linear interpolation of its samples.
//! The engine is [`crate::extractors::tetrahedral`]; this extractor is it with
//! [`crate::extractors::tetrahedral::NoClustering`].
//!
//! **Guarantees.** No ambiguity: a tetrahedron's pattern fixes its surface, so the mesh is closed
//! wherever the surface stays inside the lattice, manifold, and wound outward (tests: every
//! pattern of a tetrahedron and of a sample's 24-tetrahedron star, random fields, the closed
//! built-in fields and models, on both lattices), and free of self-intersections: every vertex
//! stays strictly inside its edge, [`crate::geometry::MIN_EDGE_FRACTION`] of the edge from its
//! ends, so a sample exactly at the iso-value (the gyroid has whole planes of them) does not put
//! the vertices of all its edges at one point, where distinct vertices would touch and
//! triangles lose their area (tests: the contract's field of values in {-1, 0, 1}).
//!
//! **Non-guarantees.** Triangle shape: a crossing next to a sample makes slivers and needles (the
//! paper's mean aspect ratios of 5.81 to 1207 unmerged); that is what clustering and edge collapse
//! are for.
//!
//! **Costs.** O(samples) per pass; 14 bytes of scratch per sample; about twice marching cubes'
//! triangles on the same grid. Both passes run in slabs of layers on rayon's threads, joined in
//! order, so the mesh does not depend on the thread count (the `scaling` experiment measures the
//! speed-up).
//!
//! ```
//! use isolab_algorithms::{extractors::MarchingTetrahedra, fields, mesh::manifold_defects, Extraction, Extractor, Grid, Samples};
//! let torus = fields::builtin("torus", Default::default()).unwrap();
//! let samples = Samples::sample_cubic(torus.clone(), Grid::covering(&torus.domain(), 32).unwrap(), 0.0).unwrap();
//! let mut out = Extraction::default();
//! MarchingTetrahedra::default().extract(&samples, &mut out).unwrap();
//! let m = &out.surface;
//! // Closed and manifold, genus 1: V - E + F = V - F/2 = 0.
//! assert!(manifold_defects(m).is_empty());
//! assert_eq!(m.positions.len() as i64 - m.triangles.len() as i64 / 2, 0);
//! ```

use crate::extract::{Chunking, ExtractError, Extraction, Extractor, ExtractorInfo, Guarantees, LevelsOfDetail};
use crate::extractors::tetrahedral::{compute_normals, extract_tetrahedral, NoClustering, TetScratch};
use crate::lattice::Lattice;
use crate::options::{OptionError, Options};
use crate::samples::Samples;
use crate::sweep::slabs::ScratchPool;

/// One line for listings.
pub const DESCRIPTION: &str =
    "Payne & Toga 1990: 16-case table on tetrahedra (BCC lattice with --lattice bcc, Kuhn split of cubes otherwise), one vertex per crossing edge";

/// Options it takes (none).
pub const OPTION_NAMES: &[&str] = &[];

/// Payne & Toga 1990: the 16-case tetrahedron table on a BCC lattice or Kuhn-split cubes.
pub const INFO: ExtractorInfo = ExtractorInfo {
    name: "marching-tetrahedra",
    description: DESCRIPTION,
    options: OPTION_NAMES,
    make: from_options,
    guarantees: Guarantees {
        cubic: true,
        bcc: true,
        closed: true,
        manifold: true,
        outward: true,
        intersection_free: true,
        trilinear_topology: false,
        keeps_small_parts: true,
        dihedral: None,
    },
    samples: crate::extract::SampleAccess::Copies("the tetrahedral engine, shared with BCC lattices (whose centre samples no array holds), reads f32 samples by flat lattice index"),
};

/// Builds it from options.
pub fn from_options(options: &Options) -> Result<Box<dyn Extractor>, OptionError> {
    options.reader(INFO.name, OPTION_NAMES).finish()?;
    Ok(Box::new(MarchingTetrahedra::default()))
}

/// Plain marching tetrahedra on a BCC lattice or a Kuhn-split cubic grid. Keeps its per-sample
/// scratch between calls, so re-meshing a same-sized chunk allocates nothing.
#[derive(Default)]
pub struct MarchingTetrahedra {
    scratch: ScratchPool<TetScratch>,
}

impl Extractor for MarchingTetrahedra {
    fn info(&self) -> &'static ExtractorInfo {
        &INFO
    }

    fn levels_of_detail(&self) -> LevelsOfDetail<'_> {
        LevelsOfDetail::Unsupported("not built: its Kuhn cubes' face diagonals call for a restriction linear on each coarse face triangle, not the bilinear one the stitching assumes; on BCC the coarse lattice's centres are not samples of the finer one")
    }

    /// On a cubic grid the Kuhn split keeps every tetrahedron inside its cube and every vertex on
    /// one cube edge, face or main diagonal, computed from that edge's samples: cell-local. It
    /// reports vertex origins (sample and edge direction), so crossings that coincide at a sample
    /// whose value is the iso-value stay apart when chunks weld.
    fn chunking(&self) -> Chunking {
        Chunking::CellLocal
    }

    fn extract_into(&self, samples: &Samples, out: &mut Extraction) -> Result<usize, ExtractError> {
        let mut scratch = self.scratch.take();
        let result = extract_tetrahedral(samples, &NoClustering, &mut scratch, out);
        compute_normals(out);
        if result.is_ok() && out.origins.wanted && matches!(samples.lattice(), Lattice::Cubic(_)) {
            scratch.fill_origins(samples.grid(), usize::MAX, &mut out.origins);
        }
        let bytes = scratch.bytes();
        self.scratch.give(scratch);
        result?;
        Ok(bytes)
    }
}
