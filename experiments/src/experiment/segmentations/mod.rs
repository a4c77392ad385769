//! `segmentations`: label maps to one surface per label, as a segmentation user meets it, in one
//! Python process: `isolab.mesh_labels` (multi-label surface nets, smoothed and not, and
//! multi-label marching tetrahedra) beside VTK's `vtkSurfaceNets3D` (Frisken 2022, smoothed and
//! not), zmesh (marching cubes of every label in one pass, the kernel igneous distributes) and
//! scikit-image's marching cubes run once per label, on the same numpy label maps.
//!
//! The timing and the checks run in `bench.py` beside this file (its header is the protocol), in
//! the pinned reference environment with the package installed from `python/` by this experiment,
//! so they time the code of this commit. Inputs: a tissue map of the MNI152 T1 template (a
//! three-class Otsu split) and Voronoi maps of random seeds at 128³ and 256³. The pictures are
//! ours, rendered here from the tissue map `bench.py` saves.

mod data;
mod page;

use super::context::{Context, Experiment, ExperimentError};
use crate::figures::render;
use crate::peers::python;
pub use data::{Data, Row};
use isolab_algorithms::{Options, TriMesh};
use isolab_pipeline::labels::{self, LabelConfig, LabelVolume};
use page::spread;
use page::{against_target, find, inputs};
use std::collections::BTreeMap;
use std::path::Path;

mod reading;

/// The experiment.
pub struct Segmentations;

const NAME: &str = "segmentations";

/// The Voronoi maps: samples per side and labels (the background among them).
const VORONOI: [(usize, usize); 2] = [(128, 64), (256, 64)];

/// The thread counts timed (the second: this machine's two cores).
const THREADS: [usize; 2] = [1, 2];

/// The implementation every ratio is taken against.
const OURS: &str = "isolab surface-nets";

/// The peers the speed target names, with the implementation of ours compared to each
/// like with like (both smoothed, or both unsmoothed marching).
const TARGETS: [(&str, &str); 2] = [("VTK SurfaceNets3D", OURS), ("zmesh", "isolab surface-nets unsmoothed")];

/// The background label.
const BACKGROUND: u32 = 0;

/// The speed-up the issue asks for.
const TARGET: f64 = 1.5;

impl Experiment for Segmentations {
    fn name(&self) -> &'static str {
        NAME
    }

    fn question(&self) -> &'static str {
        "How fast, closed and gap-free are isolab's label-map surfaces against VTK's SurfaceNets3D, zmesh and per-label marching cubes?"
    }

    fn peers(&self) -> &'static [&'static str] {
        &["VTK", "scikit-image", "zmesh", "nibabel", "nilearn", "numpy"]
    }

    fn run(&self, ctx: &Context) -> Result<(), ExperimentError> {
        let root = crate::provenance::root();
        let python = python::reference_python(&root).map_err(ExperimentError::Python)?;
        python::install_package(&python, &root).map_err(ExperimentError::Python)?;
        let repeats = ctx.repeats.max(1);
        // The tissue map bench.py makes, kept for the pictures (under target/: not committed).
        let maps = root.join("target").join(NAME);
        std::fs::create_dir_all(&maps).map_err(|source| isolab_io::IoError::Write { path: maps.clone(), source })?;
        let tissue = maps.join("mni-tissue.nii.gz");
        let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("src/experiment/segmentations/bench.py");
        let voronoi: Vec<String> = ctx.sizes(&VORONOI).iter().map(|(n, l)| format!("{n}:{l}")).collect();
        let args: Vec<String> = [
            "--repeats",
            &repeats.to_string(),
            "--threads",
            &THREADS.map(|t| t.to_string()).join(","),
            "--voronoi",
            &voronoi.join(","),
            "--save-tissue",
            tissue.to_str().unwrap_or_default(),
            "--wide",
            &crate::report::WIDE.to_string(),
            "--max-blocks",
            &crate::report::MAX_ROUNDS.to_string(),
        ]
        .iter()
        .map(|s| (*s).to_owned())
        .collect();
        let mut bench: serde_json::Value = python::run_script(&python, &script, &args, &[]).map_err(ExperimentError::Python)?;
        bench["repeats"] = repeats.into();
        let mut data: Data =
            serde_json::from_value(bench).map_err(|e| ExperimentError::Python(format!("bench.py wrote: {e}")))?;
        if tissue.exists() {
            data.drawn = pictures(ctx, &tissue)?;
            data.pictures = true;
        }
        ctx.write_data(NAME, &data)
    }

    fn section(&self, ctx: &Context) -> Result<String, ExperimentError> {
        page::section(ctx)
    }
}

/// The tissue map meshed by each of our label extractors, cut open at the middle of its first
/// axis so the inner labels show, coloured by label, side by side; returns their names.
fn pictures(ctx: &Context, tissue: &Path) -> Result<Vec<String>, ExperimentError> {
    let dir = ctx.figure_dir(NAME)?;
    let volume = LabelVolume::read(tissue, None)?;
    let mut images = Vec::new();
    for algorithm in isolab_algorithms::labels::names() {
        let config = LabelConfig { algorithm: algorithm.into(), options: Options::new(), ..Default::default() };
        let outcome = labels::mesh_labels(&volume, &config)?;
        let (mesh, colours) = cut_open(&outcome.meshes);
        let opts = render::RenderOptions { width: 420, height: 420, ..Default::default() };
        images.push(render::render_coloured(&mesh, &colours, &opts));
    }
    let refs: Vec<&render::Image> = images.iter().collect();
    render::save_png(&dir.join("tissue.png"), &render::grid(&refs, refs.len())).map_err(ExperimentError::Io)?;
    Ok(isolab_algorithms::labels::names().into_iter().map(String::from).collect())
}

/// Every label's triangles whose centroid lies on the low side of the meshes' middle x, in one
/// mesh, each vertex coloured by its label.
fn cut_open(meshes: &BTreeMap<u32, TriMesh>) -> (TriMesh, Vec<[u8; 3]>) {
    let (lo, hi) = meshes
        .values()
        .flat_map(|m| m.positions.iter())
        .fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), p| (lo.min(p.x), hi.max(p.x)));
    let middle = 0.5 * (lo + hi);
    let mut out = TriMesh::default();
    let mut colours = Vec::new();
    for (&label, mesh) in meshes {
        let base = out.positions.len() as u32;
        out.positions.extend_from_slice(&mesh.positions);
        colours.extend(std::iter::repeat_n(labels::colour(label), mesh.positions.len()));
        out.triangles.extend(
            mesh.triangles
                .iter()
                .filter(|t| t.iter().map(|&v| mesh.positions[v as usize].x).sum::<f32>() / 3.0 < middle)
                .map(|t| t.map(|v| v + base)),
        );
    }
    (out, colours)
}

/// The median of a row's calls.
pub fn median_ms(row: &Row) -> f64 {
    spread(row).median
}
