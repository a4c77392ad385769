//! `terrain_liquids`: the marching cubes terrain post's liquids (its "Viscosity" section,
//! `../shared/papers/blog-marching-cubes-terrain-materials.txt`; issue 37), on a terrain with a
//! lake and a half-flooded cave ([`isolab_algorithms::liquids::lake_and_cave`]). Each extractor
//! the post's rule carries over to meshes the solid and the liquid density and shares the contact
//! ([`isolab_algorithms::liquids::extract_layers`], which fills again the cells where marching
//! cubes' layers still cross; the rule alone is run and timed beside it where it acts); the
//! post's "naive solution" (two independent meshes) is run beside it. Then a script of brushes digs, pours and drains on a chunked terrain
//! ([`isolab_algorithms::liquids::ChunkedLayers`]): after every edit the chunks the brush touched
//! are re-meshed, and the welded layers are checked: both closed and manifold, every contact
//! vertex shared, no crossing pair (exact), no liquid inside the solid, and the masses against the
//! brushes' books. A GIF shows the edits.

mod data;
mod page;

use super::context::{Context, Experiment, ExperimentError};
use data::{Data, EditRun, Row};
use isolab_algorithms::liquids::{
    extract_layers, extract_layers_without_untangling, lake_and_cave, ChunkedLayers, Layers, Phases,
};
use isolab_algorithms::random::Random;
use isolab_algorithms::{extractors, Extraction, Extractor, Lattice, Samples, TriMesh, Vec3};
use isolab_metrics::layers::layer_contact;
use isolab_render::{self as render, RenderOptions, Shading};
use std::time::Instant;

/// The experiment.
pub struct TerrainLiquids;

const NAME: &str = "terrain_liquids";

/// Samples along x and y of the compared scene (half as many along z).
const SCENE: usize = 96;

/// Samples along x and y of the edited scene.
const EDIT_SCENE: usize = 64;

/// Brushes in the edit script (dig, pour, drain in turn).
const EDITS: usize = 200;

/// Cells per chunk of the edited terrain (the last chunk along an axis takes what remains).
const EDIT_CHUNK: usize = 16;

/// A GIF frame every this many edits.
const GIF_EVERY: usize = 10;

/// Timed runs per extractor.
const RUNS: usize = 9;

/// The extractors of the edit script: marching cubes (the post's), and marching tetrahedra, whose
/// layers provably do not overlap. The GIF shows the first.
const EDIT_EXTRACTORS: [&str; 2] = ["marching-cubes", "marching-tetrahedra"];

const SEED: u64 = 37;

fn build(name: &str) -> Result<Box<dyn Extractor>, ExperimentError> {
    extractors::by_name(name).ok_or_else(|| ExperimentError::Missing(format!("extractor {name}")))
}

fn closed_manifold(mesh: &TriMesh) -> bool {
    isolab_metrics::topology(mesh).is_watertight_manifold()
}

fn row(method: &str, phases: &Phases, layers: &Layers, times: &mut [f64]) -> Row {
    times.sort_by(f64::total_cmp);
    Row {
        method: method.into(),
        solid_triangles: layers.solid.triangles.len(),
        liquid_triangles: layers.liquid.triangles.len(),
        solid_closed_manifold: closed_manifold(&layers.solid),
        liquid_closed_manifold: closed_manifold(&layers.liquid),
        contact: layer_contact(phases, &layers.solid, &layers.liquid),
        median_ms: times[times.len() / 2],
        crossing_cells: layers.crossing_cells,
        retiled_cells: layers.retiled_cells,
    }
}

/// The post's naive solution: the two densities meshed independently, nothing shared.
fn independent_layers(extractor: &dyn Extractor, phases: &Phases) -> Result<Layers, ExperimentError> {
    let mesh = |density: &[f32]| -> Result<TriMesh, ExperimentError> {
        let values = density.iter().map(|&d| phases.max() / 2.0 - d).collect();
        let samples = Samples::from_values(Lattice::Cubic(*phases.grid()), values, 0.0)?;
        let mut out = Extraction::default();
        extractor.extract(&samples, &mut out)?;
        Ok(out.surface)
    };
    Ok(Layers { solid: mesh(phases.solid())?, liquid: mesh(phases.liquid())?, contact: 0, crossing_cells: 0, retiled_cells: 0 })
}

/// Both layers in one picture: the solid by height (brown below, green on top), the liquid blue.
fn picture(layers: &Layers, opts: &RenderOptions) -> render::Image {
    let mut mesh = layers.solid.clone();
    let offset = mesh.positions.len() as u32;
    mesh.positions.extend(&layers.liquid.positions);
    mesh.triangles.extend(layers.liquid.triangles.iter().map(|t| t.map(|v| v + offset)));
    let top = mesh.positions.iter().map(|p| p.z).fold(1.0f32, f32::max);
    let mut colours: Vec<[u8; 3]> = layers
        .solid
        .positions
        .iter()
        .map(|p| {
            let t = (p.z / top).clamp(0.0, 1.0);
            [(150.0 - 80.0 * t) as u8, (95.0 + 55.0 * t) as u8, (55.0 - 10.0 * t) as u8]
        })
        .collect();
    colours.extend(std::iter::repeat_n([40, 110, 220], layers.liquid.positions.len()));
    // The scene's z is up; the renderer's up is y.
    mesh.positions.iter_mut().for_each(|p| *p = Vec3::new(p.x, p.z, p.y));
    mesh.triangles.iter_mut().for_each(|t| t.swap(1, 2));
    render::render_coloured(&mesh, &colours, opts)
}

/// The brush script with `name`, checked after every edit; the GIF's frames and a last picture.
fn edit_run(ctx: &Context, name: &str) -> Result<(EditRun, Vec<render::Image>, render::Image), ExperimentError> {
    let mut phases = lake_and_cave(EDIT_SCENE);
    let extractor = build(name)?;
    // A quick run: the first 20 edits.
    let edits = ctx.pick(EDITS, 20);
    let [nx, ny, nz] = phases.grid().dims;
    let mut random = Random::new(SEED);
    let mut range = |lo: f32, hi: f32| lo + (hi - lo) * random.unit_f32();
    let opts = RenderOptions { width: 420, height: 300, shading: Shading::Smooth, ..Default::default() };
    let start_masses = phases.masses();
    let mut run = EditRun {
        extractor: name.into(),
        edits,
        fewest_contact: usize::MAX,
        solid_mass: [start_masses.solid, 0.0],
        liquid_mass: [start_masses.liquid, 0.0],
        ..Default::default()
    };
    let mut chunked = ChunkedLayers::new(extractor.as_ref(), &phases, EDIT_CHUNK)?;
    run.chunk_counts = chunked.counts();
    let mut frames = vec![picture(&chunked.welded(), &opts)];
    let (mut books_solid, mut books_liquid) = (start_masses.solid, start_masses.liquid);
    let bar = ctx.bar(&format!("{NAME} {name}"), edits as u64);
    let mut last = Layers::default();
    for edit in 0..edits {
        let ground = nz as f32 * 0.5;
        let centre = Vec3::new(range(4.0, nx as f32 - 5.0), range(4.0, ny as f32 - 5.0), range(ground - 6.0, ground + 3.0));
        let radius = range(2.0, 5.0);
        let amount = range(0.3, 1.0);
        match edit % 3 {
            0 => {
                let dug = phases.dig(centre, radius, amount);
                run.dug += dug;
                books_solid -= dug;
            }
            1 => {
                let poured = phases.pour(centre, radius, amount);
                run.poured += poured;
                books_liquid += poured;
            }
            _ => {
                let drained = phases.drain(centre, radius, amount);
                run.drained += drained;
                books_liquid -= drained;
            }
        }
        let touched = chunked.touching(centre, radius);
        let start = Instant::now();
        chunked.remesh(extractor.as_ref(), &phases, &touched)?;
        run.remesh_ms.push(start.elapsed().as_secs_f64() * 1e3);
        run.chunks_remeshed.push(touched.len());
        let layers = chunked.welded();
        if !(closed_manifold(&layers.solid) && closed_manifold(&layers.liquid)) {
            run.open_after += 1;
        }
        let c = layer_contact(&phases, &layers.solid, &layers.liquid);
        run.worst.unshared = run.worst.unshared.max(c.unshared);
        run.worst.crossing_pairs = run.worst.crossing_pairs.max(c.crossing_pairs);
        run.most_retiled_cells = run.most_retiled_cells.max(layers.retiled_cells);
        run.worst.liquid_inside_solid = run.worst.liquid_inside_solid.max(c.liquid_inside_solid);
        run.worst.contact_vertices = run.worst.contact_vertices.max(c.contact_vertices);
        run.fewest_contact = run.fewest_contact.min(c.contact_vertices);
        let m = phases.masses();
        let drift = |have: f64, books: f64| (have - books).abs() / books.abs().max(1.0);
        run.mass_drift = run.mass_drift.max(drift(m.solid, books_solid)).max(drift(m.liquid, books_liquid));
        if (edit + 1) % GIF_EVERY == 0 {
            frames.push(picture(&layers, &opts));
        }
        last = layers;
        bar.inc(1);
    }
    bar.finish();
    let end = phases.masses();
    run.solid_mass[1] = end.solid;
    run.liquid_mass[1] = end.liquid;
    let still = picture(&last, &RenderOptions { width: 720, height: 480, ..opts });
    Ok((run, frames, still))
}

impl Experiment for TerrainLiquids {
    fn name(&self) -> &'static str {
        NAME
    }

    fn question(&self) -> &'static str {
        "Do liquid and solid layers from one density and a viscosity meet without gaps or overlaps, and keep their mass under edits (the marching cubes terrain post)?"
    }

    fn run(&self, ctx: &Context) -> Result<(), ExperimentError> {
        let phases = lake_and_cave(SCENE);
        let mut rows = Vec::new();
        let mut refused = Vec::new();
        // Every registered surface extractor: those with edge vertices take the rule, the others
        // are refused by extract_layers (listed with its reason).
        let mut settings = Vec::new();
        let mut rule_alone = Vec::new();
        for extractor in extractors::registry().into_iter().filter(|e| !e.produces_volume()) {
            settings.push((extractor.name().to_owned(), extractor.settings()));
            let Ok(layers) = extract_layers(extractor.as_ref(), &phases) else {
                refused.push(format!("`{}`", extractor.name()));
                continue;
            };
            // Where the layers crossed after the rule, the rule alone is timed too, alternating.
            let both = layers.crossing_cells > 0;
            let (mut times, mut alone_times) = (Vec::new(), Vec::new());
            let mut alone = Layers::default();
            for _ in 0..ctx.pick(RUNS, ctx.repeats) {
                let start = Instant::now();
                std::hint::black_box(extract_layers(extractor.as_ref(), &phases)?);
                times.push(start.elapsed().as_secs_f64() * 1e3);
                if both {
                    let start = Instant::now();
                    alone = extract_layers_without_untangling(extractor.as_ref(), &phases)?;
                    alone_times.push(start.elapsed().as_secs_f64() * 1e3);
                }
            }
            rows.push(row(extractor.name(), &phases, &layers, &mut times));
            if both {
                let method = format!("{}, the post's rule alone", extractor.name());
                rule_alone.push(row(&method, &phases, &alone, &mut alone_times));
            }
        }
        let naive_extractor = rows
            .first()
            .map(|r| r.method.clone())
            .ok_or_else(|| ExperimentError::Missing("an extractor that takes the rule".into()))?;
        let start = Instant::now();
        let naive_layers = independent_layers(build(&naive_extractor)?.as_ref(), &phases)?;
        let mut times = vec![start.elapsed().as_secs_f64() * 1e3];
        let method = format!("{naive_extractor}, two independent meshes (the post's naive solution)");
        let naive = row(&method, &phases, &naive_layers, &mut times);

        let mut edits = Vec::new();
        let mut shown = None;
        for name in EDIT_EXTRACTORS {
            let (run, frames, still) = edit_run(ctx, name)?;
            edits.push(run);
            shown.get_or_insert((frames, still));
        }
        let Some((frames, still)) = shown else { return Err(ExperimentError::Missing("an edit run".into())) };
        let dir = ctx.figure_dir(NAME)?;
        let path = dir.join("after-edits.png");
        render::save_png(&path, &still)?;
        let picture = ctx.link(&path);
        let path = dir.join("edits.gif");
        render::save_gif(&path, &frames, 40)?;
        let gif = ctx.link(&path);
        let edit_scene = lake_and_cave(EDIT_SCENE).grid().dims;
        ctx.write_data(
            NAME,
            &Data { scene: phases.grid().dims, rows, naive, rule_alone, refused, edits, edit_scene, picture, gif, settings },
        )
    }

    fn section(&self, ctx: &Context) -> Result<String, ExperimentError> {
        page::section(ctx)
    }
}
