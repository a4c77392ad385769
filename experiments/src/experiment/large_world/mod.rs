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

mod reading;
mod volume;

use super::context::{Context, Experiment, ExperimentError};
use crate::figures::plot::{self, BarChart, BarSeries};
use crate::figures::series_color;
use crate::report::markdown_table;
use isolab_algorithms::chunks::stream_chunked;
use isolab_algorithms::{extractors, fields, Grid};
use isolab_io::PlyStream;
use reading::reading;
use serde::{Deserialize, Serialize};
use std::time::Instant;
use volume::{run_volume, volume_section, VolumeData, VOLUME_DATA};

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
