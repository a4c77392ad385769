//! The data file `report/data/stuart_tables.json`: what the run writes and the page reads.

use super::relaxation;
use serde::{Deserialize, Serialize};

/// One configuration.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Row {
    /// Model.
    pub model: String,
    /// Cells along the longest side.
    pub cells: usize,
    /// Lattice spacing.
    pub h: f64,
    /// `d_offset / h`.
    pub ratio: f32,
    /// Tetrahedra.
    pub tetrahedra: usize,
    /// Smallest dihedral angle, degrees.
    pub min_dihedral: f64,
    /// Largest dihedral angle, degrees.
    pub max_dihedral: f64,
    /// Distance of boundary vertices to `S`: min, max, mean (model units).
    pub distance: [f64; 3],
    /// Tetrahedral volume / volume of `S`.
    pub volume_ratio: f64,
    /// Every vertex of `S` inside.
    pub encloses: bool,
    /// Inverted tetrahedra.
    pub inverted: usize,
    /// Relaxation met the offset.
    pub converged: bool,
    /// Relaxation iterations of the chosen attempt.
    pub iterations: usize,
    /// Which attempt won (0: unperturbed).
    pub attempt: usize,
    /// Bombs after sculpting, and tetrahedra restored to defuse them.
    pub bombs: usize,
    /// Tetrahedra restored.
    pub restored: usize,
    /// The snowflake search was exhaustive.
    pub exhaustive: bool,
    /// Boundary: closed and manifold.
    pub boundary_manifold: bool,
    /// Boundary genus.
    pub boundary_genus: Option<i64>,
    /// Wall time of all attempts, ms.
    pub ms: f64,
}

/// One peer mesher's result (written by `stuart_tables/peers.py`).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct PeerRow {
    /// Model.
    pub model: String,
    /// "TetGen" or "CGAL Mesh_3".
    pub tool: String,
    /// Tetrahedra.
    #[serde(default)]
    pub tetrahedra: Option<usize>,
    /// Smallest dihedral angle, degrees.
    #[serde(default)]
    pub dihedral_min: Option<f64>,
    /// Largest dihedral angle, degrees.
    #[serde(default)]
    pub dihedral_max: Option<f64>,
    /// Wall time, s.
    #[serde(default)]
    pub seconds: Option<f64>,
    /// Tetrahedral volume / volume of `S`.
    #[serde(default)]
    pub volume_ratio: Option<f64>,
    /// Every vertex of `S` inside the mesh.
    #[serde(default)]
    pub encloses: Option<bool>,
    /// For the matched run: our tetrahedron count it aimed at.
    #[serde(default)]
    pub target: Option<usize>,
    /// Settings used.
    #[serde(default)]
    pub settings: Option<String>,
    /// Why it produced nothing.
    #[serde(default)]
    pub error: Option<String>,
}

/// The offset surface every peer meshed, per model (written by `stuart_tables/peers.py`).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct OffsetSurface {
    /// Model.
    pub model: String,
    /// Its triangles after remeshing.
    pub triangles: usize,
    /// Closed and manifold.
    pub closed_manifold: bool,
    /// Every vertex of `S` inside it.
    pub encloses: bool,
    /// Its distance from `S`, model units.
    pub d_offset: f64,
}

#[derive(Serialize, Deserialize)]
pub(crate) struct Peers {
    /// Package versions by tool.
    pub(crate) versions: std::collections::BTreeMap<String, String>,
    /// Signed-distance samples per `h` for the offset surface.
    pub(crate) grid_per_h: usize,
    /// The offset surface's target edge length, in `h`.
    pub(crate) surface_edge_h: f64,
    /// The matched CGAL run's tolerance on the tetrahedron count (a fraction of ours).
    pub(crate) match_tolerance: f64,
    pub(crate) surfaces: Vec<OffsetSurface>,
    pub(crate) rows: Vec<PeerRow>,
}

/// One ablation run: our additions to the paper's relaxation switched off one at a time.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Ablation {
    /// Model.
    pub model: String,
    /// Which variant.
    pub variant: String,
    /// Tetrahedra.
    pub tetrahedra: usize,
    /// Smallest and largest dihedral angle, degrees.
    pub dihedral: [f64; 2],
    /// Met the offset.
    pub converged: bool,
    /// Farthest boundary vertex from `S`, in `h`.
    pub max_distance_h: f64,
    /// Relaxation iterations.
    pub iterations: usize,
    /// Every vertex of `S` inside.
    pub encloses: bool,
}

#[derive(Serialize, Deserialize)]
pub(crate) struct Data {
    pub(crate) perturbations: usize,
    pub(crate) rows: Vec<Row>,
    /// Our additions switched off one at a time.
    pub(crate) ablation: Vec<Ablation>,
    /// Median wall time of the whole pipeline (one lattice) on the bunny at `BENCH_CELLS`, ms.
    pub(crate) bench_ms: f64,
    /// Its tetrahedra.
    pub(crate) bench_tetrahedra: usize,
    /// Runs timed.
    pub(crate) bench_runs: usize,
    /// Pictures, one grid per model.
    pub(crate) figures: Vec<(String, String)>,
    /// The relaxation traced: the paper's update at several time steps, and ours.
    #[serde(default)]
    pub(crate) relaxation: Vec<relaxation::StudyRun>,
    /// Link to the plot of the traces.
    #[serde(default)]
    pub(crate) relaxation_plot: Option<String>,
}
