//! Runs the `stuart_tables` experiment (Stuart et al. 2013, Tables 1-2, Figs. 7-10) and reassembles `report/REPORT.md`.
fn main() -> std::process::ExitCode {
    isolab_experiments::experiment::run_and_assemble("stuart_tables")
}
