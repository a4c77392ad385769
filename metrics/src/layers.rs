//! Two layers that should meet without gap or overlap (a solid and a liquid,
//! `isolab_algorithms::liquids`): whether the liquid's vertices on the contact are the solid's,
//! whether any triangle of one crosses a triangle of the other (exact predicates, the
//! [`intersections`](crate::intersections) test on both meshes joined by position, with each
//! contact triangle that both hold, reversed, counted once), and whether a liquid vertex off the
//! contact lies inside the solid (generalized winding number above one half).

use isolab_algorithms::bvh::TriangleBvh;
use isolab_algorithms::lattice::LatticePlace;
use isolab_algorithms::liquids::{Phase, Phases};
use isolab_algorithms::TriMesh;
use serde::{Deserialize, Serialize};
use std::collections::{HashMap, HashSet};

/// How two layers meet.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct LayerContact {
    /// Liquid vertices on a lattice edge between a solid and a liquid sample.
    pub contact_vertices: usize,
    /// Of those, the ones not bit-equal to a solid vertex (ideal 0).
    pub unshared: usize,
    /// Triangle pairs, one of each layer, that cross (ideal 0).
    pub crossing_pairs: usize,
    /// Liquid vertices off the contact inside the solid (ideal 0).
    pub liquid_inside_solid: usize,
}

type PointKey = [u32; 3];

fn point_key(p: glam::Vec3) -> PointKey {
    p.to_array().map(f32::to_bits)
}

/// How `liquid` meets `solid`, both meshed from `phases`.
pub fn layer_contact(phases: &Phases, solid: &TriMesh, liquid: &TriMesh) -> LayerContact {
    let solid_points: HashSet<PointKey> = solid.positions.iter().map(|&p| point_key(p)).collect();
    let mut contact = LayerContact::default();
    for &p in &liquid.positions {
        if let LatticePlace::Edge(a, b) = phases.grid().place(p) {
            let ends = [phases.phase(a), phases.phase(b)];
            if ends.contains(&Phase::Solid) && ends.contains(&Phase::Liquid) {
                contact.contact_vertices += 1;
                contact.unshared += usize::from(!solid_points.contains(&point_key(p)));
            }
        }
    }
    contact.crossing_pairs = crossing_pairs(solid, liquid);
    let bvh = TriangleBvh::new(solid.triangles.iter().map(|t| t.map(|v| solid.positions[v as usize])).collect());
    contact.liquid_inside_solid =
        liquid.positions.iter().filter(|&&p| !solid_points.contains(&point_key(p)) && bvh.winding_number(p) > 0.5).count();
    contact
}

/// Pairs of triangles, one from each mesh, that intersect beyond what they share: the
/// self-intersections of both joined by position (each contact triangle both hold counted once)
/// less each mesh's own.
pub fn crossing_pairs(solid: &TriMesh, liquid: &TriMesh) -> usize {
    let key = |m: &TriMesh, t: [u32; 3]| {
        let mut k = t.map(|v| point_key(m.positions[v as usize]));
        k.sort_unstable();
        k
    };
    let solid_triangles: HashSet<[PointKey; 3]> = solid.triangles.iter().map(|&t| key(solid, t)).collect();
    let mut joined = TriMesh::default();
    let mut index: HashMap<PointKey, u32> = HashMap::new();
    for (mesh, skip) in [(solid, None), (liquid, Some(&solid_triangles))] {
        for &t in &mesh.triangles {
            if skip.is_some_and(|s| s.contains(&key(mesh, t))) {
                continue;
            }
            let t = t.map(|v| {
                let p = mesh.positions[v as usize];
                *index.entry(point_key(p)).or_insert_with(|| {
                    joined.positions.push(p);
                    joined.positions.len() as u32 - 1
                })
            });
            joined.triangles.push(t);
        }
    }
    let own = crate::self_intersections(solid).count + crate::self_intersections(liquid).count;
    crate::self_intersections(&joined).count.saturating_sub(own)
}
