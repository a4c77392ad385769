//! The implementations we compare against (and ours, run the same way), behind one small trait,
//! one file per peer.
//!
//! A [`Peer`] takes a [`Job`] (mesh this grid, mesh this field, decimate this mesh, mesh this
//! scan) under a [`Protocol`] and answers with a [`PeerRun`]: its time, its counts and, where it
//! hands one back, its mesh. A peer that does not do a job says so ([`PeerError::Unsupported`]).
//!
//! - [`ours::Ours`]: one of our registered extractors, run like the peers (one-shot: a new
//!   extractor and a fresh `Extraction` per call; steady state: both kept between calls).
//! - [`cli::Cli`]: our command line, a process per call on the grid file, timed by the
//!   extraction time it reports (one-shot only).
//! - [`fast_surface_nets::FastSurfaceNets`]: the `fast-surface-nets` crate (one-shot: a new
//!   `SurfaceNetsBuffer`; steady state: the buffer reused, as a game engine does).
//! - [`isosurface_crate::IsosurfaceCrate`]: the `isosurface` crate's marching cubes.
//! - [`ferreus_rmt::FerreusRmt`]: the `ferreus_rmt` crate, a surface-following regularised
//!   marching tetrahedra that samples the field itself.
//! - [`python::PythonPeer`]: the peers in `tests/reference/peers.py` (VTK flying edges and
//!   marching cubes, scikit-image, PyMCubes, libigl, pymeshlab's quadric decimation, the scan
//!   pipeline of nibabel + VTK), one long-lived Python process serving all of them. Their code is
//!   in that script, so on this side they are one file: a name sent with each request.
//!
//! Used by the `peers`, `real_volumes`, `decimation` and `costen_table` experiments. The
//! tetrahedral meshers of `stuart_tables` (TetGen, CGAL Mesh_3, NETGEN, fTetWild, on an offset
//! surface the script builds) run offline in `stuart_tables/peers.py`, whose committed output that
//! experiment reads: they are compared by element count and quality, not by run-to-run timing.

use glam::Vec3;
use isolab_algorithms::geometry::Aabb;
use isolab_algorithms::{Field, Samples, TriMesh};
use serde::{Deserialize, Serialize};
use std::path::Path;
use std::time::Duration;

pub mod cli;
pub mod fast_surface_nets;
pub mod ferreus_rmt;
pub mod isosurface_crate;
pub mod ours;
pub mod python;

/// How a call is timed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub enum Protocol {
    /// Fresh output and fresh state for every call, as a CLI user or a first library call meets
    /// it (VTK: a new filter; ours: a new extractor and `Extraction::default()`).
    OneShot,
    /// The same call repeated with whatever the implementation lets a caller keep (ours: the
    /// extractor and its output buffers; `fast-surface-nets`: its buffer; VTK: the same filter,
    /// `Modified()` then `Update()`). Implementations with nothing to keep run as one-shot.
    SteadyState,
}

impl Protocol {
    /// Short name, as the report and the Python server spell it.
    pub fn name(self) -> &'static str {
        match self {
            Protocol::OneShot => "one-shot",
            Protocol::SteadyState => "steady-state",
        }
    }
}

/// What a peer is asked to do.
pub enum Job<'a> {
    /// Mesh a cubic grid at its iso-value. `file` holds the same grid in the `--samples-out`
    /// format (raw f32 + JSON), for peers in another process.
    Grid {
        /// The samples.
        samples: &'a Samples<'static>,
        /// The same samples on disk.
        file: &'a Path,
        /// Threads the peer may use.
        threads: usize,
    },
    /// Mesh a field the peer samples itself, over `domain` at lattice spacing `spacing`, following
    /// the surface from `seeds` (every component needs one).
    Field {
        /// The field.
        field: &'a dyn Field,
        /// The domain.
        domain: Aabb,
        /// Lattice spacing.
        spacing: f32,
        /// Iso-value.
        iso: f32,
        /// Seed points near the surface.
        seeds: &'a [Vec3],
    },
    /// Decimate the mesh file `mesh` to `target` triangles, writing the result to `out`.
    Decimate {
        /// Input mesh (PLY or OBJ).
        mesh: &'a Path,
        /// Triangles wanted.
        target: usize,
        /// Output path (OBJ).
        out: &'a Path,
    },
    /// Mesh a scan file at `level` in the file's world coordinates, writing the mesh to `out`
    /// when given. With `end_to_end`, the time includes reading the file.
    Scan {
        /// The NIfTI file.
        file: &'a Path,
        /// Iso-value in the file's units.
        level: f32,
        /// Threads the peer may use.
        threads: usize,
        /// Where to write the mesh (binary PLY).
        out: Option<&'a Path>,
        /// Time reading the file too.
        end_to_end: bool,
    },
}

/// One call's result.
#[derive(Clone, Debug, Default)]
pub struct PeerRun {
    /// Wall time of the timed call.
    pub time: Duration,
    /// Vertices of the output.
    pub vertices: usize,
    /// Triangles of the output.
    pub triangles: usize,
    /// The mesh, where the peer hands it back in process (wound outward).
    pub mesh: Option<TriMesh>,
    /// Field evaluations, for peers that sample the field themselves.
    pub evaluations: Option<usize>,
    /// Whether the peer's triangles came wound inward and were flipped to compare.
    pub flipped: bool,
}

/// Why a peer did not run.
#[derive(Debug, thiserror::Error)]
pub enum PeerError {
    /// The peer does not do this kind of job.
    #[error("{peer} does not take this job")]
    Unsupported {
        /// The peer's name.
        peer: String,
    },
    /// The peer failed or is not installed.
    #[error("{peer}: {message}")]
    Failed {
        /// The peer's name.
        peer: String,
        /// What went wrong.
        message: String,
    },
}

/// An implementation we compare against.
pub trait Peer {
    /// Its name in tables (threads are added by the caller).
    fn name(&self) -> String;
    /// Runs `job` once under `protocol`.
    fn run(&mut self, job: &Job<'_>, protocol: Protocol) -> Result<PeerRun, PeerError>;

    /// The error for a job this peer does not take.
    fn unsupported(&self) -> PeerError {
        PeerError::Unsupported { peer: self.name() }
    }
}

/// Seed points for a surface-following peer: every `stride`-th vertex of a mesh of the same
/// surface, so every component gets a seed.
pub fn seeds_from(mesh: &TriMesh, stride: usize) -> Vec<Vec3> {
    mesh.positions.iter().step_by(stride.max(1)).copied().collect()
}
