//! Figures: plots of measurements (`plot`); pictures of meshes come from the CLI's renderer
//! (`isolab_render`, re-exported here as `render`). They live here, not in `metrics`,
//! because they write files; `metrics` stays a light, read-only library.

pub mod plot;
pub mod prune;
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

/// The one table of implementation colours: every registered extractor and every peer the
/// report's charts draw, by [`implementation_key`], so an implementation has one colour on every
/// chart (libigl grey, VTK's flying edges cyan, ...). Ours keep the colours the report's figures
/// have always given them; a peer takes a shade apart from the extractors.
const NAMED: [(&str, (u8, u8, u8)); 34] = [
    ("marching cubes", PALETTE[0]),
    ("marching cubes decider", PALETTE[1]),
    ("surface nets", PALETTE[2]),
    ("dual contouring", PALETTE[3]),
    ("marching tetrahedra", PALETTE[4]),
    ("regularised marching tetrahedra", PALETTE[5]),
    ("bcc sculpt", PALETTE[6]),
    ("marching cubes 33", (0x39, 0x3b, 0x79)),
    ("manifold dual contouring", (0xbd, 0x9e, 0x39)),
    ("isosurface stuffing", (0xa5, 0x51, 0x94)),
    // Ours as the Python package and the CLI name them.
    ("isolab marching cubes", PALETTE[0]),
    ("isolab lorensen", PALETTE[0]),
    ("isolab lewiner", MORE[2]),
    ("isolab surface nets", PALETTE[2]),
    // Peers.
    ("vtk flying edges", PALETTE[7]),
    ("vtk flying edges + normals", MORE[9]),
    ("vtk marching cubes", (0x31, 0x82, 0xbd)),
    ("pyvista contour", (0x63, 0x79, 0x39)),
    ("libigl", MORE[0]),
    ("pymcubes", MORE[1]),
    ("skimage lorensen", MORE[3]),
    ("skimage lewiner", MORE[6]),
    ("zmesh", MORE[7]),
    ("meshlib", MORE[8]),
    ("warp lang (cpu)", MORE[11]),
    ("marching cubes numpy", MORE[10]),
    ("fast surface nets", MORE[4]),
    ("isosurface crate", MORE[5]),
    ("cgal edge collapse (lindstrom turk)", (0x84, 0x3c, 0x39)),
    ("openmesh decimater (quadric)", (0x7b, 0x41, 0x73)),
    ("pymeshlab quadric edge collapse", (0x52, 0x54, 0xa3)),
    ("edge collapse (paper sweep, 0.5 h)", (0xe7, 0xba, 0x52)),
    ("edge collapse safe (shortest first)", (0x6b, 0x6e, 0xcf)),
    ("edge collapse safe, intersections=allow", (0xd6, 0x61, 0x6b)),
];

/// Aliases: a peer named two ways across the experiments (its key after [`implementation_key`]).
const ALIASES: [(&str, &str); 2] = [("vtk vtkflyingedges3d", "vtk flying edges"), ("libigl signed distance", "libigl")];

/// An implementation's name as the colour table knows it: lower case, `-` and `_` as spaces, a
/// thread count suffix (` (2 threads)`) dropped, aliases resolved; and whether the suffix named
/// more than one thread.
pub fn implementation_key(label: &str) -> (String, bool) {
    let mut key = label.trim().to_lowercase().replace(['-', '_'], " ");
    let mut threaded = false;
    if let Some(open) = key.rfind(" (") {
        let suffix = &key[open + 2..];
        if suffix.ends_with(" thread)") || suffix.ends_with(" threads)") {
            threaded = !suffix.starts_with("1 ");
            key.truncate(open);
        }
    }
    if let Some((_, to)) = ALIASES.iter().find(|(from, _)| *from == key) {
        key = (*to).to_owned();
    }
    (key, threaded)
}

/// The colour of an implementation (an extractor, a peer, or any name), the same on every chart:
/// `NAMED`'s for the implementations it lists, a darker shade of it for a run on more than one
/// thread, otherwise a hue from a hash of the name (FNV-1a), so a new extractor gets its own
/// colour without a line here and without recolouring the others.
pub fn color_of(name: &str) -> (u8, u8, u8) {
    let (key, threaded) = implementation_key(name);
    let base = match NAMED.iter().find(|(n, _)| *n == key) {
        Some((_, c)) => *c,
        None => {
            let hash = key.bytes().fold(0xcbf29ce484222325u64, |h, b| (h ^ u64::from(b)).wrapping_mul(0x100000001b3));
            hsv((hash % 360) as f32, 0.65, 0.8)
        }
    };
    if threaded {
        let dark = |v: u8| (f32::from(v) * 0.6).round() as u8;
        (dark(base.0), dark(base.1), dark(base.2))
    } else {
        base
    }
}

/// Whether the colour table lists `label` (by [`implementation_key`]).
pub fn has_named_color(label: &str) -> bool {
    let key = implementation_key(label).0;
    NAMED.iter().any(|(n, _)| *n == key)
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
    fn an_implementation_has_one_colour_on_every_chart() {
        assert_eq!(color_of("pymcubes (1 thread)"), color_of("PyMCubes"));
        assert_eq!(color_of("skimage-lewiner (1 thread)"), color_of("skimage lewiner"));
        assert_eq!(color_of("VTK vtkFlyingEdges3D (1 thread)"), color_of("VTK flying edges"));
        assert_eq!(color_of("isolab marching-cubes (1 thread)"), color_of("marching-cubes"));
        assert_ne!(color_of("VTK vtkFlyingEdges3D (2 threads)"), color_of("VTK vtkFlyingEdges3D (1 thread)"));
        assert_eq!(implementation_key("warp-lang (CPU)"), ("warp lang (cpu)".to_owned(), false));
        // Apart from ours under their Python names, every entry has a colour of its own.
        let ours_again = ["isolab marching cubes", "isolab lorensen", "isolab surface nets"];
        let entries: Vec<&(&str, (u8, u8, u8))> = NAMED.iter().filter(|(n, _)| !ours_again.contains(n)).collect();
        for (i, (a, ca)) in entries.iter().enumerate() {
            for (b, cb) in entries.iter().skip(i + 1) {
                assert_ne!(ca, cb, "{a} and {b} share a colour");
            }
        }
    }

    #[test]
    fn every_implementation_the_committed_data_chart_has_a_colour_from_the_table() {
        let data = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../report/data");
        let read = |name: &str| -> serde_json::Value {
            serde_json::from_str(&std::fs::read_to_string(data.join(name)).unwrap()).unwrap()
        };
        let mut labels: Vec<String> = Vec::new();
        for (file, list, key) in [
            ("peers.json", "timings", "implementation"),
            ("python_users.json", "rows", "implementation"),
            ("decimation.json", "rows", "decimator"),
        ] {
            let v = read(file);
            labels.extend(v[list].as_array().unwrap().iter().map(|r| r[key].as_str().unwrap().to_owned()));
        }
        labels.extend(isolab_algorithms::extractors::INFOS.iter().map(|i| i.name.to_owned()));
        let charted = |l: &String| !l.contains(" CLI");
        let missing: Vec<&String> = labels.iter().filter(|l| charted(l) && !has_named_color(l)).collect();
        assert!(missing.is_empty(), "no colour in the table for {missing:?}");
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
