//! Shared helpers for the integration tests in `tests/tests/`, and the README's Rust quick start
//! as a doc test (`ReadmeQuickStart`, built for doc tests only).

use glam::Vec3;
use isolab_algorithms::{Extraction, Extractor, Grid, Lattice, Samples, TriMesh};
use isolab_metrics::{topology, Topology};

/// Path of a shipped model.
pub fn model(name: &str) -> String {
    format!("{}/../models/{name}", env!("CARGO_MANIFEST_DIR"))
}

/// A built-in field by name, or a shipped model (`name.obj`) as a signed-distance field.
pub fn object_field(name: &str) -> std::sync::Arc<dyn isolab_algorithms::Field> {
    if name.ends_with(".obj") {
        isolab_pipeline::load_field(&model(name), Default::default()).expect("shipped model")
    } else {
        isolab_algorithms::fields::builtin(name, Default::default()).expect("built-in field")
    }
}

/// Samples on a unit-spaced cubic grid of `dims`, from a closure of the integer coordinates.
pub fn grid_samples(dims: [usize; 3], mut value: impl FnMut(usize, usize, usize) -> f32) -> Samples<'static> {
    let grid = Grid { origin: Vec3::ZERO, spacing: 1.0, dims };
    let mut values = Vec::with_capacity(grid.len());
    for z in 0..dims[2] {
        for y in 0..dims[1] {
            for x in 0..dims[0] {
                values.push(value(x, y, z));
            }
        }
    }
    Samples::from_values(Lattice::Cubic(grid), values, 0.0).expect("finite values")
}

/// Samples on a unit-spaced cubic grid (`bcc = false`) or BCC lattice (`bcc = true`: the corner
/// grid of `dims` plus its cell centres) from a closure of **doubled** integer coordinates: corner
/// `(x, y, z)` is `(2x, 2y, 2z)`, the centre of cell `(x, y, z)` is `(2x+1, 2y+1, 2z+1)`.
pub fn lattice_samples(bcc: bool, dims: [usize; 3], mut value: impl FnMut([i32; 3]) -> f32) -> Samples<'static> {
    let grid = Grid { origin: Vec3::ZERO, spacing: 1.0, dims };
    let mut values = Vec::new();
    let mut fill = |g: &Grid, odd: i32| {
        for z in 0..g.dims[2] {
            for y in 0..g.dims[1] {
                for x in 0..g.dims[0] {
                    values.push(value([2 * x as i32 + odd, 2 * y as i32 + odd, 2 * z as i32 + odd]));
                }
            }
        }
    };
    fill(&grid, 0);
    if bcc {
        fill(&grid.centres(), 1);
    }
    let lattice = if bcc { Lattice::Bcc(grid) } else { Lattice::Cubic(grid) };
    Samples::from_values(lattice, values, 0.0).expect("finite values")
}

/// Samples on a cubic or BCC lattice of `n`³ corners from `value` at world points in the unit
/// cube, outside on the border: the boundary samples and, on a BCC lattice, the centres of the
/// boundary cells (the BCC tetrahedra do not reach past them, so the surface stays inside the
/// tetrahedralised region).
pub fn unit_cube_samples(bcc: bool, n: usize, mut value: impl FnMut(Vec3) -> f32) -> Samples<'static> {
    let last = 2 * (n as i32 - 1);
    lattice_samples(bcc, [n, n, n], |d| {
        if d.iter().any(|&c| c <= 1 || c >= last - 1) {
            return 1.0;
        }
        value(Vec3::new(d[0] as f32, d[1] as f32, d[2] as f32) / last as f32)
    })
}

/// Gaussian blobs `(centre, radius)` in the unit cube on either lattice ([`unit_cube_samples`]):
/// inside where their summed density exceeds `threshold`.
pub fn lattice_blobs(bcc: bool, n: usize, blobs: &[(Vec3, f32)], threshold: f32) -> Samples<'static> {
    unit_cube_samples(bcc, n, |p| {
        threshold - blobs.iter().map(|&(c, r)| (-(p - c).length_squared() / (r * r)).exp()).sum::<f32>()
    })
}

/// Runs `extractor` on `samples`.
pub fn extract(extractor: &dyn Extractor, samples: &Samples) -> Extraction {
    let mut out = Extraction::default();
    extractor.extract(samples, &mut out).expect("extraction succeeds");
    out
}

/// What orientation a test demands beyond consistency.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Orientation {
    /// Consistent and outward (positive volume).
    Outward,
    /// Consistent only (smoothing may collapse a one-sample feature to zero or negative volume).
    Consistent,
}

/// The invariant checker every extractor test ends with: not empty, closed, edge- and
/// vertex-manifold, consistently oriented, outward, no unused vertex, every index in range, and
/// an even Euler characteristic no larger than twice the components (a union of closed
/// orientable surfaces). Panics with the topology report on failure; returns it otherwise. An
/// empty mesh fails (an extractor returning nothing would pass every other check): where empty
/// is right, use [`assert_closed_manifold_or_empty`].
pub fn assert_closed_manifold(mesh: &TriMesh, what: &str) -> Topology {
    assert_closed_manifold_with(mesh, what, Orientation::Outward)
}

/// [`assert_closed_manifold`], accepting an empty mesh (for inputs whose field may keep its sign).
pub fn assert_closed_manifold_or_empty(mesh: &TriMesh, what: &str) -> Topology {
    if mesh.triangles.is_empty() {
        assert!(mesh.positions.is_empty(), "{what}: no triangles but {} vertices", mesh.positions.len());
        return topology(mesh);
    }
    assert_closed_manifold(mesh, what)
}

/// Whether the samples change sign (some below the iso-value, some above).
pub fn changes_sign(samples: &Samples) -> bool {
    let iso = samples.iso();
    samples.values().iter().any(|&v| v < iso) && samples.values().iter().any(|&v| v > iso)
}

/// For an extraction of `samples`: [`assert_closed_manifold`] where the samples change sign, an
/// empty mesh where they do not.
pub fn assert_closed_manifold_for(samples: &Samples, mesh: &TriMesh, what: &str) -> Topology {
    if changes_sign(samples) {
        assert_closed_manifold(mesh, what)
    } else {
        assert!(mesh.triangles.is_empty() && mesh.positions.is_empty(), "{what}: the field keeps its sign, yet a mesh");
        topology(mesh)
    }
}

/// [`assert_closed_manifold`] with a choice of orientation demand.
pub fn assert_closed_manifold_with(mesh: &TriMesh, what: &str, orientation: Orientation) -> Topology {
    let n = mesh.positions.len() as u32;
    assert!(mesh.triangles.iter().flatten().all(|&i| i < n), "{what}: index out of range");
    assert!(!mesh.triangles.is_empty(), "{what}: empty mesh");
    let t = topology(mesh);
    let outward_ok = orientation == Orientation::Consistent || t.outward;
    assert!(t.is_watertight_manifold() && outward_ok && t.unused_vertices == 0, "{what}: {t:#?}");
    assert!(t.euler % 2 == 0 && t.euler <= 2 * t.components as i64, "{what}: euler {} with {} components", t.euler, t.components);
    t
}

/// A smooth random field on an `n^3` unit grid: Gaussian blobs `(x, y, z, radius)` in `[0, 1]^3`
/// summed and subtracted from `threshold` (inside where the blobs are dense), forced outside on the
/// border so the surface is closed.
pub fn blob_field(n: usize, blobs: &[(f32, f32, f32, f32)], threshold: f32) -> Samples<'static> {
    grid_samples([n, n, n], |x, y, z| {
        if x == 0 || y == 0 || z == 0 || x == n - 1 || y == n - 1 || z == n - 1 {
            return 1.0;
        }
        let p = Vec3::new(x as f32, y as f32, z as f32) / (n - 1) as f32;
        let density: f32 =
            blobs.iter().map(|&(bx, by, bz, r)| (-(p - Vec3::new(bx, by, bz)).length_squared() / (r * r)).exp()).sum();
        threshold - density
    })
}

/// A 4x4x4 grid whose inner 2x2x2 block carries cube pattern `case` (bit `c` set: table corner `c`
/// inside) with values from `value(corner, inside)`, and whose outer layer is outside.
pub fn embedded_case(case: u8, value: impl Fn(usize, bool) -> f32) -> Samples<'static> {
    grid_samples([4, 4, 4], |x, y, z| {
        let inner = (1..=2).contains(&x) && (1..=2).contains(&y) && (1..=2).contains(&z);
        if !inner {
            return 1.0;
        }
        // Table corner numbering: 0 (0,0,0) 1 (1,0,0) 2 (1,1,0) 3 (0,1,0), +4 for z = 1.
        let corner = [0, 1, 3, 2][(x - 1) + 2 * (y - 1)] + 4 * (z - 1);
        value(corner, case >> corner & 1 == 1)
    })
}

/// The shipped models (`*.obj` file names), sorted.
pub fn shipped_models() -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(model(""))
        .expect("the shipped models folder")
        .map(|e| e.expect("a directory entry").file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".obj"))
        .collect();
    names.sort();
    names
}

/// [`embedded_case`] with one of three value sets per corner (`variant` 0: all 1; 1 and 2:
/// varying per corner), so vertices are not all at cell centres and a quadric has something to
/// solve.
pub fn varied_case(case: u8, variant: usize) -> Samples<'static> {
    embedded_case(case, |corner, inside| {
        let m = [1.0, 0.1 + 0.13 * corner as f32, 7.0 - 0.5 * corner as f32][variant];
        if inside {
            -m
        } else {
            m
        }
    })
}

/// A value's distance from the iso-value: over six orders of magnitude (crossings crowding the
/// corners at unequal rates), of order one, or exactly at the iso-value (one draw in sixteen).
pub fn crowded_distance(random: &mut isolab_algorithms::random::Random) -> f32 {
    let u = random.unit_f32();
    match random.next_u64() % 16 {
        0 => 0.0,
        1..=7 => 10f32.powf(-6.0 * u),
        8..=11 => 10f32.powf(-2.0 * u),
        _ => 0.5 + u,
    }
}

/// The trilinear interpolant of corner values `g` (corner `c` at
/// `isolab_algorithms::tables::marching_cubes::CORNERS[c]`) at `(x, y, z)` in the unit cell.
pub fn trilinear(g: &[f32; 8], [x, y, z]: [f32; 3]) -> f32 {
    use isolab_algorithms::tables::marching_cubes::CORNERS;
    CORNERS
        .iter()
        .zip(g)
        .map(|(c, v)| {
            let w = |i: usize, t: f32| if c[i] == 1 { t } else { 1.0 - t };
            w(0, x) * w(1, y) * w(2, z) * v
        })
        .sum()
}

/// One cell (2 x 2 x 2 samples) with corner values `g`.
pub fn cell_samples(g: &[f32; 8]) -> Samples<'static> {
    use isolab_algorithms::tables::marching_cubes::CORNERS;
    grid_samples([2, 2, 2], |x, y, z| {
        let c = CORNERS.iter().position(|c| c.map(usize::from) == [x, y, z]).expect("a corner");
        g[c]
    })
}

/// Components and Euler characteristic of a mesh (of one cell's surface, with its boundary on the
/// cell's faces).
pub fn cell_shape(mesh: &TriMesh) -> (usize, i64) {
    let t = topology(mesh);
    (t.components, t.euler)
}

/// Samples per cell side for [`interpolant_shape`].
pub const INTERPOLANT_SAMPLES: usize = 32;

/// The components and Euler characteristic of the trilinear interpolant's level set at `shift`
/// above the iso-value in the cell with corner values `g`: the interpolant sampled
/// [`INTERPOLANT_SAMPLES`] times per side and meshed by `marching-cubes-decider` (which is
/// faithful on every face; the fine cells are too small to hold a tunnel except within a hair
/// of a critical value).
pub fn interpolant_shape(g: &[f32; 8], shift: f32) -> (usize, i64) {
    use isolab_algorithms::extractors::marching_cubes::{FaceResolution, MarchingCubes, McOptions};
    let n = INTERPOLANT_SAMPLES;
    let s = grid_samples([n + 1; 3], |x, y, z| trilinear(g, [x, y, z].map(|i| i as f32 / n as f32)) - shift);
    let decider = MarchingCubes::new(McOptions {
        faces: FaceResolution::AsymptoticDecider,
        parallelism: isolab_algorithms::sweep::slabs::Parallelism::Serial,
        ..Default::default()
    });
    cell_shape(&extract(&decider, &s).surface)
}

/// Whether a shift of the iso-value by a small fraction of the corner values, either way, changes
/// the interpolant's topology in the cell: a draw the fine sampling cannot judge.
pub fn near_critical(g: &[f32; 8]) -> bool {
    let delta = 2e-3 * g.iter().fold(0.0f32, |m, v| m.max(v.abs()));
    let at = interpolant_shape(g, 0.0);
    interpolant_shape(g, -delta) != at || interpolant_shape(g, delta) != at
}

/// A draw of corner values for sign pattern `case` (bit `c`: corner `c` inside, negative):
/// magnitudes over two orders of magnitude, so thin passages (tunnels) open and close.
pub fn tunnel_corner_values(case: u8, random: &mut isolab_algorithms::random::Random) -> [f32; 8] {
    std::array::from_fn(|c| {
        let m = 10f32.powf(-2.0 * random.unit_f32());
        if case >> c & 1 == 1 {
            -m
        } else {
            m
        }
    })
}

/// An id per vertex of `positions`, equal for vertices at one position (bit for bit), drawn from
/// and added to `ids` (so several meshes can share one numbering).
pub fn position_ids(positions: &[Vec3], ids: &mut std::collections::HashMap<[u32; 3], u32>) -> Vec<u32> {
    positions
        .iter()
        .map(|p| {
            let n = ids.len() as u32;
            *ids.entry(p.to_array().map(f32::to_bits)).or_insert(n)
        })
        .collect()
}

/// README.md, whose Rust code blocks run as this crate's doc tests (the quick start must work as
/// written; its other blocks are `sh`, `python` and `text`, which rustdoc does not run).
#[doc = include_str!("../../README.md")]
#[cfg(doctest)]
pub struct ReadmeQuickStart;

/// docs/rust.md, the Rust guide, whose Rust blocks run as this crate's doc tests.
#[doc = include_str!("../../docs/rust.md")]
#[cfg(doctest)]
pub struct RustGuide;
