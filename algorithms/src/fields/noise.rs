//! Noise fields: the `asteroid` (the RMT paper's benchmark object) and game-style `terrain`.
//! Noise comes from `fastnoise-lite` (OpenSimplex2 with fractal Brownian motion), seeded.

use crate::field::{BlockSide, Field};
use crate::geometry::Aabb;
use crate::lattice::Grid;
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

/// A bound on `|noise|` for every fractal noise here. FastNoiseLite scales OpenSimplex2 to about
/// `[-1, 1]` (its output constants 99.84 in 2D and 32.69 in 3D) and divides fractal sums by the
/// sum of the octaves' amplitudes, so FBm stays in the same range; 10⁸ random points of one
/// octave reached 0.99998. The 5 % margin is ours. Terrain uses it to skip cave noise far above
/// the ground and to prove whole blocks empty or full ([`Field::block_side`]); the test `every_terrain_noise_stays_within_the_bound` checks it.
pub const NOISE_BOUND: f32 = 1.05;

/// Terrain: solid below a fractal height field, with 3D noise warping the surface into overhangs
/// and carving caves. `y` is up; the domain is `[-0.5,0.5] x [-0.25,0.25] x [-0.5,0.5]`.
///
/// The field is `max(ground, min(cave, floor))` with `ground = y - 0.12 h(x, z) + 0.05 w(x, y, z)`,
/// `cave = 0.1 (c(x, y, z) - 0.35)` and `floor = y + 0.2`, for fractal noises `h`, `w`, `c`.
/// Blocks and grids sample the height `h` once per column ([`Field::sample_block`]), and streaming
/// skips blocks whose column heights and `NOISE_BOUND` prove them above the ground or below it
/// and the floor ([`Field::block_side`]).
pub struct Terrain {
    height: FastNoiseLite,
    warp: FastNoiseLite,
    caves: FastNoiseLite,
}

const HEIGHT_SCALE: f32 = 0.12;
const WARP_SCALE: f32 = 0.05;
const CAVE_SCALE: f32 = 0.1;
const CAVE_LEVEL: f32 = 0.35;
const FLOOR_DEPTH: f32 = 0.2;
/// The largest the cave term can be: `0.1 (NOISE_BOUND - 0.35)`.
const CAVE_MAX: f32 = CAVE_SCALE * (NOISE_BOUND - CAVE_LEVEL);
/// Slack for `f32` rounding in block bounds (values are a few tenths; rounding is ~1e-7).
const BOUND_SLACK: f32 = 1e-5;

impl Terrain {
    /// The terrain for `seed`.
    pub fn new(seed: i32) -> Self {
        Self { height: fbm(seed, 1.8, 5), warp: fbm(seed.wrapping_add(1), 3.0, 3), caves: fbm(seed.wrapping_add(2), 2.5, 2) }
    }

    /// The height term `0.12 h(x, z)`, the same for a whole column.
    fn scaled_height(&self, x: f32, z: f32) -> f32 {
        HEIGHT_SCALE * self.height.get_noise_2d(x, z)
    }

    /// The ground term given the column's [`Terrain::scaled_height`]: negative below ground.
    fn ground_given(&self, p: Vec3, scaled_height: f32) -> f32 {
        p.y - scaled_height + WARP_SCALE * self.warp.get_noise_3d(p.x, p.y, p.z)
    }

    /// The ground term: height field plus a warp (negative below ground).
    fn ground(&self, p: Vec3) -> f32 {
        self.ground_given(p, self.scaled_height(p.x, p.z))
    }

    /// The field's value given the column's height. Where the ground term is at least
    /// [`CAVE_MAX`], the cave term cannot win the `max`, so the cave noise is not evaluated.
    fn value_given(&self, p: Vec3, scaled_height: f32) -> f32 {
        let ground = self.ground_given(p, scaled_height);
        if ground >= CAVE_MAX {
            return ground;
        }
        // Caves: remove material where the cave noise is high, but keep a solid floor.
        let cave = CAVE_SCALE * (self.caves.get_noise_3d(p.x, p.y, p.z) - CAVE_LEVEL);
        let floor = p.y + FLOOR_DEPTH;
        ground.max(cave.min(floor))
    }
}

impl Field for Terrain {
    fn name(&self) -> &str {
        "terrain"
    }
    fn value(&self, p: Vec3) -> f32 {
        self.value_given(p, self.scaled_height(p.x, p.z))
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
    fn sample_block(&self, grid: &Grid, lo: [usize; 3], dims: [usize; 3], out: &mut [f32]) {
        let [nx, ny, nz] = dims;
        let mut heights = vec![0.0f32; nx];
        for z in 0..nz {
            for (x, h) in heights.iter_mut().enumerate() {
                let p = grid.position(lo[0] + x, lo[1], lo[2] + z);
                *h = self.scaled_height(p.x, p.z);
            }
            for y in 0..ny {
                let row = &mut out[(z * ny + y) * nx..(z * ny + y + 1) * nx];
                for (x, (v, &h)) in row.iter_mut().zip(&heights).enumerate() {
                    *v = self.value_given(grid.position(lo[0] + x, lo[1] + y, lo[2] + z), h);
                }
            }
        }
    }
    /// Outside when even the lowest sample, under the highest column and the most negative warp,
    /// is above `iso`; inside when the highest sample, over the lowest column and the most
    /// positive warp, is below `iso` and so is `min(cave, floor)` (the floor, or the cave term's
    /// bound).
    fn block_side(&self, grid: &Grid, lo: [usize; 3], dims: [usize; 3], iso: f32) -> Option<BlockSide> {
        let [nx, ny, nz] = dims;
        if nx == 0 || ny == 0 || nz == 0 {
            return None;
        }
        let (mut h_lo, mut h_hi) = (f32::INFINITY, f32::NEG_INFINITY);
        for z in 0..nz {
            for x in 0..nx {
                let p = grid.position(lo[0] + x, lo[1], lo[2] + z);
                let h = self.scaled_height(p.x, p.z);
                h_lo = h_lo.min(h);
                h_hi = h_hi.max(h);
            }
        }
        let y_lo = grid.position(lo[0], lo[1], lo[2]).y;
        let y_hi = grid.position(lo[0], lo[1] + ny - 1, lo[2]).y;
        let warp = WARP_SCALE * NOISE_BOUND + BOUND_SLACK;
        if y_lo - h_hi - warp >= iso {
            return Some(BlockSide::Outside);
        }
        let ground_hi = y_hi - h_lo + warp;
        let cave_or_floor_hi = CAVE_MAX.min(y_hi + FLOOR_DEPTH) + BOUND_SLACK;
        (ground_hi.max(cave_or_floor_hi) < iso).then_some(BlockSide::Inside)
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

    /// A deterministic point in `[-1, 8]³` (the issue-size world reaches x, z = 7.5).
    fn point(i: u64) -> Vec3 {
        let mut h = i.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ 0xDEAD_BEEF;
        let mut next = || {
            h ^= h >> 33;
            h = h.wrapping_mul(0xFF51_AFD7_ED55_8CCD);
            h ^= h >> 33;
            (h >> 40) as f32 / (1u64 << 24) as f32 * 9.0 - 1.0
        };
        Vec3::new(next(), next(), next())
    }

    #[test]
    fn every_terrain_noise_stays_within_the_bound() {
        let t = Terrain::new(7);
        let mut most = 0.0f32;
        for i in 0..300_000 {
            let p = point(i);
            for v in [t.height.get_noise_2d(p.x, p.z), t.warp.get_noise_3d(p.x, p.y, p.z), t.caves.get_noise_3d(p.x, p.y, p.z)] {
                most = most.max(v.abs());
            }
        }
        assert!(most <= NOISE_BOUND, "|noise| reached {most}");
        assert!(most > 0.8, "the sample should come near the bound: {most}");
    }

    /// The cave short-cut changes nothing: the value equals the whole formula bit for bit.
    #[test]
    fn skipping_the_caves_above_ground_changes_no_value() {
        let t = Terrain::new(7);
        let mut skipped = 0;
        for i in 0..100_000 {
            let mut p = point(i);
            p.y = p.y * 0.06 - 0.2;
            let ground = t.ground(p);
            let cave = CAVE_SCALE * (t.caves.get_noise_3d(p.x, p.y, p.z) - CAVE_LEVEL);
            let whole = ground.max(cave.min(p.y + FLOOR_DEPTH));
            assert_eq!(t.value(p).to_bits(), whole.to_bits(), "at {p}");
            skipped += usize::from(ground >= CAVE_MAX);
        }
        assert!(skipped > 1000 && skipped < 99_000, "{skipped} of the points skipped the caves");
    }

    /// A world grid at the large-world spacing, sampled beyond the default domain.
    fn world() -> Grid {
        Grid { origin: Vec3::new(-0.5, -0.25, -0.5), spacing: 0.5 / 512.0, dims: [4097, 513, 4097] }
    }

    #[test]
    fn blocks_and_grids_sample_the_value_bit_for_bit() {
        let t = Terrain::new(7);
        let grid = world();
        for (k, lo) in [[0, 0, 0], [3001, 200, 17], [64, 480, 4000], [2048, 96, 2048]].into_iter().enumerate() {
            let dims = [9, 33, 5];
            let mut block = vec![0.0; 9 * 33 * 5];
            t.sample_block(&grid, lo, dims, &mut block);
            for (i, v) in block.iter().enumerate() {
                let (x, y, z) = (i % 9, i / 9 % 33, i / (9 * 33));
                let p = grid.position(lo[0] + x, lo[1] + y, lo[2] + z);
                assert_eq!(v.to_bits(), t.value(p).to_bits(), "block {k}, sample {x},{y},{z}");
            }
        }
        let small = Grid { origin: Vec3::new(-0.5, -0.25, -0.5), spacing: 1.0 / 24.0, dims: [25, 13, 25] };
        let mut whole = vec![0.0; 25 * 13 * 25];
        t.sample_grid(&small, 0.0, &mut whole);
        for (i, v) in whole.iter().enumerate() {
            let p = small.position(i % 25, i / 25 % 13, i / (25 * 13));
            assert_eq!(v.to_bits(), t.value(p).to_bits(), "grid sample {i}");
        }
    }

    /// Wherever a block's side is claimed without sampling, sampling it agrees; both sides occur.
    #[test]
    fn proven_block_sides_hold_at_every_sample() {
        let t = Terrain::new(7);
        let grid = world();
        let mut claims = [0usize; 2];
        let mut values = vec![0.0; 17 * 17 * 17];
        for i in 0..400u64 {
            let p = point(i);
            let lo = [(p.x.abs() * 450.0) as usize, (i as usize * 31) % 496, (p.z.abs() * 450.0) as usize];
            for iso in [0.0, 0.02, -0.03] {
                let Some(side) = t.block_side(&grid, lo, [17, 17, 17], iso) else { continue };
                t.sample_block(&grid, lo, [17, 17, 17], &mut values);
                match side {
                    BlockSide::Outside => assert!(values.iter().all(|&v| v >= iso), "block at {lo:?} is not all outside {iso}"),
                    BlockSide::Inside => assert!(values.iter().all(|&v| v < iso), "block at {lo:?} is not all inside {iso}"),
                }
                claims[usize::from(side == BlockSide::Inside)] += 1;
            }
        }
        assert!(claims[0] > 50 && claims[1] > 10, "claims outside/inside: {claims:?}");
    }
}
