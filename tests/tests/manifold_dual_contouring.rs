//! Manifold dual contouring with intersection-free triangles: no two triangles cross (the exact
//! predicate) on every cube pattern, on random grids whose crossings crowd the corners, on white
//! noise and on the shipped models; the `csg` corners stay sharp; closed, manifold and outward
//! like dual contouring, with dual contouring's vertices.

use isolab_algorithms::random::Random;
use isolab_algorithms::{extractors, fields, Extraction, Grid, Samples, Vec3};
use isolab_metrics::self_intersections;
use isolab_tests::{assert_closed_manifold, assert_closed_manifold_for};
use rayon::prelude::*;

const NAME: &str = "manifold-dual-contouring";

fn extract(samples: &Samples) -> Extraction {
    let mut out = Extraction::default();
    extractors::by_name(NAME).unwrap().extract(samples, &mut out).unwrap();
    out
}

#[test]
fn every_cube_pattern_is_closed_manifold_and_free_of_crossings() {
    let failures: Vec<String> = (0..=255u8)
        .into_par_iter()
        .flat_map_iter(|case| {
            (0..3).filter_map(move |variant| {
                let s = isolab_tests::varied_case(case, variant);
                let out = extract(&s);
                assert_closed_manifold_for(&s, &out.surface, &format!("case {case} variant {variant}"));
                let found = self_intersections(&out.surface);
                (found.count > 0 || !out.stats.warnings.is_empty())
                    .then(|| format!("case {case} variant {variant}: {} pairs {:?}", found.count, out.stats.warnings))
            })
        })
        .collect();
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// Random grids of 3 to 6 samples a side, the border outside, every inner value drawn by
/// [`isolab_tests::crowded_distance`] with a random sign: every kind of cell and neighbourhood, with vertices pulled to
/// corners and faces by the quadric error.
#[test]
fn random_grids_with_crowded_crossings_never_cross() {
    const GRIDS: u64 = 4000;
    let failures: Vec<String> = (0..GRIDS)
        .into_par_iter()
        .filter_map(|seed| {
            let mut random = Random::new(seed * 104_729 + 1);
            let n = 3 + (seed % 4) as usize;
            let inside = 0.2 + 0.6 * random.unit_f32();
            let s = isolab_tests::grid_samples([n, n, n], |x, y, z| {
                if [x, y, z].iter().any(|&c| c == 0 || c == n - 1) {
                    return 1.0;
                }
                let d = isolab_tests::crowded_distance(&mut random);
                if random.unit_f32() < inside {
                    -d.max(f32::MIN_POSITIVE)
                } else {
                    d
                }
            });
            let out = extract(&s);
            assert_closed_manifold_for(&s, &out.surface, &format!("seed {seed}"));
            let found = self_intersections(&out.surface);
            (found.count > 0 || !out.stats.warnings.is_empty())
                .then(|| format!("seed {seed} ({n}³): {} pairs {:?} {:?}", found.count, found.pairs, out.stats.warnings))
        })
        .collect();
    assert!(failures.is_empty(), "{} of {GRIDS} grids:\n{}", failures.len(), failures.join("\n"));
}

#[test]
fn csg_corners_stay_within_five_hundredths_of_the_spacing() {
    for resolution in [33, 64] {
        let f = fields::builtin("csg", Default::default()).unwrap();
        let grid = Grid::covering(&f.domain(), resolution).unwrap();
        let s = Samples::sample_cubic(f, grid, 0.0).unwrap();
        let out = extract(&s);
        let worst = fields::Csg::sharp_corners()
            .iter()
            .map(|c| out.surface.positions.iter().map(|p| p.distance(*c)).fold(f32::INFINITY, f32::min))
            .fold(0.0, f32::max)
            / grid.spacing;
        assert!(worst < 0.05, "a corner missed by {worst} spacings at {resolution}");
        assert_closed_manifold(&out.surface, "csg");
        assert_eq!(self_intersections(&out.surface).count, 0, "csg at {resolution}");
    }
}

/// Where dual contouring self-intersects (white noise, the shipped models at 64), this does not.
#[test]
fn noise_and_the_shipped_models_have_no_crossing_pair() {
    let dc = extractors::by_name("dual-contouring").unwrap();
    let names = isolab_tests::shipped_models();
    let mut dc_pairs = 0;
    for name in names.iter().map(String::as_str).chain(["asteroid", "terrain", "gyroid"]) {
        let field = isolab_tests::object_field(name);
        let grid = Grid::covering(&field.domain(), 64).unwrap();
        let s = Samples::sample_cubic(field, grid, 0.0).unwrap();
        let out = extract(&s);
        let mut reference = Extraction::default();
        dc.extract(&s, &mut reference).unwrap();
        dc_pairs += self_intersections(&reference.surface).count;
        assert_eq!(self_intersections(&out.surface).count, 0, "{name}");
        assert!(out.stats.warnings.is_empty(), "{name}: {:?}", out.stats.warnings);
        // Dual contouring's vertices come first, then an edge point per quad (two triangles).
        let quads = reference.surface.triangles.len() / 2;
        assert!(out.surface.positions.len() >= reference.surface.positions.len() + quads, "{name}");
        assert!((4 * quads..=8 * quads).contains(&out.surface.triangles.len()), "{name}");
    }
    println!("dual contouring on the same inputs: {dc_pairs} crossing pairs");
}

/// Two opposite corners of the middle cell of a 4³ grid inside (a cell with two pieces of
/// surface), and Hermite normals that put each piece's quadric minimum at the other piece's
/// corner: each normal is perpendicular to the way from its crossing to that corner (and to the
/// next axis, so the three planes meet in one point).
struct SwappedCorners;

impl isolab_algorithms::Field for SwappedCorners {
    fn name(&self) -> &str {
        "swapped corners"
    }

    fn value(&self, p: Vec3) -> f32 {
        let near = |c: Vec3| p.distance(c) < 0.25;
        if near(Vec3::ONE) || near(Vec3::splat(2.0)) {
            -1.0
        } else {
            1.0
        }
    }

    fn domain(&self) -> isolab_algorithms::Aabb {
        isolab_algorithms::Aabb { min: Vec3::ZERO, max: Vec3::splat(3.0) }
    }

    fn has_analytic_gradient(&self) -> bool {
        true
    }

    fn gradient(&self, p: Vec3) -> Vec3 {
        let first = p.distance(Vec3::ONE) < p.distance(Vec3::splat(2.0));
        let target = if first { Vec3::splat(1.9) } else { Vec3::splat(1.1) };
        // The crossing's edge runs along the axis whose coordinate is not a whole number.
        let off = (p - p.round()).abs();
        let axis = (0..3).max_by(|&a, &b| off[a].total_cmp(&off[b])).unwrap_or(0);
        (target - p).cross(Vec3::AXES[(axis + 1) % 3])
    }
}

/// Where the quadric error puts two pieces' vertices in each other's corners, their cones would
/// cross: the cell's vertices move back, and the mesh has no crossing pair.
#[test]
fn pieces_pulled_into_each_others_corners_are_moved_apart() {
    let grid = Grid { origin: Vec3::ZERO, spacing: 1.0, dims: [4, 4, 4] };
    let s = Samples::sample_cubic(std::sync::Arc::new(SwappedCorners), grid, 0.0).unwrap();
    let mut dc = Extraction::default();
    extractors::by_name("dual-contouring").unwrap().extract(&s, &mut dc).unwrap();
    // Dual contouring's vertices did swap corners (the case this test is about).
    let in_middle = |p: &&Vec3| p.cmpgt(Vec3::ONE).all() && p.cmplt(Vec3::splat(2.0)).all();
    let near = |mesh: &isolab_algorithms::TriMesh, c: Vec3| mesh.positions.iter().filter(in_middle).any(|p| p.distance(c) < 0.05);
    assert!(near(&dc.surface, Vec3::splat(1.9)) && near(&dc.surface, Vec3::splat(1.1)), "{:?}", dc.surface.positions);
    let out = extract(&s);
    assert_closed_manifold(&out.surface, "swapped corners");
    assert_eq!(self_intersections(&out.surface).count, 0);
    assert!(out.stats.warnings.is_empty(), "{:?}", out.stats.warnings);
    assert!(!near(&out.surface, Vec3::splat(1.9)) && !near(&out.surface, Vec3::splat(1.1)), "{:?}", out.surface.positions);
}
