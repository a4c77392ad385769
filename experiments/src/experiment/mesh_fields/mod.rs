//! Experiment `mesh_fields`: sampling a triangle mesh as a signed distance field, ours against
//! libigl's `signed_distance` with fast winding numbers on the very same points.
//!
//! For every shipped model, on the grid `isolab` samples at [`RESOLUTION`] along the longest
//! side (the mesh's box plus its margin), timed one-shot (a fresh output each call) and
//! alternating, [`RUNS`] runs each:
//! - ours as the extractors get it: [`isolab_algorithms::fields::MeshField`]'s narrow band
//!   (exact within [`DEFAULT_BAND_CELLS`] spacings, the sign and a lower bound beyond);
//! - ours exact at every sample (`with_band_cells(inf)`), the protocol libigl follows;
//! - libigl, in the long-lived Python peer server (`tests/reference/peers.py`); the points are
//!   built outside its timing.
//!
//! Both sides run on the machine's threads (rayon's pool; libigl's `parallel_for` takes the
//! hardware threads). Checked on every sample: the sign against libigl's, the distance within the
//! band against libigl's, and marching cubes on the narrow band against marching cubes on exact
//! samples (the mesh must be the same, bit for bit).

mod data;
mod page;

use super::context::{Context, Experiment, ExperimentError};
use crate::peers::python::PythonServer;
use crate::report::Spread;
pub use data::{Data, Row};
use isolab_algorithms::fields::{MeshField, DEFAULT_BAND_CELLS};
use isolab_algorithms::{extractors, Extraction, Field, Grid, Options, Samples};
use isolab_io::read_mesh;
use std::path::Path;
use std::sync::Arc;
use std::time::Instant;

const NAME: &str = "mesh_fields";

/// Samples along the longest side.
pub const RESOLUTION: usize = 96;

/// Timed runs per implementation (alternating).
pub const RUNS: usize = 5;

/// The target: libigl's time over ours, with the same inside/outside on every sample.
pub const TARGET_RATIO: f64 = 10.0;

/// The shipped models, largest first.
const MODELS: [&str; 6] = ["stanford-bunny", "rocker-arm", "cheburashka", "fandisk", "teapot", "spot"];

/// The `mesh_fields` experiment.
pub struct MeshFields;

impl Experiment for MeshFields {
    fn name(&self) -> &'static str {
        NAME
    }

    fn question(&self) -> &'static str {
        "How fast is a mesh turned into a signed distance field, against libigl, and what does the narrow band change?"
    }

    fn peers(&self) -> &'static [&'static str] {
        &["libigl"]
    }

    fn run(&self, ctx: &Context) -> Result<(), ExperimentError> {
        let root = crate::provenance::root();
        let (server, libigl) = match PythonServer::start(&root) {
            Ok((server, hello)) => match hello["available"]["libigl"].as_str() {
                Some(v) => (Some(server), v.to_owned()),
                None => (None, format!("not run: {}", hello["errors"]["libigl"])),
            },
            Err(e) => (None, format!("not run: {e}")),
        };
        let tmp = std::env::temp_dir().join(format!("isolab-mesh-fields-{}.f32", std::process::id()));
        let tmp_exact = tmp.with_extension("exact.f32");
        // A quick run: the first model, runs as repeats.
        let (models, runs) = (ctx.sizes(&MODELS), ctx.pick(RUNS, ctx.repeats));
        let bar = ctx.bar(NAME, models.len() as u64);
        let mut rows = Vec::new();
        for &model in models {
            let path = super::model_path(model);
            let mesh = read_mesh(Path::new(&path))?;
            let field = MeshField::new(model, &mesh.positions, &mesh.triangles)?;
            let grid = Grid::covering(&field.domain(), RESOLUTION)?;
            let exact_field = field.clone().with_band_cells(f32::INFINITY);
            let (mut narrow_ms, mut exact_ms, mut igl_ms) = (Vec::new(), Vec::new(), Vec::new());
            let (mut narrow, mut exact) = (Vec::new(), Vec::new());
            let mut igl_error = None;
            for run in 0..runs {
                narrow_ms.push(time_ms(|| narrow = sampled(&field, &grid)));
                exact_ms.push(time_ms(|| exact = sampled(&exact_field, &grid)));
                if let Some(server) = &server {
                    let request = serde_json::json!({
                        "peer": "libigl-signed-distance", "mesh": path, "origin": grid.origin.to_array(),
                        "spacing": grid.spacing, "dims": grid.dims, "out": tmp,
                        "exact_out": if run + 1 == runs { Some(&tmp_exact) } else { None },
                    });
                    match server.borrow_mut().request(&request) {
                        Ok((ms, _, _)) => igl_ms.push(ms),
                        Err(e) => igl_error = Some(e),
                    }
                }
            }
            let band = DEFAULT_BAND_CELLS * grid.spacing;
            let in_band = exact.iter().filter(|v| v.abs() < band).count();
            let igl = igl_error.is_none().then(|| read_f32(&tmp)).flatten().filter(|v| v.len() == exact.len());
            let sign_differs = igl.as_ref().map(|v| v.iter().zip(&narrow).filter(|(a, b)| (**a < 0.0) != (**b < 0.0)).count());
            let igl_exact = igl.as_ref().and_then(|_| read_f32(&tmp_exact)).filter(|v| v.len() == exact.len());
            let largest_gap_h = |libigl: &[f32]| {
                libigl
                    .iter()
                    .zip(&exact)
                    .filter(|(_, e)| e.abs() < band)
                    .map(|(a, e)| (a.abs() - e.abs()).abs() as f64)
                    .fold(0.0, f64::max)
                    / grid.spacing as f64
            };
            let band_difference_h = igl_exact.as_deref().map(largest_gap_h);
            let fwn_magnitude_h = igl.as_deref().map(largest_gap_h);
            if let Some(e) = &igl_error {
                eprintln!("mesh_fields: libigl on {model}: {e}");
            }
            rows.push(Row {
                model: model.to_owned(),
                triangles: mesh.triangles.len(),
                dims: grid.dims,
                in_band,
                narrow_band: Spread::of(narrow_ms),
                exact: Spread::of(exact_ms),
                libigl: (!igl_ms.is_empty() && igl_error.is_none()).then(|| Spread::of(igl_ms)),
                sign_differs,
                band_difference_h,
                fwn_magnitude_h,
                mesh_unchanged: same_marching_cubes(&field, &exact_field, &grid)?,
                closed: Some(field.is_closed()),
                sign_differs_from_exact: Some(narrow.iter().zip(&exact).filter(|(a, b)| (**a < 0.0) != (**b < 0.0)).count()),
            });
            bar.inc(1);
        }
        let _ = std::fs::remove_file(&tmp);
        let _ = std::fs::remove_file(&tmp_exact);
        bar.finish();
        let data =
            Data { resolution: RESOLUTION, band_cells: DEFAULT_BAND_CELLS, threads: rayon::current_num_threads(), libigl, rows };
        ctx.write_data(NAME, &data)
    }

    fn section(&self, ctx: &Context) -> Result<String, ExperimentError> {
        page::section(ctx)
    }
}

/// Wall time of `f`, ms.
fn time_ms(f: impl FnOnce()) -> f64 {
    let start = Instant::now();
    f();
    start.elapsed().as_secs_f64() * 1e3
}

/// The field on the grid, into a fresh vector (one-shot).
fn sampled(field: &MeshField, grid: &Grid) -> Vec<f32> {
    let mut values = vec![0.0; grid.len()];
    field.sample_grid(grid, 0.0, &mut values);
    values
}

fn read_f32(path: &Path) -> Option<Vec<f32>> {
    let bytes = std::fs::read(path).ok()?;
    Some(bytes.chunks_exact(4).map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]])).collect())
}

/// Whether marching cubes makes the same mesh from both fields' samples.
fn same_marching_cubes(narrow: &MeshField, exact: &MeshField, grid: &Grid) -> Result<bool, ExperimentError> {
    let info = extractors::INFOS.iter().find(|i| i.name == "marching-cubes").expect("marching cubes is registered");
    let extractor = (info.make)(&Options::new())
        .map_err(|e| ExperimentError::Failed { what: "building marching cubes".into(), reason: e.to_string() })?;
    let mesh = |field: &MeshField| -> Result<Extraction, ExperimentError> {
        let samples = Samples::sample_cubic(Arc::new(field.clone()), *grid, 0.0)?;
        let mut out = Extraction::default();
        extractor.extract(&samples, &mut out)?;
        Ok(out)
    };
    let (a, b) = (mesh(narrow)?, mesh(exact)?);
    Ok(a.surface.positions == b.surface.positions && a.surface.triangles == b.surface.triangles)
}

#[cfg(test)]
mod tests {
    use super::page::reading;
    use super::*;

    fn row(model: &str, narrow: f64, libigl: f64, signs: usize, closed: bool) -> Row {
        Row {
            model: model.into(),
            triangles: 1,
            dims: [1, 1, 1],
            in_band: 1,
            narrow_band: Spread::of(vec![narrow]),
            exact: Spread::of(vec![narrow * 5.0]),
            libigl: Some(Spread::of(vec![libigl])),
            sign_differs: Some(signs),
            band_difference_h: Some(1e-5),
            fwn_magnitude_h: None,
            mesh_unchanged: true,
            closed: Some(closed),
            sign_differs_from_exact: Some(0),
        }
    }

    #[test]
    fn the_reading_follows_the_rows() {
        let mut data = Data { resolution: 96, band_cells: 2.0, threads: 2, libigl: "2.5".into(), rows: Vec::new() };
        assert_eq!(reading(&data), "");
        data.rows = vec![row("a", 10.0, 300.0, 0, true), row("b", 10.0, 50.0, 4, false)];
        let r = reading(&data);
        assert!(r.contains("libigl takes 17.5x (5.0–30.0) the time of our narrow band, median over 2 models"), "{r}");
        assert!(r.contains("target of 10x is met on 1 of 2."), "{r}");
        assert!(r.contains("cause unverified: b (4 samples, open: capped)"), "{r}");
        assert!(r.contains("on 2 of 2 models"), "{r}");
        // Fast enough but with a sign of its own: the target (same inside/outside) is missed.
        data.rows.push(row("c", 10.0, 300.0, 3, false));
        assert!(reading(&data).contains("target of 10x is met on 1 of 3."), "{}", reading(&data));
        data.rows.pop();
        data.rows[1].sign_differs = Some(0);
        assert!(reading(&data).contains("agree on every sample of every model"));
    }
}
