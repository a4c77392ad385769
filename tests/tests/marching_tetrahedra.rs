//! Marching tetrahedra and regularised marching tetrahedra on both tetrahedral lattices: every
//! sign pattern of a sample's star, random fields, the closed built-in fields and models, and the
//! RMT paper's reduction and quality claims.

use isolab_algorithms::extractors::regularised_marching_tetrahedra::{RegularisedMarchingTetrahedra, RmtOptions};
use isolab_algorithms::extractors::tetrahedral::{topology, TetKind, DIRECTIONS};
use isolab_algorithms::extractors::MarchingTetrahedra;
use isolab_algorithms::{mesh::manifold_defects, Extractor, Grid, Lattice, Samples};
use isolab_tests::{assert_closed_manifold, assert_closed_manifold_for, extract, lattice_samples};
use proptest::prelude::*;

fn rmt() -> RegularisedMarchingTetrahedra {
    RegularisedMarchingTetrahedra::default()
}

fn paper_rmt() -> RegularisedMarchingTetrahedra {
    RegularisedMarchingTetrahedra::new(RmtOptions::paper())
}

/// A lattice where one sample (at doubled `centre`) and its 14 neighbours carry `pattern` (bit 0:
/// the sample, bit 1 + k: neighbour k inside) and every other sample is outside.
fn star_pattern(bcc: bool, pattern: u16) -> Samples<'static> {
    let kind = if bcc { TetKind::Bcc } else { TetKind::Kuhn };
    let dirs = topology(kind).directions;
    // BCC: the centre of cell (2, 2, 2) in a 6^3 corner grid; Kuhn: corner (2, 2, 2) of a 5^3 grid.
    // Either way every neighbour is surrounded by tetrahedra, so the surface closes.
    let (dims, centre) = if bcc { ([6, 6, 6], [5, 5, 5]) } else { ([5, 5, 5], [4, 4, 4]) };
    lattice_samples(bcc, dims, |q| {
        let rel = [q[0] - centre[0], q[1] - centre[1], q[2] - centre[2]];
        let bit = if rel == [0, 0, 0] { Some(0) } else { dirs.iter().position(|d| *d == rel).map(|k| k + 1) };
        // Distinct magnitudes so crossings sit at different distances.
        let m = 1.0 + 0.05 * bit.unwrap_or(15) as f32;
        match bit {
            Some(b) if pattern >> b & 1 == 1 => -m,
            _ => m,
        }
    })
}

#[test]
fn every_star_pattern_gives_a_closed_manifold_outward_surface() {
    assert_eq!(DIRECTIONS, 14);
    for bcc in [true, false] {
        for pattern in 1..1u16 << 15 {
            let s = star_pattern(bcc, pattern);
            for (name, e) in [("mt", &MarchingTetrahedra::default() as &dyn Extractor), ("rmt", &rmt())] {
                let out = extract(e, &s);
                assert!(!out.surface.triangles.is_empty(), "{name} bcc={bcc} pattern {pattern:#x}: empty");
                assert_closed_manifold(&out.surface, &format!("{name} bcc={bcc} star pattern {pattern:#x}"));
            }
        }
    }
}

fn blob_lattice(bcc: bool, n: usize, blobs: &[(f32, f32, f32, f32)], threshold: f32) -> Samples<'static> {
    let max = 2 * (n as i32 - 1);
    lattice_samples(bcc, [n, n, n], |q| {
        if q.iter().any(|&c| c <= 1 || c >= max - 1) {
            return 1.0;
        }
        let p = glam::Vec3::new(q[0] as f32, q[1] as f32, q[2] as f32) / max as f32;
        let density: f32 =
            blobs.iter().map(|&(bx, by, bz, r)| (-(p - glam::Vec3::new(bx, by, bz)).length_squared() / (r * r)).exp()).sum();
        threshold - density
    })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 300, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn random_smooth_fields_give_closed_manifold_surfaces(
        bcc in any::<bool>(),
        n in 5usize..14,
        blobs in prop::collection::vec((0.1f32..0.9, 0.1f32..0.9, 0.1f32..0.9, 0.05f32..0.4), 1..6),
        threshold in 0.2f32..0.9,
    ) {
        let s = blob_lattice(bcc, n, &blobs, threshold);
        assert_closed_manifold_for(&s, &extract(&MarchingTetrahedra::default(), &s).surface, "mt blobs");
        assert_closed_manifold_for(&s, &extract(&rmt(), &s).surface, "rmt blobs");
    }

    #[test]
    fn white_noise_gives_closed_manifold_surfaces(bcc in any::<bool>(), values in prop::collection::vec(-1.0f32..1.0, 2 * 8 * 8 * 8)) {
        let mut k = 0;
        let s = lattice_samples(bcc, [8, 8, 8], |q| {
            if q.iter().any(|&c| c <= 1 || c >= 13) { return 1.0; }
            k += 1;
            values[k % values.len()]
        });
        assert_closed_manifold_for(&s, &extract(&MarchingTetrahedra::default(), &s).surface, "mt white noise");
        assert_closed_manifold_for(&s, &extract(&rmt(), &s).surface, "rmt white noise");
    }
}

fn sampled(name: &str, bcc: bool, dims: Option<[usize; 3]>, resolution: usize) -> Samples<'static> {
    let field = isolab_tests::object_field(name);
    let grid = match dims {
        Some(d) => Grid::with_dims(&field.domain(), d).unwrap(),
        None => Grid::covering(&field.domain(), resolution).unwrap(),
    };
    let lattice = if bcc { Lattice::Bcc(grid) } else { Lattice::Cubic(grid) };
    Samples::sample(field, lattice, 0.0).unwrap()
}

#[test]
fn closed_builtin_fields_are_closed_and_manifold_on_both_lattices() {
    for (name, euler) in [("sphere", 2), ("torus", 0), ("asteroid", 2), ("csg", 2), ("thin", 8)] {
        for bcc in [true, false] {
            let s = sampled(name, bcc, None, 64);
            for (algo, e) in [("mt", &MarchingTetrahedra::default() as &dyn Extractor), ("rmt", &rmt())] {
                let t = assert_closed_manifold(&extract(e, &s).surface, &format!("{algo} {name} bcc={bcc}"));
                assert_eq!(t.euler, euler, "{algo} {name} bcc={bcc}");
            }
        }
    }
}

/// The RMT paper's claims on its three objects at its resolutions: at least 70% fewer triangles
/// than plain marching tetrahedra (the paper's own counts give 72.5-73.3%; its "79.5%" is
/// discarded / (discarded + kept)), mean Verdict aspect ratio at most 1.3 on BCC (the issue's
/// target; the paper: 1.16-2.16) and at most 1.6 on the Kuhn split (the paper: 1.33-1.35; ours
/// is 1.35-1.51, see the costen_table experiment), closed and manifold.
#[test]
fn rmt_reduces_triangles_and_regularises_them_on_the_paper_objects() {
    for (name, dims) in [("sphere", [51, 51, 51]), ("asteroid", [51, 51, 51]), ("stanford-bunny.obj", [76, 41, 57])] {
        for bcc in [true, false] {
            let s = sampled(name, bcc, Some(dims), 0);
            let mt = extract(&MarchingTetrahedra::default(), &s);
            let out = extract(&rmt(), &s);
            assert_closed_manifold(&out.surface, &format!("rmt {name} bcc={bcc}"));
            let removed = 1.0 - out.surface.triangles.len() as f64 / mt.surface.triangles.len() as f64;
            let ar = isolab_metrics::triangle_quality(&out.surface).aspect_ratio.mean;
            let bound = if bcc { 1.3 } else { 1.6 };
            assert!(removed > 0.70, "{name} bcc={bcc}: removed {removed:.3}");
            assert!(ar <= bound, "{name} bcc={bcc}: mean aspect ratio {ar:.3}");
        }
    }
}

/// The paper's algorithm without our guard: count the places its local graph test misses, per
/// field and lattice, and check that the guard leaves none and only unmerges where one was found.
/// One extractor also meshes every case in turn, twice: its kept scratch (the guard's repairs
/// included) must not change the next call's mesh.
#[test]
fn the_guard_repairs_exactly_the_cases_the_paper_misses() {
    let mut missed = Vec::new();
    let reused = rmt();
    let mut repaired = 0;
    for name in ["sphere", "torus", "asteroid", "csg", "thin", "gyroid", "terrain"] {
        for bcc in [true, false] {
            let s = sampled(name, bcc, None, 51);
            let paper = extract(&paper_rmt(), &s);
            let guarded = extract(&rmt(), &s);
            for call in ["first", "second"] {
                let again = extract(&reused, &s);
                assert!(again.surface == guarded.surface, "{name} bcc={bcc}: a reused extractor's {call} call differs");
            }
            let paper_defects = manifold_defects(&paper.surface).len();
            assert!(manifold_defects(&guarded.surface).is_empty(), "{name} bcc={bcc}: guard left defects");
            let unguarded = extract(&RegularisedMarchingTetrahedra::new(RmtOptions { guard: false, ..Default::default() }), &s);
            if manifold_defects(&unguarded.surface).is_empty() {
                assert_eq!(unguarded.surface, guarded.surface, "{name} bcc={bcc}: the guard changed a manifold mesh");
            } else {
                repaired += 1;
            }
            missed.push(format!("{name}/{}: {paper_defects}", if bcc { "bcc" } else { "cubic" }));
        }
    }
    assert!(repaired > 0, "no case exercised the guard's repairs");
    println!("defective vertices of the paper's RMT (guard off): {}", missed.join(", "));
}

/// Every closed shipped model, on both lattices: closed and manifold (topology may differ from
/// the model's where features are thinner than the lattice, as for any extractor).
#[test]
fn closed_shipped_models_give_closed_manifold_surfaces() {
    for name in ["stanford-bunny.obj", "spot.obj", "fandisk.obj", "rocker-arm.obj", "cheburashka.obj"] {
        for bcc in [true, false] {
            let s = sampled(name, bcc, None, 48);
            for (algo, e) in [("mt", &MarchingTetrahedra::default() as &dyn Extractor), ("rmt", &rmt())] {
                assert_closed_manifold(&extract(e, &s).surface, &format!("{algo} {name} bcc={bcc}"));
            }
        }
    }
}

/// Both passes run in slabs of layers on rayon's threads and join them in order: the output must
/// not depend on how many slabs there were (1-thread and 2-thread pools cut 4 and 8 slabs here),
/// nor on the lattice, for plain and regularised marching tetrahedra.
#[test]
fn slabbed_passes_give_the_same_mesh_on_any_thread_count() {
    for bcc in [false, true] {
        let s = sampled("asteroid", bcc, None, 90);
        for e in [&MarchingTetrahedra::default() as &dyn Extractor, &rmt()] {
            let run = |threads: usize| {
                let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
                pool.install(|| extract(e, &s))
            };
            let (one, two) = (run(1), run(2));
            assert!(!one.surface.triangles.is_empty());
            assert_eq!(one.surface.positions, two.surface.positions, "{} bcc={bcc}", e.name());
            assert_eq!(one.surface.triangles, two.surface.triangles, "{} bcc={bcc}", e.name());
        }
    }
}
