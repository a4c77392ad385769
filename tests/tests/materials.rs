//! Materials: each vertex takes the material of the solid sample of its lattice edge (the marching
//! cubes terrain post), for every surface extractor; brushes paint their material; the CLI writes
//! counts and vertex colours.

use glam::Vec3;
use isolab_algorithms::chunks::{Brush, ChunkedVolume};
use isolab_algorithms::materials::{self, vertex_materials, CLAY};
use isolab_algorithms::{extractors, Extraction, Grid, Lattice, Samples};

/// A sphere of radius 10 samples in a 33³ grid, material 1 where x < 16, 2 elsewhere.
fn sphere() -> (Samples<'static>, Vec<u8>) {
    let samples = isolab_tests::grid_samples([33, 33, 33], |x, y, z| {
        (Vec3::new(x as f32, y as f32, z as f32) - Vec3::splat(16.0)).length() - 10.0
    });
    let ids: Vec<u8> = (0..33 * 33 * 33).map(|i| if i % 33 < 16 { 1 } else { 2 }).collect();
    (samples, ids)
}

#[test]
fn every_surface_extractor_colours_vertices_by_their_solid_sample() {
    let (samples, ids) = sphere();
    let grid = *samples.grid();
    for e in extractors::registry().into_iter().filter(|e| !e.produces_volume()) {
        let mut out = Extraction::default();
        e.extract(&samples, &mut out).unwrap();
        let mut m = Vec::new();
        vertex_materials(&grid, samples.values(), 0.0, &ids, &out.surface.positions, &mut m);
        assert_eq!(m.len(), out.surface.positions.len());
        for (p, &id) in out.surface.positions.iter().zip(&m) {
            // Vertices clear of the material boundary (x = 15.5, between samples 15 and 16) take
            // the side's material; edge vertices exactly, cell vertices by their nearest corner.
            if p.x < 14.9 {
                assert_eq!(id, 1, "{} vertex at {p}", e.name());
            } else if p.x > 16.1 {
                assert_eq!(id, 2, "{} vertex at {p}", e.name());
            }
        }
    }
}

#[test]
fn an_adding_brush_paints_its_material_and_carving_keeps_the_old_one() {
    let (samples, ids) = sphere();
    let mc = extractors::by_name("marching-cubes").unwrap();
    let mut world = ChunkedVolume::new(mc.as_ref(), samples, 16).unwrap().with_materials(ids).unwrap();
    // A lump on top of the sphere at (16, 26, 16).
    let centre = Vec3::new(16.0, 27.0, 16.0);
    world.apply(&Brush { centre, radius: 3.0, falloff: 0.0, add: true, material: CLAY }).unwrap();
    world.remesh_dirty(mc.as_ref()).unwrap();
    let mut welded = Extraction::default();
    world.welded(&mut welded);
    let mut m = Vec::new();
    world.vertex_materials(&welded.surface, &mut m);
    let on_lump: Vec<u8> = welded
        .surface
        .positions
        .iter()
        .zip(&m)
        .filter(|(p, _)| p.distance(centre) < 3.5 && p.y > 28.0)
        .map(|(_, &id)| id)
        .collect();
    assert!(!on_lump.is_empty());
    assert!(on_lump.iter().all(|&id| id == CLAY), "the lump's top is clay: {on_lump:?}");
    let away = welded.surface.positions.iter().zip(&m).filter(|(p, _)| p.y < 10.0).map(|(_, &id)| id);
    assert!(away.into_iter().all(|id| id == 1 || id == 2), "the rest keeps its materials");
    // Carving a hole keeps the materials of what is left: the walls are not clay.
    let hole = Vec3::new(16.0, 6.0, 16.0);
    world.apply(&Brush { centre: hole, radius: 3.0, falloff: 0.0, add: false, material: CLAY }).unwrap();
    world.remesh_dirty(mc.as_ref()).unwrap();
    world.welded(&mut welded);
    world.vertex_materials(&welded.surface, &mut m);
    let walls: Vec<u8> =
        welded.surface.positions.iter().zip(&m).filter(|(p, _)| p.distance(hole) < 3.5).map(|(_, &id)| id).collect();
    assert!(!walls.is_empty() && walls.iter().all(|&id| id != CLAY));
    let bad = ChunkedVolume::new(mc.as_ref(), sphere().0, 16).unwrap().with_materials(vec![0; 5]);
    assert!(bad.err().unwrap().to_string().contains("5 material ids given for 35937 samples"));
}

#[test]
fn terrain_has_layers_at_its_surface() {
    let field = isolab_tests::object_field("terrain");
    let grid = Grid::with_dims(&field.domain(), [65, 33, 65]).unwrap();
    let samples = Samples::sample(field.clone(), Lattice::Cubic(grid), 0.0).unwrap();
    let ids = materials::sample(field.as_ref(), &grid);
    let mut out = Extraction::default();
    extractors::by_name("marching-cubes").unwrap().extract(&samples, &mut out).unwrap();
    let mut m = Vec::new();
    vertex_materials(&grid, samples.values(), 0.0, &ids, &out.surface.positions, &mut m);
    let counts = materials::histogram(&m);
    // Grass on the open ground, sand in the low valleys, rock in the caves.
    for id in [materials::GRASS, materials::SAND, materials::ROCK] {
        assert!(counts.get(id as usize).copied().unwrap_or(0) > 100, "{}: {counts:?}", materials::name(id));
    }
}
