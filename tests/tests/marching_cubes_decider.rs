//! Marching cubes with the asymptotic decider: closed and manifold on every cube pattern among
//! random neighbours and on random fields, and topologically different from the default table
//! exactly where the trilinear interpolant says so.

use isolab_algorithms::extractors::marching_cubes::{FaceResolution, MarchingCubes, McOptions};
use isolab_algorithms::sweep::slabs::Parallelism;
use isolab_tests::{assert_closed_manifold, extract, grid_samples};
use proptest::prelude::*;

fn mc(faces: FaceResolution) -> MarchingCubes {
    MarchingCubes::new(McOptions { faces, parallelism: Parallelism::Serial, ..Default::default() })
}

/// A seeded stream of uniform numbers in [0, 1).
fn rng(seed: u64) -> impl FnMut() -> f32 {
    let mut random = isolab_algorithms::random::Random::new(seed);
    move || random.unit_f32()
}

#[test]
fn all_256_cube_patterns_among_random_neighbours_are_closed_and_manifold() {
    for case in 0..=255u8 {
        for trial in 0..8u64 {
            let mut next = rng(u64::from(case) * 8 + trial + 1);
            let s = grid_samples([6, 6, 6], |x, y, z| {
                if x == 0 || y == 0 || z == 0 || x == 5 || y == 5 || z == 5 {
                    return 1.0;
                }
                let magnitude = 0.05 + next();
                let inner = (2..=3).contains(&x) && (2..=3).contains(&y) && (2..=3).contains(&z);
                let inside =
                    if inner { case >> ([0, 1, 3, 2][(x - 2) + 2 * (y - 2)] + 4 * (z - 2)) & 1 == 1 } else { next() < 0.5 };
                if inside {
                    -magnitude
                } else {
                    magnitude
                }
            });
            for faces in [FaceResolution::SeparateInside, FaceResolution::AsymptoticDecider, FaceResolution::Trilinear] {
                let out = extract(&mc(faces), &s);
                assert_closed_manifold(&out.surface, &format!("case {case} trial {trial} {faces:?}"));
            }
        }
    }
}

/// Two columns of inside samples along z, diagonal to each other across the central cell's
/// faces; `strength` is how far inside they are against how far outside the other diagonal is.
fn diagonal_columns(inside: f32, outside: f32) -> isolab_algorithms::Samples<'static> {
    grid_samples([4, 4, 5], |x, y, z| {
        if x == 0 || y == 0 || z == 0 || x == 3 || y == 3 || z == 4 {
            return 1.0;
        }
        if (x == 1 && y == 1) || (x == 2 && y == 2) {
            -inside
        } else {
            outside
        }
    })
}

#[test]
fn the_decider_joins_diagonal_columns_when_the_saddle_is_inside() {
    // Saddle (a c - b d) / (a + c - b - d) with a = c = -1, b = d = 0.5: inside, so the
    // trilinear interpolant connects the two columns through the faces between them.
    let s = diagonal_columns(1.0, 0.5);
    let classic = assert_closed_manifold(&extract(&mc(FaceResolution::SeparateInside), &s).surface, "classic");
    let decided = assert_closed_manifold(&extract(&mc(FaceResolution::AsymptoticDecider), &s).surface, "decider");
    assert_eq!(classic.components, 2, "the default table keeps the columns apart");
    assert_eq!(decided.components, 1, "the decider follows the interpolant and joins them");
    // With the saddle outside, both keep them apart.
    let s = diagonal_columns(0.5, 1.0);
    assert_eq!(assert_closed_manifold(&extract(&mc(FaceResolution::AsymptoticDecider), &s).surface, "decider").components, 2);
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 300, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn random_sign_patterns_give_closed_manifold_meshes_with_the_decider(values in prop::collection::vec(-1.0f32..1.0, 6 * 6 * 6)) {
        let s = grid_samples([8, 8, 8], |x, y, z| {
            if x == 0 || y == 0 || z == 0 || x == 7 || y == 7 || z == 7 { 1.0 } else { values[(x - 1) + 6 * ((y - 1) + 6 * (z - 1))] }
        });
        let out = extract(&mc(FaceResolution::AsymptoticDecider), &s);
        assert_closed_manifold(&out.surface, "white noise, decider");
    }
}
