//! The main job: runs every experiment (a progress bar each) and assembles `report/REPORT.md`.
//!
//! `cargo run --release -p isolab-experiments --bin report [-- --only NAME] [--assemble-only] [--repeats N] [--quick]`
//!
//! `--quick` runs every experiment at its smallest sizes, one extraction a configuration, into
//! `target/report-quick/` (never `report/`, and never committed): a contributor's view of a
//! change across the whole report in minutes.

use clap::Parser;
use isolab_experiments::experiment::{self, Context};
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

// Counts heap bytes for the `scaling` experiment's peak-memory column.
isolab_experiments::install_meter!();

#[derive(Parser)]
#[command(about = "Regenerate the isolab report: every experiment, then REPORT.md")]
struct Args {
    /// Report directory (default `report/`; `target/report-quick/` with `--quick`).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Extractions per configuration for the timing medians (default 5; 1 with `--quick`).
    #[arg(long)]
    repeats: Option<usize>,
    /// Every experiment at its smallest sizes, into a folder of its own (not `report/`).
    #[arg(long)]
    quick: bool,
    /// Run only this experiment (repeatable).
    #[arg(long)]
    only: Vec<String>,
    /// Rebuild REPORT.md from the existing data without running anything.
    #[arg(long)]
    assemble_only: bool,
}

fn main() -> ExitCode {
    let args = Args::parse();
    let out =
        args.out.unwrap_or_else(|| if args.quick { experiment::quick_report_dir() } else { experiment::default_report_dir() });
    let is_the_report = same_dir(&out, &experiment::default_report_dir());
    if args.quick && is_the_report {
        eprintln!("error: --out {}: a quick run never writes the report's folder; give another --out", out.display());
        return ExitCode::from(2);
    }
    let writes_the_readme = is_the_report;
    let ctx =
        if args.quick { Context::quick(out, args.repeats.unwrap_or(1)) } else { Context::new(out, args.repeats.unwrap_or(5)) };
    let names: Vec<&'static str> = experiment::all().iter().map(|e| e.name()).collect();
    if let Some(bad) = args.only.iter().find(|o| !names.contains(&o.as_str())) {
        eprintln!("error: unknown experiment '{bad}'; valid experiments: {}", names.join(", "));
        return ExitCode::from(2);
    }
    let start = Instant::now();
    if args.quick {
        if let Err(e) = experiment::copy_made_outside(&ctx) {
            eprintln!("error: {e}");
            return ExitCode::FAILURE;
        }
    }
    if !args.assemble_only {
        for e in experiment::all() {
            if !args.only.is_empty() && !args.only.iter().any(|o| o == e.name()) {
                continue;
            }
            match experiment::run_one(&ctx, e.as_ref()) {
                Ok(seconds) => eprintln!("{} done in {seconds:.1} s", e.name()),
                Err(err) => {
                    eprintln!("error: {}: {err}", e.name());
                    return ExitCode::FAILURE;
                }
            }
        }
    }
    match experiment::assemble(&ctx) {
        Ok(path) => {
            eprintln!("wrote {} in {:.1} s", path.display(), start.elapsed().as_secs_f64());
            if writes_the_readme {
                match isolab_experiments::readme::write_workspace_readme(&ctx) {
                    Ok(true) => eprintln!("wrote the generated parts of README.md"),
                    Ok(false) => {}
                    Err(e) => {
                        eprintln!("error: {e}");
                        return ExitCode::FAILURE;
                    }
                }
            }
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

/// Whether `a` and `b` name one folder (compared as absolute paths, `..` resolved where they exist).
fn same_dir(a: &std::path::Path, b: &std::path::Path) -> bool {
    let canonical = |p: &std::path::Path| {
        std::fs::canonicalize(p).unwrap_or_else(|_| std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf()))
    };
    canonical(a) == canonical(b)
}
