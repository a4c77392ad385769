//! Sparse extraction from a field evaluated in batches (`chunks::extract_sparse`): with a
//! Lipschitz bound the mesh equals the dense grid's, vertex for vertex and triangle for triangle,
//! for every extractor that meshes in blocks, from far fewer evaluations; the sign-change
//! heuristic keeps a surface it sees; a wrong answer from the evaluator is an error naming its
//! batch, and the evaluator's own error comes back unchanged.

use isolab_algorithms::chunks::{
    extract_sparse, BatchEval, EvalError, FieldEval, GridFieldEval, Pruning, SparseError, SparseGrid, SparseOptions,
};
use isolab_algorithms::extractors;
use isolab_algorithms::fields::{builtin, FieldParams};
use isolab_algorithms::{Chunking, Extraction, Extractor, Field, Grid, Lattice, Samples};
use isolab_metrics::topology;
use std::sync::Arc;

fn field(name: &str) -> Arc<dyn Field> {
    builtin(name, FieldParams::default()).expect("built-in field")
}

fn domain_grid(f: &dyn Field, resolution: usize) -> SparseGrid {
    let d = f.domain();
    let lo = d.min.to_array().map(f64::from);
    let hi = d.max.to_array().map(f64::from);
    SparseGrid::from_bounds(lo, hi, resolution).expect("grid")
}

fn run(
    e: &dyn Extractor,
    f: &dyn Field,
    grid: &SparseGrid,
    pruning: Pruning,
) -> (Extraction, isolab_algorithms::chunks::SparseStats) {
    let mut out = Extraction::default();
    let options = SparseOptions { chunk: 8, batch: 5000, pruning };
    let stats = extract_sparse(e, grid, 0.0, &options, &mut FieldEval(f), &mut out).expect("sparse extraction");
    (out, stats)
}

fn chunking_extractors() -> Vec<Box<dyn Extractor>> {
    extractors::registry().into_iter().filter(|e| e.chunking() != Chunking::Unsupported).collect()
}

#[test]
fn certified_pruning_gives_the_dense_mesh_for_every_extractor_that_meshes_in_blocks() {
    let extractors = chunking_extractors();
    assert!(extractors.len() >= 5, "{} extractors mesh in blocks", extractors.len());
    for name in ["sphere", "torus"] {
        let f = field(name);
        let grid = domain_grid(f.as_ref(), 57);
        for e in &extractors {
            let what = format!("{} on {name}", e.name());
            let (dense, dense_stats) = run(e.as_ref(), f.as_ref(), &grid, Pruning::Dense);
            let (sparse, stats) = run(e.as_ref(), f.as_ref(), &grid, Pruning::Lipschitz(1.0));
            assert!(!dense.surface.triangles.is_empty(), "{what}: no surface");
            assert_eq!(sparse.surface.positions, dense.surface.positions, "{what}: vertices");
            assert_eq!(sparse.surface.triangles, dense.surface.triangles, "{what}: triangles");
            assert_eq!(sparse.surface.normals, dense.surface.normals, "{what}: normals");
            // Each grid sample is evaluated at most once (dense: exactly once), so the sparse
            // run's evaluations are at most the dense grid's, the octree's centres (fewer than
            // two per block) and the refinement's (at most 8 + 64 per leaf).
            assert_eq!(dense_stats.evaluations, dense_stats.dense_points, "{what}: dense evaluations");
            assert!(
                stats.evaluations - stats.refinement_evaluations < dense_stats.evaluations + 2 * stats.blocks as u64,
                "{what}: {} evaluations, {} refining, dense {}",
                stats.evaluations,
                stats.refinement_evaluations,
                dense_stats.evaluations
            );
            assert!(stats.refinement_evaluations <= 72 * stats.blocks as u64, "{what}");
            assert!(stats.sampled_blocks < stats.blocks, "{what}: every block sampled");
        }
    }
}

#[test]
fn the_dense_mode_is_the_whole_grids_marching_cubes_in_world_units() {
    let f = field("sphere");
    let grid = domain_grid(f.as_ref(), 48);
    let mc = extractors::by_name("marching-cubes").expect("marching cubes");
    let (dense, stats) = run(mc.as_ref(), f.as_ref(), &grid, Pruning::Dense);
    assert!(stats.evaluations >= stats.dense_points, "every sample evaluated");
    let g = Grid::with_dims(&f.domain(), grid.dims).expect("grid");
    let whole = Samples::sample(f.clone(), Lattice::Cubic(g), 0.0).expect("samples");
    let mut single = Extraction::default();
    mc.extract(&whole, &mut single).expect("extraction");
    assert_eq!(dense.surface.triangles.len(), single.surface.triangles.len());
    assert_eq!(dense.surface.positions.len(), single.surface.positions.len());
    let t = topology(&dense.surface);
    assert!(t.closed && t.edge_manifold && t.outward && t.euler == 2, "{t:?}");
    // Every vertex on the sphere of radius 0.4, to the grid's interpolation error.
    let worst = dense.surface.positions.iter().map(|p| (p.length() - 0.4).abs()).fold(0.0f32, f32::max);
    assert!(worst < 0.2 * grid.spacing as f32, "{worst}");
}

#[test]
fn certified_pruning_evaluates_a_shell_not_the_volume() {
    let f = field("sphere");
    let grid = domain_grid(f.as_ref(), 257);
    let mc = extractors::by_name("marching-cubes").expect("marching cubes");
    let mut out = Extraction::default();
    let options = SparseOptions { chunk: 8, batch: 1 << 16, pruning: Pruning::Lipschitz(1.0) };
    let stats = extract_sparse(mc.as_ref(), &grid, 0.0, &options, &mut FieldEval(f.as_ref()), &mut out).expect("sparse");
    let ratio = stats.dense_points as f64 / stats.evaluations as f64;
    assert!(ratio > 5.0, "dense {} / sparse {} = {ratio}", stats.dense_points, stats.evaluations);
    let t = topology(&out.surface);
    assert!(t.closed && t.edge_manifold && t.euler == 2, "{t:?}");
}

/// A field that records every point it is asked for.
struct Recording<'a> {
    field: &'a dyn Field,
    points: Vec<[f64; 3]>,
}

impl BatchEval for Recording<'_> {
    fn eval(&mut self, points: &[[f64; 3]], out: &mut Vec<f64>) -> Result<(), EvalError> {
        self.points.extend_from_slice(points);
        FieldEval(self.field).eval(points, out)
    }
}

#[test]
fn no_grid_sample_is_evaluated_twice_and_the_dense_mode_evaluates_each_once() {
    // Small batches (many groups, blocks left for the next batch) and every apron: blocks share
    // faces and aprons, and each shared sample is still evaluated once; the mesh is the one
    // the dense mode gives.
    let f = field("torus");
    let grid = domain_grid(f.as_ref(), 41);
    let on_grid = |p: &[f64; 3]| {
        let t = [0, 1, 2].map(|a| (p[a] - grid.origin[a]) / grid.spacing);
        t.iter().all(|t| (t - t.round()).abs() < 1e-6).then(|| t.map(|t| t.round() as usize))
    };
    for e in chunking_extractors() {
        for pruning in [Pruning::Dense, Pruning::Lipschitz(1.0), Pruning::SignChange { margin: 1 }] {
            let what = format!("{} ({pruning:?})", e.name());
            let options = SparseOptions { chunk: 6, batch: 700, pruning };
            let mut recording = Recording { field: f.as_ref(), points: Vec::new() };
            let mut out = Extraction::default();
            let stats = extract_sparse(e.as_ref(), &grid, 0.0, &options, &mut recording, &mut out).expect("sparse");
            assert_eq!(stats.evaluations, recording.points.len() as u64, "{what}");
            let mut seen = std::collections::HashSet::new();
            // The octree's evaluations come first. After them the leaves' refinement and the
            // sampling take turns: every point off the grid is the refinement's, and no grid
            // sample is evaluated twice (a refinement centre on the grid is not sampled again).
            let octree = (stats.pruning_evaluations - stats.refinement_evaluations) as usize;
            let after = &recording.points[octree..];
            let samples: Vec<[usize; 3]> = after.iter().filter_map(on_grid).collect();
            assert!(after.len() - samples.len() <= stats.refinement_evaluations as usize, "{what}: a sampled point off the grid");
            for s in &samples {
                assert!(seen.insert(*s), "{what}: sample {s:?} evaluated twice");
            }
            if let Pruning::Lipschitz(_) = pruning {
                assert!(stats.refinement_evaluations > 0, "{what}: no leaf refined");
            } else {
                assert_eq!(stats.refinement_evaluations, 0, "{what}");
            }
            if pruning == Pruning::Dense {
                assert_eq!(stats.pruning_evaluations, 0, "{what}");
                assert_eq!(samples.len() as u64, stats.dense_points, "{what}");
                assert_eq!(stats.evaluations, stats.dense_points, "{what}");
            }
            assert!(!out.surface.triangles.is_empty(), "{what}: no surface");
        }
    }
}

#[test]
fn the_sign_change_heuristic_keeps_a_surface_larger_than_its_blocks() {
    let f = field("torus");
    let grid = domain_grid(f.as_ref(), 65);
    let mc = extractors::by_name("marching-cubes").expect("marching cubes");
    let (dense, _) = run(mc.as_ref(), f.as_ref(), &grid, Pruning::Dense);
    let (heuristic, stats) = run(mc.as_ref(), f.as_ref(), &grid, Pruning::SignChange { margin: 1 });
    assert_eq!(heuristic.surface.triangles, dense.surface.triangles);
    assert!(stats.sampled_blocks < stats.blocks);
}

/// An evaluator that answers wrongly on its `at`-th batch.
struct Faulty {
    at: u64,
    calls: u64,
    fault: Fault,
}

#[derive(Clone, Copy)]
enum Fault {
    Short,
    Nan,
    Fails,
}

#[derive(Debug)]
struct Mine;

impl std::fmt::Display for Mine {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("mine")
    }
}

impl std::error::Error for Mine {}

impl BatchEval for Faulty {
    fn eval(&mut self, points: &[[f64; 3]], out: &mut Vec<f64>) -> Result<(), EvalError> {
        out.clear();
        out.extend(points.iter().map(|p| (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt() - 0.4));
        self.calls += 1;
        if self.calls - 1 == self.at {
            match self.fault {
                Fault::Short => {
                    out.pop();
                }
                Fault::Nan => out[0] = f64::NAN,
                Fault::Fails => return Err(Box::new(Mine)),
            }
        }
        Ok(())
    }
}

#[test]
fn a_wrong_answer_names_its_batch_and_an_evaluators_error_comes_back_unchanged() {
    let grid = SparseGrid::from_bounds([-0.5; 3], [0.5; 3], 33).expect("grid");
    let mc = extractors::by_name("marching-cubes").expect("marching cubes");
    let options = SparseOptions { chunk: 8, batch: 1000, pruning: Pruning::Lipschitz(1.0) };
    for (fault, at) in [(Fault::Short, 0), (Fault::Short, 3), (Fault::Nan, 2), (Fault::Fails, 1)] {
        let mut eval = Faulty { at, calls: 0, fault };
        let mut out = Extraction::default();
        let err = extract_sparse(mc.as_ref(), &grid, 0.0, &options, &mut eval, &mut out).expect_err("a faulty evaluator");
        match (fault, err) {
            (Fault::Short, SparseError::BadBatch { batch, reason, lo, hi }) => {
                assert_eq!(batch, at);
                assert!(reason.contains("values; one value per point"), "{reason}");
                assert!((0..3).all(|a| lo[a] <= hi[a] && lo[a] >= -0.5 && hi[a] <= 0.5), "{lo:?} {hi:?}");
            }
            (Fault::Nan, SparseError::BadBatch { batch, reason, .. }) => {
                assert_eq!(batch, at);
                assert!(reason.contains("NaN"), "{reason}");
            }
            (Fault::Fails, SparseError::Eval(e)) => assert!(e.downcast_ref::<Mine>().is_some(), "{e}"),
            (_, other) => panic!("unexpected error: {other}"),
        }
    }
    // A grid the blocks cannot take is refused by name.
    let bad = SparseOptions { chunk: 1, ..options };
    let err = extract_sparse(mc.as_ref(), &grid, 0.0, &bad, &mut FieldEval(field("sphere").as_ref()), &mut Extraction::default());
    assert!(matches!(err, Err(SparseError::Extract(_))));
}

#[test]
fn welding_layer_by_layer_keeps_every_weld_of_the_whole_plan() {
    use isolab_algorithms::chunks::{mesh_block, weld_fragments, BlockPlan};
    let f = field("torus");
    let grid = domain_grid(f.as_ref(), 45);
    for e in chunking_extractors() {
        let chunk = SparseOptions::default_chunk(e.as_ref());
        let mut sparse = Extraction::default();
        let options = SparseOptions { chunk, batch: 4096, pruning: Pruning::Dense };
        extract_sparse(e.as_ref(), &grid, 0.0, &options, &mut FieldEval(f.as_ref()), &mut sparse).expect("sparse");
        // Every block of the plan, welded at once with every key kept.
        let plan = BlockPlan::new(e.as_ref(), grid.dims, chunk).expect("plan");
        let fragments: Vec<_> = plan
            .blocks()
            .map(|b| {
                let mut values = Vec::new();
                for z in 0..b.dims[2] {
                    for y in 0..b.dims[1] {
                        for x in 0..b.dims[0] {
                            let p = grid.point([b.lo[0] + x, b.lo[1] + y, b.lo[2] + z]);
                            values.push(f.value(glam::Vec3::new(p[0] as f32, p[1] as f32, p[2] as f32)));
                        }
                    }
                }
                mesh_block(e.as_ref(), &plan, b.id, values, 0.0).expect("block")
            })
            .collect();
        let mut whole = Extraction::default();
        weld_fragments(&fragments, &mut whole);
        let to_index = |p: &glam::Vec3| [0, 1, 2].map(|a| ((f64::from(p.to_array()[a]) - grid.origin[a]) / grid.spacing) as f32);
        let welded: Vec<[f32; 3]> = sparse.surface.positions.iter().map(to_index).collect();
        assert_eq!(sparse.surface.triangles, whole.surface.triangles, "{}", e.name());
        assert_eq!(welded.len(), whole.surface.positions.len(), "{}", e.name());
        for (a, b) in welded.iter().zip(&whole.surface.positions) {
            assert!((0..3).all(|k| (a[k] - b.to_array()[k]).abs() < 1e-3), "{}: {a:?} vs {b:?}", e.name());
        }
    }
}

#[test]
fn certified_pruning_gives_the_dense_mesh_at_257_samples_a_side() {
    let f = field("sphere");
    let grid = domain_grid(f.as_ref(), 257);
    for e in chunking_extractors() {
        let chunk = SparseOptions::default_chunk(e.as_ref());
        let mut meshes = Vec::new();
        for pruning in [Pruning::Dense, Pruning::Lipschitz(1.0)] {
            let mut out = Extraction::default();
            let options = SparseOptions { chunk, batch: 1 << 16, pruning };
            extract_sparse(e.as_ref(), &grid, 0.0, &options, &mut FieldEval(f.as_ref()), &mut out).expect("sparse");
            meshes.push(out);
        }
        assert!(!meshes[0].surface.triangles.is_empty(), "{}", e.name());
        assert_eq!(meshes[1].surface.positions, meshes[0].surface.positions, "{}", e.name());
        assert_eq!(meshes[1].surface.triangles, meshes[0].surface.triangles, "{}", e.name());
    }
}

/// Every built-in field and a shipped model's distance field, each under its own Lipschitz bound.
fn certified_fields() -> Vec<Arc<dyn Field>> {
    let mut fields: Vec<Arc<dyn Field>> = isolab_algorithms::fields::registry().iter().map(|i| field(i.name)).collect();
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let spot = isolab_io::read_mesh(&root.join("models/spot.obj")).expect("spot.obj");
    let mesh = isolab_algorithms::fields::MeshField::new("spot", &spot.positions, &spot.triangles).expect("mesh field");
    assert!(mesh.is_closed(), "spot is closed, so its signed distance is 1-Lipschitz");
    fields.push(Arc::new(mesh));
    fields
}

#[test]
fn every_certified_field_gives_the_dense_chunked_mesh_for_every_extractor_that_meshes_in_blocks() {
    let chunk = 16;
    for f in certified_fields() {
        let l = f.lipschitz().unwrap_or_else(|| panic!("{} has no bound", f.name()));
        let grid = Grid::with_dims(&f.domain(), [6 * chunk + 1; 3]).expect("grid");
        let dense = Samples::sample(f.clone(), Lattice::Cubic(grid), 0.0).expect("samples");
        for e in chunking_extractors() {
            let what = format!("{} on {} (L = {l:.2})", e.name(), f.name());
            let mut whole = Extraction::default();
            isolab_algorithms::chunks::extract_chunked(e.as_ref(), &dense, chunk, &mut whole).expect(&what);
            let mut sparse = Extraction::default();
            let options = SparseOptions { chunk, batch: 1 << 16, pruning: Pruning::Lipschitz(l) };
            let mut eval = GridFieldEval { field: f.clone(), grid };
            let stats = extract_sparse(e.as_ref(), &SparseGrid::of(&grid), 0.0, &options, &mut eval, &mut sparse).expect(&what);
            assert!(!whole.surface.triangles.is_empty(), "{what}: no surface");
            assert!(stats.sampled_blocks <= stats.blocks, "{what}");
            assert!(sparse.surface.triangles == whole.surface.triangles, "{what}: triangles differ");
            assert!(sparse.surface.positions == whole.surface.positions, "{what}: vertices differ");
            let differ = sparse.surface.normals.iter().zip(&whole.surface.normals).filter(|(a, b)| a != b).count();
            assert!(
                sparse.surface.normals.len() == whole.surface.normals.len() && differ == 0,
                "{what}: {differ} of {} normals differ",
                whole.surface.normals.len()
            );
        }
    }
}

/// A mesh the memory limit cannot hold is refused before the samples of the blocks past the
/// limit are evaluated: the error names the bytes needed and the limit, nothing is output, and
/// fewer points were evaluated than the full run's; at the full run's estimate it goes through.
/// The estimate (48 bytes per face cell of a kept block) is within a factor of two of the mesh.
#[test]
fn a_sparse_mesh_over_the_memory_limit_is_refused_before_its_blocks_are_sampled() {
    use isolab_algorithms::ExtractError;
    let f = field("sphere");
    let grid = domain_grid(f.as_ref(), 257);
    let mc = extractors::by_name("marching-cubes").expect("marching cubes");
    let options = SparseOptions { chunk: 8, batch: 1 << 12, pruning: Pruning::Lipschitz(1.0) };
    let mut full = Extraction::default();
    let mut all = Recording { field: f.as_ref(), points: Vec::new() };
    let stats = extract_sparse(mc.as_ref(), &grid, 0.0, &options, &mut all, &mut full).expect("sparse");
    let estimate = stats.sampled_blocks as u64 * 64 * 48;
    let made = (full.surface.positions.len() * 24 + full.surface.triangles.len() * 12) as u64;
    assert!(estimate < 2 * made && made < 2 * estimate, "estimate {estimate} for a mesh of {made} bytes");

    let mut refused = Extraction { memory_limit: Some(estimate / 2), ..Default::default() };
    let mut some = Recording { field: f.as_ref(), points: Vec::new() };
    match extract_sparse(mc.as_ref(), &grid, 0.0, &options, &mut some, &mut refused) {
        Err(SparseError::Extract(ExtractError::OverMemory { needed, limit, .. })) => {
            assert_eq!(limit, estimate / 2);
            assert!(needed > limit && needed <= estimate, "needed {needed}, limit {limit}, whole {estimate}");
        }
        other => panic!("expected a refusal, got {other:?}"),
    }
    assert!(refused.surface.positions.is_empty() && refused.surface.triangles.is_empty());
    assert!(some.points.len() < all.points.len(), "{} of {} points evaluated", some.points.len(), all.points.len());

    let mut enough = Extraction { memory_limit: Some(estimate), ..Default::default() };
    extract_sparse(mc.as_ref(), &grid, 0.0, &options, &mut FieldEval(f.as_ref()), &mut enough).expect("within the limit");
    assert_eq!(enough.surface.triangles, full.surface.triangles);
}
