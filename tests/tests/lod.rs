//! Levels of detail: marching cubes chunks at full and half resolution, stitched at their seams.
//! Over random terrains and random level patterns, no boundary edge is left anywhere but on the
//! world's boundary, every edge has at most two triangles, and no seam edge goes unmatched.

use isolab_algorithms::fields::{self, FieldParams};
use isolab_algorithms::lod::{extract_lod, open_edges_away_from_bounds, open_edges_off_bounds};
use isolab_algorithms::{extractors, Extraction, Grid, Lattice, Samples};
use isolab_metrics::topology;
use isolab_tests::blob_field;
use proptest::prelude::*;

#[test]
fn random_terrains_and_level_patterns_leave_no_crack() {
    let mc = extractors::by_name("marching-cubes").unwrap();
    let mut random = isolab_algorithms::random::Random::new(11);
    for seed in 1..=6 {
        let field = fields::builtin("terrain", FieldParams { seed }).unwrap();
        let grid = Grid::with_dims(&field.domain(), [65, 33, 65]).unwrap();
        let samples = Samples::sample(field, Lattice::Cubic(grid), 0.0).unwrap();
        let levels: Vec<u8> = (0..4 * 2 * 4).map(|_| (random.next_u64() % 2) as u8).collect();
        let mut out = Extraction::default();
        let stats = extract_lod(mc.as_ref(), &samples, 16, &levels, &mut out, None).unwrap();
        let what = format!("terrain seed {seed}, levels {levels:?}");
        assert_eq!(stats.unmatched, 0, "{what}");
        assert!(stats.stitched > 0 && stats.restricted > 0, "{what}: seams were stitched");
        let b = grid.bounds();
        assert_eq!(open_edges_off_bounds(&out.surface, &b), 0, "{what}: a crack");
        let t = topology(&out.surface);
        assert_eq!(t.non_manifold_edges, 0, "{what}");
        assert_eq!(t.misoriented_edges, 0, "{what}");
    }
}

#[test]
fn all_fine_equals_chunked_marching_cubes_and_all_coarse_equals_half_resolution() {
    let mc = extractors::by_name("marching-cubes").unwrap();
    let field = fields::builtin("asteroid", Default::default()).unwrap();
    let grid = Grid::with_dims(&field.domain(), [65, 65, 65]).unwrap();
    let samples = Samples::sample(field.clone(), Lattice::Cubic(grid), 0.0).unwrap();
    let mut lod = Extraction::default();
    extract_lod(mc.as_ref(), &samples, 16, &[0; 64], &mut lod, None).unwrap();
    let mut whole = Extraction::default();
    mc.extract(&samples, &mut whole).unwrap();
    assert_eq!((lod.stats.vertices, lod.stats.triangles), (whole.stats.vertices, whole.stats.triangles));
    let coarse_grid = Grid { origin: grid.origin, spacing: 2.0 * grid.spacing, dims: [33, 33, 33] };
    let coarse = Samples::sample(field, Lattice::Cubic(coarse_grid), 0.0).unwrap();
    mc.extract(&coarse, &mut whole).unwrap();
    extract_lod(mc.as_ref(), &samples, 16, &[1; 64], &mut lod, None).unwrap();
    assert_eq!((lod.stats.vertices, lod.stats.triangles), (whole.stats.vertices, whole.stats.triangles));
}

#[test]
fn bad_lod_requests_are_refused_by_name() {
    let samples = blob_field(17, &[(0.5, 0.5, 0.5, 0.3)], 0.5);
    let mc = extractors::by_name("marching-cubes").unwrap();
    let mut out = Extraction::default();
    let err = |r: Result<_, isolab_algorithms::ExtractError>| r.unwrap_err().to_string();
    assert!(err(extract_lod(mc.as_ref(), &samples, 8, &[0; 3], &mut out, None)).contains("3 levels given for 8 chunks"));
    assert!(err(extract_lod(mc.as_ref(), &samples, 8, &[2; 8], &mut out, None)).contains("level 2"));
    assert!(err(extract_lod(mc.as_ref(), &samples, 2, &[0; 512], &mut out, None)).contains("even and at least 4"));
    let sn = extractors::by_name("surface-nets").unwrap();
    assert!(err(extract_lod(sn.as_ref(), &samples, 8, &[0; 8], &mut out, None)).contains("marching-cubes"));
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 96, ..ProptestConfig::default() })]

    /// Random closed blobs under random level patterns: the stitched mesh is closed, manifold
    /// and consistently oriented.
    #[test]
    fn random_blobs_stitch_closed(
        blobs in prop::collection::vec((0.1f32..0.9, 0.1f32..0.9, 0.1f32..0.9, 0.05f32..0.3), 1..8),
        threshold in 0.3f32..0.9,
        levels in prop::collection::vec(0u8..2, 64),
        chunk in prop::sample::select(vec![4usize, 8]),
    ) {
        let samples = blob_field(17, &blobs, threshold);
        let mc = extractors::by_name("marching-cubes").unwrap();
        let mut out = Extraction::default();
        let levels = &levels[..(16 / chunk).pow(3)];
        let stats = extract_lod(mc.as_ref(), &samples, chunk, levels, &mut out, None).unwrap();
        prop_assert_eq!(stats.unmatched, 0);
        let t = topology(&out.surface);
        prop_assert!(t.closed && t.edge_manifold && t.oriented, "{:?} levels {:?}", (t.boundary_edges, t.non_manifold_edges, t.misoriented_edges), levels);
    }
}

#[test]
fn a_dual_extractors_border_inside_the_outer_cells_is_not_a_crack_but_a_hole_is() {
    // A tilted plane through the box: surface nets' mesh ends half a cell inside the box.
    let samples = isolab_tests::grid_samples([17, 17, 17], |x, y, z| y as f32 - 8.3 + 0.2 * x as f32 - 0.1 * z as f32);
    let sn = extractors::by_name("surface-nets").unwrap();
    let mut out = Extraction::default();
    sn.extract(&samples, &mut out).unwrap();
    let (b, h) = (samples.grid().bounds(), samples.grid().spacing);
    assert!(open_edges_off_bounds(&out.surface, &b) > 0, "the border is not on the box");
    assert_eq!(open_edges_away_from_bounds(&out.surface, &b, h), 0, "the border is within a cell of the box");
    // A triangle taken out in the middle: three open edges away from the box.
    let middle = out.surface.triangles.iter().position(|t| {
        t.iter().all(|&v| {
            let p = out.surface.positions[v as usize];
            (p - b.min).min_element() > 3.0 * h && (b.max - p).min_element() > 3.0 * h
        })
    });
    out.surface.triangles.remove(middle.expect("a triangle away from the box"));
    assert_eq!(open_edges_away_from_bounds(&out.surface, &b, h), 3);
}
