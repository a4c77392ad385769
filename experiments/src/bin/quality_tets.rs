//! Runs the `quality_tets` experiment (tetrahedra with proven quality against the peers) and reassembles `report/REPORT.md`.
fn main() -> std::process::ExitCode {
    isolab_experiments::experiment::run_and_assemble("quality_tets")
}
