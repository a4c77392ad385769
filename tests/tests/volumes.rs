//! Bring your own data: volume files in every format we read give the mesh scikit-image gives
//! (the goldens of `tests/reference/volumes.py`), every surface extractor meshes a real scan as
//! its declared guarantees say (closed, outward), grids round-trip through `--samples-out`, and mesh inputs give the same
//! field whatever their format and orientation.

use glam::Vec3;
use isolab_algorithms::{extractors, TriMesh};
use isolab_io::volume::Inside;
use isolab_io::{self as io, MeshExtras};
use isolab_pipeline::{run, OutputSpace, RunConfig, VolumeGrid};
use serde_json::Value;
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn fixture(name: &str) -> String {
    root().join("tests/reference/volumes").join(name).to_string_lossy().into_owned()
}

fn golden() -> Value {
    serde_json::from_str(&std::fs::read_to_string(root().join("tests/reference/golden/volumes.json")).unwrap()).unwrap()
}

/// Vertices of `ours` with no vertex of `theirs` within `tol`, and the other way round, and the
/// largest nearest distance: a sort along x and a window search.
fn unmatched(ours: &[Vec3], theirs: &[Vec3], tol: f32) -> (usize, f32) {
    let one_way = |a: &[Vec3], b: &[Vec3]| {
        let mut sorted: Vec<Vec3> = b.to_vec();
        sorted.sort_by(|p, q| p.x.total_cmp(&q.x));
        let mut missing = 0;
        let mut worst = 0.0f32;
        for p in a {
            let from = sorted.partition_point(|q| q.x < p.x - tol);
            let nearest =
                sorted[from..].iter().take_while(|q| q.x <= p.x + tol).map(|q| q.distance(*p)).fold(f32::INFINITY, f32::min);
            if nearest > tol {
                missing += 1;
            } else {
                worst = worst.max(nearest);
            }
        }
        (missing, worst)
    };
    let (m1, w1) = one_way(ours, theirs);
    let (m2, w2) = one_way(theirs, ours);
    (m1 + m2, w1.max(w2))
}

fn scan_config(algorithm: &str, file: &str, level: f32) -> RunConfig {
    let mut config = RunConfig::new(algorithm, &fixture(file), 64);
    config.iso = Some(level);
    config
}

/// The equivalence: `marching-cubes --set on-iso=exact` on each copy (NIfTI-1 sform and
/// qform, NIfTI-2, NRRD attached and detached, MetaImage) has scikit-image's vertex set, mapped
/// through the file's affine, within float32 rounding, and as many triangles as VTK's flying
/// edges and scikit-image's Lorensen table make of the same array (the live check compares the
/// polygons cell by cell); closed and outward despite the affine's negative determinant.
#[test]
fn marching_cubes_on_every_volume_copy_matches_scikit_image_in_world_coordinates() {
    let g = golden();
    let level = g["level"].as_f64().unwrap() as f32;
    let bytes = std::fs::read(root().join(g["vertex_file"].as_str().unwrap())).unwrap();
    let reference: Vec<Vec3> = bytes
        .chunks_exact(12)
        .map(|c| Vec3::from_array(std::array::from_fn(|k| f32::from_le_bytes(c[4 * k..4 * k + 4].try_into().unwrap()))))
        .collect();
    assert_eq!(reference.len() as u64, g["vertices"].as_u64().unwrap());
    let files = g["files"].as_object().unwrap();
    assert_eq!(files.len(), 6);
    for (name, entry) in files {
        let mut config = scan_config("marching-cubes", name, level);
        config.options.set("on-iso", "exact");
        let out = run(&config).unwrap();
        let mesh = &out.extraction.surface;
        let tol = entry["tolerance_mm"].as_f64().unwrap() as f32;
        let (missing, worst) = unmatched(&mesh.positions, &reference, tol);
        assert_eq!(missing, 0, "{name}: {missing} vertices unmatched within {tol} mm");
        assert!(worst < 1e-4, "{name}: worst distance {worst} mm, float32 rounding is about 2e-5");
        // Tables differ in ambiguous cells: ours, like Lorensen's and VTK's flying edges, keeps
        // the bright corners apart; Lewiner's follows the trilinear interpolant.
        let by_library = &g["triangles_by_library"];
        assert_eq!(by_library["vtkFlyingEdges3D"], by_library["skimage-lorensen"]);
        assert_eq!(mesh.triangles.len() as u64, by_library["vtkFlyingEdges3D"].as_u64().unwrap(), "{name}: triangles");
        let m = &out.report.metrics.as_ref().unwrap().topology;
        assert!(m.closed && m.outward && m.edge_manifold && m.vertex_manifold, "{name}: {m:?}");
        assert_eq!(out.report.inside, Inside::Above, "{name}: scans default to inside above");
    }
}

#[test]
fn every_surface_extractor_meshes_a_scan_as_its_guarantees_declare() {
    for info in extractors::INFOS {
        let extractor = extractors::by_name(info.name).unwrap();
        if extractor.produces_volume() {
            continue;
        }
        let out = run(&scan_config(info.name, "mni-small.nii.gz", 60.5)).unwrap();
        let t = &out.report.metrics.as_ref().unwrap().topology;
        assert!(
            out.extraction.surface.triangles.len() > 3000,
            "{}: {} triangles",
            info.name,
            out.extraction.surface.triangles.len()
        );
        // What the extractor declares, held on a real scan (the scan's surface stays inside).
        let g = info.guarantees;
        assert!(!g.closed || t.closed, "{} declares closed: {t:?}", info.name);
        assert!(!g.outward || (t.oriented && t.outward), "{} declares outward: {t:?}", info.name);
        assert!(out.report.warnings.is_empty(), "{}: {:?}", info.name, out.report.warnings);
    }
}

#[test]
fn volume_extractors_mesh_a_scan_too() {
    let mut config = scan_config("bcc-sculpt", "mni-small.nii.gz", 60.5);
    config.options.set("cells", "6");
    let out = run(&config).unwrap();
    assert!(!out.extraction.volume.tetrahedra.is_empty());
    assert!(out.report.metrics.as_ref().unwrap().topology.outward, "{:?}", out.report.metrics.as_ref().unwrap().topology);
}

#[test]
fn resampling_a_scan_keeps_its_shape_and_the_output_space_can_be_lps() {
    let native = run(&scan_config("marching-cubes", "mni-small.nii.gz", 60.5)).unwrap();
    let mut config = scan_config("marching-cubes", "mni-small.nii.gz", 60.5);
    config.volume_grid = VolumeGrid::Resampled;
    config.resolution = 96;
    let resampled = run(&config).unwrap();
    let (a, b) = (native.report.metrics.as_ref().unwrap().volume, resampled.report.metrics.as_ref().unwrap().volume);
    assert!(
        resampled.report.metrics.as_ref().unwrap().topology.outward,
        "{:?}",
        resampled.report.metrics.as_ref().unwrap().topology
    );
    assert!((a - b).abs() < 0.03 * a, "native volume {a} mm^3, resampled {b}");
    config.space = OutputSpace::Lps;
    config.volume_grid = VolumeGrid::Native;
    let lps = run(&config).unwrap();
    assert_eq!(lps.space_tag, Some("LPS"));
    for (p, q) in native.extraction.surface.positions.iter().zip(&lps.extraction.surface.positions) {
        assert!((Vec3::new(-p.x, -p.y, p.z) - *q).length() < 1e-4, "{p} {q}");
    }
    assert_eq!(native.extraction.surface.triangles, lps.extraction.surface.triangles);
}

#[test]
fn grids_round_trip_through_samples_out() {
    let dir = tempfile::tempdir().unwrap();
    for (field, algorithm) in [("torus".to_owned(), "marching-cubes"), (fixture("mni-small.nrrd"), "surface-nets")] {
        let mut config = RunConfig::new(algorithm, &field, 40);
        config.iso = (field != "torus").then_some(60.5);
        let first = run(&config).unwrap();
        let grid = dir.path().join("grid.raw");
        io::write_samples(&grid, first.samples.as_ref().unwrap(), first.samples_to_world.as_ref()).unwrap();
        let again = run(&RunConfig::new(algorithm, grid.to_str().unwrap(), 40)).unwrap();
        let (a, b) = (&first.extraction.surface, &again.extraction.surface);
        assert_eq!(a.triangles, b.triangles, "{field}");
        for (p, q) in a.positions.iter().zip(&b.positions) {
            assert!(p.distance(*q) <= 1e-5 * p.length().max(1.0), "{field}: {p} vs {q}");
        }
        assert_eq!(again.report.input.format, Some("isolab grid"));
    }
}

fn spot() -> TriMesh {
    io::read_mesh(&root().join("models/spot.obj")).unwrap()
}

fn soup_of(config: &RunConfig) -> (Vec<[Vec3; 3]>, Vec<String>) {
    let out = run(config).unwrap();
    (io::soup(&out.extraction.surface), out.report.warnings)
}

/// The "any format and orientation": the same triangles as OBJ, binary PLY, STL and
/// GLB, and wound inward, give the same marching cubes mesh; the inward one says so.
#[test]
fn mesh_inputs_give_the_same_field_in_any_format_and_orientation() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = spot();
    let (reference, warnings) = soup_of(&RunConfig::new("marching-cubes", &root().join("models/spot.obj").to_string_lossy(), 32));
    assert!(warnings.is_empty(), "{warnings:?}");
    let inward = TriMesh { triangles: mesh.triangles.iter().map(|&[a, b, c]| [a, c, b]).collect(), ..mesh.clone() };
    for (name, m) in [
        ("spot.ply", &mesh),
        ("spot.stl", &mesh),
        ("spot.glb", &mesh),
        ("spot-inward.ply", &inward),
        ("spot-inward.obj", &inward),
    ] {
        let path = dir.path().join(name);
        io::write_mesh_with(&path, m, MeshExtras::default()).unwrap();
        let (soup, warnings) = soup_of(&RunConfig::new("marching-cubes", path.to_str().unwrap(), 32));
        assert!(soup == reference, "{name}: the mesh differs from the OBJ's");
        let flipped = warnings.iter().any(|w| w.contains("faces inward"));
        assert_eq!(flipped, name.contains("inward"), "{name}: {warnings:?}");
    }
}

#[test]
fn an_iso_value_with_no_inside_is_a_warning_not_a_silent_empty_mesh() {
    for (iso, inside, needle) in
        [(5.0, None, "every sample"), (-5.0, None, "no sample"), (300.0, Some(Inside::Above), "no sample")]
    {
        let field = if inside.is_some() { fixture("mni-small.nii.gz") } else { "sphere".into() };
        let mut config = RunConfig::new("marching-cubes", &field, 16);
        config.iso = Some(iso);
        config.inside = inside;
        let out = run(&config).unwrap();
        assert!(out.extraction.surface.triangles.is_empty());
        assert!(out.report.warnings.iter().any(|w| w.contains(needle)), "{iso}: {:?}", out.report.warnings);
    }
}

/// Volume files are read in their stored type (uncompressed ones straight from the file into
/// that type, big-endian ones byte-swapped), and meshed on their own grid where their voxels lie:
/// the mesh is the one their float32 conversion gives, bit for bit.
#[test]
fn volume_files_are_read_in_their_stored_type_and_meshed_where_they_lie() {
    use isolab_algorithms::fields::Volume;
    use isolab_pipeline::{run_input, Input};
    // (file, the type its values are held in, whether read straight from the file): a scaled
    // NIfTI (slope and intercept) is held as the float32 it scales to.
    for (name, dtype, direct) in [
        ("mni-small.nhdr", "uint16", true),
        ("mni-small-qform.nii", "float32", false),
        ("mni-small.nrrd", "uint8", false),
        ("mni-small.mhd", "uint8", false),
    ] {
        let path = fixture(name);
        let file = io::volume::read_volume(Path::new(&path), Default::default()).unwrap();
        let stored = file.volume.values();
        assert_eq!(stored.dtype(), dtype, "{name}: the file stores {}", file.data_type);
        let straight = io::volume::read_stored(Path::new(&path), Default::default()).unwrap();
        assert_eq!(straight.is_some(), direct, "{name}: read straight from the file");
        let parsed = io::volume::read_volume_bytes(&std::fs::read(&path).unwrap(), Path::new(&path), Default::default()).unwrap();
        assert_eq!(parsed.volume.values(), stored, "{name}: the parser's values");
        // Meshed in place, and from the float32 conversion.
        let config = scan_config("marching-cubes", name, 60.0);
        let typed = run(&config).unwrap();
        let v = &file.volume;
        let floats = Volume::new(v.name.clone(), v.dims, v.values_f32().into_owned(), v.index_to_world).unwrap();
        let mut input = Input::from_volume(floats, file.format, "float32", file.inside);
        input.volume = Some(std::sync::Arc::new(io::volume::VolumeFile {
            volume: input.volume.as_ref().unwrap().volume.clone(),
            ..file.clone()
        }));
        let copied = run_input(&config, input).unwrap();
        let bits = |m: &TriMesh| m.positions.iter().map(|p| p.to_array().map(f32::to_bits)).collect::<Vec<_>>();
        assert!(typed.extraction.surface.triangles.len() > 100, "{name}");
        assert_eq!(typed.extraction.surface.triangles, copied.extraction.surface.triangles, "{name}");
        assert_eq!(bits(&typed.extraction.surface), bits(&copied.extraction.surface), "{name}");
        assert!(!typed.samples.as_ref().unwrap().was_converted(), "{name}: meshed where the voxels lie");
    }
}
