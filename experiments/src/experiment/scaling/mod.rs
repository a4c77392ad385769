//! `scaling`: how every extractor's time and memory grow with the grid, and how it uses threads
//! (issue 7, "how far from the limit" and "scaling"). The built-in `sphere` sampled on cubic grids
//! of 32³ to 512³ samples; each registered extractor run on the same samples on one thread (in a
//! pool of one) and on two (on rayon's global pool, called from outside it as the command line
//! calls), alternating, median of the runs (one run each at 512³). Reported per run:
//! - time, the speed-up from the second thread, and the slope of log time against log cells
//!   (about 1: bound by the cells; about 2/3: bound by the surface);
//! - time as a multiple of the machine's memory floor for that grid and output (one streaming read
//!   of the samples plus one write of the output's bytes, measured here, as in `peers`);
//! - peak heap during the extraction (a counting global allocator, [`crate::alloc_meter`], fresh
//!   extractor and output buffers) against the bytes of grid plus output.
//!
//! An extractor whose one-thread run passes `BUDGET_S` is not run on larger grids (8× the cells);
//! the report lists what was left out and why.

mod data;
mod page;

use super::context::{Context, Experiment, ExperimentError};
use crate::alloc_meter;
use crate::figures::plot::{self, Scale, Series, Style, XyPlot};
use crate::report::median;
use data::{Data, Row};
use isolab_algorithms::extractors::INFOS;
use isolab_algorithms::options::Options;
use isolab_algorithms::{fields, Extraction, Extractor, Grid, Samples};
use page::algorithms;
use std::time::Duration;

/// The experiment.
pub struct Scaling;

const NAME: &str = "scaling";

const FIELD: &str = "sphere";

/// Samples per side.
const SIZES: [usize; 5] = [32, 64, 128, 256, 512];

/// Thread counts compared.
const THREADS: [usize; 2] = [1, 2];

/// A one-thread run longer than this (seconds) stops an extractor's climb to larger grids.
const BUDGET_S: f64 = 6.0;

/// Runs per configuration and protocol at most (the report's repeats, capped).
const MAX_REPEATS: usize = 5;

/// From this grid size on, one run per configuration.
const SINGLE_RUN_FROM: usize = 512;

/// The slopes are fitted from this grid size on.
const SLOPE_FROM: usize = 64;

/// Bytes of the extraction's meshes as stored (positions, normals, indices).
fn output_bytes(out: &Extraction) -> usize {
    let s = &out.surface;
    s.positions.len() * 12
        + s.normals.len() * 12
        + s.triangles.len() * 12
        + out.volume.positions.len() * 12
        + out.volume.tetrahedra.len() * 16
}

/// A fresh extractor (no scratch held from earlier runs).
fn fresh(index: usize) -> Result<Box<dyn Extractor>, ExperimentError> {
    (INFOS[index].make)(&Options::new())
        .map_err(|e| ExperimentError::Failed { what: format!("building {}", INFOS[index].name), reason: e.to_string() })
}

/// Runs `extractor` on `samples` with `pool`'s thread count: the extraction time. When rayon's
/// global pool has that many threads (more than one) and this thread is in no pool, the call
/// runs from here on the global pool, as the command line and `peers` call, so the slab phases
/// wake every pool thread at once ([`crate::peers::ours::caller_outside`]); otherwise inside `pool`.
fn timed(
    pool: &rayon::ThreadPool,
    extractor: &dyn Extractor,
    samples: &Samples,
    out: &mut Extraction,
) -> Result<Duration, ExperimentError> {
    if on_global_pool(pool.current_num_threads()) {
        extractor.extract(samples, out)?;
    } else {
        pool.install(|| extractor.extract(samples, out))?;
    }
    Ok(out.stats.times.extraction())
}

/// Whether [`timed`] runs `threads` threads from this thread on the global pool.
fn on_global_pool(threads: usize) -> bool {
    threads > 1 && crate::peers::ours::caller_outside(threads)
}

impl Experiment for Scaling {
    fn name(&self) -> &'static str {
        NAME
    }

    fn question(&self) -> &'static str {
        "How do time and memory grow with the grid and with the threads?"
    }

    fn run(&self, ctx: &Context) -> Result<(), ExperimentError> {
        let pools = THREADS
            .iter()
            .map(|&t| rayon::ThreadPoolBuilder::new().num_threads(t).build())
            .collect::<Result<Vec<_>, _>>()
            .map_err(|e| ExperimentError::ThreadPool(e.to_string()))?;
        let metered = alloc_meter::installed();
        let field = fields::builtin(FIELD, Default::default())?;
        let mut alive: Vec<bool> = vec![true; INFOS.len()];
        let mut rows = Vec::new();
        let mut skipped = Vec::new();
        if !metered {
            skipped.push("peak memory: this binary does not install the counting allocator".to_owned());
        }
        // A quick run: up to 128³.
        let sizes = ctx.pick(&SIZES[..], &SIZES[..3]);
        let bar = ctx.bar(NAME, (sizes.len() * INFOS.len()) as u64);
        for &n in sizes {
            let grid = Grid::covering(&field.domain(), n)?;
            let samples = Samples::sample_cubic(field.clone(), grid, 0.0)?;
            let grid_bytes = samples.values().len() * 4;
            let runs = if n >= SINGLE_RUN_FROM { 1 } else { ctx.repeats.min(MAX_REPEATS) };
            for (index, info) in INFOS.iter().enumerate() {
                bar.set_message(format!("{} {n}³", info.name));
                if !alive[index] {
                    bar.inc(1);
                    continue;
                }
                // Memory first, on a fresh extractor and output, one thread.
                let extractor = fresh(index)?;
                let mut out = Extraction::default();
                let (first, peak) = alloc_meter::peak_since(|| timed(&pools[0], extractor.as_ref(), &samples, &mut out));
                let first = first?;
                // Alternating: per run, each thread count steady state then one-shot.
                let mut times: Vec<Vec<Duration>> = vec![Vec::new(); THREADS.len()];
                let mut one_shot: Vec<Vec<Duration>> = vec![Vec::new(); THREADS.len()];
                for _ in 0..runs {
                    for (k, pool) in pools.iter().enumerate() {
                        times[k].push(timed(pool, extractor.as_ref(), &samples, &mut out)?);
                        let fresh_extractor = fresh(index)?;
                        one_shot[k].push(timed(pool, fresh_extractor.as_ref(), &samples, &mut Extraction::default())?);
                    }
                }
                let spread_of = |t: &[Vec<Duration>]| -> Vec<[f64; 2]> {
                    t.iter()
                        .map(|v| {
                            let ms = v.iter().map(|d| d.as_secs_f64() * 1e3);
                            [ms.clone().fold(f64::INFINITY, f64::min), ms.fold(0.0, f64::max)]
                        })
                        .collect()
                };
                let (spread, one_shot_spread) = (spread_of(&times), spread_of(&one_shot));
                let one_shot_ms: Vec<f64> = one_shot.into_iter().map(|t| median(t).as_secs_f64() * 1e3).collect();
                let bytes = output_bytes(&out);
                let floor: Vec<Duration> = (0..runs.max(2))
                    .map(|_| {
                        let (r, w) = crate::memory::floor(samples.values(), bytes);
                        r + w
                    })
                    .collect();
                let ms: Vec<f64> = times.into_iter().map(|t| median(t).as_secs_f64() * 1e3).collect();
                rows.push(Row {
                    algorithm: info.name.to_owned(),
                    n,
                    cells: grid.dims.iter().map(|d| d.saturating_sub(1)).product(),
                    ms: ms.clone(),
                    spread,
                    one_shot_ms,
                    one_shot_spread,
                    runs,
                    triangles: out.surface.triangles.len(),
                    tetrahedra: out.volume.tetrahedra.len(),
                    floor_ms: median(floor).as_secs_f64() * 1e3,
                    grid_bytes,
                    output_bytes: bytes,
                    peak_bytes: peak,
                });
                let one_thread_s = ms[0].max(first.as_secs_f64() * 1e3) / 1e3;
                if one_thread_s > BUDGET_S && n != *sizes.last().unwrap_or(&n) {
                    alive[index] = false;
                    let next = sizes.iter().find(|&&m| m > n).copied().unwrap_or(n);
                    skipped.push(format!(
                        "{} above {n}³: one thread took {one_thread_s:.1} s at {n}³ (over the {BUDGET_S} s budget; the next grid has {}× the cells)",
                        info.name,
                        (next * next * next) / (n * n * n).max(1)
                    ));
                }
                bar.inc(1);
            }
        }
        bar.finish_with_message("done");
        let global_pool_threads = THREADS.iter().copied().find(|&t| on_global_pool(t));
        let built: Vec<Box<dyn Extractor>> = (0..INFOS.len()).map(fresh).collect::<Result<_, _>>()?;
        let settings = super::context::settings_of(built.iter().map(|e| &**e));
        let data = Data { field: FIELD.into(), threads: THREADS.to_vec(), rows, skipped, global_pool_threads, settings };
        figures(ctx, &data)?;
        ctx.write_data(NAME, &data)
    }

    fn section(&self, ctx: &Context) -> Result<String, ExperimentError> {
        page::section(ctx)
    }
}

fn figures(ctx: &Context, data: &Data) -> Result<(), ExperimentError> {
    let dir = ctx.figure_dir(NAME)?;
    let names = algorithms(data);
    let series = |thread: usize| -> Vec<Series> {
        names
            .iter()
            .map(|name| Series {
                label: name.clone(),
                color: crate::figures::color_of(name),
                points: data.rows.iter().filter(|r| &r.algorithm == name).map(|r| (r.cells as f64, r.ms[thread])).collect(),
                // Rows written before spreads were kept have none: no bars then.
                ranges: data
                    .rows
                    .iter()
                    .filter(|r| &r.algorithm == name)
                    .map_while(|r| r.spread.get(thread).map(|s| (s[0], s[1])))
                    .collect(),
            })
            .collect()
    };
    for (k, &t) in data.threads.iter().enumerate() {
        let chart = XyPlot {
            title: format!("Extraction time against cells, {}, {t} thread{}", data.field, if t == 1 { "" } else { "s" }),
            x_label: "cells".into(),
            y_label: "ms (median; bars: fastest to slowest run)".into(),
            x_scale: Scale::Log,
            y_scale: Scale::Log,
            style: Style::Lines,
            series: series(k),
        };
        plot::xy(&dir.join(format!("time-{t}-threads")), &chart).map_err(ExperimentError::Figure)?;
    }
    Ok(())
}

/// The target for the second thread (one-thread time over two-thread time).
const SECOND_THREAD_TARGET: f64 = 1.6;

/// The extractors and grid the target is set for.
const SECOND_THREAD_EXTRACTORS: [&str; 2] = ["marching-cubes", "surface-nets"];

/// See [`SECOND_THREAD_EXTRACTORS`].
const SECOND_THREAD_GRID: usize = 256;

/// Slopes from this one up read as "grows with the cells", from [`SURFACE_SLOPE_FROM`] up as
/// "grows with the surface" (whose exponent is 2/3 on the sphere), below as "hardly driven by
/// the grid".
const CELLS_SLOPE_FROM: f64 = 0.9;

/// See [`CELLS_SLOPE_FROM`].
const SURFACE_SLOPE_FROM: f64 = 0.55;

#[cfg(test)]
mod tests {
    use super::page::reading;
    use super::*;
    use crate::report::log_slope;

    fn row(algorithm: &str, n: usize, ms: [f64; 2]) -> Row {
        Row {
            algorithm: algorithm.into(),
            n,
            cells: n * n * n,
            ms: ms.to_vec(),
            spread: Vec::new(),
            one_shot_ms: ms.to_vec(),
            one_shot_spread: Vec::new(),
            runs: 1,
            triangles: 0,
            tetrahedra: 0,
            floor_ms: 1.0,
            grid_bytes: 0,
            output_bytes: 0,
            peak_bytes: None,
        }
    }

    #[test]
    fn the_reading_follows_the_rows() {
        let mut data = Data {
            field: "sphere".into(),
            threads: vec![1, 2],
            rows: Vec::new(),
            skipped: Vec::new(),
            global_pool_threads: None,
            settings: Vec::new(),
        };
        assert_eq!(reading(&data), "");
        // Time times 8 per doubling (slope 1), times 4 (slope 2/3), times 1 (slope 0).
        for (k, n) in [64usize, 128, 256].into_iter().enumerate() {
            let f = k as i32;
            data.rows.push(row("marching-cubes", n, [8f64.powi(f), 8f64.powi(f) / 2.0]));
            data.rows.push(row("surface-nets", n, [4f64.powi(f) * 3.0, 4f64.powi(f)]));
            data.rows.push(row("bcc-sculpt", n, [100.0, 90.0]));
        }
        let r = reading(&data);
        assert!(r.contains("with the cells (from 0.9): marching-cubes 1.00; with the surface (0.55 to 0.9): surface-nets 0.67; hardly driven by the grid: bcc-sculpt 0.00."), "{r}");
        assert!(r.contains("At 256³ on 1 thread, steady state: fastest surface-nets (48"), "{r}");
        assert!(r.contains("slowest bcc-sculpt (100 ms)"), "{r}");
        assert!(r.contains("`marching-cubes` one-shot 2.00×, steady state 2.00×; `surface-nets` one-shot 3.00×"), "{r}");
    }

    #[test]
    fn slopes_of_power_laws() {
        let cubic: Vec<(f64, f64)> = [1.0, 2.0, 4.0, 8.0].iter().map(|&x: &f64| (x, 3.0 * x.powi(3))).collect();
        assert!((log_slope(&cubic).unwrap() - 3.0).abs() < 1e-9);
        let flat = [(1.0, 5.0), (10.0, 5.0)];
        assert!(log_slope(&flat).unwrap().abs() < 1e-12);
        assert_eq!(log_slope(&[(1.0, 1.0)]), None);
        assert_eq!(log_slope(&[(1.0, 1.0), (1.0, 2.0)]), None);
    }
}
