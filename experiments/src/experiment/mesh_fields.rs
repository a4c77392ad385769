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

use super::context::{Context, Experiment, ExperimentError};
use crate::figures::plot::{self, BarChart, BarSeries};
use crate::figures::series_color;
use crate::peers::python::PythonServer;
use crate::report::{markdown_table, Spread};
use isolab_algorithms::fields::{MeshField, CAP_WINDING_BOUND, CROSSING_TOLERANCE, DEFAULT_BAND_CELLS};
use isolab_algorithms::{extractors, Extraction, Field, Grid, Options, Samples};
use isolab_io::read_mesh;
use serde::{Deserialize, Serialize};
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

/// One model.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Row {
    /// Model name.
    pub model: String,
    /// Its triangles.
    pub triangles: usize,
    /// Samples per axis.
    pub dims: [usize; 3],
    /// Samples nearer the mesh than the band (exact in ours).
    pub in_band: usize,
    /// Ours, narrow band, ms.
    pub narrow_band: Spread,
    /// Ours, exact at every sample, ms.
    pub exact: Spread,
    /// libigl, ms (none when the peer is missing).
    pub libigl: Option<Spread>,
    /// Samples where libigl's sign differs from ours.
    pub sign_differs: Option<usize>,
    /// Largest difference of our exact distances within the band from libigl's exact distance
    /// (`point_mesh_squared_distance`), in grid spacings.
    pub band_difference_h: Option<f64>,
    /// Largest difference of libigl's `signed_distance` magnitudes (fast-winding-number mode)
    /// from our exact distances within the band, in grid spacings.
    pub fwn_magnitude_h: Option<f64>,
    /// Whether marching cubes makes the same mesh from the narrow band as from exact samples.
    pub mesh_unchanged: bool,
    /// Whether the mesh is closed, so the narrow band takes its signs from row crossings (absent
    /// in older runs).
    #[serde(default)]
    pub closed: Option<bool>,
    /// Samples whose narrow-band sign differs from the exact field's (absent in older runs).
    #[serde(default)]
    pub sign_differs_from_exact: Option<usize>,
}

/// The experiment's data.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Data {
    /// Samples along the longest side.
    pub resolution: usize,
    /// Band half-width, spacings.
    pub band_cells: f32,
    /// Threads on each side.
    pub threads: usize,
    /// libigl's version, or why it was not run.
    pub libigl: String,
    /// One row per model.
    pub rows: Vec<Row>,
}

impl Experiment for MeshFields {
    fn name(&self) -> &'static str {
        NAME
    }

    fn question(&self) -> &'static str {
        "How fast is a mesh turned into a signed distance field, against libigl, and what does the narrow band change?"
    }

    fn run(&self, ctx: &Context) -> Result<(), ExperimentError> {
        let root = ctx.report_dir.join("..");
        let (server, libigl) = match PythonServer::start(&root) {
            Ok((server, hello)) => match hello["available"]["libigl"].as_str() {
                Some(v) => (Some(server), v.to_owned()),
                None => (None, format!("not run: {}", hello["errors"]["libigl"])),
            },
            Err(e) => (None, format!("not run: {e}")),
        };
        let tmp = std::env::temp_dir().join(format!("isolab-mesh-fields-{}.f32", std::process::id()));
        let tmp_exact = tmp.with_extension("exact.f32");
        let bar = ctx.bar(NAME, MODELS.len() as u64);
        let mut rows = Vec::new();
        for model in MODELS {
            let path = super::model_path(model);
            let mesh = read_mesh(Path::new(&path))?;
            let field = MeshField::new(model, &mesh.positions, &mesh.triangles)?;
            let grid = Grid::covering(&field.domain(), RESOLUTION)?;
            let exact_field = field.clone().with_band_cells(f32::INFINITY);
            let (mut narrow_ms, mut exact_ms, mut igl_ms) = (Vec::new(), Vec::new(), Vec::new());
            let (mut narrow, mut exact) = (Vec::new(), Vec::new());
            let mut igl_error = None;
            for run in 0..RUNS {
                narrow_ms.push(time_ms(|| narrow = sampled(&field, &grid)));
                exact_ms.push(time_ms(|| exact = sampled(&exact_field, &grid)));
                if let Some(server) = &server {
                    let request = serde_json::json!({
                        "peer": "libigl-signed-distance", "mesh": path, "origin": grid.origin.to_array(),
                        "spacing": grid.spacing, "dims": grid.dims, "out": tmp,
                        "exact_out": if run + 1 == RUNS { Some(&tmp_exact) } else { None },
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
        let data: Data = ctx.read_data(NAME)?;
        Ok(section(&data) + &figure(ctx, &data)?)
    }
}

/// The page's figure, drawn at assembly from the data: each model's time for our narrow band, our
/// exact sampling and libigl's signed distance.
fn figure(ctx: &Context, data: &Data) -> Result<String, ExperimentError> {
    if data.rows.is_empty() {
        return Ok(String::new());
    }
    let medians = |f: &dyn Fn(&Row) -> Option<f64>| data.rows.iter().map(|r| f(r).unwrap_or(f64::NAN)).collect::<Vec<f64>>();
    let mut series = vec![
        BarSeries {
            label: "isolab, narrow band".into(),
            color: series_color(0),
            values: medians(&|r| Some(r.narrow_band.median)),
        },
        BarSeries { label: "isolab, exact".into(), color: series_color(1), values: medians(&|r| Some(r.exact.median)) },
    ];
    if data.rows.iter().any(|r| r.libigl.is_some()) {
        series.push(BarSeries {
            label: "libigl signed_distance".into(),
            color: series_color(2),
            values: medians(&|r| r.libigl.as_ref().map(|s| s.median)),
        });
    }
    let chart = BarChart {
        title: format!("A mesh to {} samples a side of signed distance", data.resolution),
        y_label: "time, ms (median)".into(),
        categories: data.rows.iter().map(|r| r.model.clone()).collect(),
        series,
    };
    let stem = ctx.figure_dir(NAME)?.join("time");
    plot::bars(&stem, &chart).map_err(ExperimentError::Figure)?;
    Ok(format!(
        "\n![time per model]({})\n\n_Each model's median time, {} threads on each side._\n",
        ctx.link(&stem.with_extension("png")),
        data.threads
    ))
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

fn ratio(peer: Option<&Spread>, ours: &Spread) -> String {
    peer.map_or("–".into(), |p| format!("{:.1}x", p.median / ours.median))
}

fn ms(s: &Spread) -> String {
    format!("{:.0} ({:.0}–{:.0})", s.median, s.min, s.max)
}

/// The page's opening reading: libigl's time over ours, the target met, where the signs differ
/// (marked unverified: nobody examined those samples), and whether the narrow band changes the
/// mesh or its distances.
fn reading(data: &Data) -> String {
    let timed: Vec<&Row> = data.rows.iter().filter(|r| r.libigl.is_some()).collect();
    if data.rows.is_empty() {
        return String::new();
    }
    let mut lines = Vec::new();
    if !timed.is_empty() {
        let over = |ours: fn(&Row) -> f64| {
            Spread::of(timed.iter().map(|r| r.libigl.as_ref().map_or(f64::NAN, |l| l.median) / ours(r)).collect())
        };
        let (narrow, exact) = (over(|r| r.narrow_band.median), over(|r| r.exact.median));
        let met =
            timed.iter().filter(|r| r.libigl.as_ref().is_some_and(|l| l.median >= TARGET_RATIO * r.narrow_band.median)).count();
        lines.push(format!(
            "libigl takes {:.1}x ({:.1}–{:.1}) the time of our narrow band, median over {} models, and {:.1}x ({:.1}–{:.1}) that \
             of our exact field; the target of {TARGET_RATIO}x is met on {met} of {}.",
            narrow.median,
            narrow.min,
            narrow.max,
            timed.len(),
            exact.median,
            exact.min,
            exact.max,
            timed.len()
        ));
    }
    let differing: Vec<String> = data
        .rows
        .iter()
        .filter(|r| r.sign_differs.is_some_and(|n| n > 0))
        .map(|r| format!("{} ({} samples, {})", r.model, r.sign_differs.unwrap_or(0), mesh_kind(r)))
        .collect();
    lines.push(if differing.is_empty() {
        "Our signs and libigl's agree on every sample of every model.".to_owned()
    } else {
        format!(
            "Signs differing from libigl's, cause unverified: {}; every other model agrees on every sample.",
            differing.join(", ")
        )
    });
    let unchanged = data.rows.iter().filter(|r| r.mesh_unchanged).count();
    let from_exact: usize = data.rows.iter().filter_map(|r| r.sign_differs_from_exact).sum();
    let band = data.rows.iter().filter_map(|r| r.band_difference_h).fold(f64::NAN, f64::max);
    lines.push(format!(
        "Marching cubes makes the same mesh from the narrow band as from exact samples on {unchanged} of {} models; \
         narrow-band signs differing from our exact field: {from_exact} in all; in the band our distances are within \
         {band:.1e} spacings of libigl's exact ones.",
        data.rows.len()
    ));
    format!("**Reading.** {}\n\n", lines.join(" "))
}

/// "closed" or "open: capped".
fn mesh_kind(r: &Row) -> &'static str {
    match r.closed {
        Some(true) => "closed",
        Some(false) => "open: capped",
        None => "–",
    }
}

fn section(data: &Data) -> String {
    let mut md = String::from("## Mesh fields: a triangle mesh as a signed distance field, against libigl\n\n");
    md.push_str(&format!(
        "Every shipped model sampled on the grid `isolab` meshes it on, {} samples along the longest side (the mesh's box \
         plus its margin), by three implementations, one-shot (a fresh output each call), {RUNS} alternating runs each, on \
         {} threads each (rayon's pool; libigl's `parallel_for` takes the hardware threads). **ours, narrow band** is what \
         the extractors get: the exact signed distance within {} grid spacings of the mesh, beyond it the right sign and a \
         lower bound on the distance (see `algorithms/src/fields/mesh_sdf.rs`). Its signs are the generalized winding number's (inside where `|w|` is at least a half), found without \
         computing it at most samples: the mesh closed by cones over its holes has an integer winding number, counted by \
         the crossings along each grid row (exact orientation tests); the mesh's own differs from it by the cones' winding \
         number, so samples where that is not bounded below {} (near a cone), on rows through a triangle's edge or \
         vertex, or within {:e} spacings of a crossing take their own winding number. A closed mesh needs no cones. **ours, exact** computes every sample as \
         libigl does. **libigl** is `signed_distance` with `SIGNED_DISTANCE_TYPE_FAST_WINDING_NUMBER` ({}), on the same \
         points, built outside its timing. Times in ms: median (fastest–slowest); ratios are libigl's median over ours.\n\n",
        data.resolution,
        data.threads,
        data.band_cells,
        CAP_WINDING_BOUND,
        CROSSING_TOLERANCE,
        data.libigl
    ));
    md.push_str(&reading(data));
    md.push_str(&super::context::default_options(&["marching-cubes"]));
    let body: Vec<Vec<String>> = data
        .rows
        .iter()
        .map(|r| {
            vec![
                r.model.clone(),
                r.triangles.to_string(),
                mesh_kind(r).into(),
                format!("{}", r.dims.iter().product::<usize>()),
                format!("{}", r.in_band),
                ms(&r.narrow_band),
                ms(&r.exact),
                r.libigl.as_ref().map_or("–".into(), ms),
                ratio(r.libigl.as_ref(), &r.narrow_band),
                ratio(r.libigl.as_ref(), &r.exact),
                r.sign_differs.map_or("–".into(), |n| n.to_string()),
                r.band_difference_h.map_or("–".into(), |d| format!("{d:.1e}")),
                r.fwn_magnitude_h.map_or("–".into(), |d| format!("{d:.2}")),
                if r.mesh_unchanged { "yes".into() } else { "**no**".into() },
                r.sign_differs_from_exact.map_or("–".into(), |n| n.to_string()),
            ]
        })
        .collect();
    md.push_str(&markdown_table(
        &[
            "model",
            "triangles",
            "mesh",
            "samples",
            "in the band",
            "ours, narrow band",
            "ours, exact",
            "libigl",
            "libigl / narrow band",
            "libigl / exact",
            "signs differing from libigl",
            "in the band: ours against libigl's exact distance (h)",
            "in the band: libigl's signed_distance magnitude against exact (h)",
            "marching cubes unchanged",
            "signs differing from our exact field",
        ],
        &body,
    ));
    let below =
        data.rows.iter().filter(|r| r.libigl.as_ref().is_some_and(|l| l.median < TARGET_RATIO * r.narrow_band.median)).count();
    md.push_str(&format!(
        "\nOur target is {TARGET_RATIO}x libigl's time with the same inside/outside on every sample; {} of {} \
         models miss it here. \"Marching cubes unchanged\" compares its mesh from the narrow band with its mesh from exact samples, \
         bit for bit; `tests/tests/models.rs` checks the same for every registered extractor on three models, and \
         `fields::mesh_sdf`'s tests check that every sample in the band is exact and every one beyond is a bound. Where \
         the sign differs from libigl (only the open models can: their inside across a hole is where the winding number \
         crosses a half, not a triangle), the samples were not examined one by one; our reading, unverified, is that the two \
         fast winding numbers (approximate, with different expansions) land on different sides of a half there. Within the band our distances are checked against libigl's \
         exact distance (`point_mesh_squared_distance`, untimed). The magnitudes `signed_distance` returns in its \
         fast-winding-number mode are not exact distances everywhere (last but one column); its sign is what we compare.\n",
        below,
        data.rows.len()
    ));
    md
}

#[cfg(test)]
mod tests {
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
        data.rows[1].sign_differs = Some(0);
        assert!(reading(&data).contains("agree on every sample of every model"));
    }
}
