//! Dual contouring: sharp corners of `csg` reproduced (marching cubes and surface nets cut them),
//! closed and manifold on the smooth closed fields, and a clear error without a field.

use isolab_algorithms::{extractors, fields, Extraction, Grid, Lattice, Samples, Vec3};
use isolab_tests::assert_closed_manifold;

fn worst_corner_distance(algorithm: &str, resolution: usize) -> f32 {
    let f = fields::builtin("csg", Default::default()).unwrap();
    let grid = Grid::covering(&f.domain(), resolution).unwrap();
    let s = Samples::sample_cubic(f.clone(), grid, 0.0).unwrap();
    let mut out = Extraction::default();
    extractors::by_name(algorithm).unwrap().extract(&s, &mut out).unwrap();
    fields::Csg::sharp_corners()
        .iter()
        .map(|c| out.surface.positions.iter().map(|p| p.distance(*c)).fold(f32::INFINITY, f32::min))
        .fold(0.0, f32::max)
        / grid.spacing
}

#[test]
fn csg_corners_come_out_sharp() {
    for resolution in [33, 64] {
        let dc = worst_corner_distance("dual-contouring", resolution);
        let mc = worst_corner_distance("marching-cubes", resolution);
        let sn = worst_corner_distance("surface-nets", resolution);
        assert!(dc < 0.05, "dual contouring misses a corner by {dc} spacings at {resolution}");
        assert!(mc > 4.0 * dc && sn > 4.0 * dc, "at {resolution}: MC {mc}, SN {sn}, DC {dc} spacings");
    }
}

#[test]
fn smooth_closed_fields_are_closed_and_manifold() {
    for name in ["sphere", "torus", "csg", "thin"] {
        let f = fields::builtin(name, Default::default()).unwrap();
        let s = Samples::sample_cubic(f.clone(), Grid::covering(&f.domain(), 48).unwrap(), 0.0).unwrap();
        let mut out = Extraction::default();
        extractors::by_name("dual-contouring").unwrap().extract(&s, &mut out).unwrap();
        assert_closed_manifold(&out.surface, name);
    }
}

#[test]
fn raw_values_without_a_field_are_refused_by_name() {
    let grid = Grid { origin: Vec3::ZERO, spacing: 1.0, dims: [3, 3, 3] };
    let values: Vec<f32> = (0..27).map(|i| if i == 13 { -1.0 } else { 1.0 }).collect();
    let s = Samples::from_values(Lattice::Cubic(grid), values, 0.0).unwrap();
    let err = extractors::by_name("dual-contouring").unwrap().extract(&s, &mut Extraction::default()).unwrap_err().to_string();
    assert!(err.contains("dual-contouring") && err.contains("gradient"), "{err}");
}
