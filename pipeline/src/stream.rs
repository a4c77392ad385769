//! A volume file larger than memory, meshed block by block into a streamed PLY
//! (`isolab extract --stream`): the file is read z-slice by z-slice
//! ([`isolab_io::volume::slabs::VolumeSlabs`]), each layer of blocks is meshed by the chunk
//! engine with the extractor's apron and welded onto the previous layer by lattice keys
//! ([`isolab_algorithms::chunks::stream_blocks`]), and the vertices and triangles go straight to
//! disk ([`isolab_io::stream::PlyStream`], atomic). The mesh written is the one `--chunk N` makes
//! in memory (same vertices, same triangles; tested), in the same world (the file's affine, RAS
//! or LPS). Memory: about two copies of one layer of blocks, plus one layer's meshes and one face
//! of seam keys; never the volume.
//!
//! Everything that cannot stream is refused before a voxel is read: another input than a volume
//! file, a resampled grid, the BCC lattice, post-processes, materials, mesh metrics (they need the
//! whole mesh: `--metrics` gets the run's counts and times), an extractor that cannot chunk, an output that is not `.ply`, data that cannot be
//! read in slices (text encodings, interleaved channels), a file shorter than its header says, and
//! a layer of blocks larger than the memory available. With no `--iso` and no iso-value in the
//! file, Otsu's threshold is computed in two extra passes over the data (extremes, then the
//! histogram), as [`isolab_algorithms::fields::otsu_threshold`] computes it on the whole volume.

use crate::{
    available_memory, check_names, empty_mesh_warning, LatticeKind, Measure, OutputSpace, RunConfig, RunError, VolumeGrid,
    ISO_FROM_CONSTANT, ISO_FROM_GRID, ISO_FROM_OTSU,
};
use glam::Vec3;
use isolab_algorithms::chunks::{stream_blocks, BlockPlan, StreamError};
use isolab_algorithms::extractors;
use isolab_algorithms::fields::OtsuHistogram;
use isolab_io::stream::PlyStream;
use isolab_io::volume::slabs::VolumeSlabs;
use isolab_io::volume::{Inside, Space, StoredData};
use serde::Serialize;
use std::path::Path;
use std::time::Instant;

/// Cells per block side when `--chunk` is not given.
pub const DEFAULT_STREAM_CHUNK: usize = 64;

/// Slices read at a time by the threshold passes.
const THRESHOLD_SLICES: usize = 8;

/// What a streamed run did: its JSON on stdout or in `--metrics`.
#[derive(Clone, Debug, Serialize)]
pub struct StreamReport {
    /// Extractor name.
    pub algorithm: String,
    /// The volume file.
    pub input: String,
    /// Its format.
    pub format: &'static str,
    /// Its voxel type.
    pub data_type: &'static str,
    /// Samples per axis.
    pub shape: [usize; 3],
    /// The world the mesh is in (anatomical volumes only).
    pub space: Option<OutputSpace>,
    /// Iso-value, in the volume's own values.
    pub iso: f32,
    /// Where the iso-value came from when none was given.
    pub iso_from: Option<&'static str>,
    /// Which side of it is inside.
    pub inside: Inside,
    /// Cells per block side.
    pub chunk: usize,
    /// Samples each block reads beyond its chunk on every side.
    pub apron: usize,
    /// Blocks per axis.
    pub blocks: [usize; 3],
    /// Blocks meshed, and skipped because every sample was outside or inside.
    pub meshed_blocks: usize,
    /// Blocks with every sample outside.
    pub empty_blocks: usize,
    /// Blocks with every sample inside.
    pub full_blocks: usize,
    /// Vertices written.
    pub vertices: u64,
    /// Triangles written.
    pub triangles: u64,
    /// Vertices merged at block seams.
    pub welded: u64,
    /// Most seam keys held at once.
    pub peak_keys: usize,
    /// Most bytes of slices and block meshes held at once.
    pub peak_layer_bytes: usize,
    /// The estimate the memory check used.
    pub layer_estimate_bytes: u64,
    /// Bytes of the PLY written.
    pub output_bytes: u64,
    /// Stage times.
    pub times_ms: StreamTimes,
    /// The process's peak resident memory (`VmHWM`), MiB, where the OS reports it.
    pub peak_rss_mib: Option<f64>,
    /// Things to tell the user that are not warnings.
    pub notes: Vec<String>,
    /// Things the user should know (an empty mesh).
    pub warnings: Vec<String>,
}

/// Wall-clock milliseconds of a streamed run's stages.
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct StreamTimes {
    /// The two threshold passes (0 when the iso-value was given or in the file).
    pub threshold: f64,
    /// Reading, meshing and writing the blocks.
    pub meshing: f64,
    /// Writing the PLY's header and joining its parts.
    pub finishing: f64,
    /// Everything.
    pub total: f64,
}

/// Meshes the volume file `config.field` block by block into the PLY `output`, calling
/// `progress(done, total)` after each layer of blocks. Refuses, before reading any voxel, what
/// cannot stream (module doc).
pub fn stream_volume_file(
    config: &RunConfig,
    output: &Path,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<StreamReport, RunError> {
    let start = Instant::now();
    let refuse = |reason: String| RunError::Stream { path: config.field.clone(), reason };
    check_names(config)?;
    check_streamable(config, output).map_err(refuse)?;
    if let Some(iso) = config.iso.filter(|v| !v.is_finite()) {
        return Err(RunError::BadIso(iso));
    }
    let extractor = extractors::build(&config.algorithm, &config.options)?
        .ok_or_else(|| RunError::UnknownAlgorithm { name: config.algorithm.clone(), valid: extractors::names() })?;
    let path = Path::new(&config.field);
    let mut slabs = VolumeSlabs::open(path, config.volume)?;
    let header = slabs.header.clone();
    check_data_length(&slabs).map_err(refuse)?;
    let chunk = config.chunk.unwrap_or(DEFAULT_STREAM_CHUNK);
    let plan = BlockPlan::new(extractor.as_ref(), header.dims, chunk)?;
    let layer_estimate_bytes = layer_estimate(&plan);
    if let Some(available) = available_memory().filter(|&a| a < layer_estimate_bytes) {
        return Err(refuse(format!(
            "one layer of {chunk}-cell blocks of its {:?} samples needs about {} MiB, but only {} MiB of memory is \
             available; lower --chunk",
            header.dims,
            layer_estimate_bytes >> 20,
            available >> 20
        )));
    }
    let threshold_start = Instant::now();
    let (iso, iso_from) = match (config.iso, header.iso) {
        (Some(iso), _) => (iso, None),
        (None, Some(iso)) => (iso, Some(ISO_FROM_GRID)),
        (None, None) => streamed_otsu(&mut slabs)?,
    };
    let threshold_ms = threshold_start.elapsed().as_secs_f64() * 1e3;
    let inside = config.inside.unwrap_or(header.inside);
    let space = (header.space == Space::Ras).then_some(config.space);
    let to_world = match space.and_then(OutputSpace::map_from_ras) {
        Some(m) => m * header.affine,
        None => header.affine,
    };
    let mirror = to_world.matrix3.determinant() < 0.0;
    let map = |p: Vec3| to_world.transform_point3(p.as_dvec3()).as_vec3();
    let sign = if inside == Inside::Above { -1.0f32 } else { 1.0 };
    let [nx, ny, nz] = header.dims;
    let mut read = |count: usize, out: &mut Vec<f32>| -> Result<(), String> {
        let (from, z) = (out.len(), slabs.position());
        slabs.read_slices(count, out).map_err(|e| e.to_string())?;
        if let Some(i) = out[from..].iter().position(|v| !v.is_finite()) {
            return Err(format!(
                "'{}': voxel {:?} is not finite ({})",
                config.field,
                [i % nx, (i / nx) % ny, z + i / (nx * ny)],
                out[from + i]
            ));
        }
        if sign < 0.0 {
            out[from..].iter_mut().for_each(|v| *v = -*v);
        }
        Ok(())
    };
    let mut sink = PlyStream::create(output)?.with_space(space.map(OutputSpace::tag));
    let meshing_start = Instant::now();
    let stats = stream_blocks(extractor.as_ref(), &plan, sign * iso, &mut read, &map, mirror, &mut sink, progress).map_err(
        |e| match e {
            StreamError::Extract(e) => RunError::Extract(e),
            StreamError::Io(source) => isolab_io::IoError::Write { path: output.into(), source }.into(),
            StreamError::Read(reason) => refuse(reason),
        },
    )?;
    let meshing_ms = meshing_start.elapsed().as_secs_f64() * 1e3;
    let finishing_start = Instant::now();
    let output_bytes = sink.finish()?;
    let finishing_ms = finishing_start.elapsed().as_secs_f64() * 1e3;
    let mut notes = vec![format!(
        "streamed {} ({nx} x {ny} x {nz} voxels) in {}x{}x{} blocks of {chunk} cells",
        config.field, plan.counts[0], plan.counts[1], plan.counts[2]
    )];
    notes.extend(header.notes.iter().cloned());
    if let Some(from) = iso_from {
        notes.push(format!("no --iso given: {iso} ({from})"));
    }
    if config.measure != Measure::Counts {
        notes.push(format!(
            "a streamed run counts the mesh but does not measure it (that needs the whole mesh): `isolab metrics {}`",
            output.display()
        ));
    }
    Ok(StreamReport {
        algorithm: config.algorithm.clone(),
        input: config.field.clone(),
        format: header.format,
        data_type: header.data_type,
        shape: header.dims,
        space,
        iso,
        iso_from,
        inside,
        chunk,
        apron: plan.apron,
        blocks: plan.counts,
        meshed_blocks: stats.meshed,
        empty_blocks: stats.empty,
        full_blocks: stats.full,
        vertices: stats.vertices,
        triangles: stats.triangles,
        welded: stats.welded,
        peak_keys: stats.peak_keys,
        peak_layer_bytes: stats.peak_slab_bytes,
        layer_estimate_bytes,
        output_bytes,
        times_ms: StreamTimes {
            threshold: threshold_ms,
            meshing: meshing_ms,
            finishing: finishing_ms,
            total: start.elapsed().as_secs_f64() * 1e3,
        },
        peak_rss_mib: peak_rss_mib(),
        notes,
        warnings: empty_mesh_warning(&config.field, iso, inside, stats.empty == plan.len(), stats.full == plan.len())
            .into_iter()
            .collect(),
    })
}

/// Why `config` cannot stream into `output`, if it cannot (options only: no file is opened).
pub fn check_streamable(config: &RunConfig, output: &Path) -> Result<(), String> {
    if !crate::input::is_file_spec(&config.field) {
        return Err("--stream meshes volume files; a built-in field is sampled in memory (use --chunk)".into());
    }
    let mut unsupported = Vec::new();
    if config.volume_grid == VolumeGrid::Resampled {
        unsupported.push("--resolution/--dims (a streamed volume is meshed on its own voxel grid)");
    }
    if config.lattice == LatticeKind::Bcc {
        unsupported.push("--lattice bcc (its cell centres need the neighbouring slices)");
    }
    if !config.post.is_empty() {
        unsupported.push("--post (post-processes need the whole mesh)");
    }
    if config.materials {
        unsupported.push("--materials");
    }
    if config.measure == Measure::All {
        unsupported.push("--self-intersections (it needs the whole mesh; measure the PLY afterwards with `isolab metrics`)");
    }
    if !unsupported.is_empty() {
        return Err(format!("a streamed run does not take {}", unsupported.join(", ")));
    }
    if let Some(e) = extractors::build(&config.algorithm, &config.options).ok().flatten() {
        if e.chunking() == isolab_algorithms::Chunking::Unsupported {
            let chunking: Vec<&str> = extractors::registry()
                .iter()
                .filter(|e| e.chunking() != isolab_algorithms::Chunking::Unsupported)
                .map(|e| e.name())
                .collect();
            return Err(format!("'{}' cannot mesh in blocks; these can: {}", config.algorithm, chunking.join(", ")));
        }
    }
    let ply = output.extension().and_then(|e| e.to_str()).is_some_and(|e| e.eq_ignore_ascii_case("ply"));
    if !ply {
        return Err(format!("'{}': a streamed mesh is written as binary PLY (-o NAME.ply)", output.display()));
    }
    Ok(())
}

/// Refuses an uncompressed file shorter than its header says, before its data is read.
fn check_data_length(slabs: &VolumeSlabs) -> Result<(), String> {
    let Ok(StoredData::File(layout)) = &slabs.header.layout else { return Ok(()) };
    if layout.compression.is_some() {
        return Ok(());
    }
    let need = slabs.header.dims.iter().map(|&n| n as u64).product::<u64>() * layout.ty.size() as u64;
    let Ok(len) = std::fs::metadata(&layout.file).map(|m| m.len()) else { return Ok(()) };
    let have = len.saturating_sub(layout.start + layout.offset);
    if have < need {
        return Err(format!(
            "'{}' holds {have} bytes of voxel data after its header, but {:?} {} voxels need {need}",
            layout.file.display(),
            slabs.header.dims,
            slabs.header.data_type
        ));
    }
    Ok(())
}

/// Bytes one layer of blocks holds: its slices (chunk, two aprons and the shared sample) twice
/// (the window and the blocks' copies), plus as much again for the layer's meshes and keys.
pub fn layer_estimate(plan: &BlockPlan) -> u64 {
    let [nx, ny, nz] = plan.dims;
    let slices = (plan.chunk + 2 * plan.apron + 1).min(nz) as u64;
    slices * (nx * ny) as u64 * 4 * 3
}

/// Otsu's threshold of the whole volume, in two passes (extremes, histogram), then back at the
/// first slice.
fn streamed_otsu(slabs: &mut VolumeSlabs) -> Result<(f32, Option<&'static str>), RunError> {
    let nz = slabs.dims()[2];
    let mut buffer = Vec::new();
    let mut pass = |slabs: &mut VolumeSlabs, each: &mut dyn FnMut(&[f32])| -> Result<(), RunError> {
        slabs.rewind()?;
        while slabs.position() < nz {
            buffer.clear();
            slabs.read_slices(THRESHOLD_SLICES.min(nz - slabs.position()), &mut buffer)?;
            each(&buffer);
        }
        Ok(())
    };
    let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
    pass(slabs, &mut |values| {
        for &v in values {
            (lo, hi) = (lo.min(v), hi.max(v));
        }
    })?;
    let result = match OtsuHistogram::new(lo, hi) {
        Some(mut histogram) => {
            pass(slabs, &mut |values| histogram.add(values))?;
            (histogram.threshold(), Some(ISO_FROM_OTSU))
        }
        None => (lo, Some(ISO_FROM_CONSTANT)),
    };
    slabs.rewind()?;
    Ok(result)
}

/// The process's peak resident memory (`VmHWM`), MiB.
fn peak_rss_mib() -> Option<f64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    line.split_whitespace().nth(1)?.parse::<f64>().ok().map(|kib| kib / 1024.0)
}
