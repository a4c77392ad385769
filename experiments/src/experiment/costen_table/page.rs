//! The page `report/costen_table.md`, rendered from the data file alone.

use super::ablations::projection_section;
use super::counts;
use super::data::{Data, Row};
use super::ferreus::peer_section;
use super::passes::passes_section;
use super::questionnaire::questionnaire_section;
use super::reading::{differences, reading};
use super::sphere_match::{matched_section, sphere_radius};
use super::{METHODS, NAME, OBJECTS, PAPER, PAPER_CPU, PAPER_LOGICAL_PROCESSORS};
use crate::experiment::context::{load_object, Context, ExperimentError};
use crate::report::markdown_table;

/// The page, from the data file alone.
pub(super) fn section(ctx: &Context) -> Result<String, ExperimentError> {
    let data: Data = ctx.read_data(NAME)?;
    Ok(page_body(ctx, &data))
}

/// The smallest and largest fraction of plain marching tetrahedra's triangles that integrated
/// clustering removes, from the paper's own Appendix B counts (`*_bi` against `*_bu`, `*_si`
/// against `*_su`).
pub(super) fn paper_integrated_reduction() -> (f64, f64) {
    let triangles = |id: &str| PAPER.iter().find(|p| p.id == id).map(|p| p.n_triangles as f64);
    PAPER
        .iter()
        .filter_map(|p| {
            let stem = p.id.strip_suffix('i')?;
            Some(1.0 - p.n_triangles as f64 / triangles(&format!("{stem}u"))?)
        })
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), x| (lo.min(x), hi.max(x)))
}

/// The paper's edge scratch per sample on the simple cubic lattice (`B_edges` over the samples of
/// the first object's `*_su` row), bytes.
pub(super) fn paper_edge_bytes_per_sample() -> f64 {
    let (id, dims) = (format!("{}_su", OBJECTS[0].0), OBJECTS[0].2);
    PAPER.iter().find(|p| p.id == id).map_or(f64::NAN, |p| p.b_edges as f64 / dims.iter().product::<usize>() as f64)
}

/// The paper's mean `F_discard` (%) over the rows of one clustering (`i` or `p`): its text's
/// "average reduction of 79.53%" (integrated) and "72.20%" (post-processed), recomputed.
pub(super) fn paper_mean_discard(method: char) -> f64 {
    let v: Vec<f64> = PAPER.iter().filter(|p| p.id.ends_with(method)).map(|p| p.f_discard).collect();
    v.iter().sum::<f64>() / v.len().max(1) as f64
}

/// The range of the paper's mean aspect ratio over the rows of one clustering (`u`, `i`, `p`).
pub(super) fn paper_aspect_range(method: char) -> (f64, f64) {
    PAPER
        .iter()
        .filter(|p| p.id.ends_with(method))
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| (lo.min(p.ar_mean), hi.max(p.ar_mean)))
}

pub(super) fn pct(x: f64) -> String {
    format!("{:.1}%", 100.0 * x)
}

pub(super) fn num(x: f64) -> String {
    if x.abs() >= 100.0 {
        format!("{x:.0}")
    } else if x.abs() >= 10.0 {
        format!("{x:.1}")
    } else {
        format!("{x:.2}")
    }
}

/// "ours (paper)" or "ours" when the paper has no such row.
pub(super) fn pair(ours: String, paper: Option<String>) -> String {
    match paper {
        Some(p) => format!("{ours} ({p})"),
        None => ours,
    }
}

pub(super) fn f_discard(r: &Row) -> f64 {
    r.n_discarded as f64 / (r.n_discarded + r.n_triangles).max(1) as f64
}

pub(super) fn page_body(ctx: &Context, data: &Data) -> String {
    let mut md = String::from("## Regularised marching tetrahedra: the paper's benchmark (`costen_table`)\n\n");
    let cells = |dims: [usize; 3]| dims.map(|n| n - 1);
    let [cube, ..] = cells(OBJECTS[0].2);
    let [bx, by, bz] = cells(OBJECTS[2].2);
    let radius = load_object(OBJECTS[0].1).map_or(f64::NAN, |f| sphere_radius(f.as_ref(), 0.0));
    // What the collapse removes on the asteroid, ours and the paper's: one minus `bp` over `bu`.
    let ours_triangles = |id: &str| data.rows.iter().find(|r| r.id == id).map(|r| r.n_triangles as f64);
    let paper_triangles = |id: &str| PAPER.iter().find(|p| p.id == id).map(|p| p.n_triangles as f64);
    let removed = |bp: Option<f64>, bu: Option<f64>| match (bp, bu) {
        (Some(bp), Some(bu)) if bu > 0.0 => format!("{:.1}%", 100.0 * (1.0 - bp / bu)),
        _ => "-".to_string(),
    };
    let as_bp_ours = removed(ours_triangles("as_bp"), ours_triangles("as_bu"));
    let as_bp_paper = removed(paper_triangles("as_bp"), paper_triangles("as_bu"));
    let samples = |dims: [usize; 3]| dims.iter().product::<usize>().max(1) as f64;
    let (edge_lo, edge_hi) = data
        .rows
        .iter()
        .filter(|r| r.lattice == "cubic")
        .map(|r| r.b_edges as f64 / samples(r.dims))
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), b| (lo.min(b), hi.max(b)));
    md.push_str(&format!(
        "Appendix B of Costen (2026) regenerated: {} objects × two lattices (`b` BCC, `s` simple cubic, six tetrahedra per cube) × \
         {} clusterings (`u` none, `i` integrated as published, `p` plain marching tetrahedra then the paper's edge collapse; the \
         paper gives no threshold; ours is the post-process's default, {} h, a constant: on our asteroid it removes {as_bp_ours} of \
         the triangles, the paper's `as_bp` {as_bp_paper}), at {cube} cells a side (bunny {bx} × {by} × {bz}), {} interleaved runs each, medians. Each cell reads **ours (paper)**. \
         Rows `i+` are our RMT defaults (boundary samples merge; the manifold guard repairs what the local graph test misses), \
         rows `p+` the topology-safe edge collapse; the paper has neither. The objects are ours: a sphere of radius {radius:.2} in the unit \
         cube, our asteroid (a noise-displaced sphere, not the paper's), the bunny as a signed-distance field of the shipped \
         model; so counts compare in kind, not digit for digit. Times are from a shared machine (the paper: {PAPER_CPU} \
         with {PAPER_LOGICAL_PROCESSORS} logical processors, its sampling pass parallel on a thread count it does not state), B_edges is our per-sample scratch ({edge_lo:.1}-{edge_hi:.1} bytes a sample on the simple cubic lattice: vertex base, half-byte slots, two flags, packed signs, and the guard's buffers; the paper \
         stores {:.0}). F_discard is the paper's definition, discarded / (discarded + kept); `removed` is one minus triangles / \
         triangles of `u`.\n\n",
        OBJECTS.len(),
        METHODS.len() - 2,
        isolab_algorithms::post::edge_collapse::DEFAULT_THRESHOLD,
        data.repeats,
        paper_edge_bytes_per_sample(),
    ));
    let paper = |id: &str| PAPER.iter().find(|p| p.id == id);
    let rows = &data.rows;
    md.push_str(&reading(rows));
    md.push_str("### Counts\n\n");
    let body: Vec<Vec<String>> = rows
        .iter()
        .map(|r| {
            let p = paper(&r.id);
            vec![
                r.id.clone(),
                pair(r.n_tetrahedra.to_string(), p.map(|p| p.n_tetrahedra.to_string())),
                pair(r.n_vertices.to_string(), p.map(|p| p.n_vertices.to_string())),
                pair(r.n_triangles.to_string(), p.map(|p| p.n_triangles.to_string())),
                pair(r.n_discarded.to_string(), p.map(|p| p.n_discarded.to_string())),
                pair(pct(f_discard(r)), p.map(|p| format!("{:.1}%", p.f_discard))),
                pct(r.removed),
                pair(pct(r.n_tetrahedra as f64 / r.total_tetrahedra.max(1) as f64), p.map(|p| format!("{:.2}%", p.f_tetrahedra))),
            ]
        })
        .collect();
    md.push_str(&markdown_table(
        &["ID", "N_tetrahedra", "N_vertices", "N_triangles", "N_discarded", "F_discard", "removed", "F_tetrahedra"],
        &body,
    ));
    md.push_str(&counts::count_ratios(rows, |id| paper(id).copied()));
    md.push_str("\n### Times (ms)\n\n");
    let body: Vec<Vec<String>> = rows
        .iter()
        .map(|r| {
            let p = paper(&r.id);
            let total = r.t_sampling + r.t_vertex + r.t_geometry + r.t_normals + r.t_post;
            vec![
                r.id.clone(),
                pair(num(total), p.map(|p| num(p.t_total * 1e3))),
                pair(num(r.t_sampling), p.map(|p| num(p.t_sampling * 1e3))),
                pair(num(r.t_vertex), p.map(|p| num(p.t_vertex * 1e3))),
                pair(num(r.t_geometry + r.t_post), p.map(|p| num(p.t_geometry * 1e3))),
                num(r.t_post),
                format!(
                    "{:.0}% / {:.0}% / {:.0}%",
                    100.0 * r.t_sampling / total,
                    100.0 * r.t_vertex / total,
                    100.0 * (r.t_geometry + r.t_post) / total
                ),
            ]
        })
        .collect();
    md.push_str(&markdown_table(
        &[
            "ID",
            "T_total",
            "T_sampling",
            "T_vertex",
            "T_geometry (+ collapse)",
            "of which collapse",
            "F_sampling / F_vertex / F_geometry",
        ],
        &body,
    ));
    md.push_str("\n### Memory and triangle quality\n\n");
    let body: Vec<Vec<String>> = rows
        .iter()
        .map(|r| {
            let p = paper(&r.id);
            let q = &r.metrics.quality.aspect_ratio;
            vec![
                r.id.clone(),
                pair(r.b_lattice.to_string(), p.map(|p| p.b_lattice.to_string())),
                pair(r.b_edges.to_string(), p.map(|p| p.b_edges.to_string())),
                pair(r.b_vertices.to_string(), p.map(|p| p.b_vertices.to_string())),
                pair(r.b_indices.to_string(), p.map(|p| p.b_indices.to_string())),
                pair(num(q.mean), p.map(|p| num(p.ar_mean))),
                pair(num(q.sd), p.map(|p| num(p.ar_sd))),
                format!("{:.1}°", r.metrics.quality.min_angle_deg),
            ]
        })
        .collect();
    md.push_str(&markdown_table(
        &["ID", "B_lattice", "B_edges", "B_vertices", "B_indices", "AR_mean", "AR_sd", "min angle"],
        &body,
    ));
    md.push_str("\n### What the paper did not measure\n\n");
    let body: Vec<Vec<String>> = rows
        .iter()
        .map(|r| {
            let m = &r.metrics;
            let h = r.metrics.surface_distance.as_ref().map_or("-".into(), |d| format!("{:.3} h", d.mean / r.spacing));
            vec![
                r.id.clone(),
                if m.topology.closed { "yes" } else { "**no**" }.into(),
                if m.topology.is_watertight_manifold() { "yes".into() } else { format!("**no** ({} vertices)", r.defects) },
                m.topology.euler.to_string(),
                m.intersecting_pairs().to_string(),
                h,
                format!("{:.2}", m.overdraw.overshading),
            ]
        })
        .collect();
    md.push_str(&markdown_table(
        &[
            "ID",
            "closed",
            "manifold",
            "Euler",
            "self-intersecting pairs",
            "mean vertex distance to the surface",
            "quad overshading",
        ],
        &body,
    ));
    md.push_str(&passes_section(&data.pass_changes));
    md.push_str(&questionnaire_section());
    md.push_str(&matched_section(&data.matched_sphere));
    md.push_str(&projection_section(&data.projection));
    md.push_str(&peer_section(&data.peers));
    md.push_str(&differences(rows, &as_bp_ours, &as_bp_paper));
    md.push_str("\n| | | |\n|---|---|---|\n| ![triangles](figures/costen_table/triangles.png) | ![pass times](figures/costen_table/pass-times.png) | ![aspect ratio](figures/costen_table/aspect-ratio.png) |\n\n");
    for p in &data.pictures {
        md.push_str(&format!("![{0}]({1})\n\n_{0}_\n\n", p.caption, p.path));
    }
    let _ = ctx;
    md
}
