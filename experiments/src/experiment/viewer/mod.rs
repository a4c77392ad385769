//! `viewer`: every extractor's mesh of every pictured input at the lowest resolution of
//! `compare_algorithms`, written as small quantized binary glTF (`report/meshes/*.glb`,
//! `io::gltf::write_glb_quantized`) for the report's interactive page `report/index.html`, where a
//! reader turns two of them side by side, with each mesh's measures (closed, manifold,
//! self-intersections, aspect ratio) and the triangles that intersect. The inputs go in by their
//! meshes' total size, smallest first, until [`MESH_BUDGET_BYTES`]; an input that does not fit is
//! meshed again at three quarters of its resolution until it does (down to [`MIN_RESOLUTION`]),
//! and the page names any left out.
//!
//! The page itself is written by the assembler ([`page`]), from `REPORT.md` and this experiment's
//! data, with the viewer's JavaScript pinned in `report/vendor/` (see `viewer/README.md`).

mod data;
mod page;

use super::context::{Context, Experiment, ExperimentError};
pub use data::{Data, Mesh};
use isolab_algorithms::{extractors, fields, Extraction, Samples};
use isolab_io::{write_atomic, IoError};
use isolab_pipeline::{lattice_for, load_field, RunConfig};

/// The experiment.
pub struct Viewer;

const NAME: &str = "viewer";

/// The most bytes of meshes the report commits for the page.
pub const MESH_BUDGET_BYTES: usize = 10 << 20;

/// The coarsest resolution an input is meshed at to fit the budget before it is left out.
pub const MIN_RESOLUTION: usize = 12;

/// The inputs: (name, field spec, resolution), as `compare_algorithms` pictures them (its lowest
/// resolution).
fn inputs() -> Vec<(String, String, usize)> {
    super::context::compared_inputs().into_iter().map(|(name, spec, levels)| (name, spec, levels[0])).collect()
}

/// Every extractor's mesh of input `name` (`spec`) at `resolution`, measured and encoded.
fn meshes_of(name: &str, spec: &str, resolution: usize) -> Result<Vec<(Mesh, Vec<u8>)>, ExperimentError> {
    let field = load_field(spec, fields::DEFAULT_SEED)?;
    let lattice = lattice_for(field.as_ref(), &RunConfig::new("", spec, resolution))?;
    let samples = Samples::sample(field.clone(), lattice, 0.0)?;
    let mut meshes = Vec::new();
    for extractor in extractors::registry() {
        let mut out = Extraction::default();
        extractor.extract(&samples, &mut out)?;
        let mut bytes = Vec::new();
        isolab_io::gltf::write_glb_quantized(&mut bytes, &out.surface, "isolab report viewer")
            .map_err(|source| IoError::Write { path: "glb in memory".into(), source })?;
        let topology = isolab_metrics::topology::topology(&out.surface);
        let quality = isolab_metrics::quality::triangle_quality(&out.surface);
        let crossings = isolab_metrics::intersections::self_intersections(&out.surface);
        let mut intersecting: Vec<u32> = crossings.pairs.iter().flatten().copied().collect();
        intersecting.sort_unstable();
        intersecting.dedup();
        meshes.push((
            Mesh {
                algorithm: extractor.name().into(),
                input: name.to_owned(),
                resolution,
                triangles: out.surface.triangles.len(),
                path: format!("meshes/{}-{name}.glb", extractor.name()),
                bytes: bytes.len(),
                closed: topology.closed,
                manifold: topology.edge_manifold && topology.vertex_manifold,
                intersecting_pairs: crossings.count,
                intersecting_triangles: intersecting,
                aspect: [quality.aspect_ratio.mean, quality.aspect_ratio.max],
            },
            bytes,
        ));
    }
    Ok(meshes)
}

/// Picks whole inputs, smallest total first, while the running total stays within `budget`:
/// returns the indices kept (in input order) and those left out.
pub fn within_budget(totals: &[usize], budget: usize) -> (Vec<usize>, Vec<usize>) {
    let mut order: Vec<usize> = (0..totals.len()).collect();
    order.sort_by_key(|&k| totals[k]);
    let (mut kept, mut left, mut sum) = (Vec::new(), Vec::new(), 0usize);
    for k in order {
        if sum + totals[k] <= budget {
            sum += totals[k];
            kept.push(k);
        } else {
            left.push(k);
        }
    }
    kept.sort_unstable();
    left.sort_unstable();
    (kept, left)
}

impl Experiment for Viewer {
    fn name(&self) -> &'static str {
        NAME
    }

    fn question(&self) -> &'static str {
        "What do the extractors' meshes look like from every side?"
    }

    fn run(&self, ctx: &Context) -> Result<(), ExperimentError> {
        let extractors = extractors::registry();
        let inputs = inputs();
        let bar = ctx.bar(NAME, (inputs.len() * extractors.len()) as u64);
        // Every input's meshes in memory first, so the budget can choose whole inputs.
        let mut encoded: Vec<Vec<(Mesh, Vec<u8>)>> = Vec::new();
        for (name, spec, resolution) in &inputs {
            bar.set_message(name.clone());
            encoded.push(meshes_of(name, spec, *resolution)?);
            bar.inc(extractors.len() as u64);
        }
        bar.finish_with_message("done");
        let totals: Vec<usize> = encoded.iter().map(|m| m.iter().map(|(mesh, _)| mesh.bytes).sum()).collect();
        let (kept, left) = within_budget(&totals, MESH_BUDGET_BYTES);
        let mut room = MESH_BUDGET_BYTES - kept.iter().map(|&k| totals[k]).sum::<usize>();
        let mut chosen: Vec<usize> = kept;
        let mut still_left = Vec::new();
        // The inputs left out, again at coarser resolutions, smallest first, while they fit.
        for k in left {
            let (name, spec, mut resolution) = inputs[k].clone();
            loop {
                resolution = resolution * 3 / 4;
                if resolution < MIN_RESOLUTION {
                    still_left.push((name.clone(), totals[k]));
                    break;
                }
                let meshes = meshes_of(&name, &spec, resolution)?;
                let total: usize = meshes.iter().map(|(m, _)| m.bytes).sum();
                if total <= room {
                    room -= total;
                    encoded[k] = meshes;
                    chosen.push(k);
                    break;
                }
            }
        }
        chosen.sort_unstable();
        let dir = ctx.report_dir.join("meshes");
        if dir.exists() {
            std::fs::remove_dir_all(&dir).map_err(|source| IoError::Write { path: dir.clone(), source })?;
        }
        std::fs::create_dir_all(&dir).map_err(|source| IoError::Write { path: dir.clone(), source })?;
        let mut data = Data::default();
        for k in chosen {
            for (mesh, bytes) in &encoded[k] {
                write_atomic(&ctx.report_dir.join(&mesh.path), |w| std::io::Write::write_all(w, bytes))?;
                data.meshes.push(mesh.clone());
            }
        }
        data.left_out = still_left;
        ctx.write_data(NAME, &data)
    }

    fn section(&self, ctx: &Context) -> Result<String, ExperimentError> {
        page::section(ctx)
    }
}

/// The viewer's own script, written beside the page.
pub const SCRIPT: &str = include_str!("viewer.js");

/// `report/index.html`: the viewer above the front page (`front_md`, rendered to HTML), with the
/// meshes of this experiment's data (none when it has not run: the page says so).
pub fn page(ctx: &Context, front_md: &str) -> String {
    let data: Data = ctx.read_data(NAME).unwrap_or_default();
    let meshes = serde_json::to_string(&data.meshes).unwrap_or_else(|_| "[]".into()).replace("</", "<\\/");
    let body = crate::html::markdown_to_html(front_md);
    TEMPLATE.replacen("%MESHES%", &meshes, 1).replacen("%BODY%", &body, 1)
}

/// The page around the viewer and the front page: `%MESHES%` and `%BODY%` are filled in.
const TEMPLATE: &str = include_str!("viewer.html");

#[cfg(test)]
mod tests {
    use super::page::reading;
    use super::*;

    #[test]
    fn the_page_renders_the_front_page_and_escapes_the_mesh_list() {
        let dir = tempfile::tempdir().unwrap();
        let ctx = Context::new(dir.path().to_path_buf(), 1);
        let html = page(&ctx, "# Title\n\n| a | b |\n|---|---|\n| 1 | 2 |\n");
        assert!(html.contains("<h1>Title</h1>") && html.contains("<table>"), "{html}");
        assert!(html.contains("window.ISOLAB_MESHES = [];"));
        ctx.write_data(
            NAME,
            &Data {
                meshes: vec![Mesh {
                    algorithm: "mc".into(),
                    input: "</script><b>".into(),
                    resolution: 2,
                    triangles: 1,
                    path: "meshes/x.glb".into(),
                    bytes: 3,
                    ..Mesh::default()
                }],
                left_out: vec![],
            },
        )
        .unwrap();
        let html = page(&ctx, "");
        assert!(!html.contains("</script><b>"), "a mesh name must not close the script");
    }

    #[test]
    fn the_reading_follows_the_data() {
        let mesh = |input: &str, algorithm: &str, triangles: usize| Mesh {
            algorithm: algorithm.into(),
            input: input.into(),
            resolution: 32,
            triangles,
            bytes: 1,
            closed: triangles > 10,
            intersecting_pairs: usize::from(triangles == 12),
            ..Mesh::default()
        };
        let mut data = Data::default();
        assert_eq!(reading(&data), "");
        data.meshes = vec![mesh("sphere", "mc", 10), mesh("sphere", "sn", 12), mesh("torus", "mc", 30)];
        data.left_out = vec![("gyroid".into(), 4)];
        let r = reading(&data);
        assert!(
            r.contains("3 meshes: 2 inputs (sphere, torus) by up to 2 extractors. The largest is mc of torus (30 triangles)."),
            "{r}"
        );
        assert!(r.contains("Closed: 2 of them; manifold: 0; with self-intersections: 1."), "{r}");
        assert!(r.contains("Meshed coarser to fit the budget: none. Inputs left out by the budget: gyroid."), "{r}");
    }

    #[test]
    fn the_budget_keeps_the_smallest_inputs_whole() {
        let (kept, left) = within_budget(&[5, 40, 10, 30], 50);
        assert_eq!(kept, [0, 2, 3]);
        assert_eq!(left, [1]);
        assert_eq!(within_budget(&[], 10), (vec![], vec![]));
    }
}
