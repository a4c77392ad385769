//! The PLY reader (ascii and binary, any property types) on arbitrary bytes.
#![no_main]
use isolab_io::{parse_ply, Coordinates};
use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    if let Ok(mesh) = parse_ply(data, Path::new("fuzz.ply"), Coordinates::Finite) {
        let n = mesh.positions.len() as u32;
        assert!(mesh.triangles.iter().flatten().all(|&i| i < n));
        assert!(mesh.positions.iter().all(|p| p.is_finite()));
    }
});
