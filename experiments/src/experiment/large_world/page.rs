//! The page `report/large_world.md`, rendered from the data file alone.

use super::data::Data;
use super::reading::reading;
use super::volume::{volume_section, VolumeData, VOLUME_DATA};
use super::{ISSUE_DATA, NAME, TARGET_WORLD_CELLS};
use crate::experiment::context::{Context, ExperimentError};
use crate::figures::plot::{self, BarChart, BarSeries};
use crate::figures::series_color;
use crate::report::markdown_table;

/// The page, from the data file alone.
pub(super) fn section(ctx: &Context) -> Result<String, ExperimentError> {
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
    md.push_str(&crate::experiment::context::default_options(&[d.algorithm.as_str()]));
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
            format!("{}×{}×{}: {} meshed, {} empty, {} full", r.chunks[0], r.chunks[1], r.chunks[2], r.meshed, r.empty, r.full)
        }),
        row("of those, skipped unsampled", &|r| r.proven.map_or("not counted in this run".into(), |p| p.to_string())),
        row("vertices welded at seams", &|r| r.welded.to_string()),
        row("peak resident memory", &|r| {
            let peak = r.peak_rss_mib.map_or("not reported by the OS".into(), |m| {
                let phrase = super::reading::peak_phrase(m, r.rss_before_mib, r.dense_gib);
                phrase.strip_prefix("its peak resident memory ").unwrap_or(&phrase).to_owned()
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

/// The page's figure, drawn at assembly: each run's peak resident memory beside the dense grid
/// it meshed (what an in-memory run would hold).
pub(super) fn memory_figure(ctx: &Context, runs: &[&Data]) -> Result<String, ExperimentError> {
    let with: Vec<&&Data> = runs.iter().filter(|r| r.peak_rss_mib.is_some()).collect();
    if with.is_empty() {
        return Ok(String::new());
    }
    let chart = BarChart {
        title: "Peak memory against the grid it meshed".into(),
        y_label: "GiB".into(),
        y_scale: crate::figures::plot::Scale::Log,
        categories: with.iter().map(|r| format!("{}×{}×{}", r.dims[0], r.dims[1], r.dims[2])).collect(),
        series: vec![
            BarSeries {
                label: "dense f32 grid".into(),
                color: series_color(0),
                values: with.iter().map(|r| r.dense_gib).collect(),
            },
            BarSeries {
                label: "peak resident of the report process, streamed".into(),
                color: series_color(1),
                values: with.iter().map(|r| r.peak_rss_mib.unwrap_or(f64::NAN) / 1024.0).collect(),
            },
        ],
    };
    let stem = ctx.figure_dir(NAME)?.join("memory");
    plot::bars(&stem, &chart).map_err(ExperimentError::Figure)?;
    Ok(format!("\n![peak memory against the grid]({})\n", ctx.link(&stem.with_extension("png"))))
}
