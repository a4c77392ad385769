//! `sharp_features`: how close each extractor comes to the seven box corners of the `csg` field
//! (the one that a sphere does not bite away), at three resolutions, in grid spacings; with a
//! picture of each extractor's csg at the lowest resolution. Dual contouring places vertices from
//! the field's normals and should land on the corners; the others cut them.

use super::context::{corner_distances_h, Context, Experiment, ExperimentError};
use crate::report::markdown_table;
use isolab_algorithms::{extractors, fields, Extraction, Grid, Lattice, Samples, Vec3};
use isolab_cli::render::{render, save_png, RenderOptions};
use serde::{Deserialize, Serialize};

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
        ctx.write_data(NAME, &Data { rows, images })
    }

    fn section(&self, ctx: &Context) -> Result<String, ExperimentError> {
        let data: Data = ctx.read_data(NAME)?;
        let mut s = String::from("## Sharp features (`sharp_features`)\n\n");
        s.push_str(
            "Distance from each of the seven sharp box corners of `csg` to the nearest vertex, in grid spacings (worst and mean \
             over the corners), with the mesh's self-intersecting triangle pairs and whether it is watertight and manifold.\n\n",
        );
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
