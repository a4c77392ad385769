//! Runs the `terrain_edit` experiment (200 brush edits on a chunked terrain) and reassembles `report/REPORT.md`.
fn main() -> std::process::ExitCode {
    isolab_experiments::experiment::run_and_assemble("terrain_edit")
}
