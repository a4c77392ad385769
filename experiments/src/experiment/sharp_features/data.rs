//! The data file `report/data/sharp_features.json`: what the run writes and the page reads.

use serde::{Deserialize, Serialize};

#[derive(Serialize, Deserialize)]
pub(crate) struct Row {
    pub(crate) algorithm: String,
    /// The shape as placed (`csg`, turned, moved off the grid); `csg` in data made before the
    /// others ran.
    #[serde(default = "csg")]
    pub(crate) shape: String,
    pub(crate) resolution: usize,
    pub(crate) worst_corner_h: f64,
    pub(crate) mean_corner_h: f64,
    pub(crate) self_intersections: usize,
    pub(crate) manifold: bool,
}

fn csg() -> String {
    "csg".into()
}

#[derive(Serialize, Deserialize)]
pub(crate) struct Data {
    pub(crate) rows: Vec<Row>,
    pub(crate) images: Vec<(String, String)>,
    /// Each extractor's options as it ran (absent from runs before they were recorded).
    #[serde(default)]
    pub(crate) settings: Vec<(String, String)>,
}
