//! The glTF reader (`.glb` and `.gltf` with embedded buffers) on arbitrary bytes; external
//! buffers are refused.
#![no_main]
use isolab_io::gltf::parse_gltf;
use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let none = |_: &str| -> Result<Vec<u8>, String> { Err("no external buffers while fuzzing".into()) };
    for name in ["fuzz.glb", "fuzz.gltf"] {
        if let Ok(mesh) = parse_gltf(data, Path::new(name), &none) {
            let n = mesh.positions.len() as u32;
            assert!(mesh.triangles.iter().flatten().all(|&i| i < n));
        }
    }
});
