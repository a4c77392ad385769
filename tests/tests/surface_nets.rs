//! Surface nets: topology on every cube pattern and on random fields, the cell constraint of every
//! smoothing, quality and shrinkage on the sphere, and the closed built-in fields.

use isolab_algorithms::extractors::surface_nets::{Smoothing, SnOptions, SurfaceNets};
use isolab_algorithms::{fields, Grid, Samples};
use isolab_tests::{assert_closed_manifold, assert_closed_manifold_with, blob_field, extract, Orientation};
use proptest::prelude::*;

const ALL: [Smoothing; 4] = [Smoothing::None, Smoothing::Elastic, Smoothing::Spring, Smoothing::Implicit];

fn nets(smoothing: Smoothing) -> SurfaceNets {
    SurfaceNets::new(SnOptions { smoothing, ..Default::default() })
}

fn embedded_case(case: u8) -> Samples {
    isolab_tests::embedded_case(
        case,
        |corner, inside| if inside { -1.0 - 0.1 * corner as f32 } else { 1.0 + 0.07 * corner as f32 },
    )
}

#[test]
fn all_256_cube_patterns_give_closed_manifold_nets() {
    // One-sample features are nets of 6 to 8 vertices; the spring and implicit smoothings may pull
    // them flat or inside out (the post's "folding"), though never out of their cells, so only
    // consistency is demanded of them here.
    for case in 1..=255u8 {
        for smoothing in ALL {
            let out = extract(&nets(smoothing), &embedded_case(case));
            let orientation = match smoothing {
                Smoothing::None | Smoothing::Elastic => Orientation::Outward,
                Smoothing::Spring | Smoothing::Implicit => Orientation::Consistent,
            };
            assert_closed_manifold_with(&out.surface, &format!("case {case} {smoothing:?}"), orientation);
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 500, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn random_smooth_fields_give_closed_manifold_nets(
        n in 5usize..16,
        blobs in prop::collection::vec((0.1f32..0.9, 0.1f32..0.9, 0.1f32..0.9, 0.05f32..0.4), 1..6),
        threshold in 0.2f32..0.9,
    ) {
        let s = blob_field(n, &blobs, threshold);
        let out = extract(&nets(Smoothing::Elastic), &s);
        assert_closed_manifold(&out.surface, "blob field");
    }
}

#[test]
fn closed_builtin_fields_give_closed_manifold_nets_with_every_smoothing() {
    for name in ["sphere", "torus", "asteroid", "csg", "thin"] {
        let f = fields::builtin(name, Default::default()).unwrap();
        let s = Samples::sample_cubic(f.clone(), Grid::covering(&f.domain(), 64).unwrap(), 0.0).unwrap();
        for smoothing in ALL {
            let out = extract(&nets(smoothing), &s);
            let t = assert_closed_manifold(&out.surface, &format!("{name} {smoothing:?}"));
            let expected_euler = match name {
                "torus" => 0,
                "thin" => 8,
                _ => 2,
            };
            assert_eq!(t.euler, expected_euler, "{name} {smoothing:?}");
        }
    }
}

#[test]
fn smoothing_improves_sphere_triangles_and_reports_shrinkage() {
    let f = fields::builtin("sphere", Default::default()).unwrap();
    let s = Samples::sample_cubic(f.clone(), Grid::covering(&f.domain(), 64).unwrap(), 0.0).unwrap();
    let exact = f.analytic_volume(0.0).unwrap();
    let plain = extract(&nets(Smoothing::None), &s);
    let plain_q = isolab_metrics::triangle_quality(&plain.surface).aspect_ratio.mean;
    for smoothing in [Smoothing::Elastic, Smoothing::Spring, Smoothing::Implicit] {
        let out = extract(&nets(smoothing), &s);
        let q = isolab_metrics::triangle_quality(&out.surface).aspect_ratio.mean;
        assert!(q <= 1.3 && q < plain_q, "{smoothing:?}: mean aspect {q} (unsmoothed {plain_q})");
        let shrink = isolab_metrics::signed_volume(&out.surface) / exact - 1.0;
        assert!(shrink < 0.0 && shrink > -0.05, "{smoothing:?}: volume change {shrink}");
    }
}

#[test]
fn normals_follow_the_field_gradient() {
    let f = fields::builtin("sphere", Default::default()).unwrap();
    let s = Samples::sample_cubic(f.clone(), Grid::covering(&f.domain(), 48).unwrap(), 0.0).unwrap();
    for smoothing in ALL {
        let out = extract(&nets(smoothing), &s);
        assert_eq!(out.surface.normals.len(), out.surface.positions.len());
        let d = isolab_metrics::normal_deviation(&out.surface, f.as_ref());
        assert!(d.mean_deg < 1.0 && d.max_deg < 5.0, "{smoothing:?}: {d:?}");
    }
}

#[test]
fn parallel_slabs_join_exactly_like_one_slab_on_a_rough_field() {
    use isolab_algorithms::extractors::marching_cubes::Parallelism;
    // Many slabs on a rough field: every slab boundary is crowded with quads.
    let f = fields::builtin("asteroid", Default::default()).unwrap();
    let grid = Grid::covering(&f.domain(), 97).unwrap();
    let mut s = Samples::sample_cubic(f.clone(), grid, 0.0).unwrap();
    let [nx, ny, nz] = grid.dims;
    for z in 0..nz {
        for y in 0..ny {
            for x in 0..nx {
                let ripple = 0.004 * ((x * 7 + y * 13 + z * 29) % 11) as f32 - 0.02;
                s.values_mut()[grid.index(x, y, z)] += ripple;
            }
        }
    }
    for smoothing in [Smoothing::None, Smoothing::Elastic] {
        let parallel = extract(&nets(smoothing), &s);
        let serial =
            extract(&SurfaceNets::new(SnOptions { smoothing, parallelism: Parallelism::Serial, ..Default::default() }), &s);
        assert_eq!(parallel.surface, serial.surface, "{smoothing:?}: slabs must join to the very same mesh");
        let t = isolab_metrics::topology(&parallel.surface);
        assert!(t.closed && t.misoriented_edges == 0, "{t:?}");
    }
}
