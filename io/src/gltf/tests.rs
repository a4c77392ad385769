use super::*;

/// Decodes what `write_glb_quantized` wrote: positions (node transform applied) and triangles.
fn decode_quantized(bytes: &[u8]) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let glb = gltf::binary::Glb::from_slice(bytes).unwrap();
    let doc: serde_json::Value = serde_json::from_slice(&glb.json).unwrap();
    assert_eq!(doc["extensionsRequired"][0], "KHR_mesh_quantization");
    let bin = glb.bin.unwrap();
    let v3 = |v: &serde_json::Value| {
        Vec3::new(v[0].as_f64().unwrap() as f32, v[1].as_f64().unwrap() as f32, v[2].as_f64().unwrap() as f32)
    };
    let (t, s) = (v3(&doc["nodes"][0]["translation"]), v3(&doc["nodes"][0]["scale"]));
    let view = &doc["bufferViews"][1];
    let (offset, n) = (view["byteOffset"].as_u64().unwrap() as usize, doc["accessors"][1]["count"].as_u64().unwrap() as usize);
    let short = |at: usize| f32::from(u16::from_le_bytes([bin[at], bin[at + 1]]));
    let positions =
        (0..n).map(|k| t + s * Vec3::new(short(offset + 8 * k), short(offset + 8 * k + 2), short(offset + 8 * k + 4))).collect();
    let wide = doc["accessors"][0]["componentType"] == UNSIGNED_INT;
    let count = doc["accessors"][0]["count"].as_u64().unwrap() as usize;
    let index = |k: usize| {
        if wide {
            u32::from_le_bytes([bin[4 * k], bin[4 * k + 1], bin[4 * k + 2], bin[4 * k + 3]])
        } else {
            u32::from(u16::from_le_bytes([bin[2 * k], bin[2 * k + 1]]))
        }
    };
    let triangles = (0..count / 3).map(|t| [index(3 * t), index(3 * t + 1), index(3 * t + 2)]).collect();
    (positions, triangles)
}

#[test]
fn quantized_glb_round_trips_within_half_a_step_and_is_smaller() {
    let mut mesh = tetrahedron();
    mesh.positions =
        vec![Vec3::new(-1.5, 0.25, 3.0), Vec3::new(2.0, 0.3, 3.1), Vec3::new(0.1, 7.0, 2.9), Vec3::new(0.7, 1.0, -4.0)];
    let mut q = Vec::new();
    write_glb_quantized(&mut q, &mesh, "test").unwrap();
    let (positions, triangles) = decode_quantized(&q);
    assert_eq!(triangles, mesh.triangles);
    let step = Vec3::new(3.5, 6.75, 7.1) / QUANT_MAX;
    for (a, b) in positions.iter().zip(&mesh.positions) {
        assert!(((*a - *b).abs() - 0.51 * step).max_element() <= 1e-6, "{a} {b}");
    }
    let mut full = Vec::new();
    write_gltf(&mut full, &mesh, None, Container::Binary, "test").unwrap();
    assert!(q.len() < full.len(), "{} >= {}", q.len(), full.len());
    let big = TriMesh {
        positions: (0..70_000).map(|k| Vec3::new(k as f32, 0.0, (k % 7) as f32)).collect(),
        normals: vec![],
        triangles: vec![[0, 1, 69_999]],
    };
    let mut wide = Vec::new();
    write_glb_quantized(&mut wide, &big, "test").unwrap();
    assert_eq!(decode_quantized(&wide).1, big.triangles, "32-bit indices past 65535 vertices");
}

fn tetrahedron() -> TriMesh {
    TriMesh::unit_tetrahedron()
}

#[test]
fn both_containers_round_trip() {
    let colours = [[255, 0, 0], [0, 255, 0], [0, 0, 255], [9, 9, 9]];
    for container in [Container::Binary, Container::Embedded] {
        let mut bytes = Vec::new();
        write_gltf(&mut bytes, &tetrahedron(), Some(&colours), container, "isolab test").unwrap();
        let back = parse_gltf(&bytes, Path::new("t.glb"), &|_| Err("no files".into())).unwrap();
        assert_eq!(back.positions, tetrahedron().positions, "{container:?}");
        assert_eq!(back.triangles, tetrahedron().triangles, "{container:?}");
    }
}

#[test]
fn an_empty_mesh_is_a_valid_empty_scene_and_reads_back_as_empty() {
    let mut bytes = Vec::new();
    write_gltf(&mut bytes, &TriMesh::default(), None, Container::Binary, "isolab").unwrap();
    let e = parse_gltf(&bytes, Path::new("e.glb"), &|_| Err("no".into()));
    assert!(matches!(e, Err(IoError::Empty { .. })), "{e:?}");
}

#[test]
fn corrupt_files_are_errors_naming_the_file() {
    let mut bytes = Vec::new();
    write_gltf(&mut bytes, &tetrahedron(), None, Container::Binary, "isolab").unwrap();
    for cut in [10, 40, bytes.len() - 8] {
        let e = parse_gltf(&bytes[..cut], Path::new("cut.glb"), &|_| Err("no".into())).unwrap_err().to_string();
        assert!(e.contains("cut.glb"), "{e}");
    }
    let e = parse_gltf(
        b"{\"asset\":{\"version\":\"2.0\"},\"buffers\":[{\"byteLength\":8,\"uri\":\"x.bin\"}]}",
        Path::new("x.gltf"),
        &|u| Err(format!("refused {u}")),
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("refused x.bin"), "{e}");
}
