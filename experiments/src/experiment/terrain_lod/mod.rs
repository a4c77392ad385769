//! `terrain_lod`: levels of detail on the 256 x 128 x 256-cell `terrain` in 32³-cell chunks:
//! chunks near a viewer at one corner are meshed at full resolution, farther ones at half and at a
//! quarter, by every registered extractor that takes levels of detail
//! ([`isolab_algorithms::chunks::lod`]: marching cubes by restriction and stitching, surface nets
//! and both dual contourings by restriction and octree dual contouring's minimal edges, manifold
//! dual contouring's polygons as fans kept in their cells); the
//! `transvoxel` crate meshes the same chunks, samples and levels with Lengyel's transition cells
//! (`transvoxel_peer`). For each level pattern and each implementation: triangles, boundary edges
//! left where they are cracks, non-manifold edges and vertices, self-intersecting pairs, the shape
//! of the triangles along seams between levels, time, and the cost of switching one chunk's
//! level; pictures coloured by level.

mod data;
mod page;

use super::context::{Context, Experiment, ExperimentError};
use crate::report::Spread;
use data::{Data, Row, Switch};
use isolab_algorithms::chunks::lod::{balance_levels, extract_lod, open_edges_away_from_bounds, open_edges_off_bounds};
use isolab_algorithms::{extractors, fields, Extraction, Extractor, Grid, Lattice, LevelsOfDetail, Samples, TriMesh, Vec3};
use isolab_render::{self as render, Image, RenderOptions, Shading};
use std::collections::HashMap;
use std::time::Instant;

mod transvoxel_peer;

/// The experiment.
pub struct TerrainLod;

const NAME: &str = "terrain_lod";

const DIMS: [usize; 3] = [257, 129, 257];

const CHUNK: usize = 32;

const COUNTS: [usize; 3] = [8, 4, 8];

const RUNS: usize = 5;

/// The viewer-distance pattern: full resolution within this many chunks of the viewer's corner,
/// half resolution within twice as many, a quarter beyond.
const NEAR_CHUNKS: f32 = 2.5;

const CRATE: &str = "transvoxel crate (transition cells)";

/// The version of the `transvoxel` crate the peer runs (Cargo.toml's).
const TRANSVOXEL_VERSION: &str = "2.0.0";

/// An implementation's name in the table: the extractor and its method.
fn implementation_name(e: &dyn Extractor) -> String {
    let method = match e.levels_of_detail() {
        LevelsOfDetail::Dual(_) if e.info().guarantees.intersection_free => "octree minimal edges, fans kept in cells",
        LevelsOfDetail::Dual(_) => "octree minimal edges",
        LevelsOfDetail::Stitched => "restriction + stitching",
        LevelsOfDetail::Unsupported(_) => "none",
    };
    format!("{} ({method})", e.name())
}

/// The registered extractors (default options) that take levels of detail.
fn lod_extractors() -> Vec<Box<dyn Extractor>> {
    extractors::registry().into_iter().filter(|e| !matches!(e.levels_of_detail(), LevelsOfDetail::Unsupported(_))).collect()
}

fn flat(id: [usize; 3]) -> usize {
    id[0] + COUNTS[0] * (id[1] + COUNTS[1] * id[2])
}

fn id_of(k: usize) -> [usize; 3] {
    [k % COUNTS[0], (k / COUNTS[0]) % COUNTS[1], k / (COUNTS[0] * COUNTS[1])]
}

/// The level patterns: uniform, viewer distance (three levels, balanced) and checkerboards that
/// put a seam on every chunk face.
fn patterns() -> Vec<(String, Vec<u8>)> {
    let total = COUNTS.iter().product::<usize>();
    let mut near: Vec<u8> = (0..total)
        .map(|k| {
            let id = id_of(k);
            let d = ((id[0] as f32 + 0.5).powi(2) + (id[2] as f32 + 0.5).powi(2)).sqrt();
            (d / NEAR_CHUNKS).floor().min(2.0) as u8
        })
        .collect();
    balance_levels(COUNTS, &mut near);
    let checker = |a: u8| -> Vec<u8> {
        (0..total)
            .map(|k| {
                let id = id_of(k);
                a + ((id[0] + id[1] + id[2]) % 2) as u8
            })
            .collect()
    };
    vec![
        ("all full resolution".into(), vec![0; total]),
        ("viewer distance (full, half, quarter)".into(), near),
        ("checkerboard full / half (every seam)".into(), checker(0)),
        ("checkerboard half / quarter (every seam)".into(), checker(1)),
        ("all half resolution".into(), vec![1; total]),
        ("all quarter resolution".into(), vec![2; total]),
    ]
}

/// The shape of the seam triangles (those whose centroid lies within one cell of the coarser side,
/// `2^level` samples, of a chunk face whose two chunks differ in level).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct SeamShape {
    /// Seam triangles with an area (the others have no shape and are counted apart).
    count: usize,
    zero_area: usize,
    aspect_mean: f64,
    aspect_median: f64,
    aspect_max: f64,
    /// The mean over the triangles none of whose corners lies within [`NEAR_SAMPLE`] of a sample:
    /// marching cubes' needles where a crossing nearly meets a sample, left out.
    aspect_mean_off_samples: f64,
    /// `None` without seam triangles.
    min_angle_deg: Option<f64>,
}

/// How close to a sample (in samples) a corner counts as on it, for
/// [`SeamShape::aspect_mean_off_samples`]: above the margin that keeps marching cubes' vertices
/// off the samples at every level.
const NEAR_SAMPLE: f32 = 0.001;

/// Whether the triangle with centroid `c` (sample coordinates) is a seam triangle.
fn near_seam(c: Vec3, levels: &[u8]) -> bool {
    let id = [0, 1, 2].map(|a| ((c[a] / CHUNK as f32).floor().max(0.0) as usize).min(COUNTS[a] - 1));
    let level = levels[flat(id)];
    (0..3).any(|a| {
        let within = |plane: usize, other: usize| {
            let reach = (1u32 << level.max(levels[other])) as f32;
            (c[a] - plane as f32).abs() <= reach && levels[other] != level
        };
        let lo = id[a] * CHUNK;
        let mut below = id;
        let mut above = id;
        (id[a] > 0 && {
            below[a] -= 1;
            within(lo, flat(below))
        }) || (id[a] + 1 < COUNTS[a] && {
            above[a] += 1;
            within(lo + CHUNK, flat(above))
        })
    })
}

fn seam_shape(mesh: &TriMesh, grid: &Grid, levels: &[u8]) -> SeamShape {
    let mut aspects = Vec::new();
    let (mut zero_area, mut smallest) = (0usize, 180.0f64);
    let (mut off_sum, mut off_n) = (0.0, 0usize);
    for t in &mesh.triangles {
        let p = t.map(|v| mesh.positions[v as usize]);
        let q = p.map(|x| (x - grid.origin) / grid.spacing);
        if !near_seam((q[0] + q[1] + q[2]) / 3.0, levels) {
            continue;
        }
        let Some(s) = isolab_metrics::quality::triangle_shape(p[0], p[1], p[2]) else {
            zero_area += 1;
            continue;
        };
        aspects.push(s.aspect_ratio);
        smallest = smallest.min(s.min_angle_deg);
        if q.iter().all(|x| (*x - x.round()).abs().max_element() > NEAR_SAMPLE) {
            off_sum += s.aspect_ratio;
            off_n += 1;
        }
    }
    let count = aspects.len();
    let mean = aspects.iter().sum::<f64>() / count.max(1) as f64;
    let max = aspects.iter().copied().fold(0.0, f64::max);
    aspects.sort_by(f64::total_cmp);
    SeamShape {
        count,
        zero_area,
        aspect_mean: mean,
        aspect_median: aspects.get(count / 2).copied().unwrap_or(0.0),
        aspect_max: max,
        aspect_mean_off_samples: off_sum / off_n.max(1) as f64,
        min_angle_deg: (count > 0).then_some(smallest),
    }
}

/// One row: the mesh's seam checks and shape. `dual`: the mesh's own border lies inside the
/// outer cells (a dual method's), so open edges within a coarsest cell of the world's box are not
/// cracks. `stats`: ours, (stitched, pinched).
#[allow(clippy::too_many_arguments)]
fn row(
    implementation: &str,
    pattern: &str,
    levels: &[u8],
    mesh: &TriMesh,
    grid: &Grid,
    dual: bool,
    stats: Option<(usize, usize)>,
    times: Vec<f64>,
) -> Row {
    let t = isolab_metrics::topology(mesh);
    let top = levels.iter().copied().max().unwrap_or(0);
    let seam_boundary_edges = if dual {
        open_edges_away_from_bounds(mesh, &grid.bounds(), grid.spacing * f32::from(1u8 << top))
    } else {
        open_edges_off_bounds(mesh, &grid.bounds())
    };
    let shape = seam_shape(mesh, grid, levels);
    let mut per_level = vec![0; 1 + levels.iter().copied().max().unwrap_or(0) as usize];
    for &l in levels {
        per_level[l as usize] += 1;
    }
    Row {
        implementation: implementation.into(),
        pattern: pattern.into(),
        per_level,
        triangles: mesh.triangles.len(),
        stitched: stats.map(|s| s.0),
        pinched: stats.map(|s| s.1),
        seam_boundary_edges,
        non_manifold_edges: t.non_manifold_edges,
        non_manifold_vertices: t.non_manifold_vertices,
        misoriented_edges: t.misoriented_edges,
        self_intersecting_pairs: isolab_metrics::self_intersections(mesh).count,
        seam_triangles: shape.count,
        seam_zero_area: shape.zero_area,
        seam_aspect_mean: shape.aspect_mean,
        seam_aspect_median: shape.aspect_median,
        seam_aspect_max: shape.aspect_max,
        seam_aspect_mean_off_samples: shape.aspect_mean_off_samples,
        seam_min_angle_deg: shape.min_angle_deg,
        time_ms: Spread::of(times),
    }
}

/// Vertex colours by level: full resolution green, half blue, quarter purple.
fn level_colours(mesh: &TriMesh, triangle_levels: &[u8]) -> Vec<[u8; 3]> {
    const BY_LEVEL: [[u8; 3]; 3] = [[96, 160, 80], [80, 120, 190], [150, 90, 170]];
    let mut colours = vec![[150u8, 150, 150]; mesh.positions.len()];
    for (t, &l) in mesh.triangles.iter().zip(triangle_levels) {
        for &v in t {
            colours[v as usize] = BY_LEVEL[(l as usize).min(BY_LEVEL.len() - 1)];
        }
    }
    colours
}

/// A wireframe close-up of the seams around the corner where full, half and quarter resolution
/// meet along x at z near the viewer.
fn close_up(mesh: &TriMesh, colours: &[[u8; 3]], grid: &Grid, opts: &RenderOptions) -> Image {
    let h = grid.spacing;
    let (x0, z1) = (grid.origin.x + (2 * CHUNK) as f32 * h, grid.origin.z + 40.0 * h);
    let (mut crop, mut crop_colours, mut remap) = (TriMesh::default(), Vec::new(), HashMap::new());
    for t in &mesh.triangles {
        let c = t.iter().map(|&v| mesh.positions[v as usize]).sum::<Vec3>() / 3.0;
        if (c.x - x0).abs() >= 40.0 * h || c.z >= z1 {
            continue;
        }
        crop.triangles.push(t.map(|v| {
            *remap.entry(v).or_insert_with(|| {
                crop.positions.push(mesh.positions[v as usize]);
                crop_colours.push(colours[v as usize]);
                (crop.positions.len() - 1) as u32
            })
        }));
    }
    render::render_coloured(
        &crop,
        &crop_colours,
        &RenderOptions { shading: Shading::Flat, wireframe: true, view: Vec3::new(0.2, 0.9, 1.0), ..*opts },
    )
}

/// The first chunk of `levels` that can go one level finer and stay balanced with its
/// neighbours, and that level.
fn switchable(levels: &[u8]) -> Option<(usize, u8)> {
    (0..levels.len()).filter(|&k| levels[k] >= 1).find_map(|k| {
        let mut changed = levels.to_vec();
        changed[k] -= 1;
        let mut balanced = changed.clone();
        balance_levels(COUNTS, &mut balanced);
        // Lowering a level can only break balance toward coarser neighbours.
        let ok = (0..levels.len()).all(|o| o == k || balanced[o] == levels[o])
            && (0..levels.len()).any(|o| o != k && levels[o] == levels[k]);
        ok.then_some((k, changed[k]))
    })
}

/// Time to switch chunk `k` to `to`: ours re-runs `extract_lod` on the 3³ chunks around it, the
/// crate re-meshes it and its face neighbours whose transition faces change.
fn measure_switch(
    samples: &Samples,
    ours: &[Box<dyn Extractor>],
    levels: &[u8],
    k: usize,
    to: u8,
) -> Result<Switch, ExperimentError> {
    let id = id_of(k);
    let grid = *samples.grid();
    let lo = id.map(|c| c.saturating_sub(1));
    let hi = [0, 1, 2].map(|a| (id[a] + 1).min(COUNTS[a] - 1));
    let sub_counts = [0, 1, 2].map(|a| hi[a] - lo[a] + 1);
    let mut after = levels.to_vec();
    after[k] = to;
    let sub_levels: Vec<u8> = (0..sub_counts.iter().product::<usize>())
        .map(|s| {
            let c = [s % sub_counts[0], (s / sub_counts[0]) % sub_counts[1], s / (sub_counts[0] * sub_counts[1])];
            after[flat([lo[0] + c[0], lo[1] + c[1], lo[2] + c[2]])]
        })
        .collect();
    let dims = sub_counts.map(|c| c * CHUNK + 1);
    let s0 = lo.map(|c| c * CHUNK);
    let mut values = Vec::with_capacity(dims.iter().product());
    for z in 0..dims[2] {
        for y in 0..dims[1] {
            for x in 0..dims[0] {
                values.push(samples.values()[grid.index(s0[0] + x, s0[1] + y, s0[2] + z)]);
            }
        }
    }
    let sub_grid =
        Grid { origin: grid.origin + Vec3::new(s0[0] as f32, s0[1] as f32, s0[2] as f32) * grid.spacing, dims, ..grid };
    let sub = Samples::from_values(Lattice::Cubic(sub_grid), values, samples.iso())?;
    let mut out = Extraction::default();
    let mut ours_ms = vec![Vec::new(); ours.len()];
    for _ in 0..RUNS {
        for (e, times) in ours.iter().zip(&mut ours_ms) {
            let start = Instant::now();
            extract_lod(e.as_ref(), &sub, CHUNK, &sub_levels, &mut out, None)?;
            times.push(start.elapsed().as_secs_f64() * 1e3);
        }
    }
    // The crate: the chunk, and face neighbours one level coarser than the chunk's new level or
    // its old one (their transition faces toward it appear or go).
    let touched: Vec<usize> = std::iter::once(k)
        .chain((0..6).filter_map(|f| {
            let (axis, up) = (f / 2, f % 2 == 1);
            let mut n = id;
            if up {
                n[axis] += 1;
                (n[axis] < COUNTS[axis]).then_some(())?;
            } else {
                n[axis] = n[axis].checked_sub(1)?;
            }
            let o = flat(n);
            (levels[o] == to + 1 || levels[o] == levels[k] + 1).then_some(o)
        }))
        .collect();
    let mut crate_ms = Vec::new();
    for _ in 0..RUNS {
        let start = Instant::now();
        for &c in &touched {
            std::hint::black_box(transvoxel_peer::extract_one(&grid, samples.values(), samples.iso(), CHUNK, COUNTS, &after, c));
        }
        crate_ms.push(start.elapsed().as_secs_f64() * 1e3);
    }
    Ok(Switch {
        chunk: id,
        from: levels[k],
        to,
        ours: ours.iter().zip(ours_ms).map(|(e, t)| (implementation_name(e.as_ref()), Spread::of(t))).collect(),
        ours_chunks: sub_levels.len(),
        crate_ms: Spread::of(crate_ms),
        crate_chunks: touched.len(),
    })
}

impl Experiment for TerrainLod {
    fn name(&self) -> &'static str {
        NAME
    }

    fn question(&self) -> &'static str {
        "Do three levels of detail meet without cracks (and without self-intersections) for marching cubes, surface nets and both dual contourings, how do they compare with Transvoxel's transition cells, and how many triangles do they save?"
    }

    fn peers(&self) -> &'static [&'static str] {
        &["transvoxel"]
    }

    fn run(&self, ctx: &Context) -> Result<(), ExperimentError> {
        let field = fields::builtin("terrain", Default::default())?;
        let grid = Grid::with_dims(&field.domain(), DIMS)?;
        let samples = Samples::sample(field, Lattice::Cubic(grid), 0.0)?;
        let ours = lod_extractors();
        let patterns = patterns();
        let bar = ctx.bar(NAME, ((patterns.len() + 1) * RUNS * (ours.len() + 1)) as u64);
        let mut rows = Vec::new();
        let (mut picture, mut crate_picture, mut dual_picture) = (String::new(), String::new(), String::new());
        let opts = RenderOptions { width: 560, height: 380, shading: Shading::Smooth, ..Default::default() };
        let viewer = &patterns[1].1;
        for (name, levels) in &patterns {
            let mut outs: Vec<(Extraction, Vec<u8>)> = (0..ours.len()).map(|_| Default::default()).collect();
            let mut ours_ms = vec![Vec::new(); ours.len()];
            let mut stats = vec![None; ours.len()];
            let mut crate_ms = Vec::new();
            let mut peer = (TriMesh::default(), Vec::new());
            // Alternating, one run of each per round.
            for _ in 0..RUNS {
                for (i, e) in ours.iter().enumerate() {
                    let (out, tri_levels) = &mut outs[i];
                    let start = Instant::now();
                    stats[i] = Some(extract_lod(e.as_ref(), &samples, CHUNK, levels, out, Some(tri_levels))?);
                    ours_ms[i].push(start.elapsed().as_secs_f64() * 1e3);
                    bar.inc(1);
                }
                let start = Instant::now();
                peer = transvoxel_peer::extract(&grid, samples.values(), samples.iso(), CHUNK, COUNTS, levels);
                crate_ms.push(start.elapsed().as_secs_f64() * 1e3);
                bar.inc(1);
            }
            for (i, e) in ours.iter().enumerate() {
                let s = stats[i].expect("ran");
                let dual = matches!(e.levels_of_detail(), LevelsOfDetail::Dual(_));
                let times = std::mem::take(&mut ours_ms[i]);
                let mesh = &outs[i].0.surface;
                rows.push(row(
                    &implementation_name(e.as_ref()),
                    name,
                    levels,
                    mesh,
                    &grid,
                    dual,
                    Some((s.stitched, s.pinched)),
                    times,
                ));
            }
            rows.push(row(CRATE, name, levels, &peer.0, &grid, false, None, crate_ms));
            if levels == viewer {
                let dir = ctx.figure_dir(NAME)?;
                let close = |mesh: &TriMesh, tri_levels: &[u8]| close_up(mesh, &level_colours(mesh, tri_levels), &grid, &opts);
                let mc = ours.iter().position(|e| e.name() == "marching-cubes").unwrap_or(0);
                let (mc_out, mc_levels) = &outs[mc];
                let whole = render::render_coloured(&mc_out.surface, &level_colours(&mc_out.surface, mc_levels), &opts);
                let ours_close = close(&mc_out.surface, mc_levels);
                let path = dir.join("levels.png");
                render::save_png(&path, &render::side_by_side(&whole, &ours_close))?;
                picture = ctx.link(&path);
                let path = dir.join("transvoxel.png");
                render::save_png(&path, &render::side_by_side(&ours_close, &close(&peer.0, &peer.1)))?;
                crate_picture = ctx.link(&path);
                let by_name = |name: &str| ours.iter().position(|e| e.name() == name);
                if let (Some(a), Some(b)) = (by_name("dual-contouring"), by_name("manifold-dual-contouring")) {
                    let path = dir.join("dual.png");
                    let (left, right) = (close(&outs[a].0.surface, &outs[a].1), close(&outs[b].0.surface, &outs[b].1));
                    render::save_png(&path, &render::side_by_side(&left, &right))?;
                    dual_picture = ctx.link(&path);
                }
            }
        }
        let switch = match switchable(viewer) {
            Some((k, to)) => Some(measure_switch(&samples, &ours, viewer, k, to)?),
            None => None,
        };
        bar.finish();
        let options = ours.iter().map(|e| (e.name().to_string(), e.settings())).collect();
        ctx.write_data(NAME, &Data { rows, switch, picture, crate_picture, dual_picture, options })
    }

    fn section(&self, ctx: &Context) -> Result<String, ExperimentError> {
        page::section(ctx)
    }
}
