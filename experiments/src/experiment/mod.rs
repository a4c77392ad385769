//! The report's experiments. Each one writes `report/data/<name>.json` (its rows and the
//! parameters that produced them) and `report/figures/<name>/*`, and renders its page
//! `report/<name>.md` from that data alone, so the report can be reassembled without rerunning.
//! The front page `report/REPORT.md` links the pages and answers "which extractor for my case?"
//! from their data ([`choosing`]).
//!
//! Every experiment is a folder here of the same three files: `mod.rs`, its run (a type
//! implementing [`Experiment`]); `data.rs`, its data file's types; `page.rs`, its page rendered
//! from the data alone (`tests/tests/house.rs` checks the layout). Adding one: the folder, one
//! line in [`all`], and a two-line binary in `src/bin/` calling [`run_and_assemble`].

pub mod choosing;
pub mod compare_algorithms;
pub mod connectomics;
pub mod context;
pub mod costen_table;
pub mod decimation;
pub mod distributed;
pub mod functions;
pub mod large_world;
pub mod mesh_fields;
pub mod peers;
pub mod python_users;
pub mod quality_tets;
pub mod real_volumes;
pub mod scaling;
pub mod segmentations;
pub mod sharp_features;
pub mod sphere_convergence;
pub mod stuart_tables;
pub mod surface_nets_smoothing;
pub mod svoboda_timing;
pub mod terrain_edit;
pub mod terrain_liquids;
pub mod terrain_lod;
pub mod viewer;

pub use context::{
    compared_inputs, corner_distances_h, default_options, default_report_dir, load_object, measure, model_path, ms,
    options_as_run, quick_report_dir, settings_of, Context, Experiment, ExperimentError, Measured, FIELD_LEVELS, MODELS,
    MODEL_LEVELS,
};

use isolab_io::write_atomic;
use std::path::PathBuf;

/// Data files no experiment writes, made by a script of their own and committed (the Table 2
/// peers of `stuart_tables` and the peers of `quality_tets`, each run by its `peers.py`, and
/// `quality_tets`' label maps, run by `tests/reference/mesh3/labeled_vs_cleaving.py`): a quick
/// run copies them from `report/data/`.
pub const MADE_OUTSIDE: [&str; 3] = ["stuart_tables_peers", "quality_tets_peers", "quality_tets_labels"];

/// Copies the [`MADE_OUTSIDE`] data files from the report into `ctx`'s folder (a quick run's),
/// where they are missing.
pub fn copy_made_outside(ctx: &Context) -> Result<(), ExperimentError> {
    let report = Context::new(default_report_dir(), 1);
    for name in MADE_OUTSIDE {
        let (from, to) = (report.data_path(name), ctx.data_path(name));
        if from.exists() && !to.exists() {
            if let Some(dir) = to.parent() {
                std::fs::create_dir_all(dir).map_err(|source| isolab_io::IoError::Write { path: dir.into(), source })?;
            }
            std::fs::copy(&from, &to).map_err(|source| isolab_io::IoError::Write { path: to.clone(), source })?;
        }
    }
    Ok(())
}

/// Every experiment, in report order.
pub fn all() -> Vec<Box<dyn Experiment>> {
    vec![
        Box::new(compare_algorithms::CompareAlgorithms),
        Box::new(sphere_convergence::SphereConvergence),
        Box::new(surface_nets_smoothing::SurfaceNetsSmoothing),
        Box::new(sharp_features::SharpFeatures),
        Box::new(costen_table::CostenTable),
        Box::new(peers::Peers),
        Box::new(python_users::PythonUsers),
        Box::new(distributed::Distributed),
        Box::new(segmentations::Segmentations),
        Box::new(connectomics::Connectomics),
        Box::new(mesh_fields::MeshFields),
        Box::new(real_volumes::RealVolumes),
        Box::new(scaling::Scaling),
        Box::new(decimation::Decimation),
        Box::new(svoboda_timing::SvobodaTiming),
        Box::new(stuart_tables::StuartTables),
        Box::new(quality_tets::QualityTets),
        Box::new(terrain_edit::TerrainEdit),
        Box::new(terrain_lod::TerrainLod),
        Box::new(terrain_liquids::TerrainLiquids),
        Box::new(large_world::LargeWorld),
        Box::new(functions::Functions),
        Box::new(viewer::Viewer),
    ]
}

/// Writes the report from every experiment's data (a missing data file is noted, not fatal): one
/// page per experiment, `<name>.md`, and the front page `REPORT.md` that answers the reader's
/// question ("which extractor for my case?") and links to them.
pub fn assemble(ctx: &Context) -> Result<PathBuf, ExperimentError> {
    let mut pages = Vec::new();
    let mut rendered = Vec::new();
    for e in all() {
        let section = match e.section(ctx) {
            Ok(s) => {
                rendered.push(e.name());
                s
            }
            Err(err) => format!("## {}\n\n_Not generated yet: {err}_\n", e.name()),
        };
        let title = page_title(&section).unwrap_or(e.name()).to_owned();
        let provenance = crate::provenance::recorded(&ctx.data_path(e.name()));
        let mut body =
            under_title(&promote_headings(&findings_first(&section)), &crate::provenance::line(e.name(), provenance.as_ref()));
        // The works it follows, last (the page opens with its findings).
        if let Some(sources) = crate::bibliography::sources_of(e.name()) {
            body = format!("{}\n\n{sources}\n", body.trim_end());
        }
        let page = format!("[isolab report](REPORT.md) › {title}\n\n{}", body.trim_end()) + "\n";
        let path = ctx.report_dir.join(format!("{}.md", e.name()));
        write_atomic(&path, |w| std::io::Write::write_all(w, page.as_bytes()))?;
        let html = crate::html::html_page(&title, &page);
        write_atomic(&ctx.report_dir.join(format!("{}.html", e.name())), |w| std::io::Write::write_all(w, html.as_bytes()))?;
        pages.push(Page { name: e.name(), title, question: e.question(), provenance });
    }
    let md = front_page(ctx, &pages);
    let path = ctx.report_dir.join("REPORT.md");
    write_atomic(&path, |w| std::io::Write::write_all(w, md.as_bytes()))?;
    // The front page as a page of its own, for a reader who opens the HTML pages without the
    // viewer (each page's breadcrumb links it).
    let front_html = crate::html::html_page("isolab report", &md);
    write_atomic(&ctx.report_dir.join("REPORT.html"), |w| std::io::Write::write_all(w, front_html.as_bytes()))?;
    let html = viewer::page(ctx, &md);
    write_atomic(&ctx.report_dir.join("index.html"), |w| std::io::Write::write_all(w, html.as_bytes()))?;
    write_atomic(&ctx.report_dir.join("viewer.js"), |w| std::io::Write::write_all(w, viewer::SCRIPT.as_bytes()))?;
    let bibliography = crate::bibliography::page();
    write_atomic(&ctx.report_dir.join("bibliography.md"), |w| std::io::Write::write_all(w, bibliography.as_bytes()))?;
    let bibliography_html = crate::html::html_page("Bibliography", &bibliography);
    write_atomic(&ctx.report_dir.join("bibliography.html"), |w| std::io::Write::write_all(w, bibliography_html.as_bytes()))?;
    // Last, once every page and script that may link a figure is written.
    crate::figures::prune::prune(&ctx.report_dir, &rendered);
    Ok(path)
}

/// The front page: what was compared, the use-case recommendations, the at-a-glance table and
/// the list of experiment pages.
fn front_page(ctx: &Context, pages: &[Page]) -> String {
    let extractors: Vec<String> = isolab_algorithms::extractors::registry().iter().map(|e| format!("`{}`", e.name())).collect();
    let fields: Vec<String> = isolab_algorithms::fields::registry().iter().map(|f| format!("`{}`", f.name)).collect();
    let models: Vec<String> = context::MODELS.iter().map(|m| format!("`{m}`")).collect();
    let mut md = String::from("# isolab report\n\n");
    if pages.iter().any(|p| p.provenance.as_ref().is_some_and(|v| v.quick)) {
        md.push_str(
            "**A quick run** (`report --quick`): every experiment at its smallest sizes, to see a change across the \
             report; its numbers are not the report's, and its text may name the full run's sizes.\n\n",
        );
    }
    md.push_str(&format!(
        "Which isosurface extractor for which job? This report compares isolab's {} extractors ({}) on {} built-in \
         fields ({}), {} shipped models ({}) and a real MRI, against peer libraries run on the same inputs, and \
         repeats the experiments of the papers they follow. Generated by `cargo run --release -p isolab-experiments \
         --bin report`; do not edit by hand. Every number comes from the data files in `data/` or from a labelled paper constant in the \
         experiment's source. Times are wall-clock medians on a shared machine: compare ratios within one run.\n\n",
        extractors.len(),
        extractors.join(", "),
        fields.len(),
        fields.join(", "),
        models.len(),
        models.join(", "),
    ));
    md.push_str(&choosing::section(ctx));
    match compare_algorithms::glance(ctx) {
        Ok(table) => {
            md.push_str("## Every extractor at a glance\n\n");
            match compare_algorithms::front_figure(ctx) {
                Ok(figure) => md.push_str(&figure),
                Err(e) => md.push_str(&format!("_No figure: {e}_\n\n")),
            }
            md.push_str(&table);
            md.push_str("\nPer input, per resolution, with pictures: [compare_algorithms](compare_algorithms.md).\n\n");
        }
        Err(e) => md.push_str(&format!("## Every extractor at a glance\n\n_Not generated yet: {e}_\n\n")),
    }
    md.push_str(
        "[`index.html`](index.html) shows this page beside a viewer that turns any two extractors' meshes of an input \
         in 3D ([viewer](viewer.md) says how to open it).\n\n",
    );
    md.push_str("## The experiments\n\n");
    md.push_str(&main_job_time(ctx, &pages.iter().map(|p| p.name).collect::<Vec<_>>()));
    md.push_str(
        "Each page's data were made at the commit listed (`+changes`: with uncommitted changes outside `report/` and `README.md`, which runs write); \
         \"changed since\" means the experiment's own source files differ from those that made its data, so the page may \
         not show what its code does now (changes to the engine it measures are not tracked here). Each page states \
         its machine and the command that regenerates it under its title. The papers and posts the extractors follow \
         and the pages reproduce are in the [bibliography](bibliography.md).\n\n",
    );
    let root = crate::provenance::root();
    let rows: Vec<Vec<String>> = pages
        .iter()
        .map(|p| {
            let made = p.provenance.as_ref().map_or("not recorded".to_owned(), |v| {
                format!("`{}`, {}", v.short_commit(), v.date_utc.split('T').next().unwrap_or(&v.date_utc))
            });
            vec![format!("[{}]({}.md)", p.title, p.name), p.question.to_owned(), made, code_changed(&root, p)]
        })
        .collect();
    md.push_str(&crate::report::markdown_table(&["page", "the question it answers", "data made at", "its code since"], &rows));
    md
}

/// An assembled page's entry on the front page.
struct Page {
    name: &'static str,
    title: String,
    question: &'static str,
    provenance: Option<crate::provenance::Provenance>,
}

/// The front page's "its code since" cell for a page.
fn code_changed(root: &std::path::Path, page: &Page) -> String {
    match crate::provenance::code_since(root, page.name, page.provenance.as_ref()) {
        Some(true) => "**changed since**".into(),
        Some(false) => "unchanged".into(),
        None => "unknown".into(),
    }
}

/// `page` with `line` as a paragraph after its first `# ` heading (at the top when it has none).
fn under_title(page: &str, line: &str) -> String {
    let mut out = String::with_capacity(page.len() + line.len() + 2);
    let mut done = false;
    for l in page.split_inclusive('\n') {
        out.push_str(l);
        if !done && l.starts_with("# ") {
            out.push_str(&format!("\n{line}\n"));
            done = true;
        }
    }
    if done {
        out
    } else {
        format!("{line}\n\n{page}")
    }
}

/// `section` with its reading (the paragraph that opens `**Reading.**`) moved up to follow its
/// title: each page opens with its findings, the protocol after them.
fn findings_first(section: &str) -> String {
    let paragraphs: Vec<&str> = section.split("\n\n").collect();
    let Some(reading) = paragraphs.iter().position(|p| p.starts_with("**Reading.**")) else { return section.to_owned() };
    let title = paragraphs.iter().position(|p| p.starts_with("## ")).unwrap_or(0);
    if reading <= title + 1 {
        return section.to_owned();
    }
    let mut moved: Vec<&str> = Vec::with_capacity(paragraphs.len());
    moved.extend(&paragraphs[..=title]);
    moved.push(paragraphs[reading]);
    moved.extend(paragraphs[title + 1..].iter().enumerate().filter(|(k, _)| title + 1 + k != reading).map(|(_, p)| *p));
    moved.join("\n\n")
}

/// The section's title: its first `## ` heading.
fn page_title(section: &str) -> Option<&str> {
    section.lines().find_map(|l| l.strip_prefix("## ")).map(str::trim)
}

/// A section as a page of its own: every Markdown heading one level up (`##` becomes `#`).
fn promote_headings(section: &str) -> String {
    let mut out = String::with_capacity(section.len());
    for line in section.split_inclusive('\n') {
        let level = line.bytes().take_while(|&b| b == b'#').count();
        if level >= 2 && line.as_bytes().get(level) == Some(&b' ') {
            out.push_str(&line[1..]);
        } else {
            out.push_str(line);
        }
    }
    out
}

/// The data file of the experiments' last wall times.
const RUN_TIMES: &str = "run_times";

/// Records an experiment's wall time in `data/run_times.json` (seconds by experiment, the last
/// run of each, through the main job or the experiment's own binary); the front page states the
/// main job's time from it.
pub fn record_run_time(ctx: &Context, name: &str, seconds: f64) -> Result<(), ExperimentError> {
    let mut times: std::collections::BTreeMap<String, f64> = ctx.read_data(RUN_TIMES).unwrap_or_default();
    times.insert(name.to_owned(), (seconds * 10.0).round() / 10.0);
    ctx.write_data(RUN_TIMES, &times)
}

/// The front page's sentence on how long the main job takes, from the recorded run times.
fn main_job_time(ctx: &Context, names: &[&str]) -> String {
    let times: std::collections::BTreeMap<String, f64> = ctx.read_data(RUN_TIMES).unwrap_or_default();
    let recorded: Vec<f64> = names.iter().filter_map(|n| times.get(*n).copied()).collect();
    let missing: Vec<&str> = names.iter().copied().filter(|n| !times.contains_key(*n)).collect();
    let mut s = format!(
        "The main job runs every experiment below; their last recorded runs on this machine (`data/{RUN_TIMES}.json`) \
         took {:.0} minutes in all ({} of {} experiments recorded",
        recorded.iter().sum::<f64>() / 60.0,
        recorded.len(),
        names.len()
    );
    if missing.is_empty() {
        s.push_str(").\n\n");
    } else {
        s.push_str(&format!("; not recorded: {}, last run before times were recorded).\n\n", missing.join(", ")));
    }
    s
}

/// Runs one experiment, then records its wall time (`data/run_times.json`) and stamps every data
/// file it wrote with its [`Provenance`](crate::provenance::Provenance); returns the seconds.
pub fn run_one(ctx: &Context, e: &dyn Experiment) -> Result<f64, ExperimentError> {
    let started = std::time::SystemTime::now();
    let checkout = crate::provenance::Checkout::now();
    let t = std::time::Instant::now();
    ctx.take_written();
    e.run(ctx)?;
    let seconds = t.elapsed().as_secs_f64();
    let written = ctx.take_written();
    record_run_time(ctx, e.name(), seconds)?;
    let provenance = crate::provenance::Provenance {
        quick: ctx.quick,
        ..crate::provenance::Provenance::collect(e.name(), e.peers(), started, seconds, checkout)
    };
    for name in written.iter().filter(|n| n.as_str() != RUN_TIMES) {
        crate::provenance::stamp(&ctx.data_path(name), &provenance)?;
    }
    Ok(seconds)
}

/// Runs the experiment called `name` and reassembles the report (what each binary does).
pub fn run_and_assemble(name: &str) -> std::process::ExitCode {
    let ctx = Context::new(default_report_dir(), 5);
    let result = all()
        .into_iter()
        .find(|e| e.name() == name)
        .ok_or_else(|| ExperimentError::Missing(format!("no experiment called {name}")))
        .and_then(|e| run_one(&ctx, e.as_ref()).map(|_| ()))
        .and_then(|()| assemble(&ctx))
        .and_then(|path| {
            // The README's table holds each experiment's minutes from the run times just recorded.
            crate::readme::write_workspace_readme(&ctx)
                .map_err(|reason| ExperimentError::Failed { what: "writing README.md's generated parts".into(), reason })?;
            Ok(path)
        });
    match result {
        Ok(path) => {
            eprintln!("wrote {}", path.display());
            std::process::ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {e}");
            std::process::ExitCode::FAILURE
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn headings_move_up_one_level_and_nothing_else_changes() {
        let s = "## Title (`x`)\n\ntext # not a heading\n### Sub\n#### Deeper\n#hashtag\n| a |\n";
        assert_eq!(promote_headings(s), "# Title (`x`)\n\ntext # not a heading\n## Sub\n### Deeper\n#hashtag\n| a |\n");
        assert_eq!(page_title(s), Some("Title (`x`)"));
        assert_eq!(page_title("no heading"), None);
    }

    #[test]
    fn the_reading_moves_up_to_follow_the_title() {
        let s = "## T\n\nprotocol\n\nmore protocol\n\n**Reading.** it works.\n\n| table |\n";
        assert_eq!(findings_first(s), "## T\n\n**Reading.** it works.\n\nprotocol\n\nmore protocol\n\n| table |\n");
        let first = "## T\n\n**Reading.** first.\n\nprotocol\n";
        assert_eq!(findings_first(first), first);
        assert_eq!(findings_first("## T\n\nno reading\n"), "## T\n\nno reading\n");
    }

    #[test]
    fn provenance_goes_under_the_first_title() {
        assert_eq!(under_title("# T\n\ntext\n# U\n", "_p_"), "# T\n\n_p_\n\ntext\n# U\n");
        assert_eq!(under_title("text\n", "_p_"), "_p_\n\ntext\n");
    }

    #[test]
    fn every_experiment_states_its_question_and_names_are_unique() {
        let names: Vec<&str> = all().iter().map(|e| e.name()).collect();
        assert_eq!(crate::report::first_seen(names.iter().copied()).len(), names.len());
        for e in all() {
            assert!(e.question().ends_with('?'), "{}: {}", e.name(), e.question());
        }
    }
}
