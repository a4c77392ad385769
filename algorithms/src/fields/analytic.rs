//! Analytic fields: sphere, torus, gyroid (with analytic gradients), and the sharp `csg` and
//! topology-testing `thin` fields (signed distance, gradient by central differences).

use crate::field::Field;
use crate::geometry::Aabb;
use glam::{Vec2, Vec3};
use std::f64::consts::PI;

/// Signed distance to a sphere centred at the origin.
#[derive(Clone, Copy, Debug)]
pub struct Sphere {
    /// Radius.
    pub radius: f32,
}

impl Default for Sphere {
    fn default() -> Self {
        Self { radius: 0.4 }
    }
}

impl Field for Sphere {
    fn name(&self) -> &str {
        "sphere"
    }
    fn value(&self, p: Vec3) -> f32 {
        p.length() - self.radius
    }
    fn domain(&self) -> Aabb {
        Aabb::cube(0.5)
    }
    fn has_analytic_gradient(&self) -> bool {
        true
    }
    fn gradient(&self, p: Vec3) -> Vec3 {
        p.normalize_or(Vec3::X)
    }
    fn distance_to_surface(&self, p: Vec3, iso: f32) -> f32 {
        (self.value(p) - iso).abs()
    }
    fn lipschitz(&self) -> Option<f64> {
        Some(1.0)
    }
    fn analytic_volume(&self, iso: f32) -> Option<f64> {
        let r = f64::from(self.radius + iso);
        Some(4.0 / 3.0 * PI * r * r * r)
    }
    fn analytic_area(&self, iso: f32) -> Option<f64> {
        let r = f64::from(self.radius + iso);
        Some(4.0 * PI * r * r)
    }
}

/// Signed distance to a torus around the z axis.
#[derive(Clone, Copy, Debug)]
pub struct Torus {
    /// Distance from the axis to the tube's centre.
    pub major: f32,
    /// Tube radius.
    pub minor: f32,
}

impl Default for Torus {
    fn default() -> Self {
        Self { major: 0.3, minor: 0.12 }
    }
}

impl Field for Torus {
    fn name(&self) -> &str {
        "torus"
    }
    fn value(&self, p: Vec3) -> f32 {
        let q = Vec2::new(Vec2::new(p.x, p.y).length() - self.major, p.z);
        q.length() - self.minor
    }
    fn domain(&self) -> Aabb {
        Aabb::cube(0.5)
    }
    fn has_analytic_gradient(&self) -> bool {
        true
    }
    fn gradient(&self, p: Vec3) -> Vec3 {
        let rxy = Vec2::new(p.x, p.y).length();
        let radial = if rxy > 0.0 { Vec2::new(p.x, p.y) / rxy } else { Vec2::X };
        let ring = Vec3::new(radial.x * self.major, radial.y * self.major, 0.0);
        (p - ring).normalize_or(Vec3::Z)
    }
    fn distance_to_surface(&self, p: Vec3, iso: f32) -> f32 {
        (self.value(p) - iso).abs()
    }
    fn lipschitz(&self) -> Option<f64> {
        Some(1.0)
    }
    fn analytic_volume(&self, iso: f32) -> Option<f64> {
        let (rr, r) = (f64::from(self.major), f64::from(self.minor + iso));
        Some(2.0 * PI * PI * rr * r * r)
    }
    fn analytic_area(&self, iso: f32) -> Option<f64> {
        let (rr, r) = (f64::from(self.major), f64::from(self.minor + iso));
        Some(4.0 * PI * PI * rr * r)
    }
}

/// The gyroid `sin(kx)cos(ky) + sin(ky)cos(kz) + sin(kz)cos(kx)`; not a distance field.
#[derive(Clone, Copy, Debug)]
pub struct Gyroid {
    /// Angular frequency `k` (4 periods across the unit domain by default: `k = 8π`).
    pub frequency: f32,
}

impl Default for Gyroid {
    fn default() -> Self {
        Self { frequency: 8.0 * std::f32::consts::PI }
    }
}

impl Field for Gyroid {
    fn name(&self) -> &str {
        "gyroid"
    }
    fn value(&self, p: Vec3) -> f32 {
        let q = p * self.frequency;
        q.x.sin() * q.y.cos() + q.y.sin() * q.z.cos() + q.z.sin() * q.x.cos()
    }
    fn domain(&self) -> Aabb {
        Aabb::cube(0.5)
    }
    fn has_analytic_gradient(&self) -> bool {
        true
    }
    fn gradient(&self, p: Vec3) -> Vec3 {
        let k = self.frequency;
        let q = p * k;
        let (sx, cx) = q.x.sin_cos();
        let (sy, cy) = q.y.sin_cos();
        let (sz, cz) = q.z.sin_cos();
        Vec3::new(cx * cy - sz * sx, -sx * sy + cy * cz, -sy * sz + cz * cx) * k
    }
    /// `k √6`: each partial derivative is `k` times a sum like `cos(kx) cos(ky) - sin(kz) sin(kx)`,
    /// at most `√(cos² kx + sin² kx) √(cos² ky + sin² kz) <= √2` by Cauchy-Schwarz.
    fn lipschitz(&self) -> Option<f64> {
        Some(f64::from(self.frequency).abs() * 6f64.sqrt())
    }
}

fn box_sdf(p: Vec3, centre: Vec3, half: Vec3) -> f32 {
    let q = (p - centre).abs() - half;
    q.max(Vec3::ZERO).length() + q.max_element().min(0.0)
}

/// Capped cylinder along `axis` (0 = x, 1 = y, 2 = z).
fn cylinder_sdf(p: Vec3, centre: Vec3, axis: usize, radius: f32, half_height: f32) -> f32 {
    let q = p - centre;
    let (h, r) = match axis {
        0 => (q.x, Vec2::new(q.y, q.z).length()),
        1 => (q.y, Vec2::new(q.x, q.z).length()),
        _ => (q.z, Vec2::new(q.x, q.y).length()),
    };
    let d = Vec2::new(r - radius, h.abs() - half_height);
    d.max(Vec2::ZERO).length() + d.max_element().min(0.0)
}

/// Box union cylinder minus sphere: the classic CSG part with sharp edges and corners.
#[derive(Clone, Copy, Debug, Default)]
pub struct Csg;

impl Csg {
    /// The box's corners that survive the sphere's bite: exact sharp corners of the surface, the
    /// ground truth for feature-preserving extractors.
    pub fn sharp_corners() -> Vec<Vec3> {
        let mut corners = Vec::with_capacity(7);
        for x in [-0.25f32, 0.25] {
            for y in [-0.25f32, 0.25] {
                for z in [-0.25f32, 0.25] {
                    if (x, y, z) != (0.25, 0.25, 0.25) {
                        corners.push(Vec3::new(x, y, z));
                    }
                }
            }
        }
        corners
    }
}

impl Field for Csg {
    fn name(&self) -> &str {
        "csg"
    }
    fn value(&self, p: Vec3) -> f32 {
        let cube = box_sdf(p, Vec3::ZERO, Vec3::splat(0.25));
        let cylinder = cylinder_sdf(p, Vec3::ZERO, 1, 0.12, 0.4);
        let bite = Vec3::splat(0.25).distance(p) - 0.2;
        cube.min(cylinder).max(-bite)
    }
    fn domain(&self) -> Aabb {
        Aabb::cube(0.5)
    }
    /// The minimum and maximum of distances are 1-Lipschitz too.
    fn lipschitz(&self) -> Option<f64> {
        Some(1.0)
    }
}

/// Features near the grid spacing at resolution 64 (spacing 1/63 ≈ 0.016): a tube of radius
/// 0.012, a sheet 0.02 thick, and two 0.03-thick sheets 0.02 apart.
#[derive(Clone, Copy, Debug, Default)]
pub struct Thin;

impl Field for Thin {
    fn name(&self) -> &str {
        "thin"
    }
    fn value(&self, p: Vec3) -> f32 {
        let tube = cylinder_sdf(p, Vec3::new(0.0, -0.3, -0.3), 0, 0.012, 0.35);
        let sheet = box_sdf(p, Vec3::new(0.0, 0.3, 0.0), Vec3::new(0.35, 0.01, 0.3));
        let a = box_sdf(p, Vec3::new(0.0, -0.05, 0.195), Vec3::new(0.3, 0.2, 0.015));
        let b = box_sdf(p, Vec3::new(0.0, -0.05, 0.245), Vec3::new(0.3, 0.2, 0.015));
        tube.min(sheet).min(a).min(b)
    }
    fn domain(&self) -> Aabb {
        Aabb::cube(0.5)
    }
    /// The minimum of distances is 1-Lipschitz too.
    fn lipschitz(&self) -> Option<f64> {
        Some(1.0)
    }
}
