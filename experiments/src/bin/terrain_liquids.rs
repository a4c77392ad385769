//! Runs the `terrain_liquids` experiment (liquids beside solids) and reassembles `report/REPORT.md`.
fn main() -> std::process::ExitCode {
    isolab_experiments::experiment::run_and_assemble("terrain_liquids")
}
