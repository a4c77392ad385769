//! `python_users`: marching cubes as a researcher with a numpy array meets it, in one Python
//! process: `isolab.marching_cubes` (the Python package, both methods) beside scikit-image's
//! `marching_cubes` (Lorensen, Lewiner), PyMCubes, zmesh, VTK's `vtkFlyingEdges3D` (without and
//! with normals, and through pyvista's `contour`), libigl, warp-lang on the CPU, meshlib and
//! marching-cubes-numpy, on the same arrays, one-shot, alternating, on one and two threads, with
//! every conversion between the user's array and the returned arrays inside the timed call; each
//! call's peak memory above the input, in a process of its own; and the floor (one read of the
//! array, one write of our output).
//!
//! The timing runs in `bench.py` beside this file (its header is the protocol), in the pinned
//! reference environment (`tests/reference/.venv`) with the package installed from `python/` by
//! this experiment, so it times the code of this commit. Inputs: a gyroid at 64³ to 512³
//! (float32, C order), the 512³ gyroid as uint8, and the MNI152 T1 template as nibabel hands it
//! over (float64, Fortran order) and in its stored type (uint8). The targets and peaks are worded
//! in `targets.rs`.

mod data;
mod page;

use super::context::{Context, Experiment, ExperimentError};
use crate::figures::plot::{self, Scale, Series, Style, XyPlot};
use crate::peers::python;
use data::Data;
use page::inputs;
use page::spread;
use page::{find, label};
use std::path::Path;

mod targets;

/// The experiment.
pub struct PythonUsers;

const NAME: &str = "python_users";

const SIZES: [usize; 4] = [64, 128, 256, 512];

/// From this size on, `LARGE_REPEATS` rounds (scikit-image takes seconds a call there).
const LARGE: usize = 512;

const LARGE_REPEATS: usize = 3;

/// The thread counts timed (the second: this machine's two cores).
const THREADS: [usize; 2] = [1, 2];

/// The implementation every ratio is taken against.
const OURS: &str = "isolab lorensen";

/// The second run's label: the same script in a process whose glibc malloc asks the kernel for
/// transparent huge pages, on the sizes where first-touch page faults weigh.
const HUGE_PAGES: &str = "huge pages";

const HUGE_PAGES_TUNABLE: &str = "glibc.malloc.hugetlb=1";

const HUGE_PAGE_SIZES: [usize; 2] = [256, 512];

/// The implementations the huge pages run times (the ones the targets compare).
const HUGE_PAGE_IMPLEMENTATIONS: [&str; 4] = [OURS, "isolab lewiner", targets::VTK, targets::SKIMAGE];

/// The side of the uint8 gyroid (the memory target's input).
const UINT8_SIZE: usize = 512;

/// Rows written before there was a second run.
fn default_environment() -> String {
    "default".into()
}

impl Experiment for PythonUsers {
    fn name(&self) -> &'static str {
        NAME
    }

    fn question(&self) -> &'static str {
        "How fast is isolab's marching cubes from Python, and how much memory does it take, against scikit-image, VTK and the other marching cubes a Python user can install, on the same numpy arrays?"
    }

    fn peers(&self) -> &'static [&'static str] {
        &[
            "VTK",
            "scikit-image",
            "PyMCubes",
            "libigl",
            "marching-cubes-numpy",
            "meshlib",
            "warp",
            "zmesh",
            "nibabel",
            "nilearn",
            "numpy",
        ]
    }

    fn run(&self, ctx: &Context) -> Result<(), ExperimentError> {
        let root = crate::provenance::root();
        let python = python::reference_python(&root).map_err(ExperimentError::Python)?;
        python::install_package(&python, &root).map_err(ExperimentError::Python)?;
        let repeats = ctx.repeats.max(1);
        let sizes: Vec<String> = ctx.sizes(&SIZES).iter().map(usize::to_string).collect();
        let uint8 = ctx.pick(UINT8_SIZE, SIZES[0]).to_string();
        // A quick run leaves out the peak memory (a fresh process per implementation and input)
        // and the huge pages run.
        let sizes = sizes.join(",");
        let mut first: Vec<&str> = vec!["--sizes", &sizes, "--mni", "nilearn", "--uint8", &uint8];
        if !ctx.quick {
            first.push("--peak");
        }
        let mut data = bench(&python, &[&first], repeats, None)?;
        if !ctx.quick {
            let large: Vec<String> = HUGE_PAGE_SIZES.iter().map(usize::to_string).collect();
            let only = HUGE_PAGE_IMPLEMENTATIONS.join(",");
            let huge = bench(
                &python,
                &[&["--sizes", &large.join(","), "--environment", HUGE_PAGES, "--only", &only]],
                repeats,
                Some(HUGE_PAGES_TUNABLE),
            )?;
            data.rows.extend(huge.rows);
            data.notes.extend(huge.notes.into_iter().map(|n| format!("{HUGE_PAGES}: {n}")));
        }
        ctx.write_data(NAME, &data)?;
        figures(ctx, &data)
    }

    fn section(&self, ctx: &Context) -> Result<String, ExperimentError> {
        page::section(ctx)
    }
}

/// Runs `bench.py` with `args` (and `GLIBC_TUNABLES=tunable` when given) and reads what it wrote.
fn bench(python: &Path, args: &[&[&str]], repeats: usize, tunable: Option<&str>) -> Result<Data, ExperimentError> {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("src/experiment/python_users/bench.py");
    let mut all: Vec<String> = vec![
        "--repeats".into(),
        repeats.to_string(),
        "--large-repeats".into(),
        LARGE_REPEATS.to_string(),
        "--large-size".into(),
        LARGE.to_string(),
        "--threads".into(),
        THREADS.map(|t| t.to_string()).join(","),
        "--wide".into(),
        crate::report::WIDE.to_string(),
        "--max-blocks".into(),
        crate::report::MAX_ROUNDS.to_string(),
    ];
    all.extend(args.iter().flat_map(|a| a.iter().map(|s| (*s).to_owned())));
    let env: Vec<(&str, &str)> = tunable.map(|t| ("GLIBC_TUNABLES", t)).into_iter().collect();
    let mut bench: serde_json::Value = python::run_script(python, &script, &all, &env).map_err(ExperimentError::Python)?;
    bench["repeats"] = repeats.into();
    bench["large_repeats"] = LARGE_REPEATS.into();
    serde_json::from_value(bench).map_err(|e| ExperimentError::Python(format!("bench.py wrote: {e}")))
}

/// The peers timed on one thread beside ours.
const PEERS: [&str; 10] = [
    "skimage lorensen",
    "skimage lewiner",
    "PyMCubes",
    "zmesh",
    "VTK flying edges",
    "VTK flying edges + normals",
    "pyvista contour",
    "libigl",
    "warp-lang (CPU)",
    "marching-cubes-numpy",
];

fn figures(ctx: &Context, data: &Data) -> Result<(), ExperimentError> {
    let dir = ctx.figure_dir(NAME)?;
    let implementations =
        crate::report::first_seen(data.rows.iter().filter(|r| r.threads == 1).map(|r| r.implementation.clone()));
    let series = implementations
        .iter()
        .map(|implementation| {
            let rows: Vec<_> = data
                .rows
                .iter()
                .filter(|r| {
                    r.environment == "default" && r.input == "gyroid" && r.threads == 1 && &r.implementation == implementation
                })
                .collect();
            Series {
                label: implementation.clone(),
                color: crate::figures::color_of(implementation),
                points: rows.iter().map(|r| ((r.n as f64).powi(3), spread(r).median)).collect(),
                ranges: rows.iter().map(|r| (spread(r).min, spread(r).max)).collect(),
            }
        })
        .collect();
    let chart = XyPlot {
        title: "Gyroid, one thread, numpy array in and out".into(),
        x_label: "samples".into(),
        y_label: "ms (median; bars: fastest to slowest run)".into(),
        x_scale: Scale::Log,
        y_scale: Scale::Log,
        style: Style::Lines,
        series,
    };
    plot::xy(&dir.join("time-gyroid"), &chart).map_err(ExperimentError::Figure)
}

#[cfg(test)]
mod tests {
    use super::data::Row;
    use super::page::reading;
    use super::*;
    use std::collections::BTreeMap;

    pub(super) fn data(rows: Vec<Row>) -> Data {
        Data {
            repeats: 1,
            large_repeats: 1,
            versions: BTreeMap::new(),
            notes: Vec::new(),
            inputs: Vec::new(),
            rows,
            peaks: Vec::new(),
            floors: Vec::new(),
        }
    }

    pub(super) fn row(implementation: &str, input: &str, n: usize, threads: usize, ms: f64) -> Row {
        Row {
            implementation: implementation.into(),
            input: input.into(),
            n,
            threads,
            environment: default_environment(),
            ms: vec![ms],
            vertices: 0,
            triangles: 0,
            converts: String::new(),
            returns: String::new(),
            blocks: None,
            wide: None,
        }
    }

    #[test]
    fn the_reading_follows_the_rows() {
        let mut data = data(Vec::new());
        assert_eq!(reading(&data), "");
        data.rows = vec![
            row(OURS, "gyroid", 256, 1, 100.0),
            row(OURS, "gyroid", 256, 2, 50.0),
            row("zmesh", "gyroid", 256, 1, 300.0),
            row("VTK flying edges", "gyroid", 256, 1, 80.0),
            row(OURS, "mni", 0, 1, 40.0),
            row(OURS, "mni", 0, 2, 40.0),
            row("zmesh", "mni", 0, 1, 60.0),
            row("VTK flying edges", "mni", 0, 1, 50.0),
        ];
        let r = reading(&data);
        assert!(r.contains("zmesh 3.00×, VTK flying edges 0.80×"), "{r}");
        assert!(
            r.contains("faster than ours on every one: none; slower on every one: zmesh; either, by input: VTK flying edges."),
            "{r}"
        );
        assert!(r.contains("2 threads: 1.50× the one-thread speed, median over the inputs (1.00–2.00)"), "{r}");
    }
}
