//! Materials: one material id per sample, and the material of each surface vertex.
//!
//! Following the marching cubes terrain post (`../shared/papers/blog-marching-cubes-terrain-materials.txt`,
//! "Material"): a vertex made on a lattice edge between two samples that straddle the iso-value
//! takes the material of the edge's solid (inside) sample, of which there is exactly one. This
//! covers marching cubes and marching tetrahedra, whose vertices lie on lattice edges (cube edges
//! and, for the Kuhn split, face and body diagonals). Vertices that lie on no lattice edge (dual
//! methods' cell vertices, merged clusters) take the material of the nearest inside corner of the
//! cell holding them, the natural extension of the same rule.
//!
//! Fields say which material is where through [`Field::material`] (terrain: grass and sand at the
//! surface, dirt below, rock deeper); brushes paint their own ([`crate::chunks::Brush`]).

use crate::field::Field;
use crate::lattice::{Grid, LatticePlace};
use glam::Vec3;
use rayon::prelude::*;

/// Names of the built-in materials, by id.
pub const NAMES: [&str; 5] = ["rock", "dirt", "grass", "sand", "clay"];

/// Display colours (sRGB) of the built-in materials, by id.
pub const COLOURS: [[u8; 3]; 5] = [[128, 124, 120], [134, 96, 62], [92, 150, 70], [222, 200, 140], [190, 82, 60]];

/// The display colour of material `id` (grey past the built-in ones).
pub fn colour(id: u8) -> [u8; 3] {
    COLOURS.get(id as usize).copied().unwrap_or([160, 160, 160])
}

/// Rock (the default, [`crate::field::DEFAULT_MATERIAL`]).
pub const ROCK: u8 = crate::field::DEFAULT_MATERIAL;
/// Dirt.
pub const DIRT: u8 = 1;
/// Grass.
pub const GRASS: u8 = 2;
/// Sand.
pub const SAND: u8 = 3;
/// Clay (what the terrain experiments' brushes add).
pub const CLAY: u8 = 4;

/// The name of material `id` (`"material N"` past the built-in ones).
pub fn name(id: u8) -> String {
    NAMES.get(id as usize).map_or_else(|| format!("material {id}"), |s| (*s).to_string())
}

/// The field's material at every sample of `grid` (in parallel, x fastest).
pub fn sample(field: &dyn Field, grid: &Grid) -> Vec<u8> {
    let [nx, ny, nz] = grid.dims;
    let mut out = vec![0u8; grid.len()];
    out.par_chunks_mut(nx * ny).enumerate().take(nz).for_each(|(z, slice)| {
        for y in 0..ny {
            for x in 0..nx {
                slice[x + nx * y] = field.material(grid.position(x, y, z));
            }
        }
    });
    out
}

/// The material of a vertex at `p` (world space) on the samples `values` of `grid` with
/// `materials`: the inside sample of its lattice edge, else the nearest inside sample around it,
/// else the nearest sample's.
pub fn vertex_material(grid: &Grid, values: &[f32], iso: f32, materials: &[u8], p: Vec3) -> u8 {
    let max = grid.dims.map(|d| d.saturating_sub(1) as f32);
    let snapped = grid.index_coords(p);
    let q: [f32; 3] = std::array::from_fn(|a| snapped[a].clamp(0.0, max[a]));
    let index = |c: [usize; 3]| grid.index(c[0], c[1], c[2]);
    let lo = q.map(|c| c.floor() as usize);
    if let LatticePlace::Edge(a, b) = grid.place_of_index(q) {
        match (values[a] < iso, values[b] < iso) {
            (true, false) => return materials[a],
            (false, true) => return materials[b],
            _ => {}
        }
    }
    // The nearest inside sample within one spacing of the nearest sample (the nearest sample if
    // none is inside): cell vertices, and crossings rounded onto a sample.
    let centre = q.map(|c| c.round() as isize);
    let mut best = (f32::INFINITY, false, materials[index(lo)]);
    for dz in -1..=1isize {
        for dy in -1..=1isize {
            for dx in -1..=1isize {
                let c = [centre[0] + dx, centre[1] + dy, centre[2] + dz];
                if (0..3).any(|a| c[a] < 0 || c[a] as f32 > max[a]) {
                    continue;
                }
                let c = c.map(|v| v as usize);
                let i = index(c);
                let inside = values[i] < iso;
                let d: f32 = (0..3).map(|a| (q[a] - c[a] as f32).powi(2)).sum();
                if (inside && !best.1) || (inside == best.1 && d < best.0) {
                    best = (d, inside, materials[i]);
                }
            }
        }
    }
    best.2
}

/// Materials of every vertex of `positions` (world space); see [`vertex_material`].
pub fn vertex_materials(grid: &Grid, values: &[f32], iso: f32, materials: &[u8], positions: &[Vec3], out: &mut Vec<u8>) {
    out.clear();
    out.par_extend(positions.par_iter().map(|&p| vertex_material(grid, values, iso, materials, p)));
}

/// How many vertices have each material id (index = id).
pub fn histogram(vertex_materials: &[u8]) -> Vec<usize> {
    let mut counts = vec![0usize; vertex_materials.iter().copied().max().map_or(0, |m| m as usize + 1)];
    for &m in vertex_materials {
        counts[m as usize] += 1;
    }
    counts
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid() -> Grid {
        Grid { origin: Vec3::new(1.0, 2.0, 3.0), spacing: 0.5, dims: [3, 3, 3] }
    }

    #[test]
    fn an_edge_vertex_takes_its_inside_sample() {
        let g = grid();
        // Inside below z = 1 (sample index), materials numbered by sample.
        let values: Vec<f32> = (0..27).map(|i| if i / 9 == 0 { -1.0 } else { 1.0 }).collect();
        let materials: Vec<u8> = (0..27).map(|i| i as u8).collect();
        // A vertex on the z-edge from sample (1, 2, 0) to (1, 2, 1), 30 % of the way.
        let p = g.position(1, 2, 0) + Vec3::Z * 0.3 * g.spacing;
        assert_eq!(vertex_material(&g, &values, 0.0, &materials, p), g.index(1, 2, 0) as u8);
        // On a face diagonal from (0, 0, 0) to (1, 1, 0)... both inside: falls back to the cell.
        let q = g.position(0, 0, 0) + Vec3::new(0.4, 0.4, 0.0) * g.spacing;
        assert_eq!(vertex_material(&g, &values, 0.0, &materials, q), 0);
        // A cell-centre vertex: the nearest inside corner.
        let c = g.position(1, 1, 0) + Vec3::new(0.8, 0.3, 0.45) * g.spacing;
        assert_eq!(vertex_material(&g, &values, 0.0, &materials, c), g.index(2, 1, 0) as u8);
        assert_eq!(histogram(&[0, 2, 2]), vec![1, 0, 2]);
        assert_eq!(name(2), "grass");
        assert_eq!(name(9), "material 9");
    }
}
