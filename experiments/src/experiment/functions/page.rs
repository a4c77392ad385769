//! The page `report/functions.md`, rendered from the data file alone.

use super::data::{Data, PeerRow, Row};
use super::{BOUND_MIB, BOUND_S, DENSE_UP_TO, FEWER_TARGET, FIELDS, LARGEST, NAME, READ_AT};
use crate::experiment::context::{Context, ExperimentError};
use crate::report::{log_slope, markdown_table};

/// The page, from the data file alone.
pub(super) fn section(ctx: &Context) -> Result<String, ExperimentError> {
    let data: Data = ctx.read_data(NAME)?;
    let mut s = String::from("## Meshes from functions (`functions`)\n\n");
    s.push_str(&format!(
        "Marching cubes of a field evaluated only in the blocks its Lipschitz bound cannot rule out (sparse), and of \
             the whole grid (dense, up to {DENSE_UP_TO}³). Evaluations count every point the field was asked for, the \
             octree's centres and its refinement's below the blocks included; peak is the heap the run added. One run per cell, in one process.\n\n"
    ));
    s.push_str(&reading(&data));
    let rows: Vec<Vec<String>> = data
        .rows
        .iter()
        .map(|r| {
            vec![
                format!("`{}`", r.field),
                format!("{}³", r.n),
                r.mode.clone(),
                r.lipschitz.map_or("—".into(), |l| format!("{l:.2}")),
                format!("{:.1} M", r.evaluations as f64 / 1e6),
                format!("{:.1}x", r.dense_points as f64 / r.evaluations.max(1) as f64),
                format!("{:.0}", r.wall_ms),
                format!("{:.0}", r.eval_ms),
                r.peak_mib.map_or("—".into(), |m| format!("{m:.0}")),
                r.triangles.to_string(),
            ]
        })
        .collect();
    s.push_str(&markdown_table(
        &["field", "grid", "mode", "L", "evaluations", "fewer than dense", "wall ms", "in the field ms", "peak MiB", "triangles"],
        &rows,
    ));
    s.push_str("\n### Growth with n\n\n");
    s.push_str(
        "Slope of log evaluations and log wall time against log n over each field's sparse runs (a surface grows as n², \
         the grid as n³).\n\n",
    );
    s.push_str(&markdown_table(&["field", "sizes", "evaluations slope", "time slope"], &growth(&data.rows)));
    s.push_str("\n### Identical to dense\n\n");
    s.push_str(
        "Each extractor that meshes in blocks, certified against every block sampled (the same blocks, the same \
         welding): whether vertices, triangles and normals are the same bits. A mesh field's dense mode asks \
         the exact distance at every sample, so past the smallest size only marching cubes is compared on it; the \
         blocks, aprons and welding are the same for every field.\n\n",
    );
    let eq: Vec<Vec<String>> = data
        .equality
        .iter()
        .map(|e| {
            let yes = |b: bool| if b { "same" } else { "**differ**" }.to_owned();
            vec![
                format!("`{}`", e.field),
                format!("{}³", e.n),
                format!("`{}`", e.algorithm),
                yes(e.same_vertices),
                yes(e.same_triangles),
                yes(e.same_normals),
                e.triangles.to_string(),
                format!("{:.1}x", e.dense_evaluations as f64 / e.evaluations.max(1) as f64),
            ]
        })
        .collect();
    s.push_str(&markdown_table(
        &["field", "grid", "extractor", "vertices", "triangles", "normals", "triangle count", "fewer evaluations"],
        &eq,
    ));
    s.push_str(&python_section(&data));
    Ok(s)
}

/// The Python side's table: per callable, grid and implementation, the median call time with its
/// range, evaluations, peak RSS of its process and faces, and each time as a multiple of isolab's.
pub(super) fn python_section(data: &Data) -> String {
    let Some(side) = &data.python else {
        return format!(
            "\n### From Python\n\nNot run: {}\n",
            data.python_missing.as_deref().unwrap_or("no reference environment")
        );
    };
    let mut s = String::from("\n### From Python, against the peers\n\n");
    s.push_str(&format!(
        "Each implementation meshes the same numpy callable on the same bounds and grid, one fresh process per run \
         (one-shot: the time is the call's, after the imports; the peak is the process's RSS), rounds alternating, in \
         blocks: while any implementation's slowest run in a block took over {}× its fastest, another block runs, up to \
         {} (\"(wide)\" marks a cell still wide after its last); ratios round by round pair the runs of one round. \
         isolab and warp prune with the callable's Lipschitz bound; scikit-image samples the dense grid; PyMCubes calls \
         the function once per point. The callables:\n\n",
        crate::report::WIDE,
        crate::report::MAX_ROUNDS
    ));
    for (name, what) in &side.callables {
        s.push_str(&format!("- `{name}`: {what}\n"));
    }
    s.push('\n');
    let versions: Vec<String> = side.versions.iter().map(|(k, v)| format!("{k} {}", v.as_deref().unwrap_or("missing"))).collect();
    s.push_str(&format!("Versions: {}. {}\n\n", versions.join(", "), side.notes.join(" ")));
    let median_of = |r: &PeerRow| {
        let secs: Vec<f64> = r.runs.iter().filter_map(|x| x.seconds).collect();
        (!secs.is_empty()).then(|| crate::report::Spread::of(secs))
    };
    let mut rows = Vec::new();
    for r in &side.rows {
        let ours_row = side.rows.iter().find(|o| o.callable == r.callable && o.n == r.n && o.implementation == "isolab");
        let ours = ours_row.and_then(median_of);
        // Runs of one round paired (a failed run pairs with nothing).
        let range = ours_row.filter(|o| o.implementation != r.implementation).and_then(|o| {
            let seconds = |row: &PeerRow| row.runs.iter().map(|x| x.seconds.unwrap_or(f64::NAN)).collect::<Vec<f64>>();
            crate::report::ratio_range(&seconds(o), &seconds(r))
        });
        let spread = median_of(r);
        let first = r.runs.iter().find(|x| x.error.is_none());
        let peak = r.runs.iter().filter_map(|x| x.peak_mib).fold(f64::NAN, f64::max);
        rows.push(vec![
            format!("`{}`", r.callable),
            format!("{}³", r.n),
            r.implementation.clone(),
            spread.as_ref().map_or_else(
                || r.runs.iter().find_map(|x| x.error.clone()).unwrap_or_default(),
                |sp| {
                    let wide = if r.wide == Some(true) { " (wide)" } else { "" };
                    format!("{:.3} [{:.3}–{:.3}] ×{}{wide}", sp.median, sp.min, sp.max, r.runs.len())
                },
            ),
            match (&spread, &ours) {
                (Some(sp), Some(o)) if o.median > 0.0 => format!(
                    "{:.2}x{}",
                    sp.median / o.median,
                    range.map_or(String::new(), |(lo, hi)| format!(" ({lo:.2}–{hi:.2}x round by round)"))
                ),
                _ => "–".into(),
            },
            first.and_then(|x| x.evaluations).map_or("–".into(), |e| format!("{:.2} M", e as f64 / 1e6)),
            if peak.is_finite() { format!("{peak:.0}") } else { "–".into() },
            first.and_then(|x| x.faces).map_or("–".into(), |f| f.to_string()),
        ]);
    }
    s.push_str(&markdown_table(
        &["callable", "grid", "implementation", "seconds, median [range] ×runs", "÷ isolab", "evaluations", "peak MiB", "faces"],
        &rows,
    ));
    s
}

/// Per field: the log-log slope of sparse evaluations and wall time against n.
pub(super) fn growth(rows: &[Row]) -> Vec<Vec<String>> {
    let mut out = Vec::new();
    for (name, _) in FIELDS {
        let sparse: Vec<&Row> = rows.iter().filter(|r| r.field == name && r.mode == "sparse").collect();
        if sparse.len() < 2 {
            continue;
        }
        let slope = |y: &dyn Fn(&Row) -> f64| {
            let pts: Vec<(f64, f64)> = sparse.iter().map(|r| (r.n as f64, y(r))).collect();
            log_slope(&pts).unwrap_or(f64::NAN)
        };
        out.push(vec![
            format!("`{name}`"),
            format!("{}³–{}³", sparse[0].n, sparse[sparse.len() - 1].n),
            format!("{:.2}", slope(&|r| r.evaluations as f64)),
            format!("{:.2}", slope(&|r| r.wall_ms)),
        ]);
    }
    out
}

/// The page's reading, from the data: the evaluation ratios at [`READ_AT`], the [`LARGEST`] runs
/// against the bound, and how many comparisons were equal.
pub(super) fn reading(data: &Data) -> String {
    let mut s = String::new();
    let at_read: Vec<String> = data
        .rows
        .iter()
        .filter(|r| r.mode == "sparse" && r.n == READ_AT)
        .map(|r| format!("`{}` {:.1}x", r.field, r.dense_points as f64 / r.evaluations.max(1) as f64))
        .collect();
    if !at_read.is_empty() {
        s.push_str(&format!(
            "**Reading.** At {READ_AT}³, sparse extraction evaluated fewer points than the dense grid has: {}. ",
            at_read.join(", ")
        ));
    }
    s.push_str(&floor_reading(data));
    let big: Vec<String> = data
        .rows
        .iter()
        .filter(|r| r.mode == "sparse" && r.n == LARGEST)
        .map(|r| {
            let within = r.wall_ms <= BOUND_S * 1e3 && r.peak_mib.is_some_and(|m| m <= BOUND_MIB);
            format!(
                "`{}` in {:.1} s and {} ({} the issue's bound of {BOUND_S} s and {BOUND_MIB} MiB)",
                r.field,
                r.wall_ms / 1e3,
                r.peak_mib.map_or("unmeasured peak".into(), |m| format!("{m:.0} MiB peak")),
                if within { "within" } else { "**outside**" }
            )
        })
        .collect();
    if !big.is_empty() {
        s.push_str(&format!("At {LARGEST}³: {}. ", big.join("; ")));
    }
    let same = data.equality.iter().filter(|e| e.same_vertices && e.same_triangles && e.same_normals).count();
    s.push_str(&format!("{same} of {} certified meshes are the dense mesh bit for bit.\n\n", data.equality.len()));
    s
}

/// Per field at the floor's size: whether the sparse run reached [`FEWER_TARGET`], and the
/// cell-by-cell floor beside it (what the bound allows whatever the block size).
pub(super) fn floor_reading(data: &Data) -> String {
    let mut parts = Vec::new();
    for f in &data.floors {
        let Some(run) = data.rows.iter().find(|r| r.mode == "sparse" && r.field == f.field && r.n == f.n) else {
            continue;
        };
        let ours = run.dense_points as f64 / run.evaluations.max(1) as f64;
        let floor = f.dense_points as f64 / f.samples.max(1) as f64;
        let verdict = if ours >= FEWER_TARGET { "reaches" } else { "**misses**" };
        // The floor counts no test and no sample around the cells; where it is the larger ratio,
        // what separates the two is exactly what the blocks add.
        let gap = if floor > ours {
            " (the rest is the blocks' samples around those cells and the pruning's own evaluations)"
        } else {
            ""
        };
        parts.push(format!(
            "`{}` {verdict} it at {ours:.1}x; a test cell by cell with the same bound (L = {:.2}) would still evaluate the \
             {:.1} M corners of the cells no centre rules out, {floor:.1}x fewer than dense{gap}",
            f.field,
            f.lipschitz,
            f.samples as f64 / 1e6
        ));
    }
    let Some(first) = data.floors.first().filter(|_| !parts.is_empty()) else {
        return String::new();
    };
    format!(
        "The issue asks for at least {FEWER_TARGET:.0}x fewer evaluations than dense at {READ_AT}³; at {}³: {}. ",
        first.n,
        parts.join("; ")
    )
}

#[cfg(test)]
mod tests {
    use super::super::data::{PeerRun, PythonSide};
    use super::*;

    fn peer(implementation: &str, seconds: &[f64], wide: bool) -> PeerRow {
        let run = |s: f64| PeerRun {
            seconds: Some(s),
            faces: Some(10),
            evaluations: Some(1000),
            calls: None,
            lipschitz: None,
            peak_mib: Some(100.0),
            error: None,
        };
        PeerRow {
            callable: "sphere".into(),
            n: 256,
            implementation: implementation.into(),
            runs: seconds.iter().map(|&s| run(s)).collect(),
            blocks: Some(1),
            wide: Some(wide),
        }
    }

    fn row(field: &str, evaluations: u64) -> Row {
        Row {
            field: field.into(),
            n: 1024,
            mode: "sparse".into(),
            lipschitz: Some(9.0),
            chunk: Some(4),
            evaluations,
            pruning_evaluations: None,
            refinement_evaluations: None,
            dense_points: 1000,
            batches: 1,
            sampled_blocks: None,
            blocks: None,
            wall_ms: 1.0,
            eval_ms: 1.0,
            peak_mib: None,
            triangles: 1,
        }
    }

    #[test]
    fn the_floor_reading_says_which_field_misses_the_target_and_why_only_where_the_floor_is_higher() {
        use super::super::data::Floor;
        let floor = |field: &str, samples: u64| Floor {
            field: field.into(),
            n: 1024,
            lipschitz: 9.0,
            cells: 1,
            samples,
            dense_points: 1000,
        };
        let data = Data {
            rows: vec![row("asteroid", 100), row("sphere", 20)],
            equality: Vec::new(),
            floors: vec![floor("asteroid", 25), floor("sphere", 25)],
            python: None,
            python_missing: None,
        };
        let s = floor_reading(&data);
        assert!(s.contains("`asteroid` **misses** it at 10.0x;"), "{s}");
        assert!(s.contains("40.0x fewer than dense (the rest is"), "{s}");
        assert!(s.contains("`sphere` reaches it at 50.0x;"), "{s}");
        assert!(s.ends_with("40.0x fewer than dense. "), "no gap named where the floor is lower: {s}");
        assert!(floor_reading(&Data { floors: Vec::new(), ..data }).is_empty());
    }

    #[test]
    fn the_python_table_gives_each_peers_ratio_with_its_range_round_by_round_and_marks_wide_cells() {
        let side = PythonSide {
            versions: Default::default(),
            rows: vec![peer("isolab", &[1.0, 2.0, 1.0], false), peer("warp", &[2.0, 3.0, 4.0], true)],
            notes: Vec::new(),
            callables: Default::default(),
        };
        let data = Data { rows: Vec::new(), equality: Vec::new(), floors: Vec::new(), python: Some(side), python_missing: None };
        let s = python_section(&data);
        // Medians 1 and 3; round by round 2/1, 3/2 and 4/1.
        assert!(s.contains("| 3.00x (1.50–4.00x round by round) |"), "{s}");
        assert!(s.contains("×3 (wide) |"), "{s}");
        assert!(!s.contains("| 1.00x ("), "ours against itself has no range: {s}");
    }
}
