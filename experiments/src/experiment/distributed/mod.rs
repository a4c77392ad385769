//! `distributed`: `isolab.dask.mesh_volume` on a `distributed.LocalCluster` of one and two
//! worker processes on this machine's cores, on zarr volumes larger than each worker's memory
//! limit: wall time, blocks per second, each worker's peak memory, the weld's time, the welded
//! mesh against the one-process mesh, a run with a worker killed mid-run, and zmesh on the same
//! blocks merged naively. The runs are `bench.py` beside this file (its header is the protocol),
//! in the reference environment with the package of this commit installed.

mod data;
mod page;

use super::context::{Context, Experiment, ExperimentError};
use crate::peers::python;
use data::Data;
use std::path::Path;

/// The experiment.
pub struct Distributed;

const NAME: &str = "distributed";

/// Each worker's memory limit, MiB (a worker starts at about a third of it).
const MEMORY_LIMIT_MIB: usize = 256;

/// Cells per block along each axis, in the order run (the checks run at the first).
const CHUNKS: [usize; 2] = [128, 64];

/// The synthetic volume's samples per side (float32: 1000 MiB).
const SYNTHETIC_N: usize = 640;

/// The MNI T1 tiled this many times along its axes.
const TILES: [usize; 3] = [4, 4, 2];

/// The extractor `bench.py` gives `isolab.dask.mesh_volume` (its default options).
const MESHED_BY: &str = "marching-cubes";

/// The worker counts (the second: this machine's two cores).
const WORKERS: [usize; 2] = [1, 2];

impl Experiment for Distributed {
    fn name(&self) -> &'static str {
        NAME
    }

    fn question(&self) -> &'static str {
        "Does a volume larger than a worker's memory mesh block by block on a Dask cluster, seam-exact, and how does it scale?"
    }

    fn peers(&self) -> &'static [&'static str] {
        &["dask", "distributed", "zarr", "zmesh", "numpy"]
    }

    fn run(&self, ctx: &Context) -> Result<(), ExperimentError> {
        let root = crate::provenance::root();
        let py = python::reference_python(&root).map_err(ExperimentError::Python)?;
        python::install_package(&py, &root).map_err(ExperimentError::Python)?;
        let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("src/experiment/distributed/bench.py");
        let args: Vec<String> = [
            ("--repeats", ctx.repeats.clamp(1, 3).to_string()),
            ("--memory-limit-mib", MEMORY_LIMIT_MIB.to_string()),
            ("--chunks", ctx.sizes(&CHUNKS).iter().map(|c| c.to_string()).collect::<Vec<_>>().join(",")),
            // A quick run: a 256³ synthetic volume and the MRI untiled.
            ("--synthetic-n", ctx.pick(SYNTHETIC_N, 256).to_string()),
            ("--tiles", ctx.pick(TILES, [1, 1, 1]).map(|t| t.to_string()).join(",")),
            ("--wide", crate::report::WIDE.to_string()),
            ("--max-blocks", crate::report::MAX_ROUNDS.to_string()),
        ]
        .into_iter()
        .flat_map(|(k, v)| [k.to_owned(), v])
        .collect();
        let data: Data = python::run_script(&py, &script, &args, &[]).map_err(ExperimentError::Python)?;
        ctx.write_data(NAME, &data)
    }

    fn section(&self, ctx: &Context) -> Result<String, ExperimentError> {
        page::section(ctx)
    }
}

#[cfg(test)]
mod tests {
    use super::data::{Run, Volume};
    use super::page::reading;
    use super::*;
    use std::collections::BTreeMap;

    fn run(workers: usize, seconds: f64, cpu: f64) -> Run {
        Run {
            volume: "v".into(),
            round: 0,
            block: 0,
            workers,
            chunk: 128,
            worker_cpu_seconds: cpu,
            driver_cpu_seconds: 0.0,
            seconds,
            blocks: 10,
            blocks_per_second: 1.0,
            worker_peak_rss_mib: vec![100.0, 120.0],
            restarted: false,
        }
    }

    #[test]
    fn the_reading_follows_the_data() {
        let volume: Volume = serde_json::from_value(serde_json::json!({
            "volume": "v", "shape": [1, 1, 1], "dtype": "f4", "mib": 1000.0, "level": 0.0, "inside": "above",
            "chunk": 128, "weld_seconds": 1.0, "vertices": 1, "triangles": 1,
            "topology": {"closed": true, "boundary_edges": 0, "non_manifold_edges": 0, "genus": 0, "components": 1},
            "killed": {"seconds": 1.0, "fragments_before_kill": 1, "worker_replaced": true},
            "killed_equal": false, "equals_one_process": true,
            "zmesh": {"seconds": 1.0, "vertices_before_merge": 1, "coincident_vertices_merged": 0, "vertices": 1,
                      "triangles": 1, "collapsed_triangles": 0, "boundary_edges": 12, "non_manifold_edges": 3, "closed": false}
        }))
        .unwrap();
        let mut data = Data {
            versions: BTreeMap::new(),
            notes: Vec::new(),
            memory_limit_mib: 256,
            chunks: vec![128],
            store_chunk: 64,
            repeats: 1,
            cores: 2,
            runs: Vec::new(),
            volumes: Vec::new(),
        };
        assert_eq!(reading(&data), "");
        data.volumes.push(volume);
        data.runs = vec![run(1, 8.0, 8.0), run(2, 5.0, 9.0)];
        let r = reading(&data);
        assert!(
            r.contains(
                "On the largest volume (v), 2 workers against 1: 1.60× (1.60–1.60× round by round) with 128³ blocks (where one \
                 worker alone keeps 1.00 cores"
            ),
            "{r}"
        );
        assert!(
            r.contains("equals the one-process mesh on 1 of 1 volumes, stays the same with a worker killed mid-run on 0 of 1"),
            "{r}"
        );
        assert!(r.contains("largest worker peak is 120 MiB against the 256 MiB limit"), "{r}");
        assert!(r.contains("v 12 boundary and 3 non-manifold edges"), "{r}");
        // Rounds paired: both ends of the range from one round each; the last block's spread.
        let at =
            |round: usize, block: usize, workers: usize, seconds: f64| Run { round, block, ..run(workers, seconds, seconds) };
        data.runs =
            vec![at(0, 0, 1, 8.0), at(0, 0, 2, 4.0), at(1, 0, 1, 9.0), at(1, 0, 2, 6.0), at(2, 1, 1, 30.0), at(2, 1, 2, 10.0)];
        assert!(reading(&data).contains("(1.50–3.00× round by round)"), "{}", reading(&data));
        let one: Vec<&Run> = data.runs.iter().filter(|r| r.workers == 1).collect();
        assert!(!super::page::still_wide(&one), "one run in the last block");
        data.runs.push(at(3, 1, 1, 10.0));
        let one: Vec<&Run> = data.runs.iter().filter(|r| r.workers == 1).collect();
        assert!(super::page::still_wide(&one), "30 and 10 in the last block");
    }
}
