//! Runs the `distributed` experiment (isolab.dask on a LocalCluster of one and two workers, zarr volumes larger than a worker's memory) and reassembles `report/REPORT.md`.
fn main() -> std::process::ExitCode {
    isolab_experiments::experiment::run_and_assemble("distributed")
}
