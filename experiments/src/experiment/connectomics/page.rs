//! The page `report/connectomics.md`, rendered from the data file alone.

use super::data::{Data, Run};
use super::{NAME, SHOWN, TARGET_SPEEDUP};
use crate::experiment::context::{Context, ExperimentError};
use crate::report::markdown_table;

/// The page, from the data file alone.
pub(super) fn section(ctx: &Context) -> Result<String, ExperimentError> {
    let data: Data = ctx.read_data(NAME)?;
    Ok(page_body(&data))
}

pub(super) fn run_of<'a>(data: &'a Data, tool: &str, workers: usize) -> Option<&'a Run> {
    data.runs.iter().find(|r| r.tool == tool && r.workers == workers)
}

pub(super) fn peak(r: &Run) -> f64 {
    r.peak_rss_mib.iter().copied().fold(0.0, f64::max)
}

pub(super) fn mib(bytes: u64) -> f64 {
    bytes as f64 / f64::from(1u32 << 20)
}

/// The page's opening reading: isolab against igneous at each worker count (against the issue's
/// bar), the workers' memory against their limit and the volume, and the levels' triangles.
pub(super) fn reading(data: &Data) -> String {
    let mut lines = Vec::new();
    let workers: Vec<usize> = {
        let mut w: Vec<usize> = data.runs.iter().map(|r| r.workers).collect();
        w.sort_unstable();
        w.dedup();
        w
    };
    for &w in &workers {
        if let (Some(ours), Some(theirs)) = (run_of(data, "isolab", w), run_of(data, "igneous", w)) {
            let ratio = theirs.seconds / ours.seconds;
            let verdict = if ratio >= TARGET_SPEEDUP {
                format!("at or past the {TARGET_SPEEDUP:.0}× the issue asks")
            } else {
                format!("short of the {TARGET_SPEEDUP:.0}× the issue asks")
            };
            lines.push(format!(
                "With {w} worker(s), isolab took {:.0} s and igneous {:.0} s end to end: {ratio:.2}× igneous's speed, {verdict}.",
                ours.seconds, theirs.seconds
            ));
        }
    }
    let ours: Vec<&Run> = data.runs.iter().filter(|r| r.tool == "isolab").collect();
    if let Some(top) = ours.iter().map(|r| peak(r)).reduce(f64::max) {
        let restarted = ours.iter().filter(|r| r.restarted).count();
        lines.push(format!(
            "isolab's largest worker peak was {top:.0} MiB, against a limit of {} MiB per worker and a volume of {:.0} MiB; \
             runs with a worker restarted: {restarted} of {}.",
            data.memory_limit_mib,
            data.volume.gib * 1024.0,
            ours.len()
        ));
    }
    if let Some(r) = ours.first() {
        if let (Some(first), Some(last)) = (r.triangles.first(), r.triangles.last()) {
            lines.push(format!(
                "Its {} levels hold {} triangles at the finest and {} at the coarsest, over {} segments.",
                r.triangles.len(),
                first,
                last,
                r.segments.unwrap_or(0)
            ));
        }
    }
    if let Some(d) = &data.draco {
        if let (Some(ours), Some(best)) =
            (d.encoders.first(), d.encoders.iter().skip(1).min_by(|a, b| a.median.total_cmp(&b.median)))
        {
            lines.push(format!(
                "On the same fragments, {} encoded at {:.2}× the speed of {} ({:.1} MiB against {:.1} MiB).",
                ours.encoder,
                best.median / ours.median,
                best.encoder,
                mib(ours.bytes),
                mib(best.bytes)
            ));
        }
    }
    lines.extend(ours.iter().filter_map(|r| time_split(r)));
    if lines.is_empty() {
        return String::new();
    }
    format!("**Reading.** {}\n\n", lines.join(" "))
}

/// The share of the workers' time (their count times the wall time) spent computing tasks, from
/// Dask's task stream; `None` for data made before it was measured.
pub(super) fn busy_share(r: &Run) -> Option<f64> {
    (!r.busy_seconds.is_empty() && r.seconds > 0.0).then(|| r.busy_seconds.iter().sum::<f64>() / (r.workers as f64 * r.seconds))
}

/// Where an isolab run's wall time went: its workers' busy share and its phases.
pub(super) fn time_split(r: &Run) -> Option<String> {
    let share = busy_share(r)?;
    let phase = |name: &str| r.phases.get(name).copied().unwrap_or(f64::NAN);
    Some(format!(
        "With {} worker(s), isolab's workers computed tasks for {:.0}% of {} × its {:.0} s (idle {:.0} worker-seconds); \
         its boxes took {:.1} s of wall time, its segments' files {:.1} s and its info and cleanup {:.1} s.",
        r.workers,
        100.0 * share,
        r.workers,
        r.seconds,
        r.workers as f64 * r.seconds - r.busy_seconds.iter().sum::<f64>(),
        phase("boxes"),
        phase("files"),
        phase("info_and_cleanup"),
    ))
}

/// The table of isolab's runs' phases and their workers' seconds per kind of task.
fn time_table(data: &Data) -> String {
    let ours: Vec<&Run> = data.runs.iter().filter(|r| r.tool == "isolab" && !r.busy_seconds.is_empty()).collect();
    if ours.is_empty() {
        return String::new();
    }
    let mut kinds: Vec<&String> = ours.iter().flat_map(|r| r.task_seconds.keys()).collect();
    kinds.sort();
    kinds.dedup();
    let mut header: Vec<String> =
        ["workers", "wall s", "boxes s", "files s", "info and cleanup s", "workers computing"].map(String::from).to_vec();
    header.extend(kinds.iter().map(|k| format!("`{k}` s")));
    let rows: Vec<Vec<String>> = ours
        .iter()
        .map(|r| {
            let mut row = vec![r.workers.to_string(), format!("{:.1}", r.seconds)];
            row.extend(
                ["boxes", "files", "info_and_cleanup"].map(|p| r.phases.get(p).map_or(String::new(), |s| format!("{s:.1}"))),
            );
            row.push(busy_share(r).map_or(String::new(), |s| format!("{:.0}%", 100.0 * s)));
            row.extend(kinds.iter().map(|k| r.task_seconds.get(*k).map_or(String::new(), |s| format!("{s:.1}"))));
            row
        })
        .collect();
    let header: Vec<&str> = header.iter().map(String::as_str).collect();
    format!(
        "\n### Where isolab's time goes\n\nThe phases' wall times are the ones `mesh_labels` returns (`seconds`): the boxes \
         of every level (reading the blocks included), the segments' files (the shards) and the info and the work \
         folder's removal. Workers computing is the sum of the seconds Dask's task stream shows each worker computing, \
         over the workers' count times the wall time; the last columns split it by the task's function.\n\n{}",
        markdown_table(&header, &rows)
    )
}

pub(super) fn page_body(data: &Data) -> String {
    let mut md = String::from("## Connectome scale: label maps to neuroglancer's multi-resolution meshes (`connectomics`)\n\n");
    let v = &data.volume;
    md.push_str(&format!(
        "A Voronoi foam of {} labels in a {n}×{n}×{n} volume ({} voxels, {}, {:.2} GiB, {} nm per voxel), written \
         uncompressed both as a zarr array (isolab's input) and as a precomputed segmentation by cloud-volume (igneous's \
         input). **isolab**: `isolab.dask.mesh_labels(zarr, chunk={}, format=\"neuroglancer\", sharded=True)` on a \
         `distributed.LocalCluster` on loopback, worker processes of one thread, each limited to {} MiB: every block's \
         task writes its own level-0 fragments, each coarser box is made from the eight below it, and the shards copy \
         the fragments' bytes; no task holds a label's full-resolution mesh. **igneous**: its forge (zmesh per task of \
         {s}×{s}×{s} voxels, simplified as its defaults do) then its sharded multi-resolution merge, on a local task \
         queue of as many processes as Dask has workers. Both are timed end to end from the call to the last file \
         written; isolab's peak is each Dask worker's high-water resident memory, igneous's the largest of its \
         processes'. One round, the tools alternating at each worker count, on this machine's {} cores. Script: \
         `experiments/src/experiment/connectomics/bench.py`. Versions: {}.\n\n",
        v.cells,
        v.voxels,
        v.dtype,
        v.gib,
        v.resolution_nm,
        data.chunk,
        data.memory_limit_mib,
        data.cores,
        data.versions.iter().map(|(k, v)| format!("{k} {v}")).collect::<Vec<_>>().join(", "),
        n = v.n,
        s = data.igneous_shape,
    ));
    md.push_str(&reading(data));
    md.push_str(&crate::experiment::context::default_options(&["surface-nets"]));
    let rows: Vec<Vec<String>> = data
        .runs
        .iter()
        .map(|r| {
            vec![
                r.tool.clone(),
                r.workers.to_string(),
                format!("{:.1}", r.seconds),
                format!("{:.0}", mib(r.bytes)),
                format!("{:.0}", peak(r)),
                if r.restarted { "yes" } else { "no" }.into(),
            ]
        })
        .collect();
    md.push_str(&markdown_table(&["tool", "workers", "wall s", "MiB written", "peak process MiB", "a worker restarted"], &rows));
    md.push_str(&time_table(data));
    if let Some(r) = data.runs.iter().find(|r| r.tool == "isolab" && !r.triangles.is_empty()) {
        md.push_str("\n### isolab's levels of detail\n\n");
        let rows: Vec<Vec<String>> = (0..r.triangles.len())
            .map(|l| {
                vec![
                    l.to_string(),
                    r.fragments.get(l).map_or(String::new(), u64::to_string),
                    r.triangles[l].to_string(),
                    r.level_bytes.get(l).map_or(String::new(), |&b| format!("{:.1}", mib(b))),
                ]
            })
            .collect();
        md.push_str(&markdown_table(&["level", "fragments", "triangles", "MiB (Draco)"], &rows));
        md.push_str(
            "\nThe finest level is the extractor's full-resolution surface, cut at the blocks' faces; each coarser level \
             is simplified by meshoptimizer inside each box of the level under it, the boxes' faces locked, so that \
             levels meet without cracks. igneous simplifies already at its finest level (its forge's default error), so \
             the two write different triangle counts and bytes; the first table compares the whole runs.\n",
        );
    }
    if let Some(d) = &data.draco {
        md.push_str(&format!(
            "\n### Which Draco encoder\n\nThe same {} fragments ({} triangles: isolab's finest level of the volume's first \
             {side}×{side}×{side} voxels, decoded) encoded again by each encoder in one process on one thread, alternating, \
             {} round(s): isolab's writer (the pure-Rust `draco-core` crate) and Google's C++ Draco through DracoPy, with \
             Draco's own quantization set to give the same integers, as igneous calls it.\n\n",
            d.fragments,
            d.triangles,
            d.encoders.first().map_or(0, |e| e.seconds.len()),
            side = d.side,
        ));
        let rows: Vec<Vec<String>> = d
            .encoders
            .iter()
            .map(|e| {
                let lo = e.seconds.iter().copied().fold(f64::INFINITY, f64::min);
                let hi = e.seconds.iter().copied().fold(0.0, f64::max);
                vec![
                    e.encoder.clone(),
                    format!("{:.2}", e.median),
                    format!("{lo:.2}–{hi:.2}"),
                    format!("{:.2}", d.triangles as f64 / e.median / 1e6),
                    format!("{:.1}", mib(e.bytes)),
                ]
            })
            .collect();
        md.push_str(&markdown_table(&["encoder", "s (median)", "fastest–slowest", "M triangles/s", "MiB"], &rows));
    }
    if data.screenshot {
        md.push_str(&format!(
            "\n![neuroglancer drawing {SHOWN} of isolab's segments](figures/{NAME}/neuroglancer-isolab.png)\n\n\
             Neuroglancer's own viewer (the `neuroglancer` package's bundled client, on loopback, in headless Chromium) \
             drawing {SHOWN} segments of isolab's sharded source.\n"
        ));
    }
    if !data.notes.is_empty() {
        md.push_str(&format!("\nNotes: {}\n", data.notes.join("; ")));
    }
    md
}
