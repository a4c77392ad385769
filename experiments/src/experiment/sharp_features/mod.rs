//! `sharp_features`: how close each extractor comes to the seven box corners of the `csg` field
//! (the one that a sphere does not bite away), at three resolutions, in grid spacings; with a
//! picture of each extractor's csg at the lowest resolution. Dual contouring places vertices from
//! the field's normals and should land on the corners; the others cut them.

mod data;
mod page;

use super::context::{corner_distances_h, Context, Experiment, ExperimentError};
pub(crate) use data::{Data, Row};
use isolab_algorithms::{extractors, fields, Extraction, Grid, Lattice, Samples, Vec3};
use isolab_render::{render, save_png, RenderOptions};

/// A corner the mesh comes within this many grid spacings of counts as kept (dual contouring's
/// promise on `csg`); the front page's sharp-CAD pick uses it too.
pub(crate) const CORNER_KEPT_H: f64 = 0.05;

/// The experiment.
pub struct SharpFeatures;

const NAME: &str = "sharp_features";

const RESOLUTIONS: [usize; 3] = [32, 64, 128];

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
        page::section(ctx)
    }
}

#[cfg(test)]
mod tests {
    use super::page::reading;
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
