//! `sharp_features`: how close each extractor comes to the seven box corners of the `csg` field
//! (the one that a sphere does not bite away), at three resolutions, in grid spacings; with a
//! picture of each extractor's csg at the lowest resolution. Dual contouring places vertices from
//! the field's normals and should land on the corners; the others cut them.

use super::context::{corner_distances_h, Context, Experiment, ExperimentError};
use crate::report::markdown_table;
use isolab_algorithms::{extractors, fields, Extraction, Grid, Lattice, Samples, Vec3};
use isolab_render::{render, save_png, RenderOptions};
use serde::{Deserialize, Serialize};

/// A corner the mesh comes within this many grid spacings of counts as kept (dual contouring's
/// promise on `csg`); the front page's sharp-CAD pick uses it too.
pub(crate) const CORNER_KEPT_H: f64 = 0.05;

/// The experiment.
pub struct SharpFeatures;

const NAME: &str = "sharp_features";
const RESOLUTIONS: [usize; 3] = [32, 64, 128];

#[derive(Serialize, Deserialize)]
pub(crate) struct Row {
    pub(crate) algorithm: String,
    pub(crate) resolution: usize,
    pub(crate) worst_corner_h: f64,
    pub(crate) mean_corner_h: f64,
    pub(crate) self_intersections: usize,
    pub(crate) manifold: bool,
}

#[derive(Serialize, Deserialize)]
pub(crate) struct Data {
    pub(crate) rows: Vec<Row>,
    pub(crate) images: Vec<(String, String)>,
    /// Each extractor's options as it ran (absent from runs before they were recorded).
    #[serde(default)]
    pub(crate) settings: Vec<(String, String)>,
}

impl Experiment for SharpFeatures {
    fn name(&self) -> &'static str {
        NAME
    }

    fn question(&self) -> &'static str {
        "Which extractors keep a CAD shape's sharp corners?"
    }

    fn run(&self, ctx: &Context) -> Result<(), ExperimentError> {
        let dir = ctx.figure_dir(NAME)?;
        let field = fields::builtin("csg", Default::default())?;
        // Isosurface accuracy: volume extractors (bcc-sculpt encloses at its own spacing) are left out.
        let all: Vec<_> = extractors::registry().into_iter().filter(|e| !e.produces_volume()).collect();
        let bar = ctx.bar(NAME, (RESOLUTIONS.len() * all.len()) as u64);
        let (mut rows, mut images) = (Vec::new(), Vec::new());
        for n in RESOLUTIONS {
            let grid = Grid::covering(&field.domain(), n)?;
            let samples = Samples::sample(field.clone(), Lattice::Cubic(grid), 0.0)?;
            for e in &all {
                let mut out = Extraction::default();
                e.extract(&samples, &mut out)?;
                let d = corner_distances_h(&out.surface, grid.spacing);
                let t = isolab_metrics::topology(&out.surface);
                rows.push(Row {
                    algorithm: e.name().into(),
                    resolution: n,
                    worst_corner_h: d.iter().copied().fold(0.0, f64::max),
                    mean_corner_h: d.iter().sum::<f64>() / d.len() as f64,
                    self_intersections: isolab_metrics::self_intersections(&out.surface).count,
                    manifold: t.is_watertight_manifold(),
                });
                if n == RESOLUTIONS[0] {
                    let path = dir.join(format!("{}-csg.png", e.name()));
                    let opts = RenderOptions {
                        width: 320,
                        height: 320,
                        wireframe: true,
                        view: Vec3::new(-1.0, 0.9, -1.2),
                        ..Default::default()
                    };
                    save_png(&path, &render(&out.surface, &opts))?;
                    images.push((e.name().to_string(), ctx.link(&path)));
                }
                bar.inc(1);
            }
        }
        bar.finish_with_message("done");
        let settings = super::context::settings_of(all.iter().map(|e| &**e));
        ctx.write_data(NAME, &Data { rows, images, settings })
    }

    fn section(&self, ctx: &Context) -> Result<String, ExperimentError> {
        let data: Data = ctx.read_data(NAME)?;
        let mut s = String::from("## Sharp features (`sharp_features`)\n\n");
        s.push_str(
            "Distance from each of the seven sharp box corners of `csg` to the nearest vertex, in grid spacings (worst and mean \
             over the corners), with the mesh's self-intersecting triangle pairs and whether it is watertight and manifold.\n\n",
        );
        s.push_str(&reading(&data.rows));
        s.push_str(&super::context::options_as_run(&data.settings));
        let rows: Vec<Vec<String>> = data
            .rows
            .iter()
            .map(|r| {
                vec![
                    r.algorithm.clone(),
                    r.resolution.to_string(),
                    format!("{:.4}", r.worst_corner_h),
                    format!("{:.4}", r.mean_corner_h),
                    r.self_intersections.to_string(),
                    if r.manifold { "yes".into() } else { "**no**".into() },
                ]
            })
            .collect();
        s.push_str(&markdown_table(
            &["algorithm", "resolution", "worst corner / h", "mean corner / h", "self-int.", "watertight"],
            &rows,
        ));
        s.push_str("\nThe csg part at the lowest resolution, seen from the side away from the sphere's bite:\n\n");
        let header: Vec<&str> = data.images.iter().map(|(a, _)| a.as_str()).collect();
        let row: Vec<String> = data.images.iter().map(|(a, p)| format!("![{a}]({p})")).collect();
        s.push_str(&markdown_table(&header, &[row]));
        Ok(s)
    }
}

/// What the table shows, worded from its rows: who keeps every corner at the finest resolution
/// (and of those, who stays clean), who never does, and whose corner error shrinks in grid
/// spacings as the grid refines.
fn reading(rows: &[Row]) -> String {
    let Some(finest) = rows.iter().map(|r| r.resolution).max() else { return String::new() };
    let coarsest = rows.iter().map(|r| r.resolution).min().unwrap_or(finest);
    let names: Vec<&str> = crate::report::first_seen(rows.iter().map(|r| r.algorithm.as_str()));
    let at = |name: &str, n: usize| rows.iter().find(|r| r.algorithm == name && r.resolution == n);
    let keeps: Vec<&str> =
        names.iter().copied().filter(|n| at(n, finest).is_some_and(|r| r.worst_corner_h <= CORNER_KEPT_H)).collect();
    let clean: Vec<&str> =
        keeps.iter().copied().filter(|n| at(n, finest).is_some_and(|r| r.manifold && r.self_intersections == 0)).collect();
    let never: Vec<String> = names
        .iter()
        .filter(|n| rows.iter().filter(|r| r.algorithm == **n).all(|r| r.worst_corner_h > CORNER_KEPT_H))
        .map(|n| format!("{n} ({:.3} h)", at(n, finest).map_or(f64::NAN, |r| r.worst_corner_h)))
        .collect();
    let shrinks: Vec<&str> = names
        .iter()
        .copied()
        .filter(|n| matches!((at(n, coarsest), at(n, finest)), (Some(a), Some(b)) if b.worst_corner_h < 0.5 * a.worst_corner_h))
        .collect();
    let mut lines = vec![format!(
        "At {finest} samples, every corner within {CORNER_KEPT_H} h: {}{}.",
        if keeps.is_empty() { "none".to_owned() } else { keeps.join(", ") },
        if keeps.is_empty() {
            String::new()
        } else {
            format!(
                " (watertight, manifold and free of self-intersections among them: {})",
                if clean.is_empty() { "none".to_owned() } else { clean.join(", ") }
            )
        }
    )];
    if !never.is_empty() {
        lines.push(format!(
            "Never within it at any resolution (worst corner at {finest} samples): {}; their vertices stay on cell edges \
             or in cells without a feature rule, so a corner is cut.",
            never.join(", ")
        ));
    }
    if !shrinks.is_empty() {
        lines.push(format!(
            "The worst corner error, in spacings, falls by more than half from {coarsest} to {finest} samples for: {}.",
            shrinks.join(", ")
        ));
    }
    format!("**Reading.** {}\n\n", lines.join(" "))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(algorithm: &str, resolution: usize, worst_corner_h: f64, self_intersections: usize) -> Row {
        Row {
            algorithm: algorithm.into(),
            resolution,
            worst_corner_h,
            mean_corner_h: worst_corner_h,
            self_intersections,
            manifold: true,
        }
    }

    #[test]
    fn the_reading_follows_the_rows() {
        let rows = vec![
            row("mc", 32, 0.3, 0),
            row("mc", 64, 0.3, 0),
            row("dc", 32, 0.2, 5),
            row("dc", 64, 0.01, 3),
            row("mdc", 32, 0.2, 0),
            row("mdc", 64, 0.02, 0),
        ];
        let r = reading(&rows);
        assert!(r.contains("At 64 samples, every corner within 0.05 h: dc, mdc (watertight, manifold and free of self-intersections among them: mdc)."), "{r}");
        assert!(r.contains("Never within it at any resolution (worst corner at 64 samples): mc (0.300 h)"), "{r}");
        assert!(r.contains("falls by more than half from 32 to 64 samples for: dc, mdc."), "{r}");
    }
}
