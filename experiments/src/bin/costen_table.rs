//! Runs the `costen_table` experiment (the RMT paper's Appendix B) and reassembles `report/REPORT.md`.
fn main() -> std::process::ExitCode {
    isolab_experiments::experiment::run_and_assemble("costen_table")
}
