//! The OBJ reader on arbitrary bytes (as text when they are UTF-8, as the CLI reads them): an
//! error or a mesh with finite positions and indices in range, never a panic.
#![no_main]
use isolab_io::{parse_obj, Coordinates};
use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        if let Ok(mesh) = parse_obj(text, Path::new("fuzz.obj"), Coordinates::Finite) {
            let n = mesh.positions.len() as u32;
            assert!(mesh.triangles.iter().flatten().all(|&i| i < n));
            assert!(mesh.positions.iter().all(|p| p.is_finite()));
        }
    }
});
