//! Runs the `mesh_fields` experiment (mesh signed distance fields against libigl)
//! and reassembles `report/REPORT.md`.

isolab_experiments::install_meter!();

fn main() -> std::process::ExitCode {
    isolab_experiments::experiment::run_and_assemble("mesh_fields")
}
