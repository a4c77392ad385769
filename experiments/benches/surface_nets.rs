//! Criterion benchmarks: our surface nets (no smoothing, and the default elastic smoothing) side by
//! side with the `fast-surface-nets` crate in one run, on the same sampled grids (sphere and
//! gyroid, 64^3 to 256^3), sampling excluded, steady state (buffers reused) and one-shot (a new
//! extractor and output, or a new `SurfaceNetsBuffer`, every call; each dropped after its call
//! outside the timing, as `peers` frees its one-shot outputs: see [`one_shot`]);
//! and the smoothing methods on a 32^3 terrain chunk.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
mod protocol;
use fast_surface_nets::ndshape::{RuntimeShape, Shape};
use fast_surface_nets::{surface_nets, SurfaceNetsBuffer};
use isolab_algorithms::extractors::surface_nets::{Smoothing, SnOptions, SurfaceNets};
use isolab_algorithms::sweep::slabs::Parallelism;
use isolab_algorithms::{fields, Extraction, Extractor, Grid, Samples};
use protocol::one_shot;
use std::hint::black_box;
use std::time::Duration;

fn side_by_side(c: &mut Criterion) {
    let mut group = c.benchmark_group("surface_nets");
    group.sample_size(20).measurement_time(Duration::from_secs(4));
    for name in ["sphere", "gyroid"] {
        let field = fields::builtin(name, Default::default()).unwrap();
        for n in [64, 128, 256] {
            let grid = Grid::covering(&field.domain(), n).unwrap();
            let samples = Samples::sample_cubic(field.clone(), grid, 0.0).unwrap();
            let plain = SurfaceNets::new(SnOptions { smoothing: Smoothing::None, ..Default::default() });
            let serial = SurfaceNets::new(SnOptions {
                smoothing: Smoothing::None,
                parallelism: Parallelism::Serial,
                ..Default::default()
            });
            let smoothed = SurfaceNets::default();
            let mut out = Extraction::default();
            group.bench_with_input(BenchmarkId::new(format!("isolab/{name}"), n), &samples, |b, s| {
                b.iter(|| plain.extract(black_box(s), &mut out).unwrap())
            });
            group.bench_with_input(BenchmarkId::new(format!("isolab-one-shot/{name}"), n), &samples, |b, s| {
                one_shot(b, || {
                    let mut fresh = Extraction::default();
                    SurfaceNets::new(SnOptions { smoothing: Smoothing::None, ..Default::default() })
                        .extract(black_box(s), &mut fresh)
                        .unwrap();
                    fresh
                })
            });
            group.bench_with_input(BenchmarkId::new(format!("isolab-serial/{name}"), n), &samples, |b, s| {
                b.iter(|| serial.extract(black_box(s), &mut out).unwrap())
            });
            // One-shot: a new extractor and a new output every call.
            group.bench_with_input(BenchmarkId::new(format!("isolab-serial-one-shot/{name}"), n), &samples, |b, s| {
                one_shot(b, || {
                    let mut fresh = Extraction::default();
                    SurfaceNets::new(SnOptions {
                        smoothing: Smoothing::None,
                        parallelism: Parallelism::Serial,
                        ..Default::default()
                    })
                    .extract(black_box(s), &mut fresh)
                    .unwrap();
                    fresh
                })
            });
            group.bench_with_input(BenchmarkId::new(format!("isolab-elastic/{name}"), n), &samples, |b, s| {
                b.iter(|| smoothed.extract(black_box(s), &mut out).unwrap())
            });
            let [nx, ny, nz] = grid.dims.map(|d| d as u32);
            let shape = RuntimeShape::<u32, 3>::new([nx, ny, nz]);
            assert_eq!(shape.linearize([1, 2, 3]) as usize, grid.index(1, 2, 3), "same index order");
            let mut buffer = SurfaceNetsBuffer::default();
            group.bench_with_input(BenchmarkId::new(format!("fast-surface-nets/{name}"), n), &samples, |b, s| {
                b.iter(|| surface_nets(black_box(s.values()), &shape, [0; 3], [nx - 1, ny - 1, nz - 1], &mut buffer))
            });
            group.bench_with_input(BenchmarkId::new(format!("fast-surface-nets-one-shot/{name}"), n), &samples, |b, s| {
                one_shot(b, || {
                    let mut fresh = SurfaceNetsBuffer::default();
                    surface_nets(black_box(s.values()), &shape, [0; 3], [nx - 1, ny - 1, nz - 1], &mut fresh);
                    fresh
                })
            });
        }
    }
    group.finish();
}

fn smoothing_on_a_terrain_chunk(c: &mut Criterion) {
    let field = fields::builtin("terrain", Default::default()).unwrap();
    let grid = Grid::with_dims(&field.domain(), [33, 33, 33]).unwrap();
    let samples = Samples::sample_cubic(field.clone(), grid, 0.0).unwrap();
    let mut group = c.benchmark_group("surface_nets_smoothing_32");
    group.sample_size(20);
    for (label, smoothing) in [
        ("none", Smoothing::None),
        ("elastic", Smoothing::Elastic),
        ("spring", Smoothing::Spring),
        ("implicit", Smoothing::Implicit),
    ] {
        let sn = SurfaceNets::new(SnOptions { smoothing, iterations: 5, ..Default::default() });
        let mut out = Extraction::default();
        group.bench_function(label, |b| b.iter(|| sn.extract(black_box(&samples), &mut out).unwrap()));
    }
    group.finish();
}

criterion_group!(benches, side_by_side, smoothing_on_a_terrain_chunk);
criterion_main!(benches);
