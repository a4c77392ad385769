//! Runs the `large_world` experiment (a world of billions of samples, streamed) and reassembles `report/REPORT.md`.
fn main() -> std::process::ExitCode {
    isolab_experiments::experiment::run_and_assemble("large_world")
}
