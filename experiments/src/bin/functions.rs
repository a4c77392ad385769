//! Runs the `functions` experiment (fields meshed from evaluations near their surface, against
//! dense sampling) and reassembles `report/REPORT.md`.

isolab_experiments::install_meter!();

fn main() -> std::process::ExitCode {
    isolab_experiments::experiment::run_and_assemble("functions")
}
