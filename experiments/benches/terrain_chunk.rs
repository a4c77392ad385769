//! Criterion benchmark of issue 8's frame budget item: re-meshing one dirty 32³-cell terrain
//! chunk (33³ samples at the `terrain_edit` world's spacing, placed across the surface), sampling
//! included, output and scratch buffers reused as in steady state. Targets: at most 0.5 ms for
//! marching cubes and surface nets, 1 ms for regularised marching tetrahedra (median).

use criterion::{criterion_group, criterion_main, Criterion};
use glam::Vec3;
use isolab_algorithms::{extractors, fields, Extraction, Grid, Samples};
use std::time::Duration;

fn dirty_chunk(c: &mut Criterion) {
    let field = fields::builtin("terrain", Default::default()).unwrap();
    // The terrain_edit world: 256 cells across a 1-unit domain; this chunk straddles y = 0.
    let spacing = 1.0 / 256.0;
    let grid = Grid { origin: Vec3::new(0.0, -16.0 * spacing, 0.0), spacing, dims: [33, 33, 33] };
    let mut group = c.benchmark_group("terrain-chunk-32");
    group.sample_size(50).measurement_time(Duration::from_secs(4));
    for name in ["marching-cubes", "surface-nets", "dual-contouring", "marching-tetrahedra", "regularised-marching-tetrahedra"] {
        let e = extractors::by_name(name).unwrap();
        let mut out = Extraction::default();
        let probe = Samples::sample_cubic(field.clone(), grid, 0.0).unwrap();
        e.extract(&probe, &mut out).unwrap();
        assert!(!out.surface.triangles.is_empty(), "the chunk holds surface");
        group.bench_function(format!("{name}/sampling+extraction"), |b| {
            b.iter(|| {
                let samples = Samples::sample_cubic(field.clone(), grid, 0.0).unwrap();
                e.extract(&samples, &mut out).unwrap();
                out.surface.triangles.len()
            })
        });
        group.bench_function(format!("{name}/extraction"), |b| {
            b.iter(|| {
                e.extract(&probe, &mut out).unwrap();
                out.surface.triangles.len()
            })
        });
    }
    group.finish();
}

criterion_group!(benches, dirty_chunk);
criterion_main!(benches);
