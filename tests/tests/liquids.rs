//! Liquids beside solids (`algorithms::liquids`, the marching cubes terrain post's viscosity):
//! a terrain with a lake and a half-flooded cave (`liquids::lake_and_cave`), meshed by every extractor the post's rule
//! carries over to, and edited by brushes that dig, pour and drain.
//!
//! Checked, in ways that fail when the rule is left out or breaks: both meshes closed and
//! manifold; the rule applied (many contact vertices, and every liquid vertex on a solid–liquid
//! lattice edge bit-equal to a solid vertex; meshing the two densities independently fails that
//! check); no overlap on marching tetrahedra, where it is proved (the two meshes together, twin contact triangles set aside, have no
//! intersecting pair, decided by exact predicates, and no liquid vertex is inside the solid);
//! the brushes' mass bookkeeping exact and the densities in range.

use glam::Vec3;
use isolab_algorithms::liquids::{
    extract_layers, extract_layers_without_untangling, lake_and_cave, ChunkedLayers, Phase, Phases,
};
use isolab_algorithms::random::Random;
use isolab_algorithms::{extractors, Extraction, Grid, Options};
use isolab_metrics::layers::layer_contact;
use isolab_metrics::topology;

/// The extractor whose layers provably do not overlap (the proof in the liquids module doc needs
/// linear interpolation on simplices).
const OVERLAP_FREE: &str = "marching-tetrahedra";

fn build(name: &str) -> Box<dyn isolab_algorithms::Extractor> {
    extractors::build(name, &Options::new()).unwrap().unwrap()
}

#[test]
fn solid_and_liquid_meet_on_shared_vertices_without_overlap() {
    let phases = lake_and_cave(40);
    let count = |p: Phase| (0..phases.grid().len()).filter(|&i| phases.phase(i) == p).count();
    assert!(count(Phase::Solid) > 5000 && count(Phase::Liquid) > 500, "the lake and the cave hold water");
    // Every registered surface extractor on a cubic lattice: the rule applies (every check below
    // holds) or the extractor is refused for having vertices off the lattice edges.
    let mut applied = Vec::new();
    for e in extractors::registry().into_iter().filter(|e| !e.produces_volume()) {
        let name = e.name();
        let layers = match extract_layers(e.as_ref(), &phases) {
            Ok(layers) => layers,
            Err(err) => {
                assert!(err.to_string().contains("not on a lattice edge"), "{name}: {err}");
                continue;
            }
        };
        applied.push(name);
        for (mesh, what) in [(&layers.solid, "solid"), (&layers.liquid, "liquid")] {
            let t = topology::topology(mesh);
            assert!(t.is_watertight_manifold(), "{name} {what}: {t:?}");
        }
        let c = layer_contact(&phases, &layers.solid, &layers.liquid);
        assert!(c.contact_vertices > 200 && layers.contact >= c.contact_vertices, "{name}: {} moved, {c:?}", layers.contact);
        assert_eq!(c.unshared, 0, "{name}: liquid vertices on solid-liquid edges off the solid mesh");
        // Proved for marching tetrahedra; for marching cubes, held by filling again the cells
        // where the layers crossed (the liquids module doc).
        assert_eq!(c.crossing_pairs, 0, "{name}: solid and liquid triangles cross");
        assert_eq!(layers.retiled_cells, layers.crossing_cells, "{name}: a crossing cell was left");
        assert_eq!(c.liquid_inside_solid, 0, "{name}: liquid inside the solid");
    }
    for name in ["marching-cubes", "marching-cubes-decider", "marching-cubes-33", OVERLAP_FREE] {
        assert!(applied.contains(&name), "{name} has edge vertices: the rule must apply ({applied:?})");
    }
}

#[test]
fn marching_cubes_crossings_are_filled_again_until_none_is_left() {
    // The report's scene: with the post's rule alone, marching cubes' liquid quads and solid
    // pentagons cross in cells with solid, liquid and air corners; filled again, none does, and
    // the layers stay closed, manifold and apart.
    let phases = lake_and_cave(96);
    for name in ["marching-cubes", "marching-cubes-decider", "marching-cubes-33"] {
        let e = build(name);
        let plain = extract_layers_without_untangling(e.as_ref(), &phases).unwrap();
        let crossing = layer_contact(&phases, &plain.solid, &plain.liquid).crossing_pairs;
        assert!(crossing > 0 && plain.crossing_cells == 0, "{name}: {crossing} pairs with the rule alone");
        let layers = extract_layers(e.as_ref(), &phases).unwrap();
        assert!(layers.crossing_cells > 0 && layers.retiled_cells == layers.crossing_cells, "{name}: {layers:?}");
        for (mesh, before, what) in [(&layers.solid, &plain.solid, "solid"), (&layers.liquid, &plain.liquid, "liquid")] {
            let (t, t0) = (topology::topology(mesh), topology::topology(before));
            assert!(t.is_watertight_manifold(), "{name} {what}: {t:?}");
            assert_eq!((t.euler, t.components), (t0.euler, t0.components), "{name} {what}: a filling is a disk for a disk");
        }
        let c = layer_contact(&phases, &layers.solid, &layers.liquid);
        assert_eq!((c.unshared, c.crossing_pairs, c.liquid_inside_solid), (0, 0, 0), "{name}");
        // Only the crossing cells changed: the triangle counts move by a few per cell.
        let moved = |a: usize, b: usize| a.abs_diff(b) <= 4 * layers.crossing_cells;
        assert!(moved(layers.solid.triangles.len(), plain.solid.triangles.len()), "{name}");
        assert!(moved(layers.liquid.triangles.len(), plain.liquid.triangles.len()), "{name}");
    }
}

#[test]
fn without_the_rule_the_two_meshes_do_not_share_the_contact() {
    // The same densities meshed independently (the post's "naive solution"): the check above fails.
    let phases = lake_and_cave(40);
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
    let c = layer_contact(&phases, &solid, &liquid);
    let (unshared, on_contact) = (c.unshared, c.contact_vertices);
    // Where the base density is full on both ends of an edge the two crossings coincide anyway;
    // elsewhere they do not.
    assert!(unshared > 50, "{unshared} of {on_contact} contact vertices unshared without the rule");
}

#[test]
fn cell_vertex_extractors_are_refused_with_the_reason() {
    let phases = lake_and_cave(24);
    for name in ["surface-nets", "dual-contouring"] {
        let e = extract_layers(build(name).as_ref(), &phases).unwrap_err().to_string();
        assert!(e.contains(name) && e.contains("not on a lattice edge"), "{e}");
    }
}

#[test]
fn brushes_keep_the_mass_books_and_the_layers_keep_meeting() {
    let mut phases = lake_and_cave(32);
    let mut random = Random::new(20261204);
    let extractors = ["marching-cubes", "marching-cubes-decider", "marching-cubes-33", OVERLAP_FREE].map(build);
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
        for e in extractors.iter().filter(|_| edit % 10 == 9) {
            let layers = extract_layers(e.as_ref(), &phases).unwrap();
            let name = e.name();
            assert!(topology::topology(&layers.solid).is_watertight_manifold(), "{name} edit {edit}");
            assert!(topology::topology(&layers.liquid).is_watertight_manifold(), "{name} edit {edit}");
            let c = layer_contact(&phases, &layers.solid, &layers.liquid);
            assert_eq!((c.unshared, c.crossing_pairs, c.liquid_inside_solid), (0, 0, 0), "{name} edit {edit}");
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

/// A mesh's triangles as position triples, each rotated to start at its smallest corner, sorted:
/// two meshes with equal keys have the same triangles, whatever their vertex numbering.
fn triangle_keys(mesh: &isolab_algorithms::TriMesh) -> Vec<[[u32; 3]; 3]> {
    let mut keys: Vec<[[u32; 3]; 3]> = mesh
        .triangles
        .iter()
        .map(|t| {
            let p = t.map(|v| mesh.positions[v as usize].to_array().map(f32::to_bits));
            let first = (0..3).min_by_key(|&k| p[k]).expect("three corners");
            [p[first], p[(first + 1) % 3], p[(first + 2) % 3]]
        })
        .collect();
    keys.sort_unstable();
    keys
}

#[test]
fn chunked_layers_weld_into_the_whole_grids_and_follow_the_brushes() {
    // 64 x 64 x 31 cells in chunks of 16: the last chunk along z holds 15 cells.
    for name in ["marching-cubes", OVERLAP_FREE] {
        // Each extractor edits a fresh scene (edits pile up; a pour reaching the grid's border
        // would open the layers there, as any extractor leaves a mesh open where inside touches
        // the border).
        let mut phases = lake_and_cave(65);
        let e = build(name);
        let mut chunked = ChunkedLayers::new(e.as_ref(), &phases, 16).unwrap();
        assert_eq!(chunked.counts(), [4, 4, 2]);
        let mut random = Random::new(5);
        let mut retiled = 0;
        for edit in 0..=24 {
            if edit > 0 {
                let centre =
                    Vec3::new(4.0 + 56.0 * random.unit_f32(), 4.0 + 56.0 * random.unit_f32(), 10.0 + 10.0 * random.unit_f32());
                let radius = 2.0 + 3.0 * random.unit_f32();
                match edit % 3 {
                    0 => phases.dig(centre, radius, 0.8),
                    1 => phases.pour(centre, radius, 0.8),
                    _ => phases.drain(centre, radius, 0.8),
                };
                let touched = chunked.touching(centre, radius);
                assert!(touched.len() < 32, "{name}: a brush touches a few chunks, not all");
                chunked.remesh(e.as_ref(), &phases, &touched).unwrap();
            }
            let welded = chunked.welded();
            let whole = extract_layers(e.as_ref(), &phases).unwrap();
            let what = format!("{name} after {edit} edits");
            assert_eq!(triangle_keys(&welded.solid), triangle_keys(&whole.solid), "{what}: solid");
            assert_eq!(triangle_keys(&welded.liquid), triangle_keys(&whole.liquid), "{what}: liquid");
            for (mesh, layer) in [(&welded.solid, "solid"), (&welded.liquid, "liquid")] {
                assert!(topology::topology(mesh).is_watertight_manifold(), "{what}: {layer}");
            }
            // The layers' contact (exact self-intersection tests of both joined) every fourth edit.
            if edit % 4 == 0 {
                let c = layer_contact(&phases, &welded.solid, &welded.liquid);
                assert_eq!((c.unshared, c.crossing_pairs), (0, 0), "{what}");
            }
            assert_eq!(welded.retiled_cells, whole.retiled_cells, "{what}");
            retiled += welded.retiled_cells;
        }
        // The chunks' untangling decides as the whole grid's where it acts.
        assert!(name == OVERLAP_FREE || retiled > 0, "{name}: no cell was filled again in the script");
    }
    // Extractors whose chunks do not meet vertex for vertex are refused, naming them.
    let phases = lake_and_cave(33);
    let sn = build("surface-nets");
    let err = ChunkedLayers::new(sn.as_ref(), &phases, 8).err().expect("refused").to_string();
    assert!(err.contains("surface-nets") && err.contains("vertex for vertex"), "{err}");
}
