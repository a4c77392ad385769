//! Format detection plus every mesh reader: the bytes go wherever their content sends them.
#![no_main]
use isolab_io::{parse_mesh, Coordinates};
use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    if let Ok(mesh) = parse_mesh(data, Path::new("fuzz.mesh"), Coordinates::Finite) {
        let n = mesh.positions.len() as u32;
        assert!(mesh.triangles.iter().flatten().all(|&i| i < n));
        assert!(mesh.positions.iter().all(|p| p.is_finite()));
    }
});
