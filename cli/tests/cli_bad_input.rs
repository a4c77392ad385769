//! Bad input the CLI must refuse cleanly (a message naming the input and what is wrong, a
//! non-zero exit code, no panic, nothing written): binary garbage, truncated and malformed PLY,
//! malformed OBJ, impossible numbers, unwritable outputs, pictures of nothing.

use crate::common::{isolab, stderr};
use std::path::Path;

/// Runs `isolab` with `args`, expecting exit `code`, every needle in stderr, no panic, and no
/// file at `unwritten`.
fn refused(args: &[&str], code: i32, needles: &[&str], unwritten: &Path) {
    let o = isolab(args);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(code), "{args:?}: {err}");
    assert!(!err.contains("panicked"), "{args:?}: {err}");
    for n in needles {
        assert!(err.contains(n), "{args:?}: '{n}' not in: {err}");
    }
    assert!(!unwritten.exists(), "{args:?}: {} written", unwritten.display());
}

/// The mesh file `name` with `bytes` as a field and as a file to measure: both refused.
fn bad_mesh(dir: &Path, name: &str, bytes: &[u8], needles: &[&str]) {
    let path = dir.join(name);
    std::fs::write(&path, bytes).unwrap();
    let (p, m) = (path.to_str().unwrap(), dir.join("m.json"));
    let mut with_file = vec![name];
    with_file.extend_from_slice(needles);
    refused(&["extract", "-a", "marching-cubes", "-f", p, "-r", "8", "-m", m.to_str().unwrap()], 1, &with_file, &m);
    refused(&["metrics", p], 2, &with_file, &m);
}

/// A small marching cubes sphere written to `path` (a valid mesh to cut or render).
fn sphere_mesh(path: &Path) {
    let o =
        isolab(&["extract", "-a", "marching-cubes", "-f", "sphere", "-r", "8", "-o", path.to_str().unwrap(), "-m", "/dev/null"]);
    assert!(o.status.success(), "{}", stderr(&o));
}

const PLY_HEAD: &str = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
                        element face 1\nproperty list uchar int vertex_indices\nend_header\n";

#[test]
fn malformed_mesh_files_name_the_file_and_what_is_wrong() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // Binary garbage (a fixed pseudo-random stream with NUL bytes) under three names.
    let mut random = isolab_algorithms::random::Random::new(17);
    let garbage: Vec<u8> = (0..2000).map(|_| (random.unit() * 256.0) as u8).chain([0u8]).collect();
    bad_mesh(d, "garbage.obj", &garbage, &["binary data"]);
    bad_mesh(d, "garbage.bin", &garbage, &["binary data"]);
    bad_mesh(d, "garbage.ply", &garbage, &["not a PLY file"]);
    // PLY: truncated ascii, truncated binary, a face index past the vertices.
    bad_mesh(d, "short.ply", format!("{PLY_HEAD}0 0 0\n1 0 0\n").as_bytes(), &["short.ply:12:", "ends early"]);
    let sphere = d.join("sphere.ply");
    sphere_mesh(&sphere);
    let whole = std::fs::read(&sphere).unwrap();
    bad_mesh(d, "cut.ply", &whole[..whole.len() / 2], &["ends early"]);
    bad_mesh(d, "index.ply", format!("{PLY_HEAD}0 0 0\n1 0 0\n0 1 0\n3 0 1 9\n").as_bytes(), &["vertex 9", "only 3 vertices"]);
    // OBJ: an infinite coordinate, two coordinates, index 0 (OBJ counts from 1).
    // An infinite coordinate: refused as a field; measured (and counted) by `metrics`.
    let inf = d.join("inf.obj");
    std::fs::write(&inf, "v 0 0 0\nv inf 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let m = d.join("m.json");
    refused(
        &["extract", "-a", "marching-cubes", "-f", inf.to_str().unwrap(), "-m", m.to_str().unwrap()],
        1,
        &["inf.obj:2:", "not finite"],
        &m,
    );
    let o = isolab(&["metrics", inf.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let report: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(report["non_finite_vertices"], 1);
    bad_mesh(d, "two.obj", b"v 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", &["two.obj:1:", "2 coordinates"]);
    bad_mesh(d, "zero.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", &["zero.obj:4:", "index 0"]);
}

#[test]
fn impossible_numbers_are_refused_by_name() {
    let dir = tempfile::tempdir().unwrap();
    let m = dir.path().join("m.json");
    let ms = m.to_str().unwrap();
    let run = |extra: &[&str], code: i32, needles: &[&str]| {
        let mut args = vec!["extract", "-a", "marching-cubes", "-f", "sphere", "-m", ms];
        args.extend_from_slice(extra);
        refused(&args, code, needles, &m);
    };
    run(&["-r", "8", "--iso", "inf"], 1, &["iso-value inf", "not finite"]);
    run(&["-r", "8", "--iso=-inf"], 1, &["not finite"]);
    run(&["--dims", "10,x,10"], 2, &["--dims", "'' is not a whole number"]);
    run(&["--dims", "10,10"], 2, &["--dims", "three numbers"]);
    run(&["--dims", "10,-3,10"], 2, &["--dims", "'-3' is not a whole number"]);
    run(&["--dims", "9,9,9", "--chunk", "64"], 1, &["chunk size 64", "does not divide"]);
}

#[test]
fn unwritable_metrics_and_pictures_of_nothing_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let nowhere = d.join("no/such/dir/m.json");
    refused(
        &["extract", "-a", "marching-cubes", "-f", "sphere", "-r", "8", "-m", nowhere.to_str().unwrap()],
        1,
        &["cannot write", "m.json"],
        &nowhere,
    );
    let mesh = d.join("t.ply");
    sphere_mesh(&mesh);
    let png = d.join("t.png");
    refused(&["render", mesh.to_str().unwrap(), "-o", png.to_str().unwrap(), "--size", "0"], 2, &["--size", "0 is not in"], &png);
    let empty = d.join("empty.ply");
    std::fs::write(&empty, PLY_HEAD.replace("vertex 3", "vertex 0").replace("face 1", "face 0")).unwrap();
    refused(&["render", empty.to_str().unwrap(), "-o", png.to_str().unwrap()], 2, &["empty.ply", "no faces"], &png);
    let nan = d.join("nan.obj");
    std::fs::write(&nan, "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    refused(&["render", nan.to_str().unwrap(), "-o", png.to_str().unwrap()], 1, &["nan.obj", "1 vertex is not finite"], &png);
    let out = isolab(&["render", mesh.to_str().unwrap(), "-o", png.to_str().unwrap()]);
    assert!(out.status.success() && png.exists(), "{}", stderr(&out));
}

/// A volume too large for memory is refused from its header, before its data is read: each file
/// here claims 4096³ samples but holds a few bytes, so only a refusal that never read the data
/// names memory.
#[test]
fn a_volume_too_large_for_memory_is_refused_before_its_data_is_read() {
    let dir = std::env::temp_dir().join(format!("isolab-huge-volume-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let nrrd = dir.join("huge.nrrd");
    std::fs::write(&nrrd, b"NRRD0004\ntype: uint8\ndimension: 3\nsizes: 4096 4096 4096\nencoding: raw\n\n01234567").unwrap();
    let mhd = dir.join("huge.mhd");
    std::fs::write(&mhd, b"NDims = 3\nDimSize = 4096 4096 4096\nElementType = MET_UCHAR\nElementDataFile = LOCAL\n0123").unwrap();
    let (obj, ply) = (dir.join("out.obj"), dir.join("out.ply"));
    for (file, bytes) in [(&nrrd, "8"), (&mhd, "4")] {
        let args = ["extract", "-a", "marching-cubes", "-f", file.to_str().unwrap(), "-o", obj.to_str().unwrap()];
        refused(&args, 1, &["[4096, 4096, 4096] cubic lattice needs about", "--stream", "isolab.dask.mesh_volume"], &obj);
        // A PLY output streams instead, and the streaming refuses the data the header promises
        // but the file lacks, before reading it.
        let args = ["extract", "-a", "marching-cubes", "-f", file.to_str().unwrap(), "-o", ply.to_str().unwrap()];
        let holds = format!("holds {bytes} bytes of voxel data after its header");
        refused(&args, 1, &["streaming it block by block instead", &holds], &ply);
    }
    let _ = std::fs::remove_dir_all(&dir);
}
