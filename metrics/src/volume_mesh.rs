//! Measures of a tetrahedral mesh that should enclose and approximate a surface `S` (the
//! `bcc-sculpt` metrics of Stuart et al. 2013, Table 1):
//! - `dihedral_deg` {`min`, `max`}: over all tetrahedra (ideal: far from 0° and 180°);
//! - `boundary_distance` {`min`, `max`, `mean`}: distance of the boundary's vertices to `S`;
//! - `volume_ratio`: tetrahedral volume over the volume `S` bounds (ideal: just above 1);
//! - `encloses`: every vertex of `S` lies inside the tetrahedral mesh (winding number of the
//!   boundary at least 1/2, or within `1e-6` of the box size of it), only where `S` is a triangle mesh;
//! - `converged`: copied from the extractor (its stopping condition was met);
//! - `inverted`: tetrahedra with non-positive volume (ideal 0).

use crate::tet_quality::{tet_quality, MinMax};
use isolab_algorithms::bvh::TriangleBvh;
use isolab_algorithms::{Field, TetMesh, TriMesh};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Min, max and mean of a distance.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct DistanceRange {
    /// Smallest.
    pub min: f64,
    /// Largest.
    pub max: f64,
    /// Mean.
    pub mean: f64,
}

/// The volume-mesh section of the metrics JSON.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct VolumeMetrics {
    /// Smallest and largest dihedral angle, degrees.
    pub dihedral_deg: MinMax,
    /// Tetrahedra with non-positive volume.
    pub inverted: usize,
    /// Distance of boundary vertices to the surface (where the field is known).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub boundary_distance: Option<DistanceRange>,
    /// Tetrahedral volume / the surface's volume (where known).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub volume_ratio: Option<f64>,
    /// Every vertex of the surface mesh inside the tetrahedral mesh (mesh fields only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub encloses: Option<bool>,
    /// Whether the extractor met its stopping condition.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub converged: Option<bool>,
}

/// Measures `volume` (with its `boundary`) against `field`'s level set `iso`; `None` when there
/// are no tetrahedra.
pub fn volume_metrics(
    volume: &TetMesh,
    boundary: &TriMesh,
    field: Option<(&dyn Field, f32)>,
    converged: Option<bool>,
) -> Option<VolumeMetrics> {
    if volume.tetrahedra.is_empty() {
        return None;
    }
    let q = tet_quality(volume);
    let boundary_distance = field.filter(|_| !boundary.positions.is_empty()).map(|(f, iso)| {
        let d: Vec<f64> = boundary.positions.par_iter().map(|&p| f64::from(f.distance_to_surface(p, iso).abs())).collect();
        DistanceRange {
            min: d.iter().copied().fold(f64::INFINITY, f64::min),
            max: d.iter().copied().fold(0.0, f64::max),
            mean: d.iter().sum::<f64>() / d.len() as f64,
        }
    });
    let surface = field.and_then(|(f, _)| f.surface_mesh());
    let reference_volume = match (surface, field) {
        (Some(s), _) => Some(soup_volume(s.triangles())),
        (None, Some((f, iso))) => f.analytic_volume(iso),
        _ => None,
    };
    Some(VolumeMetrics {
        dihedral_deg: q.dihedral_deg,
        inverted: q.inverted,
        boundary_distance,
        volume_ratio: reference_volume.filter(|v| *v > 0.0).map(|v| q.total_volume / v),
        encloses: surface.map(|s| encloses(boundary, s)),
        converged,
    })
}

/// Signed volume bounded by a triangle soup (divergence theorem).
pub fn soup_volume(triangles: &[[glam::Vec3; 3]]) -> f64 {
    triangles.iter().map(|t| t[0].as_dvec3().dot(t[1].as_dvec3().cross(t[2].as_dvec3())) / 6.0).sum()
}

/// Whether every vertex of `surface` is inside the closed `boundary` (or on it).
pub fn encloses(boundary: &TriMesh, surface: &TriangleBvh) -> bool {
    let hull = TriangleBvh::new(boundary.triangles.iter().map(|t| t.map(|i| boundary.positions[i as usize])).collect());
    let tolerance = 1e-6 * hull.bounds().longest_side();
    surface
        .triangles()
        .par_iter()
        .flatten()
        .all(|&p| hull.winding_number(p) >= 0.5 || hull.closest_point(p).is_some_and(|(_, d2)| d2.sqrt() <= tolerance))
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    #[test]
    fn a_unit_tetrahedron_around_a_smaller_one() {
        let tet = TetMesh { positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z], tetrahedra: vec![[0, 1, 2, 3]] };
        let boundary = TriMesh {
            positions: tet.positions.clone(),
            normals: vec![],
            triangles: vec![[1, 2, 3], [0, 3, 2], [0, 1, 3], [0, 2, 1]],
        };
        let small: Vec<[Vec3; 3]> = boundary.triangles.iter().map(|t| t.map(|i| tet.positions[i as usize] * 0.5 + 0.1)).collect();
        let s = TriangleBvh::new(small.clone());
        assert!(encloses(&boundary, &s));
        assert!((soup_volume(&small) - 1.0 / 48.0).abs() < 1e-7, "{}", soup_volume(&small));
        let far = TriangleBvh::new(small.iter().map(|t| t.map(|p| p + Vec3::X)).collect());
        assert!(!encloses(&boundary, &far));
        let m = volume_metrics(&tet, &boundary, None, Some(true)).unwrap();
        assert_eq!((m.inverted, m.converged, m.encloses), (0, Some(true), None));
        assert!((m.dihedral_deg.max - 90.0).abs() < 1e-9);
    }
}
