//! The page `report/decimation.md`, rendered from the data file alone.

use super::data::{Data, Row};
use super::{NAME, OUTLIER_FACTOR};
use crate::experiment::context::{Context, ExperimentError};
use crate::figures::plot::{self, Scale, Series, Style, XyPlot};
use crate::report::markdown_table;

/// The page, from the data file alone.
pub(super) fn section(ctx: &Context) -> Result<String, ExperimentError> {
    let data: Data = ctx.read_data(NAME)?;
    let mut md = String::from("## Simplification against established decimators (`decimation`)\n\n");
    md.push_str(&format!(
        "Plain marching tetrahedra on BCC at the RMT paper's resolutions, simplified to the triangle count the paper's sweep \
         reaches and to a quarter of the input: our paper sweep, our topology-safe collapse (midpoint placement), \
         pymeshlab's quadric edge collapse (topology preserving, optimal placement), CGAL's edge_collapse (its default \
         Lindstrom-Turk cost and placement) and OpenMesh's Decimater (quadric priority, normal-flipping guard; it keeps \
         vertices where they were). The C++ decimators are the programs in `tests/reference/decimators/`, timing their \
         own collapse in process (file reading excluded); pymeshlab's time is its filter's. Shape columns cover the \
         triangles with an area; *zero-area* counts the others. Hausdorff is two-sided to the unsimplified surface, \
         sampled at vertices, face centroids and edge midpoints, in grid spacings. Our safe collapse runs with its \
         self-intersection test (the default) and without it (`intersections=allow`). Median of {} runs.\n\n",
        data.repeats
    ));
    md.push_str(&reading(&data.rows));
    md.push_str(&figure(ctx, &data.rows)?);
    let body: Vec<Vec<String>> = data
        .rows
        .iter()
        .map(|r| {
            vec![
                format!("{} ({} → {})", r.object, r.input_triangles, r.target),
                r.decimator.clone(),
                r.triangles.to_string(),
                format!("{:.3}", r.aspect_mean),
                format!("{:.1}°", r.min_angle_deg),
                r.degenerate.to_string(),
                format!("{:.3}", r.hausdorff_h),
                if r.manifold { "yes".into() } else { "**no**".into() },
                if r.self_intersections == 0 {
                    r.self_intersections.to_string()
                } else {
                    format!("**{}**", r.self_intersections)
                },
                crate::experiment::context::ms(r.ms),
            ]
        })
        .collect();
    md.push_str(&markdown_table(
        &[
            "input → target",
            "decimator",
            "triangles",
            "AR mean",
            "min angle",
            "zero-area",
            "Hausdorff (h)",
            "closed manifold",
            "self-intersecting pairs",
            "ms",
        ],
        &body,
    ));
    if !data.skipped.is_empty() {
        md.push_str("\n**Not run:** ");
        md.push_str(&data.skipped.join("; "));
        md.push('\n');
    }
    Ok(md)
}

/// The page's figure, drawn at assembly from the rows: each decimator's Hausdorff distance
/// against its time, one point per input and target.
pub(super) fn figure(ctx: &Context, rows: &[Row]) -> Result<String, ExperimentError> {
    let decimators: Vec<&str> = crate::report::first_seen(rows.iter().map(|r| r.decimator.as_str()));
    if decimators.is_empty() {
        return Ok(String::new());
    }
    let series = decimators
        .iter()
        .map(|d| (d, crate::figures::color_of(d)))
        .map(|(d, color)| Series {
            label: (*d).to_owned(),
            color,
            points: rows.iter().filter(|r| r.decimator == *d).map(|r| (r.ms, r.hausdorff_h)).collect(),
            ranges: Vec::new(),
        })
        .collect();
    let chart = XyPlot {
        title: "Distance to the input against time, every input and target".into(),
        x_label: "time, ms".into(),
        y_label: "Hausdorff distance to the input, grid spacings".into(),
        x_scale: Scale::Log,
        y_scale: Scale::Linear,
        style: Style::Scatter,
        series,
    };
    let stem = ctx.figure_dir(NAME)?.join("distance-time");
    plot::xy(&stem, &chart).map_err(ExperimentError::Figure)?;
    Ok(format!(
        "![Distance to the input against time]({})\n\n_Each point is one decimator on one input and target; lower and to \
         the left is better._\n\n",
        ctx.link(&stem.with_extension("png"))
    ))
}

/// What the table shows, worded from its rows: who keeps every mesh clean, who comes nearest the
/// input (Hausdorff) and makes the best-shaped triangles most often, the median times, and the
/// outliers nobody explained.
pub(super) fn reading(rows: &[Row]) -> String {
    let decimators: Vec<&str> = crate::report::first_seen(rows.iter().map(|r| r.decimator.as_str()));
    let cases: Vec<(&str, usize)> = crate::report::first_seen(rows.iter().map(|r| (r.object.as_str(), r.target)));
    if rows.is_empty() {
        return String::new();
    }
    let of = |d: &str| rows.iter().filter(move |r| r.decimator == d).collect::<Vec<_>>();
    let clean: Vec<&str> =
        decimators.iter().copied().filter(|d| of(d).iter().all(|r| r.manifold && r.self_intersections == 0)).collect();
    let unclean: Vec<String> = decimators
        .iter()
        .filter(|d| !clean.contains(d))
        .map(|d| {
            let rs = of(d);
            format!(
                "{d} ({} of {} not closed manifold, {} self-intersecting pairs in all)",
                rs.iter().filter(|r| !r.manifold).count(),
                rs.len(),
                rs.iter().map(|r| r.self_intersections).sum::<usize>()
            )
        })
        .collect();
    let mut lines = Vec::new();
    if !clean.is_empty() {
        lines.push(format!("Closed, manifold and free of self-intersections on every input: {}.", clean.join(", ")));
    }
    if !unclean.is_empty() {
        lines.push(format!("Not always: {}.", unclean.join("; ")));
    }
    let wins = |better: &dyn Fn(&Row, &Row) -> bool| -> Vec<(String, usize)> {
        let mut count: Vec<(String, usize)> = decimators.iter().map(|d| (d.to_string(), 0)).collect();
        for (object, target) in &cases {
            let here: Vec<&Row> = rows.iter().filter(|r| r.object == *object && r.target == *target).collect();
            if let Some(best) = here.iter().copied().reduce(|a, b| if better(b, a) { b } else { a }) {
                if let Some(c) = count.iter_mut().find(|(d, _)| *d == best.decimator) {
                    c.1 += 1;
                }
            }
        }
        count.retain(|(_, n)| *n > 0);
        count.sort_by_key(|c| std::cmp::Reverse(c.1));
        count
    };
    let said = |w: Vec<(String, usize)>| w.iter().map(|(d, n)| format!("{d} {n}")).collect::<Vec<_>>().join(", ");
    lines.push(format!(
        "Nearest the input (least Hausdorff distance), cases won of {}: {}.",
        cases.len(),
        said(wins(&|a, b| a.hausdorff_h < b.hausdorff_h))
    ));
    lines.push(format!(
        "Best-shaped triangles (least mean aspect ratio), cases won of {}: {}.",
        cases.len(),
        said(wins(&|a, b| a.aspect_mean < b.aspect_mean))
    ));
    let median_ms: Vec<String> = decimators
        .iter()
        .map(|d| {
            format!(
                "{d} {}",
                crate::experiment::context::ms(crate::report::Spread::of(of(d).iter().map(|r| r.ms).collect()).median)
            )
        })
        .collect();
    lines.push(format!("Median time over the cases, ms: {}.", median_ms.join(", ")));
    for (object, target) in &cases {
        let here: Vec<&Row> = rows.iter().filter(|r| r.object == *object && r.target == *target).collect();
        for r in &here {
            let others =
                crate::report::Spread::of(here.iter().filter(|o| o.decimator != r.decimator).map(|o| o.aspect_mean).collect())
                    .median;
            if r.aspect_mean > OUTLIER_FACTOR * others {
                lines.push(format!(
                    "On {object} at {target} triangles, {}'s mean aspect ratio is {:.1} against the others' median {:.2}, its \
                     minimum angle {:.1}° (unexplained).",
                    r.decimator, r.aspect_mean, others, r.min_angle_deg
                ));
            }
        }
    }
    format!("**Reading.** {}\n\n", lines.join(" "))
}
