//! Runs the `viewer` experiment (the meshes of the report's interactive page) and reassembles the report.
fn main() -> std::process::ExitCode {
    isolab_experiments::experiment::run_and_assemble("viewer")
}
