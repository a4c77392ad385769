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
//! A second part (`volume.rs`) streams a volume file (issue 34): a 1024³ `uint8` NRRD (1 GiB, more
//! than an in-memory run's header check let this machine hold before its voxels were meshed where
//! they lie) meshed by [`isolab_pipeline::stream::stream_volume_file`] (what `isolab extract
//! --stream` runs), with its time and peak memory, then meshed whole in memory where its voxels
//! lie (issue 59), the same voxels as a zarr store (zstd, 64³ chunks) streamed the same way, and
//! a 513³ one meshed in memory (`--chunk`) and streamed, alternating, in one process, both
//! one-shot and both writing a PLY.
//!
//! The terrain samples its height field once per column and proves chunks wholly above the
//! ground, or below it and the cave floor, from their column heights and the noise bound; those
//! chunks are skipped unsampled ([`isolab_algorithms::field::Field::block_side`]).

mod data;
mod page;

use super::context::{Context, Experiment, ExperimentError};
use data::Data;
use isolab_algorithms::chunks::stream_chunked;
use isolab_algorithms::{extractors, fields, Grid};
use isolab_io::PlyStream;
use std::time::Instant;
use volume::{run_volume, VolumeData};

mod reading;

mod volume;

/// The experiment.
pub struct LargeWorld;

const NAME: &str = "large_world";

/// The data file of a run at [`TARGET_WORLD_CELLS`].
const ISSUE_DATA: &str = "large_world_issue";

const CHUNK: usize = 32;

const DEFAULT_DIMS: [usize; 3] = [2049, 513, 2049];

/// The issue's example world, cells (samples are one more a side).
const TARGET_WORLD_CELLS: [usize; 3] = [8192, 512, 8192];

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
        // A quick run: a 512x128x512-cell world.
        let dims = if ctx.quick { [513, 129, 513] } else { world_dims()? };
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
        page::section(ctx)
    }
}
