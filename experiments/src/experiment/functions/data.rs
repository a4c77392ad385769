//! The data file `report/data/functions.json`: what the run writes and the page reads.

use serde::{Deserialize, Serialize};

/// One run.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub(super) struct Row {
    pub(super) field: String,
    pub(super) n: usize,
    /// `sparse` or `dense`.
    pub(super) mode: String,
    pub(super) lipschitz: Option<f64>,
    pub(super) chunk: Option<usize>,
    pub(super) evaluations: u64,
    /// Of those, the pruning's (octree and refinement centres); `None` for dense runs.
    #[serde(default)]
    pub(super) pruning_evaluations: Option<u64>,
    /// Of the pruning's, the refinement's below the blocks.
    #[serde(default)]
    pub(super) refinement_evaluations: Option<u64>,
    pub(super) dense_points: u64,
    pub(super) batches: u64,
    pub(super) sampled_blocks: Option<usize>,
    pub(super) blocks: Option<usize>,
    pub(super) wall_ms: f64,
    pub(super) eval_ms: f64,
    pub(super) peak_mib: Option<f64>,
    pub(super) triangles: usize,
}

/// A certified extraction compared with the same blocks all sampled.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub(super) struct Equality {
    pub(super) field: String,
    pub(super) n: usize,
    pub(super) algorithm: String,
    pub(super) same_vertices: bool,
    pub(super) same_triangles: bool,
    pub(super) same_normals: bool,
    pub(super) triangles: usize,
    pub(super) evaluations: u64,
    pub(super) dense_evaluations: u64,
}

/// One fresh-process run of `functions/bench.py`.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub(super) struct PeerRun {
    #[serde(default)]
    pub(super) seconds: Option<f64>,
    #[serde(default)]
    pub(super) faces: Option<usize>,
    #[serde(default)]
    pub(super) evaluations: Option<u64>,
    #[serde(default)]
    pub(super) calls: Option<u64>,
    #[serde(default)]
    pub(super) lipschitz: Option<f64>,
    #[serde(default)]
    pub(super) peak_mib: Option<f64>,
    #[serde(default)]
    pub(super) error: Option<String>,
}

/// One implementation on one callable and grid.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub(super) struct PeerRow {
    pub(super) callable: String,
    pub(super) n: usize,
    pub(super) implementation: String,
    pub(super) runs: Vec<PeerRun>,
    /// Blocks of rounds run (`bench.py` adds a block while one is wide; absent in older data).
    #[serde(default)]
    pub(super) blocks: Option<usize>,
    /// Whether its last block was still wide after the last block allowed.
    #[serde(default)]
    pub(super) wide: Option<bool>,
}

/// What `functions/bench.py` wrote.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub(super) struct PythonSide {
    pub(super) versions: std::collections::BTreeMap<String, Option<String>>,
    pub(super) rows: Vec<PeerRow>,
    #[serde(default)]
    pub(super) notes: Vec<String>,
    /// Each callable's definition, as the script states it.
    #[serde(default)]
    pub(super) callables: std::collections::BTreeMap<String, String>,
}

/// What a cell-by-cell test with the same bound could not rule out ([`super::floor::cell_floor`]).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub(super) struct Floor {
    pub(super) field: String,
    pub(super) n: usize,
    pub(super) lipschitz: f64,
    /// Cells whose centre's value does not rule them out.
    pub(super) cells: u64,
    /// Samples that are corners of those cells.
    pub(super) samples: u64,
    pub(super) dense_points: u64,
}

#[derive(Serialize, Deserialize)]
pub(super) struct Data {
    pub(super) rows: Vec<Row>,
    pub(super) equality: Vec<Equality>,
    /// The cell-by-cell floor at the reading's size (absent in older data).
    #[serde(default)]
    pub(super) floors: Vec<Floor>,
    /// The Python callables and peers; `None` where the reference environment could not be made.
    #[serde(default)]
    pub(super) python: Option<PythonSide>,
    /// Why the Python side is missing, when it is.
    #[serde(default)]
    pub(super) python_missing: Option<String>,
}
