//! The data file `report/data/terrain_lod.json`: what the run writes and the page reads.

use crate::report::Spread;
use serde::{Deserialize, Serialize};

#[derive(Clone, Debug, Serialize, Deserialize)]
pub(super) struct Row {
    pub(super) implementation: String,
    pub(super) pattern: String,
    /// Chunks at each level (0: full resolution).
    pub(super) per_level: Vec<usize>,
    pub(super) triangles: usize,
    /// Ours only: seam edges stitched (marching cubes) or polygons on minimal edges between
    /// levels (dual methods).
    pub(super) stitched: Option<usize>,
    /// Ours only: vertices the dual methods split where two rings met on a seam.
    #[serde(default)]
    pub(super) pinched: Option<usize>,
    pub(super) seam_boundary_edges: usize,
    pub(super) non_manifold_edges: usize,
    #[serde(default)]
    pub(super) non_manifold_vertices: usize,
    pub(super) misoriented_edges: usize,
    pub(super) self_intersecting_pairs: usize,
    /// Triangles along a face between chunks of different levels (module doc of `seam_triangles`).
    pub(super) seam_triangles: usize,
    /// Seam triangles without area (left out of the shape statistics).
    #[serde(default)]
    pub(super) seam_zero_area: usize,
    pub(super) seam_aspect_mean: f64,
    #[serde(default)]
    pub(super) seam_aspect_median: f64,
    pub(super) seam_aspect_max: f64,
    /// The mean over seam triangles with no corner within `NEAR_SAMPLE` of a sample.
    #[serde(default)]
    pub(super) seam_aspect_mean_off_samples: f64,
    /// `None` without seam triangles.
    pub(super) seam_min_angle_deg: Option<f64>,
    /// Whole world, ms.
    pub(super) time_ms: Spread,
}

/// Switching one chunk's level in the viewer-distance pattern.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub(super) struct Switch {
    pub(super) chunk: [usize; 3],
    pub(super) from: u8,
    pub(super) to: u8,
    /// Ours, per extractor: `extract_lod` on the chunks within one chunk of it (what its seams
    /// can reach), ms.
    pub(super) ours: Vec<(String, Spread)>,
    /// Chunks our re-run meshes.
    pub(super) ours_chunks: usize,
    /// The crate: the chunk and the face neighbours whose transition faces change, ms.
    pub(super) crate_ms: Spread,
    /// Chunks the crate re-meshes.
    pub(super) crate_chunks: usize,
}

#[derive(Serialize, Deserialize)]
pub(super) struct Data {
    pub(super) rows: Vec<Row>,
    pub(super) switch: Option<Switch>,
    pub(super) picture: String,
    pub(super) crate_picture: String,
    /// Surface nets' and dual contouring's close-ups.
    #[serde(default)]
    pub(super) dual_picture: String,
    /// Each of our extractors' settings as it ran.
    #[serde(default)]
    pub(super) options: Vec<(String, String)>,
}
