//! Svoboda's own setup, for a like-for-like ratio: the paper's field (Listings 1-2: Unity's 2D
//! Perlin noise at (x, z), times y, coordinates scaled by a zoom) and its marching cubes, where
//! "adjacent cubes are not able to share vertices" (section 5): every triangle gets three new
//! vertices, on one thread, into fresh vectors, as `Generate.cs` builds a new `Mesh` each time.

use fastnoise_lite::{FastNoiseLite, NoiseType};
use glam::Vec3;
use isolab_algorithms::geometry::Aabb;
use isolab_algorithms::tables::marching_cubes::{CORNERS, EDGES, TABLE};
use isolab_algorithms::{Field, Grid};

/// The zoom of Listing 2 (the paper's value is a setting it does not state; ours).
pub const ZOOM: f32 = 4.0;
/// The iso-value (the paper lets the user choose and does not state one; ours puts the hills
/// inside the unit box for most of the noise's range).
pub const ISO: f32 = 0.8;
/// The noise seed (the paper draws one at random).
pub const SEED: i32 = 2020;

/// `PerlinNoise(nx, nz) * ny - ISO` over the unit cube, with `n = ZOOM · p`: negative below the
/// hills. Unity's `Mathf.PerlinNoise` returns [0, 1]; FastNoiseLite's Perlin [-1, 1], mapped.
pub struct PaperField {
    noise: FastNoiseLite,
}

impl Default for PaperField {
    fn default() -> Self {
        let mut noise = FastNoiseLite::with_seed(SEED);
        noise.set_noise_type(Some(NoiseType::Perlin));
        noise.set_frequency(Some(1.0));
        Self { noise }
    }
}

impl Field for PaperField {
    fn name(&self) -> &str {
        "svoboda-heightfield"
    }
    fn value(&self, p: Vec3) -> f32 {
        let n = ZOOM * p;
        0.5 * (self.noise.get_noise_2d(n.x, n.z) + 1.0) * n.y - ISO
    }
    fn domain(&self) -> Aabb {
        Aabb::new(Vec3::ZERO, Vec3::ONE)
    }
}

/// The paper's marching cubes: the same case table as ours, but three new vertices for every
/// triangle (no sharing between cubes or within one), single-threaded, fresh output vectors.
/// Returns the vertices and the triangle count.
pub fn unshared_marching_cubes(values: &[f32], grid: &Grid, iso: f32) -> (Vec<Vec3>, usize) {
    let [nx, ny, nz] = grid.dims;
    let at = |x: usize, y: usize, z: usize| values[x + nx * (y + ny * z)];
    let mut vertices = Vec::new();
    for z in 0..nz.saturating_sub(1) {
        for y in 0..ny.saturating_sub(1) {
            for x in 0..nx.saturating_sub(1) {
                // Like the paper's `GridCell`: the cube's eight points read once, then its triangles.
                let corners: [(f32, Vec3); 8] = std::array::from_fn(|c| {
                    let [dx, dy, dz] = CORNERS[c].map(usize::from);
                    (at(x + dx, y + dy, z + dz), grid.position(x + dx, y + dy, z + dz))
                });
                let case = corners.iter().enumerate().fold(0usize, |case, (c, p)| case | (usize::from(p.0 < iso) << c));
                for triangle in TABLE[case].triangles() {
                    for &e in triangle {
                        let (a, b) = EDGES[usize::from(e)];
                        let ((va, pa), (vb, pb)) = (corners[usize::from(a)], corners[usize::from(b)]);
                        let t = if vb != va { ((iso - va) / (vb - va)).clamp(0.0, 1.0) } else { 0.5 };
                        vertices.push(pa + t * (pb - pa));
                    }
                }
            }
        }
    }
    let triangles = vertices.len() / 3;
    (vertices, triangles)
}

#[cfg(test)]
mod tests {
    use super::*;
    use isolab_algorithms::{extractors, Extraction, Lattice, Samples};
    use std::sync::Arc;

    #[test]
    fn unshared_cubes_make_our_triangles_with_three_vertices_each_on_the_surface() {
        let field: Arc<dyn Field> = Arc::new(PaperField::default());
        let grid = Grid::with_dims(&field.domain(), [21, 21, 21]).unwrap();
        let samples = Samples::sample(field.clone(), Lattice::Cubic(grid), 0.0).unwrap();
        let (vertices, triangles) = unshared_marching_cubes(samples.values(), &grid, 0.0);
        let mut ours = Extraction::default();
        extractors::by_name("marching-cubes").unwrap().extract(&samples, &mut ours).unwrap();
        assert!(triangles > 100, "{triangles}");
        assert_eq!(triangles, ours.surface.triangles.len(), "the same table, so the same triangles");
        assert_eq!(vertices.len(), 3 * triangles);
        assert!(vertices.len() > ours.surface.positions.len() * 5, "unshared: about six times the shared vertices");
        // Linear interpolation on each edge: the field is nearly zero at every vertex (one cell = 1/20).
        let worst = vertices.iter().map(|&p| field.value(p).abs()).fold(0.0, f32::max);
        assert!(worst < 0.2, "{worst}");
    }
}
