//! The data file `report/data/scaling.json`: what the run writes and the page reads.

use serde::{Deserialize, Serialize};

/// One extractor on one grid.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub(super) struct Row {
    pub(super) algorithm: String,
    pub(super) n: usize,
    pub(super) cells: usize,
    /// Median extraction time per thread count, ms (same order as `THREADS`), steady state: the
    /// extractor and its output kept between calls.
    pub(super) ms: Vec<f64>,
    /// Fastest and slowest steady-state run per thread count, ms.
    #[serde(default)]
    pub(super) spread: Vec<[f64; 2]>,
    /// Median one-shot time per thread count, ms: a new extractor and a new output every call.
    #[serde(default)]
    pub(super) one_shot_ms: Vec<f64>,
    /// Fastest and slowest one-shot run per thread count, ms.
    #[serde(default)]
    pub(super) one_shot_spread: Vec<[f64; 2]>,
    pub(super) runs: usize,
    pub(super) triangles: usize,
    pub(super) tetrahedra: usize,
    /// The memory floor for this grid and this output: read + write, ms.
    pub(super) floor_ms: f64,
    pub(super) grid_bytes: usize,
    pub(super) output_bytes: usize,
    /// Peak heap bytes the extraction added (None: the counting allocator is not installed).
    pub(super) peak_bytes: Option<usize>,
}

#[derive(Serialize, Deserialize)]
pub(super) struct Data {
    pub(super) field: String,
    pub(super) threads: Vec<usize>,
    pub(super) rows: Vec<Row>,
    pub(super) skipped: Vec<String>,
    /// The thread count that ran from the experiment's thread on rayon's global pool (the
    /// others ran inside a pool of their size); None in runs before this was recorded.
    #[serde(default)]
    pub(super) global_pool_threads: Option<usize>,
    /// Each extractor's options as it ran (absent from runs before they were recorded).
    #[serde(default)]
    pub(super) settings: Vec<(String, String)>,
}
