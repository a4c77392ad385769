//! The data file `report/data/terrain_liquids.json`: what the run writes and the page reads.

use isolab_metrics::layers::LayerContact;
use serde::{Deserialize, Serialize};

#[derive(Clone, Debug, Serialize, Deserialize)]
pub(super) struct Row {
    pub(super) method: String,
    pub(super) solid_triangles: usize,
    pub(super) liquid_triangles: usize,
    pub(super) solid_closed_manifold: bool,
    pub(super) liquid_closed_manifold: bool,
    pub(super) contact: LayerContact,
    pub(super) median_ms: f64,
    /// Cells where the layers crossed after the post's rule, and of those the ones filled again
    /// (`liquids::extract_layers`' untangling).
    #[serde(default)]
    pub(super) crossing_cells: usize,
    #[serde(default)]
    pub(super) retiled_cells: usize,
}

#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub(super) struct EditRun {
    pub(super) extractor: String,
    pub(super) edits: usize,
    /// Edits after which a layer was not closed and manifold.
    pub(super) open_after: usize,
    /// The most unshared contact vertices, crossing pairs and liquid vertices inside the solid
    /// after any edit.
    pub(super) worst: LayerContact,
    /// The fewest contact vertices after any edit (the check is not vacuous).
    pub(super) fewest_contact: usize,
    pub(super) poured: f64,
    pub(super) drained: f64,
    pub(super) dug: f64,
    /// Largest relative difference between a mass and its books over the script.
    pub(super) mass_drift: f64,
    pub(super) solid_mass: [f64; 2],
    pub(super) liquid_mass: [f64; 2],
    /// Re-meshing the chunks each edit touched, ms.
    pub(super) remesh_ms: Vec<f64>,
    /// Chunks each edit re-meshed.
    #[serde(default)]
    pub(super) chunks_remeshed: Vec<usize>,
    /// Chunks per axis.
    #[serde(default)]
    pub(super) chunk_counts: [usize; 3],
    /// The most cells filled again (where the layers crossed after the rule) after an edit.
    #[serde(default)]
    pub(super) most_retiled_cells: usize,
}

#[derive(Serialize, Deserialize)]
pub(super) struct Data {
    pub(super) scene: [usize; 3],
    /// The extractors that take the rule.
    pub(super) rows: Vec<Row>,
    /// The post's naive solution.
    pub(super) naive: Row,
    /// The extractors whose layers crossed after the rule, meshed with the rule alone (no cell
    /// filled again), timed alternating with their row.
    #[serde(default)]
    pub(super) rule_alone: Vec<Row>,
    /// Extractors `extract_layers` refuses (vertices off the lattice edges).
    pub(super) refused: Vec<String>,
    pub(super) edits: Vec<EditRun>,
    pub(super) edit_scene: [usize; 3],
    pub(super) picture: String,
    pub(super) gif: String,
    /// Each extractor's options as it ran (absent from runs before they were recorded).
    #[serde(default)]
    pub(super) settings: Vec<(String, String)>,
}
