//! The data file `report/data/distributed.json`: what the run writes and the page reads.

use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

#[derive(Clone, Debug, Serialize, Deserialize)]
pub(super) struct Run {
    pub(super) volume: String,
    pub(super) round: usize,
    /// The block of rounds it ran in (`bench.py` adds a block while one is wide; 0 in older data).
    #[serde(default)]
    pub(super) block: usize,
    pub(super) workers: usize,
    pub(super) chunk: usize,
    pub(super) worker_cpu_seconds: f64,
    pub(super) driver_cpu_seconds: f64,
    pub(super) seconds: f64,
    pub(super) blocks: usize,
    pub(super) blocks_per_second: f64,
    pub(super) worker_peak_rss_mib: Vec<f64>,
    pub(super) restarted: bool,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
pub(super) struct Killed {
    pub(super) seconds: f64,
    pub(super) fragments_before_kill: usize,
    pub(super) worker_replaced: bool,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
pub(super) struct Topology {
    pub(super) closed: bool,
    pub(super) boundary_edges: usize,
    pub(super) non_manifold_edges: usize,
    pub(super) genus: i64,
    pub(super) components: usize,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
pub(super) struct Zmesh {
    pub(super) seconds: f64,
    pub(super) vertices_before_merge: usize,
    pub(super) coincident_vertices_merged: usize,
    pub(super) vertices: usize,
    pub(super) triangles: usize,
    pub(super) collapsed_triangles: usize,
    pub(super) boundary_edges: usize,
    pub(super) non_manifold_edges: usize,
    pub(super) closed: bool,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
pub(super) struct Volume {
    pub(super) volume: String,
    pub(super) shape: Vec<usize>,
    pub(super) dtype: String,
    pub(super) mib: f64,
    pub(super) level: f64,
    pub(super) inside: String,
    pub(super) chunk: usize,
    pub(super) weld_seconds: f64,
    pub(super) vertices: usize,
    pub(super) triangles: usize,
    pub(super) topology: Topology,
    pub(super) killed: Killed,
    pub(super) killed_equal: bool,
    #[serde(default)]
    pub(super) equals_one_process: Option<bool>,
    #[serde(default)]
    pub(super) zmesh: Option<Zmesh>,
}

#[derive(Serialize, Deserialize)]
pub(super) struct Data {
    pub(super) versions: BTreeMap<String, String>,
    pub(super) notes: Vec<String>,
    pub(super) memory_limit_mib: usize,
    pub(super) chunks: Vec<usize>,
    pub(super) store_chunk: usize,
    pub(super) repeats: usize,
    pub(super) cores: usize,
    pub(super) runs: Vec<Run>,
    pub(super) volumes: Vec<Volume>,
}
