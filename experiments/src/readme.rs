//! The README's generated parts, so that no number in it is typed by hand: how long the two
//! commands took (the test command's fresh-clone run in `data/test_command.json`, written with its
//! provenance by `tests/time_fresh_clone.sh`; the main job's experiments' last runs in
//! `data/run_times.json`) and the table of experiments (each one's binary, its question from the
//! registry, and its minutes). [`fill`] rewrites what lies between each pair of markers
//! (`<!-- generated:NAME -->` and `<!-- /generated:NAME -->`); the `report` binary writes it into
//! `README.md` at every assembly, and the report's checks hold the committed README to it.

use crate::experiment::{Context, Experiment};
use serde::Deserialize;
use std::collections::BTreeMap;

/// The data file of the test command's timed fresh-clone run.
pub const TEST_COMMAND: &str = "test_command";

/// The README's generated blocks, by marker name.
pub const BLOCKS: [&str; 2] = ["times", "experiments"];

/// The step times of one timed run of the test command from a fresh clone.
#[derive(Debug, Clone, Deserialize)]
pub struct TestCommandRun {
    /// Seconds per step of `tests/all.sh`, in its order, as it printed them.
    pub steps: Vec<(String, f64)>,
    /// The whole command's wall time in seconds, the build included.
    pub total_seconds: f64,
    /// Where, when and on what it ran.
    pub provenance: TestCommandProvenance,
}

/// The part of a run's provenance the README states.
#[derive(Debug, Clone, Deserialize)]
pub struct TestCommandProvenance {
    /// The commit cloned.
    pub commit: String,
    /// When it started, UTC.
    pub date_utc: String,
    /// Threads available.
    pub cores: usize,
}

/// Minutes, as the README writes them: whole minutes, or "under 1".
fn minutes(seconds: f64) -> String {
    if seconds < 60.0 {
        "under 1".to_owned()
    } else {
        format!("{:.0}", seconds / 60.0)
    }
}

/// The "times" block: the two commands' times on this machine, from the data.
pub fn times_block(ctx: &Context, experiments: &[Box<dyn Experiment>]) -> String {
    let mut s = String::new();
    match ctx.read_data::<TestCommandRun>(TEST_COMMAND) {
        Ok(run) => {
            let steps: Vec<String> = run.steps.iter().map(|(name, secs)| format!("{name} {} min", minutes(*secs))).collect();
            s.push_str(&format!(
                "From a fresh clone on {} cores, the test command took {} minutes, the first build included ({}; \
                 commit `{}`, {}, `report/data/{TEST_COMMAND}.json`).",
                run.provenance.cores,
                minutes(run.total_seconds),
                steps.join(", "),
                &run.provenance.commit[..run.provenance.commit.len().min(10)],
                run.provenance.date_utc.get(..10).unwrap_or(&run.provenance.date_utc),
            ));
        }
        Err(_) => s.push_str("The test command's time from a fresh clone is not recorded (`tests/time_fresh_clone.sh`)."),
    }
    let times: BTreeMap<String, f64> = ctx.read_data("run_times").unwrap_or_default();
    let recorded: Vec<f64> = experiments.iter().filter_map(|e| times.get(e.name()).copied()).collect();
    s.push_str(&format!(
        " The main job's experiments took {:.1} hours in their last runs on the same machine ({} of {} recorded, \
         `report/data/run_times.json`), the build apart.\n",
        recorded.iter().sum::<f64>() / 3600.0,
        recorded.len(),
        experiments.len()
    ));
    s
}

/// The "experiments" block: a row per experiment (its binary, its question, its minutes).
pub fn experiments_block(ctx: &Context, experiments: &[Box<dyn Experiment>]) -> String {
    let times: BTreeMap<String, f64> = ctx.read_data("run_times").unwrap_or_default();
    let mut s = String::from("| Binary (`--bin`) | Question | Minutes |\n|---|---|---|\n");
    for e in experiments {
        let time = times.get(e.name()).map_or_else(|| "not recorded".to_owned(), |&t| minutes(t));
        s.push_str(&format!("| [`{0}`](report/{0}.md) | {1} | {time} |\n", e.name(), e.question()));
    }
    s
}

/// The block named `name`.
pub fn block(ctx: &Context, experiments: &[Box<dyn Experiment>], name: &str) -> String {
    match name {
        "times" => times_block(ctx, experiments),
        _ => experiments_block(ctx, experiments),
    }
}

/// `readme` with every generated block rewritten; an error names a block whose markers are
/// missing or out of order.
pub fn fill(readme: &str, ctx: &Context, experiments: &[Box<dyn Experiment>]) -> Result<String, String> {
    let mut text = readme.to_owned();
    for name in BLOCKS {
        let (open, close) = (format!("<!-- generated:{name} -->\n"), format!("<!-- /generated:{name} -->"));
        let start = text.find(&open).ok_or_else(|| format!("README.md has no `{}` marker", open.trim_end()))? + open.len();
        let end = text[start..].find(&close).ok_or_else(|| format!("README.md has no `{close}` after its opening"))? + start;
        text.replace_range(start..end, &block(ctx, experiments, name));
    }
    Ok(text)
}

/// Rewrites the workspace's `README.md` generated blocks from `ctx`'s data; whether it changed.
/// Both the main job and each experiment's own binary call it after assembling, so a run time
/// an experiment records reaches the README's table at once.
pub fn write_workspace_readme(ctx: &Context) -> Result<bool, String> {
    let path = crate::provenance::root().join("README.md");
    let text = std::fs::read_to_string(&path).map_err(|e| format!("{}: {e}", path.display()))?;
    let filled = fill(&text, ctx, &crate::experiment::all())?;
    if filled == text {
        return Ok(false);
    }
    std::fs::write(&path, filled).map_err(|e| format!("{}: {e}", path.display()))?;
    Ok(true)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::experiment::all;

    fn context_with(run_times: &str, test_command: Option<&str>) -> (tempfile::TempDir, Context) {
        let dir = tempfile::tempdir().unwrap();
        std::fs::create_dir_all(dir.path().join("data")).unwrap();
        std::fs::write(dir.path().join("data/run_times.json"), run_times).unwrap();
        if let Some(t) = test_command {
            std::fs::write(dir.path().join("data/test_command.json"), t).unwrap();
        }
        let ctx = Context::new(dir.path().to_path_buf(), 1);
        (dir, ctx)
    }

    #[test]
    fn blocks_follow_the_data() {
        let test_command = r#"{"steps": [["Rust tests", 600.0], ["Python tests", 30.0]], "total_seconds": 660.0,
            "provenance": {"commit": "0123456789abcdef", "date_utc": "2026-12-06T15:00:00Z", "cores": 2}}"#;
        let (_dir, ctx) = context_with(r#"{"terrain_lod": 90.0, "viewer": 20.0}"#, Some(test_command));
        let experiments = all();
        let times = times_block(&ctx, &experiments);
        assert!(times.contains("on 2 cores, the test command took 11 minutes"), "{times}");
        assert!(times.contains("Rust tests 10 min, Python tests under 1 min"), "{times}");
        assert!(times.contains("`0123456789`, 2026-12-06"), "{times}");
        assert!(times.contains("took 0.0 hours") && times.contains(&format!("(2 of {} recorded", experiments.len())), "{times}");
        let table = experiments_block(&ctx, &experiments);
        assert!(table.contains("| [`terrain_lod`](report/terrain_lod.md) | Do three levels"), "{table}");
        assert!(table.lines().any(|l| l.starts_with("| [`terrain_lod`]") && l.ends_with("| 2 |")), "{table}");
        assert!(table.lines().any(|l| l.starts_with("| [`viewer`]") && l.ends_with("| under 1 |")), "{table}");
        assert_eq!(table.lines().count(), experiments.len() + 2);
    }

    #[test]
    fn fill_rewrites_between_the_markers_and_names_a_missing_one() {
        let (_dir, ctx) = context_with("{}", None);
        let experiments = all();
        let readme = "# x\n<!-- generated:times -->\nold\n<!-- /generated:times -->\nmiddle\n<!-- generated:experiments -->\n\
                      <!-- /generated:experiments -->\nend\n";
        let filled = fill(readme, &ctx, &experiments).unwrap();
        assert!(!filled.contains("old") && filled.contains("middle") && filled.ends_with("end\n"));
        assert!(filled.contains("is not recorded") && filled.contains("| Binary"));
        assert_eq!(fill(&filled, &ctx, &experiments).unwrap(), filled, "filling twice changes nothing");
        let e = fill("# x\n<!-- generated:times -->\n", &ctx, &experiments).unwrap_err();
        assert!(e.contains("/generated:times"), "{e}");
    }
}
