//! The house rules ARCHITECTURE.md states, checked on the sources so a new file keeps them:
//! no source file much over 600 lines unless its module doc says why it reads best whole, and no
//! glob import of the crate's own modules outside tests (explicit imports say where a name
//! comes from; an external prelude such as rayon's is allowed).

use std::path::{Path, PathBuf};

/// The line count above which a file needs its reason ("about 600").
const LONG_FILE_LINES: usize = 620;

/// The words a long file's module doc opens its reason with.
const REASON: &str = "**Why one file";

/// The crates' source folders.
const SOURCE_DIRS: &[&str] =
    &["algorithms/src", "metrics/src", "io/src", "pipeline/src", "render/src", "cli/src", "python/src", "experiments/src"];

fn workspace() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let entries = std::fs::read_dir(dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display()));
    for entry in entries {
        let path = entry.expect("a directory entry").path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

fn sources() -> Vec<(PathBuf, String)> {
    let mut files = Vec::new();
    for dir in SOURCE_DIRS {
        rust_files(&workspace().join(dir), &mut files);
    }
    files.sort();
    assert!(files.len() > 100, "found only {} source files: are the folders right?", files.len());
    files
        .into_iter()
        .map(|p| {
            let text = std::fs::read_to_string(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
            (p, text)
        })
        .collect()
}

/// Whether a file's module doc (its leading `//!` lines) gives the reason a long file is whole.
fn states_its_reason(text: &str) -> bool {
    text.lines().take_while(|l| l.starts_with("//!") || l.trim().is_empty()).any(|l| l.contains(REASON))
}

/// Top-level `use path::*;` lines of the crate's own modules (not a `prelude`), outside tests,
/// re-exports (`pub use path::*;`, `pub(crate) use ...`) included: a glob re-export hides where a
/// public name is defined as much as a glob import hides where a used one comes from.
fn own_globs(path: &Path, text: &str) -> Vec<String> {
    if path.file_name().is_some_and(|n| n == "tests.rs") {
        return Vec::new();
    }
    let is_use = |l: &str| {
        let rest = l.strip_prefix("pub(crate) ").or_else(|| l.strip_prefix("pub ")).unwrap_or(l);
        rest.starts_with("use ")
    };
    text.lines().filter(|l| is_use(l) && l.ends_with("::*;") && !l.contains("prelude::")).map(str::to_owned).collect()
}

#[test]
fn long_files_say_why_they_are_whole() {
    let long: Vec<String> = sources()
        .iter()
        .filter(|(_, text)| text.lines().count() > LONG_FILE_LINES && !states_its_reason(text))
        .map(|(p, text)| format!("{} ({} lines)", p.display(), text.lines().count()))
        .collect();
    assert!(long.is_empty(), "over {LONG_FILE_LINES} lines with no \"{REASON}\" in the module doc: {long:#?}");
}

#[test]
fn no_glob_imports_of_our_own_modules() {
    let globs: Vec<String> = sources()
        .iter()
        .flat_map(|(p, text)| own_globs(p, text).into_iter().map(move |l| format!("{}: {l}", p.display())))
        .collect();
    assert!(globs.is_empty(), "glob imports outside tests (import the names): {globs:#?}");
}

#[test]
fn the_checks_see_what_they_look_for() {
    assert!(states_its_reason("//! Title\n//!\n//! **Why one file of about 900 lines.** ...\n\nuse x;\n"));
    assert!(!states_its_reason("//! Title\n\nuse x;\n// **Why one file** in a later comment\n"));
    let p = Path::new("a/mod.rs");
    assert_eq!(own_globs(p, "use super::*;\nuse rayon::prelude::*;\n    use super::*;\n"), vec!["use super::*;"]);
    assert_eq!(
        own_globs(p, "pub use engine::*;\npub(crate) use table::*;\npub use engine::{Star};\npub use x::prelude::*;\n"),
        vec!["pub use engine::*;", "pub(crate) use table::*;"]
    );
    assert!(own_globs(Path::new("a/tests.rs"), "use super::*;\n").is_empty());
}

/// The licence `Cargo.toml` names has its texts beside it, and CITATION.cff cites this version
/// under the same licences.
#[test]
fn the_licences_and_the_citation_match_the_manifest() {
    let manifest = std::fs::read_to_string(workspace().join("Cargo.toml")).expect("Cargo.toml");
    assert!(manifest.contains("license = \"MIT OR Apache-2.0\""), "the workspace's licence changed: update the files");
    let version = manifest
        .lines()
        .find_map(|l| l.strip_prefix("version = \""))
        .and_then(|v| v.strip_suffix('"'))
        .expect("the workspace's version");
    let mit = std::fs::read_to_string(workspace().join("LICENSE-MIT")).expect("LICENSE-MIT");
    assert!(mit.starts_with("MIT License") && mit.contains("Permission is hereby granted"));
    let apache = std::fs::read_to_string(workspace().join("LICENSE-APACHE")).expect("LICENSE-APACHE");
    assert!(apache.contains("Apache License") && apache.contains("Version 2.0, January 2004"));
    let cff = std::fs::read_to_string(workspace().join("CITATION.cff")).expect("CITATION.cff");
    assert!(cff.contains("cff-version: 1.2.0"), "{cff}");
    assert!(cff.contains(&format!("version: \"{version}\"")), "CITATION.cff does not cite version {version}");
    assert!(cff.contains("  - MIT\n") && cff.contains("  - Apache-2.0\n"), "CITATION.cff's licences");
}

/// The leading `//!` lines of a file.
fn module_doc(text: &str) -> String {
    text.lines().take_while(|l| l.starts_with("//!") || l.trim().is_empty()).collect::<Vec<_>>().join("\n")
}

/// What an extractor's module doc lacks of the sections ARCHITECTURE asks for: the paper it
/// follows (a quoted title and a year), its **Guarantees**, its **Non-guarantees** and an example.
fn missing_doc_sections(doc: &str) -> Vec<&'static str> {
    let has_year = doc.split(|c: char| !c.is_ascii_digit()).any(|t| t.len() == 4 && (t.starts_with("19") || t.starts_with("20")));
    let cites_a_paper = has_year && doc.matches('"').count() >= 2;
    let mut missing = Vec::new();
    if !cites_a_paper {
        missing.push("the paper (a quoted title and a year)");
    }
    if !doc.contains("**Guarantees") {
        missing.push("**Guarantees**");
    }
    if !doc.contains("**Non-guarantees") {
        missing.push("**Non-guarantees**");
    }
    if !doc.contains("//! ```") {
        missing.push("an example");
    }
    missing
}

#[test]
fn every_extractor_module_doc_has_its_paper_guarantees_non_guarantees_and_an_example() {
    let extractors: Vec<(PathBuf, String)> =
        sources().into_iter().filter(|(_, text)| text.lines().any(|l| l.starts_with("pub const INFO: ExtractorInfo"))).collect();
    assert!(extractors.len() >= 7, "found only {} extractor modules", extractors.len());
    let lacking: Vec<String> = extractors
        .iter()
        .filter_map(|(p, text)| {
            let missing = missing_doc_sections(&module_doc(text));
            (!missing.is_empty()).then(|| format!("{}: {}", p.display(), missing.join(", ")))
        })
        .collect();
    assert!(lacking.is_empty(), "extractor module docs without their sections: {lacking:#?}");
}

#[test]
fn the_doc_section_check_sees_what_it_looks_for() {
    let whole =
        "//! # X\n//! After Gibson, \"Nets\", 1998.\n//! **Guarantees.** a\n//! **Non-guarantees.** b\n//! ```\n//! x\n//! ```\n";
    assert!(missing_doc_sections(&module_doc(whole)).is_empty());
    assert_eq!(
        missing_doc_sections("//! # X\n//! **Guarantees.** a\n"),
        vec!["the paper (a quoted title and a year)", "**Non-guarantees**", "an example"]
    );
}

/// The experiments `experiment::all()` lists, by module name.
fn listed_experiments(mod_rs: &str) -> Vec<String> {
    let body = mod_rs.split("pub fn all()").nth(1).unwrap_or("");
    let body = body.split("\n}").next().unwrap_or("");
    body.split("Box::new(").skip(1).filter_map(|s| s.split("::").next()).map(str::to_owned).collect()
}

/// What an experiment's folder lacks of the three files every experiment has: `mod.rs` (its
/// run: `impl Experiment for`), `data.rs` (its data file's types: `struct Data`) and `page.rs`
/// (its page: `fn section(`).
fn missing_experiment_files(folder: &Path) -> Vec<String> {
    [("mod.rs", "impl Experiment for"), ("data.rs", "struct Data"), ("page.rs", "fn section(")]
        .into_iter()
        .filter(|(file, holds)| std::fs::read_to_string(folder.join(file)).map_or(true, |text| !text.contains(holds)))
        .map(|(file, holds)| format!("{file} with `{holds}`"))
        .collect()
}

#[test]
fn every_experiment_is_a_run_a_data_file_and_a_page() {
    let dir = workspace().join("experiments/src/experiment");
    let listed = listed_experiments(&std::fs::read_to_string(dir.join("mod.rs")).expect("experiment/mod.rs"));
    assert!(listed.len() >= 20, "experiment::all() lists {listed:?}");
    let lacking: Vec<String> = listed
        .iter()
        .filter_map(|name| {
            let missing = missing_experiment_files(&dir.join(name));
            (!missing.is_empty()).then(|| format!("{name}: {}", missing.join(", ")))
        })
        .collect();
    assert!(lacking.is_empty(), "experiments without their three files: {lacking:#?}");
}

#[test]
fn the_experiment_layout_check_sees_what_it_looks_for() {
    let listed =
        listed_experiments("pub fn all() -> Vec<Box<dyn Experiment>> {\n    vec![Box::new(a::A), Box::new(b_c::B)]\n}\n");
    assert_eq!(listed, ["a", "b_c"]);
    let dir = tempfile::tempdir().expect("a temporary folder");
    std::fs::write(dir.path().join("mod.rs"), "impl Experiment for X {}").expect("write");
    std::fs::write(dir.path().join("page.rs"), "fn page() {}").expect("write");
    assert_eq!(missing_experiment_files(dir.path()), ["data.rs with `struct Data`", "page.rs with `fn section(`"]);
}
