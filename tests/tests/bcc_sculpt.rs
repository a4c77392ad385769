//! `bcc-sculpt` (Stuart et al. 2013): the acceptance checks of its issue on the shipped models,
//! and enclosure, orientation and bomb-freedom over random surfaces.

use isolab_algorithms::bvh::TriangleBvh;
use isolab_algorithms::extractors::bcc_sculpt::{sculpt_surface, SculptOptions, Sculpted};
use isolab_algorithms::extractors::{self, MarchingCubes};
use isolab_algorithms::{Extraction, Extractor, Options, TetMesh};
use isolab_metrics::tet_quality::tet_quality;
use isolab_metrics::volume_mesh::{encloses, volume_metrics};
use isolab_tests::{assert_closed_manifold, blob_field, object_field};
use proptest::prelude::*;

fn sculpt_model(
    name: &str,
    cells: usize,
    ratio: f32,
    perturbations: usize,
) -> (Sculpted, std::sync::Arc<dyn isolab_algorithms::Field>) {
    let field = object_field(name);
    let surface = field.surface_mesh().expect("a mesh field");
    let options = SculptOptions { cells, offset_ratio: ratio, perturbations, ..Default::default() };
    (sculpt_surface(surface, name, &options).expect("sculpts"), field)
}

fn assert_valid_volume(volume: &TetMesh, what: &str) {
    let q = tet_quality(volume);
    assert_eq!(q.inverted, 0, "{what}: inverted tetrahedra");
    assert!(q.dihedral_deg.min > 0.0, "{what}");
}

#[test]
fn every_closed_model_is_enclosed_with_good_angles_at_ratio_0_6() {
    for name in ["spot.obj", "fandisk.obj", "rocker-arm.obj", "cheburashka.obj"] {
        let (result, field) = sculpt_model(name, 8, 0.6, 1);
        let what = format!("{name} at h = longest / 8, ratio 0.6");
        assert_valid_volume(&result.volume, &what);
        assert_eq!(result.report.bombs_left, 0, "{what}");
        assert_closed_manifold(&result.boundary, &what);
        let m =
            volume_metrics(&result.volume, &result.boundary, Some((field.as_ref(), 0.0)), Some(result.report.converged)).unwrap();
        assert_eq!(m.encloses, Some(true), "{what}: a vertex of S is outside");
        assert!(m.dihedral_deg.min >= 20.0 - 1e-9, "{what}: min dihedral {}", m.dihedral_deg.min);
        let ratio = m.volume_ratio.unwrap();
        assert!((1.0..3.0).contains(&ratio), "{what}: volume ratio {ratio}");
        // Boundary vertices are outside S (never pushed through it).
        let s = field.surface_mesh().unwrap();
        for &p in &result.boundary.positions {
            assert!(s.winding_number(p) < 0.5, "{what}: boundary vertex {p} inside S");
        }
    }
}

#[test]
fn the_paper_update_without_the_quality_floor_still_encloses() {
    let field = object_field("spot.obj");
    let options = SculptOptions { cells: 8, offset_ratio: 0.8, quality_floor: 0.0, ..Default::default() };
    let result = sculpt_surface(field.surface_mesh().unwrap(), "spot", &options).unwrap();
    assert_valid_volume(&result.volume, "spot, quality-floor 0");
    assert!(encloses(&result.boundary, field.surface_mesh().unwrap()));
}

#[test]
fn rocker_arm_keeps_its_hole_at_the_finest_spacing() {
    let (result, _) = sculpt_model("rocker-arm.obj", 14, 0.6, 1);
    let t = assert_closed_manifold(&result.boundary, "rocker-arm at h = longest / 14");
    assert_eq!(t.genus, Some(1), "the through-hole is lost: {t:?}");
}

#[test]
fn perturbations_keep_the_best_attempt_and_are_seeded() {
    let a = sculpt_model("cheburashka.obj", 8, 0.6, 3).0;
    let b = sculpt_model("cheburashka.obj", 8, 0.6, 3).0;
    assert_eq!(a.report.attempts_run, 3);
    assert_eq!(a.report.attempt, b.report.attempt, "seeded: the same attempt wins");
    assert!(a.volume == b.volume && a.boundary == b.boundary, "seeded: the same tetrahedra and boundary, bit for bit");
    let single = sculpt_model("cheburashka.obj", 8, 0.6, 1).0;
    let key = |s: &Sculpted| (s.report.converged, s.report.dihedral_deg[0]);
    assert!(key(&a) >= key(&single), "the best of three is at least the unperturbed one");
}

#[test]
fn an_open_input_gives_a_defined_result_and_a_warning() {
    let field = object_field("teapot.obj");
    let samples = isolab_algorithms::Samples::sample(
        field.clone(),
        isolab_algorithms::Lattice::Cubic(isolab_algorithms::Grid::covering(&field.domain(), 8).unwrap()),
        0.0,
    )
    .unwrap();
    let mut o = Options::new();
    o.set("cells", "8");
    let sculpt = extractors::build("bcc-sculpt", &o).unwrap().unwrap();
    let mut out = Extraction::default();
    sculpt.extract(&samples, &mut out).unwrap();
    assert!(out.stats.warnings.iter().any(|w| w.contains("teapot") && w.contains("not closed")), "{:?}", out.stats.warnings);
    assert_valid_volume(&out.volume, "teapot");
    assert_closed_manifold(&out.surface, "teapot boundary");
    assert_eq!(out.stats.tetrahedra, out.volume.tetrahedra.len());
    assert!(out.stats.converged.is_some());
}

fn mc_surface(samples: &isolab_algorithms::Samples) -> TriangleBvh {
    let mut e = Extraction::default();
    MarchingCubes::default().extract(samples, &mut e).unwrap();
    let p = &e.surface.positions;
    TriangleBvh::new(e.surface.triangles.iter().map(|t| t.map(|i| p[i as usize])).collect())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 12, ..ProptestConfig::default() })]

    /// Random blobby surfaces: the result encloses S, has no inverted tetrahedron and no bomb, and
    /// its boundary is closed and outward.
    #[test]
    fn random_surfaces_are_enclosed(
        blobs in prop::collection::vec((0.25f32..0.75, 0.25f32..0.75, 0.25f32..0.75, 0.12f32..0.3), 1..5),
        cells in 5usize..9,
        ratio in 0.3f32..0.9,
        seed in 0u64..1000,
    ) {
        let samples = blob_field(18, &blobs, 0.6);
        let surface = mc_surface(&samples);
        prop_assume!(surface.len() > 50);
        let options = SculptOptions { cells, offset_ratio: ratio, perturbations: 2, seed, ..Default::default() };
        let result = sculpt_surface(&surface, "blobs", &options).unwrap();
        prop_assert_eq!(result.report.bombs_left, 0);
        prop_assert_eq!(tet_quality(&result.volume).inverted, 0);
        prop_assert!(encloses(&result.boundary, &surface), "a vertex of S escaped: {:?}", result.report);
        let t = isolab_metrics::topology(&result.boundary);
        prop_assert!(t.closed && t.edge_manifold && t.vertex_manifold && t.outward, "{:?}", t);
    }
}

#[test]
fn bcc_sculpt_is_registered_and_refuses_bad_options() {
    assert!(extractors::INFOS.iter().any(|i| i.name == "bcc-sculpt"));
    let mut o = Options::new();
    o.set("spacing", "-1");
    assert!(extractors::build("bcc-sculpt", &o).err().unwrap().to_string().contains("spacing"));
}

#[test]
fn a_time_budget_returns_the_best_mesh_so_far() {
    let field = object_field("fandisk.obj");
    let options = SculptOptions {
        cells: 10,
        offset_ratio: 0.2,
        perturbations: 50,
        budget: Some(std::time::Duration::from_millis(1)),
        ..Default::default()
    };
    let result = sculpt_surface(field.surface_mesh().unwrap(), "fandisk", &options).unwrap();
    assert!(result.report.attempts_run >= 1 && result.report.attempts_run < 50, "{:?}", result.report);
    assert!(!result.report.converged, "ratio 0.2 cannot converge in 1 ms");
    assert_valid_volume(&result.volume, "fandisk within a budget");
    assert!(encloses(&result.boundary, field.surface_mesh().unwrap()));
}
