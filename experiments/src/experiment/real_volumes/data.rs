//! The data file `report/data/real_volumes.json`: what the run writes and the page reads.

use super::islands::Islands;
use super::{lewiner, second};
use crate::report::Spread;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// An iso-value and how it was found.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub(crate) struct Level {
    pub(crate) name: String,
    pub(crate) iso: f32,
    pub(crate) how: String,
}

/// One implementation at one iso-value.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub(crate) struct Row {
    pub(crate) implementation: String,
    pub(crate) ours: bool,
    pub(crate) level: String,
    /// Extraction time on one thread (ours in a one-thread rayon pool; VTK's Sequential backend).
    pub(crate) time_1: Spread,
    /// On two threads (rayon's pool; VTK's STDThread backend); none for single-threaded peers.
    pub(crate) time_2: Option<Spread>,
    pub(crate) vertices: usize,
    pub(crate) triangles: usize,
    pub(crate) min_angle_deg: f64,
    pub(crate) aspect_mean: f64,
    pub(crate) aspect_max: f64,
    pub(crate) components: usize,
    pub(crate) genus: Option<i64>,
    pub(crate) closed: bool,
    pub(crate) manifold: bool,
    pub(crate) outward: bool,
    pub(crate) oriented: bool,
    pub(crate) self_intersections: usize,
    /// Mean and max distance of vertices to the trilinear level set, in voxels (1 mm).
    pub(crate) distance_mean: f64,
    pub(crate) distance_max: f64,
    /// Its components and what `keep-components` keeps (absent from runs before it existed).
    #[serde(default)]
    pub(crate) islands: Option<Islands>,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
pub(super) struct EndToEnd {
    pub(super) level: String,
    /// Threads on both sides.
    pub(super) threads: usize,
    pub(super) ours_ms: Spread,
    pub(super) peer_ms: Spread,
    /// Peer median over ours.
    pub(super) ratio: f64,
    pub(super) ours_triangles: usize,
    pub(super) peer_triangles: usize,
}

#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub(crate) struct Data {
    pub(crate) source: String,
    pub(crate) shape: [usize; 3],
    pub(crate) data_type: String,
    pub(crate) spacing: [f64; 3],
    pub(crate) file_bytes: u64,
    /// Voxels that are exactly 0 (outside the brain mask of a brain-extracted template).
    pub(crate) zero_fraction: f64,
    pub(crate) levels: Vec<Level>,
    pub(crate) rows: Vec<Row>,
    pub(super) end_to_end: Vec<EndToEnd>,
    pub(crate) images: Vec<(String, String)>,
    pub(crate) versions: BTreeMap<String, String>,
    pub(crate) skipped: Vec<String>,
    pub(crate) repeats: usize,
    pub(crate) threads: usize,
    /// The second volume, of another kind (absent from runs before it was added).
    #[serde(default)]
    pub(crate) second: Option<second::SecondVolume>,
    /// Each of our extractors' options as it ran (absent from runs before they were recorded).
    #[serde(default)]
    pub(crate) settings: Vec<(String, String)>,
    /// `marching-cubes-33` against scikit-image's Lewiner, cell by cell, per level (absent from
    /// runs before it was added).
    #[serde(default)]
    pub(crate) lewiner_cells: Vec<lewiner::CellCounts>,
}
