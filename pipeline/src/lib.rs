//! # isolab pipeline
//!
//! The one run shared by the `isolab` CLI, the Python package and the report's experiments:
//! resolve an input ([`input`]: a built-in field, a mesh file, a volume file) and an algorithm by
//! name, sample once (or take a volume's own voxels), extract, post-process, map to world
//! coordinates, measure, and describe the run as the metrics JSON ([`RunReport`]). Errors are one
//! type ([`RunError`]) whose messages the CLI prints and Python raises.
//!
//! Depends on `isolab-algorithms`, `isolab-metrics` and `isolab-io` only: no command-line parser
//! (the `clap` feature derives `clap::ValueEnum` for the CLI's enums), no plotting.

pub mod config;
pub mod error;
pub mod files;
pub mod input;
pub mod labels;
pub mod neuroglancer;
pub mod registry;
pub mod stream;

pub use crate::input::load_field;
pub use crate::input::Input;
use crate::input::{load_input, InputKind, MeshChecks};
use glam::{DAffine3, DMat3, DVec3};
use isolab_algorithms::chunks::extract_chunked;
use isolab_algorithms::fields::Complement;
use isolab_algorithms::{extractors, post, Extraction, Field, Grid, Lattice, Samples, TetMesh, TriMesh};
use isolab_io::volume::{Inside, Space};
use isolab_io::{self as io, IoError};
use isolab_metrics::{volume_metrics, MeshMetrics, VolumeMetrics};
use rayon::prelude::*;
use serde::Serialize;
use std::path::Path;
use std::sync::Arc;
use std::time::Instant;

mod memory;
mod report;
pub mod sparse;

use memory::check_volume_size;
pub use memory::{available_memory, check_memory, check_memory_against, volume_file_need};
use report::{empty_mesh_warning, no_inside_warning};

pub use crate::config::{LatticeKind, Measure, OutputSpace, RunConfig, RunConfigBuilder, VolumeGrid};
pub use crate::error::RunError;

pub use report::{ChunkReport, InputReport, MeshCounts, RunReport, TimesMs};
pub use sparse::{Sparse, SparseReport};

/// Where a volume's iso-value came from when none was given: the grid's own, Otsu's threshold,
/// or the one value of a constant volume (the in-memory and the streamed run say it alike).
pub(crate) const ISO_FROM_GRID: &str = "the grid's own iso-value";
/// See [`ISO_FROM_GRID`].
pub(crate) const ISO_FROM_OTSU: &str = "Otsu's threshold of the volume's values";
/// See [`ISO_FROM_GRID`].
pub(crate) const ISO_FROM_CONSTANT: &str = "every voxel has this value";

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

/// The outcome of a run: the meshes and their report.
pub struct RunOutcome {
    /// The samples it extracted from (for a volume on its own grid: in voxel index coordinates
    /// unless the voxels are world-aligned cubes); `None` for a sparse run, which never holds
    /// them all.
    pub samples: Option<Samples<'static>>,
    /// What the extractor produced, in world coordinates.
    pub extraction: Extraction,
    /// Each surface vertex's material (with `materials`), else empty.
    pub vertex_materials: Vec<u8>,
    /// The map from the samples' coordinates to the world, when they differ (a volume meshed on
    /// its own voxel grid); what `--samples-out` records.
    pub samples_to_world: Option<DAffine3>,
    /// What to tag mesh files with (`SPACE=RAS`), for anatomical volumes.
    pub space_tag: Option<&'static str>,
    /// Things to tell the user that are not warnings (the grid a volume was meshed on).
    pub notes: Vec<String>,
    /// The true surface the mesh can be measured against ([`measure`]); `None` once the mesh was
    /// mapped out of the field's world (to LPS).
    pub truth: Option<Truth>,
    /// The metrics JSON.
    pub report: RunReport,
}

/// The samples a run extracts from, and the map from their coordinates to the world.
struct Sampled {
    samples: Samples<'static>,
    to_world: Option<DAffine3>,
    notes: Vec<String>,
}

/// A volume's own voxels as samples: read negated when inside is above (so that inside is
/// `f < iso` as everywhere in isolab), on a grid in the world when the voxels are world-aligned
/// cubes (no mapping needed), else in voxel index coordinates, with the affine that maps a mesh
/// of them to the world. `iso` is in the volume's own values. On a cubic lattice the samples are
/// the volume's values in their stored type, shared (no copy; the caller checks the memory an
/// extractor that copies them needs); a BCC lattice's are `f32`, with the cell centres.
pub fn volume_samples(
    file: &isolab_io::volume::VolumeFile,
    lattice: LatticeKind,
    inside: Inside,
    iso: f32,
) -> Result<(Samples<'static>, Option<DAffine3>), RunError> {
    let start = Instant::now();
    let v = &file.volume;
    let sign = if inside == Inside::Above { -1.0f32 } else { 1.0 };
    let m = v.index_to_world.matrix3;
    let h = m.x_axis.x;
    let aligned = h > 0.0 && m == DMat3::from_diagonal(DVec3::splat(h)) && (h as f32) as f64 == h;
    let (grid, to_world) = if aligned {
        (Grid { origin: v.index_to_world.translation.as_vec3(), spacing: h as f32, dims: v.dims }, None)
    } else {
        (Grid { origin: glam::Vec3::ZERO, spacing: 1.0, dims: v.dims }, Some(v.index_to_world))
    };
    let samples = match lattice {
        LatticeKind::Cubic => Samples::stored(grid, v.values().clone(), inside == Inside::Above, sign * iso)?,
        LatticeKind::Bcc => {
            let lattice = Lattice::Bcc(grid);
            check_memory(&lattice)?;
            let mut values: Vec<f32> = Vec::with_capacity(lattice.sample_count());
            values.par_extend(v.values_f32().par_iter().map(|&x| sign * x));
            let centres = file.centres.clone().unwrap_or_else(|| v.cell_centres());
            values.extend(centres.iter().map(|&x| sign * x));
            Samples::from_values(lattice, values, sign * iso)?
        }
    };
    Ok((samples.with_sampling_time(start.elapsed()), to_world))
}

fn native_samples(
    file: &isolab_io::volume::VolumeFile,
    config: &RunConfig,
    inside: Inside,
    iso: f32,
) -> Result<Sampled, RunError> {
    if config.lattice == LatticeKind::Cubic && !memory::meshes_in_place(config) {
        // The extractor copies the samples into f32: the old, generous check.
        check_memory(&Lattice::Cubic(Grid { origin: glam::Vec3::ZERO, spacing: 1.0, dims: file.volume.dims }))?;
    }
    let (samples, to_world) = volume_samples(file, config.lattice, inside, iso)?;
    let [a, b, c] = file.volume.dims;
    let note =
        format!("meshing {} on its own {a} x {b} x {c} voxel grid (--resolution N or --dims resamples it)", file.volume.name);
    Ok(Sampled { samples, to_world, notes: vec![note] })
}

/// Loads the input `config.field` names, then samples, extracts, post-processes and measures
/// ([`run_input`]).
pub fn run(config: &RunConfig) -> Result<RunOutcome, RunError> {
    check_names(config)?;
    check_volume_size(config)?;
    let input = load_input(&config.field, config.seed, config.volume, MeshChecks::Warn)?;
    run_input(config, input)
}

/// Refuses an unknown algorithm, option or post-process before anything is read.
fn check_names(config: &RunConfig) -> Result<(), RunError> {
    extractors::build(&config.algorithm, &config.options)?
        .ok_or_else(|| RunError::UnknownAlgorithm { name: config.algorithm.clone(), valid: extractors::names() })?;
    for p in &config.post {
        post::build_post(p)?.ok_or_else(|| RunError::UnknownPost { name: p.clone(), valid: post::post_names() })?;
    }
    Ok(())
}

/// Samples an input already loaded (a file, a built-in field, or an array handed over in
/// memory: [`Input::from_volume`]), extracts, post-processes and measures. `config.field` is
/// not read.
pub fn run_input(config: &RunConfig, input: Input) -> Result<RunOutcome, RunError> {
    let extractor = extractors::build(&config.algorithm, &config.options)?
        .ok_or_else(|| RunError::UnknownAlgorithm { name: config.algorithm.clone(), valid: extractors::names() })?;
    let posts = config
        .post
        .iter()
        .map(|p| post::build_post(p)?.ok_or_else(|| RunError::UnknownPost { name: p.clone(), valid: post::post_names() }))
        .collect::<Result<Vec<_>, _>>()?;
    if let Some(iso) = config.iso.filter(|v| !v.is_finite()) {
        return Err(RunError::BadIso(iso));
    }
    let inside = config.inside.unwrap_or(input.default_inside());
    let (iso, iso_from) = choose_iso(&input, config.iso);
    // Inside is `f < iso` in isolab: "above" meshes the complement at `-iso`.
    let field: Arc<dyn Field> = match inside {
        Inside::Below => input.field.clone(),
        Inside::Above => Arc::new(Complement(input.field.clone())),
    };
    let internal_iso = if inside == Inside::Above { -iso } else { iso };
    let native = input.volume.as_ref().filter(|_| config.volume_grid == VolumeGrid::Native);
    let mut warnings = input.warnings.clone();
    // Extractors that can estimate their output refuse one the memory available cannot hold.
    let memory_limit = available_memory();
    // The grid a field (not a volume's own voxels) is sampled on; a sparse run samples it too.
    let field_grid = match native {
        Some(_) => None,
        None => Some(sparse::grid_for(field.as_ref(), config)?),
    };
    let bound = sparse::sparse_bound(config, &input, field.as_ref(), extractor.as_ref(), field_grid.as_ref())?;
    let (samples, grid, lattice_kind, to_world, mut notes, mut extraction, chunks, sparse_report) = match (bound, field_grid) {
        (Some(bound), Some(grid)) => {
            let (extraction, report) =
                sparse::extract_sparse_run(extractor.as_ref(), &field, &grid, internal_iso, bound, config.chunk, memory_limit)?;
            warnings.extend(sparse::empty_warning(&extraction, field.as_ref(), &grid, internal_iso, iso, inside));
            (None, grid, "cubic", None, Vec::new(), extraction, None, Some(report))
        }
        _ => {
            let Sampled { samples, to_world, notes } = match native {
                Some(file) => native_samples(file, config, inside, iso)?,
                None => {
                    let lattice = lattice_for(field.as_ref(), config)?;
                    check_memory(&lattice)?;
                    let samples = Samples::sample(field.clone(), lattice, internal_iso)?;
                    Sampled { samples, to_world: None, notes: Vec::new() }
                }
            };
            warnings.extend(no_inside_warning(&samples, field.name(), iso, inside));
            let mut extraction = Extraction { memory_limit, ..Extraction::default() };
            let chunks = match config.chunk {
                Some(n) => {
                    let stats = extract_chunked(extractor.as_ref(), &samples, n, &mut extraction)?;
                    Some(ChunkReport::from((n, stats)))
                }
                None => {
                    extractor.extract(&samples, &mut extraction)?;
                    None
                }
            };
            for post in &posts {
                post.apply(&samples, &mut extraction)?;
            }
            let (grid, kind) = (*samples.grid(), samples.lattice().kind());
            (Some(samples), grid, kind, to_world, notes, extraction, chunks, None)
        }
    };
    let world_start = Instant::now();
    if let Some(a) = &to_world {
        extraction.surface.transform(a);
        extraction.volume.transform(a);
    }
    let to_world_time = world_start.elapsed();
    let mut vertex_materials = Vec::new();
    if let Some(samples) = samples.as_ref().filter(|_| config.materials) {
        let sample_materials = isolab_algorithms::materials::sample(field.as_ref(), &grid);
        let corners = &samples.values()[..grid.len()];
        let positions = &extraction.surface.positions;
        isolab_algorithms::materials::vertex_materials(
            &grid,
            corners,
            internal_iso,
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
    let world_truth = Truth { field: field.clone(), iso: internal_iso, converged: extraction.stats.converged };
    let (metrics, volume_mesh) = measure(&extraction.surface, &extraction.volume, Some(&world_truth), config.measure);
    let counts = metrics
        .is_none()
        .then_some(MeshCounts { vertices: extraction.surface.positions.len(), triangles: extraction.surface.triangles.len() });
    // Anatomical volumes: the mesh in the space asked for (metrics are the same in either).
    let anatomical = input.volume.as_ref().is_some_and(|v| v.space == Space::Ras);
    let space = anatomical.then_some(config.space);
    if let Some(map) = space.and_then(OutputSpace::map_from_ras) {
        extraction.surface.transform(&map);
        extraction.volume.transform(&map);
    }
    // The true surface, for measuring later: in the world the field is in (RAS), so not once
    // the mesh has been mapped to LPS.
    let truth = space.and_then(OutputSpace::map_from_ras).is_none().then(|| Truth {
        field: field.clone(),
        iso: internal_iso,
        converged: extraction.stats.converged,
    });
    let samples_to_world = match (to_world, space.and_then(OutputSpace::map_from_ras)) {
        (Some(a), Some(m)) => Some(m * a),
        (Some(a), None) => Some(a),
        (None, Some(m)) if native.is_some() => Some(m),
        _ => None,
    };
    for warning in &extraction.stats.warnings {
        // bcc-sculpt's own note on an open input repeats the input check's.
        if !(input.kind == InputKind::Mesh && warning.starts_with("input surface '")) {
            warnings.push(warning.clone());
        }
    }
    if let Some(v) = &input.volume {
        notes.extend(v.notes.iter().map(|n| format!("{}: {n}", v.volume.name)));
        if let Some(from) = iso_from {
            notes.push(format!("no --iso given: {iso} ({from})"));
        }
    }
    let t = extraction.stats.times;
    let ms = |d: std::time::Duration| d.as_secs_f64() * 1e3;
    let input_report = InputReport {
        kind: input.kind,
        format: input.volume.as_ref().map(|v| v.format).or(input.mesh_format),
        data_type: input.volume.as_ref().map(|v| v.data_type),
        shape: input.volume.as_ref().map(|v| v.volume.dims),
        spacing: input.volume.as_ref().map(|v| v.volume.spacing()),
        grid: input.volume.as_ref().map(|_| config.volume_grid),
        space,
        iso_from,
        notes: input.volume.as_ref().map(|v| v.notes.clone()).unwrap_or_default(),
    };
    let report = RunReport {
        algorithm: config.algorithm.clone(),
        field: field.name().to_owned(),
        resolution: grid.dims.iter().copied().max().unwrap_or(0),
        dims: grid.dims,
        lattice: lattice_kind,
        iso,
        inside,
        input: input_report,
        seed: config.seed,
        post: config.post.clone(),
        tetrahedra: extraction.stats.tetrahedra,
        times_ms: TimesMs {
            reading: ms(input.read_time),
            sampling: ms(t.sampling),
            extraction: ms(t.extraction()),
            post: ms(t.post),
            to_world: ms(to_world_time),
            total: ms(input.read_time + t.total() + to_world_time),
            vertex: ms(t.vertex),
            geometry: ms(t.geometry),
            normals: ms(t.normals),
        },
        active_cells: extraction.stats.active_cells,
        buffer_bytes: extraction.stats.buffer_bytes,
        triangles_per_second: extraction.stats.triangles as f64 / t.extraction().as_secs_f64().max(1e-9),
        analytic_volume: field.analytic_volume(internal_iso),
        analytic_area: field.analytic_area(internal_iso),
        volume_mesh,
        chunks,
        sparse: sparse_report,
        materials: material_counts,
        warnings,
        counts,
        metrics,
    };
    Ok(RunOutcome {
        samples,
        extraction,
        vertex_materials,
        samples_to_world,
        space_tag: space.map(OutputSpace::tag),
        notes,
        truth,
        report,
    })
}

/// The field a run meshed and its iso-value (inside `f < iso`), with which a mesh of it can be
/// measured against the true surface after the run ([`measure`]).
#[derive(Clone)]
pub struct Truth {
    /// The field as meshed (the complement when inside was above).
    pub field: Arc<dyn Field>,
    /// The iso-value in the field's values.
    pub iso: f32,
    /// Whether a volume extractor's relaxation converged, where it reports it.
    pub converged: Option<bool>,
}

/// Measures a run's surface and volume meshes as [`run`] does for `measure` (nothing for
/// [`Measure::Counts`]), against the true surface where `truth` is given.
pub fn measure(
    surface: &TriMesh,
    volume: &TetMesh,
    truth: Option<&Truth>,
    measure: Measure,
) -> (Option<MeshMetrics>, Option<VolumeMetrics>) {
    let field = truth.map(|t| (t.field.as_ref(), t.iso));
    let metrics = match measure {
        Measure::Counts => return (None, None),
        Measure::Metrics => MeshMetrics::measure_without_self_intersections(surface, field),
        Measure::All => MeshMetrics::measure(surface, field),
    };
    (Some(metrics), volume_metrics(volume, surface, field, truth.and_then(|t| t.converged)))
}

/// The iso-value of a run, in the input's own values, and how it was chosen when not given.
fn choose_iso(input: &Input, given: Option<f32>) -> (f32, Option<&'static str>) {
    if let Some(iso) = given {
        return (iso, None);
    }
    match &input.volume {
        Some(v) => match v.iso {
            Some(iso) => (iso, Some(ISO_FROM_GRID)),
            None => match v.volume.otsu_threshold() {
                Some(t) => (t, Some(ISO_FROM_OTSU)),
                None => (v.volume.value(0), Some(ISO_FROM_CONSTANT)),
            },
        },
        None => (0.0, None),
    }
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
    use isolab_algorithms::fields;

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
    fn output_space_maps_ras_to_lps() {
        let m = OutputSpace::Lps.map_from_ras().unwrap();
        assert_eq!(m.transform_point3(DVec3::new(1.0, 2.0, 3.0)), DVec3::new(-1.0, -2.0, 3.0));
        assert!(OutputSpace::Ras.map_from_ras().is_none());
    }

    #[test]
    fn mesh_fields_are_loaded_by_path_and_builtins_by_name() {
        let bunny = concat!(env!("CARGO_MANIFEST_DIR"), "/../models/spot.obj");
        assert_eq!(load_field(bunny, 0).unwrap().name(), "spot");
        assert_eq!(load_field("torus", 0).unwrap().name(), "torus");
        assert!(matches!(load_field("no-such-field", 0), Err(RunError::Field(isolab_algorithms::FieldError::Unknown { .. }))));
        assert_eq!(
            RunError::Field(isolab_algorithms::FieldError::Unknown { name: String::new(), valid: String::new() }).exit_code(),
            2
        );
    }
}
