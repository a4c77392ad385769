//! Marching cubes: every cube sign pattern, random fields (property tests), serial against
//! parallel, and analytic invariants on the built-in fields and shipped models.

use isolab_algorithms::extractors::marching_cubes::{FaceResolution, MarchingCubes, McOptions, NormalSource};
use isolab_algorithms::sweep::slabs::Parallelism;
use isolab_algorithms::{fields, Extractor, Grid, Samples};
use isolab_pipeline::{run, RunConfig};
use isolab_tests::{assert_closed_manifold, assert_closed_manifold_for, blob_field, extract, grid_samples};
use proptest::prelude::*;

fn serial() -> MarchingCubes {
    MarchingCubes::new(McOptions { parallelism: Parallelism::Serial, ..Default::default() })
}

fn embedded_case(case: u8, magnitude: impl Fn(usize) -> f32) -> Samples<'static> {
    isolab_tests::embedded_case(case, |corner, inside| if inside { -magnitude(corner) } else { magnitude(corner) })
}

#[test]
fn all_256_cube_patterns_give_closed_manifold_outward_meshes() {
    for case in 0..=255u8 {
        for (variant, magnitude) in [(0, 1.0f32), (1, 0.1), (2, 7.0)] {
            let s = embedded_case(case, |c| if variant == 0 { 1.0 } else { magnitude * (1.0 + c as f32 * 0.13) });
            let out = extract(&serial(), &s);
            let t = assert_closed_manifold_for(&s, &out.surface, &format!("case {case} variant {variant}"));
            assert_eq!(out.surface.triangles.is_empty(), case == 0, "case {case}");
            if case != 0 {
                assert_eq!(t.components as u32, components_of_inside_corners(case), "case {case}");
            }
        }
    }
}

/// Inside corners of the block grouped by shared cube edges: with inside corners separated on
/// every face and the outside layer around the block, each group is one closed component.
fn components_of_inside_corners(case: u8) -> u32 {
    use isolab_algorithms::tables::marching_cubes::EDGES;
    let mut groups = petgraph::unionfind::UnionFind::<u8>::new(8);
    for &(a, b) in &EDGES {
        if case >> a & 1 == 1 && case >> b & 1 == 1 {
            groups.union(a, b);
        }
    }
    (0..8u8).filter(|&c| case >> c & 1 == 1 && groups.find(c) == c).count() as u32
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 1000, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn random_smooth_fields_give_closed_manifold_meshes(
        n in 5usize..18,
        blobs in prop::collection::vec((0.1f32..0.9, 0.1f32..0.9, 0.1f32..0.9, 0.05f32..0.4), 1..6),
        threshold in 0.2f32..0.9,
    ) {
        let s = blob_field(n, &blobs, threshold);
        let out = extract(&serial(), &s);
        assert_closed_manifold_for(&s, &out.surface, "blob field");
    }

    #[test]
    fn random_sign_patterns_give_closed_manifold_meshes(
        values in prop::collection::vec(-1.0f32..1.0, 6 * 6 * 6),
    ) {
        let s = grid_samples([8, 8, 8], |x, y, z| {
            if x == 0 || y == 0 || z == 0 || x == 7 || y == 7 || z == 7 { 1.0 } else { values[(x - 1) + 6 * ((y - 1) + 6 * (z - 1))] }
        });
        let out = extract(&serial(), &s);
        assert_closed_manifold_for(&s, &out.surface, "white noise");
    }
}

#[test]
fn parallel_slabs_join_without_cracks_on_white_noise() {
    // 64^3 cells of white noise: many slabs, every slab boundary crowded with crossings.
    let mut random = isolab_algorithms::random::Random::new(0x9e3779b97f4a7c15);
    let mut next = move || random.unit_f32() - 0.5;
    let n = 65;
    let noise: Vec<f32> = (0..n * n * n).map(|_| next()).collect();
    let s = grid_samples([n, n, n], |x, y, z| {
        if x == 0 || y == 0 || z == 0 || x == n - 1 || y == n - 1 || z == n - 1 {
            1.0
        } else {
            noise[x + n * (y + n * z)]
        }
    });
    let parallel = extract(&MarchingCubes::default(), &s);
    let single = extract(&serial(), &s);
    // The slabs count first and write straight into their pieces of the output: the very same
    // mesh as one sweep, vertex for vertex, for both face rules and with sample normals.
    assert_eq!(parallel.surface, single.surface);
    for faces in [FaceResolution::SeparateInside, FaceResolution::AsymptoticDecider, FaceResolution::Trilinear] {
        let options = |parallelism| McOptions { faces, parallelism, normals: NormalSource::SampleGradient, ..Default::default() };
        let a = extract(&MarchingCubes::new(options(Parallelism::Rayon)), &s);
        let b = extract(&MarchingCubes::new(options(Parallelism::Serial)), &s);
        assert!(!a.surface.normals.is_empty());
        assert_eq!(a.surface, b.surface, "{faces:?}");
        // The same again on a reused output (steady state: zero-filled, not freshly allocated).
        let mut again = a.clone();
        MarchingCubes::new(options(Parallelism::Rayon)).extract(&s, &mut again).unwrap();
        assert_eq!(again.surface, b.surface, "{faces:?} reused");
    }
    let tp = assert_closed_manifold(&parallel.surface, "parallel white noise");
    let ts = assert_closed_manifold(&single.surface, "serial white noise");
    assert_eq!((tp.euler, tp.components), (ts.euler, ts.components));
}

/// One extractor kept across calls on different grids, each into a fresh output (one-shot) or a
/// kept one (steady state), serial and on two and three threads: every mesh equals a fresh serial
/// extractor's. Scratch state (sign bits, index arrays) wrongly carried from an earlier grid
/// would show here.
#[test]
fn kept_extractors_mesh_each_new_grid_as_a_fresh_one_does() {
    let grids: Vec<Samples<'static>> = ["sphere", "gyroid", "asteroid", "sphere"]
        .iter()
        .zip([40, 57, 66, 71])
        .map(|(name, n)| {
            let f = fields::builtin(name, Default::default()).unwrap();
            Samples::sample_cubic(f.clone(), Grid::covering(&f.domain(), n).unwrap(), 0.0).unwrap()
        })
        .collect();
    let expected: Vec<_> = grids.iter().map(|s| extract(&serial(), s).surface).collect();
    for parallelism in [Parallelism::Serial, Parallelism::Rayon] {
        for threads in [0, 2, 3] {
            let run = || {
                let kept = MarchingCubes::new(McOptions { parallelism, ..Default::default() });
                let mut reused = isolab_algorithms::Extraction::default();
                for (s, want) in grids.iter().zip(&expected) {
                    let mut fresh = isolab_algorithms::Extraction::default();
                    kept.extract(s, &mut fresh).unwrap();
                    assert!(fresh.surface == *want, "{parallelism:?}, {threads} threads (0: global pool): one-shot differs");
                    kept.extract(s, &mut reused).unwrap();
                    assert!(reused.surface == *want, "{parallelism:?}, {threads} threads (0: global pool): steady state differs");
                }
            };
            if threads == 0 {
                run();
            } else {
                rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap().install(run);
            }
        }
    }
}

#[test]
fn sphere_at_64_is_closed_genus_0_with_volume_within_half_a_percent() {
    let report = run(&RunConfig::new("marching-cubes", "sphere", 64)).unwrap().report;
    let m = report.metrics.as_ref().unwrap();
    assert!(m.topology.is_watertight_manifold() && m.topology.outward);
    assert_eq!((m.topology.euler, m.topology.genus), (2, Some(0)));
    let exact = 4.0 / 3.0 * std::f64::consts::PI * 0.4f64.powi(3);
    assert!((m.volume / exact - 1.0).abs() < 0.005, "volume {} vs {exact}", m.volume);
    // Vertices lie on the sphere to within a small fraction of the spacing (1/63).
    let d = m.surface_distance.unwrap();
    assert!(d.max < 0.05 / 63.0, "max distance {}", d.max);
}

#[test]
fn sphere_volume_and_area_converge() {
    let field = fields::builtin("sphere", Default::default()).unwrap();
    let exact_v = field.analytic_volume(0.0).unwrap();
    let mut last = f64::INFINITY;
    for n in [16, 32, 64, 128] {
        let s = Samples::sample_cubic(field.clone(), Grid::covering(&field.domain(), n).unwrap(), 0.0).unwrap();
        let out = extract(&MarchingCubes::default(), &s);
        let err = (isolab_metrics::signed_volume(&out.surface) - exact_v).abs() / exact_v;
        assert!(err < last, "volume error did not shrink at {n}: {err} >= {last}");
        last = err;
    }
    assert!(last < 1e-3, "{last}");
}

#[test]
fn torus_has_euler_characteristic_0() {
    let m = run(&RunConfig::new("marching-cubes", "torus", 64)).unwrap().report.metrics.unwrap();
    assert!(m.topology.is_watertight_manifold());
    assert_eq!((m.topology.euler, m.topology.genus, m.topology.components), (0, Some(1), 1));
    let exact = 2.0 * std::f64::consts::PI.powi(2) * 0.3 * 0.12f64.powi(2);
    assert!((m.volume / exact - 1.0).abs() < 0.01, "{} vs {exact}", m.volume);
}

#[test]
fn closed_fields_are_watertight_and_open_ones_only_open_at_the_domain() {
    for name in ["asteroid", "csg", "thin"] {
        let out = run(&RunConfig::new("marching-cubes", name, 48)).unwrap();
        assert_closed_manifold(&out.extraction.surface, name);
    }
    // Thin: a tube, a sheet and two close sheets stay four separate closed components at 64.
    let thin = run(&RunConfig::new("marching-cubes", "thin", 64)).unwrap().report.metrics.unwrap();
    assert_eq!((thin.topology.components, thin.topology.euler), (4, 8));
    for name in ["gyroid", "terrain"] {
        let out = run(&RunConfig::new("marching-cubes", name, 40)).unwrap();
        let t = isolab_metrics::topology(&out.extraction.surface);
        assert!(t.edge_manifold && t.vertex_manifold && t.oriented, "{name}: {t:?}");
        let bounds = isolab_algorithms::Grid::covering(
            &out.extraction.surface.positions.iter().fold(isolab_algorithms::Aabb::empty(), |mut b, p| {
                b.grow(*p);
                b
            }),
            2,
        )
        .unwrap()
        .bounds();
        // Every boundary edge lies on the domain's boundary.
        let on_border =
            |p: glam::Vec3| (p - bounds.min).abs().min_element() < 1e-5 || (p - bounds.max).abs().min_element() < 1e-5;
        for [a, b] in &t.offenders.boundary_edges {
            let pa = out.extraction.surface.positions[*a as usize];
            let pb = out.extraction.surface.positions[*b as usize];
            assert!(on_border(pa) && on_border(pb), "{name}: interior boundary edge {pa} {pb}");
        }
    }
}

#[test]
fn samples_exactly_at_the_iso_value_give_no_zero_area_triangles_or_touching() {
    use isolab_algorithms::extractors::marching_cubes::OnIsoSamples;
    // The gyroid is exactly zero on whole planes of grid points.
    let field = fields::builtin("gyroid", Default::default()).unwrap();
    let s = Samples::sample_cubic(field.clone(), Grid::covering(&field.domain(), 33).unwrap(), 0.0).unwrap();
    assert!(s.values().iter().filter(|&&v| v == 0.0).count() > 100, "the test needs samples exactly at the iso-value");
    let separate = extract(&MarchingCubes::default(), &s);
    assert_eq!(isolab_metrics::triangle_quality(&separate.surface).degenerate_triangles, 0);
    assert_eq!(isolab_metrics::self_intersections(&separate.surface).count, 0);
    let exact = extract(&MarchingCubes::new(McOptions { on_iso: OnIsoSamples::Exact, ..Default::default() }), &s);
    assert!(isolab_metrics::triangle_quality(&exact.surface).degenerate_triangles > 0, "exact interpolation shows the problem");
    assert_eq!(exact.surface.triangles.len(), separate.surface.triangles.len());
    // Separated vertices stay within 1e-4 of the spacing of the exact ones.
    let spacing = s.grid().spacing;
    for (a, b) in exact.surface.positions.iter().zip(&separate.surface.positions) {
        assert!(a.distance(*b) <= 1.01e-4 * spacing, "{a} {b}");
    }
}

#[test]
fn marching_cubes_output_does_not_self_intersect_on_the_builtin_fields() {
    for name in ["sphere", "torus", "gyroid", "asteroid", "terrain", "csg", "thin"] {
        let out = run(&RunConfig::new("marching-cubes", name, 40)).unwrap();
        let si = isolab_metrics::self_intersections(&out.extraction.surface);
        assert_eq!(si.count, 0, "{name}: {:?}", si.pairs);
    }
}

/// A fresh output over the memory limit fails before it is allocated, on one thread (from the
/// estimate of sampled layers) and on the parallel path (from the exact counts); the bytes it
/// names are close to what the mesh takes.
#[test]
fn an_output_over_the_memory_limit_fails_before_it_is_made() {
    use isolab_algorithms::extractors::marching_cubes::VertexValues;
    use isolab_algorithms::ExtractError;
    let f = fields::builtin("gyroid", Default::default()).unwrap();
    let samples = Samples::sample_cubic(f.clone(), Grid::covering(&f.domain(), 180).unwrap(), 0.0).unwrap();
    for parallelism in [Parallelism::Serial, Parallelism::Rayon] {
        let options = McOptions {
            parallelism,
            normals: NormalSource::SampleGradient,
            values: VertexValues::CellRange,
            ..Default::default()
        };
        let mut out = isolab_algorithms::Extraction::default();
        MarchingCubes::new(options).extract(&samples, &mut out).unwrap();
        let made = (out.surface.positions.len() * 28 + out.surface.triangles.len() * 12) as u64;
        let mc = MarchingCubes::new(options);
        let mut fresh = isolab_algorithms::Extraction { memory_limit: Some(made / 2), ..Default::default() };
        match mc.extract(&samples, &mut fresh) {
            Err(ExtractError::OverMemory { needed, limit, .. }) => {
                assert_eq!(limit, made / 2);
                assert!(needed.abs_diff(made) * 5 < made, "{parallelism:?}: needed {needed} for {made}");
            }
            other => panic!("{parallelism:?}: {other:?}"),
        }
        assert_eq!(fresh.surface.positions.capacity(), 0, "{parallelism:?}: nothing allocated");
        fresh.memory_limit = Some(2 * made);
        mc.extract(&samples, &mut fresh).unwrap();
        assert_eq!(fresh.surface.triangles.len(), out.surface.triangles.len());
    }
}
