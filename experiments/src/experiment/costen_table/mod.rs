//! `costen_table`: the RMT paper's benchmark (`../shared/papers/costen-2026-rmt-terrain.txt`,
//! Appendices A and B, Figs. 21-27) regenerated: three objects (sphere, asteroid, Stanford bunny)
//! × two lattices (BCC `b`, simple cubic `s`) × three clusterings (`u` none: plain marching
//! tetrahedra; `i` integrated: regularised marching tetrahedra as published; `p` post-processed:
//! marching tetrahedra then the paper's edge collapse), at 50 cells a side (bunny 75 × 40 × 56),
//! with the paper's numbers beside ours, and two rows per object and lattice the paper does not
//! have: `i+` (our RMT defaults: boundary merging and the manifold guard) and `p+` (the
//! topology-safe edge collapse). Every configuration runs `repeats` times, interleaved, and times
//! are medians.

use super::context::{load_object, Context, Experiment, ExperimentError};
use crate::report::{markdown_table, median, millis};
use isolab_algorithms::extract::PostProcess;
use isolab_algorithms::extractors::regularised_marching_tetrahedra::{RegularisedMarchingTetrahedra, RmtOptions};
use isolab_algorithms::extractors::tetrahedral::tetrahedron_count;
use isolab_algorithms::extractors::MarchingTetrahedra;
use isolab_algorithms::mesh::manifold_defects;
use isolab_algorithms::post::EdgeCollapse;
use isolab_algorithms::{Extraction, Extractor, Grid, Lattice, Samples};
use isolab_metrics::MeshMetrics;
use serde::{Deserialize, Serialize};
use std::time::Duration;

mod ablations;
mod counts;
mod ferreus;
mod figures;
mod passes;
mod questionnaire;
mod reading;
mod sphere_match;

use ablations::{projection, projection_section, ProjectionRow};
use ferreus::{against_ferreus, peer_section, PeerRow};
use figures::{charts, defect_closeup, pictures};
use passes::{pass_changes, passes_section, PassChange, PASS_RUNS};
use questionnaire::questionnaire_section;
use reading::{differences, reading};
use sphere_match::{matched_section, matched_sphere, sphere_radius, MatchedRow};

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

/// One configuration, measured.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Row {
    /// The paper's id (`as_bi`), ours with a `+`.
    pub id: String,
    /// Field name.
    pub field: String,
    /// `bcc` or `cubic`.
    pub lattice: String,
    /// Samples per axis of the corner grid.
    pub dims: [usize; 3],
    /// Grid spacing h.
    pub spacing: f64,
    /// Median times, ms.
    pub t_sampling: f64,
    /// Vertex pass.
    pub t_vertex: f64,
    /// Geometry pass (with the guard's checks for `i+`).
    pub t_geometry: f64,
    /// Normals.
    pub t_normals: f64,
    /// Edge collapse (`p`, `p+`).
    pub t_post: f64,
    /// Tetrahedra with a sign change.
    pub n_tetrahedra: usize,
    /// Tetrahedra in the lattice.
    pub total_tetrahedra: usize,
    /// Vertices.
    pub n_vertices: usize,
    /// Triangles.
    pub n_triangles: usize,
    /// Triangles discarded (repeated vertex, or removed by the collapse).
    pub n_discarded: usize,
    /// Samples × 4 bytes.
    pub b_lattice: usize,
    /// Per-sample scratch bytes (the paper's per-edge flags and indices).
    pub b_edges: usize,
    /// Vertices × 24 bytes (position and normal).
    pub b_vertices: usize,
    /// Triangles × 12 bytes.
    pub b_indices: usize,
    /// Triangles removed against plain marching tetrahedra on the same lattice, fraction.
    pub removed: f64,
    /// Vertices where the mesh is not a consistently wound manifold.
    pub defects: usize,
    /// Every metric of the mesh.
    pub metrics: MeshMetrics,
}

/// One side-by-side picture.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Picture {
    /// What it shows.
    pub caption: String,
    /// Path relative to the report.
    pub path: String,
}

#[derive(Serialize, Deserialize)]
struct Data {
    repeats: usize,
    rows: Vec<Row>,
    pictures: Vec<Picture>,
    #[serde(default)]
    peers: Vec<PeerRow>,
    #[serde(default)]
    projection: Vec<ProjectionRow>,
    #[serde(default)]
    matched_sphere: Vec<MatchedRow>,
    #[serde(default)]
    pass_changes: Vec<PassChange>,
}

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
        let data: Data = ctx.read_data(NAME)?;
        Ok(section(ctx, &data))
    }
}

/// The smallest and largest fraction of plain marching tetrahedra's triangles that integrated
/// clustering removes, from the paper's own Appendix B counts (`*_bi` against `*_bu`, `*_si`
/// against `*_su`).
fn paper_integrated_reduction() -> (f64, f64) {
    let triangles = |id: &str| PAPER.iter().find(|p| p.id == id).map(|p| p.n_triangles as f64);
    PAPER
        .iter()
        .filter_map(|p| {
            let stem = p.id.strip_suffix('i')?;
            Some(1.0 - p.n_triangles as f64 / triangles(&format!("{stem}u"))?)
        })
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), x| (lo.min(x), hi.max(x)))
}

/// The paper's processor, as it names it.
const PAPER_CPU: &str = "an Intel i7-11700";
/// Its logical processors.
const PAPER_LOGICAL_PROCESSORS: usize = 16;

/// The paper's edge scratch per sample on the simple cubic lattice (`B_edges` over the samples of
/// the first object's `*_su` row), bytes.
fn paper_edge_bytes_per_sample() -> f64 {
    let (id, dims) = (format!("{}_su", OBJECTS[0].0), OBJECTS[0].2);
    PAPER.iter().find(|p| p.id == id).map_or(f64::NAN, |p| p.b_edges as f64 / dims.iter().product::<usize>() as f64)
}

/// The paper's mean `F_discard` (%) over the rows of one clustering (`i` or `p`): its text's
/// "average reduction of 79.53%" (integrated) and "72.20%" (post-processed), recomputed.
fn paper_mean_discard(method: char) -> f64 {
    let v: Vec<f64> = PAPER.iter().filter(|p| p.id.ends_with(method)).map(|p| p.f_discard).collect();
    v.iter().sum::<f64>() / v.len().max(1) as f64
}

/// The range of the paper's mean aspect ratio over the rows of one clustering (`u`, `i`, `p`).
fn paper_aspect_range(method: char) -> (f64, f64) {
    PAPER
        .iter()
        .filter(|p| p.id.ends_with(method))
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| (lo.min(p.ar_mean), hi.max(p.ar_mean)))
}

fn pct(x: f64) -> String {
    format!("{:.1}%", 100.0 * x)
}

fn num(x: f64) -> String {
    if x.abs() >= 100.0 {
        format!("{x:.0}")
    } else if x.abs() >= 10.0 {
        format!("{x:.1}")
    } else {
        format!("{x:.2}")
    }
}

/// "ours (paper)" or "ours" when the paper has no such row.
fn pair(ours: String, paper: Option<String>) -> String {
    match paper {
        Some(p) => format!("{ours} ({p})"),
        None => ours,
    }
}

fn f_discard(r: &Row) -> f64 {
    r.n_discarded as f64 / (r.n_discarded + r.n_triangles).max(1) as f64
}

fn section(ctx: &Context, data: &Data) -> String {
    let mut md = String::from("## Regularised marching tetrahedra: the paper's benchmark (`costen_table`)\n\n");
    let cells = |dims: [usize; 3]| dims.map(|n| n - 1);
    let [cube, ..] = cells(OBJECTS[0].2);
    let [bx, by, bz] = cells(OBJECTS[2].2);
    let radius = load_object(OBJECTS[0].1).map_or(f64::NAN, |f| sphere_radius(f.as_ref(), 0.0));
    // What the collapse removes on the asteroid, ours and the paper's: one minus `bp` over `bu`.
    let ours_triangles = |id: &str| data.rows.iter().find(|r| r.id == id).map(|r| r.n_triangles as f64);
    let paper_triangles = |id: &str| PAPER.iter().find(|p| p.id == id).map(|p| p.n_triangles as f64);
    let removed = |bp: Option<f64>, bu: Option<f64>| match (bp, bu) {
        (Some(bp), Some(bu)) if bu > 0.0 => format!("{:.1}%", 100.0 * (1.0 - bp / bu)),
        _ => "-".to_string(),
    };
    let as_bp_ours = removed(ours_triangles("as_bp"), ours_triangles("as_bu"));
    let as_bp_paper = removed(paper_triangles("as_bp"), paper_triangles("as_bu"));
    let samples = |dims: [usize; 3]| dims.iter().product::<usize>().max(1) as f64;
    let (edge_lo, edge_hi) = data
        .rows
        .iter()
        .filter(|r| r.lattice == "cubic")
        .map(|r| r.b_edges as f64 / samples(r.dims))
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), b| (lo.min(b), hi.max(b)));
    md.push_str(&format!(
        "Appendix B of Costen (2026) regenerated: {} objects × two lattices (`b` BCC, `s` simple cubic, six tetrahedra per cube) × \
         {} clusterings (`u` none, `i` integrated as published, `p` plain marching tetrahedra then the paper's edge collapse; the \
         paper gives no threshold; ours is the post-process's default, {} h, a constant: on our asteroid it removes {as_bp_ours} of \
         the triangles, the paper's `as_bp` {as_bp_paper}), at {cube} cells a side (bunny {bx} × {by} × {bz}), {} interleaved runs each, medians. Each cell reads **ours (paper)**. \
         Rows `i+` are our RMT defaults (boundary samples merge; the manifold guard repairs what the local graph test misses), \
         rows `p+` the topology-safe edge collapse; the paper has neither. The objects are ours: a sphere of radius {radius:.2} in the unit \
         cube, our asteroid (a noise-displaced sphere, not the paper's), the bunny as a signed-distance field of the shipped \
         model; so counts compare in kind, not digit for digit. Times are from a shared machine (the paper: {PAPER_CPU} \
         with {PAPER_LOGICAL_PROCESSORS} logical processors, its sampling pass parallel on a thread count it does not state), B_edges is our per-sample scratch ({edge_lo:.1}-{edge_hi:.1} bytes a sample on the simple cubic lattice: vertex base, half-byte slots, two flags, packed signs, and the guard's buffers; the paper \
         stores {:.0}). F_discard is the paper's definition, discarded / (discarded + kept); `removed` is one minus triangles / \
         triangles of `u`.\n\n",
        OBJECTS.len(),
        METHODS.len() - 2,
        isolab_algorithms::post::edge_collapse::DEFAULT_THRESHOLD,
        data.repeats,
        paper_edge_bytes_per_sample(),
    ));
    let paper = |id: &str| PAPER.iter().find(|p| p.id == id);
    let rows = &data.rows;
    md.push_str(&reading(rows));
    md.push_str("### Counts\n\n");
    let body: Vec<Vec<String>> = rows
        .iter()
        .map(|r| {
            let p = paper(&r.id);
            vec![
                r.id.clone(),
                pair(r.n_tetrahedra.to_string(), p.map(|p| p.n_tetrahedra.to_string())),
                pair(r.n_vertices.to_string(), p.map(|p| p.n_vertices.to_string())),
                pair(r.n_triangles.to_string(), p.map(|p| p.n_triangles.to_string())),
                pair(r.n_discarded.to_string(), p.map(|p| p.n_discarded.to_string())),
                pair(pct(f_discard(r)), p.map(|p| format!("{:.1}%", p.f_discard))),
                pct(r.removed),
                pair(pct(r.n_tetrahedra as f64 / r.total_tetrahedra.max(1) as f64), p.map(|p| format!("{:.2}%", p.f_tetrahedra))),
            ]
        })
        .collect();
    md.push_str(&markdown_table(
        &["ID", "N_tetrahedra", "N_vertices", "N_triangles", "N_discarded", "F_discard", "removed", "F_tetrahedra"],
        &body,
    ));
    md.push_str(&counts::count_ratios(rows, |id| paper(id).copied()));
    md.push_str("\n### Times (ms)\n\n");
    let body: Vec<Vec<String>> = rows
        .iter()
        .map(|r| {
            let p = paper(&r.id);
            let total = r.t_sampling + r.t_vertex + r.t_geometry + r.t_normals + r.t_post;
            vec![
                r.id.clone(),
                pair(num(total), p.map(|p| num(p.t_total * 1e3))),
                pair(num(r.t_sampling), p.map(|p| num(p.t_sampling * 1e3))),
                pair(num(r.t_vertex), p.map(|p| num(p.t_vertex * 1e3))),
                pair(num(r.t_geometry + r.t_post), p.map(|p| num(p.t_geometry * 1e3))),
                num(r.t_post),
                format!(
                    "{:.0}% / {:.0}% / {:.0}%",
                    100.0 * r.t_sampling / total,
                    100.0 * r.t_vertex / total,
                    100.0 * (r.t_geometry + r.t_post) / total
                ),
            ]
        })
        .collect();
    md.push_str(&markdown_table(
        &[
            "ID",
            "T_total",
            "T_sampling",
            "T_vertex",
            "T_geometry (+ collapse)",
            "of which collapse",
            "F_sampling / F_vertex / F_geometry",
        ],
        &body,
    ));
    md.push_str("\n### Memory and triangle quality\n\n");
    let body: Vec<Vec<String>> = rows
        .iter()
        .map(|r| {
            let p = paper(&r.id);
            let q = &r.metrics.quality.aspect_ratio;
            vec![
                r.id.clone(),
                pair(r.b_lattice.to_string(), p.map(|p| p.b_lattice.to_string())),
                pair(r.b_edges.to_string(), p.map(|p| p.b_edges.to_string())),
                pair(r.b_vertices.to_string(), p.map(|p| p.b_vertices.to_string())),
                pair(r.b_indices.to_string(), p.map(|p| p.b_indices.to_string())),
                pair(num(q.mean), p.map(|p| num(p.ar_mean))),
                pair(num(q.sd), p.map(|p| num(p.ar_sd))),
                format!("{:.1}°", r.metrics.quality.min_angle_deg),
            ]
        })
        .collect();
    md.push_str(&markdown_table(
        &["ID", "B_lattice", "B_edges", "B_vertices", "B_indices", "AR_mean", "AR_sd", "min angle"],
        &body,
    ));
    md.push_str("\n### What the paper did not measure\n\n");
    let body: Vec<Vec<String>> = rows
        .iter()
        .map(|r| {
            let m = &r.metrics;
            let h = r.metrics.surface_distance.as_ref().map_or("-".into(), |d| format!("{:.3} h", d.mean / r.spacing));
            vec![
                r.id.clone(),
                if m.topology.closed { "yes" } else { "**no**" }.into(),
                if m.topology.is_watertight_manifold() { "yes".into() } else { format!("**no** ({} vertices)", r.defects) },
                m.topology.euler.to_string(),
                m.intersecting_pairs().to_string(),
                h,
                format!("{:.2}", m.overdraw.overshading),
            ]
        })
        .collect();
    md.push_str(&markdown_table(
        &[
            "ID",
            "closed",
            "manifold",
            "Euler",
            "self-intersecting pairs",
            "mean vertex distance to the surface",
            "quad overshading",
        ],
        &body,
    ));
    md.push_str(&passes_section(&data.pass_changes));
    md.push_str(&questionnaire_section());
    md.push_str(&matched_section(&data.matched_sphere));
    md.push_str(&projection_section(&data.projection));
    md.push_str(&peer_section(&data.peers));
    md.push_str(&differences(rows, &as_bp_ours, &as_bp_paper));
    md.push_str("\n| | | |\n|---|---|---|\n| ![triangles](figures/costen_table/triangles.png) | ![pass times](figures/costen_table/pass-times.png) | ![aspect ratio](figures/costen_table/aspect-ratio.png) |\n\n");
    for p in &data.pictures {
        md.push_str(&format!("![{0}]({1})\n\n_{0}_\n\n", p.caption, p.path));
    }
    let _ = ctx;
    md
}

#[cfg(test)]
mod tests;
