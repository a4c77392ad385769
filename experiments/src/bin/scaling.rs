//! Runs the `scaling` experiment (time and peak memory against grid size, one and two threads)
//! and reassembles `report/REPORT.md`.

isolab_experiments::install_meter!();

fn main() -> std::process::ExitCode {
    isolab_experiments::experiment::run_and_assemble("scaling")
}
