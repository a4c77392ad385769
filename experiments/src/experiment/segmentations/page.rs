//! The page `report/segmentations.md`, rendered from the data file alone.

use super::data::{Data, Row};
use super::reading;
use super::{BACKGROUND, NAME, OURS, TARGET, TARGETS, THREADS};
use crate::experiment::context::{Context, ExperimentError};
use crate::report::{markdown_table, ms, Spread};

/// The page, from the data file alone.
pub(super) fn section(ctx: &Context) -> Result<String, ExperimentError> {
    let data: Data = ctx.read_data(NAME)?;
    Ok(page_body(&data, data.pictures))
}

pub(super) fn spread(row: &Row) -> Spread {
    Spread::of(row.ms.clone())
}

/// The median of the meshing step alone, where the implementation has one.
pub(super) fn core_median(row: &Row) -> Option<f64> {
    row.core_ms.as_ref().filter(|c| !c.is_empty()).map(|c| Spread::of(c.clone()).median)
}

/// A speed-up as shown beside the target: two decimals, or three where two would round a miss up
/// to the target.
pub(super) fn against_target(r: f64) -> String {
    let two = format!("{r:.2}");
    if r < TARGET && two.parse::<f64>().is_ok_and(|shown| shown >= TARGET) {
        format!("{r:.3}")
    } else {
        two
    }
}

pub(super) fn find<'a>(data: &'a Data, implementation: &str, input: &str, threads: usize) -> Option<&'a Row> {
    data.rows.iter().find(|r| r.implementation == implementation && r.input == input && r.threads == threads)
}

pub(super) fn inputs(data: &Data) -> Vec<String> {
    crate::report::first_seen(data.rows.iter().map(|r| r.input.clone()))
}

pub(super) fn ratio(a: f64, b: Option<f64>) -> String {
    match b {
        Some(b) if b > 0.0 => format!("{:.2}", a / b),
        _ => "–".into(),
    }
}

pub(super) fn opt<T: ToString>(v: Option<T>) -> String {
    v.map_or("–".into(), |v| v.to_string())
}

/// Time on one input: every implementation, one and two threads, and the ratio to ours.
pub(super) fn timing_table(data: &Data, input: &str) -> String {
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
                format!("{}–{}{}", ms(s.min), ms(s.max), if r.wide == Some(true) { " (wide)" } else { "" }),
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
pub(super) fn checks_table(data: &Data, input: &str) -> String {
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
pub(super) fn target_sentences(data: &Data) -> Vec<String> {
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
                let range = crate::report::ratio_range(&our_row.ms, &peer_row.ms)
                    .map_or(String::new(), |(lo, hi)| format!(" ({lo:.2}–{hi:.2}× round by round)"));
                Some(format!("{peer} takes {}×{range} the time of `{ours}` ({verdict}){core}", against_target(r)))
            })
            .collect();
        if !verdicts.is_empty() {
            out.push(format!("{input}, one thread: {}.", verdicts.join("; ")));
        }
    }
    out
}

/// The gap-free claim, per input: which implementations leave unmatched interface triangles.
pub(super) fn interface_sentences(data: &Data) -> Vec<String> {
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

pub(super) fn page_body(data: &Data, pictures: bool) -> String {
    let mut md = String::from("## Segmentations to surfaces (`segmentations`)\n\n");
    md.push_str(&format!(
        "A label map (every sample an integer label, the background {BACKGROUND}) meshed into one surface per label, as a \
         segmentation user does it from Python: each implementation called in one process on the same numpy label map, \
         one-shot, with its conversions and the building of per-label meshes inside the timed call. After one unrecorded \
         warm-up round, every round calls each implementation once, in an order rotated by one each round. While an \
         implementation's slowest call in a block of rounds took over {wide}× its fastest, another block runs, up to {blocks} \
         (\"(wide)\" marks a cell still wide after its last); ratios round by round pair the calls of one round. {two} threads: \
         isolab (`threads={two}`) and VTK (its STDThread backend); zmesh and scikit-image run in the one-thread rounds only. \
         The script is `experiments/src/experiment/segmentations/bench.py`, run in `tests/reference/.venv` after \
         `pip install ./python` of this commit; its header gives each implementation's call.\n\n",
        two = THREADS[1],
        wide = crate::report::WIDE,
        blocks = crate::report::MAX_ROUNDS
    ));
    md.push_str(&reading::reading(data));
    let sn = isolab_algorithms::labels::surface_nets::LabelSnOptions::default();
    md.push_str(&format!(
        "Our options (the label extractors' defaults in this commit): `surface-nets` smoothing constrained, {} iterations, \
         relaxation {}, border closed; `isolab surface-nets unsmoothed` is `smoothing=none`; `marching-tetrahedra` has no \
         smoothing; `lattice-cleaving` has none either, and its timed call also fills every label with tetrahedra and \
         hands them to Python. VTK SurfaceNets3D runs with its own defaults, and unsmoothed with its smoothing off.\n\n",
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
            data.drawn().join(", "),
            data.drawn().join(", ")
        ));
    }
    if !data.notes.is_empty() {
        md.push_str("Notes from the run: ");
        md.push_str(&data.notes.join("; "));
        md.push_str(".\n");
    }
    md
}
