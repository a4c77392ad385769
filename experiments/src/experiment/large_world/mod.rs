//! `large_world`: a terrain world of billions of samples, never held as a dense grid (issue 8,
//! "large worlds"), meshed chunk by chunk and streamed to a binary PLY file with bounded memory
//! ([`isolab_algorithms::chunks::stream_chunked`]): slabs of 32³-cell chunks along z are sampled
//! straight from the `terrain` field (the same noise, continued beyond its default domain at the
//! spacing that fits 512 samples to its height), meshed by marching cubes in parallel and welded
//! to the previous slab's top face. Reports throughput, the file's size, and the process's peak
//! resident memory during the run (Linux `VmHWM`, reset before it) against the dense grid's
//! size. The file goes to the system's temporary directory and is deleted afterwards. The world's
//! size is `ISOLAB_WORLD` (default `2048,512,2048` cells); a run at the issue's size (`8192,512,8192`,
//! about half an hour on two cores) is kept in its own data file beside the default run's, and the
//! section shows both.
//!
//! A second part streams a volume file (issue 34): a 1024³ `uint8` NRRD (1 GiB, more than an
//! in-memory run's header check lets this machine hold) meshed by
//! [`isolab_pipeline::stream::stream_volume_file`] (what `isolab extract --stream` runs), with its
//! time and peak memory, the same voxels as a zarr store (zstd, 64³ chunks) streamed the same way,
//! and a 513³ one meshed in memory (`--chunk`) and streamed, alternating, in one process, both
//! one-shot and both writing a PLY.
//!
//! The terrain samples its height field once per column and proves chunks wholly above the
//! ground, or below it and the cave floor, from their column heights and the noise bound; those
//! chunks are skipped unsampled ([`isolab_algorithms::field::Field::block_side`]).

mod reading;

use super::context::{Context, Experiment, ExperimentError};
use crate::figures::plot::{self, BarChart, BarSeries};
use crate::figures::series_color;
use crate::report::{markdown_table, Spread};
use isolab_algorithms::chunks::stream_chunked;
use isolab_algorithms::{extractors, fields, Grid};
use isolab_io::PlyStream;
use reading::reading;
use serde::{Deserialize, Serialize};
use std::time::Instant;

/// The experiment.
pub struct LargeWorld;

const NAME: &str = "large_world";
/// The data file of a run at [`TARGET_WORLD_CELLS`].
const ISSUE_DATA: &str = "large_world_issue";
const CHUNK: usize = 32;
const DEFAULT_DIMS: [usize; 3] = [2049, 513, 2049];
/// The issue's example world, cells (samples are one more a side).
const TARGET_WORLD_CELLS: [usize; 3] = [8192, 512, 8192];

#[derive(Clone, Debug, Serialize, Deserialize)]
struct Data {
    dims: [usize; 3],
    chunk: usize,
    algorithm: String,
    samples: u64,
    dense_gib: f64,
    machine_gib: Option<f64>,
    seconds: f64,
    samples_per_second: f64,
    triangles_per_second: f64,
    vertices: u64,
    triangles: u64,
    welded: u64,
    chunks: [usize; 3],
    meshed: usize,
    empty: usize,
    full: usize,
    /// Empty or full chunks proven so by the field and skipped unsampled (absent in older runs).
    #[serde(default)]
    proven: Option<usize>,
    file_gib: f64,
    rss_before_mib: Option<f64>,
    peak_rss_mib: Option<f64>,
    peak_reset: bool,
    peak_keys: usize,
    peak_slab_mib: f64,
}

/// `ISOLAB_WORLD=X,Y,Z` cells (multiples of 32), else the default.
fn world_dims() -> Result<[usize; 3], ExperimentError> {
    let Ok(text) = std::env::var("ISOLAB_WORLD") else { return Ok(DEFAULT_DIMS) };
    let cells: Vec<usize> = text.split(',').map(|s| s.trim().parse::<usize>()).collect::<Result<_, _>>().map_err(|_| {
        ExperimentError::Setting(format!("ISOLAB_WORLD='{text}': give three cell counts X,Y,Z, multiples of {CHUNK}"))
    })?;
    match cells.as_slice() {
        [x, y, z] if [x, y, z].iter().all(|&&c| c >= CHUNK && c % CHUNK == 0) => Ok([x + 1, y + 1, z + 1]),
        _ => Err(ExperimentError::Setting(format!("ISOLAB_WORLD='{text}': give three cell counts, multiples of {CHUNK}"))),
    }
}

fn machine_gib() -> Option<f64> {
    let info = std::fs::read_to_string("/proc/meminfo").ok()?;
    let kib: f64 = info.lines().find(|l| l.starts_with("MemTotal:"))?.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib / (1024.0 * 1024.0))
}

impl Experiment for LargeWorld {
    fn name(&self) -> &'static str {
        NAME
    }

    fn question(&self) -> &'static str {
        "Can a world of billions of samples, or a volume file or zarr store larger than memory, be meshed block by block, at what throughput and memory?"
    }

    fn run(&self, ctx: &Context) -> Result<(), ExperimentError> {
        let dims = world_dims()?;
        let field = fields::builtin("terrain", Default::default())?;
        let domain = field.domain();
        let spacing = (domain.max.y - domain.min.y) / (dims[1] - 1) as f32;
        let grid = Grid { origin: domain.min, spacing, dims };
        let mc =
            extractors::by_name("marching-cubes").ok_or_else(|| ExperimentError::Missing("extractor marching-cubes".into()))?;
        let path = std::env::temp_dir().join(format!("isolab-large-world-{}.ply", std::process::id()));
        let slabs = (dims[2] - 1) / CHUNK;
        let bar = ctx.bar(NAME, slabs as u64);
        let rss_before_mib = crate::memory::rss_mib();
        let peak_reset = crate::memory::reset_peak_rss();
        let start = Instant::now();
        let mut sink = PlyStream::create(&path)?;
        let stats = stream_chunked(mc.as_ref(), field.as_ref(), grid, 0.0, CHUNK, &mut sink, |_, _| bar.inc(1))
            .map_err(|e| ExperimentError::Failed { what: "streaming the world".into(), reason: e.to_string() })?;
        let file_bytes = sink.finish()?;
        let seconds = start.elapsed().as_secs_f64();
        let peak_rss_mib = crate::memory::peak_rss_mib();
        bar.finish();
        let _ = std::fs::remove_file(&path);
        let samples = dims.iter().map(|&d| d as u64).product::<u64>();
        let data = Data {
            dims,
            chunk: CHUNK,
            algorithm: mc.name().into(),
            samples,
            dense_gib: samples as f64 * 4.0 / (1u64 << 30) as f64,
            machine_gib: machine_gib(),
            seconds,
            samples_per_second: samples as f64 / seconds,
            triangles_per_second: stats.triangles as f64 / seconds,
            vertices: stats.vertices,
            triangles: stats.triangles,
            welded: stats.welded,
            chunks: stats.chunks,
            meshed: stats.meshed,
            empty: stats.empty,
            full: stats.full,
            proven: Some(stats.proven),
            file_gib: file_bytes as f64 / (1u64 << 30) as f64,
            rss_before_mib,
            peak_rss_mib,
            peak_reset,
            peak_keys: stats.peak_keys,
            peak_slab_mib: stats.peak_slab_bytes as f64 / (1u64 << 20) as f64,
        };
        let is_issue_world = TARGET_WORLD_CELLS.iter().zip(&dims).all(|(c, d)| c + 1 == *d);
        ctx.write_data(if is_issue_world { ISSUE_DATA } else { NAME }, &data)?;
        run_volume(ctx)
    }

    fn section(&self, ctx: &Context) -> Result<String, ExperimentError> {
        let d: Data = ctx.read_data(NAME)?;
        let issue: Option<Data> = ctx.data_path(ISSUE_DATA).exists().then(|| ctx.read_data(ISSUE_DATA)).transpose()?;
        let runs: Vec<&Data> = std::iter::once(&d).chain(issue.as_ref()).collect();
        let mut md = String::from("## Larger than memory on one machine: a world of billions of samples and volumes streamed block by block (`large_world`)\n\n");
        md.push_str(&format!(
            "The `terrain` field continued over a world of samples, meshed by {} in {}³-cell chunks, one slab of chunks along \
             z at a time: each chunk samples the field itself, slabs are meshed in parallel, welded to the previous slab's top \
             face and streamed to a binary PLY in the temporary directory (deleted after the run). The terrain samples its \
             height field once per column, and chunks it proves wholly above the ground, or below the ground and the cave \
             floor, from their columns' heights and the noise's bound are skipped unsampled (`Field::block_side`; the \
             streamed mesh equals the sampled volume's, tested). Peak memory is the process's resident peak during the run \
             (`VmHWM`), which includes the report process's own baseline{}.\n\n",
            d.algorithm,
            d.chunk,
            d.machine_gib.map_or(String::new(), |m| format!("; this machine has {m:.1} GiB")),
        ));
        let volume: Option<VolumeData> = ctx.data_path(VOLUME_DATA).exists().then(|| ctx.read_data(VOLUME_DATA)).transpose()?;
        md.push_str(&reading(&runs, volume.as_ref()));
        md.push_str(&super::context::default_options(&[d.algorithm.as_str()]));
        let headers: Vec<String> = std::iter::once("measure".to_owned())
            .chain(runs.iter().map(|r| format!("{}×{}×{} samples", r.dims[0], r.dims[1], r.dims[2])))
            .collect();
        let row = |label: &str, cell: &dyn Fn(&Data) -> String| -> Vec<String> {
            std::iter::once(label.to_owned()).chain(runs.iter().map(|r| cell(r))).collect()
        };
        let rows = vec![
            row("samples", &|r| format!("{:.1} G ({:.1} GiB as a dense `f32` grid)", r.samples as f64 / 1e9, r.dense_gib)),
            row("wall time", &|r| format!("{:.0} s", r.seconds)),
            row("throughput", &|r| {
                format!("{:.1} M samples/s, {:.2} M triangles/s", r.samples_per_second / 1e6, r.triangles_per_second / 1e6)
            }),
            row("output", &|r| format!("{} vertices, {} triangles, {:.2} GiB PLY", r.vertices, r.triangles, r.file_gib)),
            row("chunks", &|r| {
                format!(
                    "{}×{}×{}: {} meshed, {} empty, {} full",
                    r.chunks[0], r.chunks[1], r.chunks[2], r.meshed, r.empty, r.full
                )
            }),
            row("of those, skipped unsampled", &|r| r.proven.map_or("not counted in this run".into(), |p| p.to_string())),
            row("vertices welded at seams", &|r| r.welded.to_string()),
            row("peak resident memory", &|r| {
                let peak = r.peak_rss_mib.map_or("not reported by the OS".into(), |m| {
                    format!("{m:.0} MiB ({:.2} % of the dense grid)", 100.0 * m / (r.dense_gib * 1024.0))
                });
                let reset = if r.peak_reset { "" } else { ", not resettable here: the process's peak so far" };
                let before = r.rss_before_mib.map_or(String::new(), |m| format!("; {m:.0} MiB before the run"));
                format!("{peak}{reset}{before}")
            }),
            row("most seam keys held", &|r| format!("{} (one slab's top face)", r.peak_keys)),
            row("most chunk-mesh memory held", &|r| format!("{:.0} MiB (one slab)", r.peak_slab_mib)),
        ];
        md.push_str(&markdown_table(&headers.iter().map(String::as_str).collect::<Vec<_>>(), &rows));
        md.push_str(&memory_figure(ctx, &runs)?);
        md.push_str(
            "\nThe run holds one slab of chunks at a time (the world's x and y extent, not its z extent), so its memory is \
             bounded by a slab by design; the peak resident memory in the table is what it held. How the time splits between \
             sampling the noise field and meshing is not measured here.",
        );
        if issue.is_none() {
            md.push_str(&format!(
                " `ISOLAB_WORLD={},{},{} cargo run --release -p isolab-experiments --bin large_world` runs the size a streamed \
                 world is meant for and adds it to this table.",
                TARGET_WORLD_CELLS[0], TARGET_WORLD_CELLS[1], TARGET_WORLD_CELLS[2],
            ));
        } else {
            md.push_str(&format!(
                " The larger world is the size a streamed world is meant for, run with `ISOLAB_WORLD={},{},{} cargo run --release -p \
                 isolab-experiments --bin large_world` (the report's main job runs the default size only).",
                TARGET_WORLD_CELLS[0], TARGET_WORLD_CELLS[1], TARGET_WORLD_CELLS[2],
            ));
        }
        md.push('\n');
        md.push_str(&volume_section(ctx)?);
        Ok(md)
    }
}

/// The data file of the streamed volume file.
const VOLUME_DATA: &str = "large_world_volume";
/// The streamed volume: 1024³ one-byte voxels (1 GiB), the case a native grid refuses.
const VOLUME_SIDE: usize = 1024;
/// The volume meshed both in memory and streamed, to compare like with like.
const COMPARE_SIDE: usize = 513;
/// Alternating runs of each in the comparison.
const COMPARE_RUNS: usize = 3;
/// Blocks of the streamed runs, and chunks of the in-memory one.
const VOLUME_CHUNK: usize = 64;
/// Voxel size of the volume files.
const VOXEL_SPACING: f32 = 0.5;
/// zstd's level for the zarr store (zarr-python's default, 0, is zstd's default level 3).
const ZARR_ZSTD_LEVEL: i32 = 3;
/// The iso-value of the comparison (the streamed 1024³ run takes Otsu's, as a user's would).
const COMPARE_ISO: f32 = 100.0;

/// One streamed run of a volume file (`isolab extract --stream`), in this process.
#[derive(Clone, Debug, Serialize, Deserialize)]
struct StreamedRun {
    seconds: f64,
    threshold_seconds: f64,
    peak_rss_mib: Option<f64>,
    peak_reset: bool,
    vertices: u64,
    triangles: u64,
    output_mib: f64,
    iso: f32,
    iso_from: Option<String>,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
struct VolumeData {
    side: usize,
    file_gib: f64,
    /// What the in-memory run's header check asks for this volume, MiB.
    in_memory_need_mib: u64,
    available_mib: Option<u64>,
    chunk: usize,
    algorithm: String,
    streamed: StreamedRun,
    /// The same volume as a zarr store (zstd, [`VOLUME_CHUNK`]³ chunks), streamed; its bytes on
    /// disk.
    #[serde(default)]
    zarr: Option<(StreamedRun, u64)>,
    compare_side: usize,
    compare_iso: f32,
    memory_seconds: Spread,
    memory_peak_mib: Spread,
    stream_seconds: Spread,
    stream_peak_mib: Spread,
    /// Triangles of the in-memory and streamed meshes of the compared volume.
    compare_triangles: [usize; 2],
}

/// The z-slices of a `side`³ rippled ball, brighter than its background, one `side * side`
/// slice of `uint8` at a time (x fastest).
fn for_each_volume_slice(side: usize, mut each: impl FnMut(&[u8]) -> Result<(), ExperimentError>) -> Result<(), ExperimentError> {
    let axis: Vec<f32> = (0..side).map(|i| i as f32 / side as f32 - 0.5).collect();
    let (wx, wy): (Vec<f32>, Vec<f32>) = axis.iter().map(|&c| ((40.0 * c).sin(), (30.0 * c).sin())).unzip();
    let mut slice = vec![0u8; side * side];
    for &z in &axis {
        for (j, &y) in axis.iter().enumerate() {
            for (i, &x) in axis.iter().enumerate() {
                let r = (x * x + y * y + z * z).sqrt();
                slice[j * side + i] = (128.0 + 300.0 * (0.35 - r) + 20.0 * wx[i] * wy[j]).clamp(0.0, 255.0) as u8;
            }
        }
        each(&slice)?;
    }
    Ok(())
}

/// A uint8 NRRD of the rippled ball of `side`³ voxels: its size in bytes.
fn write_volume_file(path: &std::path::Path, side: usize) -> Result<u64, ExperimentError> {
    use std::io::Write;
    let err = |source| isolab_io::IoError::Write { path: path.into(), source };
    let mut f = std::io::BufWriter::new(std::fs::File::create(path).map_err(err)?);
    let (dimension, h) = (3, VOXEL_SPACING);
    write!(
        f,
        "NRRD0004\ntype: uint8\ndimension: {dimension}\nsizes: {side} {side} {side}\nspacings: {h} {h} {h}\nencoding: raw\n\n"
    )
    .map_err(err)?;
    for_each_volume_slice(side, |slice| f.write_all(slice).map_err(|e| err(e).into()))?;
    f.flush().map_err(err)?;
    Ok(std::fs::metadata(path).map_err(err)?.len())
}

/// The same rippled ball as a zarr v3 array (plain: unit spacing) in [`VOLUME_CHUNK`]³ chunks,
/// zstd-compressed (zarr-python's default codec), written a layer of chunks at a time: its size
/// on disk in bytes.
fn write_zarr_store(path: &std::path::Path, side: usize) -> Result<u64, ExperimentError> {
    use zarrs::array::{codec::ZstdCodec, ArrayBuilder, DataType};
    let fail = |e: &dyn std::fmt::Display| ExperimentError::Failed {
        what: format!("writing {}", path.display()),
        reason: e.to_string(),
    };
    let store = std::sync::Arc::new(zarrs::filesystem::FilesystemStore::new(path).map_err(|e| fail(&e))?);
    let (n, c) = (side as u64, VOLUME_CHUNK as u64);
    let array = ArrayBuilder::new(vec![n, n, n], vec![c, c, c], DataType::UInt8, 0u8)
        .bytes_to_bytes_codecs(vec![std::sync::Arc::new(ZstdCodec::new(ZARR_ZSTD_LEVEL, false))])
        .build(store, "/")
        .map_err(|e| fail(&e))?;
    array.store_metadata().map_err(|e| fail(&e))?;
    let mut layer = Vec::with_capacity(side * side * VOLUME_CHUNK);
    let mut z = 0u64;
    for_each_volume_slice(side, |slice| {
        layer.extend_from_slice(slice);
        if layer.len() == side * side * VOLUME_CHUNK || z + (layer.len() / (side * side)) as u64 == n {
            let count = (layer.len() / (side * side)) as u64;
            let subset = zarrs::array_subset::ArraySubset::new_with_ranges(&[z..z + count, 0..n, 0..n]);
            array.store_array_subset_elements::<u8>(&subset, &layer).map_err(|e| fail(&e))?;
            z += count;
            layer.clear();
        }
        Ok(())
    })?;
    Ok(dir_bytes(path))
}

/// Bytes of the files under `path`.
fn dir_bytes(path: &std::path::Path) -> u64 {
    std::fs::read_dir(path)
        .into_iter()
        .flatten()
        .flatten()
        .map(|e| match e.file_type() {
            Ok(t) if t.is_dir() => dir_bytes(&e.path()),
            _ => e.metadata().map_or(0, |m| m.len()),
        })
        .sum()
}

fn volume_config(path: &std::path::Path, iso: Option<f32>) -> isolab_pipeline::RunConfig {
    let mut config = isolab_pipeline::RunConfig::new("marching-cubes", &path.to_string_lossy(), 64);
    config.iso = iso;
    config.chunk = Some(VOLUME_CHUNK);
    config.measure = isolab_pipeline::Measure::Counts;
    config
}

/// `path` streamed into `out`, with the peak resident memory of the run alone where the OS lets
/// it be reset.
fn streamed_run(path: &std::path::Path, out: &std::path::Path, iso: Option<f32>) -> Result<StreamedRun, ExperimentError> {
    let peak_reset = crate::memory::reset_peak_rss();
    let start = Instant::now();
    let report = isolab_pipeline::stream::stream_volume_file(&volume_config(path, iso), out, &mut |_, _| {})
        .map_err(|e| ExperimentError::Failed { what: format!("streaming {}", path.display()), reason: e.to_string() })?;
    Ok(StreamedRun {
        seconds: start.elapsed().as_secs_f64(),
        threshold_seconds: report.times_ms.threshold / 1e3,
        peak_rss_mib: crate::memory::peak_rss_mib(),
        peak_reset,
        vertices: report.vertices,
        triangles: report.triangles,
        output_mib: report.output_bytes as f64 / (1u64 << 20) as f64,
        iso: report.iso,
        iso_from: report.iso_from.map(str::to_owned),
    })
}

/// `path` read whole and meshed in chunks in memory, written to `out`: seconds, peak MiB,
/// triangles.
fn in_memory_run(path: &std::path::Path, out: &std::path::Path) -> Result<(f64, Option<f64>, usize), ExperimentError> {
    crate::memory::reset_peak_rss();
    let start = Instant::now();
    let outcome = isolab_pipeline::run(&volume_config(path, Some(COMPARE_ISO)))
        .map_err(|e| ExperimentError::Failed { what: format!("meshing {} in memory", path.display()), reason: e.to_string() })?;
    isolab_io::write_mesh_with(out, &outcome.extraction.surface, isolab_io::MeshExtras::default())?;
    Ok((start.elapsed().as_secs_f64(), crate::memory::peak_rss_mib(), outcome.extraction.surface.triangles.len()))
}

/// A directory in the system's temporary one, removed with what it holds when dropped.
struct ScratchDir(std::path::PathBuf);

impl ScratchDir {
    fn new() -> Result<Self, ExperimentError> {
        let path = std::env::temp_dir().join(format!("isolab-large-volume-{}", std::process::id()));
        std::fs::create_dir_all(&path).map_err(|source| isolab_io::IoError::Write { path: path.clone(), source })?;
        Ok(ScratchDir(path))
    }
}

impl Drop for ScratchDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// The volume-file runs: a 1 GiB volume streamed, and a smaller one meshed both ways, alternating.
fn run_volume(ctx: &Context) -> Result<(), ExperimentError> {
    let dir = ScratchDir::new()?;
    let (big, small, store) = (dir.0.join("volume.nrrd"), dir.0.join("compare.nrrd"), dir.0.join("volume.zarr"));
    let out = dir.0.join("mesh.ply");
    let bar = ctx.bar("large_world volume", 3 + 2 * COMPARE_RUNS as u64);
    let file_bytes = write_volume_file(&big, VOLUME_SIDE)?;
    let streamed = streamed_run(&big, &out, None)?;
    std::fs::remove_file(&big).map_err(|source| isolab_io::IoError::Write { path: big.clone(), source })?;
    bar.inc(1);
    let store_bytes = write_zarr_store(&store, VOLUME_SIDE)?;
    let zarr = streamed_run(&store, &out, None)?;
    std::fs::remove_dir_all(&store).map_err(|source| isolab_io::IoError::Write { path: store.clone(), source })?;
    bar.inc(1);
    write_volume_file(&small, COMPARE_SIDE)?;
    bar.inc(1);
    let (mut memory_seconds, mut memory_peak, mut stream_seconds, mut stream_peak) = (vec![], vec![], vec![], vec![]);
    let mut compare_triangles = [0, 0];
    for _ in 0..COMPARE_RUNS {
        let (seconds, peak, triangles) = in_memory_run(&small, &out)?;
        memory_seconds.push(seconds);
        memory_peak.extend(peak);
        compare_triangles[0] = triangles;
        bar.inc(1);
        let run = streamed_run(&small, &out, Some(COMPARE_ISO))?;
        stream_seconds.push(run.seconds);
        stream_peak.extend(run.peak_rss_mib);
        compare_triangles[1] = run.triangles as usize;
        bar.inc(1);
    }
    bar.finish();
    let data = VolumeData {
        side: VOLUME_SIDE,
        file_gib: file_bytes as f64 / (1u64 << 30) as f64,
        in_memory_need_mib: isolab_pipeline::volume_file_need([VOLUME_SIDE; 3], 1) >> 20,
        available_mib: isolab_pipeline::available_memory().map(|b| b >> 20),
        chunk: VOLUME_CHUNK,
        algorithm: "marching-cubes".into(),
        streamed,
        zarr: Some((zarr, store_bytes)),
        compare_side: COMPARE_SIDE,
        compare_iso: COMPARE_ISO,
        memory_seconds: Spread::of(memory_seconds),
        memory_peak_mib: Spread::of(memory_peak),
        stream_seconds: Spread::of(stream_seconds),
        stream_peak_mib: Spread::of(stream_peak),
        compare_triangles,
    };
    ctx.write_data(VOLUME_DATA, &data)
}

/// The section's part on volume files.
fn volume_section(ctx: &Context) -> Result<String, ExperimentError> {
    if !ctx.data_path(VOLUME_DATA).exists() {
        return Ok(String::new());
    }
    let d: VolumeData = ctx.read_data(VOLUME_DATA)?;
    let s = &d.streamed;
    let mut md = format!(
        "\n### A volume file larger than memory, streamed block by block (`isolab extract --stream`)\n\n\
         A {side}³ `uint8` NRRD ({gib:.2} GiB, a rippled ball) written to the temporary directory, meshed by {alg} with \
         `--stream`: read z-slice by z-slice, meshed in {c}³-cell blocks one layer at a time, welded by lattice keys and \
         written to a PLY as it goes, in this process (`stream_volume_file`, what the CLI runs). An in-memory run of it \
         would ask for {need} MiB by the header check{avail}; the CLI streams such a volume on its own when the output is \
         a PLY. No iso-value was given: {iso} ({from}), from two extra passes over the file.\n\n",
        side = d.side,
        gib = d.file_gib,
        alg = d.algorithm,
        c = d.chunk,
        need = d.in_memory_need_mib,
        avail = d.available_mib.map_or(String::new(), |a| format!(" ({a} MiB were available when it ran)")),
        iso = s.iso,
        from = s.iso_from.as_deref().unwrap_or("given"),
    );
    let peak = |p: Option<f64>, reset: bool| {
        p.map_or("not reported by the OS".into(), |m| {
            format!("{m:.0} MiB{}", if reset { "" } else { " (the process's peak so far: not resettable here)" })
        })
    };
    let runs: Vec<(&StreamedRun, String)> = std::iter::once((s, format!("{:.2} GiB raw", d.file_gib)))
        .chain(d.zarr.as_ref().map(|(z, bytes)| (z, format!("{:.0} MiB in chunk files", *bytes as f64 / (1u64 << 20) as f64))))
        .collect();
    let row = |name: &str, cell: &dyn Fn(&StreamedRun, &str) -> String| {
        std::iter::once(name.to_owned()).chain(runs.iter().map(|(r, disk)| cell(r, disk))).collect::<Vec<String>>()
    };
    let rows = vec![
        row("on disk", &|_, disk| disk.to_owned()),
        row("wall time", &|r, _| format!("{:.1} s, of which {:.1} s the threshold passes", r.seconds, r.threshold_seconds)),
        row("peak resident memory", &|r, _| peak(r.peak_rss_mib, r.peak_reset)),
        row("output", &|r, _| format!("{} vertices, {} triangles, {:.0} MiB PLY", r.vertices, r.triangles, r.output_mib)),
    ];
    let mut header = vec!["measure".to_owned(), format!("{}³ NRRD streamed", d.side)];
    if let Some((z, _)) = &d.zarr {
        header.push(format!("{}³ zarr streamed", d.side));
        let same = z.vertices == s.vertices && z.triangles == s.triangles && z.iso == s.iso;
        md.push_str(&format!(
            "The same voxels as a zarr v3 store ({c}³ chunks, zstd level {level}, zarr-python's default codec; a plain \
             array, so unit spacing), streamed the same way (`-f volume.zarr --stream`: a layer of storage chunks read \
             and decoded at a time): {verdict}.\n\n",
            c = d.chunk,
            level = ZARR_ZSTD_LEVEL,
            verdict = if same {
                "the same iso-value, vertex and triangle counts as the NRRD".to_owned()
            } else {
                format!("iso-value {}, {} vertices, {} triangles: not the NRRD's", z.iso, z.vertices, z.triangles)
            },
        ));
    }
    let header: Vec<&str> = header.iter().map(String::as_str).collect();
    md.push_str(&markdown_table(&header, &rows));
    let spread = |x: &Spread, unit: &str, digits: usize| {
        format!("{:.*} {unit} ({:.*}-{:.*})", digits, x.median, digits, x.min, digits, x.max)
    };
    md.push_str(&format!(
        "\nLike with like, in one process, one-shot, alternating ({n} runs each, median and range): a {side}³ volume \
         of the same kind at iso-value {iso}, read whole and meshed in {c}³ chunks in memory (`--chunk`), then \
         streamed (`--stream`); both write a PLY. Peak memory is each run's own where the OS lets it be reset.\n\n",
        n = d.memory_seconds.runs.len(),
        side = d.compare_side,
        iso = d.compare_iso,
        c = d.chunk,
    ));
    let rows = vec![
        vec![
            "in memory (`--chunk`)".into(),
            spread(&d.memory_seconds, "s", 2),
            spread(&d.memory_peak_mib, "MiB", 0),
            d.compare_triangles[0].to_string(),
        ],
        vec![
            "streamed (`--stream`)".into(),
            spread(&d.stream_seconds, "s", 2),
            spread(&d.stream_peak_mib, "MiB", 0),
            d.compare_triangles[1].to_string(),
        ],
    ];
    md.push_str(&markdown_table(&["run", "wall time", "peak resident memory", "triangles"], &rows));
    md.push_str(&format!(
        "\nStreamed against in memory: {:.2}x the time, {:.2}x the peak memory (medians).\n",
        d.stream_seconds.median / d.memory_seconds.median,
        d.stream_peak_mib.median / d.memory_peak_mib.median
    ));
    Ok(md)
}

/// The page's figure, drawn at assembly: each run's peak resident memory beside the dense grid
/// it meshed (what an in-memory run would hold).
fn memory_figure(ctx: &Context, runs: &[&Data]) -> Result<String, ExperimentError> {
    let with: Vec<&&Data> = runs.iter().filter(|r| r.peak_rss_mib.is_some()).collect();
    if with.is_empty() {
        return Ok(String::new());
    }
    let chart = BarChart {
        title: "Peak memory against the grid it meshed".into(),
        y_label: "GiB".into(),
        categories: with.iter().map(|r| format!("{}×{}×{}", r.dims[0], r.dims[1], r.dims[2])).collect(),
        series: vec![
            BarSeries {
                label: "dense f32 grid".into(),
                color: series_color(0),
                values: with.iter().map(|r| r.dense_gib).collect(),
            },
            BarSeries {
                label: "peak resident, streamed".into(),
                color: series_color(1),
                values: with.iter().map(|r| r.peak_rss_mib.unwrap_or(f64::NAN) / 1024.0).collect(),
            },
        ],
    };
    let stem = ctx.figure_dir(NAME)?.join("memory");
    plot::bars(&stem, &chart).map_err(ExperimentError::Figure)?;
    Ok(format!("\n![peak memory against the grid]({})\n", ctx.link(&stem.with_extension("png"))))
}
