//! Figures: plots of measurements (`plot`) and pictures of meshes (`render`). They live here,
//! not in `metrics`, because they write files; `metrics` stays a light, read-only library.

pub mod plot;
pub mod render;

/// Fixed colours per algorithm, by position in the extractor registry, so every figure agrees.
pub const PALETTE: [(u8, u8, u8); 8] = [
    (0x1f, 0x77, 0xb4),
    (0xd6, 0x27, 0x28),
    (0x2c, 0xa0, 0x2c),
    (0xff, 0x7f, 0x0e),
    (0x94, 0x67, 0xbd),
    (0x8c, 0x56, 0x4b),
    (0xe3, 0x77, 0xc2),
    (0x17, 0xbe, 0xcf),
];

/// The colour of an algorithm (or any name): its registry position, else a stable hash.
pub fn color_of(name: &str) -> (u8, u8, u8) {
    let names: Vec<&'static str> = isolab_algorithms::extractors::registry().iter().map(|e| e.name()).collect();
    let i = names.iter().position(|n| *n == name).unwrap_or_else(|| name.bytes().map(usize::from).sum::<usize>());
    PALETTE[i % PALETTE.len()]
}
