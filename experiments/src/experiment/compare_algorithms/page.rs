//! The page `report/compare_algorithms.md`, rendered from the data file alone.

use super::data::Data;
use super::reading;
use super::{leaves_domain, middle, NAME, TURNTABLE_FIELD};
use crate::experiment::context::{ms, Context, ExperimentError, Measured};
use crate::report::{first_seen, markdown_table};

/// The page, from the data file alone.
pub(super) fn section(ctx: &Context) -> Result<String, ExperimentError> {
    let data: Data = ctx.read_data(NAME)?;
    Ok(page_body(&data))
}

/// One row per algorithm over every input at the middle resolution: what a terrain engineer
/// choosing a mesher looks at first.
pub(super) fn summary(data: &Data) -> String {
    let mut algorithms: Vec<String> = Vec::new();
    for r in middle(data) {
        if !algorithms.contains(&r.algorithm) {
            algorithms.push(r.algorithm.clone());
        }
    }
    let median = |mut v: Vec<f64>| {
        v.sort_by(f64::total_cmp);
        if v.is_empty() {
            f64::NAN
        } else {
            v[v.len() / 2]
        }
    };
    let first = algorithms.first().cloned().unwrap_or_default();
    let triangles_of = |a: &str| -> f64 { middle(data).filter(|r| r.algorithm == a).map(|r| r.metrics.triangles as f64).sum() };
    let reference = triangles_of(&first).max(1.0);
    let rows: Vec<Vec<String>> = algorithms
        .iter()
        .map(|a| {
            let rows: Vec<&Measured> = middle(data).filter(|r| &r.algorithm == a).collect();
            let manifold = rows.iter().filter(|r| {
                let t = &r.metrics.topology;
                t.edge_manifold && t.vertex_manifold && t.oriented
            });
            vec![
                a.clone(),
                rows.len().to_string(),
                format!("{}/{}", manifold.count(), rows.len()),
                {
                    let i = data.intersections(a);
                    format!("{} / {}", i.middle_pairs, i.all_pairs)
                },
                format!("{:.2}", median(rows.iter().map(|r| r.metrics.quality.aspect_ratio.mean).collect())),
                format!("{:.1}", median(rows.iter().map(|r| r.metrics.quality.min_angle_deg).collect())),
                format!(
                    "{:.3}",
                    median(rows.iter().map(|r| r.metrics.surface_distance.map_or(f64::NAN, |d| d.mean / r.spacing)).collect())
                ),
                format!("{:.2}", median(rows.iter().map(|r| r.metrics.overdraw.overshading).collect())),
                format!("{:.2}", triangles_of(a) / reference),
                ms(median(rows.iter().map(|r| r.extraction_ms).collect())),
                {
                    let bare: Vec<f64> = rows.iter().filter_map(|r| r.without_field_ms).collect();
                    if bare.is_empty() {
                        "–".to_owned()
                    } else {
                        ms(median(bare))
                    }
                },
            ]
        })
        .collect();
    let mut s = markdown_table(
        &[
            "algorithm",
            "inputs",
            "manifold + oriented",
            "self-int. pairs: these inputs / every resolution",
            "median aspect mean",
            "median min angle",
            "median dist / h",
            "median overshading",
            format!("triangles vs {first}").as_str(),
            "median extract ms",
            "without field queries",
        ],
        &rows,
    );
    s.push_str(
        "\nMedians are over the inputs (so one bad field does not hide the rest); the triangle ratio sums every input. \
         \"Without field queries\" times the same extraction of the same sample values with the field withheld: an \
         extractor that asks the field for gradients (dual contouring's vertex placement) then takes them from the \
         samples' interpolant, so the difference is the time its field queries take.\n",
    );
    s.push_str(&settings_line(data));
    s
}

/// The options each extractor ran with, from the run's data (its defaults).
pub(super) fn settings_line(data: &Data) -> String {
    let said: Vec<String> =
        data.settings.iter().filter(|(_, s)| !s.is_empty()).map(|(name, s)| format!("`{name}`: {s}")).collect();
    if said.is_empty() {
        return String::new();
    }
    format!("\nEach extractor ran with its defaults: {}.\n", said.join("; "))
}

pub(super) fn yes(b: bool) -> &'static str {
    if b {
        "yes"
    } else {
        "**no**"
    }
}

/// "closed" for a mesh of a field: a defect (bold) only where the surface should close, that is
/// where the field is outside on every sample of its domain's boundary; a field whose surface
/// leaves its domain (terrain, gyroid: [`leaves_domain`]) is open by design, said without bold.
pub(super) fn closed_cell(closed: bool, open_by_design: bool) -> &'static str {
    match (closed, open_by_design) {
        (true, _) => "yes",
        (false, true) => "no (open by design)",
        (false, false) => "**no**",
    }
}

/// "watertight manifold" for a mesh of a field: open by design (not bold) where the field leaves
/// its domain and the mesh is manifold apart from its boundary; otherwise a defect.
pub(super) fn watertight_cell(t: &isolab_metrics::Topology, open_by_design: bool) -> &'static str {
    if t.is_watertight_manifold() {
        "yes"
    } else if t.edge_manifold && t.vertex_manifold && t.oriented && open_by_design {
        "no (open by design)"
    } else {
        "**no**"
    }
}

pub(super) fn page_body(data: &Data) -> String {
    // The fields whose surface leaves the domain, each sampled once.
    let open: Vec<String> =
        first_seen(data.rows.iter().map(|r| r.field.clone())).into_iter().filter(|f| leaves_domain(f)).collect();
    let mut s = String::from("## Comparing the algorithms (`compare_algorithms`)\n\n");
    let view = isolab_metrics::View::default();
    s.push_str(&format!(
        "Every registered extractor on every built-in field (at {:?} samples along the longest side) and every shipped model \
         (at {:?}), sampled once per resolution. Extraction time is the median of every run on the same samples, in rounds of {} \
         runs until a round's slowest run is within {}x its fastest (at most {} rounds; a time still spread wider is \
         marked *wide* with its fastest and slowest run). Meshes of the \
         gyroid and the terrain are cut by the domain, so they are open there by design. Distances are in grid spacings `h`; \
         *normal dev.* is the mean angle between vertex normals and the field's gradient; *overshading* is pixel-shader \
         invocations per covered pixel when GPUs shade 2x2 quads ({}x{}, early depth test; 1 is ideal).\n\n",
        data.field_levels,
        data.model_levels,
        data.repeats,
        crate::report::WIDE,
        crate::report::MAX_ROUNDS,
        view.width,
        view.height
    ));
    s.push_str(&reading::reading(data));
    s.push_str("### At a glance (middle resolution, every field and model)\n\n");
    s.push_str(&summary(data));
    s.push_str("\n### At the middle resolution\n\n");
    let rows: Vec<Vec<String>> = middle(data)
        .map(|r| {
            let m = &r.metrics;
            let t = &m.topology;
            vec![
                r.algorithm.clone(),
                r.field.clone(),
                format!("{}x{}x{}", r.dims[0], r.dims[1], r.dims[2]),
                m.triangles.to_string(),
                closed_cell(t.closed, open.contains(&r.field)).into(),
                yes(t.edge_manifold && t.vertex_manifold && t.oriented).into(),
                format!("{} / {}", t.euler, t.genus.map_or("-".into(), |g| g.to_string())),
                m.intersecting_pairs().to_string(),
                format!("{:.2} / {:.0}", m.quality.aspect_ratio.mean, m.quality.aspect_ratio.max),
                format!("{:.2}", m.quality.min_angle_deg),
                m.surface_distance.map_or("-".into(), |d| format!("{:.4}", d.mean / r.spacing)),
                m.normal_deviation.map_or("-".into(), |d| format!("{:.2}°", d.mean_deg)),
                r.analytic_volume.map_or("-".into(), |v| format!("{:+.3}%", 100.0 * (m.volume - v) / v)),
                format!("{:.2}", m.overdraw.overshading),
                format!("{}{}", ms(r.extraction_ms), r.extraction_runs.as_ref().map(|x| x.flag()).unwrap_or_default()),
            ]
        })
        .collect();
    s.push_str(&markdown_table(
        &[
            "algorithm",
            "field",
            "samples",
            "triangles",
            "closed",
            "manifold + oriented",
            "χ / genus",
            "self-int.",
            "aspect mean / max",
            "min angle",
            "dist / h",
            "normal dev.",
            "volume err.",
            "overshading",
            "extract ms",
        ],
        &rows,
    ));
    s.push_str("\n### Every resolution\n\n");
    let rows: Vec<Vec<String>> = data
        .rows
        .iter()
        .map(|r| {
            let m = &r.metrics;
            vec![
                r.algorithm.clone(),
                r.field.clone(),
                r.resolution.to_string(),
                m.triangles.to_string(),
                watertight_cell(&m.topology, open.contains(&r.field)).into(),
                m.topology.components.to_string(),
                m.topology.genus.map_or("-".into(), |g| g.to_string()),
                format!("{:.2}", m.quality.aspect_ratio.mean),
                format!("{:.2}", m.overdraw.overshading),
                format!("{:.1}", r.sampling_ms),
                format!("{}{}", ms(r.extraction_ms), r.extraction_runs.as_ref().map(|x| x.flag()).unwrap_or_default()),
                format!("{:.1}", m.triangles as f64 / (r.extraction_ms / 1e3).max(1e-12) / 1e6),
            ]
        })
        .collect();
    s.push_str(&markdown_table(
        &[
            "algorithm",
            "field",
            "resolution",
            "triangles",
            "watertight",
            "components",
            "genus",
            "aspect mean",
            "overshading",
            "sampling ms",
            "extract ms",
            "M tri/s",
        ],
        &rows,
    ));
    s.push_str(&format!(
        "\n### Figures\n\n![quality against cost]({})\n\n![overshading]({})\n\n![triangles]({})\n\n",
        data.scatter, data.overshading, data.bars
    ));
    for h in &data.histograms {
        s.push_str(&format!("![histogram]({h})\n\n"));
    }
    s.push_str("### Pictures (lowest resolution, flat shading with wireframe)\n\n");
    // Each algorithm once, in first-seen order (images are listed field by field, so the same
    // algorithm recurs non-adjacently: `Vec::dedup` kept every repeat, 91 columns for 7).
    let algorithms: Vec<String> = first_seen(data.images.iter().map(|i| i.0.clone()));
    let mut header = vec!["field".to_string()];
    header.extend(algorithms.iter().cloned());
    let fields_seen: Vec<String> = first_seen(data.images.iter().map(|i| i.1.clone()));
    let rows: Vec<Vec<String>> = fields_seen
        .iter()
        .map(|f| {
            let mut row = vec![f.clone()];
            for a in &algorithms {
                row.push(
                    data.images.iter().find(|i| &i.0 == a && &i.1 == f).map_or("-".into(), |i| format!("![{a} {f}]({})", i.2)),
                );
            }
            row
        })
        .collect();
    let header_refs: Vec<&str> = header.iter().map(String::as_str).collect();
    s.push_str(&markdown_table(&header_refs, &rows));
    for ((a, gif), (_, pair)) in data.turntables.iter().zip(&data.pairs) {
        s.push_str(&format!("\n{a} on the {TURNTABLE_FIELD}: turntable and flat (wireframe) against smooth shading\n\n![{a} turntable]({gif}) ![{a} flat and smooth]({pair})\n"));
    }
    s
}
