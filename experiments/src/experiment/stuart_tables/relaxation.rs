//! Why the paper's unguarded ODT update makes slivers here: the relaxation traced iteration by
//! iteration (Stuart et al. 2013, section 3.3, read again).
//!
//! The paper's update (its equation 2 and the sentence after it): every vertex, boundary vertices
//! included, moves toward the volume-weighted mean of its tetrahedra's circumcentres "by an amount
//! proportional to a predetermined time step" (the step is not given); boundary vertices are kept
//! off `S` by El Topo's collision handling; iterations continue while any boundary vertex is
//! farther than `d_offset`. Ours is that update with the time steps of `STUDY_STEPS`, exact
//! collision tests instead of El Topo (a colliding step is halved, then refused), and, by default,
//! a quality floor the paper does not have. The study runs the paper's update (no floor) at each
//! time step and ours with the floor, on one unperturbed lattice per model at the Table 2
//! configuration, and records per iteration the farthest boundary vertex and the smallest dihedral
//! angle, and at the end where the slivers are: how many of their four vertices lie on the boundary.

use super::{TABLE2_CELLS, TABLE2_RATIO};
use crate::experiment::context::{load_object, ExperimentError};
use crate::figures::plot::{self, Scale, Series, Style, XyPlot};
use crate::report::markdown_table;
use isolab_algorithms::extractors::bcc_sculpt::{sculpt_surface, RelaxIteration, SculptOptions};
use isolab_algorithms::geometry::dihedral_angles;
use serde::{Deserialize, Serialize};
use std::collections::HashSet;
use std::path::Path;

/// The time steps tried with the paper's update (ours is the default, 0.25).
pub(super) const STUDY_STEPS: [f32; 4] = [0.1, 0.25, 0.5, 1.0];
/// A tetrahedron whose smallest dihedral angle is below this is counted as a sliver, degrees.
pub(super) const SLIVER_DEG: f64 = 10.0;
/// The model whose traces are plotted.
pub(super) const PLOTTED: &str = "spot";

/// One traced relaxation.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct StudyRun {
    /// Model.
    pub model: String,
    /// Fraction of the way to the ODT position per iteration.
    pub time_step: f32,
    /// Quality floor, degrees (0: the paper's update).
    pub quality_floor: f32,
    /// Met the offset.
    pub converged: bool,
    /// Iterations run.
    pub iterations: usize,
    /// Smallest dihedral angle at the end, degrees.
    pub min_dihedral: f64,
    /// Farthest boundary vertex at the end, in `h`.
    pub max_distance_h: f64,
    /// Slivers at the end by how many of their vertices are on the boundary (0 to 4).
    pub slivers_by_boundary_vertices: [usize; 5],
    /// Per iteration: farthest boundary vertex (h), smallest dihedral angle, boundary vertices
    /// moved and refused.
    pub trace: Vec<(f32, f64, usize, usize)>,
}

impl StudyRun {
    /// The first iteration whose mesh has a dihedral angle below `deg`, and the farthest boundary
    /// vertex then (h).
    pub fn first_below(&self, deg: f64) -> Option<(usize, f32)> {
        self.trace.iter().enumerate().find(|(_, t)| t.1 < deg).map(|(i, t)| (i, t.0))
    }

    /// Slivers in all.
    pub fn slivers(&self) -> usize {
        self.slivers_by_boundary_vertices.iter().sum()
    }
}

/// Runs the study on `models`.
pub(super) fn run(models: &[&str]) -> Result<Vec<StudyRun>, ExperimentError> {
    let mut runs = Vec::new();
    for &model in models {
        let field = load_object(model)?;
        let surface = field.surface_mesh().expect("shipped models are mesh fields");
        let base = SculptOptions {
            cells: TABLE2_CELLS,
            offset_ratio: TABLE2_RATIO,
            perturbations: 1,
            trace: true,
            ..Default::default()
        };
        let mut variants: Vec<SculptOptions> =
            STUDY_STEPS.iter().map(|&time_step| SculptOptions { time_step, quality_floor: 0.0, ..base }).collect();
        variants.push(base);
        for options in variants {
            let result = sculpt_surface(surface, model, &options)?;
            let r = &result.report;
            runs.push(StudyRun {
                model: model.into(),
                time_step: options.time_step,
                quality_floor: options.quality_floor,
                converged: r.converged,
                iterations: r.iterations,
                min_dihedral: r.dihedral_deg[0],
                max_distance_h: f64::from(r.max_distance / r.spacing),
                slivers_by_boundary_vertices: sliver_census(&result.volume, &result.boundary),
                trace: r
                    .trace
                    .iter()
                    .map(|t: &RelaxIteration| (t.max_distance_h, t.min_dihedral, t.boundary_moved, t.boundary_refused))
                    .collect(),
            });
        }
    }
    Ok(runs)
}

/// Tetrahedra below [`SLIVER_DEG`] by how many of their vertices lie on the boundary.
pub(super) fn sliver_census(volume: &isolab_algorithms::TetMesh, boundary: &isolab_algorithms::TriMesh) -> [usize; 5] {
    let key = |p: glam::Vec3| p.to_array().map(f32::to_bits);
    let on_boundary: HashSet<[u32; 3]> = boundary.positions.iter().map(|&p| key(p)).collect();
    let mut census = [0; 5];
    for t in &volume.tetrahedra {
        let p = t.map(|v| volume.positions[v as usize]);
        if dihedral_angles(p).iter().copied().fold(180.0, f64::min) < SLIVER_DEG {
            census[p.iter().filter(|&&x| on_boundary.contains(&key(x))).count()] += 1;
        }
    }
    census
}

/// The study's table, its reading and the plot of [`PLOTTED`]'s traces.
pub(super) fn section(runs: &[StudyRun], floor: f32, plot: Option<&str>) -> String {
    let mut md = format!(
        "**Why the paper's update makes slivers here** (`stuart_tables/relaxation.rs`). The paper moves every vertex, \
         boundary vertices included, toward its ODT position (equation 2) by \"a predetermined time step\" it does not give, \
         keeps `∂V` off `S` with El Topo, and iterates while a boundary vertex is farther than `d_offset`. We ran that \
         update (no quality floor) at time steps {} and ours (step {}, {floor}° floor), one unperturbed lattice per model \
         at h = longest / {TABLE2_CELLS}, ratio {TABLE2_RATIO}, and counted the slivers (smallest dihedral angle below \
         {SLIVER_DEG}°) at the end by how many of their vertices lie on the boundary:\n\n",
        STUDY_STEPS.map(|s| s.to_string()).join(", "),
        SculptOptions::default().time_step,
    );
    let body: Vec<Vec<String>> = runs
        .iter()
        .map(|r| {
            let below = r.first_below(f64::from(floor));
            vec![
                r.model.clone(),
                if r.quality_floor > 0.0 { format!("ours, {}° floor", r.quality_floor) } else { "paper's update".into() },
                r.time_step.to_string(),
                if r.converged { "yes".into() } else { "no".into() },
                r.iterations.to_string(),
                format!("{:.1}°", r.min_dihedral),
                format!("{:.2}", r.max_distance_h),
                below.map_or("never".into(), |(i, d)| format!("{i} ({d:.2} h)")),
                r.slivers().to_string(),
                r.slivers_by_boundary_vertices.map(|c| c.to_string()).join(" / "),
            ]
        })
        .collect();
    md.push_str(&markdown_table(
        &[
            "model",
            "update",
            "time step",
            "converged",
            "iterations",
            "min °",
            "farthest (h)",
            &format!("first below {floor}° (farthest then)"),
            "slivers",
            &format!("by boundary vertices {}", (0..=4).map(|k| k.to_string()).collect::<Vec<_>>().join(" / ")),
        ],
        &body,
    ));
    md.push('\n');
    md.push_str(&reading(runs, floor));
    if let Some(link) = plot {
        md.push_str(&format!("\n![relaxation traces on {PLOTTED}]({link})\n\n"));
    }
    md
}

/// Plots [`PLOTTED`]'s traces as `<dir>/relaxation-trace.{svg,png}`; the SVG's path.
pub(super) fn plot(runs: &[StudyRun], dir: &Path) -> Result<Option<std::path::PathBuf>, ExperimentError> {
    let stem = dir.join("relaxation-trace");
    let series: Vec<Series> = runs
        .iter()
        .filter(|r| r.model == PLOTTED)
        .enumerate()
        .map(|(k, r)| Series {
            label: if r.quality_floor > 0.0 {
                format!("ours, step {}, {}° floor", r.time_step, r.quality_floor)
            } else {
                format!("paper's update, step {}", r.time_step)
            },
            color: crate::figures::series_color(k),
            points: r.trace.iter().map(|t| (f64::from(t.0), t.1.max(0.01))).collect(),
            ranges: Vec::new(),
        })
        .collect();
    if series.is_empty() {
        return Ok(None);
    }
    plot::xy(
        &stem,
        &XyPlot {
            title: format!("{PLOTTED}: smallest dihedral angle against the farthest boundary vertex, per iteration"),
            x_label: "farthest boundary vertex from S (h); iterations run right to left".into(),
            y_label: "smallest dihedral angle (degrees)".into(),
            x_scale: Scale::Linear,
            y_scale: Scale::Log,
            style: Style::Lines,
            series,
        },
    )
    .map_err(ExperimentError::Figure)?;
    Ok(Some(stem.with_extension("svg")))
}

/// What the runs show, computed: where the slivers are and when they appear.
fn reading(runs: &[StudyRun], floor: f32) -> String {
    let paper: Vec<&StudyRun> = runs.iter().filter(|r| r.quality_floor == 0.0).collect();
    let ours: Vec<&StudyRun> = runs.iter().filter(|r| r.quality_floor > 0.0).collect();
    let slivers: usize = paper.iter().map(|r| r.slivers()).sum();
    let by = |k: usize| paper.iter().map(|r| r.slivers_by_boundary_vertices[k]).sum::<usize>();
    let with_sliver = paper.iter().filter(|r| r.slivers() > 0).count();
    let converged_paper = paper.iter().filter(|r| r.converged).count();
    let converged_ours = ours.iter().filter(|r| r.converged).count();
    let floor = f64::from(floor);
    let below: Vec<(usize, f32)> = paper.iter().filter_map(|r| r.first_below(floor)).collect();
    let before_offset = below.iter().filter(|(_, d)| *d > TABLE2_RATIO).count();
    let per_step: Vec<String> = STUDY_STEPS
        .iter()
        .map(|&step| {
            let mut first: Vec<usize> =
                paper.iter().filter(|r| r.time_step == step).filter_map(|r| r.first_below(floor).map(|b| b.0)).collect();
            first.sort_unstable();
            match first.get(first.len() / 2) {
                Some(&m) => format!("{m} at step {step} (step × iterations {:.1})", m as f32 * step),
                None => format!("never at step {step}"),
            }
        })
        .collect();
    let (near, far) = below.iter().fold((f32::INFINITY, 0.0f32), |(lo, hi), b| (lo.min(b.1), hi.max(b.1)));
    format!(
        "The paper's update leaves slivers in {with_sliver} of its {} runs ({slivers} in all). {} of them have exactly \
         three vertices on the boundary and one inside, {} have four, {} fewer than three: a sliver here is a \
         boundary-layer tetrahedron whose boundary vertices came down onto its interior vertex. In {before_offset} of \
         the {} runs whose smallest angle fell below {floor}°, it did so while the farthest boundary vertex was still \
         beyond `d_offset` (between {near:.2} h and {far:.2} h): the collapse comes on the way in, not after convergence. \
         The step size changes when, not whether: the median first iteration below {floor}° is {}, so the \
         collapse comes after about the same distance travelled toward the ODT positions. Converged: \
         {converged_paper} of {} runs with the paper's update, {converged_ours} of {} with ours. Our reading: a \
         boundary vertex's tetrahedra all lie on one side of it, so its ODT position lies inward and the update pulls it \
         in at every iteration, while an interior vertex, surrounded by its tetrahedra, stays near its centre; nothing in \
         the update keeps the boundary layer thick, so the layer thins until its interior vertices lie in the boundary \
         faces' planes. The paper's section 3.2 describes the same flattening for bombs (\"as we adjust these \
         elements' vertices and move them toward the input surface they flatten\"); defusing removes the tetrahedra \
         with two boundary faces, and these slivers are not bombs (none is left after defusing). What the paper's El Topo does on contact (a \
         response that may let a vertex slide along `S`) we do not reproduce, and whether that kept the paper's layer \
         thick is unexplained.\n",
        paper.len(),
        by(3),
        by(4),
        by(0) + by(1) + by(2),
        below.len(),
        per_step.join(", "),
        paper.len(),
        ours.len(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;
    use isolab_algorithms::{TetMesh, TriMesh};

    #[test]
    fn the_census_counts_slivers_by_their_boundary_vertices() {
        // A regular-ish tetrahedron and a sliver whose apex lies almost in its base's plane.
        let positions = vec![
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::new(0.0, 0.0, 1.0),
            Vec3::new(0.4, 0.4, 0.01),
        ];
        let volume = TetMesh { positions: positions.clone(), tetrahedra: vec![[0, 1, 2, 3], [0, 1, 2, 4]] };
        // The boundary holds vertices 0, 1, 2 (and 3): the sliver has three on it.
        let boundary =
            TriMesh { positions: positions[..4].to_vec(), triangles: vec![[0, 2, 1], [0, 1, 3]], ..Default::default() };
        assert_eq!(sliver_census(&volume, &boundary), [0, 0, 0, 1, 0]);
        let run = StudyRun {
            model: "m".into(),
            time_step: 0.25,
            quality_floor: 0.0,
            converged: false,
            iterations: 3,
            min_dihedral: 1.0,
            max_distance_h: 0.7,
            slivers_by_boundary_vertices: [0, 0, 0, 1, 0],
            trace: vec![(0.9, 60.0, 1, 0), (0.8, 15.0, 1, 0), (0.7, 1.0, 0, 1)],
        };
        assert_eq!(run.first_below(20.0), Some((1, 0.8)));
        assert_eq!(run.first_below(0.5), None);
        assert_eq!(run.slivers(), 1);
    }
}
