//! Runs the `sharp_features` experiment and reassembles `report/REPORT.md`.
fn main() -> std::process::ExitCode {
    isolab_experiments::experiment::run_and_assemble("sharp_features")
}
