//! Marching cubes 33 (`marching-cubes-33`): every cell's mesh has the topology of the trilinear
//! interpolant's level set in that cell, tunnels included, on every one of the 256 sign patterns
//! with many random corner values each. The interpolant's level set is found independently: the
//! trilinear function sampled finely over the cell and meshed by `marching-cubes-decider`, whose
//! components and Euler characteristic the cell's mesh must have.

use isolab_algorithms::extractors::marching_cubes::{FaceResolution, MarchingCubes, McOptions};
use isolab_algorithms::sweep::slabs::Parallelism;
use isolab_tests::{
    assert_closed_manifold, cell_samples, cell_shape, embedded_case, extract, interpolant_shape, near_critical,
    tunnel_corner_values,
};

fn mc(faces: FaceResolution) -> MarchingCubes {
    MarchingCubes::new(McOptions { faces, parallelism: Parallelism::Serial, ..Default::default() })
}

/// Random corner values per sign pattern.
const DRAWS: u64 = 48;

#[test]
fn every_cell_has_the_topology_of_the_trilinear_interpolant() {
    let (mut compared, mut critical, mut tunnels, mut decider_wrong, mut crossed) = (0usize, 0usize, 0usize, 0usize, 0usize);
    for case in 1..=254u8 {
        let mut random = isolab_algorithms::random::Random::new(0x33 + u64::from(case));
        for draw in 0..DRAWS {
            let g = tunnel_corner_values(case, &mut random);
            let cell = cell_samples(&g);
            let reference = interpolant_shape(&g, 0.0);
            let mesh = extract(&mc(FaceResolution::Trilinear), &cell).surface;
            let ours = cell_shape(&mesh);
            if ours != reference {
                // Only a draw within a hair of a critical value of the interpolant may differ
                // (the fine sampling cannot resolve it).
                assert!(
                    near_critical(&g),
                    "case {case} draw {draw}: ours {ours:?}, the interpolant's {reference:?}; corner values {g:?}"
                );
                critical += 1;
                continue;
            }
            compared += 1;
            let below = reference;
            // A component with Euler characteristic 0 is a tube: a tunnel through the cell.
            if below.0 as i64 > below.1 {
                tunnels += 1;
                crossed += usize::from(isolab_metrics::self_intersections(&mesh).count > 0);
                let decided = cell_shape(&extract(&mc(FaceResolution::AsymptoticDecider), &cell).surface);
                decider_wrong += usize::from(decided != below);
            }
        }
    }
    let total = 254 * DRAWS as usize;
    assert!(critical * 20 < total, "{critical} of {total} draws too close to a critical value");
    // The test exercises tunnels, and they are where the face-only decider is wrong.
    assert!(tunnels >= 100, "only {tunnels} draws with a tunnel");
    assert_eq!(decider_wrong, tunnels, "the decider alone never makes a tube");
    // `marching-cubes-33` declares itself free of self-intersections: its tubes never cross.
    assert_eq!(crossed, 0, "{crossed} of {tunnels} tubes cross themselves");
    eprintln!("compared {compared}, near a critical value {critical}, with a tunnel {tunnels}, crossing itself {crossed}");
}

#[test]
fn every_pattern_among_its_neighbours_is_closed_manifold_and_outward() {
    for case in 1..=254u8 {
        let mut random = isolab_algorithms::random::Random::new(0x3333 + u64::from(case));
        for draw in 0..16 {
            let g = tunnel_corner_values(case, &mut random);
            let s = embedded_case(case, |corner, _| g[corner]);
            let out = extract(&mc(FaceResolution::Trilinear), &s);
            let t = assert_closed_manifold(&out.surface, &format!("case {case} draw {draw}"));
            assert!(t.outward, "case {case} draw {draw}: {t:?}");
        }
    }
}
