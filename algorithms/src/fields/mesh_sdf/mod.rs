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
//! whose bound keeps clear of `|w| = 1/2` takes one answer for all its samples. Only boxes near the
//! surface (or near the `|w| = 1/2` sheet spanning a hole) split down to small boxes whose samples
//! get the per-point fast winding number. A closed mesh (every edge has two triangles, wound
//! opposite ways; [`MeshField::is_closed`]) needs almost no winding numbers: its winding number is
//! an integer that changes by one at each crossing, so each grid row's signs come from counting the
//! triangles it crosses (the classic scanline test of solid voxelizers), decided with exact
//! orientation tests in the row's plane; only samples whose row touches a projected edge or vertex,
//! or that lie almost on a crossing, fall back to their own winding number. An open mesh is closed
//! by cones over its holes (its boundary found by position, so unwelded seams are not holes); the
//! rows count the cones' crossings too, and the mesh's winding number is that count less the
//! cones'. Far from the cones theirs is small by a bound; nearer, a box takes the cones' winding
//! interval (a few triangles, cheap), and a small box each sample's own cone winding number, so
//! only samples near the `|w| = 1/2` sheet across a hole need the mesh's. Distances come from
//! closest-point queries that give up beyond the band, only in boxes that may reach into it. Last,
//! every bound that ends (or neighbours the end of) a grid edge whose sign changes is made exact:
//! across a hole the level set is that sheet, which may lie farther than the band from every
//! triangle.

use crate::bvh::{TriangleBvh, WindingInterval};
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
    /// The cones that close the mesh's boundary loops (none for a closed mesh), for signs from
    /// row crossings ([`crossing_signs`]).
    caps: Caps,
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
        let caps = Caps::closing(&soup);
        let bvh = TriangleBvh::new(soup);
        let bounds = bvh.bounds();
        let domain = bounds.expanded(DOMAIN_MARGIN * bounds.longest_side());
        Ok(Self { name, bvh, domain, reoriented, caps, band_cells: DEFAULT_BAND_CELLS })
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

    /// Whether the mesh is closed: along every edge (its ends told apart by position, so an
    /// unwelded seam counts as shared), as many triangles run one way as the other. Its winding
    /// number is then an integer off the surface, and grids take their signs from
    /// crossings along rows instead of per-sample winding numbers.
    pub fn is_closed(&self) -> bool {
        self.caps.triangles.is_empty()
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
            let signs = crossing_signs(&self.bvh, &self.caps, grid, z.clone());
            let fill = BandFill { bvh: &self.bvh, caps: &self.caps, grid, band, first_layer: z.start, signs: &signs };
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
    /// The caps over the mesh's holes, for the sides of samples near them.
    caps: &'a Caps,
    grid: &'a Grid,
    /// Distance within which samples are exact.
    band: f32,
    /// The slab's first z index (its slice starts there).
    first_layer: usize,
    /// Each slab sample's side from row crossings ([`crossing_signs`]).
    signs: &'a [Side],
}

impl BandFill<'_> {
    /// Fills the samples of the box `ranges` (x, y, z index ranges) into `slab`.
    fn boxed(&self, ranges: [Range<usize>; 3], slab: &mut [f32]) {
        let [x, y, z] = &ranges;
        let region =
            Aabb::new(self.grid.position(x.start, y.start, z.start), self.grid.position(x.end - 1, y.end - 1, z.end - 1));
        let count: usize = ranges.iter().map(|r| r.len()).product();
        if let Some(caps) = self.sided(&ranges, &region) {
            // Every sample's side is known: only distances need the box hierarchy.
            let side = |i: usize| if is_inside(self.signs[i], caps) { -1.0 } else { 1.0 };
            if count <= SMALLEST_TRIED {
                return self.fill(&ranges, slab, |i, p| side(i) * self.band_distance(p));
            }
            if let Some(far) = self.bvh.distance_from_box_at_least(&region, self.band).filter(|&far| far >= self.band) {
                return self.fill(&ranges, slab, |i, _| side(i) * far);
            }
            return self.split(ranges, slab);
        }
        let certified = if count <= SMALLEST_TRIED {
            None
        } else {
            self.bvh.winding_interval(&region, WINDING_BUDGET).and_then(|w| Some((inside(&w)?, w.distance)))
        };
        match certified {
            Some((inside, far)) if far >= self.band => self.fill(&ranges, slab, |_, _| sign(inside) * far),
            Some((inside, _)) => self.fill(&ranges, slab, |_, p| sign(inside) * self.band_distance(p)),
            None if count <= SMALLEST_TRIED => {
                self.fill(&ranges, slab, |i, p| sign(self.side_at(i, p)) * self.band_distance(p));
            }
            None => self.split(ranges, slab),
        }
    }

    /// Whether row crossings give every sample of the box (`region`) its side: `Some` with the
    /// caps' winding interval over the box when some sample is [`Side::NearCaps`] (and the
    /// interval decides every such sample), `Some(None)` when no sample needs it.
    fn sided(&self, [x, y, z]: &[Range<usize>; 3], region: &Aabb) -> Option<Option<WindingInterval>> {
        let [nx, ny, _] = self.grid.dims;
        let mut near_caps = false;
        for k in z.clone() {
            for j in y.clone() {
                let row = nx * (j + ny * (k - self.first_layer));
                for &s in &self.signs[row + x.start..row + x.end] {
                    match s {
                        Side::Unknown => return None,
                        Side::NearCaps(_) => near_caps = true,
                        Side::Inside | Side::Outside => {}
                    }
                }
            }
        }
        if !near_caps {
            return Some(None);
        }
        let caps = self.caps.bvh.as_ref()?.winding_interval(region, CAP_WINDING_BOUND)?;
        let decided = z.clone().all(|k| {
            y.clone().all(|j| {
                let row = nx * (j + ny * (k - self.first_layer));
                self.signs[row + x.start..row + x.end].iter().all(|&s| match s {
                    Side::NearCaps(n) => side_from_caps(n, caps.centre, caps.error).is_some(),
                    _ => true,
                })
            })
        });
        decided.then_some(Some(caps))
    }

    /// Whether the sample `i` of the slab, at `p`, is inside: as row crossings tell it, from the
    /// caps' winding number at `p` next to a cap, and from the mesh's own winding number where
    /// neither decides.
    fn side_at(&self, i: usize, p: Vec3) -> bool {
        match self.signs[i] {
            Side::Inside => true,
            Side::Outside => false,
            Side::NearCaps(n) => self
                .caps
                .bvh
                .as_ref()
                .and_then(|caps| side_from_caps(n, caps.winding_number(p), 0.0))
                .unwrap_or_else(|| winds_inside(self.bvh, p)),
            Side::Unknown => winds_inside(self.bvh, p),
        }
    }

    /// Splits the box across its longest axis and fills both halves.
    fn split(&self, ranges: [Range<usize>; 3], slab: &mut [f32]) {
        let axis = (0..3).max_by_key(|&a| ranges[a].len()).unwrap_or(0);
        let r = &ranges[axis];
        let mid = r.start + r.len() / 2;
        let (mut low, mut high) = (ranges.clone(), ranges);
        low[axis].end = mid;
        high[axis].start = mid;
        self.boxed(low, slab);
        self.boxed(high, slab);
    }

    /// The exact distance from `p` to the mesh if it is within the band, the band otherwise.
    fn band_distance(&self, p: Vec3) -> f32 {
        self.bvh.closest_point_within(p, self.band).map_or(self.band, |(_, d2)| d2.sqrt())
    }

    /// Sets every sample of the box to `value(index in the slab, position)`.
    fn fill(&self, [x, y, z]: &[Range<usize>; 3], slab: &mut [f32], value: impl Fn(usize, Vec3) -> f32) {
        let [nx, ny, _] = self.grid.dims;
        for k in z.clone() {
            for j in y.clone() {
                let row = nx * (j + ny * (k - self.first_layer));
                for i in x.clone() {
                    slab[row + i] = value(row + i, self.grid.position(i, j, k));
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

/// Whether a sample whose side [`BandFill::sided`] decided is inside (`caps`: the caps' winding
/// interval over its box, when the box has [`Side::NearCaps`] samples).
fn is_inside(side: Side, caps: Option<WindingInterval>) -> bool {
    match side {
        Side::Inside => true,
        Side::NearCaps(n) => caps.and_then(|c| side_from_caps(n, c.centre, c.error)).unwrap_or(false),
        Side::Outside | Side::Unknown => false,
    }
}

/// Whether a sample whose mesh and caps wind `n` times around it (row crossings' count), where
/// the caps' own winding number is within `error` of `caps`, is inside: the mesh's own winding
/// number is `n` less the caps', inside where its magnitude is at least 1/2. Decided only when
/// every value in the interval keeps [`CAP_WINDING_BOUND`] clear of 1/2 (room for the error of
/// the mesh's fast winding number, which the field's sign follows); `None` otherwise.
fn side_from_caps(n: i32, caps: f64, error: f64) -> Option<bool> {
    let (low, high) = (f64::from(n) - caps - error, f64::from(n) - caps + error);
    let margin = CAP_WINDING_BOUND;
    if low >= 0.5 + margin || high <= -0.5 - margin {
        Some(true)
    } else if low >= -0.5 + margin && high <= 0.5 - margin {
        Some(false)
    } else {
        None
    }
}

/// A sample's side, as row crossings tell it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Side {
    Inside,
    Outside,
    /// A cap is near (its winding number may exceed [`CAP_WINDING_BOUND`]): mesh and caps wind
    /// this many times around the sample, and the side comes from the caps' winding number over
    /// the sample's box ([`side_from_caps`]).
    NearCaps(i32),
    /// The row touches an edge or a vertex of a triangle's projection, or a crossing lies within
    /// [`CROSSING_TOLERANCE`] of the sample: the sample's side comes from the winding number.
    Unknown,
}

/// How near a crossing (in grid spacings) makes a sample ask its own winding number instead.
pub const CROSSING_TOLERANCE: f64 = 1e-4;

/// Largest bound on the caps' winding number at a sample whose side row crossings give alone:
/// the mesh's winding number is then within this of the crossings' integer, far from 1/2.
/// Nearer the caps, the caps' winding interval over a box must keep the mesh's this far from 1/2.
pub const CAP_WINDING_BOUND: f64 = 0.25;

/// Cones closing an open mesh: one per connected piece of its boundary (the edges its triangles
/// leave uncancelled, with multiplicity), from the piece's centroid. The mesh and its caps have
/// no boundary, so their winding number `n` is an integer that row crossings count; the mesh's
/// own is `n - w_caps`.
#[derive(Clone, Debug, Default)]
struct Caps {
    /// The cones' triangles, wound so that they cancel the mesh's boundary.
    triangles: Vec<[Vec3; 3]>,
    /// The same triangles in a hierarchy, for their winding interval over a box (none for a
    /// closed mesh).
    bvh: Option<TriangleBvh>,
    /// Per cone: its apex, the largest distance from the apex to its rim, and its area.
    cones: Vec<(Vec3, f32, f64)>,
}

impl Caps {
    /// The caps of `soup` (the triangles as the field keeps them). Corners are told apart by
    /// position, not by index: a seam whose two sides repeat the same positions under different
    /// indices (the Utah teapot's patches) cancels like a shared edge, since the winding number
    /// depends on the geometry alone. Capping such a seam would put a cone through the solid,
    /// near which every sample needs its own winding number.
    fn closing(soup: &[[Vec3; 3]]) -> Self {
        let mut net: std::collections::HashMap<(u32, u32), i32> = std::collections::HashMap::new();
        let mut position_ids: std::collections::HashMap<[u32; 3], u32> = std::collections::HashMap::new();
        let mut at: Vec<Vec3> = Vec::new();
        for corners in soup {
            // `+ 0.0` makes -0.0 and 0.0 one position.
            let [a, b, c] = corners.map(|p| {
                *position_ids.entry((p + Vec3::ZERO).to_array().map(f32::to_bits)).or_insert_with(|| {
                    at.push(p);
                    (at.len() - 1) as u32
                })
            });
            for (u, v) in [(a, b), (b, c), (c, a)] {
                if u != v {
                    *net.entry((u.min(v), u.max(v))).or_default() += if u < v { 1 } else { -1 };
                }
            }
        }
        let mut edges: Vec<(u32, u32, u32)> = net
            .into_iter()
            .filter(|&(_, n)| n != 0)
            .map(|((u, v), n)| if n > 0 { (u, v, n as u32) } else { (v, u, n.unsigned_abs()) })
            .collect();
        if edges.is_empty() {
            return Self::default();
        }
        edges.sort_unstable();
        let mut ids: Vec<u32> = edges.iter().flat_map(|&(u, v, _)| [u, v]).collect();
        ids.sort_unstable();
        ids.dedup();
        let local = |v: u32| ids.binary_search(&v).unwrap_or(0);
        let mut pieces = petgraph::unionfind::UnionFind::<usize>::new(ids.len());
        for &(u, v, _) in &edges {
            pieces.union(local(u), local(v));
        }
        let mut caps = Self::default();
        let mut roots: Vec<usize> = (0..ids.len()).map(|i| pieces.find(i)).collect();
        roots.sort_unstable();
        roots.dedup();
        for root in roots {
            let rim: Vec<Vec3> = ids.iter().filter(|&&v| pieces.find(local(v)) == root).map(|&v| at[v as usize]).collect();
            let apex = (rim.iter().map(|p| p.as_dvec3()).sum::<glam::DVec3>() / rim.len() as f64).as_vec3();
            let radius = rim.iter().map(|p| p.distance(apex)).fold(0.0, f32::max);
            let mut area = 0.0;
            for &(u, v, n) in edges.iter().filter(|e| pieces.find(local(e.0)) == root) {
                let t = [apex, at[v as usize], at[u as usize]];
                area += f64::from(n) * 0.5 * (t[1] - t[0]).as_dvec3().cross((t[2] - t[0]).as_dvec3()).length();
                caps.triangles.extend(std::iter::repeat_n(t, n as usize));
            }
            caps.cones.push((apex, radius, area));
        }
        caps.bvh = Some(TriangleBvh::new(caps.triangles.clone()));
        caps
    }

    /// A bound on the caps' winding number at `p` (a triangle's solid angle is at most its area
    /// over the squared distance), infinite within a cone's ball.
    fn winding_bound(&self, p: Vec3) -> f64 {
        self.cones
            .iter()
            .map(|&(apex, radius, area)| {
                let gap = f64::from(p.distance(apex)) - f64::from(radius);
                if gap > 0.0 {
                    area / (4.0 * std::f64::consts::PI * gap * gap)
                } else {
                    f64::INFINITY
                }
            })
            .sum()
    }
}

/// The side of every sample of the z-layers `layers` of `grid` (slab order), by counting
/// crossings along each x-row. The mesh closed by its `caps` has an integer winding number `n`,
/// 0 far out along the row and changing by one at each crossing (up where the triangle faces
/// away from +x, down where it faces +x); the mesh's own winding number is `n` less the caps',
/// so where the caps' is bounded by [`CAP_WINDING_BOUND`] (everywhere, for a closed mesh) a
/// sample is inside exactly where `n` is nonzero. Whether a row meets a triangle is decided with
/// exact orientation tests in the row's (y, z) plane; a row through a projected edge or vertex,
/// or along a triangle seen edge-on, leaves its samples [`Side::Unknown`], as does a crossing
/// within [`CROSSING_TOLERANCE`] of a sample, or a cap nearby. The sides agree with the fast
/// winding number's `|w| >= 1/2` (tested on every sample of the shipped models).
fn crossing_signs(bvh: &TriangleBvh, caps: &Caps, grid: &Grid, layers: Range<usize>) -> Vec<Side> {
    use crate::predicates::o2;
    let [nx, ny, _] = grid.dims;
    let rows = ny * layers.len();
    let mut sides = vec![Side::Outside; nx * rows];
    if rows == 0 || nx == 0 {
        return sides;
    }
    let (first, last) = (grid.position(0, 0, layers.start), grid.position(0, ny - 1, layers.end - 1));
    let query = Aabb::new(Vec3::new(f32::MIN, first.y, first.z), Vec3::new(f32::MAX, last.y, last.z));
    let mut unsure = vec![false; rows];
    let mut crossings: Vec<(u32, f64, i8)> = Vec::new();
    let index_range = |lo: f32, hi: f32, origin: f32, count: usize| {
        let from = ((lo - origin) / grid.spacing).floor() - 1.0;
        let to = ((hi - origin) / grid.spacing).ceil() + 1.0;
        (from.max(0.0) as usize)..((to.max(-1.0) + 1.0) as usize).min(count)
    };
    let mut cross = |t: &[Vec3; 3]| {
        let [a, b, c] = *t;
        let facing = o2(a, b, c, 0);
        let (lo, hi) = (a.min(b).min(c), a.max(b).max(c));
        let js = index_range(lo.y, hi.y, grid.origin.y, ny);
        let ks = index_range(lo.z, hi.z, grid.origin.z, grid.dims[2]);
        for k in ks.start.max(layers.start)..ks.end.min(layers.end) {
            for j in js.clone() {
                let row = (k - layers.start) * ny + j;
                let r = grid.position(0, j, k);
                let e = [o2(a, b, r, 0), o2(b, c, r, 0), o2(c, a, r, 0)];
                if facing == 0 {
                    // Seen edge-on: only a row on its projected segment is in doubt.
                    if e == [0, 0, 0] && (lo.y..=hi.y).contains(&r.y) && (lo.z..=hi.z).contains(&r.z) {
                        unsure[row] = true;
                    }
                    continue;
                }
                if e.iter().all(|&s| s == facing) {
                    match crossing_x(t, r) {
                        Some(x) => crossings.push((row as u32, x, -facing)),
                        None => unsure[row] = true,
                    }
                } else if e.iter().all(|&s| s == facing || s == 0) {
                    unsure[row] = true;
                }
            }
        }
    };
    bvh.for_each_overlapping(&query, |_, t| cross(t));
    caps.triangles.iter().for_each(&mut cross);
    crossings.sort_unstable_by(|p, q| p.0.cmp(&q.0).then(p.1.total_cmp(&q.1)));
    let tolerance = CROSSING_TOLERANCE * f64::from(grid.spacing);
    let mut next = 0;
    for (row, unsure) in unsure.iter().enumerate() {
        let end = next + crossings[next..].iter().take_while(|c| c.0 as usize == row).count();
        let here = &crossings[next..end];
        next = end;
        let out = &mut sides[row * nx..(row + 1) * nx];
        if *unsure {
            out.fill(Side::Unknown);
            continue;
        }
        let (j, k) = (row % ny, layers.start + row / ny);
        let (mut winding, mut c) = (0i32, 0);
        for (i, side) in out.iter_mut().enumerate() {
            let p = grid.position(i, j, k);
            let x = f64::from(p.x);
            while c < here.len() && here[c].1 < x - tolerance {
                winding += i32::from(here[c].2);
                c += 1;
            }
            let on_a_crossing = c < here.len() && here[c].1 <= x + tolerance;
            *side = if on_a_crossing {
                Side::Unknown
            } else if !caps.cones.is_empty() && caps.winding_bound(p) >= CAP_WINDING_BOUND {
                Side::NearCaps(winding)
            } else if winding != 0 {
                Side::Inside
            } else {
                Side::Outside
            };
        }
    }
    sides
}

/// Where the x-parallel line through `r` (its y and z) meets the plane of triangle `t`, whose
/// projection onto (y, z) it crosses; `None` when that projection is so thin against its
/// coordinates that `f64` rounding of the barycentric weights (products of coordinate
/// differences) could move the answer by more than about 1e-9 of the triangle: the row then
/// takes its samples' winding numbers.
fn crossing_x(t: &[Vec3; 3], r: Vec3) -> Option<f64> {
    let [a, b, c] = t.map(|v| v.as_dvec3());
    let (py, pz) = (f64::from(r.y), f64::from(r.z));
    let products = |u: glam::DVec3, v: glam::DVec3| ((u.y - py) * (v.z - pz), (u.z - pz) * (v.y - py));
    let pairs = [products(b, c), products(c, a), products(a, b)];
    let [wa, wb, wc] = pairs.map(|(p, q)| p - q);
    let magnitude: f64 = pairs.iter().map(|(p, q)| p.abs() + q.abs()).sum();
    let sum = wa + wb + wc;
    let x = (wa * a.x + wb * b.x + wc * c.x) / sum;
    (sum.abs() > 1e-6 * magnitude && x.is_finite()).then_some(x)
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
mod tests;
