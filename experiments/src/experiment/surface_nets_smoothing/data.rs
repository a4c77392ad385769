//! The data file `report/data/surface_nets_smoothing.json`: what the run writes and the page reads.

use serde::{Deserialize, Serialize};

#[derive(Serialize, Deserialize)]
pub(super) struct Row {
    pub(super) field: String,
    pub(super) cells: usize,
    pub(super) method: String,
    pub(super) triangles: usize,
    pub(super) smoothing_ms: f64,
    pub(super) extraction_ms: f64,
    pub(super) aspect_mean: f64,
    pub(super) min_angle_deg: f64,
    /// Mean signed distance of vertices to the true surface, in grid spacings (negative: inward).
    pub(super) mean_signed_distance_h: f64,
    /// Mean unsigned distance, in grid spacings.
    pub(super) mean_distance_h: f64,
    /// Volume change against the analytic volume (sphere only).
    pub(super) volume_change: Option<f64>,
    pub(super) watertight: bool,
    /// On `csg` only: the farthest any true sharp corner lies from the mesh's nearest vertex, in
    /// grid spacings (feature retention).
    #[serde(default)]
    pub(super) worst_corner_h: Option<f64>,
}

#[derive(Serialize, Deserialize)]
pub(super) struct Data {
    pub(super) iterations: usize,
    pub(super) repeats: usize,
    pub(super) rows: Vec<Row>,
    pub(super) chart: String,
    pub(super) images: Vec<(String, String)>,
}
