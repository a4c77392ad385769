//! `segmentations`: label maps to one surface per label, as a segmentation user meets it, in one
//! Python process: `isolab.mesh_labels` (multi-label surface nets, smoothed and not, and
//! multi-label marching tetrahedra) beside VTK's `vtkSurfaceNets3D` (Frisken 2022, smoothed and
//! not), zmesh (marching cubes of every label in one pass, the kernel igneous distributes) and
//! scikit-image's marching cubes run once per label, on the same numpy label maps.
//!
//! The timing and the checks run in `bench.py` beside this file (its header is the protocol), in
//! the pinned reference environment with the package installed from `python/` by this experiment,
//! so they time the code of this commit. Inputs: a tissue map of the MNI152 T1 template (a
//! three-class Otsu split) and Voronoi maps of random seeds at 128³ and 256³. The pictures are
//! ours, rendered here from the tissue map `bench.py` saves.

mod reading;

use super::context::{Context, Experiment, ExperimentError};
use crate::figures::render;
use crate::peers::python;
use crate::report::{markdown_table, ms, Spread};
use isolab_algorithms::{Options, TriMesh};
use isolab_pipeline::labels::{self, LabelConfig, LabelVolume};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::Path;

/// The experiment.
pub struct Segmentations;

const NAME: &str = "segmentations";
/// The Voronoi maps: samples per side and labels (the background among them).
const VORONOI: [(usize, usize); 2] = [(128, 64), (256, 64)];
/// The thread counts timed (the second: this machine's two cores).
const THREADS: [usize; 2] = [1, 2];
/// The implementation every ratio is taken against.
const OURS: &str = "isolab surface-nets";
/// The peers the speed target names, with the implementation of ours compared to each
/// like with like (both smoothed, or both unsmoothed marching).
const TARGETS: [(&str, &str); 2] = [("VTK SurfaceNets3D", OURS), ("zmesh", "isolab surface-nets unsmoothed")];
/// The background label.
const BACKGROUND: u32 = 0;
/// The speed-up the issue asks for.
const TARGET: f64 = 1.5;

/// One implementation on one input on some threads, as `bench.py` writes it (the checks on one
/// thread only).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Row {
    /// Who meshed it.
    pub implementation: String,
    /// Which label map.
    pub input: String,
    /// Threads given.
    pub threads: usize,
    /// Every recorded call, ms, in the order run.
    pub ms: Vec<f64>,
    /// The meshing step alone in each recorded call, ms (isolab's extraction, VTK's `Update()`,
    /// zmesh's `mesh()`; none for scikit-image).
    #[serde(default)]
    pub core_ms: Option<Vec<f64>>,
    /// Labels with a mesh.
    pub labels: usize,
    /// Triangles over every label's mesh.
    pub triangles: usize,
    /// Labels whose mesh is closed (one-thread rows).
    #[serde(default)]
    pub labels_closed: Option<usize>,
    /// Labels whose mesh is edge- and vertex-manifold.
    #[serde(default)]
    pub labels_manifold: Option<usize>,
    /// Non-manifold edges and vertices over every label's mesh.
    #[serde(default)]
    pub non_manifold: Option<usize>,
    /// Triangles of zero area.
    #[serde(default)]
    pub degenerate_triangles: Option<usize>,
    /// Smallest triangle angle, degrees.
    #[serde(default)]
    pub min_angle_deg: Option<f64>,
    /// Mean radius ratio (1 for equilateral).
    #[serde(default)]
    pub mean_radius_ratio: Option<f64>,
    /// Triangles whose outside is another label.
    #[serde(default)]
    pub interface_triangles: Option<usize>,
    /// Those not found in the other label's mesh.
    #[serde(default)]
    pub unmatched_interface_triangles: Option<usize>,
}

/// An input as `bench.py` describes it.
#[derive(Clone, Debug, Serialize, Deserialize)]
struct Input {
    input: String,
    shape: Vec<usize>,
    dtype: String,
    order: String,
    labels: usize,
    #[serde(default)]
    thresholds: Vec<f64>,
}

/// What the experiment keeps.
#[derive(Serialize, Deserialize)]
pub struct Data {
    repeats: usize,
    versions: BTreeMap<String, String>,
    notes: Vec<String>,
    inputs: Vec<Input>,
    /// One row per implementation, input and thread count.
    pub rows: Vec<Row>,
    /// Whether the tissue map's pictures were drawn (`figures/segmentations/tissue.png`).
    #[serde(default)]
    pictures: bool,
}

impl Experiment for Segmentations {
    fn name(&self) -> &'static str {
        NAME
    }

    fn question(&self) -> &'static str {
        "How fast, closed and gap-free are isolab's label-map surfaces against VTK's SurfaceNets3D, zmesh and per-label marching cubes?"
    }

    fn run(&self, ctx: &Context) -> Result<(), ExperimentError> {
        let root = ctx.report_dir.join("..");
        let python = python::reference_python(&root).map_err(ExperimentError::Python)?;
        python::install_package(&python, &root).map_err(ExperimentError::Python)?;
        let repeats = ctx.repeats.max(1);
        // The tissue map bench.py makes, kept for the pictures (under target/: not committed).
        let maps = root.join("target").join(NAME);
        std::fs::create_dir_all(&maps).map_err(|source| isolab_io::IoError::Write { path: maps.clone(), source })?;
        let tissue = maps.join("mni-tissue.nii.gz");
        let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("src/experiment/segmentations/bench.py");
        let voronoi: Vec<String> = VORONOI.iter().map(|(n, l)| format!("{n}:{l}")).collect();
        let args: Vec<String> = [
            "--repeats",
            &repeats.to_string(),
            "--threads",
            &THREADS.map(|t| t.to_string()).join(","),
            "--voronoi",
            &voronoi.join(","),
            "--save-tissue",
            tissue.to_str().unwrap_or_default(),
        ]
        .iter()
        .map(|s| (*s).to_owned())
        .collect();
        let mut bench: serde_json::Value = python::run_script(&python, &script, &args, &[]).map_err(ExperimentError::Python)?;
        bench["repeats"] = repeats.into();
        let mut data: Data =
            serde_json::from_value(bench).map_err(|e| ExperimentError::Python(format!("bench.py wrote: {e}")))?;
        if tissue.exists() {
            pictures(ctx, &tissue)?;
            data.pictures = true;
        }
        ctx.write_data(NAME, &data)
    }

    fn section(&self, ctx: &Context) -> Result<String, ExperimentError> {
        let data: Data = ctx.read_data(NAME)?;
        Ok(section(&data, data.pictures))
    }
}

/// The tissue map meshed by each of our label extractors, cut open at the middle of its first
/// axis so the inner labels show, coloured by label, side by side.
fn pictures(ctx: &Context, tissue: &Path) -> Result<(), ExperimentError> {
    let dir = ctx.figure_dir(NAME)?;
    let volume = LabelVolume::read(tissue, None)?;
    let mut images = Vec::new();
    for algorithm in isolab_algorithms::labels::names() {
        let config = LabelConfig { algorithm: algorithm.into(), options: Options::new(), ..Default::default() };
        let outcome = labels::mesh_labels(&volume, &config)?;
        let (mesh, colours) = cut_open(&outcome.meshes);
        let opts = render::RenderOptions { width: 420, height: 420, ..Default::default() };
        images.push(render::render_coloured(&mesh, &colours, &opts));
    }
    let refs: Vec<&render::Image> = images.iter().collect();
    render::save_png(&dir.join("tissue.png"), &render::grid(&refs, refs.len())).map_err(ExperimentError::Io)
}

/// Every label's triangles whose centroid lies on the low side of the meshes' middle x, in one
/// mesh, each vertex coloured by its label.
fn cut_open(meshes: &BTreeMap<u32, TriMesh>) -> (TriMesh, Vec<[u8; 3]>) {
    let (lo, hi) = meshes
        .values()
        .flat_map(|m| m.positions.iter())
        .fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), p| (lo.min(p.x), hi.max(p.x)));
    let middle = 0.5 * (lo + hi);
    let mut out = TriMesh::default();
    let mut colours = Vec::new();
    for (&label, mesh) in meshes {
        let base = out.positions.len() as u32;
        out.positions.extend_from_slice(&mesh.positions);
        colours.extend(std::iter::repeat_n(labels::colour(label), mesh.positions.len()));
        out.triangles.extend(
            mesh.triangles
                .iter()
                .filter(|t| t.iter().map(|&v| mesh.positions[v as usize].x).sum::<f32>() / 3.0 < middle)
                .map(|t| t.map(|v| v + base)),
        );
    }
    (out, colours)
}

/// The median of a row's calls.
pub fn median_ms(row: &Row) -> f64 {
    spread(row).median
}

fn spread(row: &Row) -> Spread {
    Spread::of(row.ms.clone())
}

/// The median of the meshing step alone, where the implementation has one.
fn core_median(row: &Row) -> Option<f64> {
    row.core_ms.as_ref().filter(|c| !c.is_empty()).map(|c| Spread::of(c.clone()).median)
}

/// A speed-up as shown beside the target: two decimals, or three where two would round a miss up
/// to the target.
fn against_target(r: f64) -> String {
    let two = format!("{r:.2}");
    if r < TARGET && two.parse::<f64>().is_ok_and(|shown| shown >= TARGET) {
        format!("{r:.3}")
    } else {
        two
    }
}

fn find<'a>(data: &'a Data, implementation: &str, input: &str, threads: usize) -> Option<&'a Row> {
    data.rows.iter().find(|r| r.implementation == implementation && r.input == input && r.threads == threads)
}

fn inputs(data: &Data) -> Vec<String> {
    crate::report::first_seen(data.rows.iter().map(|r| r.input.clone()))
}

fn ratio(a: f64, b: Option<f64>) -> String {
    match b {
        Some(b) if b > 0.0 => format!("{:.2}", a / b),
        _ => "–".into(),
    }
}

fn opt<T: ToString>(v: Option<T>) -> String {
    v.map_or("–".into(), |v| v.to_string())
}

/// Time on one input: every implementation, one and two threads, and the ratio to ours.
fn timing_table(data: &Data, input: &str) -> String {
    let ours = find(data, OURS, input, 1).map(|r| spread(r).median);
    let rows: Vec<Vec<String>> = data
        .rows
        .iter()
        .filter(|r| r.input == input && r.threads == THREADS[0])
        .map(|r| {
            let s = spread(r);
            let two = find(data, &r.implementation, input, THREADS[1]).map(spread);
            vec![
                r.implementation.clone(),
                ms(s.median),
                format!("{}–{}", ms(s.min), ms(s.max)),
                ratio(s.median, ours),
                core_median(r).map_or("–".into(), ms),
                two.as_ref().map_or("–".into(), |t| ms(t.median)),
                r.triangles.to_string(),
            ]
        })
        .collect();
    let one = format!("{} thread, ms (median)", THREADS[0]);
    let two = format!("{} threads, ms (median)", THREADS[1]);
    let ours_header = format!("÷ {OURS}");
    markdown_table(
        &["implementation", &one, "fastest–slowest", &ours_header, "of which meshing, ms (median)", &two, "triangles"],
        &rows,
    )
}

/// The checks on one input (the one-thread run's last output).
fn checks_table(data: &Data, input: &str) -> String {
    let rows: Vec<Vec<String>> = data
        .rows
        .iter()
        .filter(|r| r.input == input && r.threads == THREADS[0])
        .map(|r| {
            vec![
                r.implementation.clone(),
                r.labels.to_string(),
                opt(r.labels_closed),
                opt(r.labels_manifold),
                opt(r.non_manifold),
                format!("{} of {}", opt(r.unmatched_interface_triangles), opt(r.interface_triangles)),
                opt(r.degenerate_triangles),
                r.min_angle_deg.map_or("–".into(), |a| format!("{a:.1}")),
                r.mean_radius_ratio.map_or("–".into(), |q| format!("{q:.3}")),
            ]
        })
        .collect();
    markdown_table(
        &[
            "implementation",
            "labels meshed",
            "closed",
            "manifold",
            "non-manifold edges + vertices",
            "unmatched interface triangles",
            "degenerate triangles",
            "min angle °",
            "mean radius ratio",
        ],
        &rows,
    )
}

/// The speed target, per input and peer: met or missed, with the measured ratio.
fn target_sentences(data: &Data) -> Vec<String> {
    let mut out = Vec::new();
    for input in inputs(data) {
        let verdicts: Vec<String> = TARGETS
            .iter()
            .filter_map(|(peer, ours)| {
                let (peer_row, our_row) = (find(data, peer, &input, 1)?, find(data, ours, &input, 1)?);
                let r = spread(peer_row).median / spread(our_row).median;
                let verdict = if r >= TARGET { "met" } else { "missed" };
                let core = match (core_median(peer_row), core_median(our_row)) {
                    (Some(p), Some(o)) if o > 0.0 => format!(", its meshing step alone {:.2}× ours", p / o),
                    _ => String::new(),
                };
                Some(format!("{peer} takes {}× the time of `{ours}` ({verdict}){core}", against_target(r)))
            })
            .collect();
        if !verdicts.is_empty() {
            out.push(format!("{input}, one thread: {}.", verdicts.join("; ")));
        }
    }
    out
}

/// The gap-free claim, per input: which implementations leave unmatched interface triangles.
fn interface_sentences(data: &Data) -> Vec<String> {
    inputs(data)
        .iter()
        .map(|input| {
            let (clean, gaps): (Vec<&Row>, Vec<&Row>) = data
                .rows
                .iter()
                .filter(|r| &r.input == input && r.threads == THREADS[0] && r.unmatched_interface_triangles.is_some())
                .partition(|r| r.unmatched_interface_triangles == Some(0));
            let names =
                |rows: &[&Row]| crate::report::listed(&rows.iter().map(|r| r.implementation.as_str()).collect::<Vec<_>>());
            format!("{input}: no unmatched interface triangle in {}; some in {}.", names(&clean), names(&gaps))
        })
        .collect()
}

fn section(data: &Data, pictures: bool) -> String {
    let mut md = String::from("## Segmentations to surfaces (`segmentations`)\n\n");
    md.push_str(&format!(
        "A label map (every sample an integer label, the background {BACKGROUND}) meshed into one surface per label, as a \
         segmentation user does it from Python: each implementation called in one process on the same numpy label map, \
         one-shot, with its conversions and the building of per-label meshes inside the timed call. After one unrecorded \
         warm-up round, every round calls each implementation once, in an order rotated by one each round. {two} threads: \
         isolab (`threads={two}`) and VTK (its STDThread backend); zmesh and scikit-image run in the one-thread rounds only. \
         The script is `experiments/src/experiment/segmentations/bench.py`, run in `tests/reference/.venv` after \
         `pip install ./python` of this commit; its header gives each implementation's call.\n\n",
        two = THREADS[1]
    ));
    md.push_str(&reading::reading(data));
    let sn = isolab_algorithms::labels::surface_nets::LabelSnOptions::default();
    md.push_str(&format!(
        "Our options (the label extractors' defaults in this commit): `surface-nets` smoothing constrained, {} iterations, \
         relaxation {}, border closed; `isolab surface-nets unsmoothed` is `smoothing=none`; `marching-tetrahedra` has no \
         smoothing. VTK SurfaceNets3D runs with its own defaults, and unsmoothed with its smoothing off.\n\n",
        sn.iterations, sn.relaxation
    ));
    md.push_str(&format!(
        "Rounds: {}. Versions: {}.\n\n",
        data.repeats,
        data.versions.iter().map(|(k, v)| format!("{k} {v}")).collect::<Vec<_>>().join(", ")
    ));
    md.push_str(&format!(
        "### The speed target\n\nOur target is at least {TARGET}× against VTK and zmesh on one thread, like with like: our \
         smoothed surface nets against VTK's smoothed SurfaceNets3D, our unsmoothed surface nets against zmesh (unsmoothed \
         marching cubes). Each verdict is on the whole call; beside it, the meshing step alone (isolab's extraction timed \
         in Rust, VTK's `Update()`, zmesh's `mesh()`, each timed inside the call; the tables' \"of which meshing\" column): \
         the rest of a call is building each label's mesh and handing the arrays to Python.\n\n"
    ));
    for s in target_sentences(data) {
        md.push_str(&format!("- {s}\n"));
    }
    md.push_str("\n### Gaps and overlaps between neighbouring labels\n\n");
    md.push_str(
        "Each label's mesh is welded first (vertices at one position made one: VTK duplicates points where it resolves a \
         non-manifold case) and wound outward. A triangle of label a that lies on the face between a sample of a and a \
         face-neighbour sample of another label (the samples nearest its centroid pushed half a sample against and along \
         its normal) is an interface triangle and \
         should be in another label's mesh too, with the same three vertices; the tables count those that are not. Our \
         meshes and VTK's share one interface surface by construction, so theirs count only where the probes misread a \
         triangle's sides (a triangle with the background on one side, near a third label, or moved off the voxel faces \
         by smoothing); zmesh and scikit-image mesh each label on its own.\n\n",
    );
    for s in interface_sentences(data) {
        md.push_str(&format!("- {s}\n"));
    }
    md.push('\n');
    for input in inputs(data) {
        md.push_str(&format!("### {input}\n\nTime:\n\n"));
        md.push_str(&timing_table(data, &input));
        md.push_str("\nWhat came out (the one-thread run's last output; every label's mesh checked):\n\n");
        md.push_str(&checks_table(data, &input));
        md.push('\n');
    }
    md.push_str("### Inputs\n\n");
    let rows: Vec<Vec<String>> = data
        .inputs
        .iter()
        .map(|i| {
            vec![
                i.input.clone(),
                i.shape.iter().map(usize::to_string).collect::<Vec<_>>().join("×"),
                i.dtype.clone(),
                i.order.clone(),
                i.labels.to_string(),
            ]
        })
        .collect();
    md.push_str(&markdown_table(&["input", "shape", "dtype", "memory order", "labels (without the background)"], &rows));
    md.push_str(
        "\nThe tissue map is the MNI152 T1 template nilearn ships, split by a three-class Otsu threshold of its non-zero \
         voxels (scikit-image's `threshold_multiotsu`) into darker, middle and brighter tissue; the Voronoi maps give every \
         sample the label of its nearest of twice as many random seeds as labels, so labels meet in many triple junctions. \
         Surface nets' non-manifold places, where there are any, are where three or more labels meet in a cell and its \
         splits (which give a pinched label's loops their own vertices) do not resolve it (the \
         `algorithms::labels::surface_nets` documentation lists when); marching tetrahedra is manifold for every map by \
         construction, with more triangles.\n\n",
    );
    if pictures {
        md.push_str(&format!(
            "![the tissue map, cut open at the middle: {}](figures/{NAME}/tissue.png)\n\nThe tissue map meshed by each of our \
             label extractors ({}, left to right), cut open at the middle of its first axis, each label in its colour.\n\n",
            isolab_algorithms::labels::names().join(", "),
            isolab_algorithms::labels::names().join(", ")
        ));
    }
    if !data.notes.is_empty() {
        md.push_str("Notes from the run: ");
        md.push_str(&data.notes.join("; "));
        md.push_str(".\n");
    }
    md
}
