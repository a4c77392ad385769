//! `isolab extract -f FILE` with the user's own data, as a new user meets it: volume and mesh
//! files that work, and every bad one the "Bring your own data" issue lists (a message naming
//! the file and what is wrong, exit code 1, no panic, no output file left behind).

use isolab_io::volume::nifti::write::nifti1;

use crate::common::{isolab, stderr};
use std::path::Path;

fn fixture(name: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/reference/volumes").join(name).to_string_lossy().into_owned()
}

const ID: [[f32; 4]; 3] = [[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0]];

/// A 6^3 uint8 ball (inside above 100).
fn ball() -> Vec<u8> {
    (0..216)
        .map(|n| {
            let (x, y, z) = ((n % 6) as f32 - 2.5, ((n / 6) % 6) as f32 - 2.5, (n / 36) as f32 - 2.5);
            if x * x + y * y + z * z < 5.0 {
                200
            } else {
                0
            }
        })
        .collect()
}

fn gzip(bytes: &[u8]) -> Vec<u8> {
    use std::io::Write;
    let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
    gz.write_all(bytes).unwrap();
    gz.finish().unwrap()
}

/// Runs `extract -f file -o out.ply -m out.json`, expects exit 1 with every needle in the
/// message, and no output left in the directory but the input.
fn refused(dir: &Path, name: &str, bytes: &[u8], extra: &[&str], needles: &[&str]) {
    let input = dir.join(name);
    std::fs::write(&input, bytes).unwrap();
    let (out, json) = (dir.join("out.ply"), dir.join("out.json"));
    let mut args = vec!["extract", "-a", "marching-cubes", "-f", input.to_str().unwrap(), "-o", out.to_str().unwrap()];
    args.extend(["-m", json.to_str().unwrap()]);
    args.extend(extra);
    let o = isolab(&args);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{name}: {err}");
    assert!(!err.contains("panicked"), "{name}: {err}");
    assert!(err.contains(name), "{name}: the message does not name the file: {err}");
    for n in needles {
        assert!(err.contains(n), "{name}: '{n}' not in: {err}");
    }
    let left: Vec<_> = std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    assert_eq!(left, vec![name.to_owned()], "{name}: files left behind");
    std::fs::remove_file(&input).unwrap();
}

#[test]
fn bad_volume_files_are_refused_with_the_file_named_and_nothing_written() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let good = nifti1(&[6, 6, 6], 2, 8, &ball(), ID, 1.0, 0.0);
    let gz = gzip(&good);
    refused(d, "truncated.nii.gz", &gz[..gz.len() / 2], &[], &["gzip", "corrupt or truncated"]);
    let mut corrupt = gz.clone();
    for b in &mut corrupt[30..60] {
        *b ^= 0xa5;
    }
    refused(d, "corrupt.nii.gz", &corrupt, &[], &["gzip"]);
    refused(d, "short.nii", &good[..good.len() - 10], &[], &["header and data disagree"]);
    refused(d, "complex.nii", &nifti1(&[6, 6, 6], 32, 64, &[0; 1728], ID, 1.0, 0.0), &[], &["datatype 32", "not supported"]);
    let zero = [[1.0, 0.0, 0.0, 0.0], [0.0, 0.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0]];
    refused(d, "zero-spacing.nii", &nifti1(&[6, 6, 6], 2, 8, &ball(), zero, 1.0, 0.0), &[], &["zero side"]);
    let inf = [[1.0, 0.0, 0.0, 0.0], [0.0, f32::INFINITY, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0]];
    refused(d, "inf-spacing.nii", &nifti1(&[6, 6, 6], 2, 8, &ball(), inf, 1.0, 0.0), &[], &["not finite"]);
    let mut floats: Vec<f32> = ball().iter().map(|&v| v as f32).collect();
    floats[6 + 36] = f32::NAN;
    let bytes: Vec<u8> = floats.iter().flat_map(|v| v.to_le_bytes()).collect();
    refused(d, "nan.nii", &nifti1(&[6, 6, 6], 16, 32, &bytes, ID, 1.0, 0.0), &[], &["voxel (0, 1, 1) is NaN"]);
    let four: Vec<u8> = ball().iter().chain(ball().iter()).copied().collect();
    refused(d, "time.nii", &nifti1(&[6, 6, 6, 2], 2, 8, &four, ID, 1.0, 0.0), &[], &["6 x 6 x 6 x 2", "--volume"]);
    refused(d, "time2.nii", &nifti1(&[6, 6, 6, 2], 2, 8, &four, ID, 1.0, 0.0), &["--volume", "2"], &["out of range"]);
    refused(
        d,
        "garbage.nrrd",
        b"NRRD0004\ntype: uchar\ndimension: 3\nsizes: 6 6 6\nencoding: gzip\n\n\x1f\x8b\x08\x00garbage",
        &[],
        &["gzip"],
    );
    refused(d, "bad.mhd", b"NDims = 3\nDimSize = 6 6\nElementType = MET_UCHAR\nElementDataFile = LOCAL\n", &[], &["DimSize"]);
}

#[test]
fn a_4d_volume_meshes_the_volume_picked() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("time.nii");
    let empty = vec![0u8; 216];
    let four: Vec<u8> = empty.iter().chain(ball().iter()).copied().collect();
    std::fs::write(&path, nifti1(&[6, 6, 6, 2], 2, 8, &four, ID, 1.0, 0.0)).unwrap();
    let o = isolab(&["extract", "-a", "surface-nets", "-f", path.to_str().unwrap(), "--volume", "1", "--iso", "100", "-m", "-"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let m: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(m["triangles"].as_u64().unwrap() > 20 && m["closed"].as_bool().unwrap() && m["outward"].as_bool().unwrap(), "{m}");
    assert!(m["input"]["notes"][0].as_str().unwrap().contains("volume 1 of 2"), "{m}");
}

#[test]
fn a_scan_meshes_to_stl_and_glb_that_metrics_reads_back() {
    let dir = tempfile::tempdir().unwrap();
    let mut counts = Vec::new();
    for ext in ["stl", "glb", "gltf", "ply"] {
        let out = dir.path().join(format!("scan.{ext}"));
        let o = isolab(&[
            "extract",
            "-a",
            "marching-cubes",
            "-f",
            &fixture("mni-small.nii.gz"),
            "--iso",
            "60.5",
            "-o",
            out.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        let err = stderr(&o);
        assert!(err.contains("note: meshing mni-small on its own 40 x 47 x 38 voxel grid"), "{err}");
        let bytes = std::fs::read(&out).unwrap();
        if ext == "stl" {
            assert!(String::from_utf8_lossy(&bytes[..80]).contains("SPACE=RAS"), "STL header tags the space for 3D Slicer");
        }
        let m = isolab(&["metrics", out.to_str().unwrap()]);
        assert!(m.status.success(), "{}", stderr(&m));
        let m: serde_json::Value = serde_json::from_slice(&m.stdout).unwrap();
        assert!(m["closed"].as_bool().unwrap() && m["outward"].as_bool().unwrap(), "{ext}: {m}");
        counts.push((m["triangles"].as_u64().unwrap(), m["volume"].as_f64().unwrap()));
    }
    for c in &counts[1..] {
        assert_eq!(c.0, counts[0].0);
        assert!((c.1 - counts[0].1).abs() < 1e-6 * c.1, "{counts:?}");
    }
}

#[test]
fn mesh_files_in_any_format_are_fields_and_inward_ones_say_so() {
    let dir = tempfile::tempdir().unwrap();
    // A binary PLY as a field (it used to be read as OBJ and fail on a line of binary garbage).
    let ply = dir.path().join("horse.ply");
    assert!(isolab(&[
        "extract",
        "-a",
        "marching-cubes",
        "-f",
        "torus",
        "-r",
        "24",
        "-o",
        ply.to_str().unwrap(),
        "-m",
        "/dev/null"
    ])
    .status
    .success());
    let o = isolab(&["extract", "-a", "marching-cubes", "-f", ply.to_str().unwrap(), "-r", "24", "-m", "-"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let m: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(m["input"]["format"], "PLY");
    assert!(m["closed"].as_bool().unwrap() && m["genus"] == 1, "{m}");
    // A closed mesh wound inward: a mesh like the outward one's, a warning, exit 0.
    let text = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("../models/spot.obj")).unwrap();
    let inward: String = text
        .lines()
        .map(|l| match l.split_whitespace().collect::<Vec<_>>().as_slice() {
            ["f", a, b, c] => format!("f {a} {c} {b}\n"),
            _ => format!("{l}\n"),
        })
        .collect();
    let path = dir.path().join("spot-inward.obj");
    std::fs::write(&path, inward).unwrap();
    let o = isolab(&["extract", "-a", "surface-nets", "-f", path.to_str().unwrap(), "-r", "32", "-m", "-"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("warning: input mesh 'spot-inward' faces inward"), "{}", stderr(&o));
    let m: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(m["triangles"].as_u64().unwrap() > 1000 && m["outward"].as_bool().unwrap(), "{m}");
    // An iso-value with nothing inside: a warning and an empty mesh, not silence.
    let o = isolab(&["extract", "-a", "marching-cubes", "-f", "sphere", "-r", "16", "--iso", "3"]);
    assert!(o.status.success() && stderr(&o).contains("the mesh is empty"), "{}", stderr(&o));
}

#[test]
fn a_scans_islands_are_dropped_by_keep_components() {
    let dir = tempfile::tempdir().unwrap();
    let scan = fixture("mni-small.nii.gz");
    let mesh = |name: &str, post: &[&str]| {
        let (out, metrics) = (dir.path().join(format!("{name}.ply")), dir.path().join(format!("{name}.json")));
        let args = [
            &["extract", "-a", "marching-cubes", "-f", &scan, "--iso", "60.5"][..],
            post,
            &["-o", out.to_str().unwrap(), "-m", metrics.to_str().unwrap()],
        ]
        .concat();
        let o = isolab(&args);
        assert!(o.status.success(), "{}", stderr(&o));
        let m: serde_json::Value = serde_json::from_slice(&std::fs::read(&metrics).unwrap()).unwrap();
        m
    };
    let all = mesh("all", &[]);
    let one = mesh("one", &["--post", "keep-components:largest=1"]);
    let components = |m: &serde_json::Value| m["components"].as_u64().unwrap_or_else(|| panic!("no components in {m}"));
    assert!(components(&all) > 1, "the small MNI at 60.5 has islands: {}", components(&all));
    assert_eq!(components(&one), 1);
    assert!(one["closed"].as_bool().unwrap() && one["outward"].as_bool().unwrap(), "{one}");
    let triangles = |m: &serde_json::Value| m["triangles"].as_u64().unwrap();
    assert!(triangles(&one) < triangles(&all));
    let bad = dir.path().join("bad.ply");
    let o = isolab(&[
        "extract",
        "-a",
        "marching-cubes",
        "-f",
        &scan,
        "--post",
        "keep-components:min-volume=-1",
        "-o",
        bad.to_str().unwrap(),
    ]);
    assert!(!o.status.success() && stderr(&o).contains("min-volume"), "{}", stderr(&o));
    assert!(!bad.exists());
}
