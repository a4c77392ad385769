//! The metrics JSON of one run (`RunReport`): what was meshed, how, what it cost, and every
//! measure of the mesh.

use super::{OutputSpace, VolumeGrid};
use crate::input::InputKind;
use isolab_algorithms::chunks::ChunkStats;
use isolab_algorithms::Samples;
use isolab_io::volume::Inside;
use isolab_metrics::{MeshMetrics, VolumeMetrics};
use serde::Serialize;

/// Wall times in milliseconds (the metrics JSON's `times_ms`).
#[derive(Clone, Copy, Debug, Serialize)]
pub struct TimesMs {
    /// Reading, parsing and checking the input file (0 for built-in fields).
    pub reading: f64,
    /// Field evaluation (for a volume on its own grid: taking its values as samples).
    pub sampling: f64,
    /// Vertex + geometry + normals.
    pub extraction: f64,
    /// Post-processes.
    pub post: f64,
    /// Mapping a volume's mesh from voxel indices to world coordinates.
    pub to_world: f64,
    /// Everything above.
    pub total: f64,
    /// Vertex pass.
    pub vertex: f64,
    /// Geometry pass.
    pub geometry: f64,
    /// Normals.
    pub normals: f64,
}

/// The metrics JSON of one run.
#[derive(Clone, Debug, Serialize)]
pub struct RunReport {
    /// Extractor name.
    pub algorithm: String,
    /// Field name.
    pub field: String,
    /// Samples along the longest side.
    pub resolution: usize,
    /// Samples per axis of the corner grid.
    pub dims: [usize; 3],
    /// Lattice kind.
    pub lattice: &'static str,
    /// Iso-value, in the input's own values.
    pub iso: f32,
    /// Which side of `iso` is inside.
    pub inside: Inside,
    /// What was meshed.
    pub input: InputReport,
    /// Seed of noise fields.
    pub seed: i32,
    /// Post-processes applied.
    pub post: Vec<String>,
    /// Tetrahedra in the volume output.
    pub tetrahedra: usize,
    /// Stage times.
    pub times_ms: TimesMs,
    /// Cells that held surface.
    pub active_cells: usize,
    /// Output plus scratch bytes.
    pub buffer_bytes: usize,
    /// Triangles per second of extraction time.
    pub triangles_per_second: f64,
    /// Analytic volume, where known.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub analytic_volume: Option<f64>,
    /// Analytic area, where known.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub analytic_area: Option<f64>,
    /// Tetrahedral-mesh measures (volume extractors: `dihedral_deg`, `boundary_distance`,
    /// `volume_ratio`, `encloses`, `converged`).
    #[serde(flatten, skip_serializing_if = "Option::is_none")]
    pub volume_mesh: Option<VolumeMetrics>,
    /// Chunked extraction (`--chunk N`): chunks per axis, meshed, skipped, welded vertices.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub chunks: Option<ChunkReport>,
    /// A sparse run's evaluations ([`crate::Sparse`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sparse: Option<crate::SparseReport>,
    /// Vertices per material (`--materials`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub materials: Option<std::collections::BTreeMap<String, usize>>,
    /// What the extractor warned about (an open input surface, non-convergence).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<String>,
    /// The surface's vertex and triangle counts, when no mesh metric was asked for
    /// ([`crate::Measure::Counts`]; otherwise `metrics` has them, under the same names).
    #[serde(flatten, skip_serializing_if = "Option::is_none")]
    pub counts: Option<MeshCounts>,
    /// Mesh measures, when asked for ([`crate::Measure`]).
    #[serde(flatten, skip_serializing_if = "Option::is_none")]
    pub metrics: Option<MeshMetrics>,
}

/// The counts a run always reports.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct MeshCounts {
    /// Surface vertices.
    pub vertices: usize,
    /// Surface triangles.
    pub triangles: usize,
}

/// The metrics JSON's `input`: what kind of input, and for volumes, what the file said.
#[derive(Clone, Debug, Serialize)]
pub struct InputReport {
    /// `builtin`, `mesh` or `volume`.
    pub kind: InputKind,
    /// File format (`PLY`, `NIfTI-1`, ...), for files.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub format: Option<&'static str>,
    /// Stored data type, for volumes.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub data_type: Option<&'static str>,
    /// Voxels per axis, for volumes.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub shape: Option<[usize; 3]>,
    /// Voxel edge lengths in world units, for volumes.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub spacing: Option<[f64; 3]>,
    /// Where a volume was meshed.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub grid: Option<VolumeGrid>,
    /// The coordinate system of the mesh, for anatomical volumes.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub space: Option<OutputSpace>,
    /// How the iso-value was chosen when the user gave none.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub iso_from: Option<&'static str>,
    /// What the reader noted (a picked volume, a unit conversion, a fallback affine).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub notes: Vec<String>,
}

/// The metrics JSON's `chunks`.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct ChunkReport {
    /// Cells per chunk side.
    pub size: usize,
    /// Chunks per axis.
    pub per_axis: [usize; 3],
    /// Chunks meshed.
    pub meshed: usize,
    /// Chunks skipped, all outside.
    pub empty: usize,
    /// Chunks skipped, all inside.
    pub full: usize,
    /// Vertices merged at seams.
    pub welded: usize,
    /// Samples each chunk reads beyond its own on every side (dual methods, clustering).
    pub apron: usize,
}

impl From<(usize, ChunkStats)> for ChunkReport {
    fn from((size, s): (usize, ChunkStats)) -> Self {
        Self { size, per_axis: s.chunks, meshed: s.meshed, empty: s.empty, full: s.full, welded: s.welded, apron: s.apron }
    }
}

/// A warning when no sample is inside, or every sample is: the mesh is then empty, and the user
/// should hear why rather than get a silent empty file.
pub(crate) fn no_inside_warning(samples: &Samples, name: &str, iso: f32, inside: Inside) -> Option<String> {
    let internal = samples.iso();
    // The lattice's corner grid (a BCC lattice's centres follow its corners' sign).
    let view = samples.view();
    let inside_count = view.count_below(internal);
    let count = view.dims().iter().product::<usize>();
    empty_mesh_warning(name, iso, inside, inside_count == 0, inside_count == count)
}

/// The warning of an empty mesh: no sample inside (`none`), or every one (`all`); shared with
/// the streamed run, which knows it from its skipped blocks.
pub(crate) fn empty_mesh_warning(name: &str, iso: f32, inside: Inside, none: bool, all: bool) -> Option<String> {
    let side = match inside {
        Inside::Above => "above",
        Inside::Below => "below",
    };
    if none {
        Some(format!(
            "no sample of '{name}' is inside at iso-value {iso} (inside is {side} it, and no value is): the mesh is empty; \
             try another --iso or --inside"
        ))
    } else if all {
        Some(format!(
            "every sample of '{name}' is inside at iso-value {iso} (inside is {side} it): the surface is outside the sampled \
             domain and the mesh is empty; try another --iso or --inside"
        ))
    } else {
        None
    }
}
