//! The page `report/distributed.md`, rendered from the data file alone.

use super::data::{Data, Run};
use super::{MESHED_BY, NAME, WORKERS};
use crate::experiment::context::{Context, ExperimentError};
use crate::report::{markdown_table, Spread};

/// The page, from the data file alone.
pub(super) fn section(ctx: &Context) -> Result<String, ExperimentError> {
    let data: Data = ctx.read_data(NAME)?;
    Ok(page_body(&data))
}

pub(super) fn seconds(runs: &[&Run]) -> Spread {
    Spread::of(runs.iter().map(|r| r.seconds).collect())
}

pub(super) fn runs_of<'a>(data: &'a Data, volume: &str, chunk: usize, workers: usize) -> Vec<&'a Run> {
    data.runs.iter().filter(|r| r.volume == volume && r.chunk == chunk && r.workers == workers).collect()
}

pub(super) fn median(values: impl Iterator<Item = f64>) -> f64 {
    Spread::of(values.collect()).median
}

/// Storage chunks a block of `chunk` cells reads per storage chunk of its own cells: it reads
/// `chunk + 1` samples per axis, one storage chunk more per axis than it covers.
pub(super) fn read_amplification(chunk: usize, store: usize) -> f64 {
    let own = chunk as f64 / store as f64;
    ((chunk + 1).div_ceil(store) as f64 / own).powi(3)
}

pub(super) fn yes(b: bool) -> &'static str {
    if b {
        "yes"
    } else {
        "no"
    }
}

/// Whether the runs of the last block of rounds still span more than [`crate::report::WIDE`]
/// times (slowest over fastest).
pub(super) fn still_wide(runs: &[&Run]) -> bool {
    let last = runs.iter().map(|r| r.block).max().unwrap_or(0);
    let times: Vec<f64> = runs.iter().filter(|r| r.block == last).map(|r| r.seconds).collect();
    times.len() > 1 && Spread::of(times).is_wide()
}

/// `one`'s time over `two`'s, round by round (the runs of one round paired): its range.
pub(super) fn speedup_range(one: &[&Run], two: &[&Run]) -> Option<(f64, f64)> {
    let (a, b): (Vec<f64>, Vec<f64>) =
        one.iter().filter_map(|o| two.iter().find(|t| t.round == o.round).map(|t| (t.seconds, o.seconds))).unzip();
    crate::report::ratio_range(&a, &b)
}

/// The second worker on the largest volume, per block size, with how busy one worker alone keeps
/// the cores.
pub(super) fn two_workers(data: &Data) -> Option<String> {
    let v = data.volumes.iter().max_by(|a, b| a.mib.total_cmp(&b.mib))?;
    let ratios: Vec<String> = data
        .chunks
        .iter()
        .filter_map(|&chunk| {
            let one = runs_of(data, &v.volume, chunk, WORKERS[0]);
            let two = runs_of(data, &v.volume, chunk, WORKERS[1]);
            (!one.is_empty() && !two.is_empty()).then(|| {
                let busy = median(one.iter().map(|r| r.worker_cpu_seconds)) / seconds(&one).median;
                let range =
                    speedup_range(&one, &two).map_or(String::new(), |(lo, hi)| format!(" ({lo:.2}–{hi:.2}× round by round)"));
                format!(
                    "{:.2}×{range} with {chunk}³ blocks (where one worker alone keeps {busy:.2} cores busy: CPU seconds over \
                     wall seconds)",
                    seconds(&one).median / seconds(&two).median
                )
            })
        })
        .collect();
    (!ratios.is_empty()).then(|| {
        format!("On the largest volume ({}), {} workers against {}: {}.", v.volume, WORKERS[1], WORKERS[0], ratios.join(", "))
    })
}

/// The page's opening reading: the second worker, whether every welded mesh is the one-process
/// mesh (undisturbed and with a worker killed), the workers' memory against their limit, and the
/// naive zmesh merge's defects.
pub(super) fn reading(data: &Data) -> String {
    if data.volumes.is_empty() && data.runs.is_empty() {
        return String::new();
    }
    let mut lines: Vec<String> = two_workers(data).into_iter().collect();
    let n = data.volumes.len();
    let equal = data.volumes.iter().filter(|v| v.equals_one_process == Some(true)).count();
    let killed = data.volumes.iter().filter(|v| v.killed_equal).count();
    let closed = data.volumes.iter().filter(|v| v.topology.closed && v.topology.non_manifold_edges == 0).count();
    lines.push(format!(
        "The welded mesh equals the one-process mesh on {equal} of {n} volumes, stays the same with a worker killed \
         mid-run on {killed} of {n}, and is closed with no non-manifold edge on {closed} of {n}."
    ));
    let peak = data.runs.iter().flat_map(|r| r.worker_peak_rss_mib.iter().copied()).fold(0.0f64, f64::max);
    let restarted = data.runs.iter().filter(|r| r.restarted).count();
    lines.push(format!(
        "The largest worker peak is {peak:.0} MiB against the {} MiB limit; runs with a worker restarted: {restarted} of {}.",
        data.memory_limit_mib,
        data.runs.len()
    ));
    let zmesh: Vec<String> = data
        .volumes
        .iter()
        .filter_map(|v| {
            let z = v.zmesh.as_ref()?;
            Some(format!("{} {} boundary and {} non-manifold edges", v.volume, z.boundary_edges, z.non_manifold_edges))
        })
        .collect();
    if !zmesh.is_empty() {
        lines.push(format!("zmesh's blocks merged naively leave: {}.", zmesh.join("; ")));
    }
    format!("**Reading.** {}\n\n", lines.join(" "))
}

pub(super) fn page_body(data: &Data) -> String {
    let mut md = String::from("## Bigger than one machine: zarr volumes on a Dask cluster (`distributed`)\n\n");
    let chunks = data.chunks.iter().map(|c| format!("{c}³")).collect::<Vec<_>>().join(" and ");
    md.push_str(&format!(
        "`isolab.dask.mesh_volume` on a `distributed.LocalCluster` (worker processes with one thread each, bound to \
         127.0.0.1) on this machine's {} cores. Each worker may use {} MiB; each volume is a zarr array on disk several \
         times that ({}³ storage chunks), read block by block by the tasks (blocks of {chunks} cells, every block a \
         fragment written atomically). Each run starts a fresh cluster and a fresh fragment folder and is timed from \
         submitting the tasks to the last fragment written; runs alternate between the worker counts, {} round(s) a block, \
         another block while either count's runs in the last one span over {}× (slowest over fastest), up to {} blocks \
         (\"(wide)\" marks a cell still wide after its last). The \
         weld of the fragments into one mesh is timed apart, in the driver process. Worker peak memory is each worker \
         process's high-water resident set (`VmHWM`), start-up included; CPU seconds are the workers' together and the \
         driver's (the client, the scheduler and the nannies share that process). Script: \
         `experiments/src/experiment/distributed/bench.py`. Versions: {}.\n\n",
        data.cores,
        data.memory_limit_mib,
        data.store_chunk,
        data.repeats,
        crate::report::WIDE,
        crate::report::MAX_ROUNDS,
        data.versions.iter().map(|(k, v)| format!("{k} {v}")).collect::<Vec<_>>().join(", ")
    ));
    md.push_str(&reading(data));
    md.push_str(&crate::experiment::context::default_options(&[MESHED_BY]));
    let mut rows = Vec::new();
    for v in &data.volumes {
        for &chunk in &data.chunks {
            let one = seconds(&runs_of(data, &v.volume, chunk, WORKERS[0]));
            for workers in WORKERS {
                let runs = runs_of(data, &v.volume, chunk, workers);
                if runs.is_empty() {
                    continue;
                }
                let s = seconds(&runs);
                let peak = runs.iter().flat_map(|r| r.worker_peak_rss_mib.iter().copied()).fold(0.0f64, f64::max);
                rows.push(vec![
                    v.volume.clone(),
                    v.shape.iter().map(usize::to_string).collect::<Vec<_>>().join("×"),
                    format!("{:.0} ({:.1}× a worker's limit)", v.mib, v.mib / data.memory_limit_mib as f64),
                    format!("{chunk}³"),
                    workers.to_string(),
                    format!("{:.1}", s.median),
                    format!("{:.1}–{:.1}{}", s.min, s.max, if still_wide(&runs) { " (wide)" } else { "" }),
                    format!("{:.0}", runs[0].blocks as f64 / s.median),
                    format!("{:.1}", median(runs.iter().map(|r| r.worker_cpu_seconds))),
                    format!("{:.1}", median(runs.iter().map(|r| r.driver_cpu_seconds))),
                    format!("{peak:.0}"),
                    yes(runs.iter().any(|r| r.restarted)).into(),
                    format!("{:.2}", one.median / s.median),
                ]);
            }
        }
    }
    md.push_str(&markdown_table(
        &[
            "volume",
            "shape",
            "MiB",
            "block",
            "workers",
            "wall s (median)",
            "fastest–slowest",
            "blocks/s",
            "worker CPU s",
            "driver CPU s",
            "worker peak MiB (largest)",
            "a worker restarted",
            "speed-up over one worker",
        ],
        &rows,
    ));
    let amplification: Vec<String> = data
        .chunks
        .iter()
        .map(|&c| format!("{c}³ blocks read {:.2}× the storage chunks they cover", read_amplification(c, data.store_chunk)))
        .collect();
    md.push_str(&format!(
        "\nOne worker with one Dask thread keeps more than one core busy (its CPU seconds over the wall seconds; zarr \
         reads and decompresses on threads of its own), and the driver, where the scheduler runs, takes its share of \
         the same cores: the one-worker baseline is more than one core's work, so two workers cannot halve it. A block reads \
         one sample more per axis than it has cells, so from a zarr store it decompresses one more storage chunk per \
         axis than it covers: {}. Each task also pays the scheduler's round trip and writes its fragment; the driver CPU \
         column is the scheduler's share of the machine's cores.\n",
        amplification.join(", ")
    ));
    md.push_str("\n### Seams, faults and the weld\n\n");
    let rows: Vec<Vec<String>> = data
        .volumes
        .iter()
        .map(|v| {
            vec![
                v.volume.clone(),
                format!("{}³", v.chunk),
                v.triangles.to_string(),
                format!("{:.1}", v.weld_seconds),
                format!(
                    "{}, {} boundary edges, {} non-manifold edges, genus {}, {} components",
                    if v.topology.closed { "closed" } else { "open" },
                    v.topology.boundary_edges,
                    v.topology.non_manifold_edges,
                    v.topology.genus,
                    v.topology.components
                ),
                v.equals_one_process.map_or("not checked".into(), |b| yes(b).to_owned()),
                format!(
                    "{} (killed after {} fragments; replaced: {}; {:.1} s)",
                    yes(v.killed_equal),
                    v.killed.fragments_before_kill,
                    yes(v.killed.worker_replaced),
                    v.killed.seconds
                ),
            ]
        })
        .collect();
    md.push_str(&markdown_table(
        &[
            "volume",
            "block",
            "triangles",
            "weld s",
            "welded mesh",
            "equals the one-process mesh",
            "a worker killed mid-run: same mesh",
        ],
        &rows,
    ));
    md.push_str(
        "\n\"Equals the one-process mesh\": the welded mesh against `isolab.extract` of the whole array in the driver \
         process, as sets: the same vertices bit for bit and the same triangles over them. \"Killed\": a worker process \
         is sent SIGKILL once the first fragment is on disk; distributed reruns its tasks on the other worker and the \
         nanny starts a new one; the welded result is compared with the undisturbed run's.\n",
    );
    let zmesh: Vec<Vec<String>> = data
        .volumes
        .iter()
        .filter_map(|v| v.zmesh.as_ref().map(|z| (v, z)))
        .map(|(v, z)| {
            vec![
                v.volume.clone(),
                format!("{:.1}", z.seconds),
                z.vertices_before_merge.to_string(),
                z.coincident_vertices_merged.to_string(),
                z.triangles.to_string(),
                z.collapsed_triangles.to_string(),
                z.boundary_edges.to_string(),
                z.non_manifold_edges.to_string(),
                yes(z.closed).into(),
            ]
        })
        .collect();
    if !zmesh.is_empty() {
        md.push_str("\n### zmesh on the same blocks, merged naively\n\n");
        md.push_str(
            "zmesh (`zmesh.Mesher` per block, the kernel igneous distributes) on the same blocks, one after another in \
             the driver, given each block's inside as a binary label (zmesh meshes labels, not intensities, so its surface \
             is not ours), each block's vertices moved to the volume's sample indices, then merged by exact position. \
             The seam defects a naive merge leaves are what the columns after the merge count.\n\n",
        );
        md.push_str(&markdown_table(
            &[
                "volume",
                "s (serial)",
                "vertices before merge",
                "coincident vertices merged",
                "triangles",
                "triangles collapsed by the merge",
                "boundary edges",
                "non-manifold edges",
                "closed",
            ],
            &zmesh,
        ));
        for v in &data.volumes {
            let Some(z) = &v.zmesh else { continue };
            let defects = z.boundary_edges + z.non_manifold_edges + z.collapsed_triangles;
            md.push_str(&format!(
                "\nOn {}: {}{}\n",
                v.volume,
                if defects == 0 {
                    format!(
                        "the naive merge left no seam defect here: zmesh's vertices on a face two blocks share coincide bit \
                         for bit, so merging by position closed every seam ({} coincident vertices merged).",
                        z.coincident_vertices_merged
                    )
                } else {
                    format!("the naive merge left {defects} seam defects (boundary and non-manifold edges, collapsed triangles).")
                },
                if z.triangles == v.triangles {
                    " zmesh's triangle count equals ours: marching cubes' triangulation depends only on which corners are \
                     inside, which the threshold keeps; the positions differ (zmesh's sit at edge midpoints)."
                } else {
                    ""
                }
            ));
        }
    }
    md.push_str(
        "\n### On many machines\n\nThe same call with `client=distributed.Client(\"tls://scheduler:8786\", \
         security=Security(...))` runs the tasks on a cluster's workers: each task needs only the zarr store's address \
         (a shared file system, or object storage through fsspec) and writes its fragment where every machine can \
         read it, so nothing but the plan crosses the network. What changes at terabyte scale: fragments go to object \
         storage beside the volume (atomic puts replace the rename), the manifest becomes the restart record of a \
         long job, and the weld, which here holds the whole mesh in one process, becomes either no weld at all \
         (`merge=False`: a viewer or game streams the fragments, which already share their seam vertices' keys) or a \
         merge tree that welds neighbouring fragments pairwise and keeps only the keys on the outer faces of each \
         merged group, as `stream_chunked` keeps only one slab's top face.\n",
    );
    if !data.notes.is_empty() {
        md.push_str(&format!("\nNotes from the run: {}.\n", data.notes.join("; ")));
    }
    md
}
