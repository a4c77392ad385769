//! Criterion benchmark of issue 8's frame budget item: re-meshing one dirty 32³-cell terrain
//! chunk (33³ samples at the `terrain_edit` world's spacing, placed across the surface), sampling
//! included, output and scratch buffers reused as in steady state. Targets (issue 15, meshing
//! alone, median): marching cubes at most 0.4 ms, surface nets 0.5 ms (its default four elastic
//! smoothing passes included), regularised marching tetrahedra 1 ms.
//!
//! Three measures per extractor: `sampling+extraction` (the chunk's 33³ samples from the noise
//! field, then meshing), `extraction` (meshing alone), and `brush-edit`: in a 3x3x3-chunk
//! `ChunkedVolume`, one small brush inside the centre chunk (alternately adding and carving) and
//! `remesh_dirty`, which re-meshes that one chunk through the real path, apron included
//! (surface nets reads 2 + 4 samples beyond each face, dual contouring 2, regularised MT 3).

use criterion::{criterion_group, criterion_main, Criterion};
use glam::Vec3;
use isolab_algorithms::chunks::{Brush, ChunkedVolume};
use isolab_algorithms::{extractors, fields, Extraction, Grid, Lattice, Samples};
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
        let world_grid =
            Grid { origin: Vec3::new(-32.0 * spacing, -48.0 * spacing, -32.0 * spacing), spacing, dims: [97, 97, 97] };
        let world_samples = Samples::sample(field.clone(), Lattice::Cubic(world_grid), 0.0).unwrap();
        // On the surface of the centre column, kept 8 cells inside the centre chunk.
        let inside = |y: usize| world_samples.values()[world_grid.index(48, y, 48)] < 0.0;
        let surface_y = (41..=55).find(|&y| inside(y) != inside(y + 1)).unwrap_or(48);
        let centre = world_grid.position(48, surface_y, 48);
        let mut world = ChunkedVolume::new(e.as_ref(), world_samples, 32).unwrap();
        world.remesh_dirty(e.as_ref()).unwrap();
        let mut add = true;
        group.bench_function(format!("{name}/brush-edit"), |b| {
            b.iter(|| {
                let brush = Brush { centre, radius: 3.0 * spacing, falloff: spacing, add, material: 0 };
                add = !add;
                assert_eq!(world.apply(&brush).unwrap(), 1, "one chunk dirtied");
                world.remesh_dirty(e.as_ref()).unwrap()
            })
        });
    }
    group.finish();
}

criterion_group!(benches, dirty_chunk);
criterion_main!(benches);
