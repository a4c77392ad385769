//! `terrain_edit`: the deformable-terrain use case of every paper in `../shared/papers/` (the
//! deformable-terrain paper, the RMT paper's section 1.1, the blog posts' chunk sections): a
//! 256 x 128 x 256-cell `terrain` in 32³ chunks, then a scripted, seeded sequence of 200 brush
//! edits (spheres adding or carving material on the surface, with falloff). Each edit's time is the
//! sample edit plus re-meshing the chunks it dirtied; medians and 99th percentiles against the
//! 16.7 ms frame budget, a plot of every edit, before/after pictures and a GIF of the sequence.
//! Only chunk-capable extractors run (see `algorithms::chunks`); the others are listed as not run.

use super::context::{Context, Experiment, ExperimentError};
use crate::figures::plot::{self, Scale, Series, Style, XyPlot};
use crate::report::markdown_table;
use isolab_algorithms::chunks::lod::open_edges_away_from_bounds;
use isolab_algorithms::chunks::{Brush, ChunkedVolume};
use isolab_algorithms::{extractors, fields, materials, Chunking, Extraction, Grid, Lattice, Samples};
use isolab_render::{self as render, RenderOptions, Shading};
use serde::{Deserialize, Serialize};
use std::time::Instant;

/// The experiment.
pub struct TerrainEdit;

const NAME: &str = "terrain_edit";
/// Samples per axis: 256 x 128 x 256 cells.
const DIMS: [usize; 3] = [257, 129, 257];
pub(crate) const CHUNK: usize = 32;
const EDITS: usize = 200;
const SEED: u64 = 2026;
/// A game's frame rate, Hz.
const FRAME_HZ: f64 = 60.0;
/// One frame at [`FRAME_HZ`], ms.
pub(crate) const FRAME_MS: f64 = 1000.0 / FRAME_HZ;
/// A brush's radius, cells: from the first to the second, uniformly.
const BRUSH_RADIUS: (f32, f32) = (3.0, 10.0);
/// A brush's falloff, cells: from the first to the second, uniformly.
const BRUSH_FALLOFF: (f32, f32) = (0.0, 3.0);
/// Every this many edits, a GIF frame.
const GIF_EVERY: usize = 10;
/// Chunk sizes of the one-thread runs (cells per side).
const CHUNK_SIZES: [usize; 3] = [16, 32, 64];
/// The per-chunk budget a game gives meshing on one worker thread, ms (p99 of one chunk's
/// re-mesh on one thread at [`CHUNK`]³ cells); the front page's terrain pick keeps within it.
pub(crate) const CHUNK_BUDGET_MS: f64 = 2.0;

/// One extractor's edit sequence at one chunk size, each dirty chunk re-meshed on its own on one
/// thread (what a game's meshing worker does).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ChunkRun {
    /// Cells per chunk side.
    pub chunk: usize,
    /// Chunks re-meshed over the sequence.
    pub chunks: usize,
    /// One chunk's re-mesh on one thread, ms: median, 99th percentile, slowest.
    pub chunk_ms: [f64; 3],
    /// Boundary edges of the welded mesh off the world's boundary after the sequence (cracks).
    pub open_seam_edges: usize,
}

/// One extractor's edit sequence.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Run {
    /// Extractor.
    pub algorithm: String,
    /// Meshing every chunk once, ms.
    pub initial_ms: f64,
    /// Each edit's time (sample edit + re-meshing), ms.
    pub edit_ms: Vec<f64>,
    /// Chunks each edit re-meshed.
    pub dirtied: Vec<usize>,
    /// Median edit, ms.
    pub median_ms: f64,
    /// 99th percentile edit, ms.
    pub p99_ms: f64,
    /// Slowest edit, ms.
    pub max_ms: f64,
    /// Triangles before and after the sequence.
    pub triangles: [usize; 2],
    /// Welded mesh closed and manifold after the sequence.
    pub manifold_after: bool,
    /// The most boundary edges off the world's boundary (cracks) in the welded mesh after any
    /// edit of the sequence (checked after every edit).
    #[serde(default)]
    pub open_seam_edges_max: usize,
    /// Mean aspect ratio and smallest angle (degrees) of the welded, edited mesh.
    #[serde(default)]
    pub quality_after: [f64; 2],
    /// The one-thread runs, one per chunk size (16³, 32³ and 64³ cells in the report).
    #[serde(default)]
    pub chunk_runs: Vec<ChunkRun>,
    /// The extractor's settings as it ran (`Extractor::settings`: smoothing, placement, faces).
    #[serde(default)]
    pub settings: String,
}

#[derive(Serialize, Deserialize)]
pub(crate) struct Data {
    pub(crate) runs: Vec<Run>,
    pub(crate) not_run: Vec<String>,
    pub(crate) before: String,
    pub(crate) after: String,
    pub(crate) gif: String,
    pub(crate) plot: String,
}

/// Names, or "none".
fn names<'a>(v: impl Iterator<Item = &'a str>) -> String {
    crate::report::listed(&v.collect::<Vec<_>>())
}

/// The page's opening reading: who keeps every edit within a frame, the median edits, who leaves
/// no crack and stays manifold, and who keeps one chunk within the per-chunk budget.
fn reading(data: &Data) -> String {
    if data.runs.is_empty() {
        return String::new();
    }
    let within = |r: &Run| r.edit_ms.iter().filter(|&&ms| ms <= FRAME_MS).count();
    let missed: Vec<String> = data
        .runs
        .iter()
        .filter(|r| within(r) < r.edit_ms.len())
        .map(|r| format!("{} ({} of {})", r.algorithm, within(r), r.edit_ms.len()))
        .collect();
    let mut lines = vec![format!(
        "Every edit within a {FRAME_MS:.1} ms frame: {}; not every one: {}.",
        names(data.runs.iter().filter(|r| within(r) == r.edit_ms.len()).map(|r| r.algorithm.as_str())),
        crate::report::listed(&missed)
    )];
    let mut by_median: Vec<&Run> = data.runs.iter().collect();
    by_median.sort_by(|a, b| a.median_ms.total_cmp(&b.median_ms));
    lines.push(format!(
        "Median edit, ms: {}.",
        by_median.iter().map(|r| format!("{} {:.2}", r.algorithm, r.median_ms)).collect::<Vec<_>>().join(", ")
    ));
    lines.push(format!(
        "No crack after any edit and closed manifold after the sequence: {}; not: {}.",
        names(data.runs.iter().filter(|r| r.open_seam_edges_max == 0 && r.manifold_after).map(|r| r.algorithm.as_str())),
        names(data.runs.iter().filter(|r| !(r.open_seam_edges_max == 0 && r.manifold_after)).map(|r| r.algorithm.as_str()))
    ));
    let at = |r: &Run| r.chunk_runs.iter().find(|c| c.chunk == CHUNK).map(|c| c.chunk_ms[1]);
    if data.runs.iter().any(|r| at(r).is_some()) {
        lines.push(format!(
            "One {CHUNK}³ chunk on one thread with its p99 within the {CHUNK_BUDGET_MS} ms budget: {}.",
            names(data.runs.iter().filter(|r| at(r).is_some_and(|p| p <= CHUNK_BUDGET_MS)).map(|r| r.algorithm.as_str()))
        ));
    }
    format!("**Reading.** {}\n\n", lines.join(" "))
}

/// What an extractor reads to mesh one chunk, in words.
fn chunk_reads(algorithm: &str) -> String {
    match isolab_algorithms::extractors::by_name(algorithm).map(|e| e.chunking()) {
        Some(isolab_algorithms::Chunking::CellLocal) => "reads exactly its chunk's samples".into(),
        Some(isolab_algorithms::Chunking::Apron(a)) => format!("also reads an apron of {a} samples of its neighbours"),
        _ => "does not chunk".into(),
    }
}

/// The scripted edits: a sphere on the current surface of a random column, radius 3-10 cells,
/// falloff 0-3 cells, alternately carving and adding (from the seeded stream `algorithms::random`,
/// so every extractor and every run sees the same sequence).
fn script(grid: &Grid, values: &dyn Fn(usize, usize) -> Option<usize>) -> Vec<Brush> {
    let mut random = isolab_algorithms::random::Random::new(SEED);
    let mut next = move || random.unit_f32();
    let mut brushes = Vec::with_capacity(EDITS);
    while brushes.len() < EDITS {
        let (x, z) = ((next() * (DIMS[0] - 1) as f32) as usize, (next() * (DIMS[2] - 1) as f32) as usize);
        let radius = BRUSH_RADIUS.0 + (BRUSH_RADIUS.1 - BRUSH_RADIUS.0) * next();
        let falloff = BRUSH_FALLOFF.0 + (BRUSH_FALLOFF.1 - BRUSH_FALLOFF.0) * next();
        let Some(y) = values(x, z) else { continue };
        brushes.push(Brush {
            centre: grid.position(x, y, z),
            radius: radius * grid.spacing,
            falloff: falloff * grid.spacing,
            add: brushes.len() % 2 == 1,
            material: materials::CLAY,
        });
    }
    brushes
}

/// The edit sequence at `chunk` cells per chunk side, every dirty chunk re-meshed on its own on
/// one thread (a one-thread pool, so the extractor's own parallelism stays on it too).
fn one_thread_run(
    e: &dyn isolab_algorithms::Extractor,
    samples: &Samples,
    sample_materials: &[u8],
    brushes: &[Brush],
    chunk: usize,
) -> Result<ChunkRun, ExperimentError> {
    let mut world = ChunkedVolume::new(e, samples.clone(), chunk)?.with_materials(sample_materials.to_vec())?;
    world.remesh_dirty(e)?;
    let pool =
        rayon::ThreadPoolBuilder::new().num_threads(1).build().map_err(|err| ExperimentError::ThreadPool(err.to_string()))?;
    let mut times = Vec::new();
    for (k, brush) in brushes.iter().enumerate() {
        world.apply(brush).map_err(|err| ExperimentError::Failed { what: format!("edit {k}"), reason: err.to_string() })?;
        times.extend(pool.install(|| world.remesh_dirty_each(e))?.iter().map(|d| d.as_secs_f64() * 1e3));
    }
    times.sort_by(f64::total_cmp);
    let mut welded = Extraction::default();
    world.welded(&mut welded);
    Ok(ChunkRun {
        chunk,
        chunks: times.len(),
        chunk_ms: [percentile(&times, 0.5), percentile(&times, 0.99), times.last().copied().unwrap_or(f64::NAN)],
        open_seam_edges: open_edges_away_from_bounds(&welded.surface, &samples.grid().bounds(), samples.grid().spacing),
    })
}

fn percentile(sorted: &[f64], q: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    sorted[((sorted.len() - 1) as f64 * q).round() as usize]
}

impl Experiment for TerrainEdit {
    fn name(&self) -> &'static str {
        NAME
    }

    fn question(&self) -> &'static str {
        "How long does re-meshing a chunked terrain after a brush edit take, and do the seams stay closed?"
    }

    fn run(&self, ctx: &Context) -> Result<(), ExperimentError> {
        let field = fields::builtin("terrain", Default::default())?;
        let grid = Grid::with_dims(&field.domain(), DIMS)?;
        let samples = Samples::sample(field.clone(), Lattice::Cubic(grid), 0.0)?;
        let sample_materials = materials::sample(field.as_ref(), &grid);
        // The surface height of a column: the topmost sign change.
        let surface_y = |x: usize, z: usize| {
            (1..DIMS[1])
                .rev()
                .find(|&y| (samples.values()[grid.index(x, y, z)] < 0.0) != (samples.values()[grid.index(x, y - 1, z)] < 0.0))
        };
        let brushes = script(&grid, &surface_y);
        let dir = ctx.figure_dir(NAME)?;
        let surface_extractors: Vec<_> = extractors::registry().into_iter().filter(|e| !e.produces_volume()).collect();
        let bar = ctx.bar(NAME, (surface_extractors.len() * EDITS) as u64);
        let mut runs = Vec::new();
        let mut not_run = Vec::new();
        let opts = RenderOptions { width: 420, height: 300, shading: Shading::Smooth, ..Default::default() };
        let (mut before, mut after, mut gif) = (String::new(), String::new(), String::new());
        for e in &surface_extractors {
            if e.chunking() == Chunking::Unsupported {
                not_run.push(e.name().to_string());
                bar.inc(EDITS as u64);
                continue;
            }
            let mut world = ChunkedVolume::new(e.as_ref(), samples.clone(), CHUNK)?.with_materials(sample_materials.clone())?;
            let mut vertex_materials = Vec::new();
            let mut coloured = |world: &ChunkedVolume, welded: &Extraction, o: &RenderOptions| {
                world.vertex_materials(&welded.surface, &mut vertex_materials);
                let colours: Vec<[u8; 3]> = vertex_materials.iter().map(|&m| materials::colour(m)).collect();
                render::render_coloured(&welded.surface, &colours, o)
            };
            let start = Instant::now();
            world.remesh_dirty(e.as_ref())?;
            let initial_ms = start.elapsed().as_secs_f64() * 1e3;
            let mut welded = Extraction::default();
            world.welded(&mut welded);
            let first_triangles = welded.surface.triangles.len();
            let record_pictures = runs.is_empty();
            let mut frames = Vec::new();
            if record_pictures {
                let path = dir.join("before.png");
                render::save_png(&path, &coloured(&world, &welded, &RenderOptions { width: 640, height: 420, ..opts }))?;
                before = ctx.link(&path);
                frames.push(coloured(&world, &welded, &opts));
            }
            let (mut edit_ms, mut dirtied) = (Vec::with_capacity(EDITS), Vec::with_capacity(EDITS));
            let bounds = grid.bounds();
            let mut open_seam_edges_max = 0;
            for (k, brush) in brushes.iter().enumerate() {
                let start = Instant::now();
                world
                    .apply(brush)
                    .map_err(|err| ExperimentError::Failed { what: format!("edit {k}"), reason: err.to_string() })?;
                let n = world.remesh_dirty(e.as_ref())?;
                edit_ms.push(start.elapsed().as_secs_f64() * 1e3);
                dirtied.push(n);
                world.welded(&mut welded);
                open_seam_edges_max =
                    open_seam_edges_max.max(open_edges_away_from_bounds(&welded.surface, &bounds, grid.spacing));
                if record_pictures && (k + 1) % GIF_EVERY == 0 {
                    frames.push(coloured(&world, &welded, &opts));
                }
                bar.inc(1);
            }
            // `welded` holds the mesh after the last edit.
            let t = isolab_metrics::topology(&welded.surface);
            let q = isolab_metrics::triangle_quality(&welded.surface);
            let chunk_runs = CHUNK_SIZES
                .iter()
                .map(|&chunk| one_thread_run(e.as_ref(), &samples, &sample_materials, &brushes, chunk))
                .collect::<Result<Vec<_>, _>>()?;
            if record_pictures {
                let path = dir.join("after.png");
                render::save_png(&path, &coloured(&world, &welded, &RenderOptions { width: 640, height: 420, ..opts }))?;
                after = ctx.link(&path);
                let path = dir.join("edits.gif");
                render::save_gif(&path, &frames, 40)?;
                gif = ctx.link(&path);
            }
            let mut sorted = edit_ms.clone();
            sorted.sort_by(f64::total_cmp);
            runs.push(Run {
                algorithm: e.name().into(),
                initial_ms,
                median_ms: percentile(&sorted, 0.5),
                p99_ms: percentile(&sorted, 0.99),
                max_ms: sorted.last().copied().unwrap_or(f64::NAN),
                edit_ms,
                dirtied,
                triangles: [first_triangles, welded.surface.triangles.len()],
                manifold_after: t.edge_manifold && t.vertex_manifold,
                open_seam_edges_max,
                quality_after: [q.aspect_ratio.mean, q.min_angle_deg],
                chunk_runs,
                settings: e.settings(),
            });
        }
        bar.finish();
        let stem = dir.join("edit-times");
        let mut series: Vec<Series> = runs
            .iter()
            .map(|r| Series {
                label: r.algorithm.clone(),
                color: crate::figures::color_of(&r.algorithm),
                points: r.edit_ms.iter().enumerate().map(|(k, &ms)| (k as f64 + 1.0, ms)).collect(),
            })
            .collect();
        series.push(Series {
            label: format!("{FRAME_MS:.1} ms frame"),
            color: (0, 0, 0),
            points: vec![(1.0, FRAME_MS), (EDITS as f64, FRAME_MS)],
        });
        let chart = XyPlot {
            title: format!("Time of each brush edit (sample edit + re-meshing dirty {CHUNK}³ chunks)"),
            x_label: "edit".into(),
            y_label: "ms".into(),
            x_scale: Scale::Linear,
            y_scale: Scale::Log,
            style: Style::Lines,
            series,
        };
        plot::xy(&stem, &chart).map_err(ExperimentError::Figure)?;
        let plot = ctx.link(&stem.with_extension("png"));
        ctx.write_data(NAME, &Data { runs, not_run, before, after, gif, plot })
    }

    fn section(&self, ctx: &Context) -> Result<String, ExperimentError> {
        let data: Data = ctx.read_data(NAME)?;
        let mut md = String::from("## Editable chunked terrain (`terrain_edit`)\n\n");
        md.push_str(&format!(
            "`terrain` at {}x{}x{} samples in {CHUNK}³-cell chunks ({} chunks), meshed once, then {EDITS} scripted brush edits \
             (seed {SEED}: a sphere of radius {}-{} cells on the surface of a random column, falloff {}-{} cells, alternately \
             carving and adding clay). An edit's time is the sample edit plus re-meshing every chunk it dirtied (in parallel); \
             the welded mesh is only assembled for pictures. Against the {FRAME_MS:.1} ms of a {FRAME_HZ} Hz frame. Every surface \
             extractor chunks: {}. An apron makes an edit dirty more chunks and each chunk cost more (dual contouring here \
             takes its normals from the samples, since edits leave the field behind).\n\n",
            DIMS[0],
            DIMS[1],
            DIMS[2],
            (DIMS[0] - 1) / CHUNK * (DIMS[1] - 1) / CHUNK * (DIMS[2] - 1) / CHUNK,
            BRUSH_RADIUS.0,
            BRUSH_RADIUS.1,
            BRUSH_FALLOFF.0,
            BRUSH_FALLOFF.1,
            data.runs.iter().map(|r| format!("`{}` {}", r.algorithm, chunk_reads(&r.algorithm))).collect::<Vec<_>>().join("; "),
        ));
        md.push_str(&reading(&data));
        let settings: Vec<(String, String)> = data.runs.iter().map(|r| (r.algorithm.clone(), r.settings.clone())).collect();
        md.push_str(&super::context::options_as_run(&settings));
        let body: Vec<Vec<String>> = data
            .runs
            .iter()
            .map(|r| {
                let within = r.edit_ms.iter().filter(|&&ms| ms <= FRAME_MS).count();
                vec![
                    r.algorithm.clone(),
                    format!("{:.0}", r.initial_ms),
                    format!("{:.2}", r.median_ms),
                    format!("{:.2}", r.p99_ms),
                    format!("{:.2}", r.max_ms),
                    format!("{within}/{}", r.edit_ms.len()),
                    format!("{:.1}", r.dirtied.iter().sum::<usize>() as f64 / r.dirtied.len().max(1) as f64),
                    format!("{} → {}", r.triangles[0], r.triangles[1]),
                    if r.manifold_after { "yes".into() } else { "**no**".into() },
                    r.open_seam_edges_max.to_string(),
                    format!("{:.2}, {:.1}°", r.quality_after[0], r.quality_after[1]),
                ]
            })
            .collect();
        md.push_str(&markdown_table(
            &[
                "extractor",
                "mesh all (ms)",
                "edit median (ms)",
                "edit p99 (ms)",
                "slowest (ms)",
                &format!("within {FRAME_MS:.1} ms"),
                "chunks per edit",
                "triangles",
                "manifold after",
                "open seam edges (most after an edit)",
                "edited mesh: mean aspect, smallest angle",
            ],
            &body,
        ));
        md.push_str(&format!(
            "\nOpen seam edges are boundary edges of the welded mesh more than one cell from the world's box (a crack between \
             chunks is made of them, and an edge-manifold check passes it; the dual extractors' own open border lies inside \
             the outermost cells), counted after every edit. The quality columns measure the \
             chunked mesh after the {EDITS} edits, not a fresh whole-domain mesh.\n\n\
             ### One chunk on one thread\n\n\
             A game re-meshes dirty chunks on worker threads, one chunk per task, within a slice of a frame. The same {EDITS} \
             edits, each dirty chunk re-meshed on its own on one thread (a one-thread pool), at three chunk sizes: one \
             chunk's time, median, p99 and slowest (ms), and the open seam edges of the welded mesh after the sequence.\n\n"
        ));
        let sizes: Vec<usize> = data.runs.first().map(|r| r.chunk_runs.iter().map(|c| c.chunk).collect()).unwrap_or_default();
        let header: Vec<String> = std::iter::once("extractor".to_owned())
            .chain(sizes.iter().map(|c| format!("{c}³: median / p99 / max (chunks)")))
            .chain(std::iter::once("open seam edges after".to_owned()))
            .collect();
        let rows: Vec<Vec<String>> =
            data.runs
                .iter()
                .map(|r| {
                    std::iter::once(r.algorithm.clone())
                        .chain(r.chunk_runs.iter().map(|c| {
                            format!("{:.2} / {:.2} / {:.2} ({})", c.chunk_ms[0], c.chunk_ms[1], c.chunk_ms[2], c.chunks)
                        }))
                        .chain(std::iter::once(
                            r.chunk_runs.iter().map(|c| c.open_seam_edges.to_string()).collect::<Vec<_>>().join(", "),
                        ))
                        .collect()
                })
                .collect();
        let header: Vec<&str> = header.iter().map(String::as_str).collect();
        md.push_str(&markdown_table(&header, &rows));
        if !data.not_run.is_empty() {
            md.push_str(&format!(
                "\n**Not run** (not chunk-capable yet: their cells or tetrahedra straddle chunk faces and need an apron and \
                 ownership rules inside the extractor): {}.\n",
                data.not_run.join(", ")
            ));
        }
        md.push_str(&format!("\n![edit times]({})\n\n", data.plot));
        md.push_str(&format!(
            "Before and after the {EDITS} edits (marching cubes, coloured by material: grass, sand in the valleys, dirt, rock in the caves, the brushes' clay), and every {GIF_EVERY}th edit as an animation:\n\n![before]({}) \
             ![after]({})\n\n![edits]({})\n",
            data.before, data.after, data.gif
        ));
        Ok(md)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(algorithm: &str, edits: [f64; 2], cracks: usize, chunk_p99: f64) -> Run {
        Run {
            algorithm: algorithm.into(),
            initial_ms: 1.0,
            edit_ms: edits.to_vec(),
            dirtied: vec![1, 1],
            median_ms: edits[0],
            p99_ms: edits[1],
            max_ms: edits[1],
            triangles: [1, 1],
            manifold_after: true,
            open_seam_edges_max: cracks,
            quality_after: [1.0, 1.0],
            chunk_runs: vec![ChunkRun { chunk: CHUNK, chunks: 1, chunk_ms: [1.0, chunk_p99, chunk_p99], open_seam_edges: 0 }],
            settings: String::new(),
        }
    }

    #[test]
    fn the_reading_follows_the_runs() {
        let mut data = Data {
            runs: Vec::new(),
            not_run: Vec::new(),
            before: String::new(),
            after: String::new(),
            gif: String::new(),
            plot: String::new(),
        };
        assert_eq!(reading(&data), "");
        data.runs = vec![run("slow", [5.0, 20.0], 0, 3.0), run("fast", [1.0, 2.0], 2, 1.0)];
        let r = reading(&data);
        assert!(r.contains("Every edit within a 16.7 ms frame: fast; not every one: slow (1 of 2)."), "{r}");
        assert!(r.contains("Median edit, ms: fast 1.00, slow 5.00."), "{r}");
        assert!(r.contains("closed manifold after the sequence: slow; not: fast."), "{r}");
        assert!(r.contains("within the 2 ms budget: fast."), "{r}");
    }
}
