//! Shared helpers for the integration tests in `tests/tests/`.

use glam::Vec3;
use isolab_algorithms::{Extraction, Extractor, Grid, Lattice, Samples, TriMesh};
use isolab_metrics::{topology, Topology};

/// Path of a shipped model.
pub fn model(name: &str) -> String {
    format!("{}/../models/{name}", env!("CARGO_MANIFEST_DIR"))
}

/// Samples on a unit-spaced cubic grid of `dims`, from a closure of the integer coordinates.
pub fn grid_samples(dims: [usize; 3], value: impl Fn(usize, usize, usize) -> f32) -> Samples {
    let grid = Grid { origin: Vec3::ZERO, spacing: 1.0, dims };
    let mut values = Vec::with_capacity(grid.len());
    for z in 0..dims[2] {
        for y in 0..dims[1] {
            for x in 0..dims[0] {
                values.push(value(x, y, z));
            }
        }
    }
    Samples::from_values(Lattice::Cubic(grid), values, 0.0).expect("finite values")
}

/// Runs `extractor` on `samples`.
pub fn extract(extractor: &dyn Extractor, samples: &Samples) -> Extraction {
    let mut out = Extraction::default();
    extractor.extract(samples, &mut out).expect("extraction succeeds");
    out
}

/// The invariant checker every extractor test ends with: closed, edge- and vertex-manifold,
/// consistently oriented, outward, no unused vertex, every index in range, and an even Euler
/// characteristic no larger than twice the components (a union of closed orientable surfaces).
/// Panics with the topology report on failure; returns it otherwise.
pub fn assert_closed_manifold(mesh: &TriMesh, what: &str) -> Topology {
    let n = mesh.positions.len() as u32;
    assert!(mesh.triangles.iter().flatten().all(|&i| i < n), "{what}: index out of range");
    let t = topology(mesh);
    if mesh.triangles.is_empty() {
        return t;
    }
    assert!(t.is_watertight_manifold() && t.outward && t.unused_vertices == 0, "{what}: {t:#?}");
    assert!(t.euler % 2 == 0 && t.euler <= 2 * t.components as i64, "{what}: euler {} with {} components", t.euler, t.components);
    t
}
