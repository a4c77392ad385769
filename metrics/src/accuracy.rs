//! Accuracy: volume and area, and the distance of vertices to the true surface.

use isolab_algorithms::{Field, TriMesh};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Signed volume `Σ a·(b×c) / 6` over triangles (divergence theorem); exact for a closed mesh,
/// positive when it is outward.
pub fn signed_volume(mesh: &TriMesh) -> f64 {
    deterministic_sum(&mesh.triangles, |t| {
        let [a, b, c] = t.map(|i| mesh.positions[i as usize].as_dvec3());
        a.dot(b.cross(c)) / 6.0
    })
}

/// Sums `f` over `items` in parallel with a fixed chunking and order, so the result is the same
/// bit for bit on every run (rayon's adaptive splitting would change the rounding).
pub fn deterministic_sum<T: Sync>(items: &[T], f: impl Fn(&T) -> f64 + Sync) -> f64 {
    let partial: Vec<f64> = items.par_chunks(4096).map(|c| c.iter().map(&f).sum::<f64>()).collect();
    partial.iter().sum()
}

/// Reads a JSON `null` (how serde_json writes NaN) back as NaN.
pub fn nan_if_null<'de, D: serde::Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::NAN))
}

/// Total triangle area.
pub fn surface_area(mesh: &TriMesh) -> f64 {
    deterministic_sum(&mesh.triangles, |t| {
        let [a, b, c] = t.map(|i| mesh.positions[i as usize].as_dvec3());
        0.5 * (b - a).cross(c - a).length()
    })
}

/// Distance of vertices to the level set (`surface_distance` in the metrics JSON).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
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
    let distances: Vec<f64> = mesh.positions.par_iter().map(|&p| f64::from(field.distance_to_surface(p, iso))).collect();
    let sum = deterministic_sum(&distances, |&d| d);
    DistanceStats { mean: sum / mesh.positions.len() as f64, max: distances.iter().copied().fold(0.0, f64::max) }
}

/// One direction of a Hausdorff distance: distances from sample points of one mesh to the
/// closest point of the other.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct OneSided {
    /// Sample points used.
    pub samples: usize,
    /// Mean distance.
    pub mean: f64,
    /// Root mean square distance.
    pub rms: f64,
    /// Largest distance: the one-sided Hausdorff distance.
    pub max: f64,
}

/// Two-sided Hausdorff distance between meshes `a` and `b`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Hausdorff {
    /// From `a`'s samples to `b`.
    pub a_to_b: OneSided,
    /// From `b`'s samples to `a`.
    pub b_to_a: OneSided,
    /// `max(a_to_b.max, b_to_a.max)`.
    pub max: f64,
}

/// Where sample points are taken on a mesh.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Sampling {
    /// Every used vertex (pymeshlab's `get_hausdorff_distance` default, so results compare).
    #[default]
    Vertices,
    /// Every used vertex, plus each triangle's centroid and edge midpoints (denser, finds gaps
    /// between vertices).
    VerticesAndFaces,
}

fn sample_points(mesh: &TriMesh, sampling: Sampling) -> Vec<glam::Vec3> {
    let mut used = vec![false; mesh.positions.len()];
    mesh.triangles.iter().flatten().for_each(|&i| used[i as usize] = true);
    let mut points: Vec<glam::Vec3> = mesh.positions.iter().zip(&used).filter(|(_, &u)| u).map(|(p, _)| *p).collect();
    if sampling == Sampling::VerticesAndFaces {
        for t in &mesh.triangles {
            let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
            points.extend([(a + b + c) / 3.0, (a + b) * 0.5, (b + c) * 0.5, (c + a) * 0.5]);
        }
    }
    points
}

fn one_sided(points: &[glam::Vec3], target: &isolab_algorithms::bvh::TriangleBvh) -> OneSided {
    if points.is_empty() || target.is_empty() {
        return OneSided::default();
    }
    let distances: Vec<f64> =
        points.par_iter().map(|&p| target.closest_point(p).map_or(0.0, |(_, d2)| f64::from(d2).sqrt())).collect();
    let (sum, sq) = (deterministic_sum(&distances, |&d| d), deterministic_sum(&distances, |&d| d * d));
    let max = distances.iter().copied().fold(0.0, f64::max);
    let n = points.len() as f64;
    OneSided { samples: points.len(), mean: sum / n, rms: (sq / n).sqrt(), max }
}

fn bvh_of(mesh: &TriMesh) -> isolab_algorithms::bvh::TriangleBvh {
    isolab_algorithms::bvh::TriangleBvh::new(mesh.triangles.iter().map(|t| t.map(|i| mesh.positions[i as usize])).collect())
}

/// Two-sided Hausdorff distance, BVH accelerated.
pub fn hausdorff(a: &TriMesh, b: &TriMesh, sampling: Sampling) -> Hausdorff {
    let a_to_b = one_sided(&sample_points(a, sampling), &bvh_of(b));
    let b_to_a = one_sided(&sample_points(b, sampling), &bvh_of(a));
    Hausdorff { a_to_b, b_to_a, max: a_to_b.max.max(b_to_a.max) }
}

/// Angle between the mesh's vertex normals and the field's gradient.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct NormalDeviation {
    /// Mean angle, degrees (ideal 0).
    pub mean_deg: f64,
    /// Largest angle, degrees.
    pub max_deg: f64,
}

/// Angle between each vertex normal (the mesh's own, or area-weighted face normals when it has
/// none) and the direction of `field`'s gradient at the vertex.
pub fn normal_deviation(mesh: &TriMesh, field: &dyn Field) -> NormalDeviation {
    let computed;
    let normals = if mesh.normals.len() == mesh.positions.len() {
        &mesh.normals
    } else {
        let mut m = mesh.clone();
        m.compute_face_weighted_normals();
        computed = m.normals;
        &computed
    };
    let angles: Vec<f64> = mesh
        .positions
        .par_iter()
        .zip(normals.par_iter())
        .filter_map(|(&p, &n)| {
            let g = field.gradient(p).normalize_or_zero();
            (g != glam::Vec3::ZERO && n != glam::Vec3::ZERO).then(|| f64::from(n.dot(g)).clamp(-1.0, 1.0).acos().to_degrees())
        })
        .collect();
    if angles.is_empty() {
        return NormalDeviation::default();
    }
    NormalDeviation {
        mean_deg: angles.iter().sum::<f64>() / angles.len() as f64,
        max_deg: angles.iter().copied().fold(0.0, f64::max),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    fn tetra(scale: f32) -> TriMesh {
        let mut t = TriMesh::unit_tetrahedron();
        t.positions.iter_mut().for_each(|p| *p *= scale);
        t
    }

    #[test]
    fn volume_area_and_hausdorff_of_scaled_tetrahedra() {
        assert!((signed_volume(&tetra(1.0)) - 1.0 / 6.0).abs() < 1e-12);
        assert!((surface_area(&tetra(1.0)) - (1.5 + 3f64.sqrt() / 2.0)).abs() < 1e-6);
        let h = hausdorff(&tetra(1.0), &tetra(1.0), Sampling::VerticesAndFaces);
        assert!(h.max < 1e-6, "{h:?}");
        // Vertex (2,0,0) of the larger one is 1 from the smaller; every vertex of the smaller lies on the larger.
        let h = hausdorff(&tetra(1.0), &tetra(2.0), Sampling::Vertices);
        assert!(h.a_to_b.max < 1e-6);
        assert!((h.b_to_a.max - 1.0).abs() < 1e-6, "{h:?}");
        assert_eq!(h.b_to_a.samples, 4);
    }

    #[test]
    fn sphere_normals_match_the_gradient() {
        let sphere = isolab_algorithms::fields::Sphere::default();
        let mut m = tetra(1.0);
        m.normals = m.positions.iter().map(|p| p.normalize_or(Vec3::X)).collect();
        let d = normal_deviation(&m, &sphere);
        assert!(d.max_deg < 1e-3, "{d:?}");
    }
}
