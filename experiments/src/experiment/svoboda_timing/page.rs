//! The page `report/svoboda_timing.md`, rendered from the data file alone.

use super::data::{Data, LikeRow, Row};
use super::paper;
use super::{ALGORITHMS, NAME, PAPER, PAPER_CPU_GHZ, SIZES};
use crate::experiment::context::{Context, ExperimentError};
use crate::report::markdown_table;
use crate::verdict::times_faster;

/// The page, from the data file alone.
pub(super) fn section(ctx: &Context) -> Result<String, ExperimentError> {
    let data: Data = ctx.read_data(NAME)?;
    let mut md = String::from("## Deformable terrain: time to triangulate once (`svoboda_timing`)\n\n");
    let mut by_runs: Vec<(usize, Vec<usize>)> = Vec::new();
    for c in SIZES {
        if let Some(r) = data.rows.iter().find(|r| r.cubes == c) {
            match by_runs.iter_mut().find(|(n, _)| *n == r.runs) {
                Some((_, sizes)) => sizes.push(c),
                None => by_runs.push((r.runs, vec![c])),
            }
        }
    }
    let runs = by_runs
        .iter()
        .map(|(n, sizes)| match (sizes.first(), sizes.last()) {
            (Some(a), Some(b)) if a != b => format!("{n} runs from {a}³ to {b}³"),
            (Some(a), _) => format!("{n} at {a}³"),
            _ => String::new(),
        })
        .collect::<Vec<_>>()
        .join(", ");
    md.push_str(&format!(
        "Svoboda (2020), Table 1: marching cubes on a Perlin-noise terrain in Unity (C#, an i5 at {PAPER_CPU_GHZ} GHz, vertices not shared \
         between cubes), N cubes a side. Ours: the `terrain` field (height field plus 3D-noise caves), N cubes a side (one more \
         sample than cubes a side), output buffers reused between runs as a game re-meshing a chunk would, on this shared machine; medians \
         of {runs}. Sampling is parallel and listed apart, as the paper samples once at start-up.\n\n",
    ));
    md.push_str(&reading(&data));
    md.push_str(&crate::experiment::context::options_as_run(&data.settings));
    let sizes: Vec<usize> = SIZES.to_vec();
    let body: Vec<Vec<String>> =
        sizes
            .iter()
            .map(|&c| {
                let mut row = vec![
                    format!("{c}³"),
                    PAPER.iter().find(|p| p.0 == c).map_or("-".into(), |p| {
                        if p.0 == PAPER[0].0 {
                            format!("< {}", p.1)
                        } else {
                            format!("{}", p.1)
                        }
                    }),
                ];
                for a in ALGORITHMS {
                    row.push(data.rows.iter().find(|r| r.algorithm == a && r.cubes == c).map_or("-".into(), |r| {
                        format!("{} ({})", crate::experiment::context::ms(r.extraction_ms), r.triangles)
                    }));
                }
                row.push(
                    data.rows.iter().find(|r| r.cubes == c).map_or("-".into(), |r| crate::experiment::context::ms(r.sampling_ms)),
                );
                row
            })
            .collect();
    let mut header = vec!["cubes", "paper: marching cubes, ms"];
    header.extend(ALGORITHMS.iter().copied());
    header.push("sampling ms");
    md.push_str(&markdown_table(&header, &body));
    if let (Some(ours), Some(paper)) =
        (PAPER.last().and_then(|p| data.rows.iter().find(|r| r.algorithm == "marching-cubes" && r.cubes == p.0)), PAPER.last())
    {
        md.push_str(&format!(
            "\nAt {}³ our marching cubes takes {} against the paper's {} ms ({:.0}× less), {} with sampling. Cells show ms (triangles).\n",
            paper.0,
            crate::experiment::context::ms(ours.extraction_ms),
            paper.1,
            paper.1 / ours.extraction_ms,
            crate::experiment::context::ms(ours.extraction_ms + ours.sampling_ms)
        ));
    }
    md.push_str("\n![time to triangulate](figures/svoboda_timing/time.png)\n");
    md.push_str(&like_section(&data.like_for_like));
    md.push_str(&differences(&data));
    Ok(md)
}

/// The like-for-like table and the ratio it gives.
pub(super) fn like_section(rows: &[LikeRow]) -> String {
    if rows.is_empty() {
        return String::new();
    }
    let mut md = format!(
        "\n**Like for like**: the paper's field (Perlin noise at (x, z) times y, zoom {}, iso-value {}: both unstated in the \
         paper, ours) and the paper's algorithm (unshared vertices: three new ones per triangle, one thread, fresh output \
         each run) here, beside our marching cubes on one thread with fresh output (one-shot), alternating; medians.\n\n",
        paper::ZOOM,
        paper::ISO
    );
    let body: Vec<Vec<String>> = rows
        .iter()
        .map(|r| {
            let p = PAPER.iter().find(|p| p.0 == r.cubes).map_or(f64::NAN, |p| p.1);
            vec![
                format!("{}³", r.cubes),
                // The paper's first entry is an upper bound, written as the paper writes it.
                if r.cubes == PAPER[0].0 { format!("< {p}") } else { format!("{p}") },
                crate::experiment::context::ms(r.unshared_ms),
                crate::experiment::context::ms(r.shared_ms),
                format!("{} ({} / {})", r.triangles, r.vertices[0], r.vertices[1]),
                // The paper's first entry is an upper bound ("< 1"): no ratio.
                if r.cubes == PAPER[0].0 { "-".into() } else { format!("{:.0}×", p / r.unshared_ms.max(1e-9)) },
                format!("{:.1}×", r.unshared_ms / r.shared_ms.max(1e-9)),
            ]
        })
        .collect();
    md.push_str(&markdown_table(
        &[
            "cubes",
            "paper ms",
            "paper's algorithm here, ms",
            "our marching cubes, one thread, ms",
            "triangles (vertices unshared / shared)",
            "paper / its algorithm here",
            "unshared / ours",
        ],
        &body,
    ));
    if let Some(last) = rows.last() {
        let p = PAPER.iter().find(|p| p.0 == last.cubes).map_or(f64::NAN, |p| p.1);
        md.push_str(&format!(
            "\nAt {}³ the paper's algorithm runs {} here than in the paper (Rust against Unity C#, and this \
             machine against the paper's; the algorithm is the same), and sharing vertices makes ours {} on one \
             thread. The paper itself warns that its times carry the Unity editor's overhead (\"The Unity \
             Editor itself also adds overhead, a fact that likely affected the reported numbers during testing\") and that \
             rendering, not marching cubes, slowed its application most at larger grids; how much of the ratio is the \
             editor's, we cannot say.\n",
            last.cubes,
            times_faster(p / last.unshared_ms.max(1e-9), 0),
            times_faster(last.unshared_ms / last.shared_ms.max(1e-9), 1)
        ));
    }
    md
}

/// The page's opening reading, worded from the rows: ours against Table 1 at the paper's largest
/// grid, the like-for-like run, and our extractors at that grid.
pub(super) fn reading(data: &Data) -> String {
    let Some(&(largest, paper)) = PAPER.last() else { return String::new() };
    let at = |a: &str| data.rows.iter().find(|r| r.algorithm == a && r.cubes == largest);
    let Some(ours) = at(ALGORITHMS[0]) else { return String::new() };
    // The like-for-like figure leads: the paper's algorithm (unshared vertices) on the paper's
    // kind of field. The main table's figure crosses field, language and vertex scheme at once.
    let mut lines = Vec::new();
    if let Some(l) = data.like_for_like.iter().find(|r| r.cubes == largest) {
        lines.push(format!(
            "Like for like at {largest}³, the paper's own algorithm on its kind of field takes {} ms here against Table 1's \
             {paper} ms: it runs {} here than in the paper (language, machine and the Unity editor's overhead apart \
             unexplained), and sharing vertices makes ours {}.",
            crate::experiment::context::ms(l.unshared_ms),
            times_faster(paper / l.unshared_ms.max(1e-9), 0),
            times_faster(l.unshared_ms / l.shared_ms.max(1e-9), 1)
        ));
    }
    lines.push(format!(
        "Our marching cubes on our `terrain` field, another field with shared vertices, takes {} ms at {largest}³ ({:.0}× \
         less than Table 1's figure, a ratio that crosses field, language and vertex scheme at once).",
        crate::experiment::context::ms(ours.extraction_ms),
        paper / ours.extraction_ms
    ));
    let mut here: Vec<&Row> = ALGORITHMS.iter().filter_map(|a| at(a)).collect();
    here.sort_by(|a, b| a.extraction_ms.total_cmp(&b.extraction_ms));
    lines.push(format!(
        "Our extractors at {largest}³, fastest first: {}.",
        here.iter()
            .map(|r| format!("{} {} ms", r.algorithm, crate::experiment::context::ms(r.extraction_ms)))
            .collect::<Vec<_>>()
            .join(", ")
    ));
    format!("**Reading.** {} Where we differ from the paper is listed at the end.\n\n", lines.join(" "))
}

/// Where we differ from the paper, each with its reason or "unexplained" (empty without rows).
pub(super) fn differences(data: &Data) -> String {
    let Some(&(largest, paper)) = PAPER.last() else { return String::new() };
    if !data.rows.iter().any(|r| r.cubes == largest) {
        return String::new();
    }
    let like = data.like_for_like.iter().find(|r| r.cubes == largest);
    let mut md = String::from("\n### Where we differ from the paper\n\n");
    if let Some(l) = like {
        md.push_str(&format!(
            "- **Time**: Table 1's {paper} ms at {largest}³ against {} ms for the same algorithm on the same kind of field \
             here: Rust against Unity C#, this machine against an i5 at {PAPER_CPU_GHZ} GHz, and the Unity editor's \
             overhead the paper names; how the ratio splits between them is unexplained.\n",
            crate::experiment::context::ms(l.unshared_ms)
        ));
        md.push_str(&format!(
            "- **Shared vertices**: the paper makes three vertices per triangle ({} at {largest}³ here), ours shares them \
             ({}); the like-for-like table times both.\n",
            l.vertices[0], l.vertices[1]
        ));
    }
    md.push_str(&format!(
        "- **The field**: the paper's noise scale and iso-value are unstated; ours are zoom {} and iso-value {} (our \
         choice), and the main table meshes our `terrain` field instead, so triangle counts are not the paper's.\n\
         - **The smallest grid**: Table 1 gives {}³ as \"< {}\" ms, an upper bound, so no ratio is taken there.\n\n",
        paper::ZOOM,
        paper::ISO,
        PAPER[0].0,
        PAPER[0].1
    ));
    md
}
