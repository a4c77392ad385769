//! `quality_tets`: tetrahedra with proven quality against the meshers people use, on the shipped
//! models (issue "Tetrahedra with proven quality", item 3).
//!
//! - **Ours.** `isosurface-stuffing` (Labelle & Shewchuk 2007) fills each model's inside on a
//!   lattice of spacing `h` = longest side / `CELLS`, sampling the model's signed distance (the
//!   generalized winding number signs it, so the bunny's holes close) at the lattice's corners;
//!   `bcc-sculpt` (Stuart et al. 2013) at the same `h`, its defaults otherwise (it encloses the
//!   model in an offset band instead of meshing its surface).
//! - **The peers**, run by `peers.py` beside this file in the reference environment (its output
//!   `data/quality_tets_peers.json` is committed so the report builds without Python): TetGen,
//!   CGAL Mesh_3, NETGEN and fTetWild on the model's own triangle mesh (the bunny's holes closed by
//!   pymeshlab), each with its sizing parameter scaled until its tetrahedron count is within a
//!   tolerance of stuffing's at `PEER_CELLS`, as closely as its parameter allows.
//! - **Measured by one definition for all** ([`data::Quality`]): dihedral range, radius ratio,
//!   inverted tetrahedra, the distance both ways between the mesh's boundary and the model's
//!   surface sampled at vertices (in `h`), volume ratio and enclosure. Ours on one thread (a
//!   one-thread rayon pool), every run kept; the peers single-threaded as `peers.py` says.
//!
//! - **Label maps** (the page's last section): `lattice-cleaving` against CGAL Mesh_3 on labeled
//!   images, run by `tests/reference/mesh3/labeled_vs_cleaving.py` (its output
//!   `data/quality_tets_labels.json` is committed, as the peers' is); the front page's pick for a
//!   label map comes from it (`label_pick`).

mod data;
mod label_pick;
mod page;
#[cfg(test)]
mod tests;

use super::context::{load_object, Context, Experiment, ExperimentError};
use crate::report::rounds_until_narrow;
use data::Data;
pub use data::{PeerRow, Quality, Row};
use isolab_algorithms::bvh::TriangleBvh;
use isolab_algorithms::extractors::bcc_sculpt::{sculpt_surface, SculptOptions};
use isolab_algorithms::extractors::{self, isosurface_stuffing};
use isolab_algorithms::{Extraction, Field, Grid, Samples, TetMesh, TriMesh};
use isolab_metrics::tet_quality::tet_quality;
use isolab_metrics::volume_mesh::{encloses, soup_volume};
use isolab_render::{self as render, RenderOptions, Shading};
use std::sync::Arc;
use std::time::Instant;

pub(crate) use label_pick::pick as pick_labels;
pub(crate) use page::pick;

/// The experiment.
pub struct QualityTets;

const NAME: &str = "quality_tets";

/// The shipped models.
const MODELS: [&str; 5] = ["stanford-bunny", "spot", "rocker-arm", "fandisk", "cheburashka"];

/// Lattice cells along each model's longest side: `h` = longest side / cells.
const CELLS: [usize; 2] = [32, 64];

/// The cells at which the peers are matched to stuffing's tetrahedron count (and `bcc-sculpt`
/// runs).
pub(crate) const PEER_CELLS: usize = 32;

/// Timed runs per round ([`rounds_until_narrow`]).
const REPEATS: usize = 3;

/// The stuffing extractor's registry name.
pub(crate) const STUFFING: &str = "isosurface-stuffing";

/// The sculpting extractor's registry name.
pub(crate) const SCULPT: &str = "bcc-sculpt";

impl Experiment for QualityTets {
    fn name(&self) -> &'static str {
        NAME
    }

    fn question(&self) -> &'static str {
        "Which tetrahedral mesher gives the best-shaped tetrahedra for a model, with what guarantee, and at what cost?"
    }

    fn peers(&self) -> &'static [&'static str] {
        &["TetGen", "CGAL (Python)", "NETGEN", "fTetWild", "libigl", "pymeshlab"]
    }

    fn run(&self, ctx: &Context) -> Result<(), ExperimentError> {
        let (models, cells) = (ctx.sizes(&MODELS), ctx.sizes(&CELLS));
        let bar = ctx.bar(NAME, (models.len() * (cells.len() + 1)) as u64);
        let pool =
            rayon::ThreadPoolBuilder::new().num_threads(1).build().map_err(|e| ExperimentError::ThreadPool(e.to_string()))?;
        let mut rows = Vec::new();
        let mut closed = Vec::new();
        let mut pictures = Vec::new();
        for &model in models {
            let field = load_object(model)?;
            let surface =
                field.surface_mesh().ok_or_else(|| ExperimentError::Missing(format!("{model} has no triangle mesh")))?;
            let mesh = model_mesh(model)?;
            if isolab_metrics::topology(&mesh).closed {
                closed.push(model.to_string());
            }
            let vertices = mesh.positions;
            let longest = f64::from(surface.bounds().longest_side());
            for &n in cells {
                let h = longest / n as f64;
                let (row, boundary) = pool.install(|| stuff(model, &field, surface, &vertices, h, n))?;
                if n == PEER_CELLS {
                    pictures.push(picture(&boundary));
                }
                rows.push(row);
                bar.inc(1);
            }
            let h = longest / PEER_CELLS as f64;
            let (row, boundary) = pool.install(|| sculpt(model, field.as_ref(), surface, &vertices, h))?;
            pictures.push(picture(&boundary));
            rows.push(row);
            bar.inc(1);
        }
        let dir = ctx.figure_dir(NAME)?;
        let path = dir.join("boundaries.png");
        render::save_png(&path, &render::grid(&pictures.iter().collect::<Vec<_>>(), 2))?;
        let data = Data {
            models: models.iter().map(|m| m.to_string()).collect(),
            closed,
            cells: cells.to_vec(),
            peer_cells: PEER_CELLS,
            declared: interval(isosurface_stuffing::GUARANTEED),
            paper: interval(isosurface_stuffing::PAPER),
            settings: [STUFFING, SCULPT]
                .iter()
                .map(|n| (n.to_string(), extractors::by_name(n).map(|e| e.settings()).unwrap_or_default()))
                .collect(),
            rows,
            figure: Some(ctx.link(&path)),
        };
        ctx.write_data(NAME, &data)
    }

    fn section(&self, ctx: &Context) -> Result<String, ExperimentError> {
        page::section(ctx)
    }
}

fn interval(i: isolab_algorithms::extract::DihedralInterval) -> [f64; 2] {
    [i.min_degrees, i.max_degrees]
}

/// The model's own triangle mesh (the file's vertices, as `peers.py` reads them).
fn model_mesh(model: &str) -> Result<TriMesh, ExperimentError> {
    Ok(isolab_io::read_mesh(std::path::Path::new(&super::context::model_path(model)))?)
}

/// A cubic grid of spacing `h` around the model, two cells of margin.
fn grid_around(surface: &TriangleBvh, h: f64) -> Grid {
    let b = surface.bounds();
    let h32 = h as f32;
    let origin = b.min - glam::Vec3::splat(2.0 * h32);
    let dims = std::array::from_fn(|a| ((b.max[a] - b.min[a]) / h32).ceil() as usize + 5);
    Grid { origin, spacing: h32, dims }
}

/// Stuffing at spacing `h`: every timed run, the measures of the last, and its boundary.
fn stuff(
    model: &str,
    field: &Arc<dyn Field>,
    surface: &TriangleBvh,
    vertices: &[glam::Vec3],
    h: f64,
    cells: usize,
) -> Result<(Row, TriMesh), ExperimentError> {
    let grid = grid_around(surface, h);
    let extractor = extractors::by_name(STUFFING).ok_or_else(|| ExperimentError::Missing(STUFFING.into()))?;
    let mut sampling = Vec::new();
    let mut out = Extraction::default();
    let extraction = rounds_until_narrow(REPEATS, || -> Result<f64, ExperimentError> {
        let start = Instant::now();
        let samples = Samples::sample_cubic(field.clone(), grid, 0.0)?;
        sampling.push(start.elapsed().as_secs_f64() * 1e3);
        out = Extraction::default();
        let start = Instant::now();
        extractor.extract(&samples, &mut out)?;
        Ok(start.elapsed().as_secs_f64() * 1e3)
    })?;
    let quality = measure(&out.volume, &out.surface, field.as_ref(), surface, vertices, h);
    let row = Row {
        model: model.into(),
        tool: STUFFING.into(),
        cells,
        h,
        quality,
        sampling_ms: sampling,
        extraction_ms: extraction.runs,
    };
    Ok((row, out.surface))
}

/// `bcc-sculpt` at spacing `h`, its defaults otherwise.
fn sculpt(
    model: &str,
    field: &dyn Field,
    surface: &TriangleBvh,
    vertices: &[glam::Vec3],
    h: f64,
) -> Result<(Row, TriMesh), ExperimentError> {
    let options = SculptOptions { spacing: Some(h as f32), ..Default::default() };
    let mut last = None;
    let extraction = rounds_until_narrow(REPEATS, || -> Result<f64, ExperimentError> {
        let start = Instant::now();
        let result = sculpt_surface(surface, model, &options)?;
        let ms = start.elapsed().as_secs_f64() * 1e3;
        last = Some(result);
        Ok(ms)
    })?;
    let result = last.ok_or_else(|| ExperimentError::Missing("a bcc-sculpt run".into()))?;
    let quality = measure(&result.volume, &result.boundary, field, surface, vertices, h);
    let runs = extraction.runs.len();
    let row = Row {
        model: model.into(),
        tool: SCULPT.into(),
        cells: PEER_CELLS,
        h,
        quality,
        sampling_ms: vec![0.0; runs],
        extraction_ms: extraction.runs,
    };
    Ok((row, result.boundary))
}

/// The measures of [`Quality`], by the definitions `peers.py` uses for the peers.
pub(crate) fn measure(
    volume: &TetMesh,
    boundary: &TriMesh,
    field: &dyn Field,
    surface: &TriangleBvh,
    vertices: &[glam::Vec3],
    h: f64,
) -> Quality {
    use rayon::prelude::*;
    let q = tet_quality(volume);
    let used = used_vertices(boundary);
    let to: Vec<f64> = used.par_iter().map(|&p| f64::from(field.distance_to_surface(p, 0.0).abs()) / h).collect();
    let hull = TriangleBvh::new(boundary.triangles.iter().map(|t| t.map(|i| boundary.positions[i as usize])).collect());
    let from: Vec<f64> =
        vertices.par_iter().map(|&p| hull.closest_point(p).map_or(f64::INFINITY, |(_, d2)| f64::from(d2).sqrt() / h)).collect();
    let mean_max = |v: &[f64]| [v.iter().sum::<f64>() / v.len().max(1) as f64, v.iter().copied().fold(0.0, f64::max)];
    Quality {
        tetrahedra: q.tetrahedra,
        dihedral: [q.dihedral_deg.min, q.dihedral_deg.max],
        radius_ratio: [q.tet_radius_ratio.mean, q.tet_radius_ratio.max],
        inverted: q.inverted,
        to_surface_h: mean_max(&to),
        from_surface_h: mean_max(&from),
        volume_ratio: q.total_volume / soup_volume(surface.triangles()),
        encloses: encloses(boundary, surface),
    }
}

/// The positions the boundary's triangles use.
fn used_vertices(mesh: &TriMesh) -> Vec<glam::Vec3> {
    let mut used = vec![false; mesh.positions.len()];
    for t in &mesh.triangles {
        for &i in t {
            used[i as usize] = true;
        }
    }
    mesh.positions.iter().zip(used).filter_map(|(p, u)| u.then_some(*p)).collect()
}

fn picture(boundary: &TriMesh) -> render::Image {
    let opts = RenderOptions { width: 180, height: 180, shading: Shading::Flat, wireframe: true, ..Default::default() };
    render::render(boundary, &opts)
}
