//! The page `report/mesh_fields.md`, rendered from the data file alone.

use super::data::{Data, Row};
use super::{NAME, RUNS, TARGET_RATIO};
use crate::experiment::context::{Context, ExperimentError};
use crate::figures::plot::{self, BarChart, BarSeries};
use crate::figures::series_color;
use crate::report::{markdown_table, Spread};
use isolab_algorithms::fields::{CAP_WINDING_BOUND, CROSSING_TOLERANCE};

/// The page, from the data file alone.
pub(super) fn section(ctx: &Context) -> Result<String, ExperimentError> {
    let data: Data = ctx.read_data(NAME)?;
    Ok(page_body(&data) + &figure(ctx, &data)?)
}

/// The page's figure, drawn at assembly from the data: each model's time for our narrow band, our
/// exact sampling and libigl's signed distance.
pub(super) fn figure(ctx: &Context, data: &Data) -> Result<String, ExperimentError> {
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
            color: crate::figures::color_of("libigl"),
            values: medians(&|r| r.libigl.as_ref().map(|s| s.median)),
        });
    }
    let chart = BarChart {
        title: format!("A mesh to {} samples a side of signed distance", data.resolution),
        y_label: "time, ms (median)".into(),
        y_scale: crate::figures::plot::Scale::Linear,
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

pub(super) fn ratio(peer: Option<&Spread>, ours: &Spread) -> String {
    peer.map_or("–".into(), |p| format!("{:.1}x", p.median / ours.median))
}

pub(super) fn ms(s: &Spread) -> String {
    format!("{:.0} ({:.0}–{:.0})", s.median, s.min, s.max)
}

/// Whether a model meets the target: libigl takes [`TARGET_RATIO`] times our narrow band's
/// time or more, and every sample has libigl's inside/outside (both halves: a fast field with a
/// different sign misses it).
pub(super) fn meets_target(r: &Row) -> bool {
    r.libigl.as_ref().is_some_and(|l| l.median >= TARGET_RATIO * r.narrow_band.median) && r.sign_differs == Some(0)
}

/// The page's opening reading: libigl's time over ours, the target met, where the signs differ
/// (marked unverified: nobody examined those samples), and whether the narrow band changes the
/// mesh or its distances.
pub(super) fn reading(data: &Data) -> String {
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
        let met = timed.iter().filter(|r| meets_target(r)).count();
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
pub(super) fn mesh_kind(r: &Row) -> &'static str {
    match r.closed {
        Some(true) => "closed",
        Some(false) => "open: capped",
        None => "–",
    }
}

pub(super) fn page_body(data: &Data) -> String {
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
    md.push_str(&crate::experiment::context::default_options(&["marching-cubes"]));
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
    let below = data.rows.iter().filter(|r| r.libigl.is_some() && !meets_target(r)).count();
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
