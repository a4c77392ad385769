//! The `terrain_lod` page: the method paragraph, the options as run, the table, the reading
//! (generated from the rows), the switching cost and the pictures.

use super::data::{Data, Row};
use super::{CHUNK, CRATE, DIMS, NAME, NEAR_SAMPLE, RUNS, TRANSVOXEL_VERSION};
use crate::experiment::context::{Context, ExperimentError};
use crate::report::{first_seen, markdown_table};

/// The page, from the data file alone.
pub(super) fn section(ctx: &Context) -> Result<String, ExperimentError> {
    let d: Data = ctx.read_data(NAME)?;
    Ok(page(&d))
}

/// The page's Markdown from the run's data.
pub(super) fn page(d: &Data) -> String {
    let mut md = String::from("## Levels of detail without cracks (`terrain_lod`)\n\n");
    let ours: Vec<&str> =
        first_seen(d.rows.iter().map(|r| r.implementation.as_str())).into_iter().filter(|&i| i != CRATE).collect();
    md.push_str(&format!(
        "The {}×{}×{}-cell `terrain` in {CHUNK}³-cell chunks, each meshed at full resolution, at half resolution (every \
         other sample) or at a quarter; chunks that touch differ by one level at most. Every registered extractor that \
         takes levels of detail runs ({}). For all of them the finer side's samples on a seam are first restricted to \
         what the coarser side sees (linear on a coarse edge, bilinear on a coarse face, an ambiguous face's interior \
         kept outside). *Restriction + stitching* (marching cubes) then fills each coarse seam triangle's polygon (its \
         corners off the seam and the fine boundary path) with the best-shaped of its triangulations and of fans from a \
         new vertex inside it whose triangles cross nothing near them (exact predicates); *octree minimal edges* (surface nets, dual contouring; Ju et al. 2002's rule for octrees) gives \
         every crossing edge of the finest cells around it a polygon joining the vertices of the cells around it, a \
         triangle where one coarse cell spans two of them, and splits a vertex where a fine cell's ring meets a coarse \
         cell's across a seam (*pinched*); *fans kept in cells* (manifold dual contouring: Ju and Udeshi 2006's \
         construction carried to the seams) turns each such polygon into a fan around its edge's crossing point, a side \
         between a fine and a coarse cell broken at a point inside the fine face they share, so that every triangle \
         stays inside its cells and the mesh cannot cross itself. **The `transvoxel` crate** ({TRANSVOXEL_VERSION}, Lengyel 2010's transition \
         cells, on the same chunks, samples and levels): each chunk is a block whose faces toward a finer face neighbour \
         are transition faces; blocks are welded by exact position (the crate keeps each transition cell's vertices \
         apart from the regular cells' at the same places). The crate's own `extract_from_field` with \
         `FieldCaching::CacheCentralBlockOnly` reads the coarse block where the finer neighbour's samples belong and \
         leaves its transition faces open, so the harness builds the crate's block view with the finer neighbours \
         itself, as its `CacheNothing` path does (a test keeps both facts). *Open seam edges* counts boundary edges \
         that are cracks: for marching cubes and the crate any off the world's boundary; for the dual methods, whose \
         own border lies inside the outer cells, any more than a coarsest cell from it. *Seam triangles* are those \
         within one coarser-side cell of a chunk face between two levels; their aspect ratio (longest edge times \
         perimeter over area, normalised to the equilateral triangle's) is given as a mean, a median and a mean \
         *off samples* (over the triangles with no corner within {NEAR_SAMPLE} of a cell of a sample: marching \
         cubes' needles, where a crossing nearly meets a sample, outweigh the rest of a mean), and triangles \
         without area, which have no shape, are counted apart. Times are medians of {RUNS} runs alternating \
         all implementations (range in brackets), on the same thread pool, sampling excluded, welding included.\n\n",
        DIMS[0] - 1,
        DIMS[1] - 1,
        DIMS[2] - 1,
        ours.iter().map(|i| format!("`{i}`")).collect::<Vec<_>>().join(", "),
    ));
    md.push_str(&reading(d));
    md.push_str(&super::super::context::options_as_run(&d.options));
    let count = |n: Option<usize>| n.map_or("-".to_string(), |n| n.to_string());
    let body: Vec<Vec<String>> = d
        .rows
        .iter()
        .map(|r| {
            vec![
                r.pattern.clone(),
                r.implementation.clone(),
                r.per_level.iter().map(|n| n.to_string()).collect::<Vec<_>>().join(" / "),
                r.triangles.to_string(),
                r.seam_boundary_edges.to_string(),
                format!("{} / {}", r.non_manifold_edges, r.non_manifold_vertices),
                r.misoriented_edges.to_string(),
                r.self_intersecting_pairs.to_string(),
                count(r.pinched),
                r.seam_triangles.to_string(),
                match r.seam_min_angle_deg {
                    None => "-".into(),
                    Some(angle) => format!(
                        "{:.2} / {:.2} / {:.2} / {:.1} / {angle:.1}°",
                        r.seam_aspect_mean, r.seam_aspect_median, r.seam_aspect_mean_off_samples, r.seam_aspect_max
                    ),
                },
                r.seam_zero_area.to_string(),
                format!("{:.1} [{:.1}-{:.1}]", r.time_ms.median, r.time_ms.min, r.time_ms.max),
            ]
        })
        .collect();
    md.push_str(&markdown_table(
        &[
            "levels",
            "implementation",
            "chunks per level",
            "triangles",
            "open seam edges",
            "non-manifold edges / vertices",
            "misoriented edges",
            "self-intersecting pairs",
            "pinched",
            "seam triangles",
            "seam aspect mean / median / mean off samples / max / smallest angle",
            "zero-area seam triangles",
            "ms",
        ],
        &body,
    ));
    if let Some(s) = &d.switch {
        let ours_times: Vec<String> =
            s.ours.iter().map(|(name, t)| format!("{name} {:.1} ms median [{:.1}-{:.1}]", t.median, t.min, t.max)).collect();
        md.push_str(&format!(
            "\n**Switching one chunk's level** (chunk {:?} of the viewer-distance pattern, level {} to {}): ours re-runs the \
             extraction on the {} chunks within one chunk of it: {}; the crate re-meshes the chunk and the face neighbours \
             whose transition faces change ({} chunks) in {:.1} ms [{:.1}-{:.1}].\n",
            s.chunk,
            s.from,
            s.to,
            s.ours_chunks,
            ours_times.join(", "),
            s.crate_chunks,
            s.crate_ms.median,
            s.crate_ms.min,
            s.crate_ms.max
        ));
    }
    if !d.picture.is_empty() {
        md.push_str(&format!(
            "\n![marching cubes, levels: full resolution green, half blue, quarter purple; right, a close-up of the seams]({})\n",
            d.picture
        ));
    }
    if !d.crate_picture.is_empty() {
        md.push_str(&format!(
            "\n![the same close-up: marching cubes' restriction and stitching left, the transvoxel crate right]({})\n",
            d.crate_picture
        ));
    }
    if !d.dual_picture.is_empty() {
        md.push_str(&format!(
            "\n![the same close-up: dual contouring left, manifold dual contouring (fans kept in cells) right]({})\n",
            d.dual_picture
        ));
    }
    md
}

/// Lines read off the rows: cracks and manifoldness per implementation, triangles kept by the
/// viewer pattern, and each of ours against the crate on the patterns with seams.
fn reading(d: &Data) -> String {
    if d.rows.is_empty() {
        return String::new();
    }
    let mut md = String::from("**Reading.**\n\n");
    let implementations = first_seen(d.rows.iter().map(|r| r.implementation.as_str()));
    for &implementation in &implementations {
        let rows: Vec<&Row> = d.rows.iter().filter(|r| r.implementation == implementation).collect();
        let open: usize = rows.iter().map(|r| r.seam_boundary_edges).sum();
        let non_manifold: usize = rows.iter().map(|r| r.non_manifold_edges + r.non_manifold_vertices).sum();
        let crossing: usize = rows.iter().map(|r| r.self_intersecting_pairs).sum();
        let pinched: usize = rows.iter().filter_map(|r| r.pinched).sum();
        // Pairs on the patterns with no seam between levels are the extractor's own mesh's.
        let without_seams: usize = rows.iter().filter(|r| r.seam_triangles == 0).map(|r| r.self_intersecting_pairs).sum();
        md.push_str(&format!(
            "- {implementation}: {}, {} over the {} patterns ({open} open seam edges, {non_manifold} non-manifold edges and \
             vertices, {crossing} self-intersecting pairs in all{}{}).\n",
            if open == 0 { "watertight" } else { "not watertight" },
            if non_manifold == 0 { "manifold" } else { "not manifold everywhere" },
            rows.len(),
            if crossing > 0 {
                format!(", {without_seams} of them on the patterns without seams, where every chunk is at one level")
            } else {
                String::new()
            },
            if pinched > 0 { format!("; {pinched} vertices pinched") } else { String::new() },
        ));
    }
    let find = |implementation: &str, pattern: usize| d.rows.iter().filter(|r| r.implementation == implementation).nth(pattern);
    for &implementation in &implementations {
        if let (Some(full), Some(near)) = (find(implementation, 0), find(implementation, 1)) {
            md.push_str(&format!(
                "- {implementation}: the viewer-distance pattern keeps {:.0} % of the full-resolution triangles.\n",
                100.0 * near.triangles as f64 / full.triangles.max(1) as f64
            ));
        }
    }
    // Each of ours against the crate on the patterns with seams between levels.
    let mixed: Vec<&str> =
        first_seen(d.rows.iter().filter(|r| r.seam_triangles > 0).map(|r| r.pattern.as_str())).into_iter().collect();
    for &implementation in implementations.iter().filter(|&&i| i != CRATE) {
        let pairs: Vec<(&Row, &Row)> = mixed
            .iter()
            .filter_map(|p| {
                let of = |i: &str| d.rows.iter().find(|r| r.implementation == i && r.pattern == *p);
                Some((of(implementation)?, of(CRATE)?))
            })
            .collect();
        if pairs.is_empty() {
            continue;
        }
        let ratios: Vec<String> = pairs.iter().map(|(o, c)| format!("{:.2}", o.time_ms.median / c.time_ms.median)).collect();
        let lower = |stat: fn(&Row) -> f64| pairs.iter().filter(|(o, c)| stat(o) < stat(c)).count();
        let ours_zero_area: usize = pairs.iter().map(|(o, _)| o.seam_zero_area).sum();
        let crate_zero_area: usize = pairs.iter().map(|(_, c)| c.seam_zero_area).sum();
        md.push_str(&format!(
            "- {implementation} against the crate on the {} patterns with seams between levels: time ratio {} (ours over \
             the crate's median); seam triangles better shaped (lower mean aspect ratio) on {} of them, lower median on \
             {}, lower mean off samples on {}; zero-area seam triangles {} against the crate's {}.\n",
            pairs.len(),
            ratios.join(", "),
            lower(|r| r.seam_aspect_mean),
            lower(|r| r.seam_aspect_median),
            lower(|r| r.seam_aspect_mean_off_samples),
            ours_zero_area,
            crate_zero_area,
        ));
    }
    md.push('\n');
    md
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(implementation: &str, pattern: &str, triangles: usize, open: usize, seam: usize, ms: f64, aspect: f64) -> Row {
        Row {
            implementation: implementation.into(),
            pattern: pattern.into(),
            per_level: vec![1],
            triangles,
            stitched: None,
            pinched: None,
            seam_boundary_edges: open,
            non_manifold_edges: 0,
            non_manifold_vertices: 0,
            misoriented_edges: 0,
            self_intersecting_pairs: 0,
            seam_triangles: seam,
            seam_zero_area: usize::from(implementation == CRATE),
            seam_aspect_mean: aspect,
            seam_aspect_median: 1.5,
            seam_aspect_max: aspect,
            seam_aspect_mean_off_samples: if implementation == CRATE { 1.1 } else { 1.2 },
            seam_min_angle_deg: None,
            time_ms: crate::report::Spread::of(vec![ms]),
        }
    }

    #[test]
    fn the_reading_follows_the_rows() {
        let mut d = Data {
            rows: Vec::new(),
            switch: None,
            picture: String::new(),
            crate_picture: String::new(),
            dual_picture: String::new(),
            options: Vec::new(),
        };
        assert_eq!(reading(&d), "");
        d.rows = vec![
            row("ours", "full", 100, 0, 0, 10.0, 1.0),
            row("ours", "near", 20, 0, 5, 10.0, 1.2),
            row(CRATE, "full", 100, 3, 0, 5.0, 1.0),
            row(CRATE, "near", 25, 0, 5, 5.0, 2.0),
        ];
        let r = reading(&d);
        assert!(r.starts_with("**Reading.**"), "{r}");
        assert!(r.contains("- ours: watertight, manifold over the 2 patterns"), "{r}");
        assert!(r.contains(&format!("- {CRATE}: not watertight")), "{r}");
        assert!(r.contains("- ours: the viewer-distance pattern keeps 20 % of the full-resolution triangles."), "{r}");
        assert!(
            r.contains(
                "time ratio 2.00 (ours over the crate's median); seam triangles better shaped (lower mean aspect ratio) on 1 \
                 of them, lower median on 0, lower mean off samples on 0; zero-area seam triangles 0 against the crate's 1."
            ),
            "{r}"
        );
    }
}
