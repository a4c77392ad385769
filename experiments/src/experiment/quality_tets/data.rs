//! The data files: `report/data/quality_tets.json` (what the run writes),
//! `report/data/quality_tets_peers.json` (what `peers.py` writes) and
//! `report/data/quality_tets_labels.json` (what `tests/reference/mesh3/labeled_vs_cleaving.py`
//! writes: label maps meshed by lattice cleaving and by CGAL Mesh_3); the page reads all three.

use serde::{Deserialize, Serialize};

/// The measures every mesher gets, by one definition (ours in Rust, the peers' in `peers.py`).
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct Quality {
    /// Tetrahedra.
    pub tetrahedra: usize,
    /// Smallest and largest dihedral angle, degrees.
    pub dihedral: [f64; 2],
    /// Radius ratio `R / (3 r)` (1 for the regular tetrahedron): mean and largest.
    pub radius_ratio: [f64; 2],
    /// Tetrahedra with non-positive volume.
    pub inverted: usize,
    /// The boundary's vertices' distance to the model's surface, in `h`: mean and largest.
    pub to_surface_h: [f64; 2],
    /// The model's vertices' distance to the boundary, in `h`: mean and largest (with the other
    /// largest, the two-sided Hausdorff distance sampled at vertices).
    pub from_surface_h: [f64; 2],
    /// Tetrahedral volume over the model's volume.
    pub volume_ratio: f64,
    /// Every vertex of the model inside the mesh or on its boundary (within 1e-6 of the box).
    pub encloses: bool,
}

/// One of our runs.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Row {
    /// Model.
    pub model: String,
    /// Extractor (`isosurface-stuffing`, `bcc-sculpt`).
    pub tool: String,
    /// Lattice cells along the model's longest side.
    pub cells: usize,
    /// The lattice spacing, model units.
    pub h: f64,
    /// The measures.
    pub quality: Quality,
    /// Sampling the field at the lattice's corners (stuffing; 0 for bcc-sculpt, which reads the
    /// triangle mesh), ms per run on one thread.
    pub sampling_ms: Vec<f64>,
    /// The extraction, ms per run on one thread.
    pub extraction_ms: Vec<f64>,
}

/// What the run writes.
#[derive(Serialize, Deserialize)]
pub(crate) struct Data {
    /// The models.
    pub(crate) models: Vec<String>,
    /// The models whose triangle mesh is closed (the others' surface has holes, which every
    /// mesher closes: distances there measure the patch, not the mesher).
    #[serde(default)]
    pub(crate) closed: Vec<String>,
    /// Lattice cells along the longest side, each run.
    pub(crate) cells: Vec<usize>,
    /// The cells the peers are matched at.
    pub(crate) peer_cells: usize,
    /// The interval `isosurface-stuffing` declares, degrees.
    pub(crate) declared: [f64; 2],
    /// The interval the paper proves for the same parameters, degrees.
    pub(crate) paper: [f64; 2],
    /// Each extractor's options as it ran.
    pub(crate) settings: Vec<(String, String)>,
    /// Every run.
    pub(crate) rows: Vec<Row>,
    /// The figure: each model's boundary, stuffing and the peers' side by side (relative link).
    #[serde(default)]
    pub(crate) figure: Option<String>,
}

/// One peer on one model, as `peers.py` wrote it (`error` instead of the measures when it failed).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct PeerRow {
    /// Model.
    pub model: String,
    /// Mesher.
    pub tool: String,
    /// The measures (absent when it failed).
    #[serde(default)]
    pub quality: Option<Quality>,
    /// Every timed run of the matched setting, seconds.
    #[serde(default)]
    pub seconds: Vec<f64>,
    /// The setting it ran with.
    #[serde(default)]
    pub settings: String,
    /// The tetrahedron count it was matched to (stuffing's at the peers' cells).
    #[serde(default)]
    pub target: usize,
    /// Runs tried while matching the count.
    #[serde(default)]
    pub tries: usize,
    /// Why it has no measures.
    #[serde(default)]
    pub error: Option<String>,
}

/// What `peers.py` writes.
#[derive(Serialize, Deserialize)]
pub(crate) struct Peers {
    /// The surface each mesher got, per model (the bunny's holes closed).
    pub(crate) inputs: Vec<PeerInput>,
    /// The count tolerance the matching aims for, a fraction of the target.
    pub(crate) match_tolerance: f64,
    /// Every peer run.
    pub(crate) rows: Vec<PeerRow>,
}

/// The surface the peers mesh for one model.
#[derive(Serialize, Deserialize)]
pub(crate) struct PeerInput {
    pub(crate) model: String,
    /// How the model became a closed input (unchanged, or its holes closed).
    pub(crate) how: String,
    pub(crate) triangles: usize,
}

/// Label maps meshed by lattice cleaving and by CGAL Mesh_3 (`labeled_vs_cleaving.py`).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Labels {
    /// The commit the script ran at, and whether the tree had changes.
    pub commit: String,
    /// Uncommitted changes at the run.
    pub dirty: bool,
    /// When (UTC).
    pub date: String,
    /// The CPU model.
    pub cpu: String,
    /// Cores, OS, Python, numpy and the C++ compiler (absent from data before they were kept).
    #[serde(default)]
    pub cores: Option<usize>,
    /// The OS.
    #[serde(default)]
    pub os: Option<String>,
    /// Python's version.
    #[serde(default)]
    pub python: Option<String>,
    /// numpy's version.
    #[serde(default)]
    pub numpy: Option<String>,
    /// The compiler of the CGAL program.
    #[serde(default)]
    pub compiler: Option<String>,
    /// isolab's version.
    pub isolab: String,
    /// One row per input and mesher.
    pub rows: Vec<LabelRow>,
}

/// One label map meshed by one mesher.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct LabelRow {
    /// The map.
    pub input: String,
    /// Its shape (numpy order).
    pub shape: Vec<usize>,
    /// `lattice-cleaving` or `CGAL Mesh_3`.
    pub tool: String,
    /// Tetrahedra (0 on a failure).
    #[serde(default)]
    pub tetrahedra: usize,
    /// Smallest and largest dihedral angle, degrees.
    #[serde(default)]
    pub dihedral: [f64; 2],
    /// Tetrahedra of non-positive volume.
    #[serde(default)]
    pub inverted: usize,
    /// Each label's tetrahedra's volume over its voxels', less one.
    #[serde(default)]
    pub volume_error: std::collections::BTreeMap<String, f64>,
    /// Times, ms: ours every run of `isolab.mesh_labels` on one thread; CGAL's `make_mesh_3`
    /// alone, one-shot in a fresh process.
    #[serde(default)]
    pub ms: Vec<f64>,
    /// CGAL's cell (and facet) size, voxels, and the tries it took to match our count.
    #[serde(default)]
    pub cell_size: Option<f64>,
    /// Tries.
    #[serde(default)]
    pub tries: Option<usize>,
    /// CGAL's version.
    #[serde(default)]
    pub cgal: Option<String>,
    /// Why a run failed.
    #[serde(default)]
    pub error: Option<String>,
}
