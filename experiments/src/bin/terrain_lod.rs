//! Runs the `terrain_lod` experiment (levels of detail without cracks) and reassembles `report/REPORT.md`.
fn main() -> std::process::ExitCode {
    isolab_experiments::experiment::run_and_assemble("terrain_lod")
}
