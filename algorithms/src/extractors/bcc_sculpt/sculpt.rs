//! Sculpting (Stuart et al. 2013, section 3.2): which lattice tetrahedra overlap the volume
//! bounded by the surface, defusing the "bombs" (boundary vertices whose removal would pinch)
//! with snowflakes, and repairing what is left non-manifold.

use super::cover::{interacting_groups, CoverProblem};
use super::lattice::BccLattice;
use super::{COVER_NODE_LIMIT, FACES, SNOWFLAKE};
use crate::bvh::TriangleBvh;
use crate::geometry::Aabb;
use crate::mesh::{manifold_defects, TriMesh};
use crate::predicates::triangle_meets_tetrahedron;
use glam::Vec3;
use rayon::prelude::*;

/// Sculpting: which lattice tetrahedra overlap the volume bounded by `S`.
pub fn sculpt(lattice: &BccLattice, surface: &TriangleBvh) -> Vec<bool> {
    let bounds = surface.bounds();
    let near = |p: Vec3| bounds.distance_squared(p) == 0.0;
    // Vertices outside the surface's box are outside; the winding number decides the rest.
    let inside: Vec<bool> = lattice.positions.par_iter().map(|&p| near(p) && surface.winding_number(p) >= 0.5).collect();
    lattice
        .tets
        .par_iter()
        .map(|tet| {
            if tet.iter().any(|&v| inside[v as usize]) {
                return true;
            }
            let p = tet.map(|v| lattice.positions[v as usize]);
            let mut b = Aabb::empty();
            p.iter().for_each(|&v| b.grow(v));
            let mut meets = false;
            surface.for_each_overlapping(&b, |_, tri| meets = meets || triangle_meets_tetrahedron(tri, &p));
            meets
        })
        .collect()
}

/// Kept tetrahedra with two or more faces on the boundary.
pub fn bombs(lattice: &BccLattice, keep: &[bool]) -> Vec<u32> {
    (0..lattice.tets.len() as u32).filter(|&t| keep[t as usize] && boundary_faces(lattice, keep, t) >= 2).collect()
}

/// Faces of kept tetrahedron `t` with no kept neighbour.
pub(super) fn boundary_faces(lattice: &BccLattice, keep: &[bool], t: u32) -> usize {
    lattice.neighbours[t as usize].iter().filter(|&&u| u == u32::MAX || !keep[u as usize]).count()
}

/// What defusing did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Defused {
    /// Bombs found.
    pub bombs: usize,
    /// Tetrahedra added back.
    pub restored: usize,
    /// Whether every group was searched exhaustively.
    pub exhaustive: bool,
}

/// Completes one snowflake per bomb, choosing the combination that adds the fewest tetrahedra.
pub fn defuse_bombs(lattice: &BccLattice, keep: &mut [bool]) -> Defused {
    let found = bombs(lattice, keep);
    let mut result = Defused { bombs: found.len(), restored: 0, exhaustive: true };
    if found.is_empty() {
        return result;
    }
    // Candidate vertices: those of the bomb with a complete snowflake.
    let candidates: Vec<Vec<u32>> = found
        .iter()
        .map(|&b| lattice.tets[b as usize].iter().copied().filter(|&v| lattice.star(v).len() == SNOWFLAKE).collect())
        .collect();
    for group in interacting_groups(lattice, keep, &candidates) {
        let problem = CoverProblem::new(lattice, keep, group.iter().map(|&i| candidates[i].as_slice()));
        let (chosen, exhaustive) = problem.solve(COVER_NODE_LIMIT);
        result.exhaustive &= exhaustive;
        for v in chosen {
            for &t in lattice.star(v) {
                if !keep[t as usize] {
                    keep[t as usize] = true;
                    result.restored += 1;
                }
            }
        }
    }
    result
}

/// What the boundary repair did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Repaired {
    /// Tetrahedra added.
    pub restored: usize,
    /// Offending vertices left.
    pub defects_left: usize,
}

/// Rounds of boundary repair before giving up.
pub(super) const REPAIR_ROUNDS: usize = 16;

/// Makes the boundary of the kept tetrahedra a 2-manifold: where two parts touch only along an
/// edge or at a vertex (thin features, like cheburashka's ears, sculpt into such pinches), the
/// snowflake of the offending vertex is completed, which makes that vertex interior. Complete
/// snowflakes hold no bombs and adding tetrahedra turns none into a bomb, so the defusing stays
/// valid. Repeats until no pinch is left (each round can expose new boundary vertices).
pub fn repair_boundary(lattice: &BccLattice, keep: &mut [bool]) -> Repaired {
    let mut result = Repaired::default();
    let mut mesh = TriMesh { positions: vec![Vec3::ZERO; lattice.positions.len()], ..Default::default() };
    for round in 0..=REPAIR_ROUNDS {
        mesh.triangles.clear();
        for (t, tet) in lattice.tets.iter().enumerate().filter(|(t, _)| keep[*t]) {
            for (f, face) in FACES.iter().enumerate() {
                let u = lattice.neighbours[t][f];
                if u == u32::MAX || !keep[u as usize] {
                    mesh.triangles.push(face.map(|k| tet[k]));
                }
            }
        }
        let defects = manifold_defects(&mesh);
        result.defects_left = defects.len();
        if round == REPAIR_ROUNDS {
            break;
        }
        let mut changed = false;
        for v in defects.into_iter().filter(|&v| lattice.star(v).len() == SNOWFLAKE) {
            for &t in lattice.star(v) {
                if !keep[t as usize] {
                    keep[t as usize] = true;
                    result.restored += 1;
                    changed = true;
                }
            }
        }
        if !changed {
            break;
        }
    }
    result
}
