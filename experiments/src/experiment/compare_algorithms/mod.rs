//! `compare_algorithms`: every registered extractor on every built-in field and shipped model at
//! three resolutions: counts, quality, topology, accuracy, time and quad overshading; a table, a
//! quality-against-cost scatter plot, aspect-ratio and angle histograms, and rendered images.

mod data;
mod page;

use super::context::{
    compared_inputs as inputs, measure, time_without_field, without_field, Context, Experiment, ExperimentError, Measured,
    FIELD_LEVELS, MODEL_LEVELS,
};
use crate::figures::color_of;
use crate::figures::plot::{self, HistogramPlot, Scale, Series, Style, XyPlot};
use crate::report::Spread;
pub(crate) use data::Data;
use isolab_algorithms::{extractors, fields, Samples};
use isolab_metrics::Histogram;
use isolab_pipeline::{lattice_for, load_field, RunConfig};
use isolab_render::{render, save_png, save_turntable, side_by_side, RenderOptions, Shading};
use page::summary;

mod reading;

/// The experiment.
pub struct CompareAlgorithms;

const NAME: &str = "compare_algorithms";

/// The field shown turning.
const TURNTABLE_FIELD: &str = "asteroid";

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
        let bar = ctx.bar(NAME, (inputs.len() * ctx.sizes(&FIELD_LEVELS).len() * extractors.len()) as u64);
        let mut data = Data {
            field_levels: ctx.sizes(&FIELD_LEVELS).to_vec(),
            model_levels: ctx.sizes(&MODEL_LEVELS).to_vec(),
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
            let levels = ctx.sizes(levels);
            for (level, &resolution) in levels.iter().enumerate() {
                let lattice = lattice_for(field.as_ref(), &RunConfig::new("", spec, resolution))?;
                let samples = Samples::sample(field.clone(), lattice, 0.0)?;
                // The same values without the field, once per grid, for the middle resolution's split.
                let bare = if level == levels.len() / 2 { Some(without_field(&samples)?) } else { None };
                for extractor in &extractors {
                    bar.set_message(format!("{} {name} {resolution}", extractor.name()));
                    let (mut row, out) = measure(extractor.as_ref(), &field, &samples, ctx.repeats)?;
                    // At the middle resolution, the time without field queries too (the glance
                    // table's split), right after the runs above.
                    if let Some(bare) = bare.as_ref().filter(|_| !extractor.produces_volume()) {
                        row.without_field_ms = Some(time_without_field(extractor.as_ref(), bare, ctx.repeats)?);
                    }
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
        page::section(ctx)
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
        series.push(Series {
            label: e.name().to_owned(),
            color: color_of(e.name()),
            points: vec![(time, aspect)],
            ranges: Vec::new(),
        });
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
        data.middle_levels().0,
        data.middle_levels().1,
    ))
}

/// The algorithm's colour as a surface tint (lightened palette colour).
fn tint(name: &str) -> [f32; 3] {
    let (r, g, b) = color_of(name);
    [r, g, b].map(|c| 0.45 + 0.55 * f32::from(c) / 255.0)
}

fn middle(data: &Data) -> impl Iterator<Item = &Measured> {
    let (f, m) = data.middle_levels();
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
                ranges: Vec::new(),
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
        y_scale: plot::Scale::Linear,
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
