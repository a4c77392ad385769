//! Accuracy: volume and area, and the distance of vertices to the true surface.

use isolab_algorithms::{Field, TriMesh};
use rayon::prelude::*;
use serde::Serialize;

/// Signed volume `Σ a·(b×c) / 6` over triangles (divergence theorem); exact for a closed mesh,
/// positive when it is outward.
pub fn signed_volume(mesh: &TriMesh) -> f64 {
    mesh.triangles
        .par_iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| mesh.positions[i as usize].as_dvec3());
            a.dot(b.cross(c)) / 6.0
        })
        .sum()
}

/// Total triangle area.
pub fn surface_area(mesh: &TriMesh) -> f64 {
    mesh.triangles
        .par_iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| mesh.positions[i as usize].as_dvec3());
            0.5 * (b - a).cross(c - a).length()
        })
        .sum()
}

/// Distance of vertices to the level set (`surface_distance` in the metrics JSON).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct DistanceStats {
    /// Mean over vertices (ideal 0).
    pub mean: f64,
    /// Largest (ideal 0).
    pub max: f64,
}

/// Distance of every used vertex to `field`'s level set `iso`: `|f - iso| / |grad f|` for
/// analytic fields, the exact distance for mesh fields ([`Field::distance_to_surface`]).
pub fn surface_distance(mesh: &TriMesh, field: &dyn Field, iso: f32) -> DistanceStats {
    if mesh.positions.is_empty() {
        return DistanceStats::default();
    }
    let (sum, max) = mesh
        .positions
        .par_iter()
        .map(|&p| f64::from(field.distance_to_surface(p, iso)))
        .fold(|| (0.0, 0.0f64), |(s, m), d| (s + d, m.max(d)))
        .reduce(|| (0.0, 0.0), |a, b| (a.0 + b.0, a.1.max(b.1)));
    DistanceStats { mean: sum / mesh.positions.len() as f64, max }
}
