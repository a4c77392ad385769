//! `compare_algorithms`: every registered extractor on every built-in field and shipped model at
//! three resolutions: counts, quality, topology, accuracy, time and quad overshading; a table, a
//! quality-against-cost scatter plot, aspect-ratio and angle histograms, and rendered images.

use super::context::{
    compared_inputs as inputs, measure, ms, Context, Experiment, ExperimentError, Measured, FIELD_LEVELS, MODEL_LEVELS,
};
use crate::figures::color_of;
use crate::figures::plot::{self, HistogramPlot, Scale, Series, Style, XyPlot};
use crate::report::{first_seen, markdown_table, Spread};
use isolab_algorithms::{extractors, fields, Samples};
use isolab_metrics::Histogram;
use isolab_pipeline::{lattice_for, load_field, RunConfig};
use isolab_render::{render, save_png, save_turntable, side_by_side, RenderOptions, Shading};
use serde::{Deserialize, Serialize};

mod reading;

/// The experiment.
pub struct CompareAlgorithms;

const NAME: &str = "compare_algorithms";
/// The field shown turning.
const TURNTABLE_FIELD: &str = "asteroid";

#[derive(Serialize, Deserialize)]
pub(crate) struct Data {
    pub(crate) field_levels: Vec<usize>,
    pub(crate) model_levels: Vec<usize>,
    pub(crate) repeats: usize,
    pub(crate) rows: Vec<Measured>,
    /// (algorithm, field, image path relative to the report)
    pub(crate) images: Vec<(String, String, String)>,
    /// (algorithm, path) of turntable GIFs and flat/smooth pairs.
    pub(crate) turntables: Vec<(String, String)>,
    pub(crate) pairs: Vec<(String, String)>,
    pub(crate) scatter: String,
    pub(crate) overshading: String,
    pub(crate) bars: String,
    pub(crate) histograms: Vec<String>,
    /// Each extractor's options as it ran, in words (its `settings()`; absent from runs before
    /// they were recorded).
    #[serde(default)]
    pub(crate) settings: Vec<(String, String)>,
}

impl Experiment for CompareAlgorithms {
    fn name(&self) -> &'static str {
        NAME
    }

    fn question(&self) -> &'static str {
        "How do the extractors compare on every field and model in shape, topology, accuracy and cost?"
    }

    fn run(&self, ctx: &Context) -> Result<(), ExperimentError> {
        let dir = ctx.figure_dir(NAME)?;
        let extractors = extractors::registry();
        let inputs = inputs();
        let bar = ctx.bar(NAME, (inputs.len() * 3 * extractors.len()) as u64);
        let mut data = Data {
            field_levels: FIELD_LEVELS.to_vec(),
            model_levels: MODEL_LEVELS.to_vec(),
            repeats: ctx.repeats,
            rows: Vec::new(),
            images: Vec::new(),
            turntables: Vec::new(),
            pairs: Vec::new(),
            scatter: String::new(),
            overshading: String::new(),
            bars: String::new(),
            histograms: Vec::new(),
            settings: extractors.iter().map(|e| (e.name().to_owned(), e.settings())).collect(),
        };
        for (name, spec, levels) in &inputs {
            let field = load_field(spec, fields::DEFAULT_SEED)?;
            for (level, &resolution) in levels.iter().enumerate() {
                let lattice = lattice_for(field.as_ref(), &RunConfig::new("", spec, resolution))?;
                let samples = Samples::sample(field.clone(), lattice, 0.0)?;
                for extractor in &extractors {
                    bar.set_message(format!("{} {name} {resolution}", extractor.name()));
                    let (row, out) = measure(extractor.as_ref(), &field, &samples, ctx.repeats)?;
                    if level == 0 {
                        let path = dir.join(format!("{}-{name}.png", extractor.name()));
                        let opts = RenderOptions {
                            width: 360,
                            height: 360,
                            wireframe: true,
                            color: tint(extractor.name()),
                            ..Default::default()
                        };
                        save_png(&path, &render(&out.surface, &opts))?;
                        data.images.push((extractor.name().into(), name.clone(), ctx.link(&path)));
                        if name == TURNTABLE_FIELD {
                            let gif = dir.join(format!("{}-{name}-turntable.gif", extractor.name()));
                            save_turntable(&gif, &out.surface, &RenderOptions { width: 240, height: 240, ..opts }, 24, 12)?;
                            data.turntables.push((extractor.name().into(), ctx.link(&gif)));
                            let pair = dir.join(format!("{}-{name}-flat-smooth.png", extractor.name()));
                            let smooth =
                                render(&out.surface, &RenderOptions { shading: Shading::Smooth, wireframe: false, ..opts });
                            save_png(&pair, &side_by_side(&render(&out.surface, &opts), &smooth))?;
                            data.pairs.push((extractor.name().into(), ctx.link(&pair)));
                        }
                    }
                    data.rows.push(row);
                    bar.inc(1);
                }
            }
        }
        bar.finish_with_message("done");
        figures(ctx, &dir, &mut data)?;
        ctx.write_data(NAME, &data)
    }

    fn section(&self, ctx: &Context) -> Result<String, ExperimentError> {
        let data: Data = ctx.read_data(NAME)?;
        Ok(section(&data))
    }
}

/// The at-a-glance table (middle resolution, one row per extractor), for the front page.
pub fn glance(ctx: &Context) -> Result<String, ExperimentError> {
    let data: Data = ctx.read_data(NAME)?;
    Ok(summary(&data))
}

/// The front page's figure, drawn at assembly from the data: one point per extractor, the median
/// over the middle-resolution inputs of its extraction time against the median of its mean
/// aspect ratio (the glance table's two columns). Returns the Markdown that shows it.
pub fn front_figure(ctx: &Context) -> Result<String, ExperimentError> {
    let data: Data = ctx.read_data(NAME)?;
    let mut series = Vec::new();
    let mut inputs = 0;
    for e in extractors::registry() {
        let rows: Vec<&Measured> = middle(&data).filter(|r| r.algorithm == e.name()).collect();
        if rows.is_empty() {
            continue;
        }
        inputs = inputs.max(rows.len());
        let time = Spread::of(rows.iter().map(|r| r.extraction_ms).collect()).median;
        let aspect = Spread::of(rows.iter().map(|r| r.metrics.quality.aspect_ratio.mean).collect()).median;
        series.push(Series { label: e.name().to_owned(), color: color_of(e.name()), points: vec![(time, aspect)] });
    }
    let chart = XyPlot {
        title: "Every extractor: triangle quality against extraction time".into(),
        x_label: "median extraction time, ms".into(),
        y_label: "median mean aspect ratio (1 is ideal)".into(),
        x_scale: Scale::Log,
        y_scale: Scale::Linear,
        style: Style::Scatter,
        series,
    };
    let stem = ctx.figure_dir("front")?.join("quality-cost");
    plot::xy(&stem, &chart).map_err(ExperimentError::Figure)?;
    Ok(format!(
        "![Every extractor: triangle quality against extraction time]({})\n\n_Each point is one extractor: the median, over \
         the {inputs} inputs at the middle resolution (fields at {}³ samples, models at {}³), of its extraction time and of \
         its triangles' mean aspect ratio; lower and to the left is better. Every input's point is in \
         [compare_algorithms](compare_algorithms.md)._\n\n",
        ctx.link(&stem.with_extension("png")),
        data.field_levels[1],
        data.model_levels[1],
    ))
}

/// The algorithm's colour as a surface tint (lightened palette colour).
fn tint(name: &str) -> [f32; 3] {
    let (r, g, b) = color_of(name);
    [r, g, b].map(|c| 0.45 + 0.55 * f32::from(c) / 255.0)
}

fn middle(data: &Data) -> impl Iterator<Item = &Measured> {
    let (f, m) = (data.field_levels[1], data.model_levels[1]);
    data.rows.iter().filter(move |r| {
        let is_field = fields::registry().iter().any(|x| x.name == r.field);
        let level = if is_field { f } else { m };
        // Rows record the largest dimension, which is the requested resolution.
        r.resolution == level
    })
}

fn figures(ctx: &Context, dir: &std::path::Path, data: &mut Data) -> Result<(), ExperimentError> {
    let algorithms: Vec<&'static str> = extractors::registry().iter().map(|e| e.name()).collect();
    let series = |f: &dyn Fn(&Measured) -> (f64, f64)| -> Vec<Series> {
        algorithms
            .iter()
            .map(|a| Series {
                label: a.to_string(),
                color: color_of(a),
                points: middle(data).filter(|r| r.algorithm == *a).map(f).collect(),
            })
            .collect()
    };
    let scatter = XyPlot {
        title: "Quality against cost (every field and model, middle resolution)".into(),
        x_label: "extraction time, ms (median)".into(),
        y_label: "mean Verdict aspect ratio (1 is ideal)".into(),
        x_scale: Scale::Log,
        y_scale: Scale::Log,
        style: Style::Scatter,
        series: series(&|r| (r.extraction_ms, r.metrics.quality.aspect_ratio.mean)),
    };
    let stem = dir.join("quality-vs-cost");
    plot::xy(&stem, &scatter).map_err(ExperimentError::Figure)?;
    let scatter_link = ctx.link(&stem.with_extension("svg"));
    let over = XyPlot {
        title: "Rendering cost: quad overshading against triangle count".into(),
        x_label: "triangles".into(),
        y_label: "shader invocations per covered pixel (1 is ideal)".into(),
        x_scale: Scale::Log,
        y_scale: Scale::Linear,
        style: Style::Scatter,
        series: series(&|r| (r.metrics.triangles as f64, r.metrics.overdraw.overshading)),
    };
    let stem = dir.join("overshading");
    plot::xy(&stem, &over).map_err(ExperimentError::Figure)?;
    let over_link = ctx.link(&stem.with_extension("svg"));
    let categories: Vec<String> = {
        let mut c: Vec<String> = Vec::new();
        for r in middle(data) {
            if !c.contains(&r.field) {
                c.push(r.field.clone());
            }
        }
        c
    };
    let per_field = |a: &str, f: &dyn Fn(&Measured) -> f64| -> Vec<f64> {
        categories.iter().map(|c| middle(data).find(|r| r.algorithm == a && &r.field == c).map_or(f64::NAN, f)).collect()
    };
    let chart = plot::BarChart {
        title: "Triangles per mesh (middle resolution)".into(),
        y_label: "triangles".into(),
        categories: categories.clone(),
        series: algorithms
            .iter()
            .map(|a| plot::BarSeries {
                label: a.to_string(),
                color: color_of(a),
                values: per_field(a, &|r| r.metrics.triangles as f64),
            })
            .collect(),
    };
    let stem = dir.join("triangles");
    plot::bars(&stem, &chart).map_err(ExperimentError::Figure)?;
    let bars_link = ctx.link(&stem.with_extension("svg"));
    let mut histogram_links = Vec::new();
    for (key, title, x_label) in [
        ("aspect", "Verdict aspect ratio of all triangles (middle resolution)", "aspect ratio"),
        ("min-angle", "Smallest angle of all triangles (middle resolution)", "degrees"),
    ] {
        let plot = HistogramPlot {
            title: title.into(),
            x_label: x_label.into(),
            series: algorithms
                .iter()
                .filter_map(|a| {
                    let hists = middle(data).filter(|r| r.algorithm == *a).map(|r| match key {
                        "aspect" => &r.metrics.histograms.aspect_ratio,
                        _ => &r.metrics.histograms.min_angle_deg,
                    });
                    merge(hists).map(|h| (a.to_string(), color_of(a), h))
                })
                .collect(),
        };
        let stem = dir.join(format!("histogram-{key}"));
        plot::histogram(&stem, &plot).map_err(ExperimentError::Figure)?;
        histogram_links.push(ctx.link(&stem.with_extension("svg")));
    }
    data.scatter = scatter_link;
    data.bars = bars_link;
    data.overshading = over_link;
    data.histograms = histogram_links;
    Ok(())
}

/// Sums histograms with the same bins.
fn merge<'a>(mut hists: impl Iterator<Item = &'a Histogram>) -> Option<Histogram> {
    let mut acc = hists.next()?.clone();
    for h in hists {
        for (a, b) in acc.counts.iter_mut().zip(&h.counts) {
            *a += b;
        }
        acc.below += h.below;
        acc.above += h.above;
    }
    Some(acc)
}

/// One row per algorithm over every input at the middle resolution: what a terrain engineer
/// choosing a mesher looks at first.
fn summary(data: &Data) -> String {
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
                rows.iter().map(|r| r.metrics.intersecting_pairs()).sum::<usize>().to_string(),
                format!("{:.2}", median(rows.iter().map(|r| r.metrics.quality.aspect_ratio.mean).collect())),
                format!("{:.1}", median(rows.iter().map(|r| r.metrics.quality.min_angle_deg).collect())),
                format!(
                    "{:.3}",
                    median(rows.iter().map(|r| r.metrics.surface_distance.map_or(f64::NAN, |d| d.mean / r.spacing)).collect())
                ),
                format!("{:.2}", median(rows.iter().map(|r| r.metrics.overdraw.overshading).collect())),
                format!("{:.2}", triangles_of(a) / reference),
                ms(median(rows.iter().map(|r| r.extraction_ms).collect())),
            ]
        })
        .collect();
    let mut s = markdown_table(
        &[
            "algorithm",
            "inputs",
            "manifold + oriented",
            "self-int. pairs (all)",
            "median aspect mean",
            "median min angle",
            "median dist / h",
            "median overshading",
            format!("triangles vs {first}").as_str(),
            "median extract ms",
        ],
        &rows,
    );
    s.push_str("\nMedians are over the inputs (so one bad field does not hide the rest); the triangle ratio sums every input.\n");
    s.push_str(&settings_line(data));
    s
}

/// The options each extractor ran with, from the run's data (its defaults).
fn settings_line(data: &Data) -> String {
    let said: Vec<String> =
        data.settings.iter().filter(|(_, s)| !s.is_empty()).map(|(name, s)| format!("`{name}`: {s}")).collect();
    if said.is_empty() {
        return String::new();
    }
    format!("\nEach extractor ran with its defaults: {}.\n", said.join("; "))
}

fn yes(b: bool) -> &'static str {
    if b {
        "yes"
    } else {
        "**no**"
    }
}

/// "closed" for a mesh of a field: a defect (bold) only where the surface should close, that is
/// where the field is outside on every sample of its domain's boundary; a field whose surface
/// leaves its domain (terrain, gyroid: [`leaves_domain`]) is open by design, said without bold.
fn closed_cell(closed: bool, open_by_design: bool) -> &'static str {
    match (closed, open_by_design) {
        (true, _) => "yes",
        (false, true) => "no (open by design)",
        (false, false) => "**no**",
    }
}

/// "watertight manifold" for a mesh of a field: open by design (not bold) where the field leaves
/// its domain and the mesh is manifold apart from its boundary; otherwise a defect.
fn watertight_cell(t: &isolab_metrics::Topology, open_by_design: bool) -> &'static str {
    if t.is_watertight_manifold() {
        "yes"
    } else if t.edge_manifold && t.vertex_manifold && t.oriented && open_by_design {
        "no (open by design)"
    } else {
        "**no**"
    }
}

/// Whether a built-in field is inside somewhere on its domain's boundary (sampled on a 33-sample
/// grid's boundary layer); shipped models and unknown names are closed inside their domains.
fn leaves_domain(field: &str) -> bool {
    let Ok(f) = isolab_algorithms::fields::builtin(field, Default::default()) else { return false };
    let Ok(grid) = isolab_algorithms::Grid::covering(&f.domain(), 33) else { return false };
    let [nx, ny, nz] = grid.dims;
    (0..nz).any(|z| {
        (0..ny).any(|y| {
            (0..nx).any(|x| {
                let border = x == 0 || y == 0 || z == 0 || x == nx - 1 || y == ny - 1 || z == nz - 1;
                border && f.value(grid.position(x, y, z)) < 0.0
            })
        })
    })
}

fn section(data: &Data) -> String {
    // The fields whose surface leaves the domain, each sampled once.
    let open: Vec<String> =
        first_seen(data.rows.iter().map(|r| r.field.clone())).into_iter().filter(|f| leaves_domain(f)).collect();
    let mut s = String::from("## Comparing the algorithms (`compare_algorithms`)\n\n");
    let view = isolab_metrics::View::default();
    s.push_str(&format!(
        "Every registered extractor on every built-in field (at {:?} samples along the longest side) and every shipped model \
         (at {:?}), sampled once per resolution. Extraction time is the median of {} runs on the same samples. Meshes of the \
         gyroid and the terrain are cut by the domain, so they are open there by design. Distances are in grid spacings `h`; \
         *normal dev.* is the mean angle between vertex normals and the field's gradient; *overshading* is pixel-shader \
         invocations per covered pixel when GPUs shade 2x2 quads ({}x{}, early depth test; 1 is ideal).\n\n",
        data.field_levels, data.model_levels, data.repeats, view.width, view.height
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
                ms(r.extraction_ms),
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
                ms(r.extraction_ms),
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
