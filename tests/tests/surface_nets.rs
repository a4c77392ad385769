//! Surface nets: topology on every cube pattern and on random fields, the cell constraint of every
//! smoothing, quality and shrinkage on the sphere, and the closed built-in fields.

use isolab_algorithms::extractors::surface_nets::{Smoothing, SnOptions, SurfaceNets};
use isolab_algorithms::{fields, Grid, Samples};
use isolab_tests::{
    assert_closed_manifold, assert_closed_manifold_for, assert_closed_manifold_with, blob_field, extract, Orientation,
};
use proptest::prelude::*;

const ALL: [Smoothing; 4] = [Smoothing::None, Smoothing::Elastic, Smoothing::Spring, Smoothing::Implicit];

fn nets(smoothing: Smoothing) -> SurfaceNets {
    SurfaceNets::new(SnOptions { smoothing, ..Default::default() })
}

fn embedded_case(case: u8) -> Samples<'static> {
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

/// Every sign pattern of two cells sharing a face (12 samples), inside an outside border: the
/// ring faces ([`isolab_algorithms::tables::marching_cubes::RING_FACES`]) of both cells are the
/// case a single vertex per piece would pinch.
#[test]
fn all_two_cell_patterns_give_closed_manifold_nets() {
    for pattern in 0..1u32 << 12 {
        let s = isolab_tests::grid_samples([5, 4, 4], |x, y, z| {
            let inner = (1..=3).contains(&x) && (1..=2).contains(&y) && (1..=2).contains(&z);
            if !inner {
                return 1.0;
            }
            let bit = (x - 1) + 3 * ((y - 1) + 2 * (z - 1));
            if pattern >> bit & 1 == 1 {
                -1.0 - 0.03 * bit as f32
            } else {
                1.0 + 0.05 * bit as f32
            }
        });
        for smoothing in [Smoothing::None, Smoothing::Elastic] {
            let out = extract(&nets(smoothing), &s);
            assert_closed_manifold_for(&s, &out.surface, &format!("two-cell pattern {pattern:#x} {smoothing:?}"));
        }
    }
}

/// The configuration the random-field test found (a passage across a face, wrapped by one piece
/// of surface in each cell): the face's inside corners are joined and the net stays manifold.
#[test]
fn a_passage_wrapped_on_both_sides_of_a_face_stays_manifold() {
    let blobs = [
        (0.568_652_2, 0.898_271_6, 0.480_821, 0.065_573_76),
        (0.519_932_7, 0.688_283_6, 0.794_322_8, 0.306_671_2),
        (0.552_438_6, 0.897_726_2, 0.302_814_75, 0.129_707_77),
        (0.216_456_12, 0.700_530_65, 0.315_334_17, 0.384_558_32),
    ];
    let s = blob_field(7, &blobs, 0.870_097);
    for smoothing in ALL {
        let out = extract(&nets(smoothing), &s);
        let orientation = match smoothing {
            Smoothing::None | Smoothing::Elastic => Orientation::Outward,
            Smoothing::Spring | Smoothing::Implicit => Orientation::Consistent,
        };
        assert_closed_manifold_with(&out.surface, &format!("{smoothing:?}"), orientation);
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
        assert_closed_manifold_for(&s, &out.surface, "blob field");
    }

    #[test]
    fn random_sign_patterns_give_closed_manifold_nets(values in prop::collection::vec(-1.0f32..1.0, 6 * 6 * 6)) {
        let s = isolab_tests::grid_samples([8, 8, 8], |x, y, z| {
            if x == 0 || y == 0 || z == 0 || x == 7 || y == 7 || z == 7 { 1.0 } else { values[(x - 1) + 6 * ((y - 1) + 6 * (z - 1))] }
        });
        let out = extract(&nets(Smoothing::None), &s);
        assert_closed_manifold_for(&s, &out.surface, "white noise");
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
    use isolab_algorithms::extractors::dual_contouring::{DcOptions, DualContouring};
    use isolab_algorithms::sweep::slabs::Parallelism;
    use isolab_algorithms::{Extraction, Extractor};
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
    let other = Samples::sample_cubic(fields::builtin("gyroid", Default::default()).unwrap(), grid, 0.0).unwrap();
    let with = |parallelism: Parallelism| -> Vec<(String, Box<dyn Extractor>)> {
        let mut all: Vec<(String, Box<dyn Extractor>)> = [Smoothing::None, Smoothing::Elastic]
            .map(|smoothing| {
                let e: Box<dyn Extractor> =
                    Box::new(SurfaceNets::new(SnOptions { smoothing, parallelism, ..Default::default() }));
                (format!("surface nets, {smoothing:?}"), e)
            })
            .into_iter()
            .collect();
        all.push(("dual contouring".into(), Box::new(DualContouring::new(DcOptions { parallelism, ..Default::default() }))));
        all
    };
    for ((what, serial), (_, parallel)) in with(Parallelism::Serial).into_iter().zip(with(Parallelism::Rayon)) {
        let expected = extract(serial.as_ref(), &s).surface;
        let t = isolab_metrics::topology(&expected);
        assert!(t.closed && t.misoriented_edges == 0, "{what}: {t:?}");
        // One-shot (a fresh output: counted, then written in place without smoothing) and steady
        // state (an output kept from another grid: slab buffers joined), from a thread outside
        // any pool and inside pools of two and three threads.
        let one_shot = || {
            let mut out = Extraction::default();
            parallel.extract(&s, &mut out).unwrap();
            out.surface
        };
        let steady = || {
            let mut out = Extraction::default();
            parallel.extract(&other, &mut out).unwrap();
            parallel.extract(&s, &mut out).unwrap();
            out.surface
        };
        for threads in [0, 2, 3] {
            let (a, b) = if threads == 0 {
                (one_shot(), steady())
            } else {
                let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
                pool.install(|| (one_shot(), steady()))
            };
            assert!(a == expected, "{what}, {threads} threads (0: global pool), one-shot: slabs must join to the very same mesh");
            assert!(b == expected, "{what}, {threads} threads (0: global pool), steady: slabs must join to the very same mesh");
        }
    }
}
