//! Criterion benchmarks: marching cubes alone (sampling excluded, no normals, as in `peers`) on
//! `sphere` and `gyroid` at 64^3, 128^3 and 256^3, serial and on rayon's global pool, steady state
//! (extractor and output reused) and one-shot (both new every call, each output dropped after its
//! call outside the timing, as `peers` frees its one-shot outputs: see [`one_shot`]), and sampling
//! the bunny field at the RMT paper's 75x40x56.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
mod protocol;
use isolab_algorithms::extractors::marching_cubes::{MarchingCubes, McOptions, NormalSource};
use isolab_algorithms::sweep::slabs::Parallelism;
use isolab_algorithms::{fields, Extraction, Extractor, Grid, Lattice, Samples};
use isolab_pipeline::load_field;
use protocol::one_shot;
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
            // As the `peers` experiment runs it: no normals (VTK runs with ComputeNormalsOff),
            // serial, or on rayon's global pool (as many threads as cores).
            for (label, parallelism) in [("serial", Parallelism::Serial), ("rayon", Parallelism::Rayon)] {
                let options = McOptions { normals: NormalSource::None, parallelism, ..Default::default() };
                let mc = MarchingCubes::new(options);
                let mut out = Extraction::default();
                group.bench_with_input(BenchmarkId::new(format!("{name}/{label}"), n), &samples, |b, s| {
                    b.iter(|| mc.extract(black_box(s), &mut out).unwrap())
                });
                // One-shot: a new extractor and a new output every call.
                group.bench_with_input(BenchmarkId::new(format!("{name}/{label}/one-shot"), n), &samples, |b, s| {
                    one_shot(b, || {
                        let mut fresh = Extraction::default();
                        MarchingCubes::new(options).extract(black_box(s), &mut fresh).unwrap();
                        fresh
                    })
                });
            }
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
