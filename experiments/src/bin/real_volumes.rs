//! Runs the `real_volumes` experiment and reassembles `report/REPORT.md`.
fn main() -> std::process::ExitCode {
    isolab_experiments::experiment::run_and_assemble("real_volumes")
}
