//! Chunked extraction (`--chunk N`): chunks share their boundary samples (plus an apron for dual
//! methods and clustering), are meshed independently, and the welded mesh equals the single-volume
//! extraction in counts and topology for every surface extractor; bad chunk sizes and extractors
//! that cannot chunk are refused by name.

use isolab_algorithms::chunks::{chunk_counts, extract_chunked};
use isolab_algorithms::extractors::{self, MarchingCubes};
use isolab_algorithms::{Chunking, Extraction, Grid, Lattice, Samples};
use isolab_metrics::{signed_volume, surface_area, topology};
use isolab_tests::{blob_field, object_field};
use proptest::prelude::*;

fn sampled(name: &str, n: usize, bcc: bool) -> Samples<'static> {
    let field = object_field(name);
    let grid = Grid::with_dims(&field.domain(), [n, n, n]).unwrap();
    Samples::sample(field, if bcc { Lattice::Bcc(grid) } else { Lattice::Cubic(grid) }, 0.0).unwrap()
}

/// The welded chunks have the whole volume's triangles and used vertices (dual methods leave a
/// vertex no quad uses in cells at the grid boundary; chunks keep only used vertices), its
/// topology, and its area and volume to rounding.
fn assert_same_mesh(whole: &Extraction, welded: &Extraction, what: &str) {
    let (a, b) = (topology(&whole.surface), topology(&welded.surface));
    assert_eq!(
        welded.surface.positions.len() - b.unused_vertices,
        whole.surface.positions.len() - a.unused_vertices,
        "{what}: used vertices"
    );
    assert_eq!(welded.surface.triangles.len(), whole.surface.triangles.len(), "{what}: triangles");
    assert_eq!(
        (a.closed, a.edge_manifold, a.vertex_manifold, a.outward, a.euler, a.components, a.boundary_edges),
        (b.closed, b.edge_manifold, b.vertex_manifold, b.outward, b.euler, b.components, b.boundary_edges),
        "{what}: topology"
    );
    // Positions differ only by rounding (chunks work in index coordinates).
    let (sa, sb) = (surface_area(&whole.surface), surface_area(&welded.surface));
    assert!((sa - sb).abs() <= 1e-5 * sa, "{what}: area {sa} vs {sb}");
    let (va, vb) = (signed_volume(&whole.surface), signed_volume(&welded.surface));
    assert!((va - vb).abs() <= 1e-5 * (va.abs() + sa.powf(1.5)), "{what}: volume {va} vs {vb}");
}

#[test]
fn welded_chunks_equal_the_single_volume_on_terrain_asteroid_and_gyroid() {
    for name in ["terrain", "asteroid", "gyroid"] {
        let samples = sampled(name, 65, false);
        for e in chunking_extractors() {
            let algorithm = e.name();
            let mut whole = Extraction::default();
            e.extract(&samples, &mut whole).unwrap();
            for chunk in [8, 16, 32] {
                let mut welded = Extraction::default();
                let stats = extract_chunked(e.as_ref(), &samples, chunk, &mut welded).unwrap();
                let what = format!("{algorithm} on {name} at 65^3 in chunks of {chunk}");
                assert_same_mesh(&whole, &welded, &what);
                if e.chunking() == Chunking::CellLocal {
                    assert_eq!(welded.surface.positions.len(), whole.surface.positions.len(), "{what}: every vertex");
                }
                let per_axis = 64 / chunk;
                assert_eq!(stats.chunks, [per_axis; 3]);
                assert_eq!(stats.meshed + stats.empty + stats.full, per_axis.pow(3), "{what}");
                assert!(stats.welded > 0, "{what}: seams were welded");
            }
        }
    }
}

#[test]
fn empty_and_full_chunks_are_skipped() {
    // A small sphere inside the first chunk (samples 0..=8): the rest is empty.
    let samples = isolab_tests::grid_samples([33, 33, 33], |x, y, z| {
        let d = ((x as f32 - 4.0).powi(2) + (y as f32 - 4.0).powi(2) + (z as f32 - 4.0).powi(2)).sqrt();
        d - 2.5
    });
    let mut out = Extraction::default();
    let stats = extract_chunked(&MarchingCubes::default(), &samples, 8, &mut out).unwrap();
    assert_eq!((stats.meshed, stats.empty, stats.full), (1, 63, 0));
    assert!(topology(&out.surface).closed);
    // Everything inside: nothing to mesh at all.
    let inside = isolab_tests::grid_samples([17, 17, 17], |_, _, _| -1.0);
    let stats = extract_chunked(&MarchingCubes::default(), &inside, 8, &mut out).unwrap();
    assert_eq!((stats.meshed, stats.full), (0, 8));
    assert!(out.surface.triangles.is_empty());
}

#[test]
fn bad_chunk_sizes_and_unsupported_extractors_are_refused_by_name() {
    let samples = sampled("sphere", 33, false);
    let grid = *samples.grid();
    let mc = MarchingCubes::default();
    let mut out = Extraction::default();
    let err = extract_chunked(&mc, &samples, 1, &mut out).unwrap_err().to_string();
    assert!(err.contains("chunk size 1 is below 2"), "{err}");
    let err = extract_chunked(&mc, &samples, 10, &mut out).unwrap_err().to_string();
    assert!(err.contains("chunk size 10 does not divide") && err.contains("32x32x32"), "{err}");
    assert_eq!(chunk_counts(&grid, 16, "x").unwrap(), [2, 2, 2]);
    let sculpt = extractors::by_name("bcc-sculpt").unwrap();
    let err = extract_chunked(sculpt.as_ref(), &samples, 16, &mut out).unwrap_err().to_string();
    assert!(err.contains("bcc-sculpt") && err.contains("cannot mesh in chunks"), "{err}");
    let bcc = sampled("sphere", 17, true);
    assert!(extract_chunked(&mc, &bcc, 8, &mut out).is_err());
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]

    /// Random blobby fields: every chunking extractor's welded chunks equal its whole-volume
    /// extraction (chunks of 2 cells have aprons wider than themselves).
    #[test]
    fn random_fields_chunk_exactly(
        blobs in prop::collection::vec((0.1f32..0.9, 0.1f32..0.9, 0.1f32..0.9, 0.05f32..0.3), 1..8),
        threshold in 0.3f32..0.9,
        chunk in prop::sample::select(vec![2usize, 4, 8]),
    ) {
        let samples = blob_field(17, &blobs, threshold);
        for e in chunking_extractors() {
            let algorithm = e.name();
            let mut whole = Extraction::default();
            e.extract(&samples, &mut whole).unwrap();
            let mut welded = Extraction::default();
            extract_chunked(e.as_ref(), &samples, chunk, &mut welded).unwrap();
            let (a, b) = (topology(&whole.surface), topology(&welded.surface));
            prop_assert_eq!(welded.surface.positions.len() - b.unused_vertices, whole.surface.positions.len() - a.unused_vertices, "{}", algorithm);
            prop_assert_eq!(welded.surface.triangles.len(), whole.surface.triangles.len(), "{}", algorithm);
            prop_assert_eq!((a.closed, a.edge_manifold, a.vertex_manifold, a.euler), (b.closed, b.edge_manifold, b.vertex_manifold, b.euler), "{}", algorithm);
        }
    }
}

mod editing {
    use super::*;
    use glam::Vec3;
    use isolab_algorithms::chunks::{Brush, ChunkState, ChunkedVolume, EditError};

    #[test]
    fn brush_edits_remesh_only_dirty_chunks_and_equal_a_fresh_extraction() {
        // Marching cubes reads no apron; the others read 2 + smoothing (surface nets: 6), 2 (dual
        // contouring) and 3 (regularised MT) samples of their neighbours.
        for (algorithm, edits) in
            [("marching-cubes", 25), ("surface-nets", 8), ("dual-contouring", 8), ("regularised-marching-tetrahedra", 8)]
        {
            let e = extractors::by_name(algorithm).unwrap();
            let samples = sampled("terrain", 65, false);
            let grid = *samples.grid();
            let mut world = ChunkedVolume::new(e.as_ref(), samples, 16).unwrap();
            assert_eq!(world.remesh_dirty(e.as_ref()).unwrap(), 64);
            let mut seed = isolab_algorithms::random::Random::new(7);
            let mut welded = Extraction::default();
            for edit in 0..edits {
                let p = Vec3::new(seed.unit_f32(), seed.unit_f32(), seed.unit_f32());
                let brush = Brush {
                    centre: grid.origin + p * grid.spacing * 64.0,
                    radius: grid.spacing * (2.0 + 6.0 * seed.unit_f32()),
                    falloff: grid.spacing * 2.0 * seed.unit_f32(),
                    add: edit % 2 == 0,
                    material: 4,
                };
                let dirtied = world.apply(&brush).unwrap();
                assert!(dirtied <= 27, "{algorithm}: a brush of radius < 10 cells touches at most 3x3x3 chunks of 16");
                // Every other edit re-meshed one chunk at a time (remesh_dirty_each, timed per chunk).
                if edit % 2 == 0 {
                    assert_eq!(world.remesh_dirty(e.as_ref()).unwrap(), dirtied);
                } else {
                    assert_eq!(world.remesh_dirty_each(e.as_ref()).unwrap().len(), dirtied);
                }
                world.welded(&mut welded);
                let mut whole = Extraction::default();
                e.extract(&world.samples().unwrap(), &mut whole).unwrap();
                assert_same_mesh(&whole, &welded, &format!("{algorithm} after edit {edit}"));
            }
        }
    }

    #[test]
    fn carving_a_chunk_empty_removes_its_mesh() {
        let samples = isolab_tests::grid_samples([33, 33, 33], |_, y, _| y as f32 - 12.5);
        let mc = MarchingCubes::default();
        let mut world = ChunkedVolume::new(&mc, samples, 16).unwrap();
        world.remesh_dirty(&mc).unwrap();
        assert_eq!(world.slots().iter().filter(|s| s.state == ChunkState::Meshed).count(), 4);
        // Carve everything below y = 16 around the first column of chunks.
        for x in [0.0f32, 8.0, 16.0] {
            for z in [0.0f32, 8.0, 16.0] {
                world
                    .apply(&Brush { centre: Vec3::new(x, 4.0, z), radius: 16.0, falloff: 0.0, add: false, material: 0 })
                    .unwrap();
            }
        }
        world.remesh_dirty(&mc).unwrap();
        let first = &world.slots()[0];
        assert_eq!(first.state, ChunkState::Empty, "chunk (0,0,0) carved out");
        assert!(first.mesh.surface.triangles.is_empty());
    }

    #[test]
    fn bad_brushes_are_refused_by_name() {
        let samples = isolab_tests::grid_samples([17, 17, 17], |_, y, _| y as f32 - 8.5);
        let mc = MarchingCubes::default();
        let mut world = ChunkedVolume::new(&mc, samples, 8).unwrap();
        let outside = world.apply(&Brush { centre: Vec3::splat(100.0), radius: 2.0, falloff: 0.0, add: true, material: 0 });
        assert!(matches!(outside, Err(EditError::Outside { .. })), "{outside:?}");
        assert!(outside.unwrap_err().to_string().contains("outside the world"));
        for (radius, falloff) in [(0.0, 0.0), (-1.0, 0.0), (1.0, -1.0), (f32::NAN, 0.0)] {
            let bad = world.apply(&Brush { centre: Vec3::splat(8.0), radius, falloff, add: true, material: 0 });
            assert!(matches!(bad, Err(EditError::BadBrush { .. })), "radius {radius}, falloff {falloff}");
        }
        assert!(ChunkedVolume::new(&mc, isolab_tests::grid_samples([17, 17, 17], |_, _, _| 1.0), 5).is_err());
    }
}

mod streaming {
    use super::*;
    use isolab_algorithms::chunks::{stream_chunked, MeshSink};
    use isolab_algorithms::{TriMesh, Vec3};

    #[derive(Default)]
    pub(super) struct Memory(pub(super) TriMesh);

    impl MeshSink for Memory {
        fn vertices(&mut self, positions: &[Vec3]) -> std::io::Result<()> {
            self.0.positions.extend_from_slice(positions);
            Ok(())
        }
        fn triangles(&mut self, triangles: &[[u32; 3]]) -> std::io::Result<()> {
            assert!(triangles.iter().flatten().all(|&v| (v as usize) < self.0.positions.len()), "indices refer to sent vertices");
            self.0.triangles.extend_from_slice(triangles);
            Ok(())
        }
    }

    /// Streaming slab by slab from the field gives the same mesh as meshing the sampled volume,
    /// while holding only one slab's face of seam keys, and skipping the chunks the field proves
    /// empty or full.
    #[test]
    fn streamed_world_equals_the_sampled_volume() {
        for (name, algorithm) in
            [("terrain", "marching-cubes"), ("asteroid", "marching-tetrahedra"), ("gyroid", "marching-cubes")]
        {
            let samples = sampled(name, 65, false);
            let e = extractors::by_name(algorithm).unwrap();
            let mut whole = Extraction::default();
            e.extract(&samples, &mut whole).unwrap();
            let mut sink = Memory::default();
            let mut slabs = 0;
            let field = isolab_tests::object_field(name);
            let stats = stream_chunked(e.as_ref(), field.as_ref(), *samples.grid(), 0.0, 16, &mut sink, |done, total| {
                slabs = done;
                assert_eq!(total, 4);
            })
            .unwrap();
            assert_eq!(slabs, 4);
            let what = format!("{algorithm} on {name}");
            assert_eq!((stats.vertices, stats.triangles), (sink.0.positions.len() as u64, sink.0.triangles.len() as u64));
            assert_eq!(sink.0.positions.len(), whole.surface.positions.len(), "{what}: vertices");
            assert_eq!(sink.0.triangles.len(), whole.surface.triangles.len(), "{what}: triangles");
            let (a, b) = (topology(&whole.surface), topology(&sink.0));
            assert_eq!((a.euler, a.boundary_edges, a.edge_manifold), (b.euler, b.boundary_edges, b.edge_manifold), "{what}");
            assert!(stats.peak_keys < sink.0.positions.len() / 2, "{what}: {} seam keys held", stats.peak_keys);
            // Terrain proves some chunks empty or full unsampled; the mesh is the same.
            assert_eq!(stats.proven > 0, name == "terrain", "{what}: {} chunks proven", stats.proven);
            assert!(stats.proven <= stats.empty + stats.full, "{what}");
        }
        let sn = extractors::by_name("surface-nets").unwrap();
        let field = isolab_tests::object_field("sphere");
        let grid = *sampled("sphere", 33, false).grid();
        let err = stream_chunked(sn.as_ref(), field.as_ref(), grid, 0.0, 16, &mut Memory::default(), |_, _| {}).unwrap_err();
        assert!(err.to_string().contains("cell-local"), "{err}");
    }
}

/// A volume streamed slice by slice into a sink gives exactly the fragments' weld (same
/// vertices in the same order, same triangles) for every chunking extractor, on uneven blocks
/// down to 2 cells; each slice is read once, in order; a mirroring map reverses the winding.
#[test]
fn a_volume_streamed_slice_by_slice_equals_its_welded_fragments() {
    use isolab_algorithms::chunks::{stream_blocks, BlockPlan};
    use isolab_algorithms::Vec3;
    let field = object_field("asteroid");
    let grid = Grid::with_dims(&field.domain(), [23, 19, 26]).unwrap();
    let sampled = Samples::sample(field, Lattice::Cubic(grid), 0.0).unwrap();
    let samples = Samples::from_values(Lattice::Cubic(grid), sampled.values().to_vec(), 0.0).unwrap();
    let slice = 23 * 19;
    for e in chunking_extractors() {
        for chunk in [2, 5, 8] {
            let what = format!("{} streamed in blocks of {chunk}", e.name());
            let expected = blocks_welded(e.as_ref(), &samples, chunk);
            let plan = BlockPlan::new(e.as_ref(), grid.dims, chunk).unwrap();
            for mirror in [false, true] {
                let mut next = 0;
                let mut read = |count: usize, out: &mut Vec<f32>| {
                    out.extend_from_slice(&samples.values()[next * slice..(next + count) * slice]);
                    next += count;
                    Ok(())
                };
                // Index coordinates to the grid's world, mirrored in x when asked.
                let map = |p: Vec3| {
                    let w = grid.origin + p * grid.spacing;
                    if mirror {
                        Vec3::new(-w.x, w.y, w.z)
                    } else {
                        w
                    }
                };
                let mut sink = streaming::Memory::default();
                let mut layers = 0;
                let stats =
                    stream_blocks(e.as_ref(), &plan, 0.0, &mut read, &map, mirror, &mut sink, |done, _| layers = done).unwrap();
                assert_eq!(next, 26, "{what}: every slice read once");
                assert_eq!(layers, plan.counts[2], "{what}");
                let mut want = expected.surface.clone();
                if mirror {
                    for p in &mut want.positions {
                        p.x = -p.x;
                    }
                    for t in &mut want.triangles {
                        t.swap(1, 2);
                    }
                }
                assert_eq!(sink.0.positions, want.positions, "{what} (mirror {mirror}): vertices");
                assert_eq!(sink.0.triangles, want.triangles, "{what} (mirror {mirror}): triangles");
                assert_eq!(stats.meshed + stats.empty + stats.full, plan.len(), "{what}");
                assert!(stats.peak_keys < sink.0.positions.len().max(8), "{what}: {} keys held", stats.peak_keys);
            }
        }
    }
}

/// Every registered extractor that meshes in chunks with its default options, from the registry
/// (a new chunking extractor is checked here without being listed).
fn chunking_extractors() -> Vec<Box<dyn isolab_algorithms::Extractor>> {
    extractors::registry().into_iter().filter(|e| e.chunking() != Chunking::Unsupported).collect()
}

/// Each block of a plan meshed on its own from its own samples (as a distributed task does),
/// then the fragments welded in the plan's order.
fn blocks_welded(e: &dyn isolab_algorithms::Extractor, samples: &Samples, chunk: usize) -> Extraction {
    use isolab_algorithms::chunks::{mesh_block, weld_fragments, BlockPlan};
    let grid = *samples.grid();
    let plan = BlockPlan::new(e, grid.dims, chunk).unwrap();
    let fragments: Vec<_> = plan
        .blocks()
        .map(|b| {
            let mut values = Vec::with_capacity(b.dims.iter().product());
            for z in b.lo[2]..b.lo[2] + b.dims[2] {
                for y in b.lo[1]..b.lo[1] + b.dims[1] {
                    let row = grid.index(b.lo[0], y, z);
                    values.extend_from_slice(&samples.values()[row..row + b.dims[0]]);
                }
            }
            mesh_block(e, &plan, b.id, values, samples.iso()).unwrap()
        })
        .collect();
    let mut out = Extraction::default();
    weld_fragments(&fragments, &mut out);
    // To the grid's world coordinates, as extract_chunked places its chunks.
    for p in &mut out.surface.positions {
        *p = grid.origin + *p * grid.spacing;
    }
    out
}

#[test]
fn blocks_meshed_apart_weld_to_exactly_the_chunked_extraction() {
    // Samples without their field: a block is only its values, as a task reading a file has.
    let field_samples = sampled("gyroid", 49, false);
    let samples = Samples::from_values(*field_samples.lattice(), field_samples.values().to_vec(), 0.0).unwrap();
    let extractors = chunking_extractors();
    assert!(extractors.len() >= 6, "the registry's chunking extractors: {}", extractors.len());
    for e in extractors {
        for chunk in [8, 16] {
            let mut chunked = Extraction::default();
            extract_chunked(e.as_ref(), &samples, chunk, &mut chunked).unwrap();
            let welded = blocks_welded(e.as_ref(), &samples, chunk);
            let what = format!("{} in blocks of {chunk}", e.name());
            assert_eq!(welded.surface.positions, chunked.surface.positions, "{what}: vertices");
            assert_eq!(welded.surface.triangles, chunked.surface.triangles, "{what}: triangles");
        }
    }
}

#[test]
fn blocks_that_do_not_divide_the_grid_still_give_the_whole_volume() {
    // 45 x 38 x 51 samples: no block size divides every axis's cells.
    let field = object_field("asteroid");
    let grid = Grid::with_dims(&field.domain(), [45, 38, 51]).unwrap();
    let sampled = Samples::sample(field, Lattice::Cubic(grid), 0.0).unwrap();
    // Without the field (dual contouring would ask it for normals the blocks do not have).
    let samples = Samples::from_values(Lattice::Cubic(grid), sampled.values().to_vec(), 0.0).unwrap();
    for e in chunking_extractors() {
        let mut whole = Extraction::default();
        e.extract(&samples, &mut whole).unwrap();
        for chunk in [7, 16] {
            let welded = blocks_welded(e.as_ref(), &samples, chunk);
            let what = format!("{} on 45x38x51 in uneven blocks of {chunk}", e.name());
            assert_same_mesh(&whole, &welded, &what);
            if e.chunking() == Chunking::CellLocal {
                assert_eq!(welded.surface.positions.len(), whole.surface.positions.len(), "{what}: every vertex");
            }
        }
    }
}

#[test]
fn a_block_plan_refuses_what_it_cannot_mesh_by_name() {
    use isolab_algorithms::chunks::{mesh_block, BlockPlan};
    let mc = MarchingCubes::default();
    let plan = BlockPlan::new(&mc, [20, 11, 9], 8).unwrap();
    assert_eq!((plan.counts, plan.len()), ([3, 2, 1], 6));
    assert_eq!(plan.block([2, 1, 0]).map(|b| (b.lo, b.dims)), Some(([16, 8, 0], [4, 3, 9])));
    assert!(refusal(BlockPlan::new(&mc, [20, 11, 9], 1)).contains("below 2 cells"));
    assert!(refusal(BlockPlan::new(&mc, [20, 1, 9], 8)).contains("no cells"));
    let bcc = extractors::by_name("bcc-sculpt").unwrap();
    assert!(refusal(BlockPlan::new(bcc.as_ref(), [20, 11, 9], 8)).contains("cannot mesh in blocks"));
    assert!(refusal(mesh_block(&mc, &plan, [0, 0, 0], vec![0.0; 5], 0.0)).contains("it was given 5"));
    assert!(refusal(mesh_block(&mc, &plan, [3, 0, 0], vec![0.0; 5], 0.0)).contains("outside the plan"));
    let mut values = vec![1.0; 9 * 9 * 9];
    values[10] = f32::NAN;
    assert!(refusal(mesh_block(&mc, &plan, [0, 0, 0], values, 0.0)).contains("[1, 1, 0] is NaN"));
}

fn refusal<T>(r: Result<T, isolab_algorithms::ExtractError>) -> String {
    match r {
        Ok(_) => panic!("accepted"),
        Err(e) => e.to_string(),
    }
}
