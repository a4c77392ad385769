//! Criterion benchmarks: marching cubes alone (sampling excluded) on `sphere` and `gyroid` at
//! 64^3, 128^3 and 256^3, steady state (extractor and output reused) and one-shot (both new every
//! call, dropped outside the timing), and sampling the bunny field at the RMT paper's 75x40x56.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use isolab_algorithms::{extractors::MarchingCubes, fields, Extraction, Extractor, Grid, Lattice, Samples};
use isolab_experiments::run::load_field;
use std::hint::black_box;
use std::time::Duration;

fn marching_cubes(c: &mut Criterion) {
    let mut group = c.benchmark_group("marching_cubes");
    group.sample_size(20).measurement_time(Duration::from_secs(4));
    for name in ["sphere", "gyroid"] {
        let field = fields::builtin(name, Default::default()).unwrap();
        for n in [64, 128, 256] {
            let grid = Grid::covering(&field.domain(), n).unwrap();
            let samples = Samples::sample_cubic(field.clone(), grid, 0.0).unwrap();
            let mc = MarchingCubes::default();
            let mut out = Extraction::default();
            group.bench_with_input(BenchmarkId::new(name, n), &samples, |b, s| {
                b.iter(|| mc.extract(black_box(s), &mut out).unwrap())
            });
            // One-shot: a new extractor and a new output every call (dropped outside the timing).
            group.bench_with_input(BenchmarkId::new(format!("{name}/one-shot"), n), &samples, |b, s| {
                b.iter_with_large_drop(|| {
                    let mut fresh = Extraction::default();
                    MarchingCubes::default().extract(black_box(s), &mut fresh).unwrap();
                    fresh
                })
            });
        }
    }
    group.finish();
}

fn sample_bunny(c: &mut Criterion) {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../models/stanford-bunny.obj");
    let field = load_field(path, 0).unwrap();
    let grid = Grid::with_dims(&field.domain(), [75, 40, 56]).unwrap();
    let mut group = c.benchmark_group("sampling");
    group.sample_size(10);
    group.bench_function("bunny_75x40x56", |b| b.iter(|| Samples::sample(field.clone(), Lattice::Cubic(grid), 0.0).unwrap()));
    group.finish();
}

criterion_group!(benches, marching_cubes, sample_bunny);
criterion_main!(benches);
