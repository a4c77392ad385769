//! Label maps (segmentations) to one mesh per label: the run that `isolab labels` and
//! `isolab.mesh_labels` share.
//!
//! A label map comes from a volume file (NIfTI, NRRD, MetaImage: integer data, or whole-number
//! floats, which segmentation tools often write) or from an array; it is meshed in voxel index
//! coordinates by a registered label extractor (`algorithms::labels`) and every mesh is mapped to
//! the world by the volume's affine, as volumes are. A chosen subset of labels is meshed against
//! everything else as background.

use std::collections::BTreeMap;
use std::path::Path;
use std::time::Instant;

use glam::DAffine3;
use isolab_algorithms::labels::{self, LabelMap, LabelSurface};
pub use isolab_algorithms::labels::{LabelSamples, LabelValues};
use isolab_algorithms::{ExtractError, Options, TriMesh};
use isolab_metrics::{accuracy, quality, topology};
use serde::Serialize;

use crate::error::RunError;

/// A label map with its place in the world.
#[derive(Clone, Debug)]
pub struct LabelVolume {
    /// Name (the file stem, or "array").
    pub name: String,
    /// Samples along i, j and k.
    pub dims: [usize; 3],
    /// One label per sample, `i + ni * (j + nj * k)`.
    pub values: LabelValues,
    /// Voxel index to world (RAS for anatomical files).
    pub index_to_world: DAffine3,
    /// Whether its world is anatomical (RAS): then meshes can be written in LPS.
    pub anatomical: bool,
    /// Things the user should know (a float file read as labels, ...).
    pub notes: Vec<String>,
}

/// Why values cannot be labels, naming the input.
fn not_labels(name: &str, reason: String) -> RunError {
    RunError::Extract(ExtractError::BadInput { algorithm: "labels", reason: format!("{name}: {reason}") })
}

impl LabelVolume {
    /// A label map from values read as floats (what the volume readers give), stored as
    /// `data_type`: every value must be a whole number from 0 to 2^24 (exact in a float). A float
    /// file of whole numbers is read as labels, with a note; one with fractions is refused, with
    /// the hint that it is an intensity volume.
    pub fn from_floats(
        name: &str,
        dims: [usize; 3],
        values: &[f32],
        data_type: &str,
        index_to_world: DAffine3,
    ) -> Result<Self, RunError> {
        const EXACT: f32 = 16_777_216.0;
        if let Some((i, v)) = values.iter().enumerate().find(|(_, v)| v.fract() != 0.0 || !v.is_finite()) {
            return Err(not_labels(
                name,
                format!(
                    "a label map holds whole numbers, but voxel {} ({} stored) is {v}: this looks like an intensity volume; \
                     mesh it with `isolab extract` (Python: isolab.extract or isolab.marching_cubes) at a level",
                    voxel(i, dims),
                    data_type
                ),
            ));
        }
        if let Some((i, v)) = values.iter().enumerate().find(|(_, v)| **v < 0.0 || **v >= EXACT) {
            return Err(not_labels(
                name,
                format!("labels are whole numbers from 0 to 16777215 here, but voxel {} is {v}", voxel(i, dims)),
            ));
        }
        let mut notes = Vec::new();
        if data_type.starts_with("float") {
            notes.push(format!("{name} is stored as {data_type}; every value is a whole number, so it is read as labels"));
        }
        let values = LabelValues::narrowest(values.iter().map(|&v| v as u32).collect());
        Ok(Self { name: name.into(), dims, values, index_to_world, anatomical: false, notes })
    }

    /// Reads a label map from a volume file (NIfTI-1/2, NRRD, MetaImage); `index` picks a 3-D
    /// volume of a 4-D file.
    pub fn read(path: &Path, index: Option<usize>) -> Result<Self, RunError> {
        let file = isolab_io::volume::read_volume(path, isolab_io::volume::VolumeOptions { index })?;
        let v = &file.volume;
        let mut out = Self::from_floats(&v.name, v.dims, &v.values_f32(), file.data_type, v.index_to_world)?;
        out.notes.splice(0..0, file.notes.iter().cloned());
        out.anatomical = file.space == isolab_io::volume::Space::Ras;
        Ok(out)
    }
}

fn voxel(i: usize, [ni, nj, _]: [usize; 3]) -> String {
    format!("({}, {}, {})", i % ni, (i / ni) % nj, i / (ni * nj))
}

/// What to mesh and how.
#[derive(Clone, Debug, Default)]
pub struct LabelConfig {
    /// A registered label extractor (`algorithms::labels::LABEL_INFOS`).
    pub algorithm: String,
    /// Its options.
    pub options: Options,
    /// The labels to mesh (every label present when `None`); the others count as background.
    pub select: Option<Vec<u32>>,
    /// The space of anatomical meshes (RAS unless asked).
    pub space: crate::OutputSpace,
}

/// One label's measures.
#[derive(Clone, Debug, Serialize)]
pub struct LabelMetrics {
    /// The label.
    pub label: u32,
    /// Samples of the label.
    pub samples: usize,
    /// Vertices and triangles of its mesh.
    pub vertices: usize,
    /// Triangles.
    pub triangles: usize,
    /// No boundary edge.
    pub closed: bool,
    /// Edge- and vertex-manifold.
    pub manifold: bool,
    /// Non-manifold edges and vertices.
    pub non_manifold: usize,
    /// Connected components.
    pub components: usize,
    /// Surface area (world units squared).
    pub area: f64,
    /// Enclosed volume (world units cubed; signed: positive when outward).
    pub volume: f64,
    /// Minimum triangle angle, degrees.
    pub min_angle_deg: f64,
    /// Mean radius ratio of the triangles: circumradius over twice the inradius (1 for
    /// equilateral, larger is worse).
    pub mean_radius_ratio: f64,
    /// Interfaces with other labels: triangles shared with each neighbouring label.
    pub neighbours: BTreeMap<u32, usize>,
}

/// A finished label run.
#[derive(Clone, Debug, Default)]
pub struct LabelOutcome {
    /// Every interface, tagged, in world coordinates.
    pub surface: LabelSurface,
    /// Each meshed label's own mesh, world coordinates.
    pub meshes: BTreeMap<u32, TriMesh>,
    /// Asked-for labels that do not occur.
    pub missing: Vec<u32>,
    /// Things the user should know (the volume's notes first).
    pub notes: Vec<String>,
    /// Wall time of the extraction, milliseconds.
    pub extract_ms: f64,
    /// Samples of every label in the input (background included), before any selection.
    pub counts: BTreeMap<u32, usize>,
    /// The space tag to write into mesh files (anatomical volumes only).
    pub space_tag: Option<&'static str>,
}

/// A label map to mesh, borrowed: [`LabelVolume::input`], or an array's memory.
#[derive(Clone, Copy, Debug)]
pub struct LabelInput<'a> {
    /// Name, for messages.
    pub name: &'a str,
    /// Samples along x, y and z.
    pub dims: [usize; 3],
    /// The labels, x fastest.
    pub values: LabelSamples<'a>,
    /// Index to world.
    pub index_to_world: DAffine3,
    /// Whether the world is anatomical (RAS).
    pub anatomical: bool,
}

impl LabelVolume {
    /// The volume as a [`LabelInput`].
    pub fn input(&self) -> LabelInput<'_> {
        LabelInput {
            name: &self.name,
            dims: self.dims,
            values: self.values.as_slice(),
            index_to_world: self.index_to_world,
            anatomical: self.anatomical,
        }
    }
}

/// Meshes every selected label of `volume` (its notes come first in the outcome's).
pub fn mesh_labels(volume: &LabelVolume, config: &LabelConfig) -> Result<LabelOutcome, RunError> {
    let mut outcome = mesh_label_input(volume.input(), config)?;
    outcome.notes.splice(0..0, volume.notes.iter().cloned());
    Ok(outcome)
}

/// Meshes every selected label of `input`.
pub fn mesh_label_input(input: LabelInput<'_>, config: &LabelConfig) -> Result<LabelOutcome, RunError> {
    let extractor = build(config)?;
    let counts = input.values.counts();
    let (keep, missing) = selection(config.select.as_deref(), &counts);
    let mut notes = Vec::new();
    if !missing.is_empty() {
        notes.push(format!("label(s) {missing:?} do not occur in {}: no mesh for them", input.name));
    }
    let selected = keep.map(|keep| input.values.keep_only(&keep));
    let values = selected.as_ref().map_or(input.values, LabelValues::as_slice);
    let mut surface = LabelSurface::default();
    let start = Instant::now();
    match values {
        LabelSamples::U8(v) => extractor.extract_u8(LabelMap::new(input.dims, v)?, &mut surface)?,
        LabelSamples::U16(v) => extractor.extract_u16(LabelMap::new(input.dims, v)?, &mut surface)?,
        LabelSamples::U32(v) => extractor.extract_u32(LabelMap::new(input.dims, v)?, &mut surface)?,
    }
    let extract_ms = start.elapsed().as_secs_f64() * 1e3;
    let space = input.anatomical.then_some(config.space);
    Ok(outcome(
        surface,
        input.index_to_world,
        space,
        LabelOutcome { missing, notes, extract_ms, counts, ..LabelOutcome::default() },
    ))
}

/// The label extractor `config` names.
pub fn build(config: &LabelConfig) -> Result<Box<dyn labels::LabelExtractor>, RunError> {
    labels::build(&config.algorithm, &config.options)?
        .ok_or_else(|| RunError::UnknownAlgorithm { name: config.algorithm.clone(), valid: labels::names().join(", ") })
}

/// The labels to keep of `select` (sorted, without the background; `None` keeps all) and those
/// asked for that `counts` does not have.
pub fn selection(select: Option<&[u32]>, counts: &BTreeMap<u32, usize>) -> (Option<Vec<u32>>, Vec<u32>) {
    let Some(select) = select else { return (None, Vec::new()) };
    let mut keep: Vec<u32> = select.iter().copied().filter(|l| *l != 0).collect();
    keep.sort_unstable();
    keep.dedup();
    let missing = keep.iter().copied().filter(|l| !counts.contains_key(l)).collect();
    (Some(keep), missing)
}

/// A surface in voxel index coordinates to the outcome: mapped to the world (and to the output
/// space of an anatomical volume), each label's mesh split off; `rest` gives the other fields.
pub fn outcome(
    mut surface: LabelSurface,
    index_to_world: DAffine3,
    space: Option<crate::OutputSpace>,
    rest: LabelOutcome,
) -> LabelOutcome {
    let mut flips = index_to_world.matrix3.determinant() < 0.0;
    surface.mesh.transform(&index_to_world);
    if let Some(map) = space.and_then(crate::OutputSpace::map_from_ras) {
        flips ^= map.matrix3.determinant() < 0.0;
        surface.mesh.transform(&map);
    }
    if flips {
        // The tetrahedra keep a positive orientation in the world.
        for t in &mut surface.tetrahedra {
            t.swap(2, 3);
        }
    }
    let meshes = surface.label_meshes();
    LabelOutcome { surface, meshes, space_tag: space.map(crate::OutputSpace::tag), ..rest }
}

/// For each label, the triangles it shares with each neighbouring label (the background
/// included): one pass over the tags.
pub fn neighbours(surface: &LabelSurface) -> BTreeMap<u32, BTreeMap<u32, usize>> {
    // Triangles come in runs of one pair (a quad's two, a cell layer's interface): count runs.
    let mut pairs: rustc_hash::FxHashMap<[u32; 2], usize> = rustc_hash::FxHashMap::default();
    let mut run: Option<([u32; 2], usize)> = None;
    for &p in &surface.pairs {
        match &mut run {
            Some((last, n)) if *last == p => *n += 1,
            _ => {
                if let Some((last, n)) = run.replace((p, 1)) {
                    *pairs.entry(last).or_insert(0) += n;
                }
            }
        }
    }
    if let Some((last, n)) = run {
        *pairs.entry(last).or_insert(0) += n;
    }
    let mut out: BTreeMap<u32, BTreeMap<u32, usize>> = BTreeMap::new();
    for ([a, b], n) in pairs {
        *out.entry(a).or_default().entry(b).or_insert(0) += n;
        *out.entry(b).or_default().entry(a).or_insert(0) += n;
    }
    out
}

/// Each label's measures (topology, area, volume, triangle shape, its interfaces).
pub fn label_metrics(outcome: &LabelOutcome) -> Vec<LabelMetrics> {
    let neighbours = neighbours(&outcome.surface);
    outcome
        .meshes
        .iter()
        .map(|(&label, mesh)| {
            let t = topology::topology(mesh);
            let q = quality::triangle_quality(mesh);
            LabelMetrics {
                label,
                samples: outcome.counts.get(&label).copied().unwrap_or(0),
                vertices: mesh.positions.len(),
                triangles: mesh.triangles.len(),
                closed: t.closed,
                manifold: t.edge_manifold && t.vertex_manifold,
                non_manifold: t.non_manifold_edges + t.non_manifold_vertices,
                components: t.components,
                area: accuracy::surface_area(mesh),
                volume: accuracy::signed_volume(mesh),
                min_angle_deg: q.min_angle_deg,
                mean_radius_ratio: q.radius_ratio.mean,
                neighbours: neighbours.get(&label).cloned().unwrap_or_default(),
            }
        })
        .collect()
}

/// A label's display colour: Matplotlib's `tab20` palette by label (the background has none); a
/// map with more labels than colours repeats them ([`colours_repeat`]).
pub fn colour(label: u32) -> [u8; 3] {
    const TAB20: [[u8; 3]; 20] = [
        [31, 119, 180],
        [174, 199, 232],
        [255, 127, 14],
        [255, 187, 120],
        [44, 160, 44],
        [152, 223, 138],
        [214, 39, 40],
        [255, 152, 150],
        [148, 103, 189],
        [197, 176, 213],
        [140, 86, 75],
        [196, 156, 148],
        [227, 119, 194],
        [247, 182, 210],
        [127, 127, 127],
        [199, 199, 199],
        [188, 189, 34],
        [219, 219, 141],
        [23, 190, 207],
        [158, 218, 229],
    ];
    TAB20[(label.saturating_sub(1) % 20) as usize]
}

/// Whether `labels` need more colours than [`colour`] has (so some share one).
pub fn colours_repeat(labels: usize) -> bool {
    labels > 20
}
