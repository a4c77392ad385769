//! Criterion benchmark of the whole `bcc-sculpt` pipeline (lattice, sculpting, defusing, ODT
//! relaxation with collision tests) on the Stanford bunny at h = longest side / 8 (about 2,500
//! tetrahedra), offset ratio 0.6, one lattice. The paper (Stuart et al. 2013): "a few minutes" per
//! run, unoptimised; the issue aims for well under a second. Phases are benchmarked separately too.

use criterion::{criterion_group, criterion_main, Criterion};
use isolab_algorithms::extractors::bcc_sculpt::{bcc_lattice, defuse_bombs, sculpt, sculpt_surface, SculptOptions};
use isolab_experiments::experiment::load_object;
use std::time::Duration;

fn pipeline(c: &mut Criterion) {
    let field = load_object("stanford-bunny").unwrap();
    let surface = field.surface_mesh().unwrap();
    let options = SculptOptions { cells: 8, offset_ratio: 0.6, ..Default::default() };
    let tets = sculpt_surface(surface, "bunny", &options).unwrap().report.tetrahedra;
    let mut group = c.benchmark_group(format!("bunny-h8-{tets}tets"));
    group.sample_size(10).measurement_time(Duration::from_secs(10));
    group.bench_function("bcc-sculpt/whole-pipeline", |b| b.iter(|| sculpt_surface(surface, "bunny", &options).unwrap()));
    let h = f64::from(surface.bounds().longest_side()) / 8.0;
    let lattice = bcc_lattice(surface.bounds(), h, glam::DQuat::IDENTITY, glam::DVec3::ZERO);
    group.bench_function("bcc-sculpt/lattice", |b| {
        b.iter(|| bcc_lattice(surface.bounds(), h, glam::DQuat::IDENTITY, glam::DVec3::ZERO))
    });
    group.bench_function("bcc-sculpt/sculpting", |b| b.iter(|| sculpt(&lattice, surface)));
    let kept = sculpt(&lattice, surface);
    group.bench_function("bcc-sculpt/defusing", |b| {
        b.iter(|| {
            let mut keep = kept.clone();
            defuse_bombs(&lattice, &mut keep)
        })
    });
    group.finish();
}

criterion_group!(benches, pipeline);
criterion_main!(benches);
