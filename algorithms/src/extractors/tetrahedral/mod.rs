//! # Tetrahedral lattices and the marching tetrahedra engine
//!
//! **Papers:** A. Payne and A. W. Toga, "Surface mapping brain function on 3D models", IEEE CG&A
//! 10(5), 1990 (marching tetrahedra); G. M. Treece, R. W. Prager and A. H. Gee, "Regularised
//! marching tetrahedra: improved iso-surface extraction", Computers & Graphics 23(4), 1999; and the
//! specification `../shared/papers/costen-2026-rmt-terrain.txt` (sections 2.3, 3.1.2, 3.1.3,
//! Algorithms 2 and 3, Figs. 7, 17-19).
//!
//! Two ways to fill space with tetrahedra, both with **14 neighbours per sample** (so per-edge
//! flags fit 16 bits and every sample's star is 24 tetrahedra whose link is a triangulated sphere
//! of 14 vertices, 36 edges and 24 triangles):
//! - [`TetKind::Bcc`] on a [`Lattice::Bcc`](crate::lattice::Lattice::Bcc): the body-centred cubic lattice (the paper's "BCDL").
//!   Each tetrahedron joins two neighbouring cell centres (a long edge of the centre grid) and a
//!   corner-grid edge of the face between them (a long edge of the corner grid), so it has two long
//!   edges (length h) and four short ones (h√3/2), dihedral angles of 60 and 90 degrees, and every
//!   tetrahedron is congruent. Twelve tetrahedra per cell (24 touch a cell, each shared by two).
//! - [`TetKind::Kuhn`] on a [`Lattice::Cubic`](crate::lattice::Lattice::Cubic): six congruent tetrahedra around each cube's main
//!   diagonal from `(0,0,0)` to `(1,1,1)`, cut in the same direction on opposite faces (the
//!   Kuhn / Freudenthal split, the paper's Fig. 19 "simple cubic"), so neighbouring cubes agree
//!   on every face without mirroring.
//!
//! Coordinates are **doubled**: a corner sample `(x, y, z)` sits at `(2x, 2y, 2z)`, a BCC centre
//! at `(2x+1, 2y+1, 2z+1)`, so both lattices share one integer frame and one direction table.
//!
//! ## The engine
//! [`extract_tetrahedral`] runs the paper's two passes for marching tetrahedra and for
//! regularised marching tetrahedra (which differ only in their [`Clustering`]):
//! - **vertex pass** (Algorithm 2): every sample collects the crossings on its 14 edges that lie
//!   nearer to it than to the other end (its *nearby intersections*; ties go to the lower sample
//!   index, so every crossing has exactly one owner), hands them to the clustering, and stores a
//!   base vertex index plus a 4-bit vertex slot per edge (14 bytes per sample, against the
//!   paper's 58: a 16-bit flag word and a 32-bit index per edge);
//! - **geometry pass** (Algorithm 3): every tetrahedron with a sign change looks up its case in
//!   the 16-case table ([`MT_TABLE`]) and emits one triangle or a quad split along its shorter
//!   diagonal, wound outward. Triangles with a repeated vertex (collapsed by clustering) are
//!   discarded and counted. A merged quad whose opposite corners coincide is split along them, so
//!   both halves vanish instead of leaving two back-to-back triangles.
//!
//! Vertex normals are the area-weighted mean of the incident triangle normals (section 3.1.2).
//! Groups of tetrahedra whose samples all share a sign are skipped from their signs alone (the
//! paper skips a cube when its centre has no flags, which misses tetrahedra whose crossings are
//! all owned by corners; this test cannot). On a cubic grid both passes read the samples' signs
//! packed 64 to a word ([`crate::sweep::sign_rows::GridSigns`]): the vertex pass visits only samples with
//! a sign change on one of their 14 edges and reads the values across those edges only (which
//! edges change comes from the bits), the geometry pass only cubes whose corners disagree.
//! The per-sample bookkeeping ([`TetScratch`]) is kept by the extractors between calls, so
//! re-meshing a same-sized chunk allocates nothing (`tests/tests/allocations.rs`).
//!
//! **Guarantees.** Without clustering the surface is closed where it stays inside the lattice,
//! manifold and outward-wound (the tests run all 16 sign patterns of a tetrahedron, every pattern
//! of a sample's star, random fields and the closed built-in fields). With clustering see
//! [`crate::extractors::regularised_marching_tetrahedra`].
//!
//! **Costs.** O(samples): one sign pass over every sample (a word per 64 on a cubic grid, a row
//! summary per row on BCC), then the 14 neighbours of the samples near the surface. Both passes
//! run in slabs of layers on rayon ([`crate::sweep::slabs`]) joined in order, so the mesh is the same on
//! any number of threads (the paper's section 3.1.4 parallelises sampling only).
//!
//! Files: [`topology`](mod@topology) (the lattices), [`table`] (the 16 cases), [`engine`] (the vertex pass and
//! the driver), [`geometry`] (the geometry pass),
//! [`repair`] (the guard's re-extraction).

pub mod engine;
pub mod folds;
pub mod geometry;
pub mod repair;
pub mod table;
pub mod topology;

pub use engine::{
    compute_normals, extract_tetrahedral, tetrahedron_count, Clustering, Islands, NoClustering, Star, TetCounts, TetScratch,
};
pub use geometry::{geometry_pass, regenerate_anchors};
pub use repair::{finish_repair, unmerge_and_regenerate};
pub use table::{MtCase, MT_TABLE};
pub use topology::{topology, TetKind, TetTopology, BCC, DIRECTIONS, KUHN};
// The engine's internals its sibling passes share.
use engine::{owns, Addresser, Plan};

#[cfg(test)]
mod tests {
    use super::topology::orientation;
    use super::*;
    use glam::Vec3;

    #[test]
    fn every_star_is_a_sphere_of_24_tetrahedra() {
        for kind in [TetKind::Bcc, TetKind::Kuhn] {
            let t = topology(kind);
            // Link of a vertex: 14 vertices, 36 edges, 24 triangles (Euler 2).
            let edges: u32 = t.adjacency.iter().map(|a| a.count_ones()).sum::<u32>() / 2;
            assert_eq!(edges, 36, "{kind:?}");
            // Tetrahedra per sample: four vertices each, over the samples per anchor cell.
            let samples_per_cell = if kind == TetKind::Bcc { 2 } else { 1 };
            assert_eq!(t.templates.len() * 4 / samples_per_cell, 24, "{kind:?}");
            for a in t.adjacency {
                assert!(a.count_ones() >= 4);
            }
            for k in 0..DIRECTIONS {
                for j in 0..DIRECTIONS {
                    assert_eq!(t.adjacency[k] >> j & 1, t.adjacency[j] >> k & 1, "symmetric");
                }
                assert_eq!(t.adjacency[k] >> (k ^ 1) & 1, 0, "opposite neighbours are never adjacent");
            }
        }
    }

    #[test]
    fn templates_are_positive_and_congruent() {
        for kind in [TetKind::Bcc, TetKind::Kuhn] {
            let t = topology(kind);
            let volumes: Vec<i64> = t.templates.iter().map(orientation).collect();
            assert!(volumes.iter().all(|&v| v == volumes[0] && v > 0), "{kind:?} {volumes:?}");
        }
    }

    #[test]
    fn bcc_dihedral_angles_are_60_and_90_degrees() {
        let t = &topology(TetKind::Bcc).templates[0];
        let p = t.map(|q| Vec3::new(q[0] as f32, q[1] as f32, q[2] as f32));
        let mut angles = Vec::new();
        for i in 0..4 {
            for j in i + 1..4 {
                let others: Vec<usize> = (0..4).filter(|&k| k != i && k != j).collect();
                let e = (p[j] - p[i]).normalize();
                let perp = |k: usize| {
                    let v = p[k] - p[i];
                    (v - e * v.dot(e)).normalize()
                };
                angles.push(perp(others[0]).dot(perp(others[1])).clamp(-1.0, 1.0).acos().to_degrees());
            }
        }
        angles.sort_by(f32::total_cmp);
        for (a, want) in angles.iter().zip([60.0, 60.0, 60.0, 60.0, 90.0, 90.0]) {
            assert!((a - want).abs() < 1e-3, "{angles:?}");
        }
    }

    #[test]
    fn the_table_has_one_triangle_or_one_quad_per_mixed_case() {
        for (c, e) in MT_TABLE.iter().enumerate() {
            let inside = (c as u32).count_ones();
            let want = match inside {
                0 | 4 => 0,
                1 | 3 => 3,
                _ => 4,
            };
            assert_eq!(e.count, want, "case {c}");
            for &(a, b) in &e.edges[..e.count as usize] {
                assert!(c >> a & 1 == 1 && c >> b & 1 == 0, "case {c}: edges run inside to outside");
            }
        }
    }
}
