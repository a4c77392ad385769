//! The quadric error function of dual contouring (Ju et al. 2002, section 2.3): the point
//! minimising the squared distances to the tangent planes of a cell's edge crossings, solved
//! around their mass point by a truncated SVD (nalgebra) so that flat and ridge-like cells keep
//! the mass point along their free directions.

use glam::Vec3;
use nalgebra::{Matrix3, Vector3};

/// Minimises `Σ (n_i · (x - p_i))²` over the crossings `points` with unit `normals`, around their
/// mass point, dropping singular values below `tolerance` times the largest. Returns the mass
/// point when there is no usable normal.
pub fn solve_qef(points: &[Vec3], normals: &[Vec3], tolerance: f32) -> Vec3 {
    let n = points.len().max(1) as f32;
    let mass = points.iter().copied().sum::<Vec3>() / n;
    let mut a = Matrix3::<f64>::zeros();
    let mut b = Vector3::<f64>::zeros();
    for (p, nrm) in points.iter().zip(normals) {
        let nv = Vector3::new(f64::from(nrm.x), f64::from(nrm.y), f64::from(nrm.z));
        let d = f64::from(nrm.dot(*p - mass));
        a += nv * nv.transpose();
        b += nv * d;
    }
    let svd = a.svd(true, true);
    let largest = svd.singular_values.max();
    if largest <= 0.0 {
        return mass;
    }
    let (Some(u), Some(vt)) = (svd.u, svd.v_t) else { return mass };
    let mut x = Vector3::zeros();
    for k in 0..3 {
        let s = svd.singular_values[k];
        if s > f64::from(tolerance) * largest {
            let uk = u.column(k);
            let vk = vt.row(k).transpose();
            x += vk * (uk.dot(&b) / s);
        }
    }
    mass + Vec3::new(x.x as f32, x.y as f32, x.z as f32)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn three_planes_meet_at_their_corner_and_one_plane_keeps_the_mass_point() {
        let corner = Vec3::new(0.3, 0.6, 0.2);
        let points = [corner + Vec3::new(0.0, 0.2, 0.3), corner + Vec3::new(0.1, 0.0, 0.25), corner + Vec3::new(0.2, 0.3, 0.0)];
        let normals = [Vec3::X, Vec3::Y, Vec3::Z];
        assert!(solve_qef(&points, &normals, 0.1).distance(corner) < 1e-5);
        // All crossings on one plane z = 0.2: x and y stay at the mass point, z on the plane.
        let flat = [Vec3::new(0.1, 0.1, 0.2), Vec3::new(0.9, 0.3, 0.2), Vec3::new(0.4, 0.8, 0.2)];
        let x = solve_qef(&flat, &[Vec3::Z; 3], 0.1);
        let mass = flat.iter().copied().sum::<Vec3>() / 3.0;
        assert!(x.distance(mass) < 1e-6, "{x} vs {mass}");
    }
}
