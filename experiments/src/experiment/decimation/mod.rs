//! `decimation`: our edge collapses against an established decimator at the same triangle counts,
//! on plain marching tetrahedra (BCC, the RMT paper's resolutions): the paper's sweep (0.5 h, its
//! own count), our topology-safe collapse, and three established decimators driven to that count
//! and to a quarter of the input: pymeshlab's quadric edge collapse (topology preserving, optimal
//! placement), CGAL's `Surface_mesh_simplification::edge_collapse` (its default Lindstrom-Turk
//! cost and placement) and OpenMesh's `DecimaterT` (quadric priority with the normal-flipping
//! guard). The two C++ ones are small programs in `tests/reference/decimators/` that
//! `tests/reference/run.sh setup` builds against Debian's libcgal-dev and libopenmesh-dev; each
//! times its own collapse in process. Measured with our metrics (validated against pymeshlab,
//! CGAL and VTK): aspect ratio, minimum angle and zero-area triangles, two-sided Hausdorff
//! distance to the unsimplified surface (vertices and face samples), manifoldness, self-intersecting
//! triangle pairs, median time. Our safe collapse runs twice: refusing collapses that would make
//! two triangles meet (its default) and with `intersections=allow`, so the test's cost and what it
//! prevents are both in the table.
//! A decimator that is not installed is listed as not run, with the reason.

mod data;
mod page;

use super::context::{load_object, Context, Experiment, ExperimentError};
use crate::peers::python::{PythonPeer, PythonServer};
use crate::peers::{Job, Peer, Protocol};
use crate::report::median;
pub(crate) use data::Data;
use data::NativeAnswer;
pub use data::Row;
use isolab_algorithms::extract::PostProcess;
use isolab_algorithms::extractors::MarchingTetrahedra;
use isolab_algorithms::post::EdgeCollapse;
use isolab_algorithms::{Extraction, Extractor, Grid, Lattice, Samples, TriMesh};
use isolab_metrics::{hausdorff, triangle_quality, Sampling};
use std::path::Path;
use std::process::Command;
use std::time::Duration;

/// The experiment.
pub struct Decimation;

const NAME: &str = "decimation";

const OBJECTS: [(&str, [usize; 3]); 3] = [("sphere", [51, 51, 51]), ("asteroid", [51, 51, 51]), ("stanford-bunny", [76, 41, 57])];

fn row(object: &str, input: &TriMesh, target: usize, decimator: &str, mesh: &TriMesh, times: Vec<Duration>, h: f32) -> Row {
    let q = triangle_quality(mesh);
    Row {
        object: object.into(),
        input_triangles: input.triangles.len(),
        target,
        decimator: decimator.into(),
        triangles: mesh.triangles.len(),
        aspect_mean: q.aspect_ratio.mean,
        min_angle_deg: q.min_angle_deg,
        degenerate: q.degenerate_triangles,
        hausdorff_h: hausdorff(mesh, input, Sampling::VerticesAndFaces).max / f64::from(h),
        manifold: isolab_metrics::topology(mesh).is_watertight_manifold(),
        self_intersections: isolab_metrics::self_intersections(mesh).count,
        ms: median(times).as_secs_f64() * 1e3,
    }
}

/// The C++ decimators: (label in the table, program in `tests/reference/.bin`).
const NATIVE: [(&str, &str); 2] =
    [("CGAL edge_collapse (Lindstrom-Turk)", "cgal_edge_collapse"), ("OpenMesh Decimater (quadric)", "openmesh_decimater")];

/// Runs a native decimator on the OBJ `input` down to `target` faces into `out` (`repeats` timed
/// collapses, each of a fresh copy): its times and the mesh it wrote.
fn run_native(
    program: &Path,
    input: &Path,
    target: usize,
    out: &Path,
    repeats: usize,
) -> Result<(Vec<Duration>, TriMesh), String> {
    let output = Command::new(program)
        .arg(input)
        .arg(target.to_string())
        .arg(out)
        .arg(repeats.to_string())
        .output()
        .map_err(|e| format!("cannot start {}: {e}", program.display()))?;
    if !output.status.success() {
        return Err(format!("{} failed: {}", program.display(), String::from_utf8_lossy(&output.stderr).trim()));
    }
    let stdout = String::from_utf8_lossy(&output.stdout);
    let line = stdout
        .lines()
        .rev()
        .find(|l| l.trim_start().starts_with('{'))
        .ok_or_else(|| format!("{} printed no result", program.display()))?;
    let answer: NativeAnswer = serde_json::from_str(line).map_err(|e| format!("{} printed {line:?}: {e}", program.display()))?;
    let mesh = isolab_io::read_mesh(out).map_err(|e| e.to_string())?;
    Ok((answer.ms.iter().map(|&ms| Duration::from_secs_f64(ms / 1e3)).collect(), mesh))
}

/// The native decimators that are built, building them (and installing their libraries) with
/// `tests/reference/run.sh setup` when one is missing; the others with the reason.
fn native_decimators(root: &Path) -> (Vec<(&'static str, std::path::PathBuf)>, Vec<String>) {
    let bin = root.join("tests/reference/.bin");
    if NATIVE.iter().any(|(_, p)| !bin.join(p).exists()) {
        // Its notes go to stderr; what is still missing afterwards is reported below.
        let _ = Command::new("bash").arg(root.join("tests/reference/run.sh")).arg("setup").status();
    }
    let mut found = Vec::new();
    let mut skipped = Vec::new();
    for (label, program) in NATIVE {
        let path = bin.join(program);
        if path.exists() {
            found.push((label, path));
        } else {
            skipped.push(format!(
                "{label}: tests/reference/.bin/{program} is not built (tests/reference/run.sh setup builds it; it needs g++ and Debian's libcgal-dev and libopenmesh-dev)"
            ));
        }
    }
    (found, skipped)
}

impl Experiment for Decimation {
    fn name(&self) -> &'static str {
        NAME
    }

    fn question(&self) -> &'static str {
        "How does our edge collapse compare with established decimators at equal triangle counts?"
    }

    fn peers(&self) -> &'static [&'static str] {
        &["CGAL (C++)", "OpenMesh", "pymeshlab"]
    }

    fn run(&self, ctx: &Context) -> Result<(), ExperimentError> {
        let repeats = ctx.repeats.min(3);
        let root = crate::provenance::root();
        let (native, mut skipped) = native_decimators(&root);
        let mut pymeshlab = match PythonServer::start(&root) {
            Ok((server, _)) => Some(PythonPeer::new(&server, "pymeshlab-quadric")),
            Err(e) => {
                skipped.push(format!("pymeshlab: {e}"));
                None
            }
        };
        let tmp = std::env::temp_dir().join(format!("isolab-decimation-{}", std::process::id()));
        std::fs::create_dir_all(&tmp).map_err(|source| isolab_io::IoError::Write { path: tmp.clone(), source })?;
        let bar = ctx.bar(NAME, OBJECTS.len() as u64);
        let mut rows = Vec::new();
        for (name, dims) in OBJECTS {
            let field = load_object(name)?;
            let grid = Grid::with_dims(&field.domain(), dims)?;
            let samples = Samples::sample(field, Lattice::Bcc(grid), 0.0)?;
            let mut mt = Extraction::default();
            MarchingTetrahedra::default().extract(&samples, &mut mt)?;
            let input = mt.surface.clone();
            let input_path = tmp.join(format!("{name}.ply"));
            isolab_io::write_mesh(&input_path, &input)?;
            let input_obj = tmp.join(format!("{name}.obj"));
            isolab_io::write_mesh(&input_obj, &input)?;
            // The paper's sweep sets the first target.
            let mut sweep = Vec::new();
            let mut out = mt.clone();
            for _ in 0..repeats {
                out = mt.clone();
                EdgeCollapse::paper(isolab_algorithms::post::edge_collapse::DEFAULT_THRESHOLD).apply(&samples, &mut out)?;
                sweep.push(out.stats.times.post);
            }
            let first = out.surface.triangles.len();
            let label = format!("edge-collapse (paper sweep, {} h)", isolab_algorithms::post::edge_collapse::DEFAULT_THRESHOLD);
            rows.push(row(name, &input, first, &label, &out.surface, sweep, grid.spacing));
            for target in [first, input.triangles.len() / 4] {
                for (refuse_intersections, label) in
                    [(true, "edge-collapse-safe (shortest first)"), (false, "edge-collapse-safe, intersections=allow")]
                {
                    let mut times = Vec::new();
                    let mut safe = mt.clone();
                    for _ in 0..repeats {
                        safe = mt.clone();
                        let post =
                            EdgeCollapse { target, threshold: f32::INFINITY, refuse_intersections, ..EdgeCollapse::safe(0.5) };
                        post.apply(&samples, &mut safe)?;
                        times.push(safe.stats.times.post);
                    }
                    rows.push(row(name, &input, target, label, &safe.surface, times, grid.spacing));
                }
                if let Some(py) = pymeshlab.as_mut() {
                    let out_path = tmp.join(format!("{name}-{target}.obj"));
                    let mut times = Vec::new();
                    let mut failed = None;
                    for _ in 0..repeats {
                        match py.run(&Job::Decimate { mesh: &input_path, target, out: &out_path }, Protocol::OneShot) {
                            Ok(run) => times.push(run.time),
                            Err(e) => failed = Some(e),
                        }
                    }
                    match (failed, isolab_io::read_mesh(&out_path)) {
                        (None, Ok(mesh)) => {
                            rows.push(row(name, &input, target, "pymeshlab quadric edge collapse", &mesh, times, grid.spacing))
                        }
                        (Some(e), _) => skipped.push(format!("pymeshlab on {name}: {e}")),
                        (None, Err(e)) => skipped.push(format!("pymeshlab on {name}: {e}")),
                    }
                }
                for (label, program) in &native {
                    let out_path = tmp.join(format!("{name}-{target}-native.obj"));
                    match run_native(program, &input_obj, target, &out_path, repeats) {
                        Ok((times, mesh)) => rows.push(row(name, &input, target, label, &mesh, times, grid.spacing)),
                        Err(e) => skipped.push(format!("{label} on {name}: {e}")),
                    }
                }
            }
            bar.inc(1);
        }
        drop(pymeshlab);
        let _ = std::fs::remove_dir_all(&tmp);
        bar.finish();
        ctx.write_data(NAME, &Data { repeats, rows, skipped })
    }

    fn section(&self, ctx: &Context) -> Result<String, ExperimentError> {
        page::section(ctx)
    }
}

/// A decimator's mean aspect ratio on an input this many times the median of the others' is
/// called out as unexplained.
const OUTLIER_FACTOR: f64 = 5.0;

#[cfg(test)]
mod tests {
    use super::page::reading;
    use super::*;

    fn row(object: &str, decimator: &str, hausdorff_h: f64, aspect_mean: f64, manifold: bool, self_intersections: usize) -> Row {
        Row {
            object: object.into(),
            input_triangles: 100,
            target: 25,
            decimator: decimator.into(),
            triangles: 25,
            aspect_mean,
            min_angle_deg: 1.0,
            degenerate: 0,
            hausdorff_h,
            manifold,
            self_intersections,
            ms: 1.0,
        }
    }

    #[test]
    fn the_reading_follows_the_rows() {
        let rows = vec![
            row("sphere", "a", 0.1, 1.2, true, 0),
            row("sphere", "b", 0.2, 1.1, true, 2),
            row("sphere", "c", 0.3, 30.0, true, 0),
            row("bunny", "a", 0.4, 1.3, true, 0),
            row("bunny", "b", 0.1, 1.4, false, 0),
            row("bunny", "c", 0.5, 1.5, true, 0),
        ];
        let r = reading(&rows);
        assert!(r.contains("free of self-intersections on every input: a, c."), "{r}");
        assert!(r.contains("b (1 of 2 not closed manifold, 2 self-intersecting pairs in all)"), "{r}");
        assert!(r.contains("least Hausdorff distance), cases won of 2: a 1, b 1."), "{r}");
        assert!(r.contains("least mean aspect ratio), cases won of 2: a 1, b 1."), "{r}");
        assert!(r.contains("On sphere at 25 triangles, c's mean aspect ratio is 30.0"), "{r}");
    }
}
