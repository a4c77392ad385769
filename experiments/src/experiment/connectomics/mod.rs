//! `connectomics`: a label volume of a billion voxels and thousands of labels to a neuroglancer
//! multi-resolution mesh source, by `isolab.dask.mesh_labels(..., format="neuroglancer")` on a
//! `distributed.LocalCluster` of one and two workers whose memory limits are below the volume,
//! against igneous (forge, then its sharded multi-resolution merge) on the same volume,
//! resolution and worker count; neuroglancer's own viewer draws the result. The runs are
//! `bench.py` beside this file (its header is the protocol), in the reference environment with
//! the package of this commit installed.

mod data;
mod page;

use super::context::{Context, Experiment, ExperimentError};
use crate::peers::python;
use data::Data;
use std::path::Path;

/// The experiment.
pub struct Connectomics;

const NAME: &str = "connectomics";

/// Samples per side of the volume (uint32: 4 GiB).
const N: usize = 1024;

/// Voronoi cells (labels).
const CELLS: usize = 2000;

/// Cells per level-0 box (isolab's block).
const CHUNK: usize = 128;

/// Each Dask worker's memory limit, MiB.
const MEMORY_LIMIT_MIB: usize = 1024;

/// igneous's task shape (voxels per side of a forge task).
const IGNEOUS_SHAPE: usize = 256;

/// Segments drawn in the neuroglancer picture.
const SHOWN: usize = 40;

/// The bar: isolab end to end at least this many times igneous's speed.
const TARGET_SPEEDUP: f64 = 3.0;

impl Experiment for Connectomics {
    fn name(&self) -> &'static str {
        NAME
    }

    fn question(&self) -> &'static str {
        "Can a billion-voxel label volume become neuroglancer's multi-resolution meshes on Dask, no label gathered, and how does it compare with igneous?"
    }

    fn peers(&self) -> &'static [&'static str] {
        &["igneous", "cloud-volume", "DracoPy", "neuroglancer", "zmesh", "dask", "distributed", "zarr", "numpy", "meshopt"]
    }

    fn run(&self, ctx: &Context) -> Result<(), ExperimentError> {
        let root = crate::provenance::root();
        let py = python::reference_python(&root).map_err(ExperimentError::Python)?;
        python::install_package(&py, &root).map_err(ExperimentError::Python)?;
        let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("src/experiment/connectomics/bench.py");
        let work = root.join("target").join("connectomics");
        let shots = ctx.figure_dir(NAME)?;
        let args: Vec<String> = [
            // A quick run: a 256³ volume of 100 cells, in 64³ blocks and 128³ igneous tasks.
            ("--n", ctx.pick(N, 256).to_string()),
            ("--cells", ctx.pick(CELLS, 100).to_string()),
            ("--chunk", ctx.pick(CHUNK, 64).to_string()),
            ("--memory-limit-mib", MEMORY_LIMIT_MIB.to_string()),
            ("--igneous-shape", ctx.pick(IGNEOUS_SHAPE, 128).to_string()),
            ("--screenshot-segments", SHOWN.to_string()),
            ("--work", work.to_string_lossy().into_owned()),
            ("--shots", shots.to_string_lossy().into_owned()),
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
    use super::data::{Draco, Encoder, Run, VolumeInfo};
    use super::page::{page_body, reading};
    use super::*;
    use std::collections::BTreeMap;

    fn run(tool: &str, workers: usize, seconds: f64) -> Run {
        Run {
            tool: tool.into(),
            workers,
            seconds,
            bytes: 1 << 20,
            peak_rss_mib: vec![300.0, 420.0],
            restarted: false,
            segments: Some(9),
            lods: Some(2),
            fragments: vec![20, 9],
            triangles: vec![1000, 250],
            level_bytes: vec![100, 30],
            phases: BTreeMap::new(),
            busy_seconds: Vec::new(),
            task_seconds: BTreeMap::new(),
        }
    }

    fn data(ours: f64, theirs: f64) -> Data {
        Data {
            versions: BTreeMap::new(),
            notes: Vec::new(),
            volume: VolumeInfo {
                n: 8,
                cells: 9,
                voxels: 512,
                gib: 0.5,
                dtype: "uint32".into(),
                resolution_nm: 8.0,
                made_seconds: 1.0,
            },
            chunk: 4,
            memory_limit_mib: 256,
            igneous_shape: 8,
            cores: 2,
            runs: vec![run("isolab", 2, ours), run("igneous", 2, theirs)],
            screenshot: false,
            draco: Some(Draco {
                side: 8,
                fragments: 3,
                triangles: 1000,
                encoders: vec![
                    Encoder { encoder: "ours".into(), seconds: vec![1.0], median: 1.0, bytes: 1 << 20 },
                    Encoder { encoder: "theirs".into(), seconds: vec![3.0], median: 3.0, bytes: 1 << 21 },
                ],
            }),
        }
    }

    #[test]
    fn the_reading_follows_the_numbers() {
        let fast = reading(&data(10.0, 40.0));
        assert!(fast.contains("4.00× igneous's speed, at or past"), "{fast}");
        assert!(fast.contains("peak was 420 MiB, against a limit of 256 MiB"), "{fast}");
        assert!(fast.contains("1000 triangles at the finest and 250 at the coarsest, over 9 segments"), "{fast}");
        let slow = reading(&data(10.0, 20.0));
        assert!(slow.contains("2.00× igneous's speed, short of"), "{slow}");
        assert!(slow.contains("ours encoded at 3.00× the speed of theirs (1.0 MiB against 2.0 MiB)"), "{slow}");
        assert!(page_body(&data(10.0, 20.0)).contains("| igneous | 2 | 20.0 |"));
        assert!(!slow.contains("computed tasks"), "no task stream, no split: {slow}");
    }

    #[test]
    fn the_time_split_follows_the_task_stream() {
        let mut d = data(10.0, 20.0);
        let ours = &mut d.runs[0];
        ours.busy_seconds = vec![6.0, 9.0];
        ours.phases = [("boxes", 8.0), ("files", 1.5), ("info_and_cleanup", 0.25)].map(|(k, v)| (k.to_string(), v)).into();
        ours.task_seconds = [("_ng_level0_task", 12.0), ("_ng_shard_task", 1.4)].map(|(k, v)| (k.to_string(), v)).into();
        let s = reading(&d);
        assert!(
            s.contains(
                "computed tasks for 75% of 2 × its 10 s (idle 5 worker-seconds); its boxes took 8.0 s of wall time, \
                        its segments' files 1.5 s and its info and cleanup 0.2 s."
            ),
            "{s}"
        );
        let page = page_body(&d);
        assert!(page.contains("| 2 | 10.0 | 8.0 | 1.5 | 0.2 | 75% | 12.0 | 1.4 |"), "{page}");
    }
}
