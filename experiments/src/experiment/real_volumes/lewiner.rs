//! `real_volumes`' cell-by-cell comparison of `marching-cubes-33` with scikit-image's Lewiner on
//! the MNI template at each of the page's levels and on the second volume (the fMRI series' first
//! volume) at its own level: every cell where the two differ, named by the
//! rules of `python/tests/lewiner_cells.py` (the Python test's own, so the page and the test
//! judge alike), counted by reason. `lewiner_cells.py` beside this file runs them in the
//! reference environment, on the array nibabel loads, with the package of this commit.

use super::{Data, Level};
use crate::peers::python;
use crate::report::markdown_table;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::Path;

/// One level's cells by reason.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub(crate) struct CellCounts {
    /// The level's name (the script gives the iso-value only).
    #[serde(default)]
    pub(crate) level: String,
    pub(crate) iso: f32,
    /// Cells by reason, and "same" (and "same, with a centre": both put a vertex inside).
    pub(crate) counts: BTreeMap<String, usize>,
    /// Cells no rule names (the Python test fails on any).
    pub(crate) unnamed: usize,
    /// The first unnamed cells, with their corner values.
    pub(crate) examples: Vec<String>,
    pub(crate) seconds: f64,
}

#[derive(Deserialize)]
struct ScriptOut {
    rows: Vec<CellCounts>,
    versions: BTreeMap<String, String>,
}

/// Runs the comparison on `scan` (its volume `volume` when it is a 4D series) at `levels`;
/// returns the rows and the versions it ran with.
pub(super) fn classify(
    root: &Path,
    scan: &Path,
    volume: Option<usize>,
    levels: &[Level],
) -> Result<(Vec<CellCounts>, BTreeMap<String, String>), String> {
    let py = python::reference_python(root)?;
    python::install_package(&py, root)?;
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("src/experiment/real_volumes/lewiner_cells.py");
    let scan = scan.to_string_lossy().into_owned();
    let mut args = vec![volume.map_or(scan.clone(), |v| format!("{scan}:{v}"))];
    args.extend(levels.iter().map(|l| l.iso.to_string()));
    let out: ScriptOut = python::run_script(&py, &script, &args, &[])?;
    let rows = out.rows.into_iter().zip(levels).map(|(row, level)| CellCounts { level: level.name.clone(), ..row }).collect();
    Ok((rows, out.versions))
}

/// The page's section: a row per level, a column per reason.
pub(super) fn section(data: &Data) -> String {
    if data.lewiner_cells.is_empty() {
        return String::new();
    }
    let mut reasons: Vec<&String> =
        data.lewiner_cells.iter().flat_map(|r| r.counts.keys()).filter(|k| !k.starts_with("same")).collect();
    reasons.sort();
    reasons.dedup();
    let mut header = vec!["level", "cells compared", "the same"];
    header.extend(reasons.iter().map(|r| r.as_str()));
    header.push("unnamed");
    let rows: Vec<Vec<String>> = data
        .lewiner_cells
        .iter()
        .map(|r| {
            let compared: usize =
                r.counts.iter().filter(|(k, _)| k.as_str() != "same, with a centre").map(|(_, v)| v).sum::<usize>() + r.unnamed;
            let mut row = vec![
                format!("{} ({})", r.level, r.iso),
                compared.to_string(),
                r.counts.get("same").copied().unwrap_or(0).to_string(),
            ];
            row.extend(reasons.iter().map(|k| r.counts.get(*k).copied().unwrap_or(0).to_string()));
            row.push(r.unnamed.to_string());
            row
        })
        .collect();
    let mut s = format!(
        "### Cell by cell against scikit-image's Lewiner\n\nOn the MNI template at the page's levels and on the second volume at its \
         own. `marching-cubes-33` and scikit-image's Lewiner each mesh a cell from its eight corner \
         values alone, so every cell the surface crosses is compared on its own (each cell spread into its own block of a volume twice \
         the size, both libraries masked to those blocks). A cell is the same when both make as many triangles and put the same vertex \
         inside it, if any (ours keeps Lewiner's centre {} of a cell inside its faces). Every other cell is named by the \
         interpolant's own level set in the cell, sampled finely: a topology scikit-image misses (its one-slice tunnel test), a tube ours \
         draws otherwise so that it does not cross itself, or a cell within a hair of a critical value, where neither can be judged. \
         The rules are `python/tests/lewiner_cells.py`'s, which the Python test holds to no unnamed cell.\n\n",
        isolab_algorithms::tables::marching_cubes_33::CENTRE_MARGIN
    );
    s.push_str(&markdown_table(&header, &rows));
    for r in data.lewiner_cells.iter().filter(|r| r.unnamed > 0) {
        s.push_str(&format!("\nUnnamed at {}: {}\n", r.level, r.examples.join("; ")));
    }
    s.push('\n');
    s
}
