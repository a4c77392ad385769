//! Self-intersecting triangle pairs of every registered extractor on every built-in field and
//! shipped model, held to what was measured: an extractor that declares itself free of
//! self-intersections must give none, and no other may give more than the committed bound (so a
//! change that adds folds fails here; one that removes some should lower the bound). A new
//! extractor has no bound yet and fails until its measured counts are added.
//!
//! Every input is sampled on a cubic grid of 40 samples along its longest side (the models as
//! signed distance fields), and the extractors run with their defaults; the volume extractor is
//! measured on its boundary surface.

use isolab_algorithms::extractors::{self, INFOS};
use isolab_algorithms::random::Random;
use isolab_algorithms::{fields, Extraction, Grid, Lattice, Samples};
use isolab_metrics::self_intersections;
use rayon::prelude::*;

const RESOLUTION: usize = 40;

/// Measured self-intersecting pairs at [`RESOLUTION`]: (extractor, input, pairs). Inputs not
/// listed for an extractor gave none.
/// Dual contouring places the teapot's vertices at features whose quads cross (not one quad
/// folding: the fold-aware split does not remove these).
const BOUNDS: &[(&str, &str, usize)] = &[("dual-contouring", "teapot.obj", 4)];

fn inputs() -> Vec<String> {
    let mut names: Vec<String> = fields::registry().iter().map(|f| f.name.to_owned()).collect();
    names.extend(isolab_tests::shipped_models());
    names
}

#[test]
fn no_extractor_self_intersects_more_than_measured() {
    let inputs = inputs();
    assert!(inputs.len() >= 12, "{inputs:?}");
    let mut measured = Vec::new();
    for input in &inputs {
        let field = isolab_tests::object_field(input);
        let grid = Grid::covering(&field.domain(), RESOLUTION).unwrap();
        let samples = Samples::sample(field, Lattice::Cubic(grid), 0.0).unwrap();
        for info in INFOS.iter().filter(|i| i.guarantees.cubic) {
            let extractor = extractors::by_name(info.name).unwrap();
            let mut out = Extraction::default();
            extractor.extract(&samples, &mut out).unwrap();
            assert!(!out.surface.triangles.is_empty(), "{} on {input}: no surface", info.name);
            measured.push((info.name, input.as_str(), self_intersections(&out.surface).count, info.guarantees.intersection_free));
        }
    }
    let mut failures = Vec::new();
    for &(name, input, count, free) in &measured {
        let bound = BOUNDS.iter().find(|b| b.0 == name && b.1 == input).map_or(0, |b| b.2);
        if (free && count > 0) || count > bound {
            failures.push(format!("{name} on {input}: {count} pairs (bound {bound}, declared free: {free})"));
        }
    }
    let listed: Vec<String> =
        measured.iter().filter(|m| m.2 > 0).map(|m| format!("(\"{}\", \"{}\", {}),", m.0, m.1, m.2)).collect();
    assert!(failures.is_empty(), "{}\nmeasured now:\n{}", failures.join("\n"), listed.join("\n"));
    // Every bound is still needed (a bound far above what is measured could not fail).
    for &(name, input, bound) in BOUNDS {
        let now = measured.iter().find(|m| m.0 == name && m.1 == input).map_or(0, |m| m.2);
        assert_eq!(now, bound, "{name} on {input}: measured {now}, bound {bound}: lower the bound\n{}", listed.join("\n"));
    }
}

/// Every corner pattern of one cell, meshed by each extractor that reads the marching cubes
/// tables, with corner values drawn by [`isolab_tests::crowded_distance`]: no two triangles cross (the exact
/// predicate). Triangles of different cells lie in different cubes and meet only on the segments
/// of their shared face, so one cell free of crossings is the whole mesh free of them.
#[test]
fn no_marching_cubes_cell_folds_over_itself() {
    const DRAWS: usize = 3000;
    for name in ["marching-cubes", "marching-cubes-decider", "marching-cubes-33"] {
        let extractor = extractors::by_name(name).unwrap();
        let info = INFOS.iter().find(|i| i.name == name).unwrap();
        assert!(info.guarantees.intersection_free, "{name} declares itself free of self-intersections");
        let failures: Vec<String> = (1..255u32)
            .into_par_iter()
            .filter_map(|case| {
                let mut random = Random::new(u64::from(case) * 7919);
                let mut out = Extraction::default();
                for draw in 0..DRAWS {
                    let v: [f32; 8] = std::array::from_fn(|c| {
                        let d = isolab_tests::crowded_distance(&mut random);
                        if case >> c & 1 == 1 {
                            -d.max(f32::MIN_POSITIVE)
                        } else {
                            d
                        }
                    });
                    // Table corners: 0 (0,0,0) 1 (1,0,0) 2 (1,1,0) 3 (0,1,0), +4 for z = 1.
                    let s = isolab_tests::grid_samples([2, 2, 2], |x, y, z| v[[0, 1, 3, 2][x + 2 * y] + 4 * z]);
                    extractor.extract(&s, &mut out).unwrap();
                    let found = self_intersections(&out.surface);
                    if found.count > 0 {
                        return Some(format!("{name} case {case} draw {draw} corners {v:?}: pairs {:?}", found.pairs));
                    }
                }
                None
            })
            .collect();
        assert!(failures.is_empty(), "{}", failures.join("\n"));
    }
}

/// Merging crossings can fold a triangle through its neighbours; regularised marching
/// tetrahedra's guard unmerges the folds it finds. On white noise (the most folds per cell) on
/// both lattices: the fold check removes most of what the manifold guard alone leaves, and no
/// more remain than measured (the remainder lies beyond the two-ring the check searches).
#[test]
fn the_regularised_fold_check_removes_the_folds_merging_makes() {
    const MEASURED_REMAINING: usize = 4;
    let build = |guard: &str| {
        let mut o = isolab_algorithms::Options::new();
        o.set("guard", guard);
        extractors::build("regularised-marching-tetrahedra", &o).unwrap().unwrap()
    };
    let (manifold_only, with_folds) = (build("manifold"), build("true"));
    let (mut before, mut after) = (0, 0);
    let mut random = Random::new(20261202);
    for _ in 0..8 {
        let grid = Grid { origin: glam::Vec3::ZERO, spacing: 1.0, dims: [24, 24, 24] };
        for lattice in [Lattice::Cubic(grid), Lattice::Bcc(grid)] {
            let values = (0..lattice.sample_count()).map(|_| random.unit_f32() - 0.5).collect();
            let samples = Samples::from_values(lattice, values, 0.0).unwrap();
            let mut out = Extraction::default();
            manifold_only.extract(&samples, &mut out).unwrap();
            before += self_intersections(&out.surface).count;
            with_folds.extract(&samples, &mut out).unwrap();
            assert!(isolab_algorithms::mesh::manifold_defects(&out.surface).is_empty());
            after += self_intersections(&out.surface).count;
        }
    }
    assert!(before >= 4 * after.max(1), "manifold guard {before} pairs, with the fold check {after}");
    assert_eq!(after, MEASURED_REMAINING, "manifold guard alone: {before}; update the bound if lower");
}
