//! A triangle mesh as a signed distance field.
//!
//! Distance is exact (closest point over a [`TriangleBvh`]); the sign comes from the
//! generalized winding number `w` (Jacobson et al. 2013): inside where `|w|` is at least 1/2. A
//! mesh with holes, like the Stanford bunny's base, therefore still has a sensible inside, and the
//! level set closes over the holes.
//!
//! The field does not depend on the input's orientation: inside a closed surface wound inward
//! `w` is -1, and `|w|` is still 1. A mesh whose total signed volume is negative (wound inward
//! as a whole, common in files from the wild) is also flipped before anything else, so that its
//! triangles (the surface `S` that `bcc-sculpt` encloses) face outward like every other input;
//! [`MeshField::reoriented`] says when that happened. A hollow shell whose inner wall faces the
//! cavity keeps its cavity: there `w` is 0 whichever way the whole is wound.
//!
//! The default domain is the mesh's bounding box plus a margin of 5% of its longest side.
//!
//! ## Sampling a grid: a narrow band
//!
//! Extractors only read values near the level set, so [`Field::sample_grid`] computes the exact
//! value only in a narrow band, as OpenVDB's mesh-to-volume does (Museth 2013, "VDB",
//! DOI 10.1145/2487228.2487235; its default half-width is 3 voxels, ours is
//! [`DEFAULT_BAND_CELLS`]): every sample nearer the mesh than `|iso|` plus the band gets its exact
//! signed distance, the one [`Field::value`] gives, bit for bit. Every farther sample gets the
//! right sign and a lower bound on its distance (never less than the band), so the grid is still
//! a conservative distance bound, safe for sphere tracing.
//!
//! The sign does not need a winding number per sample. The grid is split recursively into boxes;
//! [`TriangleBvh::winding_interval`] bounds the exact winding number over a whole box, and a box
//! whose bound keeps clear of `|w| = 1/2` takes one answer for all its samples. Only boxes near
//! the surface (or near the `|w| = 1/2` sheet spanning a hole) split down to small boxes whose samples
//! get the per-point fast winding number. Distances come from closest-point queries that give up
//! beyond the band, only in boxes that may reach into it. Last, every bound that ends (or
//! neighbours the end of) a grid edge whose sign changes is made exact: across a hole the level
//! set is that sheet, which may lie farther than the band from every triangle.

use crate::bvh::TriangleBvh;
use crate::field::{sample_pointwise, Field, FieldError};
use crate::geometry::Aabb;
use crate::lattice::Grid;
use glam::Vec3;
use rayon::prelude::*;
use std::ops::Range;

/// Fraction of the longest side added around the mesh's bounding box.
pub const DOMAIN_MARGIN: f32 = 0.05;

/// Half-width of the exact band when sampling a grid, in grid spacings. Marching cubes, surface
/// nets and dual contouring read values at most two spacings from the surface (an edge's ends,
/// and their neighbours for sample-gradient normals).
pub const DEFAULT_BAND_CELLS: f32 = 3.0;

/// Largest uncertainty of the winding number over a box worth finishing a bound for.
const WINDING_BUDGET: f64 = 0.5;

/// Boxes of at most this many samples are not bounded (near the surface, where they end up, the
/// bound almost always fails): each of their samples gets its own winding number.
const SMALLEST_TRIED: usize = 16;

/// z-layers per parallel task when sampling a grid.
const SLAB_LAYERS: usize = 8;

/// Signed distance to a triangle mesh.
#[derive(Clone)]
pub struct MeshField {
    name: String,
    bvh: TriangleBvh,
    domain: Aabb,
    reoriented: bool,
    band_cells: f32,
}

impl MeshField {
    /// Builds the field from vertex positions and counter-clockwise triangles.
    pub fn new(name: impl Into<String>, positions: &[Vec3], triangles: &[[u32; 3]]) -> Result<Self, FieldError> {
        let name = name.into();
        if triangles.is_empty() {
            return Err(FieldError::EmptyMesh { name });
        }
        if let Some(vertex) = positions.iter().position(|p| !p.is_finite()) {
            return Err(FieldError::NonFiniteVertex { name, vertex });
        }
        let mut soup = Vec::with_capacity(triangles.len());
        for (triangle, t) in triangles.iter().enumerate() {
            if let Some(&vertex) = t.iter().find(|&&i| i as usize >= positions.len()) {
                return Err(FieldError::BadIndex { name, triangle, vertex, vertices: positions.len() });
            }
            soup.push(t.map(|i| positions[i as usize]));
        }
        let reoriented = signed_volume(&soup) < 0.0;
        if reoriented {
            for t in &mut soup {
                t.swap(1, 2);
            }
        }
        let bvh = TriangleBvh::new(soup);
        let bounds = bvh.bounds();
        let domain = bounds.expanded(DOMAIN_MARGIN * bounds.longest_side());
        Ok(Self { name, bvh, domain, reoriented, band_cells: DEFAULT_BAND_CELLS })
    }

    /// Sets the half-width of the exact band used when sampling grids, in grid spacings;
    /// `f32::INFINITY` makes every sample exact (each one a full closest-point query and winding
    /// number, as [`Field::value`]).
    pub fn with_band_cells(mut self, cells: f32) -> Self {
        self.band_cells = cells;
        self
    }

    /// Makes exact every bound (a sample at least `band` from the mesh) that ends a lattice edge
    /// whose sign changes, or neighbours such an end: across a hole the level set is the
    /// `|w| = 1/2` sheet, which may pass farther than the band from every triangle, and the
    /// extractors interpolate along those edges (and take sample gradients at their ends).
    fn exact_at_sign_changes(&self, grid: &Grid, band: f32, values: &mut [f32]) {
        let [nx, ny, nz] = grid.dims;
        let layer = nx * ny;
        let at = |i: usize| [i % nx, (i / nx) % ny, i / layer];
        let neighbours = move |i: usize| {
            let [x, y, z] = at(i);
            [
                (x > 0, i.wrapping_sub(1)),
                (x + 1 < nx, i + 1),
                (y > 0, i.wrapping_sub(nx)),
                (y + 1 < ny, i + nx),
                (z > 0, i.wrapping_sub(layer)),
                (z + 1 < nz, i + layer),
            ]
            .into_iter()
            .filter_map(|(inside, j)| inside.then_some(j))
        };
        let ends: Vec<usize> = (0..values.len())
            .into_par_iter()
            .filter(|&i| neighbours(i).any(|j| (values[j] < 0.0) != (values[i] < 0.0)))
            .collect();
        let mut fix: Vec<usize> =
            ends.iter().flat_map(|&i| std::iter::once(i).chain(neighbours(i))).filter(|&i| values[i].abs() >= band).collect();
        fix.sort_unstable();
        fix.dedup();
        let exact: Vec<f32> = fix
            .par_iter()
            .map(|&i| {
                let [x, y, z] = at(i);
                values[i].signum() * self.unsigned_distance(grid.position(x, y, z))
            })
            .collect();
        for (&i, v) in fix.iter().zip(exact) {
            values[i] = v;
        }
    }

    /// The half-width of the exact band, in grid spacings.
    pub fn band_cells(&self) -> f32 {
        self.band_cells
    }

    /// Whether the input was wound inward as a whole (negative signed volume) and was flipped.
    pub fn reoriented(&self) -> bool {
        self.reoriented
    }

    /// The triangle hierarchy (for exact distance queries).
    pub fn bvh(&self) -> &TriangleBvh {
        &self.bvh
    }

    /// Exact unsigned distance from `p` to the mesh.
    pub fn unsigned_distance(&self, p: Vec3) -> f32 {
        self.bvh.closest_point(p).map_or(f32::INFINITY, |(_, d2)| d2.sqrt())
    }
}

impl Field for MeshField {
    fn name(&self) -> &str {
        &self.name
    }
    fn value(&self, p: Vec3) -> f32 {
        sign(winds_inside(&self.bvh, p)) * self.unsigned_distance(p)
    }

    fn sample_grid(&self, grid: &Grid, iso: f32, out: &mut [f32]) {
        let band = iso.abs() + self.band_cells * grid.spacing;
        let [nx, ny, nz] = grid.dims;
        if !band.is_finite() || nx == 0 || ny == 0 {
            return sample_pointwise(self, grid, out);
        }
        out.par_chunks_mut(nx * ny * SLAB_LAYERS).enumerate().for_each(|(k, slab)| {
            let z = k * SLAB_LAYERS..(k * SLAB_LAYERS + SLAB_LAYERS).min(nz);
            let fill = BandFill { bvh: &self.bvh, grid, band, first_layer: z.start };
            fill.boxed([0..nx, 0..ny, z], slab);
        });
        self.exact_at_sign_changes(grid, band, out);
    }

    fn surface_mesh(&self) -> Option<&TriangleBvh> {
        Some(&self.bvh)
    }

    fn domain(&self) -> Aabb {
        self.domain
    }
    fn distance_to_surface(&self, p: Vec3, iso: f32) -> f32 {
        if iso == 0.0 {
            self.unsigned_distance(p)
        } else {
            (self.value(p) - iso).abs()
        }
    }
}

/// Narrow-band sampling of one slab of a grid (see the module doc).
struct BandFill<'a> {
    bvh: &'a TriangleBvh,
    grid: &'a Grid,
    /// Distance within which samples are exact.
    band: f32,
    /// The slab's first z index (its slice starts there).
    first_layer: usize,
}

impl BandFill<'_> {
    /// Fills the samples of the box `ranges` (x, y, z index ranges) into `slab`.
    fn boxed(&self, ranges: [Range<usize>; 3], slab: &mut [f32]) {
        let [x, y, z] = &ranges;
        let region =
            Aabb::new(self.grid.position(x.start, y.start, z.start), self.grid.position(x.end - 1, y.end - 1, z.end - 1));
        let count: usize = ranges.iter().map(|r| r.len()).product();
        let certified = if count <= SMALLEST_TRIED {
            None
        } else {
            self.bvh.winding_interval(&region, WINDING_BUDGET).and_then(|w| Some((inside(&w)?, w.distance)))
        };
        match certified {
            Some((inside, far)) if far >= self.band => self.fill(&ranges, slab, |_| sign(inside) * far),
            Some((inside, _)) => self.fill(&ranges, slab, |p| sign(inside) * self.band_distance(p)),
            None if count <= SMALLEST_TRIED => {
                self.fill(&ranges, slab, |p| sign(winds_inside(self.bvh, p)) * self.band_distance(p));
            }
            None => {
                let axis = (0..3).max_by_key(|&a| ranges[a].len()).unwrap_or(0);
                let r = &ranges[axis];
                let mid = r.start + r.len() / 2;
                let (mut low, mut high) = (ranges.clone(), ranges);
                low[axis].end = mid;
                high[axis].start = mid;
                self.boxed(low, slab);
                self.boxed(high, slab);
            }
        }
    }

    /// The exact distance from `p` to the mesh if it is within the band, the band otherwise.
    fn band_distance(&self, p: Vec3) -> f32 {
        self.bvh.closest_point_within(p, self.band).map_or(self.band, |(_, d2)| d2.sqrt())
    }

    fn fill(&self, [x, y, z]: &[Range<usize>; 3], slab: &mut [f32], value: impl Fn(Vec3) -> f32) {
        let [nx, ny, _] = self.grid.dims;
        for k in z.clone() {
            for j in y.clone() {
                let row = nx * (j + ny * (k - self.first_layer));
                for i in x.clone() {
                    slab[row + i] = value(self.grid.position(i, j, k));
                }
            }
        }
    }
}

/// Whether a winding-number interval is certainly inside (`|w| >= 1/2` everywhere), certainly
/// outside, or neither (`None`).
fn inside(w: &crate::bvh::WindingInterval) -> Option<bool> {
    let (low, high) = (w.centre - w.error, w.centre + w.error);
    if low >= 0.5 || high <= -0.5 {
        Some(true)
    } else if low > -0.5 && high < 0.5 {
        Some(false)
    } else {
        None
    }
}

/// The field's inside: `|w| >= 1/2` (see the module doc).
fn winds_inside(bvh: &TriangleBvh, p: Vec3) -> bool {
    bvh.winding_number(p).abs() >= 0.5
}

/// -1 inside, +1 outside.
fn sign(inside: bool) -> f32 {
    if inside {
        -1.0
    } else {
        1.0
    }
}

/// Signed volume of a triangle soup about its bounding box centre (positive for a closed mesh
/// wound outward; for an open one, its sign still says which way most of it faces).
fn signed_volume(soup: &[[Vec3; 3]]) -> f64 {
    let mut bounds = Aabb::empty();
    soup.iter().flatten().for_each(|&p| bounds.grow(p));
    let o = bounds.centre().as_dvec3();
    soup.iter()
        .map(|t| {
            let [a, b, c] = t.map(|p| p.as_dvec3() - o);
            a.dot(b.cross(c))
        })
        .sum::<f64>()
        / 6.0
}

#[cfg(test)]
mod tests {
    use super::*;

    fn octahedron() -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let v = vec![Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z];
        let t = vec![[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]];
        (v, t)
    }

    #[test]
    fn octahedron_sign_and_distance() {
        let (v, t) = octahedron();
        let f = MeshField::new("octa", &v, &t).unwrap();
        assert!(f.value(Vec3::ZERO) < 0.0);
        assert!((f.value(Vec3::ZERO) + 1.0 / 3f32.sqrt()).abs() < 1e-5);
        assert!((f.value(Vec3::new(2.0, 0.0, 0.0)) - 1.0).abs() < 1e-5);
    }

    #[test]
    fn open_mesh_still_has_an_inside() {
        let (v, mut t) = octahedron();
        t.pop(); // a hole
        let f = MeshField::new("open", &v, &t).unwrap();
        assert!(f.value(Vec3::new(0.1, 0.1, 0.1)) < 0.0);
        assert!(f.value(Vec3::new(0.0, 0.0, 3.0)) > 0.0);
    }

    #[test]
    fn an_inward_mesh_gives_the_same_field_and_is_flipped() {
        let (v, t) = octahedron();
        let outward = MeshField::new("out", &v, &t).unwrap();
        let inward_triangles: Vec<[u32; 3]> = t.iter().map(|&[a, b, c]| [a, c, b]).collect();
        let inward = MeshField::new("in", &v, &inward_triangles).unwrap();
        assert!(!outward.reoriented() && inward.reoriented());
        for p in [Vec3::ZERO, Vec3::new(0.2, -0.1, 0.3), Vec3::new(1.5, 0.0, 0.2), Vec3::new(-0.4, 0.4, 0.1)] {
            assert_eq!(inward.value(p), outward.value(p), "{p}");
        }
        // Two disjoint shells, one wound each way: both have an inside (|w|).
        let mut v2 = v.clone();
        v2.extend(v.iter().map(|p| *p + Vec3::new(5.0, 0.0, 0.0)));
        let mut t2 = t.clone();
        t2.extend(inward_triangles.iter().map(|tri| tri.map(|i| i + 6)));
        let mixed = MeshField::new("mixed", &v2, &t2).unwrap();
        assert!(mixed.value(Vec3::ZERO) < 0.0 && mixed.value(Vec3::new(5.0, 0.0, 0.0)) < 0.0);
        assert!(mixed.value(Vec3::new(2.5, 0.0, 0.0)) > 0.0);
    }

    #[test]
    fn a_hollow_shell_keeps_its_cavity_either_way_round() {
        let (v, t) = octahedron();
        // Outer shell outward, inner shell (half size) facing the cavity.
        let mut positions = v.clone();
        positions.extend(v.iter().map(|p| *p * 0.5));
        let mut triangles = t.clone();
        triangles.extend(t.iter().map(|&[a, b, c]| [a + 6, c + 6, b + 6]));
        let flipped: Vec<[u32; 3]> = triangles.iter().map(|&[a, b, c]| [a, c, b]).collect();
        for (name, tris) in [("hollow", &triangles), ("hollow-inward", &flipped)] {
            let f = MeshField::new(name, &positions, tris).unwrap();
            assert!(f.value(Vec3::ZERO) > 0.0, "{name}: the cavity is outside");
            assert!(f.value(Vec3::new(0.7, 0.0, 0.0)) < 0.0, "{name}: the wall is inside");
        }
    }

    /// Narrow-band values against exact ones on a grid: the same sign everywhere, the same bits
    /// within the band, a lower bound no less than the band beyond it. Returns how many samples
    /// were in the band and how many beyond.
    fn check_band(field: MeshField, n: usize, iso: f32) -> (usize, usize) {
        let grid = Grid::covering(&field.domain(), n).unwrap();
        let mut banded = vec![0.0; grid.len()];
        field.sample_grid(&grid, iso, &mut banded);
        let exact = field.with_band_cells(f32::INFINITY);
        let mut reference = vec![0.0; grid.len()];
        exact.sample_grid(&grid, iso, &mut reference);
        let band = iso.abs() + DEFAULT_BAND_CELLS * grid.spacing;
        let (mut near, mut far) = (0, 0);
        for (i, (&b, &e)) in banded.iter().zip(&reference).enumerate() {
            assert_eq!(b < 0.0, e < 0.0, "sample {i}: sign {b} against {e}");
            if e.abs() < band {
                assert_eq!(b, e, "sample {i} is in the band");
                near += 1;
            } else {
                assert!(b.abs() >= band && b.abs() <= e.abs(), "sample {i}: {b} is no bound on {e} (band {band})");
                far += 1;
            }
        }
        (near, far)
    }

    #[test]
    fn narrow_band_samples_are_exact_near_the_surface_and_bounds_beyond() {
        let (v, t) = octahedron();
        let (near, far) = check_band(MeshField::new("octa", &v, &t).unwrap(), 41, 0.0);
        assert!(near > 1000 && far > 10_000, "{near} in the band, {far} beyond");
        // An offset level set widens the band by the offset.
        check_band(MeshField::new("octa", &v, &t).unwrap(), 41, 0.15);
        check_band(MeshField::new("octa", &v, &t).unwrap(), 41, -0.1);
        // An open mesh: the |w| = 1/2 sheet across the hole is found sample by sample.
        let mut open = t.clone();
        open.pop();
        check_band(MeshField::new("open", &v, &open).unwrap(), 41, 0.0);
        // A hollow shell, and two shells wound opposite ways.
        let mut positions = v.clone();
        positions.extend(v.iter().map(|p| *p * 0.5));
        let mut hollow = t.clone();
        hollow.extend(t.iter().map(|&[a, b, c]| [a + 6, c + 6, b + 6]));
        check_band(MeshField::new("hollow", &positions, &hollow).unwrap(), 41, 0.0);
        let mut apart = v.clone();
        apart.extend(v.iter().map(|p| *p + Vec3::new(2.5, 0.0, 0.0)));
        let mut mixed = t.clone();
        mixed.extend(t.iter().map(|&[a, b, c]| [a + 6, c + 6, b + 6]));
        check_band(MeshField::new("mixed", &apart, &mixed).unwrap(), 37, 0.0);
    }

    #[test]
    fn a_box_clear_of_the_mesh_gets_a_winding_interval_and_one_touching_it_does_not() {
        let (v, t) = octahedron();
        let f = MeshField::new("octa", &v, &t).unwrap();
        let inner = Aabb::new(Vec3::splat(-0.02), Vec3::splat(0.02));
        let w = f.bvh().winding_interval(&inner, 0.5).unwrap();
        assert!(w.centre - w.error >= 0.5 && w.error > 0.0, "{w:?}");
        assert!(w.distance > 0.0 && w.distance <= 1.0 / 3f32.sqrt() - 0.02, "{w:?}");
        let outer = Aabb::new(Vec3::splat(2.0), Vec3::splat(2.2));
        let w = f.bvh().winding_interval(&outer, 0.5).unwrap();
        assert!(w.centre + w.error < 0.5 && w.centre - w.error > -0.5, "{w:?}");
        // The distance is a lower bound on every point of the box.
        let nearest_corner = f.unsigned_distance(Vec3::splat(2.0));
        assert!(w.distance <= nearest_corner && w.distance > 0.0, "{w:?} against {nearest_corner}");
        let straddling = Aabb::new(Vec3::splat(0.2), Vec3::splat(0.6));
        assert!(f.bvh().winding_interval(&straddling, 0.5).is_none());
    }

    #[test]
    fn bad_meshes_are_rejected_with_the_offender_named() {
        let (v, _) = octahedron();
        assert!(matches!(MeshField::new("e", &v, &[]), Err(FieldError::EmptyMesh { .. })));
        let e = MeshField::new("b", &v, &[[0, 1, 9]]).err().unwrap();
        assert!(e.to_string().contains("vertex 9"), "{e}");
        let mut nan = v.clone();
        nan[3].y = f32::NAN;
        assert!(matches!(MeshField::new("n", &nan, &[[0, 1, 3]]), Err(FieldError::NonFiniteVertex { vertex: 3, .. })));
    }
}
