//! The data file `report/data/sphere_convergence.json`: what the run writes and the page reads.

use serde::{Deserialize, Serialize};

#[derive(Serialize, Deserialize)]
pub(crate) struct Row {
    pub(crate) algorithm: String,
    pub(crate) resolution: usize,
    pub(crate) triangles: usize,
    pub(crate) volume_error: f64,
    pub(crate) area_error: f64,
    pub(crate) mean_distance_over_spacing: f64,
    pub(crate) max_distance_over_spacing: f64,
}

#[derive(Serialize, Deserialize)]
pub(crate) struct Data {
    /// Each extractor's options as it ran (absent from runs before they were recorded).
    #[serde(default)]
    pub(crate) settings: Vec<(String, String)>,
    pub(crate) radius: f64,
    pub(crate) rows: Vec<Row>,
    pub(crate) plot: String,
}
