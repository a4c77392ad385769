//! A triangle mesh as a signed distance field.
//!
//! Distance is exact (closest point over a [`TriangleBvh`]); the sign comes from the
//! generalized winding number `w` (Jacobson et al. 2013): inside where `|w|` is at least 1/2. A
//! mesh with holes, like the Stanford bunny's base, therefore still has a sensible inside, and the
//! level set closes over the holes.
//!
//! The field does not depend on the input's orientation: inside a closed surface wound inward
//! `w` is -1, and `|w|` is still 1. A mesh whose total signed volume is negative (wound inward
//! as a whole, common in files from the wild) is also flipped before anything else, so that its
//! triangles (the surface `S` that `bcc-sculpt` encloses) face outward like every other input;
//! [`MeshField::reoriented`] says when that happened. A hollow shell whose inner wall faces the
//! cavity keeps its cavity: there `w` is 0 whichever way the whole is wound.
//!
//! The default domain is the mesh's bounding box plus a margin of 5% of its longest side.

use crate::bvh::TriangleBvh;
use crate::field::{Field, FieldError};
use crate::geometry::Aabb;
use glam::Vec3;

/// Fraction of the longest side added around the mesh's bounding box.
pub const DOMAIN_MARGIN: f32 = 0.05;

/// Signed distance to a triangle mesh.
pub struct MeshField {
    name: String,
    bvh: TriangleBvh,
    domain: Aabb,
    reoriented: bool,
}

impl MeshField {
    /// Builds the field from vertex positions and counter-clockwise triangles.
    pub fn new(name: impl Into<String>, positions: &[Vec3], triangles: &[[u32; 3]]) -> Result<Self, FieldError> {
        let name = name.into();
        if triangles.is_empty() {
            return Err(FieldError::EmptyMesh { name });
        }
        if let Some(vertex) = positions.iter().position(|p| !p.is_finite()) {
            return Err(FieldError::NonFiniteVertex { name, vertex });
        }
        let mut soup = Vec::with_capacity(triangles.len());
        for (triangle, t) in triangles.iter().enumerate() {
            if let Some(&vertex) = t.iter().find(|&&i| i as usize >= positions.len()) {
                return Err(FieldError::BadIndex { name, triangle, vertex, vertices: positions.len() });
            }
            soup.push(t.map(|i| positions[i as usize]));
        }
        let reoriented = signed_volume(&soup) < 0.0;
        if reoriented {
            for t in &mut soup {
                t.swap(1, 2);
            }
        }
        let bvh = TriangleBvh::new(soup);
        let bounds = bvh.bounds();
        let domain = bounds.expanded(DOMAIN_MARGIN * bounds.longest_side());
        Ok(Self { name, bvh, domain, reoriented })
    }

    /// Whether the input was wound inward as a whole (negative signed volume) and was flipped.
    pub fn reoriented(&self) -> bool {
        self.reoriented
    }

    /// The triangle hierarchy (for exact distance queries).
    pub fn bvh(&self) -> &TriangleBvh {
        &self.bvh
    }

    /// Exact unsigned distance from `p` to the mesh.
    pub fn unsigned_distance(&self, p: Vec3) -> f32 {
        self.bvh.closest_point(p).map_or(f32::INFINITY, |(_, d2)| d2.sqrt())
    }
}

impl Field for MeshField {
    fn name(&self) -> &str {
        &self.name
    }
    fn value(&self, p: Vec3) -> f32 {
        let d = self.unsigned_distance(p);
        if self.bvh.winding_number(p).abs() >= 0.5 {
            -d
        } else {
            d
        }
    }

    fn surface_mesh(&self) -> Option<&TriangleBvh> {
        Some(&self.bvh)
    }

    fn domain(&self) -> Aabb {
        self.domain
    }
    fn distance_to_surface(&self, p: Vec3, iso: f32) -> f32 {
        if iso == 0.0 {
            self.unsigned_distance(p)
        } else {
            (self.value(p) - iso).abs()
        }
    }
}

/// Signed volume of a triangle soup about its bounding box centre (positive for a closed mesh
/// wound outward; for an open one, its sign still says which way most of it faces).
fn signed_volume(soup: &[[Vec3; 3]]) -> f64 {
    let mut bounds = Aabb::empty();
    soup.iter().flatten().for_each(|&p| bounds.grow(p));
    let o = bounds.centre().as_dvec3();
    soup.iter()
        .map(|t| {
            let [a, b, c] = t.map(|p| p.as_dvec3() - o);
            a.dot(b.cross(c))
        })
        .sum::<f64>()
        / 6.0
}

#[cfg(test)]
mod tests {
    use super::*;

    fn octahedron() -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let v = vec![Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z];
        let t = vec![[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]];
        (v, t)
    }

    #[test]
    fn octahedron_sign_and_distance() {
        let (v, t) = octahedron();
        let f = MeshField::new("octa", &v, &t).unwrap();
        assert!(f.value(Vec3::ZERO) < 0.0);
        assert!((f.value(Vec3::ZERO) + 1.0 / 3f32.sqrt()).abs() < 1e-5);
        assert!((f.value(Vec3::new(2.0, 0.0, 0.0)) - 1.0).abs() < 1e-5);
    }

    #[test]
    fn open_mesh_still_has_an_inside() {
        let (v, mut t) = octahedron();
        t.pop(); // a hole
        let f = MeshField::new("open", &v, &t).unwrap();
        assert!(f.value(Vec3::new(0.1, 0.1, 0.1)) < 0.0);
        assert!(f.value(Vec3::new(0.0, 0.0, 3.0)) > 0.0);
    }

    #[test]
    fn an_inward_mesh_gives_the_same_field_and_is_flipped() {
        let (v, t) = octahedron();
        let outward = MeshField::new("out", &v, &t).unwrap();
        let inward_triangles: Vec<[u32; 3]> = t.iter().map(|&[a, b, c]| [a, c, b]).collect();
        let inward = MeshField::new("in", &v, &inward_triangles).unwrap();
        assert!(!outward.reoriented() && inward.reoriented());
        for p in [Vec3::ZERO, Vec3::new(0.2, -0.1, 0.3), Vec3::new(1.5, 0.0, 0.2), Vec3::new(-0.4, 0.4, 0.1)] {
            assert_eq!(inward.value(p), outward.value(p), "{p}");
        }
        // Two disjoint shells, one wound each way: both have an inside (|w|).
        let mut v2 = v.clone();
        v2.extend(v.iter().map(|p| *p + Vec3::new(5.0, 0.0, 0.0)));
        let mut t2 = t.clone();
        t2.extend(inward_triangles.iter().map(|tri| tri.map(|i| i + 6)));
        let mixed = MeshField::new("mixed", &v2, &t2).unwrap();
        assert!(mixed.value(Vec3::ZERO) < 0.0 && mixed.value(Vec3::new(5.0, 0.0, 0.0)) < 0.0);
        assert!(mixed.value(Vec3::new(2.5, 0.0, 0.0)) > 0.0);
    }

    #[test]
    fn a_hollow_shell_keeps_its_cavity_either_way_round() {
        let (v, t) = octahedron();
        // Outer shell outward, inner shell (half size) facing the cavity.
        let mut positions = v.clone();
        positions.extend(v.iter().map(|p| *p * 0.5));
        let mut triangles = t.clone();
        triangles.extend(t.iter().map(|&[a, b, c]| [a + 6, c + 6, b + 6]));
        let flipped: Vec<[u32; 3]> = triangles.iter().map(|&[a, b, c]| [a, c, b]).collect();
        for (name, tris) in [("hollow", &triangles), ("hollow-inward", &flipped)] {
            let f = MeshField::new(name, &positions, tris).unwrap();
            assert!(f.value(Vec3::ZERO) > 0.0, "{name}: the cavity is outside");
            assert!(f.value(Vec3::new(0.7, 0.0, 0.0)) < 0.0, "{name}: the wall is inside");
        }
    }

    #[test]
    fn bad_meshes_are_rejected_with_the_offender_named() {
        let (v, _) = octahedron();
        assert!(matches!(MeshField::new("e", &v, &[]), Err(FieldError::EmptyMesh { .. })));
        let e = MeshField::new("b", &v, &[[0, 1, 9]]).err().unwrap();
        assert!(e.to_string().contains("vertex 9"), "{e}");
        let mut nan = v.clone();
        nan[3].y = f32::NAN;
        assert!(matches!(MeshField::new("n", &nan, &[[0, 1, 3]]), Err(FieldError::NonFiniteVertex { vertex: 3, .. })));
    }
}
