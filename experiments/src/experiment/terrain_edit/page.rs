//! The page `report/terrain_edit.md`, rendered from the data file alone.

use super::data::{Data, Run};
use super::{BRUSH_FALLOFF, BRUSH_RADIUS, CHUNK, CHUNK_BUDGET_MS, DIMS, EDITS, FRAME_HZ, FRAME_MS, GIF_EVERY, NAME, SEED};
use crate::experiment::context::{Context, ExperimentError};
use crate::report::markdown_table;

/// The page, from the data file alone.
pub(super) fn section(ctx: &Context) -> Result<String, ExperimentError> {
    let data: Data = ctx.read_data(NAME)?;
    let mut md = String::from("## Editable chunked terrain (`terrain_edit`)\n\n");
    md.push_str(&format!(
        "`terrain` at {}x{}x{} samples in {CHUNK}³-cell chunks ({} chunks), meshed once, then {EDITS} scripted brush edits \
         (seed {SEED}: a sphere of radius {}-{} cells on the surface of a random column, falloff {}-{} cells, alternately \
         carving and adding clay). An edit's time is the sample edit plus re-meshing every chunk it dirtied (in parallel); \
         the welded mesh is only assembled for pictures. Against the {FRAME_MS:.1} ms of a {FRAME_HZ} Hz frame. Every surface \
         extractor chunks: {}. An apron makes an edit dirty more chunks and each chunk cost more (dual contouring here \
         takes its normals from the samples, since edits leave the field behind).\n\n",
        DIMS[0],
        DIMS[1],
        DIMS[2],
        (DIMS[0] - 1) / CHUNK * (DIMS[1] - 1) / CHUNK * (DIMS[2] - 1) / CHUNK,
        BRUSH_RADIUS.0,
        BRUSH_RADIUS.1,
        BRUSH_FALLOFF.0,
        BRUSH_FALLOFF.1,
        data.runs.iter().map(|r| format!("`{}` {}", r.algorithm, chunk_reads(&r.algorithm))).collect::<Vec<_>>().join("; "),
    ));
    md.push_str(&reading(&data));
    let settings: Vec<(String, String)> = data.runs.iter().map(|r| (r.algorithm.clone(), r.settings.clone())).collect();
    md.push_str(&crate::experiment::context::options_as_run(&settings));
    let body: Vec<Vec<String>> = data
        .runs
        .iter()
        .map(|r| {
            let within = r.edit_ms.iter().filter(|&&ms| ms <= FRAME_MS).count();
            vec![
                r.algorithm.clone(),
                format!("{:.0}", r.initial_ms),
                format!("{:.2}", r.median_ms),
                format!("{:.2}", r.p99_ms),
                format!("{:.2}", r.max_ms),
                format!("{within}/{}", r.edit_ms.len()),
                format!("{:.1}", r.dirtied.iter().sum::<usize>() as f64 / r.dirtied.len().max(1) as f64),
                format!("{} → {}", r.triangles[0], r.triangles[1]),
                if r.manifold_after { "yes".into() } else { "**no**".into() },
                r.open_seam_edges_max.to_string(),
                format!("{:.2}, {:.1}°", r.quality_after[0], r.quality_after[1]),
            ]
        })
        .collect();
    md.push_str(&markdown_table(
        &[
            "extractor",
            "mesh all (ms)",
            "edit median (ms)",
            "edit p99 (ms)",
            "slowest (ms)",
            &format!("within {FRAME_MS:.1} ms"),
            "chunks per edit",
            "triangles",
            "manifold after",
            "open seam edges (most after an edit)",
            "edited mesh: mean aspect, smallest angle",
        ],
        &body,
    ));
    md.push_str(&format!(
        "\nOpen seam edges are boundary edges of the welded mesh more than one cell from the world's box (a crack between \
         chunks is made of them, and an edge-manifold check passes it; the dual extractors' own open border lies inside \
         the outermost cells), counted after every edit. The quality columns measure the \
         chunked mesh after the {EDITS} edits, not a fresh whole-domain mesh.\n\n\
         ### One chunk on one thread\n\n\
         A game re-meshes dirty chunks on worker threads, one chunk per task, within a slice of a frame. The same {EDITS} \
         edits, each dirty chunk re-meshed on its own on one thread (a one-thread pool), at three chunk sizes: one \
         chunk's time, median, p99 and slowest (ms), and the open seam edges of the welded mesh after the sequence.\n\n"
    ));
    let sizes: Vec<usize> = data.runs.first().map(|r| r.chunk_runs.iter().map(|c| c.chunk).collect()).unwrap_or_default();
    let header: Vec<String> = std::iter::once("extractor".to_owned())
        .chain(sizes.iter().map(|c| format!("{c}³: median / p99 / max (chunks)")))
        .chain(std::iter::once("open seam edges after".to_owned()))
        .collect();
    let rows: Vec<Vec<String>> = data
        .runs
        .iter()
        .map(|r| {
            std::iter::once(r.algorithm.clone())
                .chain(
                    r.chunk_runs
                        .iter()
                        .map(|c| format!("{:.2} / {:.2} / {:.2} ({})", c.chunk_ms[0], c.chunk_ms[1], c.chunk_ms[2], c.chunks)),
                )
                .chain(std::iter::once(r.chunk_runs.iter().map(|c| c.open_seam_edges.to_string()).collect::<Vec<_>>().join(", ")))
                .collect()
        })
        .collect();
    let header: Vec<&str> = header.iter().map(String::as_str).collect();
    md.push_str(&markdown_table(&header, &rows));
    if !data.not_run.is_empty() {
        md.push_str(&format!(
            "\n**Not run** (not chunk-capable yet: their cells or tetrahedra straddle chunk faces and need an apron and \
             ownership rules inside the extractor): {}.\n",
            data.not_run.join(", ")
        ));
    }
    md.push_str(&format!("\n![edit times]({})\n\n", data.plot));
    md.push_str(&format!(
        "Before and after the {EDITS} edits (marching cubes, coloured by material: grass, sand in the valleys, dirt, rock in the caves, the brushes' clay), and every {GIF_EVERY}th edit as an animation:\n\n![before]({}) \
         ![after]({})\n\n![edits]({})\n",
        data.before, data.after, data.gif
    ));
    Ok(md)
}

/// Names, or "none".
pub(super) fn names<'a>(v: impl Iterator<Item = &'a str>) -> String {
    crate::report::listed(&v.collect::<Vec<_>>())
}

/// The page's opening reading: who keeps every edit within a frame, the median edits, who leaves
/// no crack and stays manifold, and who keeps one chunk within the per-chunk budget.
pub(super) fn reading(data: &Data) -> String {
    if data.runs.is_empty() {
        return String::new();
    }
    let within = |r: &Run| r.edit_ms.iter().filter(|&&ms| ms <= FRAME_MS).count();
    let missed: Vec<String> = data
        .runs
        .iter()
        .filter(|r| within(r) < r.edit_ms.len())
        .map(|r| format!("{} ({} of {})", r.algorithm, within(r), r.edit_ms.len()))
        .collect();
    let mut lines = vec![format!(
        "Every edit within a {FRAME_MS:.1} ms frame: {}; not every one: {}.",
        names(data.runs.iter().filter(|r| within(r) == r.edit_ms.len()).map(|r| r.algorithm.as_str())),
        crate::report::listed(&missed)
    )];
    let mut by_median: Vec<&Run> = data.runs.iter().collect();
    by_median.sort_by(|a, b| a.median_ms.total_cmp(&b.median_ms));
    lines.push(format!(
        "Median edit, ms: {}.",
        by_median.iter().map(|r| format!("{} {:.2}", r.algorithm, r.median_ms)).collect::<Vec<_>>().join(", ")
    ));
    lines.push(format!(
        "No crack after any edit and closed manifold after the sequence: {}; not: {}.",
        names(data.runs.iter().filter(|r| r.open_seam_edges_max == 0 && r.manifold_after).map(|r| r.algorithm.as_str())),
        names(data.runs.iter().filter(|r| !(r.open_seam_edges_max == 0 && r.manifold_after)).map(|r| r.algorithm.as_str()))
    ));
    let at = |r: &Run| r.chunk_runs.iter().find(|c| c.chunk == CHUNK).map(|c| c.chunk_ms[1]);
    if data.runs.iter().any(|r| at(r).is_some()) {
        lines.push(format!(
            "One {CHUNK}³ chunk on one thread with its p99 within the {CHUNK_BUDGET_MS} ms budget: {}.",
            names(data.runs.iter().filter(|r| at(r).is_some_and(|p| p <= CHUNK_BUDGET_MS)).map(|r| r.algorithm.as_str()))
        ));
    }
    format!("**Reading.** {}\n\n", lines.join(" "))
}

/// What an extractor reads to mesh one chunk, in words.
pub(super) fn chunk_reads(algorithm: &str) -> String {
    match isolab_algorithms::extractors::by_name(algorithm).map(|e| e.chunking()) {
        Some(isolab_algorithms::Chunking::CellLocal) => "reads exactly its chunk's samples".into(),
        Some(isolab_algorithms::Chunking::Apron(a)) => format!("also reads an apron of {a} samples of its neighbours"),
        _ => "does not chunk".into(),
    }
}
