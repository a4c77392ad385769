//! The main job: runs every experiment (a progress bar each) and assembles `report/REPORT.md`.
//!
//! `cargo run --release -p isolab-experiments --bin report [-- --only NAME] [--assemble-only] [--repeats N]`

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
    /// Report directory.
    #[arg(long, default_value_os_t = experiment::default_report_dir())]
    out: PathBuf,
    /// Extractions per configuration for the timing medians.
    #[arg(long, default_value_t = 5)]
    repeats: usize,
    /// Run only this experiment (repeatable).
    #[arg(long)]
    only: Vec<String>,
    /// Rebuild REPORT.md from the existing data without running anything.
    #[arg(long)]
    assemble_only: bool,
}

fn main() -> ExitCode {
    let args = Args::parse();
    let writes_the_readme = args.out == experiment::default_report_dir();
    let ctx = Context::new(args.out, args.repeats);
    let names: Vec<&'static str> = experiment::all().iter().map(|e| e.name()).collect();
    if let Some(bad) = args.only.iter().find(|o| !names.contains(&o.as_str())) {
        eprintln!("error: unknown experiment '{bad}'; valid experiments: {}", names.join(", "));
        return ExitCode::from(2);
    }
    let start = Instant::now();
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
