//! The report promises the same numbers on every run (times aside): metrics must not depend on
//! how rayon splits work.

use isolab_metrics::MeshMetrics;
use isolab_pipeline::{run, RunConfig};

#[test]
fn measuring_twice_gives_identical_json() {
    let out = run(&RunConfig::new("marching-cubes", "gyroid", 48)).unwrap();
    let field = isolab_algorithms::fields::builtin("gyroid", Default::default()).unwrap();
    let a = serde_json::to_string(&MeshMetrics::measure(&out.extraction.surface, Some((field.as_ref(), 0.0)))).unwrap();
    for _ in 0..3 {
        let b = serde_json::to_string(&MeshMetrics::measure(&out.extraction.surface, Some((field.as_ref(), 0.0)))).unwrap();
        assert_eq!(a, b);
    }
    // On one thread and on two (rayon splits the work differently).
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        let b = pool
            .install(|| serde_json::to_string(&MeshMetrics::measure(&out.extraction.surface, Some((field.as_ref(), 0.0)))))
            .unwrap();
        assert_eq!(a, b, "metrics on {threads} thread(s)");
    }
    // And extraction itself is repeatable.
    let again = run(&RunConfig::new("marching-cubes", "gyroid", 48)).unwrap();
    assert_eq!(again.extraction.surface, out.extraction.surface);
}
