//! Self-intersections: pairs of triangles that meet anywhere other than along the vertices and
//! edges they share. Candidate pairs come from a bounding volume hierarchy; every test is decided
//! by exact orientation predicates (Shewchuk's, from the `robust` crate) on the `f32` coordinates,
//! which are exact in `f64`, so the answer does not depend on rounding.
//!
//! As in CGAL's `Polygon_mesh_processing::self_intersections`:
//! - triangles sharing an edge intersect only when they fold onto each other (coplanar, opposite
//!   vertices on the same side of the edge);
//! - triangles sharing one vertex intersect when the opposite edge of either meets the other
//!   triangle, or an edge from the shared vertex runs into the other triangle in its plane;
//! - other pairs intersect when they share any point (touching counts).
//!
//! Degenerate triangles (repeated index or zero area) are skipped: the topology report counts them.

use glam::Vec3;
use isolab_algorithms::bvh::TriangleBvh;
use isolab_algorithms::predicates::has_zero_area;
pub use isolab_algorithms::predicates::{indexed_triangles_intersect, segment_meets_triangle, triangles_meet};
use isolab_algorithms::{Aabb, TriMesh};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// At most this many intersecting pairs are listed.
pub const MAX_LISTED_PAIRS: usize = 100;

/// Self-intersection report.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct SelfIntersections {
    /// Intersecting triangle pairs (ideal 0).
    pub count: usize,
    /// The first [`MAX_LISTED_PAIRS`] pairs, as triangle indices `[i, j]` with `i < j`, sorted.
    pub pairs: Vec<[u32; 2]>,
}

fn is_degenerate(mesh: &TriMesh, t: [u32; 3]) -> bool {
    if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
        return true;
    }
    has_zero_area(t.map(|i| mesh.positions[i as usize]))
}

/// Whether triangles `i` and `j` of `mesh` (both non-degenerate) intersect beyond what they share.
pub fn pair_intersects(mesh: &TriMesh, i: u32, j: u32) -> bool {
    indexed_triangles_intersect(mesh.triangles[i as usize], mesh.triangles[j as usize], |v| mesh.positions[v as usize])
}

/// All self-intersecting pairs of `mesh`.
pub fn self_intersections(mesh: &TriMesh) -> SelfIntersections {
    let valid: Vec<bool> = mesh.triangles.par_iter().map(|&t| !is_degenerate(mesh, t)).collect();
    let soup: Vec<[Vec3; 3]> = mesh.triangles.iter().map(|t| t.map(|i| mesh.positions[i as usize])).collect();
    let bvh = TriangleBvh::new(soup.clone());
    let mut pairs: Vec<[u32; 2]> = (0..mesh.triangles.len() as u32)
        .into_par_iter()
        .filter(|&i| valid[i as usize])
        .flat_map_iter(|i| {
            let mut bounds = Aabb::empty();
            soup[i as usize].iter().for_each(|&v| bounds.grow(v));
            let mut hits = Vec::new();
            bvh.for_each_overlapping(&bounds, |j, _| {
                if j > i && valid[j as usize] && pair_intersects(mesh, i, j) {
                    hits.push([i, j]);
                }
            });
            hits
        })
        .collect();
    pairs.sort_unstable();
    let count = pairs.len();
    pairs.truncate(MAX_LISTED_PAIRS);
    SelfIntersections { count, pairs }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mesh(positions: Vec<Vec3>, triangles: Vec<[u32; 3]>) -> TriMesh {
        TriMesh { positions, normals: vec![], triangles }
    }

    #[test]
    fn crossing_and_separate_triangles() {
        let a = [Vec3::ZERO, Vec3::X, Vec3::Y];
        let crossing = [Vec3::new(0.2, 0.2, -1.0), Vec3::new(0.2, 0.2, 1.0), Vec3::new(0.3, 0.1, 0.0)];
        assert!(triangles_meet(&a, &crossing));
        let above = a.map(|v| v + Vec3::Z * 0.1);
        assert!(!triangles_meet(&a, &above));
        // Coplanar overlap and coplanar containment.
        assert!(triangles_meet(&a, &a.map(|v| v * 0.5 + Vec3::splat(0.1).with_z(0.0))));
        // Touching at a point counts.
        assert!(triangles_meet(&a, &[Vec3::X, Vec3::new(2.0, 0.0, 0.0), Vec3::new(1.0, 0.0, 1.0)]));
    }

    #[test]
    fn closed_tetrahedron_has_none_and_a_pierced_one_is_listed() {
        let tet = TriMesh::unit_tetrahedron();
        assert_eq!(self_intersections(&tet).count, 0);
        // A separate triangle piercing face [0, 2, 1] (z = 0) only.
        let mut pierced = tet.clone();
        pierced.positions.extend([Vec3::new(0.2, 0.2, -0.5), Vec3::new(0.3, 0.2, 0.05), Vec3::new(0.2, 0.3, 0.05)]);
        pierced.triangles.push([4, 5, 6]);
        let r = self_intersections(&pierced);
        assert_eq!((r.count, r.pairs.clone()), (1, vec![[0, 4]]));
    }

    #[test]
    fn shared_edge_fold_and_shared_vertex_overlap() {
        // Two triangles on edge 0-1 folded onto each other (coplanar, same side).
        let folded =
            mesh(vec![Vec3::ZERO, Vec3::X, Vec3::new(0.5, 1.0, 0.0), Vec3::new(0.5, 0.5, 0.0)], vec![[0, 1, 2], [1, 0, 3]]);
        assert!(pair_intersects(&folded, 0, 1));
        // The same edge with the second triangle on the other side: fine.
        let flat =
            mesh(vec![Vec3::ZERO, Vec3::X, Vec3::new(0.5, 1.0, 0.0), Vec3::new(0.5, -1.0, 0.0)], vec![[0, 1, 2], [1, 0, 3]]);
        assert!(!pair_intersects(&flat, 0, 1));
        // Sharing vertex 0; the second triangle's edge runs into the first in its plane.
        let wedge = mesh(
            vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::new(0.3, 0.3, 0.0), Vec3::new(0.3, 0.3, 1.0)],
            vec![[0, 1, 2], [0, 3, 4]],
        );
        assert!(pair_intersects(&wedge, 0, 1));
        // Sharing vertex 0 and otherwise apart.
        let apart = mesh(
            vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::new(-1.0, 0.0, 0.5), Vec3::new(0.0, -1.0, 0.5)],
            vec![[0, 1, 2], [0, 3, 4]],
        );
        assert!(!pair_intersects(&apart, 0, 1));
    }
}
