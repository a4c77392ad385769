//! Built-in fields and the field registry.
//!
//! Every built-in field has a stable name, a one-line description and a default domain. Noise
//! fields take a seed ([`FieldParams::seed`], default [`DEFAULT_SEED`]) so runs are repeatable.
//! Mesh files become fields through [`MeshField`] (signed distance, sign from the generalized
//! winding number), volume files through [`VolumeField`] (trilinear in world coordinates), and
//! [`Complement`] flips which side is inside.

mod analytic;
mod complement;
mod mesh_sdf;
mod noise;
pub mod volume;

pub use analytic::{Csg, Gyroid, Sphere, Thin, Torus};
pub use complement::Complement;
pub use mesh_sdf::{MeshField, CAP_WINDING_BOUND, CROSSING_TOLERANCE, DEFAULT_BAND_CELLS};
pub use noise::{Asteroid, Terrain, NOISE_GRADIENT_BOUND_2D, NOISE_GRADIENT_BOUND_3D};
pub use volume::{otsu_threshold, OtsuHistogram, Volume, VolumeField};

use crate::field::{Field, FieldError};
use std::sync::Arc;

/// The seed used when none is given.
pub const DEFAULT_SEED: i32 = 1337;

/// Parameters shared by the built-in fields.
#[derive(Clone, Copy, Debug)]
pub struct FieldParams {
    /// Seed of the noise fields (`asteroid`, `terrain`); analytic fields ignore it.
    pub seed: i32,
}

impl Default for FieldParams {
    fn default() -> Self {
        Self { seed: DEFAULT_SEED }
    }
}

/// A registry entry: name, one-line description, constructor.
pub struct FieldInfo {
    /// Stable name used on the command line and in the report.
    pub name: &'static str,
    /// One line saying what the field is.
    pub description: &'static str,
    /// Builds the field.
    pub make: fn(FieldParams) -> Arc<dyn Field>,
}

/// All built-in fields, in the order the report lists them.
pub fn registry() -> &'static [FieldInfo] {
    const FIELDS: &[FieldInfo] = &[
        FieldInfo {
            name: "sphere",
            description: "signed distance to a sphere of radius 0.4 in [-0.5,0.5]^3",
            make: |_| Arc::new(Sphere::default()),
        },
        FieldInfo {
            name: "torus",
            description: "signed distance to a torus (R 0.3, r 0.12) around z in [-0.5,0.5]^3; genus 1",
            make: |_| Arc::new(Torus::default()),
        },
        FieldInfo {
            name: "gyroid",
            description: "sin(kx)cos(ky)+sin(ky)cos(kz)+sin(kz)cos(kx), 4 periods across [-0.5,0.5]^3; open at the domain",
            make: |_| Arc::new(Gyroid::default()),
        },
        FieldInfo {
            name: "asteroid",
            description: "sphere of radius 0.35 displaced by fractal 3D simplex noise (the RMT paper's benchmark object)",
            make: |p| Arc::new(Asteroid::new(p.seed)),
        },
        FieldInfo {
            name: "terrain",
            description:
                "fractal height field with 3D-noise overhangs and caves in [-0.5,0.5]x[-0.25,0.25]x[-0.5,0.5]; open at the domain",
            make: |p| Arc::new(Terrain::new(p.seed)),
        },
        FieldInfo {
            name: "csg",
            description: "box union cylinder minus sphere: sharp edges and corners",
            make: |_| Arc::new(Csg),
        },
        FieldInfo {
            name: "thin",
            description: "thin tube, thin sheet and two close parallel sheets, near the grid spacing at resolution 64",
            make: |_| Arc::new(Thin),
        },
    ];
    FIELDS
}

/// Builds the built-in field called `name`.
pub fn builtin(name: &str, params: FieldParams) -> Result<Arc<dyn Field>, FieldError> {
    registry().iter().find(|f| f.name == name).map(|f| (f.make)(params)).ok_or_else(|| FieldError::Unknown {
        name: name.to_owned(),
        valid: registry().iter().map(|f| f.name).collect::<Vec<_>>().join(", "),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    #[test]
    fn every_builtin_is_finite_and_changes_sign_in_its_domain() {
        for info in registry() {
            let f = (info.make)(FieldParams::default());
            assert_eq!(f.name(), info.name);
            let d = f.domain();
            let (mut neg, mut pos) = (false, false);
            let n = 24;
            for i in 0..n {
                for j in 0..n {
                    for k in 0..n {
                        let t = Vec3::new(i as f32, j as f32, k as f32) / (n - 1) as f32;
                        let v = f.value(d.min + d.extent() * t);
                        assert!(v.is_finite(), "{} not finite", info.name);
                        neg |= v < 0.0;
                        pos |= v > 0.0;
                    }
                }
            }
            assert!(neg && pos, "{} has no surface", info.name);
        }
    }

    #[test]
    fn analytic_gradients_match_central_differences() {
        for info in registry() {
            let f = (info.make)(FieldParams::default());
            if !f.has_analytic_gradient() {
                continue;
            }
            for p in [Vec3::new(0.11, -0.23, 0.31), Vec3::new(-0.3, 0.05, 0.2), Vec3::new(0.2, 0.3, -0.1)] {
                let g = f.gradient(p);
                let c = crate::field::central_difference(f.as_ref(), p, 1e-3);
                assert!((g - c).length() < 2e-2 * g.length().max(1.0), "{}: {g} vs {c}", info.name);
            }
        }
    }

    #[test]
    fn every_builtin_has_a_lipschitz_bound_its_values_keep() {
        for info in registry() {
            let f = (info.make)(FieldParams::default());
            let l = f.lipschitz().unwrap_or_else(|| panic!("{} has no Lipschitz bound", info.name));
            let d = f.domain();
            let mut steepest = 0.0f64;
            let n = 20;
            for i in 0..n * n * n {
                let t = Vec3::new((i % n) as f32, (i / n % n) as f32, (i / (n * n)) as f32) / (n - 1) as f32;
                let p = d.min + d.extent() * t;
                for step in [Vec3::new(3e-3, 1e-3, -2e-3), Vec3::new(-1e-2, 4e-3, 2e-3)] {
                    let q = p + step;
                    steepest = steepest.max(f64::from((f.value(p) - f.value(q)).abs()) / f64::from(step.length()));
                }
            }
            assert!(steepest <= l * (1.0 + 1e-3), "{}: {steepest} > {l}", info.name);
            assert!(steepest > l / 20.0, "{}: {steepest}, bound {l} is loose beyond use", info.name);
        }
    }

    #[test]
    fn unknown_field_lists_valid_names() {
        let err = builtin("spere", FieldParams::default()).err().unwrap().to_string();
        assert!(err.contains("spere") && err.contains("sphere") && err.contains("terrain"));
    }
}
