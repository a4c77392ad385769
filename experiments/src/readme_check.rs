//! The README and the guides in `docs/`: the README's generated parts match the committed data,
//! it reads as a front door (length, sentences, the two commands, its links, a true Layout), and
//! every guide's links resolve. (Unit tests, beside the report's checks whose helpers they use.)

use crate::experiment::{all, Context};
use crate::report_check::{links, report_dir, workspace};
use std::path::PathBuf;

/// The README's generated parts (the commands' times, the experiments table) are what the
/// committed data gives: `report` rewrites them at every assembly.
#[test]
fn the_readme_generated_parts_match_the_committed_data() {
    let path = workspace().join("README.md");
    let readme = std::fs::read_to_string(&path).expect("README.md");
    let filled = crate::readme::fill(&readme, &Context::new(report_dir(), 1), &all()).expect("markers");
    assert!(filled == readme, "README.md's generated parts are stale: rerun `--bin report -- --assemble-only` and commit it");
}

/// README.md's prose sentences (outside code blocks, tables and markers), split at full stops.
fn readme_sentences(readme: &str) -> Vec<String> {
    let mut prose = String::new();
    let mut in_code = false;
    for line in readme.lines() {
        if line.starts_with("```") {
            in_code = !in_code;
            prose.push_str(".\n");
            continue;
        }
        if in_code || line.starts_with('|') || line.starts_with("<!--") || line.starts_with('#') {
            prose.push_str(".\n");
            continue;
        }
        prose.push_str(line);
        prose.push('\n');
    }
    prose.split(['.', '?', '!']).map(|s| s.split_whitespace().collect::<Vec<_>>().join(" ")).filter(|s| !s.is_empty()).collect()
}

/// The README reads in a minute: under 2,500 words, no sentence over 60, the test command `.ci/run`
/// runs written in it, and every relative link resolving.
#[test]
fn the_readme_is_a_front_door() {
    const MAX_WORDS: usize = 2500;
    const MAX_SENTENCE_WORDS: usize = 60;
    let readme = std::fs::read_to_string(workspace().join("README.md")).expect("README.md");
    let words = readme.split_whitespace().count();
    assert!(words < MAX_WORDS, "README.md has {words} words (at most {MAX_WORDS})");
    // A decimal point or a path's dot splits early, which only shortens sentences: lists and
    // parentheses stay whole, so the long ones are still found.
    let long: Vec<String> =
        readme_sentences(&readme).into_iter().filter(|s| s.split_whitespace().count() > MAX_SENTENCE_WORDS).collect();
    assert!(long.is_empty(), "sentences over {MAX_SENTENCE_WORDS} words: {long:#?}");
    let ci = std::fs::read_to_string(workspace().join(".ci/run")).expect(".ci/run");
    assert!(readme.contains("\nbash tests/all.sh") && ci.contains("bash tests/all.sh"), "the test command is not in both");
    assert!(readme.contains("\ncargo run --release -p isolab-experiments --bin report"), "the main job is not written out");
    let missing: Vec<String> = links(&readme).into_iter().filter(|l| !workspace().join(l).exists()).collect();
    assert!(missing.is_empty(), "README.md links to missing files: {missing:?}");
    for member in ["algorithms/", "metrics/", "io/", "pipeline/", "render/", "cli/", "python/", "experiments/", "tests/"] {
        assert!(readme.contains(&format!("\n{member}")), "the Layout misses {member}");
    }
}

#[test]
fn the_readme_sentence_splitter_sees_long_sentences() {
    let long = format!("# T\n\n{}.\n\n```sh\n{}\n```\n", "word ".repeat(61), "code ".repeat(80));
    let sentences = readme_sentences(&long);
    assert_eq!(sentences.iter().filter(|s| s.split_whitespace().count() > 60).count(), 1, "{sentences:?}");
}

/// The pages `docs/build.sh` generates into `docs/` (gitignored), relative to `docs/`.
const GENERATED_DOCS: [&str; 1] = ["reference/cli.md"];

/// Whether two paths name one file, `..` and `.` resolved by their text (neither need exist).
fn same_file(a: &std::path::Path, b: &std::path::Path) -> bool {
    fn normal(path: &std::path::Path) -> PathBuf {
        let mut out = PathBuf::new();
        for part in path.components() {
            match part {
                std::path::Component::ParentDir => {
                    out.pop();
                }
                std::path::Component::CurDir => {}
                other => out.push(other),
            }
        }
        out
    }
    normal(a) == normal(b)
}

/// Every relative link of the guides in `docs/` resolves, to a committed page or to one
/// `docs/build.sh` generates.
#[test]
fn the_guides_links_resolve() {
    let docs = workspace().join("docs");
    fn markdown(dir: &std::path::Path, out: &mut Vec<PathBuf>) {
        for entry in std::fs::read_dir(dir).expect("a docs folder") {
            let path = entry.expect("entry").path();
            if path.is_dir() {
                markdown(&path, out);
            } else if path.extension().is_some_and(|e| e == "md") {
                out.push(path);
            }
        }
    }
    // Pages docs/build.sh writes before MkDocs runs (not committed; a clean clone lacks them).
    let build_script = std::fs::read_to_string(docs.join("build.sh")).expect("docs/build.sh");
    let generated: Vec<PathBuf> = GENERATED_DOCS
        .iter()
        .inspect(|page| assert!(build_script.contains(&format!("docs/{page}")), "docs/build.sh no longer writes {page}"))
        .map(|page| docs.join(page))
        .collect();
    let mut pages = Vec::new();
    markdown(&docs, &mut pages);
    assert!(pages.len() >= 5, "docs/ has {} pages", pages.len());
    for page in pages {
        let text = std::fs::read_to_string(&page).expect("page");
        let here = page.parent().expect("a page's folder");
        let resolves = |link: &String| {
            let target = here.join(link);
            target.exists() || generated.iter().any(|g| same_file(g, &target))
        };
        let missing: Vec<String> = links(&text).into_iter().filter(|l| !resolves(l)).collect();
        assert!(missing.is_empty(), "{} links to missing files: {missing:?}", page.display());
    }
}
