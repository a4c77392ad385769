//! The page `report/sphere_convergence.md`, rendered from the data file alone.

use super::data::{Data, Row};
use super::{NAME, SECOND_ORDER_SLOPE, SECOND_ORDER_TOLERANCE};
use crate::experiment::context::{Context, ExperimentError};
use crate::report::{log_slope, markdown_table};

/// The page, from the data file alone.
pub(super) fn section(ctx: &Context) -> Result<String, ExperimentError> {
    let data: Data = ctx.read_data(NAME)?;
    let mut s = String::from("## Convergence on the sphere (`sphere_convergence`)\n\n");
    s.push_str(&format!(
        "Relative volume and area error against 4/3 π r³ and 4 π r² (r = {}), and vertex distance to the sphere in grid \
         spacings, as the resolution doubles. Second-order convergence shows as a slope of -2 on the log-log plot.\n\n",
        data.radius
    ));
    s.push_str(&reading(&data.rows));
    s.push_str(&crate::experiment::context::options_as_run(&data.settings));
    let rows: Vec<Vec<String>> = data
        .rows
        .iter()
        .map(|r| {
            vec![
                r.algorithm.clone(),
                r.resolution.to_string(),
                r.triangles.to_string(),
                format!("{:+.4}%", 100.0 * r.volume_error),
                format!("{:+.4}%", 100.0 * r.area_error),
                format!("{:.4}", r.mean_distance_over_spacing),
                format!("{:.4}", r.max_distance_over_spacing),
            ]
        })
        .collect();
    s.push_str(&markdown_table(
        &["algorithm", "resolution", "triangles", "volume error", "area error", "mean dist / h", "max dist / h"],
        &rows,
    ));
    s.push_str(&format!("\n![volume error]({})\n", data.plot));
    Ok(s)
}

/// What the table shows, worded from it: each extractor's order of convergence (the log-log
/// slope of its volume error against resolution), which side of the exact volume it stays on,
/// and the largest error at the finest resolution, with each extractor's settings.
pub(super) fn reading(rows: &[Row]) -> String {
    let names: Vec<&str> = crate::report::first_seen(rows.iter().map(|r| r.algorithm.as_str()));
    fn of<'a>(rows: &'a [Row], name: &'a str) -> impl Iterator<Item = &'a Row> + 'a {
        rows.iter().filter(move |r| r.algorithm == name)
    }
    let slopes: Vec<(&str, f64)> = names
        .iter()
        .filter_map(|&n| {
            Some((n, log_slope(&of(rows, n).map(|r| (r.resolution as f64, r.volume_error.abs())).collect::<Vec<_>>())?))
        })
        .collect();
    let (second, other): (Vec<_>, Vec<_>) =
        slopes.iter().partition(|(_, s)| (s - SECOND_ORDER_SLOPE).abs() <= SECOND_ORDER_TOLERANCE);
    let list = |v: &[&(&str, f64)]| v.iter().map(|(n, s)| format!("{n} {s:.2}")).collect::<Vec<_>>().join(", ");
    let mut lines = Vec::new();
    if !second.is_empty() {
        lines.push(format!(
            "Second order (a volume-error slope within {SECOND_ORDER_TOLERANCE} of {SECOND_ORDER_SLOPE} over the resolutions): {}.",
            list(&second)
        ));
    }
    if !other.is_empty() {
        lines.push(format!("Not second order: {}.", list(&other)));
    }
    let side = |sign: f64| -> Vec<&str> {
        names.iter().copied().filter(|&n| of(rows, n).all(|r| r.volume_error * sign > 0.0)).collect()
    };
    let (below, above) = (side(-1.0), side(1.0));
    if !below.is_empty() {
        lines.push(format!("Below the exact volume at every resolution: {}.", below.join(", ")));
    }
    if !above.is_empty() {
        lines.push(format!("Above it at every resolution: {}.", above.join(", ")));
    }
    let finest = rows.iter().map(|r| r.resolution).max().unwrap_or(0);
    if let Some(worst) =
        rows.iter().filter(|r| r.resolution == finest).max_by(|a, b| a.volume_error.abs().total_cmp(&b.volume_error.abs()))
    {
        let settings = isolab_algorithms::extractors::by_name(&worst.algorithm).map(|e| e.settings()).unwrap_or_default();
        lines.push(format!(
            "The largest volume error at {finest} samples is that of {}, {:+.4}%{}.",
            worst.algorithm,
            100.0 * worst.volume_error,
            if settings.is_empty() { String::new() } else { format!(" (it runs with its defaults: {settings})") }
        ));
    }
    format!("**Reading.** {}\n\n", lines.join(" "))
}
