//! The front page's pick for tetrahedra from a label map (one mesh for a whole segmentation),
//! from `data/quality_tets_labels.json` alone.

use super::data::{LabelRow, Labels};
use crate::experiment::choosing::Choice;
use crate::experiment::context::{Context, ExperimentError};
use crate::report::{first_seen, Spread};
use isolab_algorithms::labels::LABEL_INFOS;

/// The page the numbers are on.
const PAGE: &str = "quality_tets";

/// The front page's pick, from the label maps' data.
pub(crate) fn pick(ctx: &Context) -> Result<Choice, ExperimentError> {
    let labels: Labels = ctx.read_data("quality_tets_labels")?;
    pick_over(&labels)
        .ok_or_else(|| ExperimentError::Missing("a mesher of every label map without an inverted tetrahedron".into()))
}

/// The dihedral interval the registry declares for `tool`, if it is one of our label extractors.
fn declared(tool: &str) -> Option<[f64; 2]> {
    let d = LABEL_INFOS.iter().find(|i| i.name == tool)?.guarantees.dihedral?;
    Some([d.min_degrees, d.max_degrees])
}

/// The largest per-label volume error of a row, as a fraction.
fn worst_volume(r: &LabelRow) -> f64 {
    r.volume_error.values().map(|v| v.abs()).fold(0.0, f64::max)
}

/// The rule: among the meshers with a mesh of every map and no inverted tetrahedron on any, the
/// highest worst minimum dihedral angle over the maps; a tie within a tenth of a degree goes to
/// the one that declares an interval. The sentence adds each one's largest per-label volume error
/// and the ratio of median times on each map.
pub(super) fn pick_over(l: &Labels) -> Option<Choice> {
    let maps = first_seen(l.rows.iter().map(|r| r.input.as_str()));
    let tools = first_seen(l.rows.iter().map(|r| r.tool.as_str()));
    let rows_of = |tool: &str| -> Option<Vec<&LabelRow>> {
        maps.iter()
            .map(|m| l.rows.iter().find(|r| r.tool == tool && r.input == *m && r.error.is_none() && r.tetrahedra > 0))
            .collect()
    };
    let fit: Vec<(&str, Vec<&LabelRow>)> =
        tools.iter().filter_map(|&t| Some((t, rows_of(t)?))).filter(|(_, rows)| rows.iter().all(|r| r.inverted == 0)).collect();
    let floor = |rows: &[&LabelRow]| rows.iter().map(|r| r.dihedral[0]).fold(f64::INFINITY, f64::min);
    let key = |(t, rows): &(&str, Vec<&LabelRow>)| floor(rows) + if declared(t).is_some() { 0.1 } else { 0.0 };
    let (best, best_rows) = fit.iter().max_by(|a, b| key(a).total_cmp(&key(b)))?;
    let volume = |rows: &[&LabelRow]| 100.0 * rows.iter().map(|r| worst_volume(r)).fold(0.0, f64::max);
    let others: Vec<String> = fit
        .iter()
        .filter(|(t, _)| t != best)
        .map(|(t, rows)| format!("{t} {:.1}°, largest label volume error {:.1}%", floor(rows), volume(rows)))
        .collect();
    let mut why = format!(
        "Of the meshers with a mesh of each of the {} label maps and no inverted tetrahedron, it has the highest worst minimum \
         dihedral angle, {:.1}°, with a largest label volume error of {:.1}% against the maps' voxel counts{}",
        maps.len(),
        floor(best_rows),
        volume(best_rows),
        if others.is_empty() { String::new() } else { format!(" ({})", others.join("; ")) }
    );
    if let Some([lo, hi]) = declared(best) {
        why.push_str(&format!(", and it declares every angle within {lo:.1}-{hi:.1}°"));
    }
    why.push('.');
    let times: Vec<String> = fit
        .iter()
        .filter(|(t, _)| t != best)
        .flat_map(|(t, rows)| rows.iter().zip(best_rows).map(move |(other, ours)| (*t, other, ours)))
        .filter_map(|(t, other, ours)| {
            let (a, b) = (Spread::of(ours.ms.clone()).median, Spread::of(other.ms.clone()).median);
            (a > 0.0 && b.is_finite()).then(|| format!("{t} {}x on {}", times_ratio(b / a), ours.input))
        })
        .collect();
    if !times.is_empty() {
        why.push_str(&format!(
            " Time, each other's median over its median: {} (ours every run of the whole call in one process, CGAL's \
             `make_mesh_3` alone, one-shot in a fresh process; one thread each).",
            times.join("; ")
        ));
    }
    let unfit: Vec<&str> = tools.iter().copied().filter(|t| !fit.iter().any(|(f, _)| f == t)).collect();
    if !unfit.is_empty() {
        why.push_str(&format!(" Failing a map or inverting a tetrahedron: {}.", unfit.join(", ")));
    }
    Some(Choice { pick: (*best).to_owned(), why, pages: vec![PAGE] })
}

/// A time ratio: whole above ten, two significant digits below.
fn times_ratio(r: f64) -> String {
    if r >= 10.0 {
        format!("{r:.0}")
    } else {
        format!("{:.*}", (1 - r.log10().floor() as i32).max(0) as usize, r)
    }
}
