//! Relaxation (Stuart et al. 2013, section 3.3): optimal Delaunay triangulation (ODT) updates of
//! the vertices, boundary vertices pulled to `d_offset` from the surface, every move checked
//! by exact tests (no inverted tetrahedron, the swept region of each boundary triangle clear of
//! the surface, the quality floor), halving the step until clear.

use super::lattice::signed_volume;
use super::lattice::BccLattice;
use super::{tets_dihedral_range, RelaxIteration, SculptOptions, FACES};
use crate::bvh::TriangleBvh;
use crate::geometry::{circumcentre, dihedral_angles, Aabb};
use crate::mesh::{TetMesh, TriMesh};
use crate::predicates::triangle_meets_tetrahedron;
use glam::{DVec3, Vec3};
use rayon::prelude::*;
use std::time::Instant;

/// The kept tetrahedra as a mesh of their own, with boundary faces and stars.
pub(super) struct VolumeMesh {
    pub(super) positions: Vec<Vec3>,
    pub(super) tets: Vec<[u32; 4]>,
    pub(super) star_start: Vec<u32>,
    pub(super) star: Vec<u32>,
    /// Boundary triangles, outward.
    pub(super) boundary: Vec<[u32; 3]>,
    /// `face_star[face_start[v]..face_start[v + 1]]`: boundary triangles around vertex `v`.
    pub(super) face_start: Vec<u32>,
    pub(super) face_star: Vec<u32>,
}

impl VolumeMesh {
    pub(super) fn from_lattice(lattice: &BccLattice, keep: &[bool]) -> Self {
        let mut index = vec![u32::MAX; lattice.positions.len()];
        let mut positions = Vec::new();
        let mut tets = Vec::new();
        let mut boundary = Vec::new();
        for (t, tet) in lattice.tets.iter().enumerate().filter(|(t, _)| keep[*t]) {
            let local = tet.map(|v| {
                if index[v as usize] == u32::MAX {
                    index[v as usize] = positions.len() as u32;
                    positions.push(lattice.positions[v as usize]);
                }
                index[v as usize]
            });
            tets.push(local);
            for (f, face) in FACES.iter().enumerate() {
                let u = lattice.neighbours[t][f];
                if u == u32::MAX || !keep[u as usize] {
                    boundary.push(face.map(|k| local[k]));
                }
            }
        }
        let crate::mesh::Incidence { start: star_start, items: star } = crate::mesh::Incidence::of(positions.len(), &tets);
        let crate::mesh::Incidence { start: face_start, items: face_star } =
            crate::mesh::Incidence::of(positions.len(), &boundary);
        Self { positions, tets, star_start, star, boundary, face_start, face_star }
    }

    pub(super) fn star(&self, v: usize) -> &[u32] {
        &self.star[self.star_start[v] as usize..self.star_start[v + 1] as usize]
    }

    pub(super) fn faces(&self, v: usize) -> &[u32] {
        &self.face_star[self.face_start[v] as usize..self.face_start[v + 1] as usize]
    }

    pub(super) fn is_boundary(&self, v: usize) -> bool {
        self.face_start[v] != self.face_start[v + 1]
    }

    pub(super) fn into_meshes(self) -> (TetMesh, TriMesh) {
        let mut index = vec![u32::MAX; self.positions.len()];
        let mut surface = TriMesh::default();
        for tri in &self.boundary {
            let local = tri.map(|v| {
                if index[v as usize] == u32::MAX {
                    index[v as usize] = surface.positions.len() as u32;
                    surface.positions.push(self.positions[v as usize]);
                }
                index[v as usize]
            });
            surface.triangles.push(local);
        }
        surface.compute_face_weighted_normals();
        (TetMesh { positions: self.positions, tetrahedra: self.tets }, surface)
    }
}

/// How relaxation ended.
pub(super) struct Relaxed {
    pub(super) iterations: usize,
    pub(super) converged: bool,
    pub(super) max_distance: f32,
    /// Per iteration, with [`SculptOptions::trace`].
    pub(super) trace: Vec<RelaxIteration>,
}

/// Iterations in a row without the farthest boundary vertex coming [`STALL_PROGRESS`] `h` closer
/// before relaxation gives up.
pub(super) const STALL_ITERATIONS: usize = 25;

/// Progress, in lattice spacings, that resets the stall count.
pub(super) const STALL_PROGRESS: f32 = 1e-3;

/// Variational vertex adjustment (section 3.3): ODT steps that keep every tetrahedron positive
/// and the boundary off `S`.
pub(super) fn relax(
    mesh: &mut VolumeMesh,
    surface: &TriangleBvh,
    h: f64,
    options: &SculptOptions,
    deadline: Option<Instant>,
) -> Relaxed {
    let offset = (f64::from(options.offset_ratio) * h) as f32;
    // A tetrahedron may not shrink below this volume (a BCC tetrahedron has h³/12).
    let min_volume = 1e-4 * h * h * h;
    let still = (1e-6 * h) as f32;
    let mut stalled = 0;
    let mut iterations = 0;
    let mut best_distance = f32::INFINITY;
    let limits = StepLimits { min_volume, still, quality_floor: options.quality_floor, clearance: options.clearance * offset };
    let mut trace = Vec::new();
    loop {
        let max_distance = (0..mesh.positions.len())
            .into_par_iter()
            .filter(|&v| mesh.is_boundary(v))
            .map(|v| surface.closest_point(mesh.positions[v]).map_or(f32::INFINITY, |(_, d2)| d2.sqrt()))
            .reduce(|| 0.0, f32::max);
        let converged = max_distance <= offset;
        if max_distance < best_distance - STALL_PROGRESS * h as f32 {
            best_distance = max_distance;
            stalled = 0;
        } else {
            stalled += 1;
        }
        let out_of_time = deadline.is_some_and(|d| Instant::now() >= d);
        if converged || iterations >= options.max_iterations || stalled >= STALL_ITERATIONS || out_of_time {
            return Relaxed { iterations, converged, max_distance, trace };
        }
        iterations += 1;
        let mut record = options.trace.then(|| RelaxIteration {
            max_distance_h: max_distance / h as f32,
            min_dihedral: tets_dihedral_range(&mesh.positions, &mesh.tets)[0],
            ..Default::default()
        });
        let targets = odt_targets(mesh);
        for (v, &target) in targets.iter().enumerate() {
            let p = mesh.positions[v];
            let step = (target - p.as_dvec3()) * f64::from(options.time_step);
            let moved = try_step(mesh, surface, v, step, &limits);
            // A step shorter than `still` is not a refusal: the vertex is where it wants to be.
            if let Some(r) = record.as_mut().filter(|_| step.length() as f32 > still) {
                let counter = match (mesh.is_boundary(v), moved) {
                    (true, true) => &mut r.boundary_moved,
                    (true, false) => &mut r.boundary_refused,
                    (false, true) => &mut r.interior_moved,
                    (false, false) => &mut r.interior_refused,
                };
                *counter += 1;
            }
            if moved || !options.attract {
                continue;
            }
            // A boundary vertex the ODT step cannot bring closer: step toward its closest point on
            // S instead, under the same tests.
            if !mesh.is_boundary(v) {
                continue;
            }
            let Some((c, d2)) = surface.closest_point(p) else { continue };
            let d = d2.sqrt();
            if d > offset {
                let pull = (c - p).as_dvec3() * f64::from(options.time_step * (d - 0.5 * offset) / d);
                try_step(mesh, surface, v, pull, &limits);
            }
        }
        trace.extend(record);
    }
}

/// What a relaxation step must respect.
#[derive(Clone, Copy)]
pub(super) struct StepLimits {
    /// Smallest volume a tetrahedron may keep.
    pub(super) min_volume: f64,
    /// Moves shorter than this are not made.
    pub(super) still: f32,
    /// Quality floor, degrees of dihedral angle.
    pub(super) quality_floor: f32,
    /// Distance a boundary vertex keeps from `S`.
    pub(super) clearance: f32,
}

/// Moves `v` by `step`, halving it up to four times until the move keeps every tetrahedron
/// positive and above the quality floor and (on the boundary) sweeps clear of `S`. Whether it moved.
pub(super) fn try_step(mesh: &mut VolumeMesh, surface: &TriangleBvh, v: usize, step: DVec3, limits: &StepLimits) -> bool {
    let StepLimits { min_volume, still, quality_floor, clearance } = *limits;
    let p = mesh.positions[v];
    let boundary = mesh.is_boundary(v);
    let mut scale = 1.0;
    for _ in 0..5 {
        let q = (p.as_dvec3() + step * scale).as_vec3();
        if q.distance(p) <= still {
            return false;
        }
        if star_stays_positive(mesh, v, q, min_volume)
            && keeps_quality(mesh, v, q, quality_floor)
            && (!boundary || keeps_clearance(surface, p, q, clearance))
            && (!boundary || sweep_is_clear(mesh, surface, v, q))
        {
            mesh.positions[v] = q;
            return true;
        }
        scale *= 0.5;
    }
    false
}

/// Each vertex's ODT position: the volume-weighted mean of its tetrahedra's circumcentres
/// (equation 2 of the paper, from Alliez et al. 2005).
pub(super) fn odt_targets(mesh: &VolumeMesh) -> Vec<DVec3> {
    let centres: Vec<(f64, DVec3)> = mesh
        .tets
        .par_iter()
        .map(|t| {
            let p = t.map(|v| mesh.positions[v as usize].as_dvec3());
            let volume = (p[1] - p[0]).dot((p[2] - p[0]).cross(p[3] - p[0])) / 6.0;
            match circumcentre(p) {
                Some(c) if volume > 0.0 => (volume, c * volume),
                _ => (0.0, DVec3::ZERO),
            }
        })
        .collect();
    (0..mesh.positions.len())
        .into_par_iter()
        .map(|v| {
            let (w, sum) = mesh.star(v).iter().fold((0.0, DVec3::ZERO), |(w, s), &t| {
                let (vol, c) = centres[t as usize];
                (w + vol, s + c)
            });
            if w > 0.0 {
                sum / w
            } else {
                mesh.positions[v].as_dvec3()
            }
        })
        .collect()
}

/// A boundary vertex may not come closer to `S` than `clearance` (unless it is moving away): a
/// vertex glued to `S` would pin the triangles around it, so that its neighbours could not
/// approach `S` without their triangles' sweep touching it.
pub(super) fn keeps_clearance(surface: &TriangleBvh, p: Vec3, q: Vec3, clearance: f32) -> bool {
    if clearance <= 0.0 {
        return true;
    }
    let d = |x: Vec3| surface.closest_point(x).map_or(f32::INFINITY, |(_, d2)| d2.sqrt());
    let after = d(q);
    after >= clearance || after >= d(p)
}

/// Whether every tetrahedron around `v` keeps at least `min_volume` with `v` at `q`.
pub(super) fn star_stays_positive(mesh: &VolumeMesh, v: usize, q: Vec3, min_volume: f64) -> bool {
    mesh.star(v).iter().all(|&t| {
        let p = mesh.tets[t as usize].map(|u| if u as usize == v { q } else { mesh.positions[u as usize] });
        signed_volume(p) / 6.0 > min_volume
    })
}

/// Whether moving `v` to `q` keeps every tetrahedron around it at or above `floor` degrees of
/// dihedral angle, or no worse than it was (so the mesh's minimum never drops below the floor).
pub(super) fn keeps_quality(mesh: &VolumeMesh, v: usize, q: Vec3, floor: f32) -> bool {
    if floor <= 0.0 {
        return true;
    }
    let floor = f64::from(floor);
    let min_angle = |p: [Vec3; 4]| dihedral_angles(p).iter().copied().fold(180.0, f64::min);
    mesh.star(v).iter().all(|&t| {
        let tet = mesh.tets[t as usize];
        let after = min_angle(tet.map(|u| if u as usize == v { q } else { mesh.positions[u as usize] }));
        after >= floor || after >= min_angle(tet.map(|u| mesh.positions[u as usize]))
    })
}

/// Whether moving boundary vertex `v` to `q` keeps every boundary triangle around it off `S`:
/// the region a triangle `(p, a, b)` sweeps when `p` moves to `q` is the tetrahedron
/// `(p, q, a, b)`, tested exactly against the nearby triangles of `S`.
pub(super) fn sweep_is_clear(mesh: &VolumeMesh, surface: &TriangleBvh, v: usize, q: Vec3) -> bool {
    let p = mesh.positions[v];
    mesh.faces(v).iter().all(|&f| {
        let tri = mesh.boundary[f as usize];
        let k = tri.iter().position(|&u| u as usize == v).unwrap_or(0);
        let (a, b) = (mesh.positions[tri[(k + 1) % 3] as usize], mesh.positions[tri[(k + 2) % 3] as usize]);
        let swept = [p, q, a, b];
        let mut b = Aabb::empty();
        swept.iter().for_each(|&x| b.grow(x));
        let planes = SeparatingPlanes::of(&swept);
        let mut clear = true;
        surface.for_each_overlapping(&b, |_, s| {
            clear = clear && (planes.separates(s) || !triangle_meets_tetrahedron(s, &swept));
        });
        clear
    })
}

/// The outward face planes of a tetrahedron, for a fast conservative "clearly apart" test before
/// the exact one.
pub(super) struct SeparatingPlanes {
    pub(super) planes: [(Vec3, f32); 4],
    pub(super) valid: bool,
}

impl SeparatingPlanes {
    pub(super) fn of(t: &[Vec3; 4]) -> Self {
        let sign = signed_volume(*t).signum() as f32;
        let planes = FACES.map(|f| {
            let n = (t[f[1]] - t[f[0]]).cross(t[f[2]] - t[f[0]]) * sign;
            let n = n.normalize_or_zero();
            (n, n.dot(t[f[0]]))
        });
        let scale = t.iter().map(|p| p.abs().max_element()).fold(0.0, f32::max);
        let valid = signed_volume(*t).abs() > 1e-9 * f64::from(scale).powi(3) && planes.iter().all(|(n, _)| *n != Vec3::ZERO);
        Self { planes, valid }
    }

    /// True only when every vertex of `s` lies clearly outside one face plane.
    pub(super) fn separates(&self, s: &[Vec3; 3]) -> bool {
        self.valid && self.planes.iter().any(|(n, d)| s.iter().all(|p| n.dot(*p) - d > 1e-5 * (1.0 + d.abs())))
    }
}
