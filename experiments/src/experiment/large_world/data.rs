//! The data file `report/data/large_world.json`: what the run writes and the page reads.

use serde::{Deserialize, Serialize};

#[derive(Clone, Debug, Serialize, Deserialize)]
pub(super) struct Data {
    pub(super) dims: [usize; 3],
    pub(super) chunk: usize,
    pub(super) algorithm: String,
    pub(super) samples: u64,
    pub(super) dense_gib: f64,
    pub(super) machine_gib: Option<f64>,
    pub(super) seconds: f64,
    pub(super) samples_per_second: f64,
    pub(super) triangles_per_second: f64,
    pub(super) vertices: u64,
    pub(super) triangles: u64,
    pub(super) welded: u64,
    pub(super) chunks: [usize; 3],
    pub(super) meshed: usize,
    pub(super) empty: usize,
    pub(super) full: usize,
    /// Empty or full chunks proven so by the field and skipped unsampled (absent in older runs).
    #[serde(default)]
    pub(super) proven: Option<usize>,
    pub(super) file_gib: f64,
    pub(super) rss_before_mib: Option<f64>,
    pub(super) peak_rss_mib: Option<f64>,
    pub(super) peak_reset: bool,
    pub(super) peak_keys: usize,
    pub(super) peak_slab_mib: f64,
}
