//! `isosurface-stuffing` on real inputs: every built-in field and every shipped model, on both
//! lattices, keeps every tetrahedron positively oriented with its dihedral angles in the declared
//! interval; closed smooth objects give a closed boundary, wound outward, with its vertices on the
//! field's surface and the object's volume.

use isolab_algorithms::extractors::{self, isosurface_stuffing};
use isolab_algorithms::geometry::dihedral_angles;
use isolab_algorithms::{fields, Extraction, Grid, Lattice, Samples};
use isolab_metrics::topology;
use isolab_tests::{object_field, shipped_models};

fn stuff(name: &str, resolution: usize, bcc: bool) -> (Extraction, Samples<'static>) {
    stuff_at(name, resolution, bcc, 0.0)
}

fn stuff_at(name: &str, resolution: usize, bcc: bool, iso: f32) -> (Extraction, Samples<'static>) {
    let field = object_field(name);
    let grid = Grid::covering(&field.domain(), resolution).expect("grid");
    let lattice = if bcc { Lattice::Bcc(grid) } else { Lattice::Cubic(grid) };
    let samples = Samples::sample(field, lattice, iso).expect("samples");
    let mut out = Extraction::default();
    extractors::by_name("isosurface-stuffing").expect("registered").extract(&samples, &mut out).expect("extraction");
    (out, samples)
}

/// Every tetrahedron positive, every angle within the declared interval; returns the volume.
fn check_quality(out: &Extraction, what: &str) -> f64 {
    let interval = isosurface_stuffing::INFO.guarantees.dihedral.expect("declared");
    let t = &out.volume;
    assert!(!t.tetrahedra.is_empty(), "{what}: no tetrahedra");
    let mut volume = 0.0;
    for tet in &t.tetrahedra {
        let p = tet.map(|i| t.positions[i as usize]);
        let [a, b, c, d] = p.map(|x| x.as_dvec3());
        let v = (b - a).dot((c - a).cross(d - a)) / 6.0;
        assert!(v > 0.0, "{what}: inverted {p:?}");
        volume += v;
        for angle in dihedral_angles(p) {
            assert!(interval.contains(angle), "{what}: {angle:.3}° outside {interval:?}");
        }
    }
    volume
}

#[test]
fn every_built_in_field_keeps_the_interval() {
    for info in fields::registry() {
        for bcc in [false, true] {
            let what = format!("{} ({})", info.name, if bcc { "bcc" } else { "cubic" });
            let (out, _) = stuff(info.name, 40, bcc);
            check_quality(&out, &what);
        }
    }
}

#[test]
fn closed_objects_give_closed_outward_boundaries_on_their_surface() {
    let models = shipped_models();
    let closed: Vec<&str> = ["sphere", "torus", "asteroid"].into_iter().chain(models.iter().map(String::as_str)).collect();
    for name in closed {
        let (out, samples) = stuff(name, 48, false);
        let what = name.to_owned();
        let volume = check_quality(&out, &what);
        let t = topology(&out.surface);
        assert!(t.closed, "{what}: boundary not closed: {t:?}");
        assert_eq!(t.misoriented_edges, 0, "{what}: boundary not consistently wound");
        // The boundary encloses the tetrahedra's volume (so it faces out).
        let enclosed: f64 = out
            .surface
            .triangles
            .iter()
            .map(|tri| {
                let [a, b, c] = tri.map(|i| out.surface.positions[i as usize].as_dvec3());
                a.dot(b.cross(c)) / 6.0
            })
            .sum();
        assert!(
            (enclosed - volume).abs() < 1e-4 * volume.abs().max(1e-9),
            "{what}: boundary encloses {enclosed}, tetrahedra {volume}"
        );
        // Boundary vertices on the field's surface (cut points refined on the field, warped
        // vertices moved onto them), where the field is continuous: an open model's sign flips
        // across its holes (it has no Lipschitz bound), where no root lies.
        let field = samples.field().expect("a field");
        if field.lipschitz().is_none() {
            continue;
        }
        let h = samples.grid().spacing;
        let far = out.surface.positions.iter().map(|&p| field.value(p).abs()).fold(0.0f32, f32::max);
        assert!(far < 1e-3 * h, "{what}: a boundary vertex {far} from the surface (h = {h})");
    }
}

#[test]
fn the_sphere_volume_converges() {
    let exact = 4.0 / 3.0 * std::f64::consts::PI * 0.4f64.powi(3);
    let errors: Vec<f64> = [16, 32, 64]
        .iter()
        .map(|&n| {
            let (out, _) = stuff("sphere", n, false);
            (check_quality(&out, "sphere") - exact).abs() / exact
        })
        .collect();
    // Faces are chords: second order, so each halving of h cuts the error about four times.
    assert!(errors[1] < errors[0] / 2.5 && errors[2] < errors[1] / 2.5, "{errors:?}");
}

#[test]
fn a_mesh_field_is_stuffed_at_a_nonzero_level() {
    // Corners and cube centres are sampled for the same iso-value, and the boundary lies on the
    // inset surface (an offset outward would leave the domain).
    let iso = -0.12;
    let (out, samples) = stuff_at("spot.obj", 32, false, iso);
    check_quality(&out, "spot offset");
    let field = samples.field().expect("a field");
    let h = samples.grid().spacing;
    let far = out.surface.positions.iter().map(|&p| (field.value(p) - iso).abs()).fold(0.0f32, f32::max);
    assert!(far < 1e-3 * h, "a boundary vertex {far} off the level (h = {h})");
}

/// A real binary segmentation: the MNI152 brain mask as nilearn makes it (99 x 117 x 95 voxels of
/// 2 mm, `tests/reference/volumes/README.md`), read from its NIfTI file by the pipeline and meshed
/// on its own voxel grid at 0.5, and the T1 template it comes from at two levels (a noisy scan):
/// every tetrahedron positive and inside the declared interval in world coordinates, the boundary
/// closed and consistently wound, enclosing the tetrahedra's volume, which is the mask's voxel
/// volume within 1% (a binary mask's cut points sit at mid-edge, so the boundary is a
/// chamfered voxel surface).
#[test]
fn the_mni_brain_mask_and_its_scan_keep_the_interval() {
    use isolab_pipeline::{run, RunConfig};
    let volumes = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/reference/volumes");
    let cases = [("mni-brain-mask.nii.gz", 0.5), ("mni-small.nii.gz", 60.5), ("mni-small.nii.gz", 120.5)];
    for (file, level) in cases {
        let path = volumes.join(file);
        let mut config = RunConfig::new("isosurface-stuffing", &path.to_string_lossy(), 64);
        config.iso = Some(level);
        let out = run(&config).unwrap_or_else(|e| panic!("{file}: {e}"));
        let what = format!("{file} at {level}");
        let volume = check_quality(&out.extraction, &what);
        let t = topology(&out.extraction.surface);
        assert!(t.closed, "{what}: boundary not closed: {t:?}");
        assert_eq!(t.misoriented_edges, 0, "{what}: boundary not consistently wound");
        let enclosed: f64 = out
            .extraction
            .surface
            .triangles
            .iter()
            .map(|tri| {
                let [a, b, c] = tri.map(|i| out.extraction.surface.positions[i as usize].as_dvec3());
                a.dot(b.cross(c)) / 6.0
            })
            .sum();
        assert!((enclosed - volume).abs() < 1e-4 * volume, "{what}: boundary encloses {enclosed}, tetrahedra {volume}");
        if file == "mni-brain-mask.nii.gz" {
            // 235,375 voxels of 8 mm³ inside (nilearn's count, the fixture's README).
            let voxels = 235_375.0 * 8.0;
            assert!((volume / voxels - 1.0).abs() < 0.01, "{what}: {volume} mm³ against the mask's {voxels} mm³");
        }
    }
}
