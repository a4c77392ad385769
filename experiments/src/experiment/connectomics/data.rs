//! The data file `report/data/connectomics.json`: what the run writes and the page reads.

use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

#[derive(Clone, Debug, Serialize, Deserialize)]
pub(super) struct Run {
    pub(super) tool: String,
    pub(super) workers: usize,
    pub(super) seconds: f64,
    pub(super) bytes: u64,
    pub(super) peak_rss_mib: Vec<f64>,
    pub(super) restarted: bool,
    #[serde(default)]
    pub(super) segments: Option<usize>,
    #[serde(default)]
    pub(super) lods: Option<usize>,
    #[serde(default)]
    pub(super) fragments: Vec<u64>,
    #[serde(default)]
    pub(super) triangles: Vec<u64>,
    #[serde(default)]
    pub(super) level_bytes: Vec<u64>,
    /// isolab's phases, wall seconds: `boxes`, `files`, `info_and_cleanup` (absent from data made
    /// before they were measured).
    #[serde(default)]
    pub(super) phases: BTreeMap<String, f64>,
    /// isolab's workers' seconds computing, from Dask's task stream, sorted.
    #[serde(default)]
    pub(super) busy_seconds: Vec<f64>,
    /// isolab's seconds computing per kind of task (the task function's name).
    #[serde(default)]
    pub(super) task_seconds: BTreeMap<String, f64>,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
pub(super) struct VolumeInfo {
    pub(super) n: usize,
    pub(super) cells: usize,
    pub(super) voxels: u64,
    pub(super) gib: f64,
    pub(super) dtype: String,
    pub(super) resolution_nm: f64,
    pub(super) made_seconds: f64,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
pub(super) struct Encoder {
    pub(super) encoder: String,
    pub(super) seconds: Vec<f64>,
    pub(super) median: f64,
    pub(super) bytes: u64,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
pub(super) struct Draco {
    pub(super) side: usize,
    pub(super) fragments: usize,
    pub(super) triangles: u64,
    pub(super) encoders: Vec<Encoder>,
}

#[derive(Serialize, Deserialize)]
pub(super) struct Data {
    pub(super) versions: BTreeMap<String, String>,
    pub(super) notes: Vec<String>,
    pub(super) volume: VolumeInfo,
    pub(super) chunk: usize,
    pub(super) memory_limit_mib: usize,
    pub(super) igneous_shape: usize,
    pub(super) cores: usize,
    pub(super) runs: Vec<Run>,
    pub(super) screenshot: bool,
    /// The Draco encoders on the same fragments (absent from data made before it was measured).
    #[serde(default)]
    pub(super) draco: Option<Draco>,
}
