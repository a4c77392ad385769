//! Runs the `python_users` experiment (marching cubes from Python against scikit-image, PyMCubes, zmesh and VTK on the same numpy arrays) and reassembles `report/REPORT.md`.
fn main() -> std::process::ExitCode {
    isolab_experiments::experiment::run_and_assemble("python_users")
}
