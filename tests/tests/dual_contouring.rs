//! Dual contouring: sharp corners of `csg` reproduced (marching cubes and surface nets cut them),
//! closed and manifold on the smooth closed fields, and a clear error without a field.

use isolab_algorithms::{extractors, fields, Extraction, Grid, Samples};
use isolab_tests::assert_closed_manifold;

fn worst_corner_distance(algorithm: &str, resolution: usize) -> f32 {
    let f = fields::builtin("csg", Default::default()).unwrap();
    let grid = Grid::covering(&f.domain(), resolution).unwrap();
    let s = Samples::sample_cubic(f.clone(), grid, 0.0).unwrap();
    let mut out = Extraction::default();
    extractors::by_name(algorithm).unwrap().extract(&s, &mut out).unwrap();
    fields::Csg::sharp_corners()
        .iter()
        .map(|c| out.surface.positions.iter().map(|p| p.distance(*c)).fold(f32::INFINITY, f32::min))
        .fold(0.0, f32::max)
        / grid.spacing
}

#[test]
fn csg_corners_come_out_sharp() {
    for resolution in [33, 64] {
        let dc = worst_corner_distance("dual-contouring", resolution);
        let mc = worst_corner_distance("marching-cubes", resolution);
        let sn = worst_corner_distance("surface-nets", resolution);
        assert!(dc < 0.05, "dual contouring misses a corner by {dc} spacings at {resolution}");
        assert!(mc > 4.0 * dc && sn > 4.0 * dc, "at {resolution}: MC {mc}, SN {sn}, DC {dc} spacings");
    }
}

#[test]
fn smooth_closed_fields_are_closed_and_manifold() {
    for name in ["sphere", "torus", "csg", "thin"] {
        let f = fields::builtin(name, Default::default()).unwrap();
        let s = Samples::sample_cubic(f.clone(), Grid::covering(&f.domain(), 48).unwrap(), 0.0).unwrap();
        let mut out = Extraction::default();
        extractors::by_name("dual-contouring").unwrap().extract(&s, &mut out).unwrap();
        assert_closed_manifold(&out.surface, name);
    }
}

/// Raw samples (a file, edited terrain) carry no field: the Hermite normals come from each cell's
/// trilinear interpolant, and the vertices still sit on the sphere.
#[test]
fn raw_values_without_a_field_take_normals_from_the_samples() {
    let f = isolab_tests::object_field("sphere");
    let sampled = Samples::sample_cubic(f.clone(), Grid::covering(&f.domain(), 48).unwrap(), 0.0).unwrap();
    let h = sampled.grid().spacing;
    let raw = Samples::from_values(*sampled.lattice(), sampled.values().to_vec(), 0.0).unwrap();
    let dc = extractors::by_name("dual-contouring").unwrap();
    let (mut with_field, mut from_samples) = (Extraction::default(), Extraction::default());
    dc.extract(&sampled, &mut with_field).unwrap();
    dc.extract(&raw, &mut from_samples).unwrap();
    assert_closed_manifold(&from_samples.surface, "sphere from raw samples");
    assert_eq!(from_samples.surface.triangles.len(), with_field.surface.triangles.len());
    let worst = |e: &Extraction| e.surface.positions.iter().map(|p| (p.length() - 0.4).abs() / h).fold(0.0f32, f32::max);
    let (a, b) = (worst(&with_field), worst(&from_samples));
    println!("worst distance / h: field normals {a}, sample normals {b}");
    assert!(b < 0.1, "raw-sample dual contouring within 0.1 h of the sphere, got {b}");
}
