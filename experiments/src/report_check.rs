//! (Unit tests of the crate, not an integration test: the crate then has no integration test, so
//! `cargo test` builds none of its 23 binaries.)
//!
//! The generated report: its pages assemble from the committed data and match what is committed,
//! every link resolves, the front page recommends for every use case and stays short, and no
//! number is typed into the experiments' prose (every number is computed from the data or from a
//! labelled constant).

use crate::experiment::{all, assemble, Context};
use crate::reviewed_literals::{names_file, REVIEWED, REVIEWED_COMPARISONS};
use std::path::{Path, PathBuf};

/// The front page must fit on a few screens.
/// Lines of the front page outside its tables (the tables grow with the registries of
/// extractors and experiments, which must not need a test edit).
const FRONT_PAGE_MAX_LINES: usize = 40;

pub(crate) fn workspace() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

pub(crate) fn report_dir() -> PathBuf {
    workspace().join("report")
}

/// The report assembled afresh from the committed data, in a temporary directory.
fn assembled() -> tempfile::TempDir {
    let tmp = tempfile::tempdir().expect("temporary directory");
    let data = tmp.path().join("data");
    std::fs::create_dir_all(&data).expect("data directory");
    for entry in std::fs::read_dir(report_dir().join("data")).expect("report/data") {
        let entry = entry.expect("entry");
        std::fs::copy(entry.path(), data.join(entry.file_name())).expect("copy data");
    }
    assemble(&Context::new(tmp.path().to_path_buf(), 1)).expect("assemble");
    tmp
}

/// The relative link targets of a Markdown page (`](target)`), without anchors.
pub(crate) fn links(md: &str) -> Vec<String> {
    md.split("](")
        .skip(1)
        .filter_map(|rest| rest.split(')').next())
        .map(|t| t.split('#').next().unwrap_or("").to_owned())
        .filter(|t| !t.is_empty() && !t.starts_with("http"))
        .collect()
}

/// The relative `href` and `src` targets of an HTML page, without anchors.
fn html_links(html: &str) -> Vec<String> {
    ["href=\"", "src=\""]
        .iter()
        .flat_map(|attr| html.split(attr).skip(1).filter_map(|rest| rest.split('"').next()))
        .map(|t| t.split('#').next().unwrap_or("").to_owned())
        .filter(|t| !t.is_empty() && !t.contains("://") && !t.starts_with("data:"))
        .collect()
}

/// The front page's list of the registered extractors ("compares isolab's N extractors (...)
/// on"), cut out: it follows the registry, which the tests check directly, so that registering an
/// extractor needs no reassembly for the committed pages to match.
fn without_registry_list(text: &str) -> String {
    let (start, end) = ("compares isolab's ", ") on ");
    match text.find(start) {
        Some(i) => match text[i..].find(end) {
            Some(j) => format!("{}{start}[the registry]{}", &text[..i], &text[i + j..]),
            None => text.to_owned(),
        },
        None => text.to_owned(),
    }
}

#[test]
fn pages_assemble_from_the_committed_data_and_match_what_is_committed() {
    let tmp = assembled();
    let mut names: Vec<String> = all().iter().flat_map(|e| [format!("{}.md", e.name()), format!("{}.html", e.name())]).collect();
    names.extend(
        ["REPORT.md", "REPORT.html", "index.html", "viewer.js", "bibliography.md", "bibliography.html"].map(String::from),
    );
    for name in &names {
        let fresh = std::fs::read_to_string(tmp.path().join(name)).expect("assembled page");
        assert!(!fresh.contains("Not generated yet"), "{name}: a section is missing its data");
        let committed = std::fs::read_to_string(report_dir().join(name))
            .unwrap_or_else(|_| panic!("report/{name} is not committed: run the report's --assemble-only"));
        assert!(
            without_registry_list(&fresh) == without_registry_list(&committed),
            "report/{name} is stale: rerun `--bin report -- --assemble-only` and commit it"
        );
        for target in links(&fresh).into_iter().chain(html_links(&fresh)) {
            assert!(report_dir().join(&target).exists(), "{name}: link to '{target}', which does not exist");
        }
    }
}

#[test]
fn the_front_page_lists_every_registered_extractor() {
    let tmp = assembled();
    let front = std::fs::read_to_string(tmp.path().join("REPORT.md")).expect("front page");
    let names: Vec<String> = isolab_algorithms::extractors::registry().iter().map(|e| format!("`{}`", e.name())).collect();
    let list = format!("compares isolab's {} extractors ({}) on ", names.len(), names.join(", "));
    assert!(front.contains(&list), "the front page's list is not the registry's: {list}");
    assert_ne!(without_registry_list(&front), front, "the list is where the comparison cuts it out");
}

#[test]
fn the_front_page_recommends_for_every_use_case_links_every_page_and_is_short() {
    let tmp = assembled();
    let front = std::fs::read_to_string(tmp.path().join("REPORT.md")).expect("front page");
    assert!(front.contains("## Choosing an extractor"));
    assert!(!front.contains("no recommendation yet"), "a use case has no recommendation:\n{front}");
    let picks = front.lines().filter(|l| l.starts_with("- **") && l.contains(": `")).count();
    assert!(picks >= 5, "{picks} use cases recommended");
    for e in all() {
        assert!(front.contains(&format!("]({}.md)", e.name())), "front page does not link {}", e.name());
    }
    let lines = front.lines().filter(|l| !l.starts_with('|')).count();
    assert!(lines <= FRONT_PAGE_MAX_LINES, "front page has {lines} lines outside its tables (at most {FRONT_PAGE_MAX_LINES})");
}

/// The pages that reproduce a paper or post of `../shared/papers/`: each lists where we differ.
const PAPER_PAGES: &[&str] = &["costen_table", "stuart_tables", "svoboda_timing", "surface_nets_smoothing", "terrain_liquids"];

/// Where a page's reading must start: within its first lines (the heading, the provenance line,
/// the one paragraph that says what ran, then the reading, a paragraph or a list).
const READING_WITHIN_LINES: usize = 10;

#[test]
fn every_page_opens_with_a_reading() {
    let tmp = assembled();
    for e in all() {
        let page = std::fs::read_to_string(tmp.path().join(format!("{}.md", e.name()))).expect("assembled page");
        let opens = page.lines().take(READING_WITHIN_LINES).any(|l| l.starts_with("**Reading.**"));
        assert!(opens, "{}.md does not open with a reading (\"**Reading.** ...\" in its first lines)", e.name());
    }
}

#[test]
fn every_page_states_where_its_data_ran_and_how_to_regenerate_it() {
    let tmp = assembled();
    let front = std::fs::read_to_string(tmp.path().join("REPORT.md")).expect("front page");
    assert!(front.contains("| data made at | its code since |"), "the front page lists no commits");
    for e in all() {
        let page = std::fs::read_to_string(tmp.path().join(format!("{}.md", e.name()))).expect("assembled page");
        let head: Vec<&str> = page.lines().take(READING_WITHIN_LINES).collect();
        let line =
            head.iter().find(|l| l.contains("Regenerate: `")).unwrap_or_else(|| panic!("{}.md: no provenance line", e.name()));
        assert!(line.contains(&format!("--bin {}`", e.name())), "{}.md: {line}", e.name());
        assert!(line.contains("Data made at commit `") || line.contains("not recorded"), "{}.md: {line}", e.name());
    }
}

#[test]
fn no_page_has_an_accidental_code_block() {
    // Four leading spaces outside a fenced block make Markdown a code block: in generated prose,
    // a string continuation that kept its indentation.
    let tmp = assembled();
    for e in all() {
        let page = std::fs::read_to_string(tmp.path().join(format!("{}.md", e.name()))).expect("assembled page");
        let mut fenced = false;
        for (k, line) in page.lines().enumerate() {
            if line.starts_with("```") {
                fenced = !fenced;
            }
            assert!(fenced || !line.starts_with("    "), "{}.md line {}: indented as code: {line}", e.name(), k + 1);
        }
    }
}

#[test]
fn every_paper_page_lists_where_we_differ() {
    let tmp = assembled();
    let names: Vec<&str> = all().iter().map(|e| e.name()).collect();
    for page in PAPER_PAGES {
        assert!(names.contains(page), "{page} is not a registered experiment");
        let text = std::fs::read_to_string(tmp.path().join(format!("{page}.md"))).expect("assembled page");
        let mut lines = text.lines().skip_while(|l| !(l.starts_with('#') && l.contains("Where we differ from the ")));
        lines.next();
        let entries = lines.take_while(|l| !l.starts_with('#')).filter(|l| l.starts_with("- ")).count();
        assert!(entries > 0, "{page}.md has no \"Where we differ from the paper\" list with entries");
    }
}

/// A string literal of a Rust source file: its text and line.
struct Literal {
    text: String,
    line: usize,
}

/// The string literals of Rust source, outside comments and char literals (a small lexer: plain,
/// raw and byte strings; a test module at the end is left out).
fn string_literals(src: &str) -> Vec<Literal> {
    let src = src.split("#[cfg(test)]\nmod tests").next().unwrap_or(src);
    let b = src.as_bytes();
    let (mut i, mut line, mut out) = (0usize, 1usize, Vec::new());
    while i < b.len() {
        match b[i] {
            b'\n' => {
                line += 1;
                i += 1;
            }
            b'/' if b.get(i + 1) == Some(&b'/') => {
                while i < b.len() && b[i] != b'\n' {
                    i += 1;
                }
            }
            b'/' if b.get(i + 1) == Some(&b'*') => {
                while i + 1 < b.len() && !(b[i] == b'*' && b[i + 1] == b'/') {
                    line += usize::from(b[i] == b'\n');
                    i += 1;
                }
                i += 2;
            }
            b'\'' => {
                // A char literal ('x', '\n', '\'') or a lifetime ('a): skip either.
                if b.get(i + 1) == Some(&b'\\') {
                    i += 2;
                    while i < b.len() && b[i] != b'\'' {
                        i += 1;
                    }
                    i += 1;
                } else {
                    let len = src[i + 1..].chars().next().map_or(1, char::len_utf8);
                    i += if b.get(i + 1 + len) == Some(&b'\'') { len + 2 } else { 1 };
                }
            }
            b'r' if (b.get(i + 1) == Some(&b'"') || b.get(i + 1) == Some(&b'#'))
                && (i == 0 || !(b[i - 1].is_ascii_alphanumeric() || b[i - 1] == b'_')) =>
            {
                let hashes = b[i + 1..].iter().take_while(|&&c| c == b'#').count();
                if b.get(i + 1 + hashes) != Some(&b'"') {
                    i += 1;
                    continue;
                }
                let start = i + 2 + hashes;
                let close = format!("\"{}", "#".repeat(hashes));
                let end = src[start..].find(&close).map_or(b.len(), |k| start + k);
                out.push(Literal { text: src[start..end].to_owned(), line });
                line += src[start..end].matches('\n').count();
                i = end + close.len();
            }
            b'"' => {
                let start = i + 1;
                i = start;
                while i < b.len() && b[i] != b'"' {
                    i += if b[i] == b'\\' { 2 } else { 1 };
                }
                let text = &src[start..i.min(b.len())];
                out.push(Literal { text: text.to_owned(), line });
                line += text.matches('\n').count();
                i += 1;
            }
            _ => i += 1,
        }
    }
    out
}

/// A literal's text with its format placeholders (`{...}`) removed and `{{`/`}}` kept as braces.
fn without_placeholders(text: &str) -> String {
    let (mut out, mut chars) = (String::new(), text.chars().peekable());
    while let Some(c) = chars.next() {
        match c {
            '{' if chars.peek() == Some(&'{') => {
                chars.next();
                out.push('{');
            }
            '}' if chars.peek() == Some(&'}') => {
                chars.next();
                out.push('}');
            }
            '{' => {
                for d in chars.by_ref() {
                    if d == '}' {
                        break;
                    }
                }
                out.push('∎');
            }
            _ => out.push(c),
        }
    }
    out
}

/// Words after which a number is a reference into a paper, not a measurement.
const REFERENCES: [&str; 12] =
    ["Table", "Tables", "Fig.", "Figs.", "Figure", "Figures", "section", "Section", "Appendix", "et al.", "Eq.", "equation"];

/// The typed numbers of one literal: the numbers of its words that are not names (a word that
/// starts with a letter or a placeholder: `log10`, `x86_64`, `i7-11700`, `{n}^3`), references into
/// a paper (`Table 2`, `Figs. 7-10`) or years of a citation (`Costen (2026)`, `Svoboda 2020`). A
/// word that starts with a letter is a number all the same when it is a multiple (`x52`) or holds
/// a decimal (`h0.5`, `AR1.34`), except a version (`v1.2`).
fn typed_numbers(text: &str) -> Vec<String> {
    let t = without_placeholders(text);
    let chars: Vec<char> = t.chars().collect();
    let in_word = |c: char| c.is_alphanumeric() || "_-.^∎'".contains(c);
    let mut found = Vec::new();
    let mut k = 0;
    while k < chars.len() {
        if !in_word(chars[k]) {
            k += 1;
            continue;
        }
        let start = k;
        while k < chars.len() && in_word(chars[k]) {
            k += 1;
        }
        let word: String = chars[start..k].iter().collect();
        let first = word.trim_start_matches(['.', '-', '\'']).chars().next().unwrap_or(' ');
        if first.is_alphabetic() {
            found.extend(letter_initial_numbers(&word));
            continue;
        }
        if !first.is_ascii_digit() || word.starts_with("3D") || word.starts_with("2D") {
            continue;
        }
        let before: String = chars[..start].iter().collect();
        // A list or range of references continues the reference ("Figs. 7-10", "Tables 1, 2").
        let lead = before.trim_end_matches(|c: char| c.is_ascii_digit() || ", -–".contains(c));
        if REFERENCES.iter().any(|r| lead.ends_with(r)) {
            continue;
        }
        let digits: String = word.chars().take_while(char::is_ascii_digit).collect();
        let previous = before.trim_end().rsplit(|c: char| c.is_whitespace()).next().unwrap_or("");
        let cites = before.ends_with('(') || previous.chars().next().is_some_and(char::is_uppercase);
        if digits.len() == 4 && (digits.starts_with("19") || digits.starts_with("20")) && cites {
            continue;
        }
        let mut number = String::new();
        for c in word.chars().chain([' ']) {
            if c.is_ascii_digit() || (c == '.' && !number.is_empty()) {
                number.push(c);
            } else if !number.is_empty() {
                found.push(number.trim_end_matches('.').to_owned());
                number.clear();
            }
        }
    }
    found
}

/// The numbers a word that starts with a letter types: those after a multiplication sign's `x`
/// (`x52`, `x1.5`) and decimals after letters (`h0.5`, `AR1.34`); none from names (`f32`,
/// `MNI152`, `x86_64`) or versions (`v1.2`).
fn letter_initial_numbers(word: &str) -> Vec<String> {
    let lead: String = word.chars().take_while(|c| c.is_alphabetic() || *c == '_').collect();
    let rest = &word[lead.len()..];
    let number: String = rest.chars().take_while(|c| c.is_ascii_digit() || *c == '.').collect();
    let number = number.trim_end_matches('.');
    let tail = &rest[number.len()..];
    if number.is_empty() || lead.eq_ignore_ascii_case("v") || tail.starts_with('_') {
        return Vec::new();
    }
    let multiple = lead == "x" && (tail.is_empty() || !tail.starts_with(|c: char| c.is_ascii_alphanumeric()));
    let decimal = number.contains('.') && !tail.starts_with('.');
    if multiple || decimal {
        vec![number.to_owned()]
    } else {
        Vec::new()
    }
}

/// Words that state a comparison; a sentence with one of them typed without a placeholder states
/// a verdict no data chose.
const COMPARISONS: [&str; 9] = ["faster", "slower", "better", "worse", "above", "below", "matches", "reproduced", "reproduces"];

/// Whether a literal is a typed comparison: a sentence (six words or more) with a comparison
/// word, placeholders or not (a placeholder fills in a number, not the word that judges it).
/// `above` and `below` followed by punctuation or the literal's end name a place on the page
/// ("the tables below"), not a comparison.
fn typed_comparison(text: &str) -> Option<&'static str> {
    if text.split_whitespace().count() < 6 {
        return None;
    }
    let lower = text.to_lowercase();
    let mut words = Vec::new();
    let mut start = None;
    for (i, c) in lower.char_indices().chain([(lower.len(), ' ')]) {
        match (c.is_alphanumeric(), start) {
            (true, None) => start = Some(i),
            (false, Some(s)) => {
                words.push((s, &lower[s..i]));
                start = None;
            }
            _ => {}
        }
    }
    let place = |end: usize| {
        let next = lower[end..].trim_start_matches([' ', '\\', '\n']).chars().next();
        !next.is_some_and(|c| c.is_alphanumeric() || c == '{')
    };
    COMPARISONS
        .iter()
        .copied()
        .find(|c| words.iter().any(|&(s, w)| w == *c && !((w == "above" || w == "below") && place(s + w.len()))))
}

#[test]
fn the_detectors_catch_what_they_look_for() {
    assert_eq!(typed_numbers("runs x52 faster with h0.5 and AR1.34"), ["52", "0.5", "1.34"]);
    assert!(
        typed_numbers("f32 samples, MNI152, x86_64, v1.2, log10 and u8").is_empty(),
        "{:?}",
        typed_numbers("f32 MNI152 x86_64 v1.2")
    );
    assert_eq!(typed_comparison("our marching cubes is faster than VTK on every grid"), Some("faster"));
    assert_eq!(typed_comparison("at {n} cells ours is faster than VTK"), Some("faster"), "placeholders hide no verdict");
    assert_eq!(typed_comparison("ours took {} ms, below the {} ms of VTK"), Some("below"));
    assert_eq!(typed_comparison("and {} more inputs in the tables below"), None, "a place on the page");
    assert_eq!(typed_comparison("the wake-up times are measured below)."), None);
    assert_eq!(typed_comparison("faster"), None);
}

#[test]
fn no_comparison_is_typed_into_the_experiments_prose() {
    let dir = workspace().join("experiments/src/experiment");
    let mut typed = Vec::new();
    for path in experiment_sources(&dir) {
        let src = std::fs::read_to_string(&path).expect("source");
        let rel = path.strip_prefix(&dir).unwrap_or(&path).to_string_lossy().into_owned();
        for lit in string_literals(&src) {
            let Some(word) = typed_comparison(&lit.text) else { continue };
            if REVIEWED_COMPARISONS.iter().any(|(f, frag, _)| names_file(f, &rel) && lit.text.contains(frag)) {
                continue;
            }
            typed.push(format!("{rel}:{}: \"{word}\" in {:?}", lit.line, lit.text.chars().take(120).collect::<String>()));
        }
    }
    assert!(
        typed.is_empty(),
        "{} literals state a comparison no data chose; generate it from the numbers it compares, or review it:\n{}",
        typed.len(),
        typed.join("\n")
    );
}

/// The experiments' sources that write the report (a module's tests in their own `tests.rs`
/// write nothing into it).
fn experiment_sources(dir: &std::path::Path) -> Vec<PathBuf> {
    let mut files = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for entry in std::fs::read_dir(&d).expect("experiment sources") {
            let path = entry.expect("entry").path();
            if path.is_dir() {
                stack.push(path);
            } else if path.extension().is_some_and(|e| e == "rs") && path.file_name().is_some_and(|n| n != "tests.rs") {
                files.push(path);
            }
        }
    }
    files.sort();
    files
}

#[test]
fn no_number_is_typed_into_the_experiments_prose() {
    let dir = workspace().join("experiments/src/experiment");
    let mut typed = Vec::new();
    for path in experiment_sources(&dir) {
        let src = std::fs::read_to_string(&path).expect("source");
        let rel = path.strip_prefix(&dir).unwrap_or(&path).to_string_lossy().into_owned();
        for lit in string_literals(&src) {
            let numbers = typed_numbers(&lit.text);
            if numbers.is_empty() || REVIEWED.iter().any(|(f, frag, _)| names_file(f, &rel) && lit.text.contains(frag)) {
                continue;
            }
            typed.push(format!("{rel}:{}: {:?} in {:?}", lit.line, numbers, lit.text.chars().take(100).collect::<String>()));
        }
    }
    assert!(
        typed.is_empty(),
        "{} literals type a number into the report; compute it from the data or a labelled constant:\n{}",
        typed.len(),
        typed.join("\n")
    );
}

#[test]
fn the_audit_finds_typed_numbers_and_spares_references_and_placeholders() {
    assert_eq!(typed_numbers("the paper's own counts give 72.5-73.3%"), ["72.5", "73.3"]);
    assert_eq!(typed_numbers("sampling on 16 threads"), ["16"]);
    assert!(typed_numbers("{:.1} ms over {n}³ and {x:>8.3}").is_empty());
    assert!(typed_numbers("Table 2 and Figs. 7-10, section 4.1, Stuart et al. 2013, Appendices C-D").is_empty());
    assert!(typed_numbers("log10 of x86_64 `f32` {{literal braces}} an i7-11700, {n}^3, in 3D").is_empty());
    assert!(typed_numbers("Costen (2026) and Svoboda 2020").is_empty());
    assert_eq!(typed_numbers("default + clearance=0.5, 2x2 quads, at 64³."), ["0.5", "2", "2", "64"]);
    let lits =
        string_literals("// \"7 in a comment\"\nlet a = 'x'; let s = \"a 5\"; fn f<'a>() {}\nlet r = r#\"raw \"9\" \"#;\n");
    let texts: Vec<&str> = lits.iter().map(|l| l.text.as_str()).collect();
    assert_eq!(texts, ["a 5", "raw \"9\" "]);
    assert_eq!(lits[1].line, 3);
}

/// The `functions` page's data (issue 60): every certified sparse mesh it compared is the dense
/// mesh bit for bit, and at 1024³ the distances needed at least 30x fewer evaluations than the
/// grid has points (evaluations are counted, not timed: the same on any machine).
#[test]
fn sparse_meshes_in_the_report_are_the_dense_ones_from_far_fewer_evaluations() {
    let path = report_dir().join("data/functions.json");
    let data: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&path).expect("functions.json")).unwrap();
    let equality = data["equality"].as_array().expect("equality rows");
    // The issue's bar: every chunking extractor at 256³ and 512³ on the analytic fields, and at
    // 256³ on a mesh field (its dense mode queries the exact distance everywhere).
    let compared = |field: &str, n: usize, algorithm: &str| {
        equality.iter().any(|e| e["field"] == field && e["n"] == n && e["algorithm"] == algorithm)
    };
    let chunking: Vec<_> = isolab_algorithms::extractors::registry()
        .into_iter()
        .filter(|e| e.chunking() != isolab_algorithms::Chunking::Unsupported)
        .map(|e| e.name().to_owned())
        .collect();
    assert!(chunking.len() >= 8, "{chunking:?}");
    for algorithm in &chunking {
        for field in ["sphere", "torus", "asteroid", "gyroid"] {
            for n in [256, 512] {
                assert!(compared(field, n, algorithm), "no comparison of {algorithm} on {field} at {n}³");
            }
        }
        assert!(compared("spot", 256, algorithm), "no comparison of {algorithm} on spot at 256³");
    }
    for e in equality {
        for key in ["same_vertices", "same_triangles", "same_normals"] {
            assert_eq!(e[key], serde_json::Value::Bool(true), "{key}: {e}");
        }
    }
    for field in ["sphere", "torus"] {
        let row = data["rows"]
            .as_array()
            .unwrap()
            .iter()
            .find(|r| r["field"] == field && r["mode"] == "sparse" && r["n"] == 1024)
            .unwrap_or_else(|| panic!("no sparse {field} at 1024"));
        let ratio = row["dense_points"].as_f64().unwrap() / row["evaluations"].as_f64().unwrap();
        assert!(ratio >= 30.0, "{field} at 1024³: {ratio:.1}x fewer evaluations");
    }
}

#[test]
fn every_committed_figure_is_linked_from_the_report() {
    // The assembler prunes what no page links (`figures::prune`); a figure left over means the
    // committed report was not reassembled after a run.
    let names: Vec<&str> = all().iter().map(|e| e.name()).collect();
    let stale = crate::figures::prune::unlinked(&report_dir(), &names);
    assert!(stale.is_empty(), "{} figures no page links; rerun `--bin report -- --assemble-only`: {stale:?}", stale.len());
}
