//! Liquids beside solids (`algorithms::liquids`, the marching cubes terrain post's viscosity):
//! a terrain with a lake and a half-flooded cave, meshed by every extractor the post's rule
//! carries over to, and edited by brushes that dig, pour and drain.
//!
//! Checked, in ways that fail when the rule is left out or breaks: both meshes closed and
//! manifold; the rule applied (many contact vertices, and every liquid vertex on a solid–liquid
//! lattice edge bit-equal to a solid vertex; meshing the two densities independently fails that
//! check); no overlap (the two meshes together, twin contact triangles set aside, have no
//! intersecting pair, decided by exact predicates, and no liquid vertex is inside the solid);
//! the brushes' mass bookkeeping exact and the densities in range.

use glam::Vec3;
use isolab_algorithms::liquids::{extract_layers, lattice_place, LatticePlace, Phase, Phases};
use isolab_algorithms::random::Random;
use isolab_algorithms::{extractors, Extraction, Grid, Options, TriMesh};
use isolab_metrics::{intersections, topology};
use std::collections::HashSet;

/// The extractors with a vertex on every crossing lattice edge (the rule's precondition).
const EDGE_VERTEX_EXTRACTORS: [&str; 4] =
    ["marching-cubes", "marching-cubes-decider", "marching-cubes-33", "marching-tetrahedra"];

/// A terrain of `n` x `n` x `n / 2` samples: rolling ground with a basin holding a lake, a
/// spherical cave under it half full of water, air on every border sample.
fn terrain(n: usize) -> Phases {
    let dims = [n, n, n / 2];
    let grid = Grid { origin: Vec3::ZERO, spacing: 1.0, dims };
    let mut phases = Phases::empty(grid, 1.0);
    let (c, h) = (n as f32 / 2.0, (n / 2) as f32);
    phases.fill(|p| {
        let border = p.x < 0.5 || p.y < 0.5 || p.z < 0.5 || p.x > n as f32 - 1.5 || p.y > n as f32 - 1.5 || p.z > h - 1.5;
        if border {
            return (0.0, 0.0);
        }
        let r = ((p.x - c).powi(2) + (p.y - c).powi(2)).sqrt();
        let ground =
            0.55 * h + 0.08 * h * (p.x * 0.31).sin() * (p.y * 0.23).cos() - 0.25 * h * (-(r / (0.3 * n as f32)).powi(2)).exp();
        let ramp = |d: f32| (0.5 + d / 1.5).clamp(0.0, 1.0);
        let mut solid = ramp(ground - p.z);
        // A cave: a ball carved out of the ground, its lower half water.
        let cave = Vec3::new(0.3 * n as f32, 0.65 * n as f32, 0.3 * h);
        let cave_r = 0.14 * n as f32;
        solid = solid.min(ramp(p.distance(cave) - cave_r));
        let lake = ramp(0.52 * h - p.z) * ramp(0.4 * n as f32 - r);
        let flood = ramp(cave.z - p.z) * ramp(cave_r + 1.0 - p.distance(cave));
        (solid, lake.max(flood).min(1.0 - solid))
    });
    phases
}

fn build(name: &str) -> Box<dyn isolab_algorithms::Extractor> {
    extractors::build(name, &Options::new()).unwrap().unwrap()
}

/// Liquid vertices on a solid–liquid edge that are not bit-equal to a solid vertex, and how many
/// such vertices there are.
fn unshared_contact(phases: &Phases, solid: &TriMesh, liquid: &TriMesh) -> (usize, usize) {
    let solid_points: HashSet<[u32; 3]> = solid.positions.iter().map(|p| p.to_array().map(f32::to_bits)).collect();
    let mut on_contact = 0;
    let mut unshared = 0;
    for &p in &liquid.positions {
        if let LatticePlace::Edge(a, b) = lattice_place(phases.grid(), p) {
            let ends = [phases.phase(a), phases.phase(b)];
            if ends.contains(&Phase::Solid) && ends.contains(&Phase::Liquid) {
                on_contact += 1;
                unshared += usize::from(!solid_points.contains(&p.to_array().map(f32::to_bits)));
            }
        }
    }
    (unshared, on_contact)
}

/// Triangle pairs of the two meshes that cross (exact predicates), the contact triangles that
/// appear in both (reversed) set aside.
fn overlaps(solid: &TriMesh, liquid: &TriMesh) -> usize {
    let key = |m: &TriMesh, t: [u32; 3]| {
        let mut k = t.map(|v| m.positions[v as usize].to_array().map(f32::to_bits));
        k.sort();
        k
    };
    let solid_tris: HashSet<_> = solid.triangles.iter().map(|&t| key(solid, t)).collect();
    // One mesh of both, vertices shared by position, each twin contact triangle kept once.
    let mut union = TriMesh::default();
    let mut index = std::collections::HashMap::new();
    let mut add = |m: &TriMesh, skip: &HashSet<[[u32; 3]; 3]>, union: &mut TriMesh| {
        for &t in &m.triangles {
            if skip.contains(&key(m, t)) {
                continue;
            }
            let t = t.map(|v| {
                let p = m.positions[v as usize];
                *index.entry(p.to_array().map(f32::to_bits)).or_insert_with(|| {
                    union.positions.push(p);
                    union.positions.len() as u32 - 1
                })
            });
            union.triangles.push(t);
        }
    };
    add(solid, &HashSet::new(), &mut union);
    add(liquid, &solid_tris, &mut union);
    let own = intersections::self_intersections(solid).count + intersections::self_intersections(liquid).count;
    assert_eq!(own, 0, "each mesh alone is free of self-intersections");
    intersections::self_intersections(&union).count
}

/// Liquid vertices off the contact strictly inside the solid (exact winding number above 1/2).
fn liquid_inside_solid(solid: &TriMesh, liquid: &TriMesh) -> usize {
    let solid_points: HashSet<[u32; 3]> = solid.positions.iter().map(|p| p.to_array().map(f32::to_bits)).collect();
    let bvh = isolab_algorithms::bvh::TriangleBvh::new(
        solid.triangles.iter().map(|t| t.map(|v| solid.positions[v as usize])).collect(),
    );
    liquid
        .positions
        .iter()
        .filter(|p| !solid_points.contains(&p.to_array().map(f32::to_bits)))
        .filter(|&&p| bvh.winding_number(p) > 0.5)
        .count()
}

#[test]
fn solid_and_liquid_meet_on_shared_vertices_without_overlap() {
    let phases = terrain(40);
    let count = |p: Phase| (0..phases.grid().len()).filter(|&i| phases.phase(i) == p).count();
    assert!(count(Phase::Solid) > 5000 && count(Phase::Liquid) > 500, "the lake and the cave hold water");
    for name in EDGE_VERTEX_EXTRACTORS {
        let layers = extract_layers(build(name).as_ref(), &phases).unwrap();
        for (mesh, what) in [(&layers.solid, "solid"), (&layers.liquid, "liquid")] {
            let t = topology::topology(mesh);
            assert!(t.is_watertight_manifold(), "{name} {what}: {t:?}");
        }
        let (unshared, on_contact) = unshared_contact(&phases, &layers.solid, &layers.liquid);
        assert!(
            on_contact > 200 && layers.contact >= on_contact,
            "{name}: {} moved, {on_contact} on the contact",
            layers.contact
        );
        assert_eq!(unshared, 0, "{name}: liquid vertices on solid-liquid edges off the solid mesh");
        assert_eq!(overlaps(&layers.solid, &layers.liquid), 0, "{name}: solid and liquid triangles cross");
        assert_eq!(liquid_inside_solid(&layers.solid, &layers.liquid), 0, "{name}: liquid inside the solid");
    }
}

#[test]
fn without_the_rule_the_two_meshes_do_not_share_the_contact() {
    // The same densities meshed independently (the post's "naive solution"): the check above fails.
    let phases = terrain(40);
    let mc = build("marching-cubes");
    let mesh = |density: &[f32]| {
        let values = density.iter().map(|&d| phases.max() / 2.0 - d).collect();
        let samples =
            isolab_algorithms::Samples::from_values(isolab_algorithms::Lattice::Cubic(*phases.grid()), values, 0.0).unwrap();
        let mut out = Extraction::default();
        mc.extract(&samples, &mut out).unwrap();
        out.surface
    };
    let (solid, liquid) = (mesh(phases.solid()), mesh(phases.liquid()));
    let (unshared, on_contact) = unshared_contact(&phases, &solid, &liquid);
    // Where the base density is full on both ends of an edge the two crossings coincide anyway;
    // elsewhere they do not.
    assert!(unshared > 50, "{unshared} of {on_contact} contact vertices unshared without the rule");
}

#[test]
fn cell_vertex_extractors_are_refused_with_the_reason() {
    let phases = terrain(24);
    for name in ["surface-nets", "dual-contouring"] {
        let e = extract_layers(build(name).as_ref(), &phases).unwrap_err().to_string();
        assert!(e.contains(name) && e.contains("not on a lattice edge"), "{e}");
    }
}

#[test]
fn brushes_keep_the_mass_books_and_the_layers_keep_meeting() {
    let mut phases = terrain(32);
    let mut random = Random::new(20261204);
    let mt = build("marching-tetrahedra");
    let [nx, ny, nz] = phases.grid().dims;
    let mut range = |lo: f32, hi: f32| lo + (hi - lo) * random.unit_f32();
    for edit in 0..60 {
        let before = phases.masses();
        let centre = Vec3::new(range(2.0, nx as f32 - 3.0), range(2.0, ny as f32 - 3.0), range(2.0, nz as f32 - 3.0));
        let (radius, amount) = (range(1.5, 4.0), range(0.1, 0.9));
        let after_edit = |phases: &Phases| phases.masses();
        match edit % 3 {
            0 => {
                let poured = phases.pour(centre, radius, amount);
                let after = after_edit(&phases);
                assert_eq!(after.solid, before.solid, "edit {edit}: pouring moved solid");
                assert!((after.liquid - (before.liquid + poured)).abs() < 1e-9 * after.liquid.max(1.0), "edit {edit}");
            }
            1 => {
                let drained = phases.drain(centre, radius, amount);
                let after = after_edit(&phases);
                assert!(drained >= 0.0 && after.solid == before.solid, "edit {edit}");
                assert!((after.liquid - (before.liquid - drained)).abs() < 1e-9 * before.liquid.max(1.0), "edit {edit}");
            }
            _ => {
                let dug = phases.dig(centre, radius, amount);
                let after = after_edit(&phases);
                assert!(dug >= 0.0 && after.liquid == before.liquid, "edit {edit}: digging moved liquid");
                assert!((after.solid - (before.solid - dug)).abs() < 1e-9 * before.solid.max(1.0), "edit {edit}");
            }
        }
        for i in 0..phases.grid().len() {
            let (s, l) = (phases.solid()[i], phases.liquid()[i]);
            assert!(s >= 0.0 && l >= 0.0 && s + l <= phases.max() * (1.0 + 1e-6), "edit {edit}, sample {i}: {s} + {l}");
        }
        if edit % 10 == 9 {
            let layers = extract_layers(mt.as_ref(), &phases).unwrap();
            assert!(topology::topology(&layers.solid).is_watertight_manifold(), "edit {edit}");
            assert!(topology::topology(&layers.liquid).is_watertight_manifold(), "edit {edit}");
            assert_eq!(unshared_contact(&phases, &layers.solid, &layers.liquid).0, 0, "edit {edit}");
            assert_eq!(overlaps(&layers.solid, &layers.liquid), 0, "edit {edit}");
        }
    }
    // A pour into air far from everything adds exactly what the samples took.
    let mut empty = Phases::empty(*phases.grid(), 2.0);
    let poured = empty.pour(Vec3::splat(8.0), 3.0, 0.5);
    assert!(poured > 0.0 && (empty.masses().liquid - poured).abs() < 1e-12);
}

#[test]
fn the_posts_base_and_viscosity_round_trip() {
    let grid = Grid { origin: Vec3::ZERO, spacing: 0.5, dims: [3, 3, 3] };
    let base: Vec<f32> = (0..27).map(|i| i as f32 / 10.0 - 0.3).collect();
    let viscosity: Vec<f32> = (0..27).map(|i| (i % 7) as f32 / 5.0 - 0.1).collect();
    let phases = Phases::from_base_viscosity(grid, 2.0, &base, &viscosity).unwrap();
    for i in 0..27 {
        let (b, v) = (base[i].clamp(0.0, 2.0), viscosity[i].clamp(0.0, 1.0));
        assert!((phases.base(i) - b).abs() < 1e-6, "sample {i}");
        if b > 0.0 {
            assert!((phases.viscosity(i) - v).abs() < 1e-5, "sample {i}");
        }
        let want = if v * b > 1.0 {
            Phase::Solid
        } else if (1.0 - v) * b > 1.0 {
            Phase::Liquid
        } else {
            Phase::Air
        };
        assert_eq!(phases.phase(i), want, "sample {i}");
    }
    let mut nan = base.clone();
    nan[4] = f32::NAN;
    let e = Phases::from_base_viscosity(grid, 2.0, &nan, &viscosity).unwrap_err().to_string();
    assert!(e.contains("sample 4"), "{e}");
    let e = Phases::from_base_viscosity(grid, 2.0, &base[..5], &viscosity).unwrap_err().to_string();
    assert!(e.contains("needs 27"), "{e}");
}
