//! The data file `report/data/costen_table.json`: what the run writes and the page reads.

use super::ablations::ProjectionRow;
use super::ferreus::PeerRow;
use super::passes::PassChange;
use super::sphere_match::MatchedRow;
use isolab_metrics::MeshMetrics;
use serde::{Deserialize, Serialize};

/// One configuration, measured.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Row {
    /// The paper's id (`as_bi`), ours with a `+`.
    pub id: String,
    /// Field name.
    pub field: String,
    /// `bcc` or `cubic`.
    pub lattice: String,
    /// Samples per axis of the corner grid.
    pub dims: [usize; 3],
    /// Grid spacing h.
    pub spacing: f64,
    /// Median times, ms.
    pub t_sampling: f64,
    /// Vertex pass.
    pub t_vertex: f64,
    /// Geometry pass (with the guard's checks for `i+`).
    pub t_geometry: f64,
    /// Normals.
    pub t_normals: f64,
    /// Edge collapse (`p`, `p+`).
    pub t_post: f64,
    /// Tetrahedra with a sign change.
    pub n_tetrahedra: usize,
    /// Tetrahedra in the lattice.
    pub total_tetrahedra: usize,
    /// Vertices.
    pub n_vertices: usize,
    /// Triangles.
    pub n_triangles: usize,
    /// Triangles discarded (repeated vertex, or removed by the collapse).
    pub n_discarded: usize,
    /// Samples × 4 bytes.
    pub b_lattice: usize,
    /// Per-sample scratch bytes (the paper's per-edge flags and indices).
    pub b_edges: usize,
    /// Vertices × 24 bytes (position and normal).
    pub b_vertices: usize,
    /// Triangles × 12 bytes.
    pub b_indices: usize,
    /// Triangles removed against plain marching tetrahedra on the same lattice, fraction.
    pub removed: f64,
    /// Vertices where the mesh is not a consistently wound manifold.
    pub defects: usize,
    /// Every metric of the mesh.
    pub metrics: MeshMetrics,
}

/// One side-by-side picture.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Picture {
    /// What it shows.
    pub caption: String,
    /// Path relative to the report.
    pub path: String,
}

#[derive(Serialize, Deserialize)]
pub(super) struct Data {
    pub(super) repeats: usize,
    pub(super) rows: Vec<Row>,
    pub(super) pictures: Vec<Picture>,
    #[serde(default)]
    pub(super) peers: Vec<PeerRow>,
    #[serde(default)]
    pub(super) projection: Vec<ProjectionRow>,
    #[serde(default)]
    pub(super) matched_sphere: Vec<MatchedRow>,
    #[serde(default)]
    pub(super) pass_changes: Vec<PassChange>,
}
