//! `isolab extract --stream`: a volume file meshed block by block as its slices are read gives
//! the mesh `--chunk` makes in memory, refuses before reading what it cannot do, streams on its
//! own when the volume does not fit in memory, and holds far less than the volume.

use crate::common::{isolab, stderr};
use std::collections::BTreeSet;
use std::io::Write;
use std::path::Path;

/// A blob and a ring as 16-bit intensities (object brighter than its background), x fastest.
fn intensities(dims: [usize; 3]) -> Vec<u16> {
    let [nx, ny, nz] = dims;
    let mut v = Vec::with_capacity(nx * ny * nz);
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                let p = [i as f64 / nx as f64 - 0.45, j as f64 / ny as f64 - 0.5, k as f64 / nz as f64 - 0.55];
                let blob = 0.32 - (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt() + 0.04 * (9.0 * p[0]).sin();
                let ring = 0.07 - ((p[0].hypot(p[2]) - 0.28).hypot(p[1] - 0.3));
                v.push((2000.0 + 4000.0 * blob.max(ring)).round() as u16);
            }
        }
    }
    v
}

/// An NRRD of `dims` 16-bit voxels with the given space directions, raw or gzip.
fn write_nrrd(path: &Path, dims: [usize; 3], directions: &str, gzip: bool) {
    let bytes: Vec<u8> = intensities(dims).iter().flat_map(|v| v.to_le_bytes()).collect();
    let mut f = std::fs::File::create(path).unwrap();
    write!(
        f,
        "NRRD0004\ntype: uint16\ndimension: 3\nspace: left-posterior-superior\nsizes: {} {} {}\nspace directions: \
         {directions}\nspace origin: (-12.5,30,4)\nendian: little\nencoding: {}\n\n",
        dims[0],
        dims[1],
        dims[2],
        if gzip { "gzip" } else { "raw" }
    )
    .unwrap();
    if gzip {
        let mut z = flate2::write::GzEncoder::new(f, flate2::Compression::fast());
        z.write_all(&bytes).unwrap();
        z.finish().unwrap();
    } else {
        f.write_all(&bytes).unwrap();
    }
}

/// Runs `isolab` with `args`, asserting success, and returns its stdout as JSON.
fn succeeds(args: &[&str], env: &[(&str, &str)]) -> (serde_json::Value, String) {
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_isolab")).args(args).envs(env.iter().copied()).output().unwrap();
    let err = stderr(&o);
    assert!(o.status.success(), "{args:?}: {err}");
    (serde_json::from_slice(&o.stdout).unwrap_or_else(|e| panic!("{args:?}: stdout is not JSON ({e})")), err)
}

/// A mesh as sets: vertex positions (bits), and triangles by their corners' positions, each
/// rotated to start at its smallest corner (winding kept).
fn canonical(path: &Path) -> (BTreeSet<[u32; 3]>, BTreeSet<[[u32; 3]; 3]>) {
    let mesh = isolab_io::read_mesh(path).unwrap();
    let bits = |i: u32| mesh.positions[i as usize].to_array().map(f32::to_bits);
    let vertices = mesh.positions.iter().map(|p| p.to_array().map(f32::to_bits)).collect();
    let triangles = mesh
        .triangles
        .iter()
        .map(|t| {
            let c = t.map(bits);
            let first = (0..3).min_by_key(|&i| c[i]).unwrap();
            [c[first], c[(first + 1) % 3], c[(first + 2) % 3]]
        })
        .collect();
    assert_eq!(mesh.positions.len(), BTreeSet::from_iter(mesh.positions.iter().map(|p| p.to_array().map(f32::to_bits))).len());
    (vertices, triangles)
}

/// Streamed and in-memory chunked runs of one volume, with a sheared, mirrored affine (so both
/// mesh in voxel coordinates and map the same way): the same vertices and the same triangles,
/// bit for bit, for every chunking extractor family, in RAS and LPS; the JSON says what ran.
#[test]
fn a_streamed_volume_is_the_mesh_chunk_makes_in_memory() {
    let dir = tempfile::tempdir().unwrap();
    let dims = [33, 25, 41];
    let file = dir.path().join("scan.nrrd");
    write_nrrd(&file, dims, "(0.9,0.1,0) (0,-1.1,0.2) (0.05,0,1.3)", false);
    let (f, mem, streamed) = (file.to_str().unwrap(), dir.path().join("mem.ply"), dir.path().join("stream.ply"));
    for algorithm in ["marching-cubes", "marching-cubes-33", "surface-nets", "manifold-dual-contouring", "marching-tetrahedra"] {
        for space in ["ras", "lps"] {
            let what = format!("{algorithm} in {space}");
            let common = ["extract", "-a", algorithm, "-f", f, "--chunk", "8", "--space", space];
            let (_, _) = succeeds(&[&common[..], &["-o", mem.to_str().unwrap()]].concat(), &[]);
            let (report, err) = succeeds(&[&common[..], &["--stream", "-o", streamed.to_str().unwrap()]].concat(), &[]);
            assert!(err.contains("note: streamed"), "{what}: {err}");
            let (want, got) = (canonical(&mem), canonical(&streamed));
            assert!(!want.1.is_empty(), "{what}: empty mesh");
            assert_eq!(got.0, want.0, "{what}: vertices");
            assert_eq!(got.1, want.1, "{what}: triangles");
            assert_eq!(report["triangles"], want.1.len() as u64, "{what}");
            assert_eq!(report["shape"], serde_json::json!(dims), "{what}");
            assert_eq!(report["blocks"], serde_json::json!([4, 3, 5]), "{what}");
            assert_eq!(report["iso_from"], "Otsu's threshold of the volume's values", "{what}");
            assert_eq!(report["space"], space.to_uppercase(), "{what}");
            let header = std::fs::read(&streamed).unwrap();
            let tag = format!("comment SPACE={}", space.to_uppercase());
            assert!(header.windows(tag.len()).any(|w| w == tag.as_bytes()), "{what}: no {tag}");
        }
    }
}

/// A gzip volume with world-aligned cubic voxels, where the chunks do not divide the volume
/// (which only streaming allows): the mesh of the divisible part agrees with the in-memory run
/// within rounding (memory meshes in world coordinates, streaming maps voxel coordinates), and a
/// given iso-value is taken as given.
#[test]
fn a_gzip_volume_streams_in_blocks_that_need_not_divide_it() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("scan.nrrd");
    write_nrrd(&file, [33, 33, 33], "(0.5,0,0) (0,0.5,0) (0,0,0.5)", true);
    let (f, mem, streamed) = (file.to_str().unwrap(), dir.path().join("mem.ply"), dir.path().join("stream.ply"));
    succeeds(&["extract", "-a", "marching-cubes", "-f", f, "--iso", "2100", "--chunk", "8", "-o", mem.to_str().unwrap()], &[]);
    let (report, _) = succeeds(
        &[
            "extract",
            "-a",
            "marching-cubes",
            "-f",
            f,
            "--iso",
            "2100",
            "--chunk",
            "7",
            "--stream",
            "-o",
            streamed.to_str().unwrap(),
        ],
        &[],
    );
    assert_eq!(report["iso"], 2100.0);
    assert_eq!(report["iso_from"], serde_json::Value::Null);
    assert_eq!(report["blocks"], serde_json::json!([5, 5, 5]));
    let (a, b) = (isolab_io::read_mesh(&mem).unwrap(), isolab_io::read_mesh(&streamed).unwrap());
    assert_eq!(a.triangles.len(), b.triangles.len());
    assert_eq!(a.positions.len(), b.positions.len());
    let mut pa: Vec<[f32; 3]> = a.positions.iter().map(|p| p.to_array()).collect();
    let mut pb: Vec<[f32; 3]> = b.positions.iter().map(|p| p.to_array()).collect();
    let key = |p: &[f32; 3]| p.map(|c| (c * 64.0).round() as i64);
    pa.sort_by_key(key);
    pb.sort_by_key(key);
    for (x, y) in pa.iter().zip(&pb) {
        assert!((0..3).all(|i| (x[i] - y[i]).abs() < 1e-4), "{x:?} against {y:?}");
    }
}

/// What cannot stream is refused before any voxel is read, with a reason, exit 1, no file.
#[test]
fn what_cannot_stream_is_refused_with_the_reason() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("scan.nrrd");
    write_nrrd(&file, [9, 9, 9], "(1,0,0) (0,1,0) (0,0,1)", false);
    let truncated = dir.path().join("truncated.nrrd");
    let bytes = std::fs::read(&file).unwrap();
    std::fs::write(&truncated, &bytes[..bytes.len() - 100]).unwrap();
    let text = dir.path().join("text.nrrd");
    std::fs::write(&text, "NRRD0004\ntype: uint8\ndimension: 3\nsizes: 2 2 2\nencoding: ascii\n\n0 1 0 1 0 1 0 1\n").unwrap();
    let (f, out) = (file.to_str().unwrap(), dir.path().join("out.ply"));
    let o = out.to_str().unwrap();
    let obj = dir.path().join("out.obj");
    let cases: Vec<(Vec<&str>, &str, &Path)> = vec![
        (vec!["-a", "marching-cubes", "-f", "sphere"], "meshes volume files", &out),
        (vec!["-a", "marching-cubes", "-f", f, "-r", "16"], "--resolution/--dims", &out),
        (vec!["-a", "marching-cubes", "-f", f, "--lattice", "bcc"], "--lattice bcc", &out),
        (vec!["-a", "marching-cubes", "-f", f, "--post", "edge-collapse"], "--post", &out),
        (vec!["-a", "marching-cubes", "-f", f, "--self-intersections"], "--self-intersections", &out),
        (vec!["-f", f, "-a", "bcc-sculpt"], "cannot mesh in blocks; these can: marching-cubes", &out),
        (vec!["-a", "marching-cubes", "-f", truncated.to_str().unwrap()], "bytes of voxel data after its header", &out),
        (vec!["-a", "marching-cubes", "-f", text.to_str().unwrap()], "cannot be read slab by slab", &out),
    ];
    for (args, needle, unwritten) in cases {
        let full = [&["extract", "--stream", "-o", o][..], &args[..]].concat();
        let run = isolab(&full);
        let err = stderr(&run);
        assert_eq!(run.status.code(), Some(1), "{full:?}: {err}");
        assert!(err.contains(needle), "{full:?}: '{needle}' not in {err}");
        assert!(!err.contains("panicked"), "{full:?}: {err}");
        assert!(!unwritten.exists(), "{full:?}: written");
    }
    let run = isolab(&["extract", "-a", "marching-cubes", "--stream", "-f", f, "-o", obj.to_str().unwrap()]);
    assert_eq!(run.status.code(), Some(1));
    assert!(stderr(&run).contains("binary PLY"), "{}", stderr(&run));
    assert!(!obj.exists());
    assert!(std::fs::read_dir(dir.path()).unwrap().all(|e| !e.unwrap().file_name().to_string_lossy().ends_with(".part")));
}

/// A volume that does not fit in the memory available (`ISOLAB_MEMORY_MIB`, a smaller machine)
/// streams on its own when its output is a PLY, and is refused naming `--stream` otherwise; a
/// layer of blocks that does not fit either is refused naming `--chunk`.
#[test]
fn a_volume_too_large_for_memory_streams_on_its_own() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("scan.nrrd");
    write_nrrd(&file, [65, 65, 65], "(1,0,0) (0,1,0) (0,0,1)", false);
    let (f, out) = (file.to_str().unwrap(), dir.path().join("out.ply"));
    let small = [("ISOLAB_MEMORY_MIB", "2")];
    let (report, err) =
        succeeds(&["extract", "-a", "marching-cubes", "-f", f, "--chunk", "8", "-o", out.to_str().unwrap()], &small);
    assert!(err.contains("streaming it block by block instead"), "{err}");
    assert!(report["triangles"].as_u64().unwrap() > 0);
    assert_eq!(isolab_io::read_mesh(&out).unwrap().triangles.len() as u64, report["triangles"].as_u64().unwrap());
    let obj = dir.path().join("out.obj");
    let run = std::process::Command::new(env!("CARGO_BIN_EXE_isolab"))
        .args(["extract", "-a", "marching-cubes", "-f", f, "--chunk", "8", "-o", obj.to_str().unwrap()])
        .envs(small)
        .output()
        .unwrap();
    assert_eq!(run.status.code(), Some(1));
    assert!(stderr(&run).contains("--stream with a .ply output"), "{}", stderr(&run));
    assert!(!obj.exists());
    std::fs::remove_file(&out).unwrap();
    let run = std::process::Command::new(env!("CARGO_BIN_EXE_isolab"))
        .args(["extract", "-a", "marching-cubes", "-f", f, "--stream", "-o", out.to_str().unwrap()])
        .envs(small)
        .output()
        .unwrap();
    assert_eq!(run.status.code(), Some(1));
    assert!(stderr(&run).contains("lower --chunk"), "{}", stderr(&run));
    assert!(!out.exists());
}

/// Meshed on its own grid by marching cubes, a volume file's voxels are read in their stored type
/// and meshed where they lie: the run needs the file's data and the mesh, not the samples as
/// float32 and a generous guess (the check a copying extractor or `--chunk` still makes, which
/// refuses the same volume on the same smaller machine). A mesh over the memory available is
/// refused before it is made, naming its size; with a PLY output the run streams instead.
#[test]
fn a_volume_meshed_in_place_needs_its_data_and_its_mesh() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("scan.nrrd");
    write_nrrd(&file, [129, 129, 129], "(1,0,0) (0,1,0) (0,0,1)", false);
    let f = file.to_str().unwrap();
    let obj = dir.path().join("out.obj");
    // 4 MiB of uint16 data; as float32 samples and the old guess, about 85 MiB.
    let smaller = [("ISOLAB_MEMORY_MIB", "24")];
    let (report, _) = succeeds(&["extract", "-a", "marching-cubes", "-f", f, "-o", obj.to_str().unwrap()], &smaller);
    assert!(report["triangles"].as_u64().unwrap() > 1000);
    assert_eq!(isolab_io::read_mesh(&obj).unwrap().triangles.len() as u64, report["triangles"].as_u64().unwrap());
    for refused in [vec!["-a", "surface-nets"], vec!["-a", "marching-cubes", "--chunk", "16"]] {
        let mut args = vec!["extract", "-f", f, "-o", obj.to_str().unwrap()];
        args.extend(refused.iter());
        let run = std::process::Command::new(env!("CARGO_BIN_EXE_isolab")).args(&args).envs(smaller).output().unwrap();
        assert_eq!(run.status.code(), Some(1), "{args:?}");
        assert!(stderr(&run).contains("MiB"), "{args:?}: {}", stderr(&run));
    }
    // The data fits 5 MiB, the mesh does not: refused before it is made, or streamed to a PLY.
    std::fs::remove_file(&obj).unwrap();
    let tight = [("ISOLAB_MEMORY_MIB", "5")];
    let run = std::process::Command::new(env!("CARGO_BIN_EXE_isolab"))
        .args(["extract", "-a", "marching-cubes", "-f", f, "-o", obj.to_str().unwrap()])
        .envs(tight)
        .output()
        .unwrap();
    assert_eq!(run.status.code(), Some(1));
    assert!(stderr(&run).contains("MiB allowed"), "{}", stderr(&run));
    assert!(!stderr(&run).contains("panicked"), "{}", stderr(&run));
    assert!(!obj.exists());
    // A small volume of many surfaces: its mesh over the memory available, its stream not.
    let busy = dir.path().join("busy.nrrd");
    let n = 129;
    let voxels: Vec<u8> = (0..n * n * n)
        .map(|i| {
            let [x, y, z] = [i % n, i / n % n, i / (n * n)].map(|c| (c as f32 * 1.7).sin());
            (128.0 + 100.0 * x * y * z) as u8
        })
        .collect();
    let header = format!("NRRD0004\ntype: uint8\ndimension: 3\nsizes: {n} {n} {n}\nencoding: raw\n\n");
    std::fs::write(&busy, [header.as_bytes(), &voxels].concat()).unwrap();
    let ply = dir.path().join("busy.ply");
    let limit = [("ISOLAB_MEMORY_MIB", "16")];
    let (report, err) =
        succeeds(&["extract", "-a", "marching-cubes", "-f", busy.to_str().unwrap(), "-o", ply.to_str().unwrap()], &limit);
    assert!(err.contains("MiB allowed") && err.contains("streaming it block by block instead"), "{err}");
    assert!(report["triangles"].as_u64().unwrap() > 100_000, "{report}");
}

/// Streaming holds a layer of blocks, not the volume: the peak resident memory of a streamed
/// 256³ run is below the size of the volume's samples as f32 (what an in-memory run holds
/// before anything else), and the mesh is the whole object's.
#[test]
fn a_streamed_volume_is_not_held_in_memory() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("big.nrrd");
    let n = 256;
    write_nrrd(&file, [n, n, n], "(1,0,0) (0,1,0) (0,0,1)", false);
    let out = dir.path().join("big.ply");
    let (report, _) = succeeds(
        &[
            "extract",
            "-a",
            "marching-cubes",
            "-f",
            file.to_str().unwrap(),
            "--iso",
            "2000",
            "--chunk",
            "16",
            "--stream",
            "-o",
            out.to_str().unwrap(),
        ],
        &[],
    );
    let samples_mib = (n * n * n * 4) as f64 / (1 << 20) as f64;
    let peak = report["peak_rss_mib"].as_f64().expect("VmHWM on Linux");
    assert!(peak < samples_mib, "peak {peak} MiB against {samples_mib} MiB of samples");
    assert!(report["peak_layer_bytes"].as_f64().unwrap() < samples_mib * (1 << 20) as f64 / 4.0);
    let mesh = isolab_io::read_mesh(&out).unwrap();
    let m = isolab_metrics::MeshMetrics::measure(&mesh, None);
    assert_eq!(m.topology.boundary_edges, 0, "closed");
}
