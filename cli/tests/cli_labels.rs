//! `isolab labels`: a label map file to one mesh per label (a folder of files, or one `.glb`),
//! neighbouring labels sharing their interface triangles; bad input refused with the input named
//! and nothing written.

use crate::common::{isolab, stderr};
use isolab_algorithms::TriMesh;
use std::collections::HashSet;
use std::path::Path;

/// A raw NRRD of `dims` samples of `kind` ("uint8", "float") from little-endian `data`.
fn nrrd(path: &Path, kind: &str, dims: [usize; 3], data: &[u8]) {
    let mut bytes = format!(
        "NRRD0004\ntype: {kind}\ndimension: 3\nsizes: {} {} {}\nencoding: raw\nendian: little\n\n",
        dims[0], dims[1], dims[2]
    )
    .into_bytes();
    bytes.extend_from_slice(data);
    std::fs::write(path, bytes).unwrap();
}

/// Labels 1 and 2 side by side and a lone label 5, in a 10 x 8 x 8 map.
fn three_labels(dir: &Path) -> std::path::PathBuf {
    let dims = [10, 8, 8];
    let mut data = vec![0u8; 640];
    for z in 2..6 {
        for y in 2..6 {
            for x in 1..9 {
                data[x + 10 * (y + 8 * z)] = if x < 5 { 1 } else { 2 };
            }
        }
    }
    data[5 + 10 * (6 + 8 * 6)] = 5;
    let path = dir.join("seg.nrrd");
    nrrd(&path, "uint8", dims, &data);
    path
}

/// Triangles as sets of vertex positions (bit patterns), for matching across meshes.
fn triangle_set(mesh: &TriMesh) -> HashSet<Vec<[u32; 3]>> {
    mesh.triangles
        .iter()
        .map(|t| {
            let mut v: Vec<[u32; 3]> = t.iter().map(|&i| mesh.positions[i as usize].to_array().map(f32::to_bits)).collect();
            v.sort_unstable();
            v
        })
        .collect()
}

fn closed_outward(mesh: &TriMesh, what: &str) {
    let t = isolab_metrics::topology::topology(mesh);
    assert!(t.closed && t.edge_manifold && t.vertex_manifold && t.outward, "{what}: {t:#?}");
}

#[test]
fn a_folder_gets_one_closed_mesh_per_label_sharing_interfaces() {
    let dir = tempfile::tempdir().unwrap();
    let seg = three_labels(dir.path());
    let out = dir.path().join("meshes");
    let m = dir.path().join("m.json");
    for algorithm in ["surface-nets", "marching-tetrahedra", "lattice-cleaving"] {
        let o = isolab(&[
            "labels",
            "-f",
            seg.to_str().unwrap(),
            "-a",
            algorithm,
            "-o",
            out.to_str().unwrap(),
            "-m",
            m.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        let meshes: Vec<TriMesh> =
            [1, 2, 5].iter().map(|l| isolab_io::read_mesh(&out.join(format!("seg-label-{l}.ply"))).unwrap()).collect();
        for (mesh, l) in meshes.iter().zip([1, 2, 5]) {
            closed_outward(mesh, &format!("{algorithm} label {l}"));
        }
        // The 1|2 interface: the same triangles in both files.
        let (one, two) = (triangle_set(&meshes[0]), triangle_set(&meshes[1]));
        let shared = one.intersection(&two).count();
        assert!(shared >= 2 * 16, "{algorithm}: {shared} shared triangles");
        let json: serde_json::Value = serde_json::from_slice(&std::fs::read(&m).unwrap()).unwrap();
        let rows = json.as_array().unwrap();
        assert_eq!(rows.len(), 3);
        assert!(rows.iter().all(|r| r["closed"] == true), "{json}");
        assert_eq!(rows[0]["neighbours"]["2"].as_u64(), Some(shared as u64), "{algorithm}: {json}");
        assert_eq!(rows[2]["samples"], 1);
    }
}

#[test]
fn lattice_cleaving_writes_labelled_tetrahedra_as_vtk() {
    let dir = tempfile::tempdir().unwrap();
    let seg = three_labels(dir.path());
    let vtk = dir.path().join("seg-tets.vtk");
    let o = isolab(&["labels", "-f", seg.to_str().unwrap(), "-a", "lattice-cleaving", "-o", vtk.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = std::fs::read_to_string(&vtk).unwrap();
    let mut lines = text.lines();
    let points: usize =
        lines.by_ref().find_map(|l| l.strip_prefix("POINTS ")).unwrap().split(' ').next().unwrap().parse().unwrap();
    let positions: Vec<[f64; 3]> = lines
        .by_ref()
        .take(points)
        .map(|l| {
            let v: Vec<f64> = l.split(' ').map(|x| x.parse().unwrap()).collect();
            [v[0], v[1], v[2]]
        })
        .collect();
    let cells: usize = lines.next().unwrap().strip_prefix("CELLS ").unwrap().split(' ').next().unwrap().parse().unwrap();
    let tets: Vec<[usize; 4]> = lines
        .by_ref()
        .take(cells)
        .map(|l| {
            let v: Vec<usize> = l.split(' ').map(|x| x.parse().unwrap()).collect();
            assert_eq!(v[0], 4);
            [v[1], v[2], v[3], v[4]]
        })
        .collect();
    let rest: Vec<&str> = lines.collect();
    let at = rest.iter().position(|l| l.starts_with("CELL_DATA")).unwrap();
    assert_eq!(rest[at], format!("CELL_DATA {cells}"));
    assert_eq!(rest[at + 1], "SCALARS label unsigned_int 1");
    let labels: Vec<u32> = rest[at + 3..].iter().map(|l| l.parse().unwrap()).collect();
    assert_eq!(labels.len(), cells);
    // Every tetrahedron positive; each label's volume near its samples' count (the map's
    // spacing is one).
    let mut volume = std::collections::BTreeMap::new();
    for (t, l) in tets.iter().zip(&labels) {
        let [a, b, c, d] = t.map(|i| glam::DVec3::from(positions[i]));
        let v = (b - a).dot((c - a).cross(d - a)) / 6.0;
        assert!(v > 0.0, "{t:?}");
        *volume.entry(*l).or_insert(0.0) += v;
    }
    assert_eq!(volume.keys().copied().collect::<Vec<_>>(), [1, 2, 5]);
    assert!((volume[&1] - 64.0).abs() < 0.15 * 64.0 && (volume[&2] - 64.0).abs() < 0.15 * 64.0, "{volume:?}");
    // A surface extractor has no tetrahedra: refused before any work, nothing written.
    let refused = dir.path().join("nets.vtk");
    let o = isolab(&["labels", "-f", seg.to_str().unwrap(), "-o", refused.to_str().unwrap()]);
    assert!(o.status.code() == Some(1) && stderr(&o).contains("lattice-cleaving") && !refused.exists(), "{}", stderr(&o));
    // Lattice cleaving meshes closed borders only, and says so.
    let o = isolab(&["labels", "-f", seg.to_str().unwrap(), "-a", "lattice-cleaving", "--set", "border=open"]);
    assert!(o.status.code() == Some(2) && stderr(&o).contains("closed"), "{}", stderr(&o));
}

#[test]
fn lattice_cleaving_writes_the_same_tetrahedra_as_gmsh_msh() {
    let dir = tempfile::tempdir().unwrap();
    let seg = three_labels(dir.path());
    let write = |name: &str| {
        let path = dir.path().join(name);
        let o = isolab(&["labels", "-f", seg.to_str().unwrap(), "-a", "lattice-cleaving", "-o", path.to_str().unwrap()]);
        assert!(o.status.success(), "{}", stderr(&o));
        std::fs::read_to_string(path).unwrap()
    };
    let (vtk, msh) = (write("seg.vtk"), write("seg.msh"));
    let section = |text: &str, name: &str| -> Vec<String> {
        let mut lines = text.lines().skip_while(|l| *l != format!("${name}")).skip(1);
        let n: usize = lines.next().unwrap().parse().unwrap();
        lines.by_ref().take(n).map(str::to_owned).collect()
    };
    assert_eq!(section(&msh, "PhysicalNames"), ["3 1 \"label 1\"", "3 2 \"label 2\"", "3 5 \"label 5\""]);
    // Nodes and tetrahedra are the .vtk's, numbered from one; each tetrahedron tagged by its label.
    let points = vtk.lines().skip_while(|l| !l.starts_with("POINTS")).skip(1);
    let nodes = section(&msh, "Nodes");
    assert_eq!(
        nodes.len(),
        vtk.lines().find_map(|l| l.strip_prefix("POINTS ")).unwrap().split(' ').next().unwrap().parse::<usize>().unwrap()
    );
    for (i, (node, point)) in nodes.iter().zip(points).enumerate() {
        assert_eq!(*node, format!("{} {point}", i + 1));
    }
    let cells: Vec<&str> =
        vtk.lines().skip_while(|l| !l.starts_with("CELLS")).skip(1).take_while(|l| l.starts_with("4 ")).collect();
    let labels: Vec<&str> = vtk.lines().skip_while(|l| *l != "LOOKUP_TABLE default").skip(1).collect();
    let elements = section(&msh, "Elements");
    assert_eq!((elements.len(), labels.len()), (cells.len(), cells.len()));
    for (i, ((element, cell), label)) in elements.iter().zip(&cells).zip(&labels).enumerate() {
        let one_based: Vec<String> = cell.split(' ').skip(1).map(|v| (v.parse::<u32>().unwrap() + 1).to_string()).collect();
        assert_eq!(*element, format!("{} 4 2 {label} {label} {}", i + 1, one_based.join(" ")));
    }
    // A surface extractor has no tetrahedra: refused before any work, nothing written.
    let refused = dir.path().join("nets.msh");
    let o = isolab(&["labels", "-f", seg.to_str().unwrap(), "-o", refused.to_str().unwrap()]);
    assert!(o.status.code() == Some(1) && stderr(&o).contains(".msh output") && !refused.exists(), "{}", stderr(&o));
}

#[test]
fn a_glb_gets_a_named_node_per_label() {
    let dir = tempfile::tempdir().unwrap();
    let seg = three_labels(dir.path());
    let glb = dir.path().join("seg.glb");
    let o = isolab(&["labels", "-f", seg.to_str().unwrap(), "-o", glb.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let bytes = std::fs::read(&glb).unwrap();
    let json_len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    let doc: serde_json::Value = serde_json::from_slice(&bytes[20..20 + json_len]).unwrap();
    let names: Vec<&str> = doc["nodes"].as_array().unwrap().iter().map(|n| n["name"].as_str().unwrap()).collect();
    assert_eq!(names, ["label 1", "label 2", "label 5"]);
    assert_eq!(doc["materials"].as_array().unwrap().len(), 3);
    // The reader takes every node: the three meshes together.
    let all = isolab_io::read_mesh(&glb).unwrap();
    assert!(all.triangles.len() > 100);
}

#[test]
fn bad_label_input_is_refused_with_nothing_written() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let out = d.join("out.glb");
    // An intensity volume (fractional floats).
    let floats: Vec<u8> = (0..64).flat_map(|i| (i as f32 * 0.37).to_le_bytes()).collect();
    let scan = d.join("scan.nrrd");
    nrrd(&scan, "float", [4, 4, 4], &floats);
    let o = isolab(&["labels", "-f", scan.to_str().unwrap(), "-o", out.to_str().unwrap()]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("scan") && err.contains("intensity volume") && err.contains("isolab extract"), "{err}");
    assert!(!err.contains("panicked") && !out.exists(), "{err}");
    // Whole-number floats are labels, with a note.
    let whole: Vec<u8> = (0..64).flat_map(|i| f32::from(u8::from(i % 3 == 0)).to_le_bytes()).collect();
    nrrd(&scan, "float", [4, 4, 4], &whole);
    let o = isolab(&["labels", "-f", scan.to_str().unwrap(), "-o", out.to_str().unwrap()]);
    assert!(o.status.success() && stderr(&o).contains("whole number"), "{}", stderr(&o));
    // A single mesh file that is not a .glb, an unknown algorithm, an absent label.
    let seg = three_labels(d);
    let ply = d.join("one.ply");
    let o = isolab(&["labels", "-f", seg.to_str().unwrap(), "-o", ply.to_str().unwrap()]);
    assert!(o.status.code() == Some(1) && stderr(&o).contains("folder") && !ply.exists(), "{}", stderr(&o));
    let o = isolab(&["labels", "-f", seg.to_str().unwrap(), "-a", "marching-cubes"]);
    assert!(
        o.status.code() == Some(2) && stderr(&o).contains("surface-nets, marching-tetrahedra, lattice-cleaving"),
        "{}",
        stderr(&o)
    );
    let folder = d.join("some");
    let o = isolab(&["labels", "-f", seg.to_str().unwrap(), "--labels", "2,9", "-o", folder.to_str().unwrap()]);
    assert!(o.status.success() && stderr(&o).contains("[9] do not occur"), "{}", stderr(&o));
    let written: Vec<String> =
        std::fs::read_dir(&folder).unwrap().map(|e| e.unwrap().file_name().into_string().unwrap()).collect();
    assert_eq!(written, ["seg-label-2.ply"]);
}

/// A manifest's fragment sizes per level (the spec's layout), for checking what the CLI wrote.
fn manifest_sizes(bytes: &[u8]) -> Vec<Vec<u32>> {
    let word = |i: usize| u32::from_le_bytes(bytes[4 * i..4 * i + 4].try_into().unwrap());
    let lods = word(6) as usize;
    let counts: Vec<usize> = (0..lods).map(|l| word(7 + 4 * lods + l) as usize).collect();
    let mut at = 7 + 5 * lods;
    let mut out = Vec::new();
    for n in counts {
        at += 3 * n;
        out.push((0..n).map(|i| word(at + i)).collect());
        at += n;
    }
    assert_eq!(4 * at, bytes.len(), "the manifest's length");
    out
}

#[test]
fn neuroglancer_sources_are_written_unsharded_and_sharded() {
    let dir = tempfile::tempdir().unwrap();
    let seg = three_labels(dir.path());
    let out = dir.path().join("ng");
    let o =
        isolab(&["labels", "-f", seg.to_str().unwrap(), "--format", "neuroglancer", "--chunk", "4", "-o", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let info: serde_json::Value = serde_json::from_slice(&std::fs::read(out.join("info")).unwrap()).unwrap();
    assert_eq!(info["@type"], "neuroglancer_multilod_draco");
    assert_eq!(info["vertex_quantization_bits"], 16);
    for label in [1, 2, 5] {
        let sizes = manifest_sizes(&std::fs::read(out.join(format!("{label}.index"))).unwrap());
        // 3 x 3 x 3 boxes of 4 cells (11 and 9 cells with the closed border): three levels.
        assert_eq!(sizes.len(), 3, "label {label}");
        assert_eq!(sizes[2].len(), 1, "label {label}: one box at the top");
        let total: u64 = sizes.iter().flatten().map(|&n| u64::from(n)).sum();
        assert_eq!(std::fs::metadata(out.join(label.to_string())).unwrap().len(), total, "label {label}");
    }
    assert!(!out.join(".isolab-work").exists());
    let sharded = dir.path().join("sharded");
    let o = isolab(&[
        "labels",
        "-f",
        seg.to_str().unwrap(),
        "--format",
        "neuroglancer",
        "--sharded",
        "--lods",
        "2",
        "-o",
        sharded.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let info: serde_json::Value = serde_json::from_slice(&std::fs::read(sharded.join("info")).unwrap()).unwrap();
    assert_eq!(info["sharding"]["hash"], "murmurhash3_x86_128");
    assert!(sharded.join("0.shard").is_file());
    // The legacy format: a float fragment per block and label, each label's `<label>:0` naming them.
    let legacy = dir.path().join("legacy");
    let o = isolab(&[
        "labels",
        "-f",
        seg.to_str().unwrap(),
        "--format",
        "neuroglancer-legacy",
        "--chunk",
        "4",
        "-o",
        legacy.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let info: serde_json::Value = serde_json::from_slice(&std::fs::read(legacy.join("info")).unwrap()).unwrap();
    assert_eq!(info["@type"], "neuroglancer_legacy_mesh");
    for label in [1, 2, 5] {
        let m: serde_json::Value = serde_json::from_slice(&std::fs::read(legacy.join(format!("{label}:0"))).unwrap()).unwrap();
        let names = m["fragments"].as_array().unwrap();
        assert!(!names.is_empty(), "label {label}");
        for name in names {
            let bytes = std::fs::read(legacy.join(name.as_str().unwrap())).unwrap();
            let nv = u32::from_le_bytes(bytes[..4].try_into().unwrap()) as usize;
            assert!(nv > 0 && (bytes.len() - 4 - 12 * nv) % 12 == 0, "label {label}: {name}");
        }
    }
    // Bad settings: refused before anything is written.
    for (flag, value, says) in
        [("--quantization-bits", "12", "10 or 16"), ("--lods", "0", "1 to 16"), ("--chunk", "1", "2 cells")]
    {
        let none = dir.path().join(format!("none{flag}"));
        let o = isolab(&[
            "labels",
            "-f",
            seg.to_str().unwrap(),
            "--format",
            "neuroglancer",
            flag,
            value,
            "-o",
            none.to_str().unwrap(),
        ]);
        let err = stderr(&o);
        assert!(o.status.code() == Some(1) && err.contains(says) && err.contains("neuroglancer") && !none.exists(), "{err}");
    }
    let file = dir.path().join("ng.ply");
    let o = isolab(&["labels", "-f", seg.to_str().unwrap(), "--format", "neuroglancer", "-o", file.to_str().unwrap()]);
    assert!(o.status.code() == Some(1) && stderr(&o).contains("folder") && !file.exists(), "{}", stderr(&o));
}
