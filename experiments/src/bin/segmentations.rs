//! Runs the `segmentations` experiment (label maps to surfaces against VTK's SurfaceNets3D, zmesh and scikit-image per label, from Python) and reassembles `report/REPORT.md`.
fn main() -> std::process::ExitCode {
    isolab_experiments::experiment::run_and_assemble("segmentations")
}
