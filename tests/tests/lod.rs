//! Levels of detail: chunks at full, half and quarter resolution (and coarser), stitched at their
//! seams, for every registered extractor whose [`LevelsOfDetail`] capability says it takes them
//! (marching cubes by restriction and stitching, surface nets and both dual contourings by octree dual
//! contouring's minimal edges). Over random terrains and random balanced level patterns, no
//! boundary edge is left anywhere but on the world's boundary (a dual mesh's own border, inside
//! the outer cells, excepted), every edge has at most two triangles, orientation agrees, and no
//! seam edge goes unmatched; with every chunk at one level the result is the extractor's own mesh
//! at that resolution; an extractor that declares itself free of self-intersections (marching
//! cubes, manifold dual contouring) keeps that promise across levels. The others are refused
//! with their reason.

use isolab_algorithms::chunks::lod::{balance_levels, extract_lod, open_edges_away_from_bounds, open_edges_off_bounds};
use isolab_algorithms::fields::{self, FieldParams};
use isolab_algorithms::{extractors, Extraction, Extractor, Grid, Lattice, LevelsOfDetail, Samples, TriMesh, Vec3};
use isolab_metrics::topology;
use isolab_tests::blob_field;
use proptest::prelude::*;

/// The registered extractors (default options) that take levels of detail.
fn lod_extractors() -> Vec<Box<dyn Extractor>> {
    let list: Vec<Box<dyn Extractor>> =
        extractors::registry().into_iter().filter(|e| !matches!(e.levels_of_detail(), LevelsOfDetail::Unsupported(_))).collect();
    let names: Vec<&str> = list.iter().map(|e| e.name()).collect();
    for expected in ["marching-cubes", "surface-nets", "dual-contouring", "manifold-dual-contouring"] {
        assert!(names.contains(&expected), "{expected} takes levels of detail: {names:?}");
    }
    list
}

/// Open edges that are cracks: for marching cubes any off the world's box, for the dual methods
/// any more than a coarsest cell (`2^top` samples) from it (their own border lies inside the
/// outer cells).
fn cracks(extractor: &dyn Extractor, mesh: &TriMesh, grid: &Grid, top: u8) -> usize {
    match extractor.levels_of_detail() {
        LevelsOfDetail::Dual(_) => open_edges_away_from_bounds(mesh, &grid.bounds(), grid.spacing * f32::from(1u8 << top)),
        _ => open_edges_off_bounds(mesh, &grid.bounds()),
    }
}

#[test]
fn random_terrains_and_level_patterns_leave_no_crack() {
    for e in lod_extractors() {
        let mut random = isolab_algorithms::random::Random::new(11);
        let mut seams_between_coarse_levels = 0;
        for seed in 1..=6 {
            let field = fields::builtin("terrain", FieldParams { seed }).unwrap();
            let grid = Grid::with_dims(&field.domain(), [65, 33, 65]).unwrap();
            let samples = Samples::sample(field, Lattice::Cubic(grid), 0.0).unwrap();
            // Levels 0 to 3 (16³-cell chunks have 2³ cells at level 3), balanced.
            let mut levels: Vec<u8> = (0..4 * 2 * 4).map(|_| (random.next_u64() % 4) as u8).collect();
            balance_levels([4, 2, 4], &mut levels);
            let mut out = Extraction::default();
            let stats = extract_lod(e.as_ref(), &samples, 16, &levels, &mut out, None).unwrap();
            let what = format!("{}: terrain seed {seed}, levels {levels:?}", e.name());
            assert_eq!(stats.unmatched, 0, "{what}");
            assert!(stats.stitched > 0 && stats.restricted > 0, "{what}: seams were stitched");
            assert_eq!(stats.per_level.iter().sum::<usize>(), levels.len(), "{what}");
            seams_between_coarse_levels += usize::from(stats.per_level[1] > 0 && stats.per_level[2] > 0);
            let top = levels.iter().copied().max().unwrap_or(0);
            assert_eq!(cracks(e.as_ref(), &out.surface, &grid, top), 0, "{what}: a crack");
            let t = topology(&out.surface);
            assert_eq!(t.non_manifold_edges, 0, "{what}");
            assert_eq!(t.non_manifold_vertices, 0, "{what}");
            assert_eq!(t.misoriented_edges, 0, "{what}");
            // Marching cubes' stitched seams are filled so that nothing crosses (the lod module
            // doc), and manifold dual contouring's fans keep every triangle in its cells: every
            // extractor that declares itself free of self-intersections is held to it across
            // levels too.
            if e.info().guarantees.intersection_free {
                assert_eq!((stats.fanned, isolab_metrics::self_intersections(&out.surface).count), (0, 0), "{what}");
            }
        }
        assert!(
            seams_between_coarse_levels >= 3,
            "{}: half- and quarter-resolution chunks met in {seams_between_coarse_levels} terrains",
            e.name()
        );
    }
}

/// The largest distance from a vertex of `a` to the nearest vertex of `b` (vertices binned by
/// cells of side `h`, the nearest searched in the 27 bins around).
fn farthest_vertex(a: &TriMesh, b: &TriMesh, h: f32) -> f32 {
    let bin = |p: Vec3| (p / h).floor().as_ivec3().to_array();
    let mut bins: std::collections::HashMap<[i32; 3], Vec<Vec3>> = std::collections::HashMap::new();
    for &p in &b.positions {
        bins.entry(bin(p)).or_default().push(p);
    }
    a.positions
        .iter()
        .map(|&p| {
            let c = bin(p);
            (0..27)
                .flat_map(|d| {
                    let key = [c[0] + d % 3 - 1, c[1] + (d / 3) % 3 - 1, c[2] + d / 9 - 1];
                    bins.get(&key).into_iter().flatten().map(move |q| q.distance(p))
                })
                .fold(f32::INFINITY, f32::min)
        })
        .fold(0.0, f32::max)
}

#[test]
fn uniform_levels_equal_each_extractors_own_mesh_at_full_half_and_quarter_resolution() {
    let field = fields::builtin("asteroid", Default::default()).unwrap();
    let grid = Grid::with_dims(&field.domain(), [65, 65, 65]).unwrap();
    let samples = Samples::sample(field.clone(), Lattice::Cubic(grid), 0.0).unwrap();
    for e in lod_extractors() {
        for level in 0..=2u8 {
            let step = 1usize << level;
            let n = 64 / step + 1;
            let level_grid = Grid { origin: grid.origin, spacing: step as f32 * grid.spacing, dims: [n, n, n] };
            let level_samples = Samples::sample(field.clone(), Lattice::Cubic(level_grid), 0.0).unwrap();
            let mut whole = Extraction::default();
            e.extract(&level_samples, &mut whole).unwrap();
            let mut lod = Extraction::default();
            extract_lod(e.as_ref(), &samples, 16, &[level; 64], &mut lod, None).unwrap();
            let what = format!("{} at level {level}", e.name());
            assert_eq!((lod.stats.vertices, lod.stats.triangles), (whole.stats.vertices, whole.stats.triangles), "{what}");
            // The same vertices (smoothing sums neighbours in another order: within 1e-4 cells).
            let h = level_grid.spacing;
            let far = farthest_vertex(&lod.surface, &whole.surface, h).max(farthest_vertex(&whole.surface, &lod.surface, h));
            assert!(far <= 1e-4 * h, "{what}: a vertex {far} from the other mesh's");
            let (va, vb) =
                (isolab_metrics::accuracy::signed_volume(&lod.surface), isolab_metrics::accuracy::signed_volume(&whole.surface));
            assert!((va - vb).abs() <= 1e-4 * vb.abs(), "{what}: volume {va} against {vb}");
        }
    }
}

#[test]
fn bad_lod_requests_are_refused_by_name() {
    let samples = blob_field(17, &[(0.5, 0.5, 0.5, 0.3)], 0.5);
    let mc = extractors::by_name("marching-cubes").unwrap();
    let mut out = Extraction::default();
    let err = |r: Result<_, isolab_algorithms::ExtractError>| r.unwrap_err().to_string();
    assert!(err(extract_lod(mc.as_ref(), &samples, 8, &[0; 3], &mut out, None)).contains("3 levels given for 8 chunks"));
    assert!(err(extract_lod(mc.as_ref(), &samples, 8, &[5; 8], &mut out, None)).contains("level 5 is not supported"));
    assert!(err(extract_lod(mc.as_ref(), &samples, 8, &[3; 8], &mut out, None)).contains("cannot be meshed at level 3"));
    assert!(err(extract_lod(mc.as_ref(), &samples, 2, &[1; 512], &mut out, None)).contains("even and at least 4"));
    let unbalanced = [0, 2, 1, 1, 1, 1, 1, 1];
    assert!(err(extract_lod(mc.as_ref(), &samples, 8, &unbalanced, &mut out, None)).contains("differ by more than one level"));
    let mut balanced = unbalanced;
    balance_levels([2, 2, 2], &mut balanced);
    assert_eq!(balanced, [0, 1, 1, 1, 1, 1, 1, 1]);
    extract_lod(mc.as_ref(), &samples, 8, &balanced, &mut out, None).unwrap();
    let mt = extractors::by_name("marching-tetrahedra").unwrap();
    assert!(err(extract_lod(mt.as_ref(), &samples, 8, &[0; 8], &mut out, None)).contains("not supported for marching-tetrahedra"));
}

#[test]
fn the_extractors_that_take_levels_of_detail_say_so_and_the_others_are_refused_with_their_reason() {
    let samples = blob_field(17, &[(0.5, 0.5, 0.5, 0.3)], 0.5);
    let mut out = Extraction::default();
    let mut supported = Vec::new();
    for e in extractors::registry() {
        let result = extract_lod(e.as_ref(), &samples, 8, &[0, 1, 1, 0, 1, 0, 0, 1], &mut out, None);
        match e.levels_of_detail() {
            LevelsOfDetail::Stitched | LevelsOfDetail::Dual(_) => {
                let stats = result.unwrap_or_else(|err| panic!("{}: {err}", e.name()));
                assert_eq!(stats.unmatched, 0, "{}", e.name());
                assert!(topology(&out.surface).closed, "{}", e.name());
                supported.push(e.name());
            }
            LevelsOfDetail::Unsupported(why) => {
                let message = result.err().map(|err| err.to_string()).unwrap_or_default();
                assert!(message.contains(e.name()) && message.contains(why), "{}: {message}", e.name());
            }
        }
    }
    for expected in ["marching-cubes", "surface-nets", "dual-contouring", "manifold-dual-contouring"] {
        assert!(supported.contains(&expected), "{supported:?}");
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 96, ..ProptestConfig::default() })]

    /// Random closed blobs under random level patterns: every extractor's stitched mesh is
    /// closed, edge-manifold, consistently oriented and outward.
    #[test]
    fn random_blobs_stitch_closed(
        blobs in prop::collection::vec((0.1f32..0.9, 0.1f32..0.9, 0.1f32..0.9, 0.05f32..0.3), 1..8),
        threshold in 0.3f32..0.9,
        levels in prop::collection::vec(0u8..3, 64),
        chunk in prop::sample::select(vec![4usize, 8]),
    ) {
        // 4³-cell chunks take levels 0 and 1, 8³-cell chunks 0 to 2.
        let samples = blob_field(chunk * 4 + 1, &blobs, threshold);
        let top = if chunk == 4 { 1 } else { 2 };
        let mut levels: Vec<u8> = levels.iter().map(|&l| l.min(top)).collect();
        balance_levels([4, 4, 4], &mut levels);
        for e in lod_extractors() {
            let mut out = Extraction::default();
            let stats = extract_lod(e.as_ref(), &samples, chunk, &levels, &mut out, None).unwrap();
            prop_assert_eq!(stats.unmatched, 0, "{}", e.name());
            if e.info().guarantees.intersection_free {
                let crossing = isolab_metrics::self_intersections(&out.surface).count;
                prop_assert_eq!((stats.fanned, crossing), (0, 0), "{}: levels {:?}", e.name(), levels);
            }
            let t = topology(&out.surface);
            prop_assert!(
                t.closed && t.edge_manifold && t.vertex_manifold && t.oriented && (t.outward || out.surface.triangles.is_empty()),
                "{}: {:?} levels {:?}", e.name(), (t.boundary_edges, t.non_manifold_edges, t.misoriented_edges), levels
            );
        }
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
