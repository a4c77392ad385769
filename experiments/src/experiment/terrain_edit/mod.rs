//! `terrain_edit`: the deformable-terrain use case of every paper in `../shared/papers/` (the
//! deformable-terrain paper, the RMT paper's section 1.1, the blog posts' chunk sections): a
//! 256 x 128 x 256-cell `terrain` in 32³ chunks, then a scripted, seeded sequence of 200 brush
//! edits (spheres adding or carving material on the surface, with falloff). Each edit's time is the
//! sample edit plus re-meshing the chunks it dirtied; medians and 99th percentiles against the
//! 16.7 ms frame budget, a plot of every edit, before/after pictures and a GIF of the sequence.
//! Only chunk-capable extractors run (see `algorithms::chunks`); the others are listed as not run.

mod data;
mod page;

use super::context::{Context, Experiment, ExperimentError};
use crate::figures::plot::{self, Scale, Series, Style, XyPlot};
pub(crate) use data::Data;
pub use data::{ChunkRun, Run};
use isolab_algorithms::chunks::lod::open_edges_away_from_bounds;
use isolab_algorithms::chunks::{Brush, ChunkedVolume};
use isolab_algorithms::{extractors, fields, materials, Chunking, Extraction, Grid, Lattice, Samples};
use isolab_render::{self as render, RenderOptions, Shading};
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
        let mut brushes = script(&grid, &surface_y);
        // A quick run: the first 20 edits.
        brushes.truncate(ctx.pick(EDITS, 20));
        let edits = brushes.len();
        let dir = ctx.figure_dir(NAME)?;
        let surface_extractors: Vec<_> = extractors::registry().into_iter().filter(|e| !e.produces_volume()).collect();
        let bar = ctx.bar(NAME, (surface_extractors.len() * edits) as u64);
        let mut runs = Vec::new();
        let mut not_run = Vec::new();
        let opts = RenderOptions { width: 420, height: 300, shading: Shading::Smooth, ..Default::default() };
        let (mut before, mut after, mut gif) = (String::new(), String::new(), String::new());
        for e in &surface_extractors {
            if e.chunking() == Chunking::Unsupported {
                not_run.push(e.name().to_string());
                bar.inc(edits as u64);
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
            let (mut edit_ms, mut dirtied) = (Vec::with_capacity(edits), Vec::with_capacity(edits));
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
                ranges: Vec::new(),
            })
            .collect();
        series.push(Series {
            label: format!("{FRAME_MS:.1} ms frame"),
            color: (0, 0, 0),
            points: vec![(1.0, FRAME_MS), (edits as f64, FRAME_MS)],
            ranges: Vec::new(),
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
        page::section(ctx)
    }
}

#[cfg(test)]
mod tests {
    use super::page::reading;
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
