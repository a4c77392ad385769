//! Runs the `peers` experiment (ours against the peer libraries on the same grids) and reassembles `report/REPORT.md`.
fn main() -> std::process::ExitCode {
    isolab_experiments::experiment::run_and_assemble("peers")
}
