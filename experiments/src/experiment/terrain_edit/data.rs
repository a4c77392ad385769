//! The data file `report/data/terrain_edit.json`: what the run writes and the page reads.

use serde::{Deserialize, Serialize};

/// One extractor's edit sequence at one chunk size, each dirty chunk re-meshed on its own on one
/// thread (what a game's meshing worker does).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ChunkRun {
    /// Cells per chunk side.
    pub chunk: usize,
    /// Chunks re-meshed over the sequence.
    pub chunks: usize,
    /// One chunk's re-mesh on one thread, ms: median, 99th percentile, slowest.
    pub chunk_ms: [f64; 3],
    /// Boundary edges of the welded mesh off the world's boundary after the sequence (cracks).
    pub open_seam_edges: usize,
}

/// One extractor's edit sequence.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Run {
    /// Extractor.
    pub algorithm: String,
    /// Meshing every chunk once, ms.
    pub initial_ms: f64,
    /// Each edit's time (sample edit + re-meshing), ms.
    pub edit_ms: Vec<f64>,
    /// Chunks each edit re-meshed.
    pub dirtied: Vec<usize>,
    /// Median edit, ms.
    pub median_ms: f64,
    /// 99th percentile edit, ms.
    pub p99_ms: f64,
    /// Slowest edit, ms.
    pub max_ms: f64,
    /// Triangles before and after the sequence.
    pub triangles: [usize; 2],
    /// Welded mesh closed and manifold after the sequence.
    pub manifold_after: bool,
    /// The most boundary edges off the world's boundary (cracks) in the welded mesh after any
    /// edit of the sequence (checked after every edit).
    #[serde(default)]
    pub open_seam_edges_max: usize,
    /// Mean aspect ratio and smallest angle (degrees) of the welded, edited mesh.
    #[serde(default)]
    pub quality_after: [f64; 2],
    /// The one-thread runs, one per chunk size (16³, 32³ and 64³ cells in the report).
    #[serde(default)]
    pub chunk_runs: Vec<ChunkRun>,
    /// The extractor's settings as it ran (`Extractor::settings`: smoothing, placement, faces).
    #[serde(default)]
    pub settings: String,
}

#[derive(Serialize, Deserialize)]
pub(crate) struct Data {
    pub(crate) runs: Vec<Run>,
    pub(crate) not_run: Vec<String>,
    pub(crate) before: String,
    pub(crate) after: String,
    pub(crate) gif: String,
    pub(crate) plot: String,
}
