//! Steady-state re-meshing allocates nothing: a counting global allocator around the second
//! extraction of same-sized samples into the same output buffers (issue 8: re-meshing a dirty
//! chunk in a frame). Single-threaded rayon pool, so the count is the extractor's own.

use isolab_algorithms::{extractors, Extraction, Grid, Lattice, Samples};
use stats_alloc::{Region, StatsAlloc, INSTRUMENTED_SYSTEM};
use std::alloc::System;

#[global_allocator]
static GLOBAL: &StatsAlloc<System> = &INSTRUMENTED_SYSTEM;

/// The counts are process-wide: tests take turns.
static TURN: std::sync::Mutex<()> = std::sync::Mutex::new(());

fn chunk_samples(seed: i32) -> Samples<'static> {
    let field = isolab_algorithms::fields::builtin("terrain", isolab_algorithms::fields::FieldParams { seed }).unwrap();
    let grid = Grid::with_dims(&field.domain(), [33, 33, 33]).unwrap();
    Samples::sample(field, Lattice::Cubic(grid), 0.0).unwrap()
}

/// Every chunking extractor re-meshes a 32³ chunk without allocating (the tetrahedral engine's
/// guard, marching cubes 33's tunnel tests and the dual engine's passes keep their buffers too).
#[test]
fn steady_state_remeshing_allocates_nothing() {
    let _turn = TURN.lock().unwrap_or_else(|e| e.into_inner());
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
    let (a, b) = (chunk_samples(1), chunk_samples(2));
    // Every registered extractor that meshes in chunks (the registry's list, not a hand-kept one):
    // a chunk re-meshed in a frame must not allocate, whoever wrote the extractor.
    for e in extractors::registry().into_iter().filter(|e| e.chunking() != isolab_algorithms::Chunking::Unsupported) {
        let name = e.name();
        let mut out = Extraction::default();
        let counts = pool.install(|| {
            // Warm up on both so buffers reach their steady size.
            for s in [&a, &b, &a, &b] {
                e.extract(s, &mut out).unwrap();
            }
            let region = Region::new(GLOBAL);
            e.extract(&a, &mut out).unwrap();
            let c = region.change();
            c.allocations + c.reallocations
        });
        assert_eq!(counts, 0, "{name} allocated while re-meshing a 32^3 chunk");
    }
}

/// The whole edit path: a brush edit on a `ChunkedVolume` and re-meshing the dirty chunks through
/// their persistent slots (samples copied out with their apron, origins, ownership, keys) allocates
/// nothing once the slots' buffers have grown, for the cell-local and apron extractors alike.
#[test]
fn steady_state_brush_edits_allocate_nothing() {
    let _turn = TURN.lock().unwrap_or_else(|e| e.into_inner());
    use isolab_algorithms::chunks::{Brush, ChunkedVolume};
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
    let field = isolab_algorithms::fields::builtin("terrain", Default::default()).unwrap();
    let grid = Grid::with_dims(&field.domain(), [65, 33, 65]).unwrap();
    let samples = Samples::sample(field, Lattice::Cubic(grid), 0.0).unwrap();
    // On the surface of the centre column.
    let inside = |y: usize| samples.values()[grid.index(32, y, 32)] < 0.0;
    let y = (1..32).find(|&y| inside(y) != inside(y + 1)).unwrap();
    let centre = grid.position(32, y, 32);
    // Every registered extractor that meshes in chunks (the registry's list, not a hand-kept one).
    for e in extractors::registry().into_iter().filter(|e| e.chunking() != isolab_algorithms::Chunking::Unsupported) {
        let name = e.name();
        let mut world = ChunkedVolume::new(e.as_ref(), samples.clone(), 16).unwrap();
        let counts = pool.install(|| {
            world.remesh_dirty(e.as_ref()).unwrap();
            let brush = |add| Brush { centre, radius: 3.0 * grid.spacing, falloff: grid.spacing, add, material: 0 };
            for k in 0..6 {
                world.apply(&brush(k % 2 == 0)).unwrap();
                world.remesh_dirty(e.as_ref()).unwrap();
            }
            let region = Region::new(GLOBAL);
            world.apply(&brush(true)).unwrap();
            let dirtied = world.remesh_dirty(e.as_ref()).unwrap();
            assert!(dirtied > 0);
            let c = region.change();
            c.allocations + c.reallocations
        });
        assert_eq!(counts, 0, "{name} allocated during a steady-state brush edit");
    }
}
