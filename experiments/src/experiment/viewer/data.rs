//! The data file `report/data/viewer.json`: what the run writes and the page reads.

use serde::{Deserialize, Serialize};

/// One mesh on the page.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct Mesh {
    /// Extractor.
    pub algorithm: String,
    /// Input (built-in field or shipped model).
    pub input: String,
    /// Samples along the longest side.
    pub resolution: usize,
    /// Triangles.
    pub triangles: usize,
    /// The `.glb`, relative to the report.
    pub path: String,
    /// Its size.
    pub bytes: usize,
    /// Closed (no boundary edge).
    #[serde(default)]
    pub closed: bool,
    /// Edge- and vertex-manifold.
    #[serde(default)]
    pub manifold: bool,
    /// Self-intersecting triangle pairs.
    #[serde(default)]
    pub intersecting_pairs: usize,
    /// The triangles of the first listed intersecting pairs (`metrics::intersections`), sorted.
    #[serde(default)]
    pub intersecting_triangles: Vec<u32>,
    /// Mean and largest aspect ratio (1 for equilateral).
    #[serde(default)]
    pub aspect: [f64; 2],
}

/// The experiment's data.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct Data {
    /// The meshes written, input by input.
    pub meshes: Vec<Mesh>,
    /// Inputs left out by the budget, with their meshes' total size.
    pub left_out: Vec<(String, usize)>,
}
