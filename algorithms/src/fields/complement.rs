//! The complement of a field: `-f`, so that "inside is above the iso-value" (a scan, whose
//! object is brighter than its background) becomes isolab's "inside is `f < iso`" at iso `-iso`.
//!
//! Meshes of the complement are wound so that their normals point toward decreasing values of
//! the original field: out of the bright object. `--inside above` on the command line wraps the
//! field in this.

use crate::field::Field;
use crate::geometry::Aabb;
use glam::Vec3;
use std::sync::Arc;

/// `-f` for any field `f`.
pub struct Complement(pub Arc<dyn Field>);

impl Field for Complement {
    fn name(&self) -> &str {
        self.0.name()
    }

    fn value(&self, p: Vec3) -> f32 {
        -self.0.value(p)
    }

    fn domain(&self) -> Aabb {
        self.0.domain()
    }

    fn has_analytic_gradient(&self) -> bool {
        self.0.has_analytic_gradient()
    }

    fn gradient(&self, p: Vec3) -> Vec3 {
        -self.0.gradient(p)
    }

    fn difference_step(&self) -> f32 {
        self.0.difference_step()
    }

    fn distance_to_surface(&self, p: Vec3, iso: f32) -> f32 {
        self.0.distance_to_surface(p, -iso)
    }

    fn material(&self, p: Vec3) -> u8 {
        self.0.material(p)
    }

    /// `-f` changes as fast as `f`.
    fn lipschitz(&self) -> Option<f64> {
        self.0.lipschitz()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_complement_negates_value_gradient_and_iso() {
        let sphere: Arc<dyn Field> = Arc::new(crate::fields::Sphere::default());
        let c = Complement(sphere.clone());
        let p = Vec3::new(0.1, 0.2, -0.3);
        assert_eq!(c.value(p), -sphere.value(p));
        assert_eq!(c.gradient(p), -sphere.gradient(p));
        assert_eq!(c.distance_to_surface(p, -0.05), sphere.distance_to_surface(p, 0.05));
        assert!(c.surface_mesh().is_none() && c.analytic_volume(0.0).is_none());
        assert_eq!(c.lipschitz(), Some(1.0));
    }
}
