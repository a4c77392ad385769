//! `sphere_convergence`: relative volume and area error and vertex distance on the sphere as the
//! resolution doubles, for every extractor; a table and a log-log plot.

mod data;
mod page;

use super::context::{Context, Experiment, ExperimentError};
use crate::figures::color_of;
use crate::figures::plot::{self, Scale, Series, Style, XyPlot};
pub(crate) use data::{Data, Row};
use isolab_algorithms::{extractors, fields, Extraction, Samples};
use isolab_pipeline::{lattice_for, RunConfig};

/// The experiment.
pub struct SphereConvergence;

const NAME: &str = "sphere_convergence";

const RESOLUTIONS: [usize; 5] = [16, 32, 64, 128, 256];

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
                ranges: Vec::new(),
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
        page::section(ctx)
    }
}

/// The log-log slope of an error that falls with the square of the spacing.
const SECOND_ORDER_SLOPE: f64 = -2.0;

/// How near that slope a volume error's log-log slope must be to read as second order.
const SECOND_ORDER_TOLERANCE: f64 = 0.25;

#[cfg(test)]
mod tests {
    use super::page::reading;
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
