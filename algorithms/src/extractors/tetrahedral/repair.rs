//! The repair RMT's guard uses: samples whose merging left a non-manifold vertex get one vertex
//! per crossing again and only the geometry pass reruns; unused vertices are dropped at the end.

use super::{owns, regenerate_anchors, topology, Addresser, TetKind, TetScratch};
use crate::extract::Extraction;
use crate::geometry::edge_crossing_fraction;
use crate::samples::Samples;
use glam::Vec3;

/// Forbids merging at the samples that made the merged vertices among `vertices`, gives each of
/// their crossings its own new vertex, and re-emits the triangles of the tetrahedra around them
/// ([`regenerate_anchors`]; the whole geometry pass on BCC lattices). Returns whether anything
/// changed. The old merged vertices stay in `out.surface.positions`, unreferenced, until
/// [`finish_repair`].
pub fn unmerge_and_regenerate(samples: &Samples, scratch: &mut TetScratch, out: &mut Extraction, vertices: &[u32]) -> bool {
    let lattice = *samples.lattice();
    let topo = topology(TetKind::of(&lattice));
    let at = Addresser::new(&lattice);
    let values = samples.values();
    let iso = samples.iso();
    let mut unmerged = std::mem::take(&mut scratch.unmerged);
    unmerged.clear();
    for &v in vertices {
        let Some(&(sample, members, _)) = scratch.owner.get(v as usize) else { continue };
        let i = sample as usize;
        if members < 2 || scratch.no_merge[i] {
            continue;
        }
        scratch.no_merge[i] = true;
        unmerged.push(i);
        let q = at.coords(i);
        let (vi, base) = (values[i], out.surface.positions.len() as u32);
        let mut packed = 0u64;
        let mut slot = 0u64;
        let neighbour = |d: &[i32; 3]| at.index([q[0] + d[0], q[1] + d[1], q[2] + d[2]]);
        // The edges the vertex pass gives crossings: those in a tetrahedron of the lattice.
        let present = topo.directions.iter().enumerate().fold(0u16, |n, (k, d)| n | u16::from(neighbour(d).is_some()) << k);
        let in_tetrahedra = topo.edges_in_tetrahedra(present);
        for (k, d) in topo.directions.iter().enumerate().filter(|&(k, _)| in_tetrahedra >> k & 1 == 1) {
            let Some(j) = neighbour(d) else { continue };
            let vj = values[j];
            if (vj < iso) != (vi < iso) && owns(i, vi, j, vj, iso) {
                let step = Vec3::new(d[0] as f32, d[1] as f32, d[2] as f32) * (0.5 * at.corners.spacing);
                out.surface.positions.push(at.position(q) + step * edge_crossing_fraction(vi, vj, iso));
                scratch.owner.push((sample, 1, k as u8));
                packed |= slot << (4 * k);
                slot += 1;
            }
        }
        scratch.base[i] = base;
        scratch.slots[i] = packed;
    }
    let changed = !unmerged.is_empty();
    if changed {
        let time = out.stats.times.geometry;
        regenerate_anchors(samples, scratch, out, &unmerged);
        out.stats.times.geometry += time;
    }
    scratch.unmerged = unmerged;
    changed
}

/// After repairs: drops vertices no triangle uses (renumbering the rest in order). `used` is a
/// buffer for the renumbering, kept by the caller. Normals come after ([`compute_normals`](super::engine::compute_normals)).
pub fn finish_repair(out: &mut Extraction, used: &mut Vec<u32>) {
    let mesh = &mut out.surface;
    used.clear();
    used.resize(mesh.positions.len(), u32::MAX);
    for t in &mesh.triangles {
        for &v in t {
            used[v as usize] = 0;
        }
    }
    let mut next = 0u32;
    for (v, u) in used.iter_mut().enumerate() {
        if *u == 0 {
            *u = next;
            mesh.positions[next as usize] = mesh.positions[v];
            next += 1;
        }
    }
    mesh.positions.truncate(next as usize);
    let origins = &mut out.origins.vertices;
    if origins.len() == used.len() {
        for (v, &u) in used.iter().enumerate() {
            if u != u32::MAX {
                origins[u as usize] = origins[v];
            }
        }
        origins.truncate(next as usize);
    }
    for t in &mut mesh.triangles {
        *t = t.map(|v| used[v as usize]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::extractors::regularised_marching_tetrahedra::RmtOptions;
    use crate::extractors::tetrahedral::extract_tetrahedral;
    use crate::lattice::{Grid, Lattice};
    use crate::mesh::ManifoldCheck;

    /// Each repair round, re-emitting only the anchors around the unmerged samples gives the
    /// triangles and counts the whole geometry pass gives, on cubic grids where the guard repairs.
    #[test]
    fn a_partial_repass_equals_the_whole_pass() {
        let mut rounds = 0;
        for name in ["torus", "csg", "thin", "gyroid", "terrain"] {
            let field = crate::fields::builtin(name, Default::default()).unwrap();
            let grid = Grid::covering(&field.domain(), 51).unwrap();
            let samples = Samples::sample(field, Lattice::Cubic(grid), 0.0).unwrap();
            let (mut scratch, mut out) = (TetScratch::default(), Extraction::default());
            extract_tetrahedral(&samples, &RmtOptions::default(), &mut scratch, &mut out).unwrap();
            let mut check = ManifoldCheck::default();
            loop {
                let defects = check.defects_among(&out.surface, |v| scratch.is_merged(v)).to_vec();
                let (mut whole_scratch, mut whole) = (scratch.clone(), out.clone());
                whole_scratch.anchors_valid = false;
                let changed = unmerge_and_regenerate(&samples, &mut scratch, &mut out, &defects);
                unmerge_and_regenerate(&samples, &mut whole_scratch, &mut whole, &defects);
                if !changed {
                    break;
                }
                rounds += 1;
                assert_eq!(out.surface.triangles, whole.surface.triangles, "{name}");
                let stats = |o: &Extraction| (o.stats.discarded_triangles, o.stats.active_cells);
                assert_eq!(stats(&out), stats(&whole), "{name}");
            }
        }
        assert!(rounds > 0, "no field needed a repair");
    }
}
