//! `costen_table`: the RMT paper's benchmark (`../shared/papers/costen-2026-rmt-terrain.txt`,
//! Appendices A and B, Figs. 21-27) regenerated: three objects (sphere, asteroid, Stanford bunny)
//! × two lattices (BCC `b`, simple cubic `s`) × three clusterings (`u` none: plain marching
//! tetrahedra; `i` integrated: regularised marching tetrahedra as published; `p` post-processed:
//! marching tetrahedra then the paper's edge collapse), at 50 cells a side (bunny 75 × 40 × 56),
//! with the paper's numbers beside ours, and two rows per object and lattice the paper does not
//! have: `i+` (our RMT defaults: boundary merging and the manifold guard) and `p+` (the
//! topology-safe edge collapse). Every configuration runs `repeats` times, interleaved, and times
//! are medians.

mod data;
mod page;

use super::context::{load_object, Context, Experiment, ExperimentError};
use crate::report::{median, millis};
use ablations::projection;
use data::Data;
pub use data::{Picture, Row};
use ferreus::against_ferreus;
use figures::{charts, defect_closeup, pictures};
use isolab_algorithms::extract::PostProcess;
use isolab_algorithms::extractors::regularised_marching_tetrahedra::{RegularisedMarchingTetrahedra, RmtOptions};
use isolab_algorithms::extractors::tetrahedral::tetrahedron_count;
use isolab_algorithms::extractors::MarchingTetrahedra;
use isolab_algorithms::mesh::manifold_defects;
use isolab_algorithms::post::EdgeCollapse;
use isolab_algorithms::{Extraction, Extractor, Grid, Lattice, Samples};
use isolab_metrics::MeshMetrics;
use page::{f_discard, num, paper_aspect_range, paper_integrated_reduction, paper_mean_discard, pct};
use passes::{pass_changes, PASS_RUNS};
use sphere_match::matched_sphere;
use std::time::Duration;

mod ablations;

mod counts;

mod ferreus;

mod figures;

mod passes;

mod questionnaire;

mod reading;

mod sphere_match;

/// The experiment.
pub struct CostenTable;

const NAME: &str = "costen_table";

/// The paper's objects: id prefix, our field, and its sample counts (50 cells = 51 samples).
const OBJECTS: [(&str, &str, [usize; 3]); 3] =
    [("ss", "sphere", [51, 51, 51]), ("as", "asteroid", [51, 51, 51]), ("bs", "stanford-bunny", [76, 41, 57])];

/// Clusterings: the paper's three, then ours.
const METHODS: [&str; 5] = ["u", "i", "p", "i+", "p+"];

/// One row of the paper's Appendix B (times in seconds, bytes, percentages).
#[derive(Clone, Copy, Debug)]
pub(super) struct PaperRow {
    /// Configuration: object, lattice, clustering (`as_bi`).
    pub(super) id: &'static str,
    pub(super) t_total: f64,
    pub(super) t_sampling: f64,
    pub(super) t_vertex: f64,
    pub(super) t_geometry: f64,
    pub(super) n_tetrahedra: u64,
    pub(super) n_vertices: u64,
    pub(super) n_triangles: u64,
    pub(super) n_discarded: u64,
    pub(super) b_lattice: u64,
    pub(super) b_edges: u64,
    pub(super) b_vertices: u64,
    pub(super) b_indices: u64,
    /// F_tetrahedra, %.
    pub(super) f_tetrahedra: f64,
    /// F_discard, %.
    pub(super) f_discard: f64,
    pub(super) ar_mean: f64,
    pub(super) ar_sd: f64,
}

/// A [`PaperRow`] in the paper's column order: id, T_total, T_sampling, T_vertex, T_geometry,
/// N_tetrahedra, N_vertices, N_triangles, N_discarded, B_lattice, B_edges, B_vertices, B_indices,
/// F_tetrahedra, F_discard, AR_mean, AR_sd (the table reads as the paper prints it).
#[allow(clippy::too_many_arguments)]
const fn paper_row(
    id: &'static str,
    (t_total, t_sampling, t_vertex, t_geometry): (f64, f64, f64, f64),
    (n_tetrahedra, n_vertices, n_triangles, n_discarded): (u64, u64, u64, u64),
    (b_lattice, b_edges, b_vertices, b_indices): (u64, u64, u64, u64),
    (f_tetrahedra, f_discard, ar_mean, ar_sd): (f64, f64, f64, f64),
) -> PaperRow {
    PaperRow {
        id,
        t_total,
        t_sampling,
        t_vertex,
        t_geometry,
        n_tetrahedra,
        n_vertices,
        n_triangles,
        n_discarded,
        b_lattice,
        b_edges,
        b_vertices,
        b_indices,
        f_tetrahedra,
        f_discard,
        ar_mean,
        ar_sd,
    }
}

#[rustfmt::skip]
const PAPER: [PaperRow; 18] = [
    paper_row("ss_bu", (0.0178, 0.00703, 0.00696, 0.00308), (160992, 50865, 101720, 0), (1114048, 16153696, 1220760, 1220640), (10.52, 0.0, 775.93, 12057.93)),
    paper_row("ss_bi", (0.0182, 0.00712, 0.00748, 0.00288), (160992, 13605, 27200, 105086), (1114048, 16153696, 326520, 326400), (10.52, 79.44, 2.16, 58.67)),
    paper_row("ss_bp", (0.0596, 0.01122, 0.00637, 0.0412), (160992, 13074, 26144, 75576), (1114048, 16153696, 313776, 313728), (10.52, 74.30, 1.23, 0.21)),
    paper_row("ss_su", (0.0118, 0.0066, 0.00314, 0.00179), (70104, 35098, 70192, 0), (530604, 7693758, 842352, 842304), (9.347, 0.0, 1207.37, 15880.64)),
    paper_row("ss_si", (0.0122, 0.00657, 0.00363, 0.00175), (70104, 9296, 18588, 72356), (530604, 7693758, 223104, 223056), (9.347, 79.56, 1.34, 0.28)),
    paper_row("ss_sp", (0.0403, 0.0108, 0.0031, 0.0261), (70104, 10685, 21366, 48826), (530604, 7693758, 256440, 256392), (9.347, 69.56, 1.38, 0.32)),
    paper_row("as_bu", (0.0288, 0.0203, 0.00625, 0.00144), (72240, 22550, 45096, 0), (1114048, 16153696, 541200, 541152), (4.722, 0.0, 5.81, 78.56)),
    paper_row("as_bi", (0.0294, 0.0206, 0.00668, 0.00142), (72240, 6012, 12020, 46530), (1114048, 16153696, 144288, 144240), (4.722, 79.47, 1.16, 0.15)),
    paper_row("as_bp", (0.0458, 0.0215, 0.00623, 0.0174), (72240, 5665, 11326, 33770), (1114048, 16153696, 135960, 135912), (4.722, 74.88, 1.23, 0.21)),
    paper_row("as_su", (0.0166, 0.0123, 0.00288, 0.00113), (31572, 15840, 31676, 0), (530604, 7693758, 380160, 380112), (4.210, 0.0, 6.53, 106.34)),
    paper_row("as_si", (0.0172, 0.0125, 0.00323, 0.00115), (31572, 4172, 8340, 32743), (530604, 7693758, 100128, 100080), (4.210, 79.70, 1.33, 0.28)),
    paper_row("as_sp", (0.0306, 0.0159, 0.00283, 0.0115), (31572, 4697, 9390, 22286), (530604, 7693758, 112728, 112680), (4.210, 70.36, 1.39, 0.32)),
    paper_row("bs_bu", (10.0, 10.0, 0.01, 0.00229), (122808, 37332, 74660, 0), (1487640, 21570780, 895968, 895920), (5.980, 0.0, 9.43, 522.45)),
    paper_row("bs_bi", (9.9, 9.89, 0.0112, 0.0022), (122808, 10256, 20508, 77111), (1487640, 21570780, 246144, 246096), (5.980, 78.99, 1.17, 0.16)),
    paper_row("bs_bp", (10.0, 9.96, 0.0101, 0.0297), (122808, 9669, 19334, 55326), (1487640, 21570780, 232056, 232008), (5.980, 74.10, 1.24, 0.21)),
    paper_row("bs_su", (5.96, 5.95, 0.00391, 0.00161), (50910, 25384, 50764, 0), (710448, 10301496, 609216, 609168), (5.051, 0.0, 7.89, 187.63)),
    paper_row("bs_si", (5.98, 5.97, 0.00467, 0.00168), (50910, 6579, 13154, 52610), (710448, 10301496, 157896, 157848), (5.051, 79.99, 1.35, 0.28)),
    paper_row("bs_sp", (5.86, 5.83, 0.00404, 0.0182), (50910, 7616, 15228, 35536), (710448, 10301496, 182784, 182736), (5.051, 70.00, 1.39, 0.32)),
];

/// Extracts with method `m` (one of [`METHODS`]).
fn run_method(m: &str, samples: &Samples, out: &mut Extraction) -> Result<usize, ExperimentError> {
    let rmt = RegularisedMarchingTetrahedra::new;
    match m {
        "u" | "p" | "p+" => MarchingTetrahedra::default().extract(samples, out)?,
        "i" => rmt(RmtOptions::paper()).extract(samples, out)?,
        _ => rmt(RmtOptions::default()).extract(samples, out)?,
    }
    let scratch = out.stats.buffer_bytes.saturating_sub(out.surface.capacity_bytes() + out.volume.capacity_bytes());
    match m {
        "p" => EdgeCollapse::paper(isolab_algorithms::post::edge_collapse::DEFAULT_THRESHOLD).apply(samples, out)?,
        "p+" => EdgeCollapse::safe(isolab_algorithms::post::edge_collapse::DEFAULT_THRESHOLD).apply(samples, out)?,
        _ => {}
    }
    Ok(scratch)
}

impl Experiment for CostenTable {
    fn name(&self) -> &'static str {
        NAME
    }

    fn question(&self) -> &'static str {
        "Does regularised marching tetrahedra reproduce Costen's benchmark: counts, times and quality?"
    }

    fn peers(&self) -> &'static [&'static str] {
        &["ferreus_rmt"]
    }

    fn run(&self, ctx: &Context) -> Result<(), ExperimentError> {
        let dir = ctx.figure_dir(NAME)?;
        let repeats = ctx.repeats;
        let bar = ctx.bar(NAME, (OBJECTS.len() * 2 * repeats) as u64 + 3);
        let mut rows = Vec::new();
        let mut closeups = Vec::new();
        for (prefix, name, dims) in OBJECTS {
            let field = load_object(name)?;
            for (code, bcc) in [("b", true), ("s", false)] {
                let grid = Grid::with_dims(&field.domain(), dims)?;
                let lattice = if bcc { Lattice::Bcc(grid) } else { Lattice::Cubic(grid) };
                // Interleaved repeats: sample, then every method once, per round.
                let mut times: Vec<[Vec<Duration>; 5]> = METHODS.iter().map(|_| Default::default()).collect();
                let mut sampling = Vec::new();
                let mut last: Vec<(Extraction, usize)> = Vec::new();
                for r in 0..repeats {
                    let samples = Samples::sample(field.clone(), lattice, 0.0)?;
                    sampling.push(samples.sampling_time());
                    for (k, m) in METHODS.iter().enumerate() {
                        let mut out = Extraction::default();
                        let scratch = run_method(m, &samples, &mut out)?;
                        let t = out.stats.times;
                        for (slot, d) in times[k].iter_mut().zip([t.vertex, t.geometry, t.normals, t.post, t.extraction()]) {
                            slot.push(d);
                        }
                        if r + 1 == repeats {
                            last.push((out, scratch));
                        }
                    }
                    bar.inc(1);
                }
                let unmerged = last[0].0.surface.triangles.len().max(1);
                for (m, (out, _)) in METHODS.iter().zip(&last) {
                    let id = format!("{prefix}_{code}{m}");
                    if let Some(picture) = defect_closeup(ctx, &dir, &id, &out.surface, grid.spacing)? {
                        closeups.push(picture);
                    }
                }
                for (k, (m, (out, scratch))) in METHODS.iter().zip(last).enumerate() {
                    let [v, g, n, p, _] = times[k].clone().map(median);
                    let metrics = MeshMetrics::measure(&out.surface, Some((field.as_ref(), 0.0)));
                    rows.push(Row {
                        id: format!("{prefix}_{code}{m}"),
                        field: name.into(),
                        lattice: lattice.kind().into(),
                        dims,
                        spacing: f64::from(grid.spacing),
                        t_sampling: millis(median(sampling.clone())),
                        t_vertex: millis(v),
                        t_geometry: millis(g),
                        t_normals: millis(n),
                        t_post: millis(p),
                        n_tetrahedra: out.stats.active_cells,
                        total_tetrahedra: tetrahedron_count(&lattice),
                        n_vertices: out.surface.positions.len(),
                        n_triangles: out.surface.triangles.len(),
                        n_discarded: out.stats.discarded_triangles,
                        b_lattice: lattice.sample_count() * 4,
                        b_edges: scratch,
                        b_vertices: out.surface.positions.len() * 24,
                        b_indices: out.surface.triangles.len() * 12,
                        removed: 1.0 - out.surface.triangles.len() as f64 / unmerged as f64,
                        defects: manifold_defects(&out.surface).len(),
                        metrics,
                    });
                }
            }
        }
        let mut pictures = pictures(ctx, &dir)?;
        pictures.extend(closeups);
        bar.inc(3);
        charts(&dir, &rows)?;
        let peers = against_ferreus(repeats)?;
        let projection = projection(repeats)?;
        let matched_sphere = matched_sphere(&rows)?;
        let pass_changes = pass_changes(PASS_RUNS)?;
        bar.finish();
        ctx.write_data(NAME, &Data { repeats, rows, pictures, peers, projection, matched_sphere, pass_changes })
    }

    fn section(&self, ctx: &Context) -> Result<String, ExperimentError> {
        page::section(ctx)
    }
}

/// The paper's processor, as it names it.
const PAPER_CPU: &str = "an Intel i7-11700";

/// Its logical processors.
const PAPER_LOGICAL_PROCESSORS: usize = 16;

#[cfg(test)]
mod tests;
