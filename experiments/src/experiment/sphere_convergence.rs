//! `sphere_convergence`: relative volume and area error and vertex distance on the sphere as the
//! resolution doubles, for every extractor; a table and a log-log plot.

use super::context::{Context, Experiment, ExperimentError};
use crate::figures::color_of;
use crate::figures::plot::{self, Scale, Series, Style, XyPlot};
use crate::report::{log_slope, markdown_table};
use isolab_algorithms::{extractors, fields, Extraction, Samples};
use isolab_pipeline::{lattice_for, RunConfig};
use serde::{Deserialize, Serialize};

/// The experiment.
pub struct SphereConvergence;

const NAME: &str = "sphere_convergence";
const RESOLUTIONS: [usize; 5] = [16, 32, 64, 128, 256];

#[derive(Serialize, Deserialize)]
pub(crate) struct Row {
    pub(crate) algorithm: String,
    pub(crate) resolution: usize,
    pub(crate) triangles: usize,
    pub(crate) volume_error: f64,
    pub(crate) area_error: f64,
    pub(crate) mean_distance_over_spacing: f64,
    pub(crate) max_distance_over_spacing: f64,
}

#[derive(Serialize, Deserialize)]
pub(crate) struct Data {
    /// Each extractor's options as it ran (absent from runs before they were recorded).
    #[serde(default)]
    pub(crate) settings: Vec<(String, String)>,
    pub(crate) radius: f64,
    pub(crate) rows: Vec<Row>,
    pub(crate) plot: String,
}

impl Experiment for SphereConvergence {
    fn name(&self) -> &'static str {
        NAME
    }

    fn question(&self) -> &'static str {
        "How fast does each extractor's error on the sphere shrink as the grid gets finer?"
    }

    fn run(&self, ctx: &Context) -> Result<(), ExperimentError> {
        let field = fields::builtin("sphere", Default::default())?;
        let (v, a) = (field.analytic_volume(0.0).unwrap_or(1.0), field.analytic_area(0.0).unwrap_or(1.0));
        // Isosurface accuracy: volume extractors (bcc-sculpt encloses at its own spacing) are left out.
        let extractors: Vec<_> = extractors::registry().into_iter().filter(|e| !e.produces_volume()).collect();
        let bar = ctx.bar(NAME, (RESOLUTIONS.len() * extractors.len()) as u64);
        let mut rows = Vec::new();
        for n in RESOLUTIONS {
            let lattice = lattice_for(field.as_ref(), &RunConfig::new("", "sphere", n))?;
            let spacing = f64::from(lattice.grid().spacing);
            let samples = Samples::sample(field.clone(), lattice, 0.0)?;
            for e in &extractors {
                let mut out = Extraction::default();
                e.extract(&samples, &mut out)?;
                let d = isolab_metrics::surface_distance(&out.surface, field.as_ref(), 0.0);
                rows.push(Row {
                    algorithm: e.name().into(),
                    resolution: n,
                    triangles: out.surface.triangles.len(),
                    volume_error: (isolab_metrics::signed_volume(&out.surface) - v) / v,
                    area_error: (isolab_metrics::surface_area(&out.surface) - a) / a,
                    mean_distance_over_spacing: d.mean / spacing,
                    max_distance_over_spacing: d.max / spacing,
                });
                bar.inc(1);
            }
        }
        bar.finish_with_message("done");
        let stem = ctx.figure_dir(NAME)?.join("volume-error");
        let series = extractors
            .iter()
            .map(|e| Series {
                label: e.name().into(),
                color: color_of(e.name()),
                points: rows
                    .iter()
                    .filter(|r| r.algorithm == e.name())
                    .map(|r| (r.resolution as f64, r.volume_error.abs()))
                    .collect(),
            })
            .collect();
        let plot = XyPlot {
            title: "Sphere: relative volume error against resolution".into(),
            x_label: "samples along the side".into(),
            y_label: "|volume error| / exact volume".into(),
            x_scale: Scale::Log,
            y_scale: Scale::Log,
            style: Style::Lines,
            series,
        };
        plot::xy(&stem, &plot).map_err(ExperimentError::Figure)?;
        let settings = super::context::settings_of(extractors.iter().map(|e| &**e));
        ctx.write_data(NAME, &Data { settings, radius: 0.4, rows, plot: ctx.link(&stem.with_extension("svg")) })
    }

    fn section(&self, ctx: &Context) -> Result<String, ExperimentError> {
        let data: Data = ctx.read_data(NAME)?;
        let mut s = String::from("## Convergence on the sphere (`sphere_convergence`)\n\n");
        s.push_str(&format!(
            "Relative volume and area error against 4/3 π r³ and 4 π r² (r = {}), and vertex distance to the sphere in grid \
             spacings, as the resolution doubles. Second-order convergence shows as a slope of -2 on the log-log plot.\n\n",
            data.radius
        ));
        s.push_str(&reading(&data.rows));
        s.push_str(&super::context::options_as_run(&data.settings));
        let rows: Vec<Vec<String>> = data
            .rows
            .iter()
            .map(|r| {
                vec![
                    r.algorithm.clone(),
                    r.resolution.to_string(),
                    r.triangles.to_string(),
                    format!("{:+.4}%", 100.0 * r.volume_error),
                    format!("{:+.4}%", 100.0 * r.area_error),
                    format!("{:.4}", r.mean_distance_over_spacing),
                    format!("{:.4}", r.max_distance_over_spacing),
                ]
            })
            .collect();
        s.push_str(&markdown_table(
            &["algorithm", "resolution", "triangles", "volume error", "area error", "mean dist / h", "max dist / h"],
            &rows,
        ));
        s.push_str(&format!("\n![volume error]({})\n", data.plot));
        Ok(s)
    }
}

/// The log-log slope of an error that falls with the square of the spacing.
const SECOND_ORDER_SLOPE: f64 = -2.0;

/// How near that slope a volume error's log-log slope must be to read as second order.
const SECOND_ORDER_TOLERANCE: f64 = 0.25;

/// What the table shows, worded from it: each extractor's order of convergence (the log-log
/// slope of its volume error against resolution), which side of the exact volume it stays on,
/// and the largest error at the finest resolution, with each extractor's settings.
fn reading(rows: &[Row]) -> String {
    let names: Vec<&str> = crate::report::first_seen(rows.iter().map(|r| r.algorithm.as_str()));
    fn of<'a>(rows: &'a [Row], name: &'a str) -> impl Iterator<Item = &'a Row> + 'a {
        rows.iter().filter(move |r| r.algorithm == name)
    }
    let slopes: Vec<(&str, f64)> = names
        .iter()
        .filter_map(|&n| {
            Some((n, log_slope(&of(rows, n).map(|r| (r.resolution as f64, r.volume_error.abs())).collect::<Vec<_>>())?))
        })
        .collect();
    let (second, other): (Vec<_>, Vec<_>) =
        slopes.iter().partition(|(_, s)| (s - SECOND_ORDER_SLOPE).abs() <= SECOND_ORDER_TOLERANCE);
    let list = |v: &[&(&str, f64)]| v.iter().map(|(n, s)| format!("{n} {s:.2}")).collect::<Vec<_>>().join(", ");
    let mut lines = Vec::new();
    if !second.is_empty() {
        lines.push(format!(
            "Second order (a volume-error slope within {SECOND_ORDER_TOLERANCE} of {SECOND_ORDER_SLOPE} over the resolutions): {}.",
            list(&second)
        ));
    }
    if !other.is_empty() {
        lines.push(format!("Not second order: {}.", list(&other)));
    }
    let side = |sign: f64| -> Vec<&str> {
        names.iter().copied().filter(|&n| of(rows, n).all(|r| r.volume_error * sign > 0.0)).collect()
    };
    let (below, above) = (side(-1.0), side(1.0));
    if !below.is_empty() {
        lines.push(format!("Below the exact volume at every resolution: {}.", below.join(", ")));
    }
    if !above.is_empty() {
        lines.push(format!("Above it at every resolution: {}.", above.join(", ")));
    }
    let finest = rows.iter().map(|r| r.resolution).max().unwrap_or(0);
    if let Some(worst) =
        rows.iter().filter(|r| r.resolution == finest).max_by(|a, b| a.volume_error.abs().total_cmp(&b.volume_error.abs()))
    {
        let settings = isolab_algorithms::extractors::by_name(&worst.algorithm).map(|e| e.settings()).unwrap_or_default();
        lines.push(format!(
            "The largest volume error at {finest} samples is that of {}, {:+.4}%{}.",
            worst.algorithm,
            100.0 * worst.volume_error,
            if settings.is_empty() { String::new() } else { format!(" (it runs with its defaults: {settings})") }
        ));
    }
    format!("**Reading.** {}\n\n", lines.join(" "))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(algorithm: &str, resolution: usize, volume_error: f64) -> Row {
        Row {
            algorithm: algorithm.into(),
            resolution,
            triangles: 0,
            volume_error,
            area_error: 0.0,
            mean_distance_over_spacing: 0.0,
            max_distance_over_spacing: 0.0,
        }
    }

    #[test]
    fn the_reading_follows_the_numbers() {
        let rows = vec![
            row("a", 16, -0.04),
            row("a", 32, -0.01),
            row("a", 64, -0.0025),
            row("b", 16, 0.02),
            row("b", 32, 0.01),
            row("b", 64, 0.005),
        ];
        let r = reading(&rows);
        assert!(r.contains("Second order (a volume-error slope within 0.25 of -2 over the resolutions): a -2.00."), "{r}");
        assert!(r.contains("Not second order: b -1.00."), "{r}");
        assert!(
            r.contains("Below the exact volume at every resolution: a.") && r.contains("Above it at every resolution: b."),
            "{r}"
        );
        assert!(r.contains("The largest volume error at 64 samples is that of b, +0.5000%"), "{r}");
    }
}
