//! Noise fields: the `asteroid` (the RMT paper's benchmark object) and game-style `terrain`.
//! Noise comes from `fastnoise-lite` (OpenSimplex2 with fractal Brownian motion), seeded.

use crate::field::{BlockSide, Field};
use crate::geometry::Aabb;
use crate::lattice::Grid;
use fastnoise_lite::{FastNoiseLite, FractalType, NoiseType};
use glam::Vec3;

/// A bound on the gradient of one octave of FastNoiseLite's OpenSimplex2 at frequency 1 (its
/// domain rotation included), in 3D. Measured, not proved: over 10⁷ random points in
/// `[-20, 20]³` for 8 seeds, then a local ascent from the 200 steepest, central differences
/// reached 10.14 at most (9.3-10.1 per seed); the 23 % margin is ours. The test
/// `noise_changes_no_faster_than_its_bound` checks it again. A proven bound from the kernel
/// (`(0.6 - r²)⁴ (g · d)` summed over the contributing lattice points) is about 60, which
/// would make sparse extraction prune six times less.
pub const NOISE_GRADIENT_BOUND_3D: f64 = 12.5;

/// [`NOISE_GRADIENT_BOUND_3D`] for 2D noise (its skewed domain included): 7.39 measured the
/// same way, every seed within 0.003 of it; 22 % margin.
pub const NOISE_GRADIENT_BOUND_2D: f64 = 9.0;

/// A Lipschitz bound of [`fbm`]'s noise: octave `i` has amplitude `gain^i / Σ gain^j` and
/// frequency `frequency 2^i`, so with FastNoiseLite's gain 1/2 and lacunarity 2 every octave
/// adds `frequency × bound / Σ gain^j`.
fn fbm_lipschitz(frequency: f32, octaves: i32, one_octave_bound: f64) -> f64 {
    let amplitudes: f64 = (0..octaves).map(|i| 0.5f64.powi(i)).sum();
    f64::from(frequency) * one_octave_bound * f64::from(octaves) / amplitudes
}

fn fbm(seed: i32, frequency: f32, octaves: i32) -> FastNoiseLite {
    let mut n = FastNoiseLite::with_seed(seed);
    n.set_noise_type(Some(NoiseType::OpenSimplex2));
    n.set_fractal_type(Some(FractalType::FBm));
    n.set_fractal_octaves(Some(octaves));
    n.set_frequency(Some(frequency));
    n
}

const ASTEROID_FREQUENCY: f32 = 2.5;
const ASTEROID_OCTAVES: i32 = 5;
const ASTEROID_AMPLITUDE: f32 = 0.1;

/// A sphere of radius 0.35 displaced along its radius by fractal 3D noise of amplitude 0.1.
pub struct Asteroid {
    noise: FastNoiseLite,
    seed: i32,
}

impl Asteroid {
    /// The asteroid for `seed`.
    pub fn new(seed: i32) -> Self {
        Self { noise: fbm(seed, ASTEROID_FREQUENCY, ASTEROID_OCTAVES), seed }
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
        p.length() - 0.35 - ASTEROID_AMPLITUDE * self.noise.get_noise_3d(p.x, p.y, p.z)
    }
    fn domain(&self) -> Aabb {
        Aabb::cube(0.5)
    }
    /// 1 for the distance to the centre, plus the noise's amplitude times its bound (measured
    /// for one octave: [`NOISE_GRADIENT_BOUND_3D`]).
    fn lipschitz(&self) -> Option<f64> {
        let noise = fbm_lipschitz(ASTEROID_FREQUENCY, ASTEROID_OCTAVES, NOISE_GRADIENT_BOUND_3D);
        Some(1.0 + f64::from(ASTEROID_AMPLITUDE) * noise)
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

const HEIGHT_FREQUENCY: f32 = 1.8;
const HEIGHT_OCTAVES: i32 = 5;
const WARP_FREQUENCY: f32 = 3.0;
const WARP_OCTAVES: i32 = 3;
const CAVE_FREQUENCY: f32 = 2.5;
const CAVE_OCTAVES: i32 = 2;
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
        Self {
            height: fbm(seed, HEIGHT_FREQUENCY, HEIGHT_OCTAVES),
            warp: fbm(seed.wrapping_add(1), WARP_FREQUENCY, WARP_OCTAVES),
            caves: fbm(seed.wrapping_add(2), CAVE_FREQUENCY, CAVE_OCTAVES),
        }
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
    /// `max(ground, min(cave, floor))` changes no faster than its fastest term: the ground's
    /// `1 + 0.12 L_h + 0.05 L_w`, the cave's `0.1 L_c`, the floor's 1 (noise bounds measured
    /// for one octave: [`NOISE_GRADIENT_BOUND_2D`], [`NOISE_GRADIENT_BOUND_3D`]).
    fn lipschitz(&self) -> Option<f64> {
        let height = fbm_lipschitz(HEIGHT_FREQUENCY, HEIGHT_OCTAVES, NOISE_GRADIENT_BOUND_2D);
        let warp = fbm_lipschitz(WARP_FREQUENCY, WARP_OCTAVES, NOISE_GRADIENT_BOUND_3D);
        let caves = fbm_lipschitz(CAVE_FREQUENCY, CAVE_OCTAVES, NOISE_GRADIENT_BOUND_3D);
        let ground = 1.0 + f64::from(HEIGHT_SCALE) * height + f64::from(WARP_SCALE) * warp;
        Some(ground.max(f64::from(CAVE_SCALE) * caves).max(1.0))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A point of `[-w, w]³` from two hashes of `i`.
    fn point_within(i: u64, w: f32) -> Vec3 {
        let h = |k: u64| {
            let mut x = i.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ k.wrapping_mul(0xD1B5_4A32_D192_ED03);
            x ^= x >> 31;
            x = x.wrapping_mul(0xBF58_476D_1CE4_E5B9);
            x ^= x >> 29;
            ((x >> 40) as f32 / (1u64 << 24) as f32 * 2.0 - 1.0) * w
        };
        Vec3::new(h(1), h(2), h(3))
    }

    #[test]
    fn noise_changes_no_faster_than_its_bound() {
        for seed in [DEFAULT_SEED_FOR_TESTS, 1, 7] {
            let one = fbm(seed, 1.0, 1);
            let (mut steepest_3d, mut steepest_2d) = (0.0f64, 0.0f64);
            for i in 0..200_000u64 {
                let p = point_within(i, 20.0);
                let q = p + point_within(i + (1 << 40), 1e-2);
                let d = f64::from(p.distance(q));
                let change_3d = f64::from(one.get_noise_3d(p.x, p.y, p.z) - one.get_noise_3d(q.x, q.y, q.z)).abs();
                let d_2d = f64::from(glam::Vec2::new(p.x - q.x, p.y - q.y).length());
                let change_2d = f64::from(one.get_noise_2d(p.x, p.y) - one.get_noise_2d(q.x, q.y)).abs();
                steepest_3d = steepest_3d.max(change_3d / d);
                steepest_2d = steepest_2d.max(change_2d / d_2d);
            }
            assert!(steepest_3d <= NOISE_GRADIENT_BOUND_3D, "seed {seed}: 3D {steepest_3d}");
            assert!(steepest_2d <= NOISE_GRADIENT_BOUND_2D, "seed {seed}: 2D {steepest_2d}");
            // The bound is not vacuous: random pairs come within a factor of two of it.
            assert!(steepest_3d > NOISE_GRADIENT_BOUND_3D / 2.0 && steepest_2d > NOISE_GRADIENT_BOUND_2D / 2.0);
        }
    }

    #[test]
    fn noise_fields_change_no_faster_than_their_lipschitz_bounds() {
        let fields: [&dyn Field; 2] = [&Asteroid::new(DEFAULT_SEED_FOR_TESTS), &Terrain::new(DEFAULT_SEED_FOR_TESTS)];
        for f in fields {
            let l = f.lipschitz().unwrap();
            let mut steepest = 0.0f64;
            for i in 0..200_000u64 {
                let p = point_within(i, 0.5);
                let q = p + point_within(i + (1 << 40), 2e-3);
                steepest = steepest.max(f64::from((f.value(p) - f.value(q)).abs()) / f64::from(p.distance(q)));
            }
            assert!(steepest <= l, "{}: {steepest} > {l}", f.name());
            assert!(steepest > l / 20.0, "{}: {steepest}, bound {l}", f.name());
        }
    }

    const DEFAULT_SEED_FOR_TESTS: i32 = crate::fields::DEFAULT_SEED;

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
