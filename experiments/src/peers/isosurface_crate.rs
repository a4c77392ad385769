//! The `isosurface` crate's marching cubes (one thread, n³ grids only). It samples a `Source`
//! itself: ours reads the stored grid, so its time includes that lookup. It also meshes one layer
//! of cells past the far faces, which a closed surface inside the grid never reaches. One-shot:
//! new output vectors; steady state: the vectors cleared and reused.

use super::{Job, Peer, PeerError, PeerRun, Protocol};
use std::time::Instant;

/// The stored grid as the crate's `Source`: it asks for values at `(x, y, z)` in the unit cube in
/// steps of `1 / (n - 1)`; past the far faces (where it also looks) the grid is outside.
struct GridSource<'a> {
    values: &'a [f32],
    n: usize,
}

impl isosurface::source::Source for GridSource<'_> {
    fn sample(&self, x: f32, y: f32, z: f32) -> f32 {
        let last = (self.n - 1) as f32;
        let index = |c: f32| (c * last).round() as usize;
        let (i, j, k) = (index(x), index(y), index(z));
        if i >= self.n || j >= self.n || k >= self.n {
            return 1.0;
        }
        self.values[i + self.n * (j + self.n * k)]
    }
}

/// The `isosurface` crate peer (jobs: [`Job::Grid`] on n³ grids at iso-value 0).
#[derive(Default)]
pub struct IsosurfaceCrate {
    vertices: Vec<f32>,
    indices: Vec<u32>,
}

impl Peer for IsosurfaceCrate {
    fn name(&self) -> String {
        "isosurface crate".into()
    }

    fn run(&mut self, job: &Job<'_>, protocol: Protocol) -> Result<PeerRun, PeerError> {
        let Job::Grid { samples, .. } = job else { return Err(self.unsupported()) };
        let [nx, ny, nz] = samples.lattice().grid().dims;
        if nx != ny || ny != nz || samples.iso() != 0.0 {
            return Err(PeerError::Failed { peer: self.name(), message: "meshes n³ grids at the zero level only".into() });
        }
        // One-shot: fresh vectors, freed at the end of this call (after the timing), as our
        // one-shot output is; freeing the last call's just before the timing would hand this call
        // pages already touched.
        let (mut fresh_vertices, mut fresh_indices) = (Vec::new(), Vec::new());
        let (vertices, indices) = match protocol {
            Protocol::OneShot => (&mut fresh_vertices, &mut fresh_indices),
            Protocol::SteadyState => (&mut self.vertices, &mut self.indices),
        };
        vertices.clear();
        indices.clear();
        let source = GridSource { values: samples.values(), n: nx };
        let t = Instant::now();
        isosurface::marching_cubes::MarchingCubes::new(nx).extract(&source, vertices, indices);
        let time = t.elapsed();
        Ok(PeerRun { time, vertices: vertices.len() / 3, triangles: indices.len() / 3, ..PeerRun::default() })
    }
}
