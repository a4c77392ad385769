//! Figures: plots of measurements (`plot`); pictures of meshes come from the CLI's renderer
//! (`isolab_render`, re-exported here as `render`). They live here, not in `metrics`,
//! because they write files; `metrics` stays a light, read-only library.

pub mod plot;
pub use isolab_render as render;

/// Eight distinct colours (Tableau's), for series that are not algorithms.
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

/// Twelve more, after [`PALETTE`]: the rest of Tableau's twenty (its grey and olive, then the
/// light shades of the eight), so that a figure of up to twenty series repeats no colour.
const MORE: [(u8, u8, u8); 12] = [
    (0x7f, 0x7f, 0x7f),
    (0xbc, 0xbd, 0x22),
    (0xae, 0xc7, 0xe8),
    (0xff, 0x98, 0x96),
    (0x98, 0xdf, 0x8a),
    (0xff, 0xbb, 0x78),
    (0xc5, 0xb0, 0xd5),
    (0xc4, 0x9c, 0x94),
    (0xf7, 0xb6, 0xd2),
    (0x9e, 0xda, 0xe5),
    (0xc7, 0xc7, 0xc7),
    (0xdb, 0xdb, 0x8d),
];

/// The colour of series `k` of a figure that is not about the registered algorithms: distinct for
/// the first twenty, then hues from the golden angle.
pub fn series_color(k: usize) -> (u8, u8, u8) {
    match k {
        _ if k < PALETTE.len() => PALETTE[k],
        _ if k < PALETTE.len() + MORE.len() => MORE[k - PALETTE.len()],
        _ => hsv((k as f32 * 137.508) % 360.0, 0.65, 0.8),
    }
}

/// The colours the report's figures have always given the registered algorithms.
const NAMED: [(&str, (u8, u8, u8)); 7] = [
    ("marching-cubes", PALETTE[0]),
    ("marching-cubes-decider", PALETTE[1]),
    ("surface-nets", PALETTE[2]),
    ("dual-contouring", PALETTE[3]),
    ("marching-tetrahedra", PALETTE[4]),
    ("regularised-marching-tetrahedra", PALETTE[5]),
    ("bcc-sculpt", PALETTE[6]),
];

/// The colour of an algorithm (or any name), the same in every figure and stable as the registry
/// grows: the colours above for the algorithms that have them, otherwise a hue from a hash of
/// the name (FNV-1a), so a new algorithm gets its own colour without a line here and without
/// recolouring the others.
pub fn color_of(name: &str) -> (u8, u8, u8) {
    if let Some((_, c)) = NAMED.iter().find(|(n, _)| *n == name) {
        return *c;
    }
    let hash = name.bytes().fold(0xcbf29ce484222325u64, |h, b| (h ^ u64::from(b)).wrapping_mul(0x100000001b3));
    hsv((hash % 360) as f32, 0.65, 0.8)
}

/// An sRGB colour from hue (degrees), saturation and value in [0, 1].
fn hsv(h: f32, s: f32, v: f32) -> (u8, u8, u8) {
    let c = v * s;
    let x = c * (1.0 - ((h / 60.0) % 2.0 - 1.0).abs());
    let (r, g, b) = match (h / 60.0) as u32 {
        0 => (c, x, 0.0),
        1 => (x, c, 0.0),
        2 => (0.0, c, x),
        3 => (0.0, x, c),
        4 => (x, 0.0, c),
        _ => (c, 0.0, x),
    };
    let to = |u: f32| ((u + v - c) * 255.0).round() as u8;
    (to(r), to(g), to(b))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_registered_algorithm_has_its_own_stable_colour() {
        let names: Vec<&str> = isolab_algorithms::extractors::INFOS.iter().map(|i| i.name).collect();
        let colours: Vec<_> = names.iter().map(|n| color_of(n)).collect();
        for (i, a) in colours.iter().enumerate() {
            for (j, b) in colours.iter().enumerate().skip(i + 1) {
                let d = (a.0 as i32 - b.0 as i32).abs() + (a.1 as i32 - b.1 as i32).abs() + (a.2 as i32 - b.2 as i32).abs();
                assert!(d > 60, "{} and {} look alike: {a:?} {b:?}", names[i], names[j]);
            }
        }
        // A name outside the table gets a saturated colour of its own from its hash.
        let (r, g, b) = color_of("a-new-extractor");
        assert!(r.max(g).max(b) - r.min(g).min(b) > 60, "a new extractor's colour is grey: {:?}", (r, g, b));
        assert_ne!(color_of("a-new-extractor"), color_of("another-new-extractor"));
        assert_eq!(hsv(0.0, 1.0, 1.0), (255, 0, 0));
        assert_eq!(hsv(120.0, 1.0, 1.0), (0, 255, 0));
    }

    #[test]
    fn twenty_series_get_twenty_colours() {
        let colours: Vec<_> = (0..20).map(series_color).collect();
        for (i, a) in colours.iter().enumerate() {
            assert!(colours[i + 1..].iter().all(|b| b != a), "series {i} repeats {a:?}");
        }
        assert_eq!(series_color(0), PALETTE[0]);
    }
}
