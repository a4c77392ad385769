//! The pipeline shared by the CLI and the experiments: resolve a field and an algorithm by name,
//! sample once, extract, post-process, measure, and describe the run as the metrics JSON.

use crate::io::{self, IoError};
use isolab_algorithms::chunks::{extract_chunked, ChunkStats};
use isolab_algorithms::{
    extractors, fields, ExtractError, Extraction, Field, FieldError, Grid, Lattice, LatticeError, OptionError, Options,
    SampleError, Samples,
};
use isolab_metrics::{volume_metrics, MeshMetrics, VolumeMetrics};
use serde::Serialize;
use std::path::Path;
use std::sync::Arc;

/// Which lattice to sample on.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum LatticeKind {
    /// A cubic grid.
    #[default]
    Cubic,
    /// A body-centred cubic lattice (twice the samples).
    Bcc,
}

/// What to run.
#[derive(Clone, Debug)]
pub struct RunConfig {
    /// Extractor name.
    pub algorithm: String,
    /// Built-in field name, or a path to an `.obj` file.
    pub field: String,
    /// Samples along the domain's longest side.
    pub resolution: usize,
    /// Exact samples per axis, overriding `resolution` (e.g. the RMT paper's 75x40x56 bunny).
    pub dims: Option<[usize; 3]>,
    /// Lattice kind.
    pub lattice: LatticeKind,
    /// Iso-value.
    pub iso: f32,
    /// Seed of noise fields.
    pub seed: i32,
    /// Post-processes to apply in order.
    pub post: Vec<String>,
    /// Algorithm options by name (`smoothing`, `iterations`, ...).
    pub options: Options,
    /// Mesh in chunks of this many cells per side and weld (`--chunk N`).
    pub chunk: Option<usize>,
    /// Give every vertex the field's material (`--materials`).
    pub materials: bool,
}

impl RunConfig {
    /// A config with defaults for everything but the algorithm, field and resolution.
    pub fn new(algorithm: &str, field: &str, resolution: usize) -> Self {
        Self {
            algorithm: algorithm.into(),
            field: field.into(),
            resolution,
            dims: None,
            lattice: LatticeKind::Cubic,
            iso: 0.0,
            seed: fields::DEFAULT_SEED,
            post: Vec::new(),
            options: Options::new(),
            chunk: None,
            materials: false,
        }
    }
}

/// Everything that can go wrong in a run. [`RunError::exit_code`] maps it to the CLI's code.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// No extractor has that name.
    #[error("unknown algorithm '{name}'; valid algorithms: {valid}")]
    UnknownAlgorithm {
        /// Name given.
        name: String,
        /// Valid names.
        valid: String,
    },
    /// An algorithm option is unknown or out of range.
    #[error(transparent)]
    Option(#[from] OptionError),
    /// No post-process has that name.
    #[error("unknown post-process '{name}'; valid post-processes: {valid}")]
    UnknownPost {
        /// Name given.
        name: String,
        /// Valid names.
        valid: String,
    },
    /// Field problems (unknown name, bad mesh).
    #[error(transparent)]
    Field(#[from] FieldError),
    /// File problems.
    #[error(transparent)]
    Io(#[from] IoError),
    /// Impossible lattice.
    #[error(transparent)]
    Lattice(#[from] LatticeError),
    /// Non-finite samples.
    #[error(transparent)]
    Samples(#[from] SampleError),
    /// Extraction failed.
    #[error(transparent)]
    Extract(#[from] ExtractError),
    /// The iso-value is NaN or infinite.
    #[error("iso-value {0} is not finite")]
    BadIso(f32),
    /// Not enough memory for the lattice.
    #[error("a {dims:?} {lattice} lattice needs about {need_mib} MiB, but only {available_mib} MiB of memory is available; lower --resolution")]
    OutOfMemory {
        /// Samples per axis.
        dims: [usize; 3],
        /// Lattice kind.
        lattice: &'static str,
        /// Estimated need.
        need_mib: u64,
        /// Available.
        available_mib: u64,
    },
}

impl RunError {
    /// 2 for an unknown name (usage error), 1 otherwise.
    pub fn exit_code(&self) -> i32 {
        match self {
            RunError::UnknownAlgorithm { .. }
            | RunError::UnknownPost { .. }
            | RunError::Option(_)
            | RunError::Field(FieldError::Unknown { .. }) => 2,
            _ => 1,
        }
    }
}

/// Loads a built-in field by name, or an OBJ file as a signed-distance field.
pub fn load_field(spec: &str, seed: i32) -> Result<Arc<dyn Field>, RunError> {
    let path = Path::new(spec);
    let looks_like_file = spec.to_ascii_lowercase().ends_with(".obj") || spec.contains('/') || path.is_file();
    if !looks_like_file {
        return Ok(fields::builtin(spec, fields::FieldParams { seed })?);
    }
    let mesh = io::read_obj(path, io::Coordinates::Finite)?;
    let name = path.file_stem().and_then(|s| s.to_str()).unwrap_or(spec);
    Ok(Arc::new(fields::MeshField::new(name, &mesh.positions, &mesh.triangles)?))
}

/// Memory available to this process, from `/proc/meminfo` (None where unknown).
pub fn available_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

/// Refuses lattices whose samples plus a generous output estimate (four times the samples'
/// bytes) exceed the memory available to this process.
pub fn check_memory(lattice: &Lattice) -> Result<(), RunError> {
    check_memory_against(lattice, available_memory())
}

/// [`check_memory`] against a given number of available bytes (`None`: unknown, accept).
pub fn check_memory_against(lattice: &Lattice, available: Option<u64>) -> Result<(), RunError> {
    let need = lattice.sample_count() as u64 * 4 * 5;
    match available {
        Some(available) if need > available => Err(RunError::OutOfMemory {
            dims: lattice.grid().dims,
            lattice: lattice.kind(),
            need_mib: need >> 20,
            available_mib: available >> 20,
        }),
        _ => Ok(()),
    }
}

/// Builds the lattice a config asks for.
pub fn lattice_for(field: &dyn Field, config: &RunConfig) -> Result<Lattice, RunError> {
    let domain = field.domain();
    let grid = match config.dims {
        Some(dims) => Grid::with_dims(&domain, dims)?,
        None => Grid::covering(&domain, config.resolution)?,
    };
    Ok(match config.lattice {
        LatticeKind::Cubic => Lattice::Cubic(grid),
        LatticeKind::Bcc => Lattice::Bcc(grid),
    })
}

/// Wall times in milliseconds (the metrics JSON's `times_ms`).
#[derive(Clone, Copy, Debug, Serialize)]
pub struct TimesMs {
    /// Field evaluation.
    pub sampling: f64,
    /// Vertex + geometry + normals.
    pub extraction: f64,
    /// Post-processes.
    pub post: f64,
    /// Everything.
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
    /// Iso-value.
    pub iso: f32,
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
    /// Vertices per material (`--materials`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub materials: Option<std::collections::BTreeMap<String, usize>>,
    /// What the extractor warned about (an open input surface, non-convergence).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<String>,
    /// Mesh measures.
    #[serde(flatten)]
    pub metrics: MeshMetrics,
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

/// The outcome of a run: the meshes and their report.
pub struct RunOutcome {
    /// The samples it extracted from.
    pub samples: Samples,
    /// What the extractor produced.
    pub extraction: Extraction,
    /// Each surface vertex's material (with `materials`), else empty.
    pub vertex_materials: Vec<u8>,
    /// The metrics JSON.
    pub report: RunReport,
}

/// Samples, extracts, post-processes and measures.
pub fn run(config: &RunConfig) -> Result<RunOutcome, RunError> {
    let extractor = extractors::build(&config.algorithm, &config.options)?
        .ok_or_else(|| RunError::UnknownAlgorithm { name: config.algorithm.clone(), valid: extractors::names() })?;
    let posts = config
        .post
        .iter()
        .map(|p| {
            extractors::build_post(p)?.ok_or_else(|| RunError::UnknownPost { name: p.clone(), valid: extractors::post_names() })
        })
        .collect::<Result<Vec<_>, _>>()?;
    if !config.iso.is_finite() {
        return Err(RunError::BadIso(config.iso));
    }
    let field = load_field(&config.field, config.seed)?;
    let lattice = lattice_for(field.as_ref(), config)?;
    check_memory(&lattice)?;
    let samples = Samples::sample(field.clone(), lattice, config.iso)?;
    let mut extraction = Extraction::default();
    let chunks = match config.chunk {
        Some(n) => Some(ChunkReport::from((n, extract_chunked(extractor.as_ref(), &samples, n, &mut extraction)?))),
        None => {
            extractor.extract(&samples, &mut extraction)?;
            None
        }
    };
    for post in &posts {
        post.apply(&samples, &mut extraction)?;
    }
    let mut vertex_materials = Vec::new();
    if config.materials {
        let grid = *samples.grid();
        let sample_materials = isolab_algorithms::materials::sample(field.as_ref(), &grid);
        let corners = &samples.values()[..grid.len()];
        let positions = &extraction.surface.positions;
        isolab_algorithms::materials::vertex_materials(
            &grid,
            corners,
            config.iso,
            &sample_materials,
            positions,
            &mut vertex_materials,
        );
    }
    let material_counts = config.materials.then(|| {
        let counts = isolab_algorithms::materials::histogram(&vertex_materials);
        counts
            .iter()
            .enumerate()
            .filter(|(_, &n)| n > 0)
            .map(|(id, &n)| (isolab_algorithms::materials::name(id as u8), n))
            .collect()
    });
    let metrics = MeshMetrics::measure(&extraction.surface, Some((field.as_ref(), config.iso)));
    let volume_mesh =
        volume_metrics(&extraction.volume, &extraction.surface, Some((field.as_ref(), config.iso)), extraction.stats.converged);
    let t = extraction.stats.times;
    let ms = |d: std::time::Duration| d.as_secs_f64() * 1e3;
    let report = RunReport {
        algorithm: config.algorithm.clone(),
        field: field.name().to_owned(),
        resolution: samples.grid().dims.iter().copied().max().unwrap_or(0),
        dims: samples.grid().dims,
        lattice: samples.lattice().kind(),
        iso: config.iso,
        seed: config.seed,
        post: config.post.clone(),
        tetrahedra: extraction.stats.tetrahedra,
        times_ms: TimesMs {
            sampling: ms(t.sampling),
            extraction: ms(t.extraction()),
            post: ms(t.post),
            total: ms(t.total()),
            vertex: ms(t.vertex),
            geometry: ms(t.geometry),
            normals: ms(t.normals),
        },
        active_cells: extraction.stats.active_cells,
        buffer_bytes: extraction.stats.buffer_bytes,
        triangles_per_second: extraction.stats.triangles as f64 / t.extraction().as_secs_f64().max(1e-9),
        analytic_volume: field.analytic_volume(config.iso),
        analytic_area: field.analytic_area(config.iso),
        volume_mesh,
        chunks,
        materials: material_counts,
        warnings: extraction.stats.warnings.clone(),
        metrics,
    };
    Ok(RunOutcome { samples, extraction, vertex_materials, report })
}

/// Writes any serializable value as pretty JSON, atomically.
pub fn write_json(path: &Path, value: &impl Serialize) -> Result<(), IoError> {
    io::write_atomic(path, |w| {
        serde_json::to_writer_pretty(&mut *w, value).map_err(std::io::Error::other)?;
        std::io::Write::write_all(w, b"\n")
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lattices_larger_than_memory_are_refused_with_sizes() {
        let field = fields::builtin("sphere", Default::default()).unwrap();
        let lattice = lattice_for(field.as_ref(), &RunConfig::new("marching-cubes", "sphere", 512)).unwrap();
        let err = check_memory_against(&lattice, Some(1 << 30)).unwrap_err();
        assert!(matches!(err, RunError::OutOfMemory { need_mib: 2560, available_mib: 1024, .. }), "{err}");
        assert!(err.to_string().contains("lower --resolution"));
        assert!(check_memory_against(&lattice, Some(1 << 34)).is_ok());
        assert!(check_memory_against(&lattice, None).is_ok());
    }

    #[test]
    fn mesh_fields_are_loaded_by_path_and_builtins_by_name() {
        let bunny = concat!(env!("CARGO_MANIFEST_DIR"), "/../models/spot.obj");
        assert_eq!(load_field(bunny, 0).unwrap().name(), "spot");
        assert_eq!(load_field("torus", 0).unwrap().name(), "torus");
        assert!(matches!(load_field("no-such-field", 0), Err(RunError::Field(FieldError::Unknown { .. }))));
        assert_eq!(RunError::Field(FieldError::Unknown { name: String::new(), valid: String::new() }).exit_code(), 2);
    }
}
