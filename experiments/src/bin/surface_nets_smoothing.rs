//! Runs the `surface_nets_smoothing` experiment and reassembles `report/REPORT.md`.
fn main() -> std::process::ExitCode {
    isolab_experiments::experiment::run_and_assemble("surface_nets_smoothing")
}
