//! `sphere_convergence`: relative volume and area error and vertex distance on the sphere as the
//! resolution doubles, for every extractor; a table and a log-log plot.

use super::context::{Context, Experiment, ExperimentError};
use crate::figures::color_of;
use crate::figures::plot::{self, Scale, Series, Style, XyPlot};
use crate::report::markdown_table;
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
        ctx.write_data(NAME, &Data { radius: 0.4, rows, plot: ctx.link(&stem.with_extension("svg")) })
    }

    fn section(&self, ctx: &Context) -> Result<String, ExperimentError> {
        let data: Data = ctx.read_data(NAME)?;
        let mut s = String::from("## Convergence on the sphere (`sphere_convergence`)\n\n");
        s.push_str(&format!(
            "Relative volume and area error against 4/3 π r³ and 4 π r² (r = {}), and vertex distance to the sphere in grid \
             spacings, as the resolution doubles. Second-order convergence shows as a slope of -2 on the log-log plot.\n\n",
            data.radius
        ));
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
