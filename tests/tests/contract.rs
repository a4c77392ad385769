//! The contract every registered extractor keeps, checked for every entry of
//! `extractors::INFOS`, so an extractor is tested the day it is registered. Its promises are
//! data (`ExtractorInfo::guarantees`); what it does not promise is not checked here.
//!
//! On smooth blobs and white-noise sign fields, on both lattices (random ones from proptest):
//! - a lattice it does not declare is refused with `ExtractError::UnsupportedLattice`;
//! - where the field changes sign inside the lattice the surface is not empty, and where it does
//!   not the surface is empty (and no error);
//! - closed, manifold, outward and free of self-intersections wherever it declares so; the
//!   trilinear interpolant's topology in every cell where it declares so (every sign pattern of
//!   one cell, random corner values, against a fine sampling of the interpolant); where the
//!   surface leaves the lattice (inside samples on its border: white noise, a tilted plane, a
//!   saddle), closed means open only along the lattice's border (every boundary edge within one
//!   cell of it), and outward means consistently wound;
//! - every tetrahedron positively oriented with its dihedral angles in the declared interval, where
//!   one is declared;
//! - the stats agree with the output (`finish_counts` called: vertex, triangle and tetrahedron
//!   counts), the sampling time is copied, the stage times are filled, normals are one per
//!   vertex or none, every index is in range;
//! - the same output on one thread and on two;
//! - re-extraction into a used `Extraction` equals extraction into a fresh one.
//!
//! Every post-process in `POST_INFOS` likewise keeps what its `guarantees` promise, on marching
//! tetrahedra of random blobs, and fills its stats and post time.
//!
//! `ISOLAB_CONTRACT_CASES=N` runs N random cases per property instead of 12 (a soak run).

use glam::Vec3;
use isolab_algorithms::extractors::{self, ExtractorInfo};
use isolab_algorithms::{post, ExtractError, Extraction, Extractor, Options, Samples};
use isolab_metrics::{self_intersections, topology};
use isolab_tests::{
    cell_samples, cell_shape, interpolant_shape, lattice_blobs, lattice_samples, near_critical, tunnel_corner_values,
    unit_cube_samples,
};
use proptest::prelude::*;

/// [`isolab_tests::unit_cube_samples`] under the name the tests here use.
fn field_samples(bcc: bool, n: usize, value: impl FnMut(Vec3) -> f32) -> Samples<'static> {
    unit_cube_samples(bcc, n, value)
}

/// Gaussian blobs `(centre, radius)` in the unit cube: inside where they are dense.
fn blobs(bcc: bool, n: usize, blobs: &[(Vec3, f32)], threshold: f32) -> Samples<'static> {
    lattice_blobs(bcc, n, blobs, threshold)
}

/// Random blobs for the property tests: 1 to 4 `(centre, radius)` well inside the unit cube.
fn random_blobs() -> impl Strategy<Value = Vec<(Vec3, f32)>> {
    prop::collection::vec((0.2f32..0.8, 0.2f32..0.8, 0.2f32..0.8, 0.08f32..0.3), 1..5)
        .prop_map(|v| v.into_iter().map(|(x, y, z, r)| (Vec3::new(x, y, z), r)).collect())
}

/// White-noise values from a seed: in ±[0.1, 1], none at the iso-value, inside (negative) with
/// probability 0.45.
fn white_noise(seed: u64) -> impl FnMut() -> f32 {
    let mut random = isolab_algorithms::random::Random::new(seed);
    move || {
        let v = 0.1 + 0.9 * random.unit() as f32;
        if random.unit() < 0.45 {
            -v
        } else {
            v
        }
    }
}

/// A white-noise sign field from a seed, outside on the border ([`white_noise`]).
fn noise(bcc: bool, n: usize, seed: u64) -> Samples<'static> {
    let mut value = white_noise(seed);
    field_samples(bcc, n, |_| value())
}

/// Random cases per property: 12, or `ISOLAB_CONTRACT_CASES` for a soak run.
fn soak_cases() -> u32 {
    std::env::var("ISOLAB_CONTRACT_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(12)
}

fn build(info: &ExtractorInfo) -> Box<dyn Extractor> {
    (info.make)(&Options::new()).unwrap_or_else(|e| panic!("{}: default options fail: {e}", info.name))
}

fn supports(info: &ExtractorInfo, samples: &Samples) -> bool {
    match samples.lattice() {
        isolab_algorithms::Lattice::Cubic(_) => info.guarantees.cubic,
        isolab_algorithms::Lattice::Bcc(_) => info.guarantees.bcc,
    }
}

/// Extraction on a rayon pool of `threads`.
fn extract_on(threads: usize, e: &dyn Extractor, samples: &Samples, out: &mut Extraction) -> Result<(), ExtractError> {
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("thread pool");
    pool.install(|| e.extract(samples, out))
}

/// The contract on one input, `what` naming it in failures. `crosses`: whether the field
/// changes sign inside the lattice. `other`: a different input, extracted first into the buffer
/// the re-extraction check reuses.
fn check(info: &ExtractorInfo, samples: &Samples, crosses: bool, other: &Samples, what: &str) {
    let e = build(info);
    let what = format!("{} on {what} ({})", info.name, samples.lattice().kind());
    let mut out = Extraction::default();
    let result = extract_on(2, e.as_ref(), samples, &mut out);
    if !supports(info, samples) {
        assert!(
            matches!(result, Err(ExtractError::UnsupportedLattice { .. })),
            "{what}: must refuse the lattice, got {result:?}"
        );
        return;
    }
    result.unwrap_or_else(|err| panic!("{what}: {err}"));
    let mesh = &out.surface;
    // An extractor that may lose small parts may be empty where the field changes sign.
    let may_lose = !info.guarantees.keeps_small_parts && mesh.triangles.is_empty();
    assert_eq!(
        mesh.triangles.is_empty(),
        !crosses || may_lose,
        "{what}: {} triangles where the field {} sign",
        mesh.triangles.len(),
        if crosses { "changes" } else { "keeps its" }
    );
    let n = mesh.positions.len() as u32;
    assert!(mesh.triangles.iter().flatten().all(|&i| i < n), "{what}: index out of range");
    assert!(
        mesh.normals.is_empty() || mesh.normals.len() == mesh.positions.len(),
        "{what}: {} normals for {} vertices",
        mesh.normals.len(),
        n
    );
    // Stats agree with the output.
    let s = &out.stats;
    assert_eq!((s.vertices, s.triangles), (mesh.positions.len(), mesh.triangles.len()), "{what}: stats counts (finish_counts?)");
    assert_eq!(s.tetrahedra, out.volume.tetrahedra.len(), "{what}: stats tetrahedra");
    assert_eq!(s.times.sampling, samples.sampling_time(), "{what}: sampling time not copied");
    if crosses {
        assert!(s.times.extraction() > std::time::Duration::ZERO, "{what}: no stage time filled");
    }
    // Declared guarantees.
    let g = info.guarantees;
    if crosses {
        let t = topology(mesh);
        let leaves = leaves_the_lattice(samples);
        if g.closed && leaves {
            let stray = boundary_edges_off_the_border(mesh, samples);
            assert!(stray.is_empty(), "{what}: declared closed, but open inside the lattice at {stray:?}");
        } else if g.closed {
            assert!(t.closed && t.boundary_edges == 0, "{what}: declared closed: {t:#?}");
        }
        if g.manifold {
            assert!(t.edge_manifold && t.vertex_manifold && t.unused_vertices == 0, "{what}: declared manifold: {t:#?}");
        }
        if g.outward {
            assert!(t.oriented && (leaves || t.outward), "{what}: declared outward: {t:#?}");
        }
        if g.intersection_free {
            let x = self_intersections(mesh);
            assert_eq!(x.count, 0, "{what}: declared free of self-intersections: {:?}", x.pairs);
        }
    }
    if let Some(interval) = g.dihedral {
        let v = &out.volume;
        for (i, tet) in v.tetrahedra.iter().enumerate() {
            let p = tet.map(|k| v.positions[k as usize]);
            let [a, b, c, d] = p.map(|x| x.as_dvec3());
            assert!((b - a).dot((c - a).cross(d - a)) > 0.0, "{what}: tetrahedron {i} inverted or flat: {p:?}");
            for angle in isolab_algorithms::geometry::dihedral_angles(p) {
                assert!(
                    interval.contains(angle),
                    "{what}: tetrahedron {i} has a {angle:.3}° dihedral angle, outside {interval:?}"
                );
            }
        }
    }
    // One thread and two give the same output.
    let mut serial = Extraction::default();
    extract_on(1, e.as_ref(), samples, &mut serial).unwrap_or_else(|err| panic!("{what}: {err}"));
    assert!(serial.surface == out.surface && serial.volume == out.volume, "{what}: one thread and two differ");
    // Re-extraction into a used buffer equals extraction into a fresh one.
    let mut used = Extraction::default();
    let _ = extract_on(2, e.as_ref(), other, &mut used);
    extract_on(2, e.as_ref(), samples, &mut used).unwrap_or_else(|err| panic!("{what}: {err}"));
    assert!(used.surface == out.surface && used.volume == out.volume, "{what}: a used buffer gives another output");
    assert_eq!(
        (used.stats.vertices, used.stats.triangles, used.stats.tetrahedra, &used.stats.warnings),
        (s.vertices, s.triangles, s.tetrahedra, &s.warnings),
        "{what}: a used buffer gives other stats"
    );
}

fn every_extractor(samples: &Samples, crosses: bool, other: &Samples, what: &str) {
    assert!(!extractors::INFOS.is_empty());
    for info in extractors::INFOS {
        check(info, samples, crosses, other, what);
    }
}

#[test]
fn fixed_fields_on_both_lattices() {
    for bcc in [false, true] {
        let n = if bcc { 10 } else { 14 };
        let sphere = blobs(bcc, n, &[(Vec3::splat(0.5), 0.3)], 0.5);
        let two = blobs(bcc, n, &[(Vec3::new(0.3, 0.4, 0.5), 0.15), (Vec3::new(0.7, 0.6, 0.5), 0.2)], 0.5);
        let outside = field_samples(bcc, n, |_| 1.0);
        let inside_core = field_samples(bcc, n, |_| -1.0);
        every_extractor(&sphere, true, &two, "one blob");
        every_extractor(&two, true, &sphere, "two blobs");
        every_extractor(&outside, false, &sphere, "no inside");
        // Inside everywhere but the border: one closed surface along the border.
        every_extractor(&inside_core, true, &outside, "inside but the border");
        every_extractor(&noise(bcc, 6, 7), true, &sphere, "white noise 6³, seed 7");
        // Many samples exactly at the iso-value (the gyroid has whole planes of them): vertices
        // must not meet at those samples.
        every_extractor(&on_iso(bcc, n, 11), true, &sphere, "values in {-1, 0, 1}");
    }
}

/// Whether some sample on the lattice's border is inside: the surface then leaves the lattice.
fn leaves_the_lattice(samples: &Samples) -> bool {
    let [nx, ny, nz] = samples.grid().dims;
    let (iso, values) = (samples.iso(), samples.values());
    (0..nz).any(|z| {
        (0..ny).any(|y| {
            (0..nx).any(|x| {
                let border = x == 0 || y == 0 || z == 0 || x + 1 == nx || y + 1 == ny || z + 1 == nz;
                border && values[x + nx * (y + ny * z)] < iso
            })
        })
    })
}

/// The boundary edges (used by one triangle) of `mesh` with an end farther than one cell from
/// the border of `samples`' cubic grid: where a surface that leaves the lattice is open although
/// it should not be.
fn boundary_edges_off_the_border(mesh: &isolab_algorithms::TriMesh, samples: &Samples) -> Vec<[u32; 2]> {
    let grid = samples.grid();
    let (lo, hi) = (grid.origin, grid.position(grid.dims[0] - 1, grid.dims[1] - 1, grid.dims[2] - 1));
    let near_border = |i: u32| {
        let p = mesh.positions[i as usize];
        let d = (p - lo).min(hi - p).min_element();
        d <= grid.spacing * 1.0001
    };
    let mut uses = std::collections::HashMap::<[u32; 2], usize>::new();
    for t in &mesh.triangles {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            *uses.entry([a.min(b), a.max(b)]).or_default() += 1;
        }
    }
    let mut stray: Vec<[u32; 2]> =
        uses.into_iter().filter(|&(e, n)| n == 1 && !(near_border(e[0]) && near_border(e[1]))).map(|(e, _)| e).collect();
    stray.sort_unstable();
    stray
}

/// White noise on the whole lattice, its border included: the surface leaves the lattice
/// everywhere, through every kind of boundary cell (faces, edges and corners of the domain, and
/// ambiguous faces on the border).
fn open_noise(bcc: bool, n: usize, seed: u64) -> Samples<'static> {
    let mut value = white_noise(seed);
    lattice_samples(bcc, [n, n, n], |_| value())
}

#[test]
fn surfaces_that_leave_the_lattice() {
    for bcc in [false, true] {
        let n = if bcc { 6 } else { 9 };
        let last = 2.0 * (n - 1) as f32;
        // Doubled lattice coordinates: a tilted plane and a saddle, both cut by the border.
        let plane = lattice_samples(bcc, [n, n, n], |d| d[0] as f32 + 0.37 * d[1] as f32 - 0.21 * d[2] as f32 - 0.45 * last);
        let saddle = lattice_samples(bcc, [n, n, n], |d| {
            let [x, y, z] = d.map(|c| c as f32 / last - 0.5);
            x * x - y * y + 0.3 * z - 0.013
        });
        let sphere = blobs(bcc, n, &[(Vec3::splat(0.5), 0.3)], 0.5);
        every_extractor(&plane, true, &sphere, "a tilted plane through the lattice");
        every_extractor(&saddle, true, &sphere, "a saddle through the lattice");
        for seed in 0..24 {
            for info in extractors::INFOS {
                // Volume extractors on a few seeds only: bcc-sculpt takes seconds on each.
                let volume = build(info).produces_volume();
                if volume && seed >= 2 {
                    continue;
                }
                let n = if volume { 4 } else { 3 + (seed as usize % 5) };
                let samples = open_noise(bcc, n, seed);
                let crosses = samples.values().iter().any(|&v| v < 0.0);
                check(info, &samples, crosses, &sphere, &format!("white noise {n}³ to the border, seed {seed}"));
            }
        }
    }
}

/// Every extractor that declares `trilinear_topology`: on every sign pattern of one cell, with
/// random corner values that open and close tunnels, the cell's mesh has the components and Euler
/// characteristic of its trilinear interpolant's level set (a fine sampling of it; draws within a
/// hair of a critical value, which the sampling cannot judge, are counted and bounded).
#[test]
fn the_trilinear_interpolants_topology_where_declared() {
    let declared: Vec<&ExtractorInfo> = extractors::INFOS.iter().filter(|i| i.guarantees.trilinear_topology).collect();
    let draws = 2 + soak_cases() as u64 / 4;
    for info in declared {
        let e = build(info);
        let (mut tunnels, mut critical) = (0usize, 0usize);
        for case in 1..=254u8 {
            let mut random = isolab_algorithms::random::Random::new(0xc0 + u64::from(case));
            for draw in 0..draws {
                let g = tunnel_corner_values(case, &mut random);
                let ours = cell_shape(&extract_on_cell(e.as_ref(), &g));
                let reference = interpolant_shape(&g, 0.0);
                if ours != reference {
                    assert!(
                        near_critical(&g),
                        "{}: case {case} draw {draw}: {ours:?}, the interpolant's {reference:?}; {g:?}",
                        info.name
                    );
                    critical += 1;
                }
                tunnels += usize::from(reference.0 as i64 > reference.1);
            }
        }
        let total = 254 * draws as usize;
        assert!(critical * 20 < total, "{}: {critical} of {total} draws near a critical value", info.name);
        assert!(tunnels > 0, "{}: no draw with a tunnel", info.name);
    }
}

fn extract_on_cell(e: &dyn Extractor, g: &[f32; 8]) -> isolab_algorithms::TriMesh {
    let mut out = Extraction::default();
    e.extract(&cell_samples(g), &mut out).unwrap_or_else(|err| panic!("{g:?}: {err}"));
    out.surface
}

/// Random values in {-1, 0, 1} (a third of them exactly at the iso-value), outside on the border.
fn on_iso(bcc: bool, n: usize, seed: u64) -> Samples<'static> {
    let mut random = isolab_algorithms::random::Random::new(seed);
    field_samples(bcc, n, |_| (random.unit() * 3.0).floor().min(2.0) as f32 - 1.0)
}

/// Every post-process in `POST_INFOS` on `input` (marching tetrahedra of `samples`: closed,
/// manifold, outward, no self-intersection), with its default options and, if it takes a
/// `target`, down to a quarter of the triangles: the stats agree with the output, the post time
/// is filled, normals are one per vertex or none, indices are in range, the output is the same
/// on a second run, and it keeps whatever its `guarantees` promise.
fn every_post_process(samples: &Samples, input: &Extraction, what: &str) {
    let before = topology(&input.surface);
    for info in post::POST_INFOS {
        let mut settings = vec![Options::new()];
        if info.options.contains(&"target") {
            let mut o = Options::new();
            o.set("target", &(input.surface.triangles.len() / 4).max(1).to_string());
            settings.push(o);
        }
        for options in settings {
            let post = (info.make)(&options).unwrap_or_else(|e| panic!("{}: {e}", info.name));
            let what = format!("{} {options:?} on {what}", info.name);
            let mut out = input.clone();
            post.apply(samples, &mut out).unwrap_or_else(|e| panic!("{what}: {e}"));
            let mesh = &out.surface;
            assert_eq!((out.stats.vertices, out.stats.triangles), (mesh.positions.len(), mesh.triangles.len()), "{what}: stats");
            assert!(out.stats.times.post > std::time::Duration::ZERO, "{what}: post time not filled");
            assert!(mesh.normals.is_empty() || mesh.normals.len() == mesh.positions.len(), "{what}: normals");
            let n = mesh.positions.len() as u32;
            assert!(mesh.triangles.iter().flatten().all(|&i| i < n), "{what}: index out of range");
            let mut again = input.clone();
            post.apply(samples, &mut again).unwrap();
            assert!(again.surface == out.surface, "{what}: a second run differs");
            let g = info.guarantees;
            let after = topology(mesh);
            if g.keeps_closed_manifold {
                assert!(after.is_watertight_manifold(), "{what}: not a closed manifold: {after:?}");
            }
            if g.keeps_closed_manifold && g.keeps_every_component {
                assert_eq!(after.euler, before.euler, "{what}: Euler characteristic");
            }
            if g.keeps_every_component {
                assert_eq!(after.components, before.components, "{what}: components");
            }
            if g.keeps_outward {
                assert!(after.outward, "{what}: not outward");
            }
            if g.adds_no_intersection {
                assert_eq!(self_intersections(mesh).count, 0, "{what}: self-intersections");
            }
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: soak_cases(), failure_persistence: None, ..ProptestConfig::default() })]

    /// The post-processes' contract, on marching tetrahedra of random blobs.
    #[test]
    fn post_processes_keep_what_they_declare(
        bcc in any::<bool>(),
        n in 7usize..13,
        list in random_blobs(),
        threshold in 0.3f32..0.8,
    ) {
        let samples = blobs(bcc, n, &list, threshold);
        let mut input = Extraction::default();
        extractors::by_name("marching-tetrahedra").unwrap().extract(&samples, &mut input).unwrap();
        if !input.surface.triangles.is_empty() {
            every_post_process(&samples, &input, &format!("blobs {list:?} at {threshold}"));
        }
    }

    #[test]
    fn random_blob_fields(
        bcc in any::<bool>(),
        n in 7usize..13,
        list in random_blobs(),
        threshold in 0.3f32..0.8,
    ) {
        let samples = blobs(bcc, n, &list, threshold);
        let crosses = samples.values().iter().any(|&v| v < 0.0);
        let other = blobs(bcc, n, &[(Vec3::splat(0.5), 0.3)], 0.5);
        every_extractor(&samples, crosses, &other, &format!("blobs {list:?} at {threshold}"));
    }

    /// White noise: surface extractors on up to 9³, volume extractors on 5³ (bcc-sculpt's cover
    /// search grows with the number of components: a white-noise 9³ takes it seconds).
    #[test]
    fn random_white_noise(bcc in any::<bool>(), n in 5usize..10, seed in any::<u64>()) {
        for info in extractors::INFOS {
            let n = if build(info).produces_volume() { 5 } else { n };
            let samples = noise(bcc, n, seed);
            let crosses = samples.values().iter().any(|&v| v < 0.0);
            let other = blobs(bcc, n, &[(Vec3::splat(0.5), 0.3)], 0.5);
            check(info, &samples, crosses, &other, &format!("white noise {n}³, seed {seed}"));
        }
    }
}
