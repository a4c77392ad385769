//! Noise fields: the `asteroid` (the RMT paper's benchmark object) and game-style `terrain`.
//! Noise comes from `fastnoise-lite` (OpenSimplex2 with fractal Brownian motion), seeded.

use crate::field::Field;
use crate::geometry::Aabb;
use fastnoise_lite::{FastNoiseLite, FractalType, NoiseType};
use glam::Vec3;

fn fbm(seed: i32, frequency: f32, octaves: i32) -> FastNoiseLite {
    let mut n = FastNoiseLite::with_seed(seed);
    n.set_noise_type(Some(NoiseType::OpenSimplex2));
    n.set_fractal_type(Some(FractalType::FBm));
    n.set_fractal_octaves(Some(octaves));
    n.set_frequency(Some(frequency));
    n
}

/// A sphere of radius 0.35 displaced along its radius by fractal 3D noise of amplitude 0.1.
pub struct Asteroid {
    noise: FastNoiseLite,
    seed: i32,
}

impl Asteroid {
    /// The asteroid for `seed`.
    pub fn new(seed: i32) -> Self {
        Self { noise: fbm(seed, 2.5, 5), seed }
    }

    /// The seed it was built with.
    pub fn seed(&self) -> i32 {
        self.seed
    }
}

impl Field for Asteroid {
    fn name(&self) -> &str {
        "asteroid"
    }
    fn value(&self, p: Vec3) -> f32 {
        p.length() - 0.35 - 0.1 * self.noise.get_noise_3d(p.x, p.y, p.z)
    }
    fn domain(&self) -> Aabb {
        Aabb::cube(0.5)
    }
}

/// Terrain: solid below a fractal height field, with 3D noise warping the surface into overhangs
/// and carving caves. `y` is up; the domain is `[-0.5,0.5] x [-0.25,0.25] x [-0.5,0.5]`.
pub struct Terrain {
    height: FastNoiseLite,
    warp: FastNoiseLite,
    caves: FastNoiseLite,
}

impl Terrain {
    /// The terrain for `seed`.
    pub fn new(seed: i32) -> Self {
        Self { height: fbm(seed, 1.8, 5), warp: fbm(seed.wrapping_add(1), 3.0, 3), caves: fbm(seed.wrapping_add(2), 2.5, 2) }
    }
}

impl Terrain {
    /// The ground term: height field plus a warp (negative below ground).
    fn ground(&self, p: Vec3) -> f32 {
        p.y - 0.12 * self.height.get_noise_2d(p.x, p.z) + 0.05 * self.warp.get_noise_3d(p.x, p.y, p.z)
    }
}

impl Field for Terrain {
    fn name(&self) -> &str {
        "terrain"
    }
    fn value(&self, p: Vec3) -> f32 {
        let ground = self.ground(p);
        // Caves: remove material where the cave noise is high, but keep a solid floor.
        let cave = 0.1 * (self.caves.get_noise_3d(p.x, p.y, p.z) - 0.35);
        let floor = p.y + 0.2;
        ground.max(cave.min(floor))
    }
    fn domain(&self) -> Aabb {
        Aabb::new(Vec3::new(-0.5, -0.25, -0.5), Vec3::new(0.5, 0.25, 0.5))
    }
    /// Layers by depth below the ground: grass (sand in the low valleys) within 0.012 of it,
    /// dirt to 0.04, rock below and in the caves.
    fn material(&self, p: Vec3) -> u8 {
        use crate::materials::{DIRT, GRASS, ROCK, SAND};
        let depth = -self.ground(p);
        if depth < 0.012 {
            if p.y < -0.06 {
                SAND
            } else {
                GRASS
            }
        } else if depth < 0.04 {
            DIRT
        } else {
            ROCK
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn seeds_change_the_asteroid_and_repeat_exactly() {
        let p = Vec3::new(0.3, 0.1, -0.2);
        assert_eq!(Asteroid::new(1).value(p), Asteroid::new(1).value(p));
        assert_ne!(Asteroid::new(1).value(p), Asteroid::new(2).value(p));
    }

    #[test]
    fn terrain_is_solid_at_the_bottom_and_empty_at_the_top() {
        let t = Terrain::new(7);
        for x in [-0.4f32, 0.0, 0.4] {
            assert!(t.value(Vec3::new(x, -0.24, x)) < 0.0);
            assert!(t.value(Vec3::new(x, 0.24, -x)) > 0.0);
        }
    }
}
