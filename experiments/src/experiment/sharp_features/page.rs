//! The page `report/sharp_features.md`, rendered from the data file alone.

use super::data::{Data, Row};
use super::{CORNER_KEPT_H, NAME};
use crate::experiment::context::{Context, ExperimentError};
use crate::report::markdown_table;

/// The page, from the data file alone.
pub(super) fn section(ctx: &Context) -> Result<String, ExperimentError> {
    let data: Data = ctx.read_data(NAME)?;
    let mut s = String::from("## Sharp features (`sharp_features`)\n\n");
    s.push_str(
        "Distance from each of the seven sharp box corners of `csg` to the nearest vertex, in grid spacings (worst and mean \
         over the corners), with the mesh's self-intersecting triangle pairs and whether it is watertight and manifold. The \
         `csg` box's faces are parallel to the grid and its corners lie at the same fraction of a cell at every \
         resolution, the best case for vertices placed from normals; so the same shape runs turned about a generic axis \
         (`csg turned`: no face parallel to the grid) and moved by a fraction of a cell that differs at each resolution \
         (`csg moved off the grid`), each on a grid covering its own box.\n\n",
    );
    s.push_str(&reading(&data.rows));
    s.push_str(&crate::experiment::context::options_as_run(&data.settings));
    let rows: Vec<Vec<String>> = data
        .rows
        .iter()
        .map(|r| {
            vec![
                r.algorithm.clone(),
                r.shape.clone(),
                r.resolution.to_string(),
                format!("{:.4}", r.worst_corner_h),
                format!("{:.4}", r.mean_corner_h),
                r.self_intersections.to_string(),
                if r.manifold { "yes".into() } else { "**no**".into() },
            ]
        })
        .collect();
    s.push_str(&markdown_table(
        &["algorithm", "shape", "resolution", "worst corner / h", "mean corner / h", "self-int.", "watertight"],
        &rows,
    ));
    s.push_str("\nThe csg part at the lowest resolution, seen from the side away from the sphere's bite:\n\n");
    let header: Vec<&str> = data.images.iter().map(|(a, _)| a.as_str()).collect();
    let row: Vec<String> = data.images.iter().map(|(a, p)| format!("![{a}]({p})")).collect();
    s.push_str(&markdown_table(&header, &[row]));
    Ok(s)
}

/// What the table shows, worded from its rows, shape by shape: who keeps every corner at the
/// finest resolution (and of those, who stays clean), who never does, and whose corner error
/// shrinks in grid spacings as the grid refines.
pub(super) fn reading(rows: &[Row]) -> String {
    let shapes = crate::report::first_seen(rows.iter().map(|r| r.shape.as_str()));
    let parts: Vec<String> = shapes
        .iter()
        .map(|shape| {
            let of: Vec<&Row> = rows.iter().filter(|r| r.shape == *shape).collect();
            format!("`{shape}`: {}", shape_reading(&of))
        })
        .collect();
    if parts.is_empty() {
        return String::new();
    }
    format!("**Reading.** {}\n\n", parts.join(" "))
}

/// The reading of one shape's rows.
fn shape_reading(rows: &[&Row]) -> String {
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
        "at {finest} samples, every corner within {CORNER_KEPT_H} h: {}{}.",
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
    lines.join(" ")
}
