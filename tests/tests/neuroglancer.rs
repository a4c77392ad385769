//! The neuroglancer multi-resolution source written block by block
//! (`isolab_pipeline::neuroglancer`), checked on its work files (the float meshes of every box
//! at every level): level 0 reassembles every label's whole-map mesh (same area, closed, same
//! Euler characteristic); every level is closed across its boxes (no crack between fragments);
//! above level 0 no triangle crosses its box's 2x2x2 grid, and every vertex on a box face is a
//! level-0 vertex (so levels meet without cracks). The files themselves are read back from the
//! spec by an independent reader in `python/tests/test_neuroglancer.py`.

use std::collections::{BTreeMap, HashMap};

use glam::Vec3;
use isolab_algorithms::labels::{self, LabelBlockPlan, LabelMap, LabelSamples, LabelSurface};
use isolab_algorithms::{Options, TriMesh};
use isolab_pipeline::neuroglancer::{self as ngp, boxfile, Layout, NgConfig};

/// A Voronoi map of `seeds` cells (labels 1..) inside a ball, background outside.
fn voronoi(dims: [usize; 3], seeds: usize) -> Vec<u16> {
    let mut random = isolab_algorithms::random::Random::new(7);
    let pts: Vec<Vec3> = (0..seeds)
        .map(|_| {
            Vec3::new(random.unit() as f32, random.unit() as f32, random.unit() as f32)
                * Vec3::new(dims[0] as f32, dims[1] as f32, dims[2] as f32)
        })
        .collect();
    let centre = Vec3::new(dims[0] as f32, dims[1] as f32, dims[2] as f32) / 2.0;
    let radius = dims.iter().min().copied().unwrap_or(0) as f32 * 0.45;
    let mut out = Vec::with_capacity(dims.iter().product());
    for z in 0..dims[2] {
        for y in 0..dims[1] {
            for x in 0..dims[0] {
                let p = Vec3::new(x as f32, y as f32, z as f32);
                if p.distance(centre) > radius {
                    out.push(0);
                    continue;
                }
                let nearest = pts.iter().enumerate().min_by(|a, b| a.1.distance(p).total_cmp(&b.1.distance(p))).map(|(i, _)| i);
                out.push(nearest.map_or(0, |i| i as u16 + 1));
            }
        }
    }
    out
}

fn area(m: &TriMesh) -> f64 {
    m.triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| m.positions[i as usize].as_dvec3());
            (b - a).cross(c - a).length() / 2.0
        })
        .sum()
}

/// Boundary edges (used by one triangle) and the Euler characteristic of meshes welded by
/// position.
fn welded_topology(meshes: &[&TriMesh]) -> (usize, i64) {
    let mut ids: HashMap<[u32; 3], u32> = HashMap::new();
    let mut edges: HashMap<(u32, u32), usize> = HashMap::new();
    let mut faces = 0i64;
    for m in meshes {
        let map = isolab_tests::position_ids(&m.positions, &mut ids);
        for t in &m.triangles {
            faces += 1;
            let v = t.map(|i| map[i as usize]);
            for k in 0..3 {
                let (a, b) = (v[k], v[(k + 1) % 3]);
                *edges.entry((a.min(b), a.max(b))).or_insert(0) += 1;
            }
        }
    }
    let boundary = edges.values().filter(|&&n| n == 1).count();
    (boundary, ids.len() as i64 - edges.len() as i64 + faces)
}

struct Source {
    dir: tempfile::TempDir,
    layout: Layout,
    whole: BTreeMap<u32, TriMesh>,
}

fn write(algorithm: &str, dims: [usize; 3], chunk: usize, lods: usize) -> Source {
    let map = voronoi(dims, 14);
    let extractor = labels::build(algorithm, &Options::new()).unwrap().unwrap();
    let plan = LabelBlockPlan::new(extractor.as_ref(), dims, chunk).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let config = NgConfig {
        lods,
        bits: 16,
        sharded: false,
        transform: isolab_io::neuroglancer::MultilodInfo::IDENTITY,
        names: Vec::new(),
        keep_work: true,
        legacy: false,
    };
    let report = ngp::write_source(extractor.as_ref(), &plan, LabelSamples::U16(&map), None, dir.path(), &config).unwrap();
    let mut surface = LabelSurface::default();
    extractor.extract_u16(LabelMap::new(dims, &map).unwrap(), &mut surface).unwrap();
    let whole = surface.label_meshes();
    assert_eq!(report.segments, whole.len());
    assert_eq!(report.fragments.len(), lods);
    let layout = Layout::new(&plan, lods, 16).unwrap();
    Source { dir, layout, whole }
}

/// A box's mesh of one label, with the box's low corner and size.
type Part = (TriMesh, [f64; 3], [f64; 3]);

/// Every label's float meshes at `level`, with their boxes.
fn level_meshes(s: &Source, level: usize) -> BTreeMap<u32, Vec<Part>> {
    let mut out: BTreeMap<u32, Vec<_>> = BTreeMap::new();
    let [cx, cy, cz] = s.layout.counts_at(level);
    for z in 0..cz {
        for y in 0..cy {
            for x in 0..cx {
                let p = [x as u32, y as u32, z as u32];
                let path = ngp::box_path(&s.dir.path().join(".isolab-work"), level, p);
                if !path.exists() {
                    continue;
                }
                let (lo, size) = s.layout.box_at(level, p);
                for (label, mesh) in boxfile::read_meshes(&path).unwrap() {
                    out.entry(label).or_default().push((mesh, lo, size));
                }
            }
        }
    }
    out
}

fn check(s: &Source) {
    let level0 = level_meshes(s, 0);
    assert_eq!(level0.keys().collect::<Vec<_>>(), s.whole.keys().collect::<Vec<_>>());
    let mut level0_vertices = std::collections::HashSet::new();
    for (label, parts) in &level0 {
        let whole = &s.whole[label];
        let sum: f64 = parts.iter().map(|(m, _, _)| area(m)).sum();
        assert!((sum - area(whole)).abs() <= 1e-4 * area(whole), "label {label}: level 0 area {sum} vs {}", area(whole));
        let meshes: Vec<&TriMesh> = parts.iter().map(|(m, _, _)| m).collect();
        let (open, euler) = welded_topology(&meshes);
        let (whole_open, whole_euler) = welded_topology(&[whole]);
        assert_eq!((open, euler), (whole_open, whole_euler), "label {label}: level 0 welded");
        for (m, lo, size) in parts {
            for p in &m.positions {
                level0_vertices.insert(p.to_array().map(f32::to_bits));
                for a in 0..3 {
                    assert!(
                        f64::from(p[a]) >= lo[a] && f64::from(p[a]) <= lo[a] + size[a],
                        "label {label}: vertex outside its box"
                    );
                }
            }
        }
    }
    for level in 1..s.layout.lods {
        let meshes = level_meshes(s, level);
        assert_eq!(meshes.len(), level0.len(), "level {level} keeps every label");
        let half = (s.layout.chunk << (level - 1)) as f64;
        for (label, parts) in &meshes {
            let all: Vec<&TriMesh> = parts.iter().map(|(m, _, _)| m).collect();
            let (open, _) = welded_topology(&all);
            assert_eq!(open, 0, "label {label}: level {level} has cracks between its boxes");
            for (m, lo, _) in parts {
                for t in &m.triangles {
                    // Each triangle lies in one child box of its box: per axis, all three
                    // vertices on one side of the midplane (on it counts as both).
                    for (a, low) in lo.iter().enumerate() {
                        let mid = low + half;
                        let v = t.map(|i| f64::from(m.positions[i as usize][a]));
                        assert!(
                            v.iter().all(|&c| c <= mid) || v.iter().all(|&c| c >= mid),
                            "label {label}: level {level} triangle crosses its box's grid"
                        );
                    }
                }
                for p in &m.positions {
                    let on_grid = (0..3).any(|a| ((f64::from(p[a]) - s.layout.origin[a]) / half).fract() == 0.0);
                    if on_grid {
                        assert!(
                            level0_vertices.contains(&p.to_array().map(f32::to_bits)),
                            "label {label}: level {level} vertex on a box face that level 0 does not have"
                        );
                    }
                }
            }
        }
    }
}

#[test]
fn surface_nets_fragments_reassemble_the_whole_map() {
    let s = write("surface-nets", [30, 26, 34], 8, 4);
    check(&s);
}

#[test]
fn marching_tetrahedra_fragments_reassemble_the_whole_map() {
    let s = write("marching-tetrahedra", [21, 18, 24], 6, 3);
    check(&s);
}
