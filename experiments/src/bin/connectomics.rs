//! Runs the `connectomics` experiment (a billion-voxel label volume to neuroglancer's multi-resolution meshes on Dask, against igneous) and reassembles `report/REPORT.md`.
fn main() -> std::process::ExitCode {
    isolab_experiments::experiment::run_and_assemble("connectomics")
}
