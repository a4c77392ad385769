//! Our additions to the paper, measured: projecting merged vertices onto the level set.

use super::{num, OBJECTS};
use crate::experiment::context::{load_object, ExperimentError};
use crate::report::{markdown_table, median, millis};
use isolab_algorithms::extractors::regularised_marching_tetrahedra::{RegularisedMarchingTetrahedra, RmtOptions};
use isolab_algorithms::{Extraction, Extractor, Grid, Lattice, Samples};
use isolab_metrics::MeshMetrics;
use serde::{Deserialize, Serialize};

/// RMT with merged vertices at the mean, and projected with Newton steps (`project=newton`).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ProjectionRow {
    /// Field name.
    pub field: String,
    /// Grid spacing.
    pub spacing: f64,
    /// Merged vertices at the mean of their crossings.
    pub mean: MeshMetrics,
    /// Merged vertices projected.
    pub newton: MeshMetrics,
    /// Median extraction time, ms: mean, projected.
    pub times_ms: [f64; 2],
}

/// Our RMT (BCC) with and without the Newton projection of merged vertices.
pub(super) fn projection(repeats: usize) -> Result<Vec<ProjectionRow>, ExperimentError> {
    use isolab_algorithms::extractors::regularised_marching_tetrahedra::Projection;
    let mut rows = Vec::new();
    for (_, name, dims) in OBJECTS {
        let field = load_object(name)?;
        let grid = Grid::with_dims(&field.domain(), dims)?;
        let samples = Samples::sample(field.clone(), Lattice::Bcc(grid), 0.0)?;
        let measure = |projection| -> Result<(MeshMetrics, f64), ExperimentError> {
            let e = RegularisedMarchingTetrahedra::new(RmtOptions { projection, ..Default::default() });
            let mut out = Extraction::default();
            let mut t = Vec::new();
            for _ in 0..repeats {
                e.extract(&samples, &mut out)?;
                t.push(out.stats.times.extraction());
            }
            Ok((MeshMetrics::measure(&out.surface, Some((field.as_ref(), 0.0))), millis(median(t))))
        };
        let (mean, t_mean) = measure(Projection::Mean)?;
        let (newton, t_newton) = measure(Projection::Newton)?;
        rows.push(ProjectionRow {
            field: name.into(),
            spacing: f64::from(grid.spacing),
            mean,
            newton,
            times_ms: [t_mean, t_newton],
        });
    }
    Ok(rows)
}

pub(super) fn projection_section(rows: &[ProjectionRow]) -> String {
    if rows.is_empty() {
        return String::new();
    }
    let mut md = String::from(
        "\n### Projecting merged vertices onto the surface (`project=newton`)\n\nOur RMT on BCC at the benchmark resolutions, merged \
         vertices at the mean of their crossings (the paper) or moved onto the level set with up to three Newton steps along \
         the field gradient. Distances in grid spacings.\n\n",
    );
    let body: Vec<Vec<String>> = rows
        .iter()
        .flat_map(|r| {
            [("mean", &r.mean, r.times_ms[0]), ("newton", &r.newton, r.times_ms[1])].map(|(label, m, t)| {
                let d = m.surface_distance.as_ref();
                vec![
                    format!("{} / {label}", r.field),
                    d.map_or("-".into(), |d| format!("{:.4}", d.mean / r.spacing)),
                    d.map_or("-".into(), |d| format!("{:.3}", d.max / r.spacing)),
                    m.normal_deviation.as_ref().map_or("-".into(), |n| format!("{:.2}°", n.mean_deg)),
                    format!("{:.3}", m.quality.aspect_ratio.mean),
                    format!("{:.1}°", m.quality.min_angle_deg),
                    if m.topology.is_watertight_manifold() { "yes".into() } else { "**no**".into() },
                    m.intersecting_pairs().to_string(),
                    num(t),
                ]
            })
        })
        .collect();
    md.push_str(&markdown_table(
        &[
            "object / vertices",
            "mean distance (h)",
            "max distance (h)",
            "normal deviation",
            "AR mean",
            "min angle",
            "closed manifold",
            "self-intersections",
            "extraction ms",
        ],
        &body,
    ));
    md
}
