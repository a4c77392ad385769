//! `large_world`: a terrain world of billions of samples, never held as a dense grid (issue 8,
//! "large worlds"), meshed chunk by chunk and streamed to a binary PLY file with bounded memory
//! ([`isolab_algorithms::chunks::stream_chunked`]): slabs of 32³-cell chunks along z are sampled
//! straight from the `terrain` field (the same noise, continued beyond its default domain at the
//! spacing that fits 512 samples to its height), meshed by marching cubes in parallel and welded
//! to the previous slab's top face. Reports throughput, the file's size, and the process's peak
//! resident memory during the run (Linux `VmHWM`, reset before it) against the dense grid's
//! size. The file goes to the system's temporary directory and is deleted afterwards. The world's
//! size is `ISOLAB_WORLD` (default `2048,512,2048` cells).

use super::context::{Context, Experiment, ExperimentError};
use crate::io::PlyStream;
use crate::report::markdown_table;
use isolab_algorithms::chunks::stream_chunked;
use isolab_algorithms::{extractors, fields, Grid};
use serde::{Deserialize, Serialize};
use std::time::Instant;

/// The experiment.
pub struct LargeWorld;

const NAME: &str = "large_world";
const CHUNK: usize = 32;
const DEFAULT_DIMS: [usize; 3] = [2049, 513, 2049];
/// The issue's example world, cells (samples are one more a side).
const ISSUE_WORLD_CELLS: [usize; 3] = [8192, 512, 8192];

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
        ExperimentError::Figure(format!("ISOLAB_WORLD='{text}': give three cell counts X,Y,Z, multiples of {CHUNK}"))
    })?;
    match cells.as_slice() {
        [x, y, z] if [x, y, z].iter().all(|&&c| c >= CHUNK && c % CHUNK == 0) => Ok([x + 1, y + 1, z + 1]),
        _ => Err(ExperimentError::Figure(format!("ISOLAB_WORLD='{text}': give three cell counts, multiples of {CHUNK}"))),
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
        "Can a world of billions of samples be meshed chunk by chunk, at what throughput and memory?"
    }

    fn run(&self, ctx: &Context) -> Result<(), ExperimentError> {
        let dims = world_dims()?;
        let field = fields::builtin("terrain", Default::default())?;
        let domain = field.domain();
        let spacing = (domain.max.y - domain.min.y) / (dims[1] - 1) as f32;
        let grid = Grid { origin: domain.min, spacing, dims };
        let mc = extractors::by_name("marching-cubes").ok_or_else(|| ExperimentError::Figure("no marching-cubes".into()))?;
        let path = std::env::temp_dir().join(format!("isolab-large-world-{}.ply", std::process::id()));
        let slabs = (dims[2] - 1) / CHUNK;
        let bar = ctx.bar(NAME, slabs as u64);
        let rss_before_mib = crate::memory::rss_mib();
        let peak_reset = crate::memory::reset_peak_rss();
        let start = Instant::now();
        let mut sink = PlyStream::create(&path)?;
        let stats = stream_chunked(mc.as_ref(), field.as_ref(), grid, 0.0, CHUNK, &mut sink, |_, _| bar.inc(1))
            .map_err(|e| ExperimentError::Figure(format!("streaming the world: {e}")))?;
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
            file_gib: file_bytes as f64 / (1u64 << 30) as f64,
            rss_before_mib,
            peak_rss_mib,
            peak_reset,
            peak_keys: stats.peak_keys,
            peak_slab_mib: stats.peak_slab_bytes as f64 / (1u64 << 20) as f64,
        };
        ctx.write_data(NAME, &data)
    }

    fn section(&self, ctx: &Context) -> Result<String, ExperimentError> {
        let d: Data = ctx.read_data(NAME)?;
        let mut md = String::from("## A world of billions of samples, streamed chunk by chunk (`large_world`)\n\n");
        md.push_str(&format!(
            "The `terrain` field continued over {}×{}×{} samples ({:.1} G samples; as a dense `f32` grid {:.1} GiB{}), meshed by {} in \
             {}³-cell chunks, one slab of chunks along z at a time: each chunk samples the field itself, slabs are meshed in \
             parallel, welded to the previous slab's top face and streamed to a binary PLY in the temporary directory (deleted \
             after the run). Peak memory is the process's resident peak during the run (`VmHWM`{}), which includes the report \
             process's own baseline ({}).\n\n",
            d.dims[0],
            d.dims[1],
            d.dims[2],
            d.samples as f64 / 1e9,
            d.dense_gib,
            d.machine_gib.map_or(String::new(), |m| format!(", this machine has {m:.1} GiB")),
            d.algorithm,
            d.chunk,
            if d.peak_reset { ", reset before the run" } else { ", not resettable here: the process's peak so far" },
            d.rss_before_mib.map_or("unknown".into(), |m| format!("{m:.0} MiB before the run")),
        ));
        let rows = vec![
            vec!["wall time".into(), format!("{:.0} s", d.seconds)],
            vec![
                "throughput".into(),
                format!("{:.1} M samples/s, {:.2} M triangles/s", d.samples_per_second / 1e6, d.triangles_per_second / 1e6),
            ],
            vec!["output".into(), format!("{} vertices, {} triangles, {:.2} GiB PLY", d.vertices, d.triangles, d.file_gib)],
            vec![
                "chunks".into(),
                format!(
                    "{}×{}×{}: {} meshed, {} empty, {} full (skipped from their min/max after sampling)",
                    d.chunks[0], d.chunks[1], d.chunks[2], d.meshed, d.empty, d.full
                ),
            ],
            vec!["vertices welded at seams".into(), d.welded.to_string()],
            vec![
                "peak resident memory".into(),
                d.peak_rss_mib.map_or("not reported by the OS".into(), |m| {
                    format!("{m:.0} MiB ({:.1} % of the dense grid)", 100.0 * m / (d.dense_gib * 1024.0))
                }),
            ],
            vec!["most seam keys held".into(), format!("{} (one slab's top face)", d.peak_keys)],
            vec!["most chunk-mesh memory held".into(), format!("{:.0} MiB (one slab)", d.peak_slab_mib)],
        ];
        md.push_str(&markdown_table(&["measure", "value"], &rows));
        let [x, y, z] = ISSUE_WORLD_CELLS.map(|c| (c + 1) as f64);
        let issue_samples = x * y * z;
        let times = issue_samples / d.samples.max(1) as f64;
        let slab = (x * y) / (d.dims[0] * d.dims[1]).max(1) as f64;
        md.push_str(&format!(
            "\nSampling the noise field dominates the time (about ten noise evaluations per sample; most chunks turn out empty or \
             full only after sampling). Memory grows with one slab (the world's x and y extent), not with its z extent. \
             `ISOLAB_WORLD={},{},{} cargo run --release -p isolab-experiments --bin large_world` runs the issue's example \
             size ({:.0} GiB dense; {times:.0} times these samples, about {times:.0} times the time at this throughput, {slab:.0} \
             times the slab memory).\n",
            ISSUE_WORLD_CELLS[0],
            ISSUE_WORLD_CELLS[1],
            ISSUE_WORLD_CELLS[2],
            issue_samples * 4.0 / f64::from(1u32 << 30),
        ));
        Ok(md)
    }
}
