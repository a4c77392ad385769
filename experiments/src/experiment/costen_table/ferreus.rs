//! The side-by-side run against the `ferreus_rmt` crate (an independent, surface-following RMT).

use super::{num, OBJECTS};
use crate::experiment::context::{load_object, ExperimentError};
use crate::peers::ferreus_rmt::FerreusRmt;
use crate::peers::{Job, Peer, Protocol};
use crate::report::{markdown_table, median, millis};
use isolab_algorithms::extractors::regularised_marching_tetrahedra::RegularisedMarchingTetrahedra;
use isolab_algorithms::{Extraction, Extractor, Grid, Lattice, Samples};
use isolab_metrics::MeshMetrics;
use serde::{Deserialize, Serialize};

/// Our RMT against `ferreus_rmt` on one object (BCC, same spacing), medians of interleaved runs.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct PeerRow {
    /// Field name.
    pub field: String,
    /// Grid spacing.
    pub spacing: f64,
    /// Ours: sampling plus extraction, ms.
    pub ours_total_ms: f64,
    /// Ours: extraction only, ms.
    pub ours_extraction_ms: f64,
    /// Field evaluations we make (every lattice sample).
    pub ours_evaluations: usize,
    /// Theirs: `build_isosurface`, field evaluations included, ms.
    pub theirs_ms: f64,
    /// Field evaluations they make.
    pub theirs_evaluations: usize,
    /// Whether their triangles had to be flipped to face outward.
    pub theirs_flipped: bool,
    /// Our mesh's metrics.
    pub ours: MeshMetrics,
    /// Their mesh's metrics.
    pub theirs: MeshMetrics,
}

/// Our guarded RMT and `ferreus_rmt` on the paper's three objects, alternating, `repeats` times.
pub(super) fn against_ferreus(repeats: usize) -> Result<Vec<PeerRow>, ExperimentError> {
    let mut rows = Vec::new();
    for (_, name, dims) in OBJECTS {
        let field = load_object(name)?;
        let grid = Grid::with_dims(&field.domain(), dims)?;
        let lattice = Lattice::Bcc(grid);
        let (mut ours_total, mut ours_extraction, mut theirs) = (Vec::new(), Vec::new(), Vec::new());
        let mut last = None;
        for _ in 0..repeats {
            let t = std::time::Instant::now();
            let samples = Samples::sample(field.clone(), lattice, 0.0)?;
            let mut out = Extraction::default();
            RegularisedMarchingTetrahedra::default().extract(&samples, &mut out)?;
            ours_total.push(t.elapsed());
            ours_extraction.push(out.stats.times.extraction());
            let seeds = crate::peers::seeds_from(&out.surface, SEED_EVERY);
            let job = Job::Field { field: field.as_ref(), domain: grid.bounds(), spacing: grid.spacing, iso: 0.0, seeds: &seeds };
            let run = FerreusRmt.run(&job, Protocol::OneShot)?;
            theirs.push(run.time);
            last = Some((out, run));
        }
        let Some((out, run)) = last else { continue };
        let theirs_mesh = run.mesh.unwrap_or_default();
        rows.push(PeerRow {
            field: name.into(),
            spacing: f64::from(grid.spacing),
            ours_total_ms: millis(median(ours_total)),
            ours_extraction_ms: millis(median(ours_extraction)),
            ours_evaluations: lattice.sample_count(),
            theirs_ms: millis(median(theirs)),
            theirs_evaluations: run.evaluations.unwrap_or(0),
            theirs_flipped: run.flipped,
            ours: MeshMetrics::measure(&out.surface, Some((field.as_ref(), 0.0))),
            theirs: MeshMetrics::measure(&theirs_mesh, Some((field.as_ref(), 0.0))),
        });
    }
    Ok(rows)
}

/// `ferreus_rmt` starts from every this many vertices of our mesh.
const SEED_EVERY: usize = 500;

pub(super) fn peer_section(rows: &[PeerRow]) -> String {
    if rows.is_empty() {
        return String::new();
    }
    let mut md = format!(
        "\n### Against `ferreus_rmt`\n\nThe `ferreus_rmt` crate (Maptek; its version is in `Cargo.lock`) is an independent regularised marching tetrahedra \
         that follows the surface from seed points (here every {SEED_EVERY}th vertex of our mesh) instead of sampling the whole volume, \
         on Treece's stacked-plane lattice at the same spacing. Both evaluate the field in parallel; its time includes its field \
         evaluations, so compare it with our sampling + extraction. Both one-shot: every run builds a new extractor and a fresh \
         output (ours) or calls its builder anew (theirs). Same field, same spacing, runs alternating, medians.\n\n",
    );
    let body: Vec<Vec<String>> = rows
        .iter()
        .flat_map(|r| {
            let line = |who: &str, time: String, evals: usize, m: &MeshMetrics| {
                let q = &m.quality;
                vec![
                    format!("{} / {who}", r.field),
                    time,
                    evals.to_string(),
                    m.triangles.to_string(),
                    format!("{:.3}", q.aspect_ratio.mean),
                    format!("{:.2}", q.aspect_ratio.sd),
                    format!("{:.1}°", q.min_angle_deg),
                    if m.topology.is_watertight_manifold() { "yes".into() } else { "**no**".into() },
                    m.intersecting_pairs().to_string(),
                    m.surface_distance.as_ref().map_or("-".into(), |d| format!("{:.3} h", d.mean / r.spacing)),
                ]
            };
            [
                line(
                    "isolab",
                    format!("{} ({} extraction)", num(r.ours_total_ms), num(r.ours_extraction_ms)),
                    r.ours_evaluations,
                    &r.ours,
                ),
                line(
                    if r.theirs_flipped { "ferreus_rmt (flipped)" } else { "ferreus_rmt" },
                    num(r.theirs_ms),
                    r.theirs_evaluations,
                    &r.theirs,
                ),
            ]
        })
        .collect();
    md.push_str(&markdown_table(
        &[
            "object / implementation",
            "ms",
            "field evaluations",
            "triangles",
            "AR mean",
            "AR sd",
            "min angle",
            "closed manifold",
            "self-intersections",
            "mean distance",
        ],
        &body,
    ));
    md
}
