//! The data file `report/data/decimation.json`: what the run writes and the page reads.

use serde::{Deserialize, Serialize};

/// One decimator on one input at one target.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Row {
    /// Object.
    pub object: String,
    /// Triangles of the plain marching tetrahedra input.
    pub input_triangles: usize,
    /// Target triangle count (the paper sweep's own count, or a quarter of the input).
    pub target: usize,
    /// Decimator.
    pub decimator: String,
    /// Triangles it left.
    pub triangles: usize,
    /// Mean Verdict aspect ratio.
    pub aspect_mean: f64,
    /// Smallest angle of the triangles with an area, degrees.
    pub min_angle_deg: f64,
    /// Triangles of zero area (left out of the shape statistics).
    #[serde(default)]
    pub degenerate: usize,
    /// Two-sided Hausdorff distance to the input surface, in grid spacings.
    pub hausdorff_h: f64,
    /// Closed, manifold and consistently oriented.
    pub manifold: bool,
    /// Self-intersecting triangle pairs (the input has none).
    #[serde(default)]
    pub self_intersections: usize,
    /// Median time, ms.
    pub ms: f64,
}

#[derive(Serialize, Deserialize)]
pub(crate) struct Data {
    pub(crate) repeats: usize,
    pub(crate) rows: Vec<Row>,
    pub(crate) skipped: Vec<String>,
}

/// What a native decimator printed.
#[derive(Deserialize)]
pub(super) struct NativeAnswer {
    pub(super) ms: Vec<f64>,
}
