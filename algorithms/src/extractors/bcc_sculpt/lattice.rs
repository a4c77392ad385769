//! The body-centred cubic lattice `bcc-sculpt` starts from (Stuart et al. 2013, section 3.1):
//! corner and centre vertices over the surface's box plus a margin, each cube cut into the
//! lattice's congruent tetrahedra, optionally rotated and shifted (perturbed attempts), with the
//! tetrahedra's face neighbours.

use super::{FACES, MARGIN_CELLS};
use crate::geometry::Aabb;
use glam::{DQuat, DVec3, Vec3};
use std::collections::HashMap;

/// Rotation and translation (as a fraction of a cell) of attempt `attempt`: none for attempt 0,
/// else a uniformly random rotation (Shoemake 1992) and shift, from a SplitMix64 stream.
pub fn perturbation(seed: u64, attempt: usize) -> (DQuat, DVec3) {
    if attempt == 0 {
        return (DQuat::IDENTITY, DVec3::ZERO);
    }
    let mut random = crate::random::Random::new(seed ^ (attempt as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15));
    let mut next = || random.unit();
    let (u1, u2, u3) = (next(), next(), next());
    let tau = std::f64::consts::TAU;
    let q = DQuat::from_xyzw(
        (1.0 - u1).sqrt() * (tau * u2).sin(),
        (1.0 - u1).sqrt() * (tau * u2).cos(),
        u1.sqrt() * (tau * u3).sin(),
        u1.sqrt() * (tau * u3).cos(),
    )
    .normalize();
    (q, DVec3::new(next(), next(), next()))
}

/// A BCC lattice: positions (world frame), positively oriented tetrahedra, the neighbour across
/// each face (`u32::MAX`: none) and each vertex's incident tetrahedra.
pub struct BccLattice {
    /// Vertex positions.
    pub positions: Vec<Vec3>,
    /// Tetrahedra, positively oriented.
    pub tets: Vec<[u32; 4]>,
    /// Neighbour across the face opposite each vertex.
    pub neighbours: Vec<[u32; 4]>,
    /// `star[star_start[v]..star_start[v + 1]]` are the tetrahedra around vertex `v`.
    pub star_start: Vec<u32>,
    /// Incident tetrahedra, grouped by vertex.
    pub star: Vec<u32>,
}

impl BccLattice {
    /// Tetrahedra incident to vertex `v`.
    pub fn star(&self, v: u32) -> &[u32] {
        &self.star[self.star_start[v as usize] as usize..self.star_start[v as usize + 1] as usize]
    }
}

/// The BCC tetrahedralization, spacing `h`, of `bounds` plus `MARGIN_CELLS`, built in a frame
/// rotated by `rotation` and shifted by `shift` cells. The tetrahedra are
/// [`crate::extractors::tetrahedral::TetTopology`]'s BCC templates (the lattice marching tetrahedra meshes):
/// around each edge between adjacent centres, the four corners of the face they straddle close
/// four tetrahedra (twelve per cell).
pub fn bcc_lattice(bounds: Aabb, h: f64, rotation: DQuat, shift: DVec3) -> BccLattice {
    // The surface's bounds in the lattice frame (rotate the box's corners back).
    let inverse = rotation.inverse();
    let mut local = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
    for k in 0..8 {
        let c = DVec3::new(
            if k & 1 == 0 { bounds.min.x } else { bounds.max.x } as f64,
            if k & 2 == 0 { bounds.min.y } else { bounds.max.y } as f64,
            if k & 4 == 0 { bounds.min.z } else { bounds.max.z } as f64,
        );
        let l = inverse * c;
        local = (local.0.min(l), local.1.max(l));
    }
    let origin = ((local.0 / h).floor() - DVec3::splat(MARGIN_CELLS) - shift) * h;
    let n = ((local.1 - origin) / h).ceil() + DVec3::splat(MARGIN_CELLS);
    let [nx, ny, nz] = [n.x as usize, n.y as usize, n.z as usize];
    let corner = |i: usize, j: usize, k: usize| (i + (nx + 1) * (j + (ny + 1) * k)) as u32;
    let corners = (nx + 1) * (ny + 1) * (nz + 1);
    let centre = |i: usize, j: usize, k: usize| (corners + i + nx * (j + ny * k)) as u32;
    let mut positions = Vec::with_capacity(corners + nx * ny * nz);
    let world = |l: DVec3| (rotation * l).as_vec3();
    for k in 0..=nz {
        for j in 0..=ny {
            for i in 0..=nx {
                positions.push(world(origin + DVec3::new(i as f64, j as f64, k as f64) * h));
            }
        }
    }
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                positions.push(world(origin + (DVec3::new(i as f64, j as f64, k as f64) + 0.5) * h));
            }
        }
    }
    // The tetrahedra are the BCC topology's templates (the one BCC lattice marching tetrahedra
    // also uses), anchored at every cell centre whose neighbour across the template's face exists.
    // Template vertices are doubled offsets: odd coordinates are centres, even ones corners.
    let templates = &crate::extractors::tetrahedral::topology(crate::extractors::tetrahedral::TetKind::Bcc).templates;
    let vertex = |d: [i64; 3]| {
        let [x, y, z] = d.map(|c| (c.div_euclid(2)) as usize);
        if d[0] & 1 == 1 {
            centre(x, y, z)
        } else {
            corner(x, y, z)
        }
    };
    let dims = [nx, ny, nz];
    let mut tets = Vec::with_capacity(12 * nx * ny * nz);
    for axis in 0..3 {
        for k in 0..nz {
            for j in 0..ny {
                for i in 0..nx {
                    if [i, j, k][axis] + 1 >= dims[axis] {
                        continue;
                    }
                    let anchor = [i, j, k].map(|c| 2 * c as i64 + 1);
                    for template in &templates[4 * axis..4 * axis + 4] {
                        tets.push(template.map(|o| vertex(std::array::from_fn(|a| anchor[a] + i64::from(o[a])))));
                    }
                }
            }
        }
    }
    // The templates are positively oriented in the lattice frame and a rotation keeps orientation.
    debug_assert!(tets.iter().all(|t| signed_volume(t.map(|v| positions[v as usize])) > 0.0));
    let neighbours = face_neighbours(&tets);
    let crate::mesh::Incidence { start: star_start, items: star } = crate::mesh::Incidence::of(positions.len(), &tets);
    BccLattice { positions, tets, neighbours, star_start, star }
}

/// Six times the signed volume, in `f64`.
pub(super) fn signed_volume(p: [Vec3; 4]) -> f64 {
    let d = p.map(|v| v.as_dvec3());
    (d[1] - d[0]).dot((d[2] - d[0]).cross(d[3] - d[0]))
}

/// The tetrahedron across each face (`u32::MAX` where none).
pub(super) fn face_neighbours(tets: &[[u32; 4]]) -> Vec<[u32; 4]> {
    let mut first: HashMap<[u32; 3], (u32, usize)> = HashMap::with_capacity(2 * tets.len());
    let mut neighbours = vec![[u32::MAX; 4]; tets.len()];
    for (t, tet) in tets.iter().enumerate() {
        for (f, face) in FACES.iter().enumerate() {
            let mut key = face.map(|k| tet[k]);
            key.sort_unstable();
            if let Some((u, g)) = first.remove(&key) {
                neighbours[t][f] = u;
                neighbours[u as usize][g] = t as u32;
            } else {
                first.insert(key, (t as u32, f));
            }
        }
    }
    neighbours
}
