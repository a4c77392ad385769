//! The STL reader (ascii and binary) on arbitrary bytes.
#![no_main]
use isolab_io::stl::parse_stl;
use isolab_io::Coordinates;
use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    if let Ok(mesh) = parse_stl(data, Path::new("fuzz.stl"), Coordinates::Finite) {
        let n = mesh.positions.len() as u32;
        assert!(mesh.triangles.iter().flatten().all(|&i| i < n));
        assert!(mesh.positions.iter().all(|p| p.is_finite()));
    }
});
