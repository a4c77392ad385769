//! `svoboda_timing`: the deformable-terrain paper's Table 1
//! (`../shared/papers/svoboda-2020-marching-cubes-deformable-terrain.txt`, section 6: marching
//! cubes on a Perlin-noise terrain, 1 to 50 cubes a side, its Unity/C# implementation on an i5 at
//! 3.5 GHz: 83 ms at 50³), regenerated with our marching cubes on the `terrain` field, then on to
//! 256³, with the other surface extractors beside it. The grid has N cubes a side (N + 1 samples);
//! times are medians of many runs, extraction alone (the paper's "time to triangulate") and with
//! sampling.

mod data;
mod page;

use super::context::{Context, Experiment, ExperimentError};
use crate::figures::plot::{self, Scale, Series, Style, XyPlot};
use crate::report::median;
use data::Data;
pub use data::{LikeRow, Row};
use isolab_algorithms::extractors;
use isolab_algorithms::{fields, Extraction, Grid, Lattice, Samples};
use std::time::{Duration, Instant};

mod paper;

/// The experiment.
pub struct SvobodaTiming;

const NAME: &str = "svoboda_timing";

/// Cubes a side: the paper's six sizes, then ours.
const SIZES: [usize; 9] = [1, 10, 20, 30, 40, 50, 64, 128, 256];

/// The paper's Table 1, ms (`< 1` at 1³ shown as 1).
const PAPER: [(usize, f64); 6] = [(1, 1.0), (10, 1.0), (20, 6.0), (30, 19.0), (40, 44.0), (50, 83.0)];

/// The paper's machine: an Intel i5 at this clock, GHz.
const PAPER_CPU_GHZ: f64 = 3.5;

const ALGORITHMS: [&str; 4] = ["marching-cubes", "surface-nets", "marching-tetrahedra", "regularised-marching-tetrahedra"];

/// The paper's sizes on the paper's field: its unshared marching cubes and ours, alternating, on
/// one thread, each with fresh output.
fn like_for_like() -> Result<Vec<LikeRow>, ExperimentError> {
    let field: std::sync::Arc<dyn isolab_algorithms::Field> = std::sync::Arc::new(paper::PaperField::default());
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().map_err(|e| ExperimentError::ThreadPool(e.to_string()))?;
    let mc = extractors::by_name("marching-cubes").ok_or_else(|| ExperimentError::Missing("extractor marching-cubes".into()))?;
    let mut rows = Vec::new();
    for (cubes, _) in PAPER {
        let n = cubes + 1;
        let grid = Grid::with_dims(&field.domain(), [n, n, n])?;
        let samples = Samples::sample(field.clone(), Lattice::Cubic(grid), 0.0)?;
        let runs = runs_for(cubes);
        let (mut unshared, mut shared) = (Vec::with_capacity(runs), Vec::with_capacity(runs));
        let (mut triangles, mut vertices) = (0, [0, 0]);
        for _ in 0..runs {
            let start = Instant::now();
            let (v, t) = paper::unshared_marching_cubes(samples.values(), &grid, samples.iso());
            unshared.push(start.elapsed());
            let out = pool.install(|| {
                let start = Instant::now();
                let mut out = Extraction::default();
                let result = mc.extract(&samples, &mut out);
                shared.push(start.elapsed());
                result.map(|()| out)
            })?;
            triangles = t;
            vertices = [v.len(), out.surface.positions.len()];
        }
        rows.push(LikeRow {
            cubes,
            unshared_ms: median(unshared).as_secs_f64() * 1e3,
            shared_ms: median(shared).as_secs_f64() * 1e3,
            triangles,
            vertices,
            runs,
        });
    }
    Ok(rows)
}

/// More runs for small grids, where one run is microseconds.
fn runs_for(cubes: usize) -> usize {
    match cubes {
        0..=20 => 101,
        21..=64 => 31,
        65..=128 => 9,
        _ => 5,
    }
}

impl Experiment for SvobodaTiming {
    fn name(&self) -> &'static str {
        NAME
    }

    fn question(&self) -> &'static str {
        "How long does one triangulation of a deformable terrain take, beside Svoboda's table?"
    }

    fn run(&self, ctx: &Context) -> Result<(), ExperimentError> {
        let field = fields::builtin("terrain", Default::default())?;
        let bar = ctx.bar(NAME, SIZES.len() as u64);
        let built: Vec<_> = ALGORITHMS.iter().filter_map(|a| extractors::by_name(a)).collect();
        let mut rows = Vec::new();
        for cubes in SIZES {
            let n = cubes + 1;
            let grid = Grid::with_dims(&field.domain(), [n, n, n])?;
            let runs = runs_for(cubes);
            let mut sampling = Vec::with_capacity(runs);
            let mut samples = Samples::sample(field.clone(), Lattice::Cubic(grid), 0.0)?;
            let mut times: Vec<Vec<Duration>> = vec![Vec::with_capacity(runs); built.len()];
            let mut outs: Vec<Extraction> = built.iter().map(|_| Extraction::default()).collect();
            for _ in 0..runs {
                samples = Samples::sample(field.clone(), Lattice::Cubic(grid), 0.0)?;
                sampling.push(samples.sampling_time());
                // Alternating, buffers reused (steady-state re-meshing, as in a game).
                for (k, e) in built.iter().enumerate() {
                    e.extract(&samples, &mut outs[k])?;
                    times[k].push(outs[k].stats.times.extraction());
                }
            }
            let sampling_ms = median(sampling).as_secs_f64() * 1e3;
            for (k, e) in built.iter().enumerate() {
                rows.push(Row {
                    algorithm: e.name().into(),
                    cubes,
                    extraction_ms: median(std::mem::take(&mut times[k])).as_secs_f64() * 1e3,
                    sampling_ms,
                    triangles: outs[k].surface.triangles.len(),
                    runs,
                });
            }
            drop(samples);
            bar.inc(1);
        }
        bar.finish();
        let dir = ctx.figure_dir(NAME)?;
        let mut series: Vec<Series> = ALGORITHMS
            .iter()
            .map(|a| Series {
                label: format!("isolab {a}"),
                color: crate::figures::color_of(a),
                points: rows
                    .iter()
                    .filter(|r| r.algorithm == *a && r.cubes > 1)
                    .map(|r| ((r.cubes as f64).powi(3), r.extraction_ms))
                    .collect(),
                ranges: Vec::new(),
            })
            .collect();
        series.push(Series {
            label: "Svoboda 2020 (Unity, C#)".into(),
            color: (0, 0, 0),
            points: PAPER.iter().filter(|p| p.0 > 1).map(|&(c, ms)| ((c as f64).powi(3), ms)).collect(),
            ranges: Vec::new(),
        });
        let chart = XyPlot {
            title: "Time to triangulate a noise terrain once".into(),
            x_label: "cubes".into(),
            y_label: "ms (median)".into(),
            x_scale: Scale::Log,
            y_scale: Scale::Log,
            style: Style::Lines,
            series,
        };
        plot::xy(&dir.join("time"), &chart).map_err(ExperimentError::Figure)?;
        let like_for_like = like_for_like()?;
        let settings = super::context::settings_of(built.iter().map(|e| &**e));
        ctx.write_data(NAME, &Data { rows, like_for_like, settings })
    }

    fn section(&self, ctx: &Context) -> Result<String, ExperimentError> {
        page::section(ctx)
    }
}

#[cfg(test)]
mod tests {
    use super::page::{differences, reading};
    use super::*;

    #[test]
    fn the_reading_follows_the_rows() {
        let mut data = Data { rows: Vec::new(), like_for_like: Vec::new(), settings: Vec::new() };
        assert_eq!(reading(&data), "");
        let row = |algorithm: &str, ms: f64| Row {
            algorithm: algorithm.into(),
            cubes: 50,
            extraction_ms: ms,
            sampling_ms: 1.0,
            triangles: 1,
            runs: 1,
        };
        data.rows = vec![row("surface-nets", 2.0), row("marching-cubes", 0.83)];
        data.like_for_like =
            vec![LikeRow { cubes: 50, unshared_ms: 1.0, shared_ms: 0.5, triangles: 1, vertices: [6, 4], runs: 1 }];
        let r = reading(&data);
        assert!(r.starts_with("**Reading.** Like for like at 50³"), "the like-for-like figure leads: {r}");
        assert!(r.contains("takes 0.83 ms at 50³ (100× less than Table 1's figure, a ratio that crosses"), "{r}");
        assert!(r.contains("runs 83× faster here than in the paper"), "{r}");
        assert!(r.contains("and sharing vertices makes ours 2.0× faster"), "{r}");
        // The comparison words follow the numbers: sharing that costs time says so.
        let mut slower =
            Data { rows: vec![row("marching-cubes", 0.83)], like_for_like: data.like_for_like.clone(), settings: Vec::new() };
        slower.like_for_like[0].shared_ms = 2.0;
        assert!(reading(&slower).contains("sharing vertices makes ours 2.0× slower"), "{}", reading(&slower));
        assert!(r.contains("fastest first: marching-cubes 0.83 ms, surface-nets 2.00 ms."), "{r}");
        let d = differences(&data);
        assert!(d.contains("### Where we differ from the paper"), "{d}");
        assert!(d.contains("(6 at 50³ here), ours shares them (4)"), "{d}");
        assert!(d.contains("Table 1's 83 ms at 50³ against 1.00 ms"), "{d}");
    }
}
