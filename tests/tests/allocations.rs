//! Steady-state re-meshing allocates nothing: a counting global allocator around the second
//! extraction of same-sized samples into the same output buffers (issue 8: re-meshing a dirty
//! chunk in a frame). Single-threaded rayon pool, so the count is the extractor's own.

use isolab_algorithms::{extractors, Extraction, Grid, Lattice, Samples};
use stats_alloc::{Region, StatsAlloc, INSTRUMENTED_SYSTEM};
use std::alloc::System;

#[global_allocator]
static GLOBAL: &StatsAlloc<System> = &INSTRUMENTED_SYSTEM;

fn chunk_samples(seed: i32) -> Samples {
    let field = isolab_algorithms::fields::builtin("terrain", isolab_algorithms::fields::FieldParams { seed }).unwrap();
    let grid = Grid::with_dims(&field.domain(), [33, 33, 33]).unwrap();
    Samples::sample(field, Lattice::Cubic(grid), 0.0).unwrap()
}

/// The cubic-grid surface extractors re-mesh a 32³ chunk without allocating. (The tetrahedral
/// engine still allocates its per-sample scratch on every call: not yet covered.)
#[test]
fn steady_state_remeshing_allocates_nothing() {
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
    let (a, b) = (chunk_samples(1), chunk_samples(2));
    for name in ["marching-cubes", "marching-cubes-decider", "surface-nets", "dual-contouring"] {
        let e = extractors::by_name(name).unwrap();
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
