//! The section's pictures (the paper's objects, a defect close-up) and bar charts.

use super::{Picture, Row, PAPER};
use crate::experiment::context::{load_object, Context, ExperimentError};
use crate::figures::plot;
use crate::figures::plot::{BarChart, BarSeries};
use isolab_algorithms::extractors::regularised_marching_tetrahedra::RegularisedMarchingTetrahedra;
use isolab_algorithms::mesh::manifold_defects;
use isolab_algorithms::{Extraction, Extractor, Grid, Lattice, Samples, Vec3};
use isolab_render::{render, save_png, side_by_side, RenderOptions, Shading};

/// The defect close-up's radius around the first faulty vertex, in grid spacings.
const CLOSE_UP_H: f32 = 3.0;

/// Figs. 21-23: bunny at the benchmark resolution, a low-resolution sphere, a medium-resolution
/// asteroid; BCC, integrated clustering (our defaults); flat shading beside smooth shading.
pub(super) fn pictures(ctx: &Context, dir: &std::path::Path) -> Result<Vec<Picture>, ExperimentError> {
    let mut pictures = Vec::new();
    for (name, dims, figure) in
        [("stanford-bunny", [76, 41, 57], "Fig. 21"), ("sphere", [17, 17, 17], "Fig. 22"), ("asteroid", [51, 51, 51], "Fig. 23")]
    {
        let [x, y, z] = dims.map(|n: usize| n - 1);
        let label = if x == y && y == z {
            format!("{name}, {x}³ cells ({figure})")
        } else {
            format!("{name}, {x} × {y} × {z} cells ({figure})")
        };
        let field = load_object(name)?;
        let grid = Grid::with_dims(&field.domain(), dims)?;
        let samples = Samples::sample(field, Lattice::Bcc(grid), 0.0)?;
        let mut out = Extraction::default();
        RegularisedMarchingTetrahedra::default().extract(&samples, &mut out)?;
        let view = if name == "stanford-bunny" { Vec3::new(0.3, 0.35, 1.0) } else { Vec3::new(1.0, 0.75, 1.35) };
        let opts = |shading, wireframe| RenderOptions { width: 360, height: 360, shading, wireframe, view, ..Default::default() };
        let image =
            side_by_side(&render(&out.surface, &opts(Shading::Flat, true)), &render(&out.surface, &opts(Shading::Smooth, false)));
        let path = dir.join(format!("{name}-bcc-rmt.png"));
        save_png(&path, &image)?;
        pictures.push(Picture {
            caption: format!("{label}: flat shading with wireframe, and smooth shading"),
            path: ctx.link(&path),
        });
    }
    Ok(pictures)
}

/// A close-up of the first place where `mesh` is not manifold: the triangles within three
/// spacings of the defect, seen along their mean normal, with the wireframe. `None` when the mesh
/// is manifold.
pub(super) fn defect_closeup(
    ctx: &Context,
    dir: &std::path::Path,
    id: &str,
    mesh: &isolab_algorithms::TriMesh,
    spacing: f32,
) -> Result<Option<Picture>, ExperimentError> {
    let defects = manifold_defects(mesh);
    let Some(&v) = defects.first() else { return Ok(None) };
    let centre = mesh.positions[v as usize];
    let near = |t: &[u32; 3]| t.iter().any(|&i| mesh.positions[i as usize].distance(centre) < CLOSE_UP_H * spacing);
    let mut crop = isolab_algorithms::TriMesh {
        positions: mesh.positions.clone(),
        normals: Vec::new(),
        triangles: mesh.triangles.iter().copied().filter(near).collect(),
    };
    crop.compute_face_weighted_normals();
    let normal = crop.triangles.iter().fold(Vec3::ZERO, |n, t| {
        let p = t.map(|i| crop.positions[i as usize]);
        n + (p[1] - p[0]).cross(p[2] - p[0])
    });
    let used: std::collections::BTreeSet<u32> = crop.triangles.iter().flatten().copied().collect();
    let remap: std::collections::BTreeMap<u32, u32> = used.iter().enumerate().map(|(k, &i)| (i, k as u32)).collect();
    crop.positions = used.iter().map(|&i| mesh.positions[i as usize]).collect();
    crop.triangles = crop.triangles.iter().map(|t| t.map(|i| remap[&i])).collect();
    crop.compute_face_weighted_normals();
    let opts = RenderOptions {
        width: 320,
        height: 320,
        wireframe: true,
        view: normal.normalize_or(Vec3::Z) + Vec3::new(0.2, 0.3, 0.1),
        color: [0.8, 0.3, 0.3],
        ..Default::default()
    };
    let path = dir.join(format!("defect-{id}.png"));
    save_png(&path, &render(&crop, &opts))?;
    Ok(Some(Picture {
        caption: format!(
            "{id}: where it is not manifold ({} vertices at fault; close-up within {CLOSE_UP_H} h of the first)",
            defects.len()
        ),
        path: ctx.link(&path),
    }))
}

/// Figs. 25-27: triangles, pass times and mean aspect ratio of every configuration.
pub(super) fn charts(dir: &std::path::Path, rows: &[Row]) -> Result<(), ExperimentError> {
    let paper_rows: Vec<&Row> = rows.iter().filter(|r| !r.id.ends_with('+')).collect();
    let categories: Vec<String> = paper_rows.iter().map(|r| r.id.clone()).collect();
    let paper = |id: &str| PAPER.iter().find(|p| p.id == id);
    let ours = (40, 110, 180);
    let theirs = (200, 120, 40);
    let series = |label: &str, color, values: Vec<f64>| BarSeries { label: label.into(), color, values };
    let charts = [
        (
            "triangles",
            BarChart {
                title: "Triangles per configuration (Fig. 25)".into(),
                y_label: "triangles".into(),
                y_scale: crate::figures::plot::Scale::Linear,
                categories: categories.clone(),
                series: vec![
                    series("isolab", ours, paper_rows.iter().map(|r| r.n_triangles as f64).collect()),
                    series(
                        "paper",
                        theirs,
                        paper_rows.iter().map(|r| paper(&r.id).map_or(f64::NAN, |p| p.n_triangles as f64)).collect(),
                    ),
                ],
            },
        ),
        (
            "pass-times",
            BarChart {
                title: "Vertex and geometry pass, median ms (Fig. 26)".into(),
                y_label: "ms".into(),
                y_scale: crate::figures::plot::Scale::Linear,
                categories: categories.clone(),
                series: vec![
                    series("isolab vertex", ours, paper_rows.iter().map(|r| r.t_vertex).collect()),
                    series(
                        "isolab geometry + collapse",
                        (120, 170, 220),
                        paper_rows.iter().map(|r| r.t_geometry + r.t_post).collect(),
                    ),
                    series(
                        "paper vertex",
                        theirs,
                        paper_rows.iter().map(|r| paper(&r.id).map_or(f64::NAN, |p| p.t_vertex * 1e3)).collect(),
                    ),
                    series(
                        "paper geometry",
                        (240, 190, 120),
                        paper_rows.iter().map(|r| paper(&r.id).map_or(f64::NAN, |p| p.t_geometry * 1e3)).collect(),
                    ),
                ],
            },
        ),
        (
            "aspect-ratio",
            BarChart {
                title: "Mean aspect ratio, log10 (Fig. 27)".into(),
                y_label: "log10 mean Verdict aspect ratio".into(),
                y_scale: crate::figures::plot::Scale::Linear,
                categories,
                series: vec![
                    series("isolab", ours, paper_rows.iter().map(|r| r.metrics.quality.aspect_ratio.mean.log10()).collect()),
                    series(
                        "paper",
                        theirs,
                        paper_rows.iter().map(|r| paper(&r.id).map_or(f64::NAN, |p| p.ar_mean.log10())).collect(),
                    ),
                ],
            },
        ),
    ];
    for (stem, chart) in charts {
        plot::bars(&dir.join(stem), &chart).map_err(ExperimentError::Figure)?;
    }
    Ok(())
}
