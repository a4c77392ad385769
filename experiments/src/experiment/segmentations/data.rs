//! The data file `report/data/segmentations.json`: what the run writes and the page reads.

use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// One implementation on one input on some threads, as `bench.py` writes it (the checks on one
/// thread only).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Row {
    /// Who meshed it.
    pub implementation: String,
    /// Which label map.
    pub input: String,
    /// Threads given.
    pub threads: usize,
    /// Every recorded call, ms, in the order run.
    pub ms: Vec<f64>,
    /// The meshing step alone in each recorded call, ms (isolab's extraction, VTK's `Update()`,
    /// zmesh's `mesh()`; none for scikit-image).
    #[serde(default)]
    pub core_ms: Option<Vec<f64>>,
    /// Blocks of rounds run (`bench.py` adds a block while one is wide; absent in older data).
    #[serde(default)]
    pub blocks: Option<usize>,
    /// Whether its last block was still wide (slowest call over [`crate::report::WIDE`] times the
    /// fastest).
    #[serde(default)]
    pub wide: Option<bool>,
    /// Labels with a mesh.
    pub labels: usize,
    /// Triangles over every label's mesh.
    pub triangles: usize,
    /// Labels whose mesh is closed (one-thread rows).
    #[serde(default)]
    pub labels_closed: Option<usize>,
    /// Labels whose mesh is edge- and vertex-manifold.
    #[serde(default)]
    pub labels_manifold: Option<usize>,
    /// Non-manifold edges and vertices over every label's mesh.
    #[serde(default)]
    pub non_manifold: Option<usize>,
    /// Triangles of zero area.
    #[serde(default)]
    pub degenerate_triangles: Option<usize>,
    /// Smallest triangle angle, degrees.
    #[serde(default)]
    pub min_angle_deg: Option<f64>,
    /// Mean radius ratio (1 for equilateral).
    #[serde(default)]
    pub mean_radius_ratio: Option<f64>,
    /// Triangles whose outside is another label.
    #[serde(default)]
    pub interface_triangles: Option<usize>,
    /// Those not found in the other label's mesh.
    #[serde(default)]
    pub unmatched_interface_triangles: Option<usize>,
}

/// An input as `bench.py` describes it.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub(super) struct Input {
    pub(super) input: String,
    pub(super) shape: Vec<usize>,
    pub(super) dtype: String,
    pub(super) order: String,
    pub(super) labels: usize,
    #[serde(default)]
    pub(super) thresholds: Vec<f64>,
}

/// What the experiment keeps.
#[derive(Serialize, Deserialize)]
pub struct Data {
    pub(super) repeats: usize,
    pub(super) versions: BTreeMap<String, String>,
    pub(super) notes: Vec<String>,
    pub(super) inputs: Vec<Input>,
    /// One row per implementation, input and thread count.
    pub rows: Vec<Row>,
    /// Whether the tissue map's pictures were drawn (`figures/segmentations/tissue.png`).
    #[serde(default)]
    pub(super) pictures: bool,
    /// The label extractors drawn, left to right (empty in data from before this field, when the
    /// registry's first two were all it had and all that were drawn).
    #[serde(default)]
    pub(super) drawn: Vec<String>,
}

impl Data {
    /// The label extractors the tissue picture shows, left to right.
    pub(super) fn drawn(&self) -> Vec<String> {
        if self.drawn.is_empty() {
            isolab_algorithms::labels::names().into_iter().take(2).map(String::from).collect()
        } else {
            self.drawn.clone()
        }
    }
}
