//! The data file `report/data/mesh_fields.json`: what the run writes and the page reads.

use crate::report::Spread;
use serde::{Deserialize, Serialize};

/// One model.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Row {
    /// Model name.
    pub model: String,
    /// Its triangles.
    pub triangles: usize,
    /// Samples per axis.
    pub dims: [usize; 3],
    /// Samples nearer the mesh than the band (exact in ours).
    pub in_band: usize,
    /// Ours, narrow band, ms.
    pub narrow_band: Spread,
    /// Ours, exact at every sample, ms.
    pub exact: Spread,
    /// libigl, ms (none when the peer is missing).
    pub libigl: Option<Spread>,
    /// Samples where libigl's sign differs from ours.
    pub sign_differs: Option<usize>,
    /// Largest difference of our exact distances within the band from libigl's exact distance
    /// (`point_mesh_squared_distance`), in grid spacings.
    pub band_difference_h: Option<f64>,
    /// Largest difference of libigl's `signed_distance` magnitudes (fast-winding-number mode)
    /// from our exact distances within the band, in grid spacings.
    pub fwn_magnitude_h: Option<f64>,
    /// Whether marching cubes makes the same mesh from the narrow band as from exact samples.
    pub mesh_unchanged: bool,
    /// Whether the mesh is closed, so the narrow band takes its signs from row crossings (absent
    /// in older runs).
    #[serde(default)]
    pub closed: Option<bool>,
    /// Samples whose narrow-band sign differs from the exact field's (absent in older runs).
    #[serde(default)]
    pub sign_differs_from_exact: Option<usize>,
}

/// The experiment's data.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Data {
    /// Samples along the longest side.
    pub resolution: usize,
    /// Band half-width, spacings.
    pub band_cells: f32,
    /// Threads on each side.
    pub threads: usize,
    /// libigl's version, or why it was not run.
    pub libigl: String,
    /// One row per model.
    pub rows: Vec<Row>,
}
