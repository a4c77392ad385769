//! `terrain_lod`: levels of detail on the 256 x 128 x 256-cell `terrain` in 32³-cell chunks
//! (issue 8, "levels of detail"): chunks near a viewer at one corner are meshed by marching cubes
//! at full resolution, the rest at half resolution, and the seams are closed by restriction and
//! stitching ([`isolab_algorithms::lod`]). Reports triangles against all-full resolution, the seam
//! edges stitched (the cracks a naive mesher leaves), boundary edges left off the world's
//! boundary (0 when watertight), manifoldness, time; a picture coloured by level.

use super::context::{Context, Experiment, ExperimentError};
use crate::report::{markdown_table, median};
use isolab_algorithms::lod::{extract_lod, open_edges_off_bounds};
use isolab_algorithms::{extractors, fields, Extraction, Grid, Lattice, Samples, TriMesh, Vec3};
use isolab_cli::render::{self, RenderOptions, Shading};
use serde::{Deserialize, Serialize};
use std::collections::HashMap;
use std::time::Instant;

/// The experiment.
pub struct TerrainLod;

const NAME: &str = "terrain_lod";
const DIMS: [usize; 3] = [257, 129, 257];
const CHUNK: usize = 32;
const RUNS: usize = 5;

#[derive(Clone, Debug, Serialize, Deserialize)]
struct Row {
    pattern: String,
    fine: usize,
    coarse: usize,
    triangles: usize,
    stitched: usize,
    unmatched: usize,
    seam_boundary_edges: usize,
    non_manifold_edges: usize,
    median_ms: f64,
}

#[derive(Serialize, Deserialize)]
struct Data {
    rows: Vec<Row>,
    picture: String,
}

impl Experiment for TerrainLod {
    fn name(&self) -> &'static str {
        NAME
    }

    fn question(&self) -> &'static str {
        "Do levels of detail meet without cracks, and how many triangles do they save?"
    }

    fn run(&self, ctx: &Context) -> Result<(), ExperimentError> {
        let field = fields::builtin("terrain", Default::default())?;
        let grid = Grid::with_dims(&field.domain(), DIMS)?;
        let samples = Samples::sample(field, Lattice::Cubic(grid), 0.0)?;
        let mc = extractors::by_name("marching-cubes").ok_or_else(|| ExperimentError::Figure("no marching-cubes".into()))?;
        let counts = [8, 4, 8];
        let total = counts.iter().product::<usize>();
        // Full resolution within half the world's width of the viewer's corner (x = z = 0).
        let near: Vec<u8> = (0..total)
            .map(|k| {
                let (x, z) = ((k % 8) as f32 + 0.5, (k / 32) as f32 + 0.5);
                u8::from((x * x + z * z).sqrt() > 4.0)
            })
            .collect();
        let checker: Vec<u8> = (0..total).map(|k| ((k % 8 + (k / 8) % 4 + k / 32) % 2) as u8).collect();
        let patterns: [(&str, Vec<u8>); 4] = [
            ("all full resolution", vec![0; total]),
            ("viewer distance (full near, half far)", near.clone()),
            ("checkerboard (every seam)", checker),
            ("all half resolution", vec![1; total]),
        ];
        let bar = ctx.bar(NAME, (patterns.len() * RUNS) as u64);
        let bounds = grid.bounds();
        let mut rows = Vec::new();
        let mut picture = String::new();
        for (name, levels) in &patterns {
            let mut out = Extraction::default();
            let mut tri_levels = Vec::new();
            let mut times = Vec::new();
            let mut stats = None;
            for _ in 0..RUNS {
                let start = Instant::now();
                stats = Some(extract_lod(mc.as_ref(), &samples, CHUNK, levels, &mut out, Some(&mut tri_levels))?);
                times.push(start.elapsed());
                bar.inc(1);
            }
            let stats = stats.expect("ran");
            let t = isolab_metrics::topology(&out.surface);
            rows.push(Row {
                pattern: (*name).into(),
                fine: stats.fine,
                coarse: stats.coarse,
                triangles: out.surface.triangles.len(),
                stitched: stats.stitched,
                unmatched: stats.unmatched,
                seam_boundary_edges: open_edges_off_bounds(&out.surface, &bounds),
                non_manifold_edges: t.non_manifold_edges,
                median_ms: median(times).as_secs_f64() * 1e3,
            });
            if *levels == near {
                // Colour by level: full resolution green, half blue (vertices take their triangles').
                let mut colours = vec![[150u8, 150, 150]; out.surface.positions.len()];
                for (t, &l) in out.surface.triangles.iter().zip(&tri_levels) {
                    for &v in t {
                        colours[v as usize] = if l == 0 { [96, 160, 80] } else { [80, 120, 190] };
                    }
                }
                let dir = ctx.figure_dir(NAME)?;
                let opts = RenderOptions { width: 560, height: 380, shading: Shading::Smooth, ..Default::default() };
                let whole = render::render_coloured(&out.surface, &colours, &opts);
                // A close-up of the seam at x = 128 cells (chunks 3 | 4 of the first row), wireframe.
                let h = grid.spacing;
                let (x0, z1) = (grid.origin.x + 128.0 * h, grid.origin.z + 40.0 * h);
                let (mut crop, mut crop_colours, mut remap) = (TriMesh::default(), Vec::new(), HashMap::new());
                for t in &out.surface.triangles {
                    let c = t.iter().map(|&v| out.surface.positions[v as usize]).sum::<Vec3>() / 3.0;
                    if (c.x - x0).abs() >= 20.0 * h || c.z >= z1 {
                        continue;
                    }
                    crop.triangles.push(t.map(|v| {
                        *remap.entry(v).or_insert_with(|| {
                            crop.positions.push(out.surface.positions[v as usize]);
                            crop_colours.push(colours[v as usize]);
                            (crop.positions.len() - 1) as u32
                        })
                    }));
                }
                let close = render::render_coloured(
                    &crop,
                    &crop_colours,
                    &RenderOptions { shading: Shading::Flat, wireframe: true, view: Vec3::new(0.2, 0.9, 1.0), ..opts },
                );
                let path = dir.join("levels.png");
                render::save_png(&path, &render::side_by_side(&whole, &close))?;
                picture = ctx.link(&path);
            }
        }
        bar.finish();
        ctx.write_data(NAME, &Data { rows, picture })
    }

    fn section(&self, ctx: &Context) -> Result<String, ExperimentError> {
        let d: Data = ctx.read_data(NAME)?;
        let mut md = String::from("## Levels of detail without cracks (`terrain_lod`)\n\n");
        md.push_str(&format!(
            "The {}×{}×{}-cell `terrain` in {CHUNK}³-cell chunks, each meshed by marching cubes at full resolution or at half \
             resolution (every other sample). Where levels meet, the fine side's samples on the seam are restricted to what the \
             coarse side sees and each coarse seam triangle is fanned over the fine boundary path (`algorithms::lod`; Lengyel's \
             Transvoxel is the reference approach, this one needs no transition table). *Stitched* counts the coarse seam edges, \
             each of which would be a crack without stitching; *open seam edges* counts boundary edges left anywhere but on the \
             world's boundary. Times are medians of {RUNS} runs, sampling excluded.\n\n",
            DIMS[0] - 1,
            DIMS[1] - 1,
            DIMS[2] - 1,
        ));
        let body: Vec<Vec<String>> = d
            .rows
            .iter()
            .map(|r| {
                vec![
                    r.pattern.clone(),
                    format!("{} / {}", r.fine, r.coarse),
                    r.triangles.to_string(),
                    r.stitched.to_string(),
                    r.seam_boundary_edges.to_string(),
                    r.non_manifold_edges.to_string(),
                    format!("{:.1}", r.median_ms),
                ]
            })
            .collect();
        md.push_str(&markdown_table(
            &["levels", "chunks full / half", "triangles", "seam edges stitched", "open seam edges", "non-manifold edges", "ms"],
            &body,
        ));
        if let (Some(full), Some(near)) = (d.rows.first(), d.rows.get(1)) {
            md.push_str(&format!(
                "\nThe viewer-distance pattern keeps {:.0} % of the full-resolution triangles.\n",
                100.0 * near.triangles as f64 / full.triangles.max(1) as f64
            ));
        }
        if !d.picture.is_empty() {
            md.push_str(&format!("\n![levels: full resolution green, half blue; right, a close-up of a seam]({})\n", d.picture));
        }
        Ok(md)
    }
}
