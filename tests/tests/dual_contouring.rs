//! Dual contouring: sharp corners of `csg` reproduced (marching cubes and surface nets cut them),
//! closed and manifold on the smooth closed fields, and a clear error without a field.

use isolab_algorithms::{extractors, fields, Extraction, Grid, Samples};
use isolab_tests::{assert_closed_manifold, assert_closed_manifold_for};

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

#[test]
fn all_256_cube_patterns_give_closed_manifold_outward_meshes() {
    let dc = extractors::by_name("dual-contouring").unwrap();
    let mut intersecting = Vec::new();
    for case in 0..=255u8 {
        for variant in 0..3 {
            let s = isolab_tests::varied_case(case, variant);
            let mut out = Extraction::default();
            dc.extract(&s, &mut out).unwrap();
            assert_closed_manifold_for(&s, &out.surface, &format!("case {case} variant {variant}"));
            let x = isolab_metrics::self_intersections(&out.surface).count;
            if x > 0 {
                intersecting.push((case, variant, x));
            }
        }
    }
    // Dual contouring does not promise freedom from self-intersections (its registry entry says
    // so): vertices placed in the 27 cells around one cube pattern fold quads over each other on
    // some patterns. The count is exact, as measured, so a change that adds folds or removes
    // some fails here until it is updated; `manifold-dual-contouring` has none on these cases
    // (tests/tests/manifold_dual_contouring.rs).
    let pairs: usize = intersecting.iter().map(|c| c.2).sum();
    assert_eq!((intersecting.len(), pairs), (85, 1211), "{intersecting:?}");
}

/// Vertices at features fold quads: split along the shorter diagonal, dual contouring of the
/// cheburashka and the teapot at 64 self-intersected. Splitting a folded quad along its other
/// diagonal leaves every shipped model without a self-intersecting pair.
#[test]
fn no_shipped_model_self_intersects_at_64() {
    let dc = extractors::by_name("dual-contouring").unwrap();
    let names = isolab_tests::shipped_models();
    assert!(names.len() >= 6, "{names:?}");
    for name in &names {
        let field = isolab_tests::object_field(name);
        let grid = isolab_algorithms::Grid::covering(&field.domain(), 64).unwrap();
        let s = Samples::sample_cubic(field, grid, 0.0).unwrap();
        let mut out = Extraction::default();
        dc.extract(&s, &mut out).unwrap();
        assert_closed_manifold(&out.surface, name);
        assert_eq!(isolab_metrics::self_intersections(&out.surface).count, 0, "{name}");
    }
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig { cases: 200, failure_persistence: None, ..Default::default() })]

    #[test]
    fn random_smooth_fields_give_closed_manifold_outward_meshes(
        n in 5usize..16,
        blobs in proptest::collection::vec((0.1f32..0.9, 0.1f32..0.9, 0.1f32..0.9, 0.05f32..0.4), 1..6),
        threshold in 0.2f32..0.9,
    ) {
        let s = isolab_tests::blob_field(n, &blobs, threshold);
        let mut out = Extraction::default();
        extractors::by_name("dual-contouring").unwrap().extract(&s, &mut out).unwrap();
        assert_closed_manifold_for(&s, &out.surface, "blob field");
    }
}
