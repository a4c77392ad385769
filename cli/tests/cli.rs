//! The `isolab` command line as scripts use it: outputs, metrics, and every kind of bad input
//! (a clear message, a non-zero exit code, no panic, no half-written file).

use crate::common::{isolab, stderr};
use std::path::Path;
use std::process::Output;

fn assert_clean_failure(o: &Output, code: i32, needles: &[&str]) {
    let err = stderr(o);
    assert_eq!(o.status.code(), Some(code), "stderr: {err}");
    assert!(!err.contains("panicked"), "{err}");
    for n in needles {
        assert!(err.contains(n), "'{n}' not in: {err}");
    }
}

fn json(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

#[test]
fn list_names_algorithms_post_processes_and_fields() {
    let o = isolab(&["list"]);
    assert!(o.status.success());
    let out = String::from_utf8_lossy(&o.stdout);
    for name in ["marching-cubes", "post-processes", "sphere", "torus", "gyroid", "asteroid", "terrain", "csg", "thin"] {
        assert!(out.contains(name), "{name} missing from:\n{out}");
    }
    // Every built-in field says the bound its sparse runs prune with.
    assert_eq!(out.matches("Lipschitz bound").count(), isolab_algorithms::fields::registry().len(), "{out}");
}

#[test]
fn extract_writes_mesh_and_metrics_that_metrics_command_reproduces() {
    let dir = tempfile::tempdir().unwrap();
    for ext in ["obj", "ply"] {
        let mesh = dir.path().join(format!("s.{ext}"));
        let metrics = dir.path().join("s.json");
        let o = isolab(&[
            "extract",
            "--algorithm",
            "marching-cubes",
            "--field",
            "sphere",
            "--resolution",
            "32",
            "--output",
            mesh.to_str().unwrap(),
            "--metrics",
            metrics.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        let m = json(&metrics);
        for key in [
            "algorithm",
            "field",
            "resolution",
            "lattice",
            "vertices",
            "triangles",
            "tetrahedra",
            "times_ms",
            "aspect_ratio",
            "aspect_ratio_cgal",
            "min_angle_deg",
            "max_angle_deg",
            "closed",
            "edge_manifold",
            "vertex_manifold",
            "oriented",
            "components",
            "euler",
            "genus",
            "boundary_edges",
            "degenerate_triangles",
            "volume",
            "area",
            "surface_distance",
        ] {
            assert!(m.get(key).is_some(), "metrics JSON lacks '{key}'");
        }
        for key in ["sampling", "extraction", "post", "total"] {
            assert!(m["times_ms"][key].is_number(), "times_ms.{key}");
        }
        assert_eq!(m["euler"], 2);
        assert_eq!(m["closed"], true);
        let again = isolab(&["metrics", mesh.to_str().unwrap()]);
        assert!(again.status.success(), "{}", stderr(&again));
        let r: serde_json::Value = serde_json::from_slice(&again.stdout).unwrap();
        for key in ["vertices", "triangles", "euler", "genus", "closed"] {
            assert_eq!(r[key], m[key], "{key} differs after a round trip through .{ext}");
        }
        let (a, b) = (r["volume"].as_f64().unwrap(), m["volume"].as_f64().unwrap());
        assert!((a - b).abs() < 1e-6 * b.abs(), "{a} vs {b}");
    }
}

#[test]
fn extract_computes_only_the_measures_asked_for() {
    let run = |extra: &[&str]| {
        let mut args = vec!["extract", "-a", "marching-cubes", "-f", "torus", "-r", "24"];
        args.extend_from_slice(extra);
        let o = isolab(&args);
        assert!(o.status.success(), "{}", stderr(&o));
        serde_json::from_slice::<serde_json::Value>(&o.stdout).unwrap()
    };
    // Nothing asked: the run's times and counts, no mesh metric.
    let plain = run(&[]);
    assert!(plain["triangles"].as_u64().unwrap() > 500 && plain["vertices"].as_u64().unwrap() > 250, "{plain}");
    assert!(plain["times_ms"]["extraction"].is_number(), "{plain}");
    for key in ["closed", "genus", "aspect_ratio", "area", "surface_distance", "self_intersections", "overdraw"] {
        assert!(plain.get(key).is_none(), "'{key}' was computed unasked: {plain}");
    }
    // -m: every metric but the exact self-intersection test.
    let metrics = run(&["-m", "-"]);
    assert_eq!((metrics["closed"].as_bool(), metrics["genus"].as_u64()), (Some(true), Some(1)), "{metrics}");
    assert_eq!(metrics["triangles"], plain["triangles"]);
    assert!(metrics.get("self_intersections").is_none(), "{metrics}");
    // --self-intersections: that test too (on stdout without -m).
    let all = run(&["--self-intersections"]);
    assert_eq!(all["self_intersections"]["count"], 0, "{all}");
    assert_eq!(all["genus"], 1);
}
#[test]
fn unknown_names_exit_2_and_list_the_valid_ones() {
    let o = isolab(&["extract", "-a", "marching-cube", "-f", "sphere"]);
    assert_clean_failure(&o, 2, &["unknown algorithm 'marching-cube'", "marching-cubes"]);
    let o = isolab(&["extract", "-a", "marching-cubes", "-f", "spere"]);
    assert_clean_failure(&o, 2, &["unknown field 'spere'", "sphere", "terrain"]);
    let o = isolab(&["extract", "-a", "marching-cubes", "-f", "sphere", "--post", "nope"]);
    assert_clean_failure(&o, 2, &["unknown post-process 'nope'", "edge-collapse", "edge-collapse-safe"]);
}

#[test]
fn tetrahedral_options_are_checked() {
    let o = isolab(&["extract", "-a", "marching-tetrahedra", "-f", "sphere", "-r", "16", "--lattice", "tet"]);
    assert_clean_failure(&o, 2, &["tet", "cubic", "bcc"]);
    for spec in ["edge-collapse:threshold=0", "edge-collapse-safe:threshold=-0.5"] {
        let o = isolab(&["extract", "-a", "marching-tetrahedra", "-f", "sphere", "-r", "16", "--post", spec]);
        assert_clean_failure(&o, 2, &["threshold", "(0, 100]"]);
    }
    let o = isolab(&["extract", "-a", "regularised-marching-tetrahedra", "-f", "sphere", "-r", "16", "--set", "guard=maybe"]);
    assert_clean_failure(&o, 2, &["guard", "true, manifold, false"]);
    let o = isolab(&[
        "extract",
        "-a",
        "marching-tetrahedra",
        "-f",
        "sphere",
        "-r",
        "16",
        "--lattice",
        "bcc",
        "--post",
        "edge-collapse-safe",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
}

#[test]
fn impossible_resolutions_are_refused_before_allocating() {
    let o = isolab(&["extract", "-a", "marching-cubes", "-f", "sphere", "-r", "1"]);
    assert_clean_failure(&o, 1, &["resolution 1", "at least 2"]);
    let o = isolab(&["extract", "-a", "marching-cubes", "-f", "sphere", "-r", "5000", "--dense"]);
    assert_clean_failure(&o, 1, &["samples"]);
    // Sampled near its surface, a grid may be larger, but not without bound.
    let o = isolab(&["extract", "-a", "marching-cubes", "-f", "sphere", "-r", "20000"]);
    assert_clean_failure(&o, 1, &["samples"]);
    let o = isolab(&["extract", "-a", "marching-cubes", "-f", "sphere", "--dims", "10,1,10"]);
    assert_clean_failure(&o, 1, &["at least 2"]);
    let o = isolab(&["extract", "-a", "marching-cubes", "-f", "sphere", "--iso", "NaN"]);
    assert_clean_failure(&o, 1, &["iso"]);
    let o = isolab(&["extract", "-a", "marching-cubes", "-f", "sphere", "--lattice", "bcc", "-r", "8"]);
    assert_clean_failure(&o, 1, &["cubic"]);
}

#[test]
fn malformed_and_empty_obj_files_name_the_file_and_line() {
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("bad.obj");
    std::fs::write(&bad, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n").unwrap();
    let o = isolab(&["extract", "-a", "marching-cubes", "-f", bad.to_str().unwrap(), "-r", "8"]);
    assert_clean_failure(&o, 1, &["bad.obj:4:", "out of range"]);
    let nan = dir.path().join("nan.obj");
    std::fs::write(&nan, "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let o = isolab(&["extract", "-a", "marching-cubes", "-f", nan.to_str().unwrap(), "-r", "8"]);
    assert_clean_failure(&o, 1, &["nan.obj:2:", "not finite"]);
    // Measuring reports NaN vertices instead of refusing or crashing.
    let o = isolab(&["metrics", nan.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let m: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(m["non_finite_vertices"], 1);
    assert_eq!(m["volume"], serde_json::Value::Null);
    let empty = dir.path().join("empty.obj");
    std::fs::write(&empty, "# nothing here\n").unwrap();
    assert_clean_failure(
        &isolab(&["extract", "-a", "marching-cubes", "-f", empty.to_str().unwrap()]),
        1,
        &["empty.obj", "no faces"],
    );
    let missing = dir.path().join("missing.obj");
    assert_clean_failure(&isolab(&["metrics", missing.to_str().unwrap()]), 2, &["missing.obj"]);
    assert_clean_failure(&isolab(&["metrics", empty.to_str().unwrap()]), 2, &["empty.obj", "no faces"]);
    let lines = dir.path().join("lines.obj");
    std::fs::write(&lines, "v 0 0 0\nv 1 0 0\nf 1 2\n").unwrap();
    assert_clean_failure(&isolab(&["metrics", lines.to_str().unwrap()]), 2, &["lines.obj:3:", "at least 3"]);
    let ply = dir.path().join("odd.ply");
    std::fs::write(&ply, "ply\nformat binary_little_endian 1.0\nelement vertex 1\nproperty double x\nend_header\n").unwrap();
    assert_clean_failure(&isolab(&["metrics", ply.to_str().unwrap()]), 2, &["odd.ply", "no scalar x, y and z"]);
}

#[test]
fn unwritable_outputs_fail_and_leave_no_file() {
    let dir = tempfile::tempdir().unwrap();
    let nowhere = dir.path().join("no/such/dir/s.obj");
    let o = isolab(&["extract", "-a", "marching-cubes", "-f", "sphere", "-r", "8", "-o", nowhere.to_str().unwrap()]);
    assert_clean_failure(&o, 1, &["cannot write", "s.obj"]);
    // The output path is an existing directory: the rename fails after writing.
    let target = dir.path().join("taken.obj");
    std::fs::create_dir(&target).unwrap();
    std::fs::write(target.join("keep"), "x").unwrap();
    let o = isolab(&["extract", "-a", "marching-cubes", "-f", "sphere", "-r", "8", "-o", target.to_str().unwrap()]);
    assert_clean_failure(&o, 1, &["cannot write", "taken.obj"]);
    let left: Vec<_> = std::fs::read_dir(dir.path()).unwrap().map(|e| e.unwrap().file_name()).collect();
    assert_eq!(left.len(), 1, "temporary files left behind: {left:?}");
    let o =
        isolab(&["extract", "-a", "marching-cubes", "-f", "sphere", "-r", "8", "-o", dir.path().join("s.xyz").to_str().unwrap()]);
    assert_clean_failure(&o, 1, &["unknown extension"]);
}

#[test]
fn render_writes_png_and_gif_pictures() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = dir.path().join("t.ply");
    assert!(isolab(&[
        "extract",
        "-a",
        "marching-cubes",
        "-f",
        "torus",
        "-r",
        "16",
        "-o",
        mesh.to_str().unwrap(),
        "-m",
        dir.path().join("t.json").to_str().unwrap()
    ])
    .status
    .success());
    let png = dir.path().join("t.png");
    let o = isolab(&["render", mesh.to_str().unwrap(), "-o", png.to_str().unwrap(), "--wireframe", "--size", "64"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(&std::fs::read(&png).unwrap()[1..4], b"PNG");
    let gif = dir.path().join("t.gif");
    let o = isolab(&["render", mesh.to_str().unwrap(), "-o", gif.to_str().unwrap(), "--smooth", "--size", "32"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(&std::fs::read(&gif).unwrap()[0..3], b"GIF");
    assert_clean_failure(
        &isolab(&["render", mesh.to_str().unwrap(), "-o", dir.path().join("t.bmp").to_str().unwrap()]),
        1,
        &["unknown extension"],
    );
    assert_clean_failure(&isolab(&["render", "missing.obj", "-o", png.to_str().unwrap()]), 2, &["missing.obj"]);
}

#[test]
fn algorithm_options_are_checked_and_named() {
    let o = isolab(&["extract", "-a", "surface-nets", "-f", "sphere", "-r", "16", "--smoothing", "spring", "--iterations", "3"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = isolab(&["extract", "-a", "surface-nets", "-f", "sphere", "-r", "16", "--iterations", "-2"]);
    assert_clean_failure(&o, 2, &["surface-nets", "'iterations'", "negative"]);
    let o = isolab(&["extract", "-a", "surface-nets", "-f", "sphere", "-r", "16", "--set", "damping=3"]);
    assert_clean_failure(&o, 2, &["'damping'", "[0, 1]"]);
    let o = isolab(&["extract", "-a", "surface-nets", "-f", "sphere", "-r", "16", "--smoothing", "magic"]);
    assert_clean_failure(&o, 2, &["'smoothing'", "none, elastic, spring, implicit"]);
    let o = isolab(&["extract", "-a", "marching-cubes", "-f", "sphere", "-r", "16", "--smoothing", "elastic"]);
    assert_clean_failure(&o, 2, &["marching-cubes does not take option 'smoothing'"]);
    let o = isolab(&["extract", "-a", "marching-cubes", "-f", "sphere", "-r", "16", "--set", "novalue"]);
    assert_clean_failure(&o, 2, &["NAME=VALUE"]);
}

#[test]
fn samples_out_writes_the_raw_grid_and_its_header() {
    let dir = tempfile::tempdir().unwrap();
    let raw = dir.path().join("g.raw");
    let o = isolab(&[
        "extract",
        "-a",
        "marching-cubes",
        "-f",
        "terrain",
        "--dims",
        "9,5,7",
        "-m",
        "/dev/null",
        "--samples-out",
        raw.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let bytes = std::fs::read(&raw).unwrap();
    assert_eq!(bytes.len(), 9 * 5 * 7 * 4);
    let header = json(&dir.path().join("g.raw.json"));
    assert_eq!(header["dims"], serde_json::json!([9, 5, 7]));
    assert_eq!(header["lattice"], "cubic");
    // The first value is the field at the origin corner.
    let first = f32::from_le_bytes(bytes[..4].try_into().unwrap());
    assert!(first.is_finite());
    let o = isolab(&["extract", "-a", "marching-cubes", "-f", "sphere", "-r", "8", "--samples-out", "/no/such/dir/g.raw"]);
    assert_clean_failure(&o, 1, &["/no/such/dir/g.raw"]);
}

#[test]
fn bcc_sculpt_writes_tetrahedra_beside_the_surface_and_its_metrics() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = dir.path().join("spot.obj");
    let metrics = dir.path().join("spot.json");
    let model = concat!(env!("CARGO_MANIFEST_DIR"), "/../models/spot.obj");
    let o = isolab(&[
        "extract",
        "-a",
        "bcc-sculpt",
        "-f",
        model,
        "-r",
        "12",
        "--set",
        "cells=6",
        "--offset-ratio",
        "0.8",
        "--perturbations",
        "1",
        "-o",
        mesh.to_str().unwrap(),
        "-m",
        metrics.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let m = json(&metrics);
    for key in ["tetrahedra", "dihedral_deg", "boundary_distance", "volume_ratio", "encloses", "converged"] {
        assert!(m.get(key).is_some(), "{key} missing from the metrics JSON");
    }
    assert_eq!(m["encloses"], true);
    let vtk = std::fs::read_to_string(dir.path().join("spot.vtk")).unwrap();
    let cells = format!("CELLS {} ", m["tetrahedra"]);
    assert!(vtk.starts_with("# vtk DataFile") && vtk.contains(&cells), "tetrahedra written beside the surface");
}

#[test]
fn bcc_sculpt_refuses_impossible_settings_by_name() {
    let model = concat!(env!("CARGO_MANIFEST_DIR"), "/../models/spot.obj");
    let run = |extra: &[&str]| {
        let mut args = vec!["extract", "-a", "bcc-sculpt", "-f", model, "-r", "8"];
        args.extend_from_slice(extra);
        isolab(&args)
    };
    assert_clean_failure(&run(&["--spacing", "100"]), 1, &["spacing 100", "larger than 'spot'"]);
    assert_clean_failure(&run(&["--offset-ratio", "0"]), 2, &["offset-ratio", "above 0"]);
    assert_clean_failure(&run(&["--offset-ratio", "-0.5"]), 2, &["offset-ratio"]);
    assert_clean_failure(&run(&["--perturbations", "0"]), 2, &["perturbations", "at least 1"]);
    let o = isolab(&["extract", "-a", "marching-cubes", "-f", "sphere", "-r", "8", "--spacing", "1"]);
    assert_clean_failure(&o, 2, &["marching-cubes does not take option 'spacing'"]);
}

#[test]
fn chunked_extraction_matches_the_whole_volume_and_refuses_bad_sizes() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("a.json"), dir.path().join("b.json"));
    let whole = isolab(&["extract", "-a", "marching-cubes", "-f", "asteroid", "--dims", "65,65,65", "-m", a.to_str().unwrap()]);
    assert!(whole.status.success(), "{}", stderr(&whole));
    let chunked = isolab(&[
        "extract",
        "-a",
        "marching-cubes",
        "-f",
        "asteroid",
        "--dims",
        "65,65,65",
        "--chunk",
        "16",
        "-m",
        b.to_str().unwrap(),
    ]);
    assert!(chunked.status.success(), "{}", stderr(&chunked));
    let (a, b) = (json(&a), json(&b));
    assert_eq!((&a["vertices"], &a["triangles"], &a["euler"]), (&b["vertices"], &b["triangles"], &b["euler"]));
    assert_eq!(b["chunks"]["per_axis"], serde_json::json!([4, 4, 4]));
    let o = isolab(&["extract", "-a", "marching-cubes", "-f", "asteroid", "--dims", "65,65,65", "--chunk", "10"]);
    assert_clean_failure(&o, 1, &["chunk size 10 does not divide"]);
    let o = isolab(&["extract", "-a", "marching-cubes", "-f", "asteroid", "--dims", "65,65,65", "--chunk", "1"]);
    assert_clean_failure(&o, 1, &["below 2"]);
    // Surface nets chunks with an apron (2 + its 4 smoothing iterations) and gives the whole
    // volume's triangles.
    let (c, d) = (dir.path().join("c.json"), dir.path().join("d.json"));
    let sn = |extra: &[&str], m: &std::path::Path| {
        let mut args = vec!["extract", "-a", "surface-nets", "-f", "asteroid", "--dims", "65,65,65", "-m", m.to_str().unwrap()];
        args.extend_from_slice(extra);
        isolab(&args)
    };
    assert!(sn(&[], &c).status.success());
    let o = sn(&["--chunk", "16"], &d);
    assert!(o.status.success(), "{}", stderr(&o));
    let (c, d) = (json(&c), json(&d));
    assert_eq!((&c["triangles"], &c["euler"]), (&d["triangles"], &d["euler"]));
    assert_eq!(d["chunks"]["apron"], serde_json::json!(6));
    let o = isolab(&["extract", "-a", "bcc-sculpt", "-f", "sphere", "--dims", "33,33,33", "--chunk", "16"]);
    assert_clean_failure(&o, 1, &["bcc-sculpt", "cannot mesh in chunks"]);
}

#[test]
fn materials_are_counted_and_written_as_vertex_colours() {
    let dir = tempfile::tempdir().unwrap();
    let (obj, ply, m) = (dir.path().join("t.obj"), dir.path().join("t.ply"), dir.path().join("t.json"));
    let base = ["extract", "-a", "marching-cubes", "-f", "terrain", "--dims", "65,33,65", "--materials"];
    let o = isolab(&[&base[..], &["-o", obj.to_str().unwrap(), "-m", m.to_str().unwrap()]].concat());
    assert!(o.status.success(), "{}", stderr(&o));
    let report = json(&m);
    let counts = report["materials"].as_object().expect("materials in the metrics JSON");
    let total: u64 = counts.values().map(|v| v.as_u64().unwrap()).sum();
    assert_eq!(total, report["vertices"].as_u64().unwrap());
    assert!(counts.contains_key("grass") && counts.contains_key("rock"), "{counts:?}");
    let text = std::fs::read_to_string(&obj).unwrap();
    let first = text.lines().find(|l| l.starts_with("v ")).unwrap();
    assert_eq!(first.split_whitespace().count(), 7, "v x y z r g b: {first}");
    // The coloured PLY reads back (colours skipped) with the same counts.
    let o = isolab(&[&base[..], &["-o", ply.to_str().unwrap()]].concat());
    assert!(o.status.success(), "{}", stderr(&o));
    let back = isolab(&["metrics", ply.to_str().unwrap()]);
    assert!(back.status.success(), "{}", stderr(&back));
    let back: serde_json::Value = serde_json::from_slice(&back.stdout).unwrap();
    assert_eq!(back["vertices"], report["vertices"]);
    assert_eq!(back["triangles"], report["triangles"]);
}

/// The CLI re-executes itself with huge pages for malloc (Linux with glibc); the re-executed
/// process must see the same arguments and name, and make the same mesh.
#[cfg(unix)]
#[test]
fn re_executing_with_huge_pages_keeps_the_arguments_the_name_and_the_mesh() {
    use std::os::unix::process::CommandExt;
    use std::process::Command;
    let dir = tempfile::tempdir().unwrap();
    let run = |no_huge: bool, out: &Path| {
        let mut c = Command::new(env!("CARGO_BIN_EXE_isolab"));
        c.args(["extract", "-a", "surface-nets", "-f", "gyroid", "-r", "24", "-o"]).arg(out).env_remove("GLIBC_TUNABLES");
        if no_huge {
            c.env("ISOLAB_NO_HUGE_PAGES", "1");
        } else {
            c.env_remove("ISOLAB_NO_HUGE_PAGES");
        }
        let o = c.output().unwrap();
        assert!(o.status.success(), "{}", stderr(&o));
        std::fs::read(out).unwrap()
    };
    let (huge, plain) = (dir.path().join("huge.obj"), dir.path().join("plain.obj"));
    assert_eq!(run(false, &huge), run(true, &plain), "the same mesh either way");
    for no_huge in [false, true] {
        let mut c = Command::new(env!("CARGO_BIN_EXE_isolab"));
        c.arg0("isolab-under-test").env_remove("GLIBC_TUNABLES");
        if no_huge {
            c.env("ISOLAB_NO_HUGE_PAGES", "1");
        } else {
            c.env_remove("ISOLAB_NO_HUGE_PAGES");
        }
        let o = c.output().unwrap();
        assert_eq!(o.status.code(), Some(2));
        assert!(stderr(&o).contains("Usage: isolab-under-test"), "the name it was called by: {}", stderr(&o));
    }
}

#[test]
fn sparse_runs_write_the_dense_runs_mesh_from_fewer_evaluations() {
    let dir = tempfile::tempdir().unwrap();
    let path = |name: &str| dir.path().join(name).to_string_lossy().into_owned();
    let cases =
        [("torus", "marching-cubes"), ("sphere", "surface-nets"), ("gyroid", "dual-contouring"), ("asteroid", "marching-cubes")];
    for (field, algorithm) in cases {
        let mut meshes = Vec::new();
        for mode in ["--sparse", "--dense"] {
            let (mesh, metrics) = (path(&format!("{field}{mode}.ply")), path(&format!("{field}{mode}.json")));
            let o =
                isolab(&["extract", "-a", algorithm, "-f", field, "-r", "97", "--chunk", "8", mode, "-o", &mesh, "-m", &metrics]);
            assert!(o.status.success(), "{field} {mode}: {}", stderr(&o));
            let report = json(Path::new(&metrics));
            assert!(report["triangles"].as_u64().unwrap() > 1000, "{field} {mode}");
            if mode == "--sparse" {
                let s = &report["sparse"];
                assert_eq!(s["dense_points"].as_u64(), Some(97 * 97 * 97), "{field}");
                // At 97³ only a distance with cell-local blocks prunes enough to save evaluations.
                if field == "torus" {
                    assert!(s["evaluations"].as_u64().unwrap() * 2 < s["dense_points"].as_u64().unwrap(), "{field}: {s}");
                }
                assert_eq!(s["field_bound"], serde_json::Value::Bool(true));
            } else {
                assert!(report.get("sparse").is_none(), "{field}: a dense run says sparse");
            }
            meshes.push(binary_ply(Path::new(&mesh)));
        }
        let [(sparse_vertices, sparse_faces), (dense_vertices, dense_faces)] = [&meshes[0], &meshes[1]];
        assert!(sparse_faces == dense_faces, "{field}: the triangles differ");
        assert_eq!(sparse_vertices.len(), dense_vertices.len(), "{field}");
        for (s, d) in sparse_vertices.iter().zip(dense_vertices) {
            assert_eq!(s[..3], d[..3], "{field}: positions differ");
            // Normals: the samples' gradient where the dense run may take the field's.
            let dot: f32 = (0..3).map(|a| s[3 + a] * d[3 + a]).sum();
            assert!(dot > 0.98, "{field}: normals {s:?} and {d:?}");
        }
    }
}

/// The vertices (position and normal) and the face bytes of a binary PLY isolab wrote.
fn binary_ply(path: &Path) -> (Vec<[f32; 6]>, Vec<u8>) {
    let bytes = std::fs::read(path).unwrap();
    let end = bytes.windows(11).position(|w| w == b"end_header\n").unwrap() + 11;
    let header = String::from_utf8_lossy(&bytes[..end]);
    let count: usize = header.lines().find_map(|l| l.strip_prefix("element vertex ")).unwrap().trim().parse().unwrap();
    assert!(header.contains("property float nx"), "{header}");
    let vertex = |k: usize| {
        std::array::from_fn(|c| {
            let at = end + 24 * k + 4 * c;
            f32::from_le_bytes(bytes[at..at + 4].try_into().unwrap())
        })
    };
    ((0..count).map(vertex).collect(), bytes[end + 24 * count..].to_vec())
}

#[test]
fn large_grids_of_certified_fields_are_sampled_near_the_surface_unasked() {
    let o = isolab(&["extract", "-a", "marching-cubes", "-f", "sphere", "-r", "600"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let report: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(report["sparse"]["evaluations"].as_u64().unwrap() * 15 < 600 * 600 * 600, "{}", report["sparse"]);
    // Small grids stay dense: as fast or faster there.
    let o = isolab(&["extract", "-a", "marching-cubes", "-f", "sphere", "-r", "64"]);
    let report: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(report.get("sparse").is_none());
}

#[test]
fn sparse_runs_that_cannot_be_certified_or_lose_the_samples_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let samples = dir.path().join("s.raw").to_string_lossy().into_owned();
    let base = ["extract", "-f", "sphere", "-r", "33", "--sparse"];
    let with = |extra: &[&str]| isolab(&[&base[..], extra].concat());
    assert_clean_failure(&with(&["-a", "marching-cubes", "--post", "edge-collapse"]), 1, &["sparsely", "post-processes"]);
    assert_clean_failure(&with(&["-a", "marching-cubes", "--materials"]), 1, &["sparsely", "--materials"]);
    assert_clean_failure(&with(&["-a", "marching-cubes", "--lattice", "bcc"]), 1, &["sparsely", "BCC"]);
    assert_clean_failure(&with(&["-a", "bcc-sculpt"]), 1, &["sparsely", "bcc-sculpt", "blocks"]);
    assert_clean_failure(&with(&["-a", "marching-cubes", "--samples-out", &samples]), 1, &["sparsely", "--samples-out"]);
    assert!(!Path::new(&samples).exists());
    let o = isolab(&["extract", "-a", "marching-cubes", "-f", "sphere", "--sparse", "--dense"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    // A bound that is not a positive number is refused: 0 would rule out every block.
    for bad in ["0", "inf", "NaN"] {
        assert_clean_failure(&with(&["-a", "marching-cubes", "--lipschitz", bad]), 1, &["--lipschitz", "positive finite"]);
    }
    // A bound given replaces the field's own, and is reported as given.
    let o = with(&["-a", "marching-cubes", "--lipschitz", "2.5"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let report: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(report["sparse"]["lipschitz"].as_f64(), Some(2.5));
    assert_eq!(report["sparse"]["field_bound"], serde_json::Value::Bool(false));
}
