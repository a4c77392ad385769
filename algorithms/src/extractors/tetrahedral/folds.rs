//! The fold check of regularised marching tetrahedra's guard: merging moves a vertex to the mean
//! of its island's crossings, which can carry one of its triangles through a neighbouring
//! triangle without breaking the mesh's topology (the manifold check cannot see it). Plain
//! marching tetrahedra never crosses itself, so every crossing pair has a merged vertex, and the
//! guard unmerges it.
//!
//! The check tests each wanted vertex's triangles against every triangle of its two-ring (the
//! triangles around the vertices of its own) with the exact predicate
//! ([`crate::predicates::indexed_triangles_intersect`]: pairs sharing a side cross only when
//! folded flat onto each other, as the two triangles of a collapsed blob do). A merged vertex stays within its sample's star, so its triangles can
//! only reach triangles a few lattice cells away; a crossing with a triangle outside the two-ring
//! (two sheets of the surface meeting from far apart in the mesh) is not looked for.

use glam::Vec3;

use crate::mesh::{Incidence, TriMesh};
use crate::predicates::indexed_triangles_intersect;

/// The fold check with its buffers kept between calls (the guard of a re-meshed chunk allocates
/// nothing once they have grown).
#[derive(Clone, Debug, Default)]
pub struct FoldCheck {
    incidence: Incidence,
    normals: Vec<Vec3>,
    bad: Vec<u32>,
}

impl FoldCheck {
    /// Bytes held.
    pub fn bytes(&self) -> usize {
        (self.incidence.start.capacity() + self.incidence.items.capacity() + self.bad.capacity()) * 4
            + self.normals.capacity() * 12
    }

    /// The wanted vertices whose triangles cross a triangle of their two-ring, and the wanted
    /// vertices of the triangles they cross; sorted, without repeats.
    pub fn folds_among(&mut self, mesh: &TriMesh, wanted: impl Fn(u32) -> bool) -> &[u32] {
        let Self { incidence, normals, bad } = self;
        incidence.rebuild(mesh.positions.len(), &mesh.triangles);
        let t = &mesh.triangles;
        let at = |v: u32| mesh.positions[v as usize];
        normals.clear();
        normals.extend(t.iter().map(|&[a, b, c]| (at(b) - at(a)).cross(at(c) - at(a)).normalize_or_zero()));
        bad.clear();
        for v in 0..mesh.positions.len() as u32 {
            if !wanted(v) {
                continue;
            }
            let fan = incidence.of_vertex(v);
            // Only a vertex one of whose triangles has turned away from its fan's mean normal is
            // tested: a fold turns a triangle over (the fan's other triangles can only cross a
            // flat neighbourhood by leaving it).
            let n = fan.iter().fold(Vec3::ZERO, |s, &a| s + normals[a as usize]).normalize_or_zero();
            if n != Vec3::ZERO && fan.iter().all(|&a| normals[a as usize].dot(n) >= FLAT) {
                continue;
            }
            for &a in fan {
                let ta = t[a as usize];
                for &w in &ta {
                    for &b in incidence.of_vertex(w) {
                        let tb = t[b as usize];
                        if b != a && boxes_meet(ta.map(at), tb.map(at)) && indexed_triangles_intersect(ta, tb, at) {
                            bad.extend(ta.into_iter().chain(tb).filter(|&x| wanted(x)));
                        }
                    }
                }
            }
        }
        bad.sort_unstable();
        bad.dedup();
        bad
    }
}

/// Whether two triangles' bounding boxes meet.
fn boxes_meet(a: [Vec3; 3], b: [Vec3; 3]) -> bool {
    let lo = |p: [Vec3; 3]| p[0].min(p[1]).min(p[2]);
    let hi = |p: [Vec3; 3]| p[0].max(p[1]).max(p[2]);
    lo(a).cmple(hi(b)).all() && lo(b).cmple(hi(a)).all()
}

/// The cosine below which a triangle's normal counts as turned away from its vertex's fan (90
/// degrees).
const FLAT: f32 = 0.0;
