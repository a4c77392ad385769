//! The data file `report/data/svoboda_timing.json`: what the run writes and the page reads.

use serde::{Deserialize, Serialize};

/// One algorithm at one size.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Row {
    /// Algorithm.
    pub algorithm: String,
    /// Cubes a side.
    pub cubes: usize,
    /// Median extraction time, ms.
    pub extraction_ms: f64,
    /// Median sampling time, ms.
    pub sampling_ms: f64,
    /// Triangles.
    pub triangles: usize,
    /// Runs timed.
    pub runs: usize,
}

/// The paper's field and algorithm beside ours, one thread, one shot (a fresh output every run).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct LikeRow {
    /// Cubes a side.
    pub cubes: usize,
    /// The paper's marching cubes (unshared vertices) here, median ms.
    pub unshared_ms: f64,
    /// Our marching cubes (shared vertices), median ms.
    pub shared_ms: f64,
    /// Triangles (the same for both).
    pub triangles: usize,
    /// Vertices of the unshared and the shared mesh.
    pub vertices: [usize; 2],
    /// Runs timed.
    pub runs: usize,
}

#[derive(Serialize, Deserialize)]
pub(super) struct Data {
    pub(super) rows: Vec<Row>,
    #[serde(default)]
    pub(super) like_for_like: Vec<LikeRow>,
    /// Each extractor's options as it ran (absent from runs before they were recorded).
    #[serde(default)]
    pub(super) settings: Vec<(String, String)>,
}
