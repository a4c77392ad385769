//! Figures no page links: every chart is drawn as both `.svg` and `.png` and a page links one,
//! and a rerun with fewer inputs leaves its older pictures behind. The assembler removes them
//! from the folders of the experiments whose pages it rendered, so the committed report holds
//! only what a reader can reach (it has a size budget).

use std::path::{Path, PathBuf};

/// The text every link can be in: the report's pages, scripts and data files.
fn linking_text(report: &Path) -> String {
    let mut text = String::new();
    for dir in [report.to_path_buf(), report.join("data")] {
        let Ok(entries) = std::fs::read_dir(&dir) else { continue };
        for entry in entries.flatten() {
            let path = entry.path();
            let linking = path.extension().is_some_and(|e| e == "md" || e == "html" || e == "js" || e == "json");
            if linking {
                text.push_str(&std::fs::read_to_string(&path).unwrap_or_default());
            }
        }
    }
    text
}

/// The files under `report/figures/<name>/` for each of `names` whose file name appears in no
/// page, script or data file of the report (a file name, not a path: a link built from parts
/// still keeps its file).
pub fn unlinked(report: &Path, names: &[&str]) -> Vec<PathBuf> {
    let text = linking_text(report);
    let mut out = Vec::new();
    for name in names {
        let Ok(entries) = std::fs::read_dir(report.join("figures").join(name)) else { continue };
        for entry in entries.flatten() {
            let path = entry.path();
            let file = path.file_name().map(|f| f.to_string_lossy().into_owned()).unwrap_or_default();
            if path.is_file() && !text.contains(&file) {
                out.push(path);
            }
        }
    }
    out.sort();
    out
}

/// Removes [`unlinked`]'s files; returns how many.
pub fn prune(report: &Path, names: &[&str]) -> usize {
    unlinked(report, names).iter().filter(|p| std::fs::remove_file(p).is_ok()).count()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_the_files_no_page_names_go() {
        let dir = tempfile::tempdir().expect("temporary folder");
        let report = dir.path();
        let figures = report.join("figures/demo");
        std::fs::create_dir_all(&figures).unwrap();
        std::fs::create_dir_all(report.join("figures/other")).unwrap();
        for f in ["chart.svg", "chart.png", "picture.png", "linked-from-data.glb"] {
            std::fs::write(figures.join(f), "x").unwrap();
        }
        std::fs::write(report.join("figures/other/stale.png"), "x").unwrap();
        std::fs::write(report.join("demo.md"), "![chart](figures/demo/chart.svg) ![p](figures/demo/picture.png)").unwrap();
        std::fs::create_dir_all(report.join("data")).unwrap();
        std::fs::write(report.join("data/demo.json"), "{\"mesh\": \"linked-from-data.glb\"}").unwrap();
        assert_eq!(unlinked(report, &["demo"]), vec![figures.join("chart.png")]);
        assert_eq!(prune(report, &["demo"]), 1);
        assert!(!figures.join("chart.png").exists() && figures.join("chart.svg").exists());
        // A folder not named is left alone.
        assert!(report.join("figures/other/stale.png").exists());
    }
}
