//! The `fast-surface-nets` crate (bonsairobo, MIT/Apache): naive surface nets on a dense grid, one
//! thread. One-shot: a new `SurfaceNetsBuffer` per call, freed after it; steady state: the buffer
//! reused, as a game engine meshing chunk after chunk does.

use super::{Job, Peer, PeerError, PeerRun, Protocol};
use fast_surface_nets::ndshape::RuntimeShape;
use fast_surface_nets::{surface_nets, SurfaceNetsBuffer};
use std::time::Instant;

/// The `fast-surface-nets` peer (jobs: [`Job::Grid`], iso-value 0, one thread).
#[derive(Default)]
pub struct FastSurfaceNets {
    buffer: SurfaceNetsBuffer,
}

impl Peer for FastSurfaceNets {
    fn name(&self) -> String {
        "fast-surface-nets".into()
    }

    fn run(&mut self, job: &Job<'_>, protocol: Protocol) -> Result<PeerRun, PeerError> {
        let Job::Grid { samples, .. } = job else { return Err(self.unsupported()) };
        if samples.iso() != 0.0 {
            return Err(PeerError::Failed { peer: self.name(), message: "meshes the zero level only".into() });
        }
        let [nx, ny, nz] = samples.lattice().grid().dims.map(|d| d as u32);
        let shape = RuntimeShape::<u32, 3>::new([nx, ny, nz]);
        // One-shot: a fresh buffer, freed at the end of this call (after the timing), as our
        // one-shot output is; freeing the last call's just before the timing would hand this call
        // pages already touched.
        let mut fresh = SurfaceNetsBuffer::default();
        let buffer = match protocol {
            Protocol::OneShot => &mut fresh,
            Protocol::SteadyState => &mut self.buffer,
        };
        let t = Instant::now();
        surface_nets(samples.values(), &shape, [0; 3], [nx - 1, ny - 1, nz - 1], buffer);
        let time = t.elapsed();
        Ok(PeerRun { time, vertices: buffer.positions.len(), triangles: buffer.indices.len() / 3, ..PeerRun::default() })
    }
}
