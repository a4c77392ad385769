//! Runs the `svoboda_timing` experiment (the deformable-terrain paper's Table 1) and reassembles `report/REPORT.md`.
fn main() -> std::process::ExitCode {
    isolab_experiments::experiment::run_and_assemble("svoboda_timing")
}
