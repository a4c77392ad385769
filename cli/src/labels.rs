//! `isolab labels`: a label map to one mesh per label (files in a folder, or one `.glb` with a
//! named, coloured node per label), with each label's metrics.

use std::path::{Path, PathBuf};

use isolab_io as io;
use isolab_pipeline::labels::{self, LabelConfig, LabelVolume};
use isolab_pipeline::{write_json, RunError};

/// One `isolab labels` call.
pub struct Job {
    /// The label map file.
    pub input: PathBuf,
    /// Which 3-D volume of a 4-D file.
    pub volume: Option<usize>,
    /// Algorithm, options, labels, space.
    pub config: LabelConfig,
    /// A folder or a `.glb`.
    pub output: Option<PathBuf>,
    /// Per-label file format in a folder, or `neuroglancer`.
    pub format: String,
    /// The neuroglancer source's settings (with `format` `neuroglancer`).
    pub neuroglancer: NeuroglancerJob,
    /// Metrics JSON path (`-`: stdout).
    pub metrics: Option<PathBuf>,
}

/// `--format neuroglancer`'s settings.
#[derive(Clone, Copy, Debug)]
pub struct NeuroglancerJob {
    /// Cells per level-0 box.
    pub chunk: usize,
    /// Levels of detail (`None`: down to one box).
    pub lods: Option<usize>,
    /// Shards instead of two files per segment.
    pub sharded: bool,
    /// Quantization bits.
    pub bits: u32,
}

/// Where the meshes go.
enum Target {
    /// One `.glb`, a node per label.
    Scene(PathBuf),
    /// A folder, a file per label with this extension.
    Folder(PathBuf, String),
    /// A folder holding a neuroglancer precomputed mesh source.
    Neuroglancer(PathBuf),
    /// One `.vtk` unstructured grid or `.msh` (Gmsh 2.2) file: the tetrahedra, a label per cell.
    Tetrahedra(PathBuf),
}

fn bad_output(path: &Path, reason: &str) -> RunError {
    io::IoError::Write { path: path.into(), source: std::io::Error::new(std::io::ErrorKind::InvalidInput, reason.to_owned()) }
        .into()
}

/// Checks the output before any work: a `.glb` in an existing folder, a `.vtk` or `.msh` there
/// from an algorithm that makes tetrahedra, or a folder (created) and a mesh format.
fn target(output: &Path, format: &str, config: &LabelConfig) -> Result<Target, RunError> {
    let ext = io::extension(output);
    if let Some(ext @ ("vtk" | "msh")) = ext.as_deref() {
        let extractor = labels::build(config)?;
        if extractor.info().guarantees.dihedral.is_none() {
            return Err(bad_output(
                output,
                &format!(
                    "a .{ext} output holds tetrahedra, and {} makes surfaces only: use -a lattice-cleaving, or give a folder or a .glb",
                    config.algorithm
                ),
            ));
        }
        let dir = output.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
        if !dir.is_dir() {
            return Err(bad_output(output, "its folder does not exist"));
        }
        return Ok(Target::Tetrahedra(output.into()));
    }
    if ext.as_deref() == Some("glb") {
        let dir = output.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
        if !dir.is_dir() {
            return Err(bad_output(output, "its folder does not exist"));
        }
        return Ok(Target::Scene(output.into()));
    }
    if ext.is_some() && io::MeshFormat::from_extension(output).is_some() {
        return Err(bad_output(
            output,
            "one file holds every label only as .glb (a node per label); give a folder for one file per label",
        ));
    }
    if format == "neuroglancer" || format == "neuroglancer-legacy" {
        if ext.is_some() {
            return Err(bad_output(output, "a neuroglancer source is a folder: give a folder name, not a file"));
        }
        std::fs::create_dir_all(output).map_err(|source| io::IoError::Write { path: output.into(), source })?;
        return Ok(Target::Neuroglancer(output.into()));
    }
    let probe = Path::new("label").with_extension(format);
    if io::MeshFormat::from_extension(&probe).is_none() {
        return Err(bad_output(
            output,
            &format!("--format {format} is not a mesh format (ply, obj, stl, glb, gltf) nor neuroglancer"),
        ));
    }
    std::fs::create_dir_all(output).map_err(|source| io::IoError::Write { path: output.into(), source })?;
    Ok(Target::Folder(output.into(), format.to_owned()))
}

/// The outcome's tetrahedra, a label per cell, as one `.vtk` or, by its extension, `.msh`.
fn write_tetrahedra(path: &Path, outcome: &labels::LabelOutcome) -> Result<(), RunError> {
    let s = &outcome.surface;
    io::write_labelled_tets(path, &s.mesh.positions, &s.tetrahedra, &s.tetrahedron_labels, outcome.space_tag)?;
    Ok(())
}

/// Runs the job: reads, meshes, writes, reports.
pub fn run(job: &Job) -> Result<(), RunError> {
    if job.format.starts_with("neuroglancer") {
        check_neuroglancer(job)?;
    }
    let target = job.output.as_deref().map(|o| target(o, &job.format, &job.config)).transpose()?;
    let volume = LabelVolume::read(&job.input, job.volume)?;
    if let Some(Target::Neuroglancer(dir)) = &target {
        return run_neuroglancer(job, &volume, dir);
    }
    let outcome = labels::mesh_labels(&volume, &job.config)?;
    for note in &outcome.notes {
        eprintln!("note: {note}");
    }
    if labels::colours_repeat(outcome.meshes.len()) {
        eprintln!("note: {} labels share 20 colours, so some colours repeat", outcome.meshes.len());
    }
    if outcome.meshes.is_empty() {
        eprintln!("warning: {} has no label to mesh (every selected sample is background)", volume.name);
    }
    let name = |label: u32| format!("{}-label-{label}", volume.name);
    match &target {
        Some(Target::Scene(path)) => {
            let names: Vec<String> = outcome.meshes.keys().map(|&l| format!("label {l}")).collect();
            let parts: Vec<io::gltf::Part<'_>> = outcome
                .meshes
                .iter()
                .zip(&names)
                .map(|((&label, mesh), name)| io::gltf::Part { name, mesh, colour: labels::colour(label) })
                .collect();
            io::write_atomic(path, |w| io::gltf::write_glb_parts(w, &parts, concat!("isolab ", env!("CARGO_PKG_VERSION"))))?;
        }
        Some(Target::Folder(dir, ext)) => {
            for (&label, mesh) in &outcome.meshes {
                let path = dir.join(name(label)).with_extension(ext);
                isolab_pipeline::files::write_meshes(&path, mesh, &Default::default(), &[], outcome.space_tag)?;
            }
            if !outcome.surface.tetrahedra.is_empty() {
                write_tetrahedra(&dir.join(format!("{}-tetrahedra.vtk", volume.name)), &outcome)?;
            }
        }
        Some(Target::Tetrahedra(path)) => write_tetrahedra(path, &outcome)?,
        Some(Target::Neuroglancer(_)) | None => {}
    }
    let metrics = labels::label_metrics(&outcome);
    match job.metrics.as_deref() {
        Some(path) if path.as_os_str() != "-" => write_json(path, &metrics)?,
        Some(_) => println!("{}", serde_json::to_string_pretty(&metrics).unwrap_or_default()),
        None => {
            println!("{} labels meshed by {} in {:.1} ms", metrics.len(), job.config.algorithm, outcome.extract_ms);
            if !outcome.surface.tetrahedra.is_empty() {
                println!("{} tetrahedra filling them", outcome.surface.tetrahedra.len());
            }
            for m in &metrics {
                println!(
                    "label {:>6}: {:>8} triangles, {}, {}, area {:.4}, volume {:.4}, neighbours {:?}",
                    m.label,
                    m.triangles,
                    if m.closed { "closed" } else { "open" },
                    if m.manifold { "manifold".to_owned() } else { format!("{} non-manifold", m.non_manifold) },
                    m.area,
                    m.volume,
                    m.neighbours.keys().collect::<Vec<_>>()
                );
            }
        }
    }
    Ok(())
}

fn neuroglancer_error(output: &Path, reason: String) -> RunError {
    RunError::Neuroglancer { output: output.display().to_string(), reason }
}

/// Refuses bad `--format neuroglancer` settings before anything is read or written.
fn check_neuroglancer(job: &Job) -> Result<(), RunError> {
    let output = job.output.as_deref().unwrap_or(Path::new("(none)"));
    let ng = &job.neuroglancer;
    if job.output.is_none() {
        return Err(neuroglancer_error(output, "give the source's folder with -o".into()));
    }
    if ng.bits != 10 && ng.bits != 16 {
        return Err(neuroglancer_error(output, format!("--quantization-bits must be 10 or 16, not {}", ng.bits)));
    }
    if ng.lods.is_some_and(|l| !(1..=16).contains(&l)) {
        return Err(neuroglancer_error(output, format!("--lods must be 1 to 16, not {}", ng.lods.unwrap_or(0))));
    }
    if ng.chunk < 2 {
        return Err(neuroglancer_error(output, format!("--chunk must be 2 cells or more, not {}", ng.chunk)));
    }
    Ok(())
}

/// `--format neuroglancer`: the map's multi-resolution mesh source in `dir`, block by block.
fn run_neuroglancer(job: &Job, volume: &LabelVolume, dir: &Path) -> Result<(), RunError> {
    use isolab_pipeline::neuroglancer::{self as ngp, NgConfig};
    let started = std::time::Instant::now();
    for note in &volume.notes {
        eprintln!("note: {note}");
    }
    let extractor = labels::build(&job.config)?;
    let plan = isolab_algorithms::labels::LabelBlockPlan::new(extractor.as_ref(), volume.dims, job.neuroglancer.chunk)?;
    let deepest = plan.counts.iter().map(|&c| usize::BITS - (c.max(1) - 1).leading_zeros()).max().unwrap_or(0) as usize;
    let lods = job.neuroglancer.lods.unwrap_or(deepest + 1);
    let counts = volume.values.as_slice().counts();
    let (keep, missing) = labels::selection(job.config.select.as_deref(), &counts);
    if !missing.is_empty() {
        eprintln!("note: labels {missing:?} do not occur in {}: no mesh for them", volume.name);
    }
    let config = NgConfig {
        lods,
        bits: job.neuroglancer.bits,
        sharded: job.neuroglancer.sharded,
        transform: ngp::transform_of(&volume.index_to_world),
        names: Vec::new(),
        keep_work: false,
        legacy: job.format == "neuroglancer-legacy",
    };
    let report = ngp::write_source(extractor.as_ref(), &plan, volume.values.as_slice(), keep.as_deref(), dir, &config)
        .map_err(|e| neuroglancer_error(dir, e.to_string()))?;
    let summary = serde_json::json!({ "output": dir, "lods": lods, "chunk": plan.chunk, "seconds": started.elapsed().as_secs_f64(), "written": report });
    match job.metrics.as_deref() {
        Some(path) if path.as_os_str() != "-" => write_json(path, &summary)?,
        Some(_) => println!("{}", serde_json::to_string_pretty(&summary).unwrap_or_default()),
        None => println!(
            "{} segments to {} ({} levels of detail; fragments per level {:?}, triangles per level {:?})",
            report.segments,
            dir.display(),
            lods,
            report.fragments,
            report.triangles
        ),
    }
    Ok(())
}
