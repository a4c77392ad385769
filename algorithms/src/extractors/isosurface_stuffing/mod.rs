//! `isosurface-stuffing`: tetrahedra with proven dihedral angles filling the inside of an
//! isosurface, after F. Labelle and J. R. Shewchuk, "Isosurface Stuffing: Fast Tetrahedral Meshes
//! with Good Dihedral Angles", ACM Transactions on Graphics 26(3), SIGGRAPH 2007 (the uniform
//! variant, sections 2-4; the graded octree variant is not built).
//!
//! **Summary.** Four passes over the BCC lattice (corners and cell centres; every tetrahedron has
//! two long edges, between two corners or two centres, and four short ones):
//! 1. **Signs**: each lattice vertex is negative (inside, `f < iso`), zero or positive.
//! 2. **Cut points** ([`cut_points`]): on every edge between a negative and a positive vertex,
//!    where the field crosses the iso-value: the samples' linear interpolation, refined on the
//!    field itself when the samples carry one (regula falsi, so vertices lie on the true surface).
//! 3. **Warping** ([`warp`]): a cut point closer to an end of its edge than `alpha-long` (long
//!    edges) or `alpha-short` (short edges) times the edge's length *violates* that end. A
//!    violated vertex moves onto its nearest violating cut point and becomes zero, which removes
//!    the cut points of its edges. Positive vertices move first, then negative ones still violated
//!    by a cut point whose positive end stayed. No cut point left is then within `alpha` of an end.
//! 4. **Stencils** ([`stencils::fill`]): each lattice tetrahedron is kept whole, dropped, or cut
//!    at its cut points into one to three tetrahedra, quadrilaterals split by the paper's rules
//!    (its parity rule on faces whose long edge has two negative ends).
//!
//! Cubic grids are meshed on the BCC lattice they span: their samples are the corners, and each
//! cube's centre takes the field's value there when the samples carry a field, and otherwise the
//! mean of the cube's eight corners (the trilinear interpolant at the centre).
//!
//! **Guarantees.** With the paper's parameters `alpha-long = 0.24999` and `alpha-short = 0.41189`
//! (the defaults) every dihedral angle lies in [9.3°, 161.7°] ([`GUARANTEED`]) and no tetrahedron
//! is inverted, declared as [`crate::extract::Guarantees::dihedral`] and held by two tests: the
//! exhaustive stencil test (every lattice tetrahedron orientation, every sign before warping,
//! every set of warped vertices, each warped along every lattice edge its signs allow by half or
//! all of its threshold, cut points at both thresholds and midway; a finer sweep, four warp and
//! five cut positions, finds the same extremes) and the contract test on every input. This is a
//! measured bound over those positions, not a proof over the continuum as the paper's
//! computer-assisted one is. With `alpha-long = 0.21509` and `alpha-short = 0.35900` the same test
//! holds [6.4°, 164.2°]. Every surface vertex is a cut point or a warped vertex, so it lies on the
//! field's surface when the samples carry the field (and on the samples' linear interpolation
//! otherwise). The tetrahedra conform (faces shared whole). The boundary is outward.
//!
//! **Where we differ from the paper.** The paper proves [10.7°, 164.8°] for the defaults and
//! [8.9°, 158.8°] for the second pair; our stencils reach 9.32° and 161.6° (defaults: on a kept
//! tetrahedron whose three other vertices were warped, and on the 2-1-1 pyramid with one warped
//! vertex) and 6.49° and 164.1° (second pair: already on unwarped prisms, 8.32°). Unexplained: the
//! stencils, the parity rule and the warping order were rebuilt from the paper's description, not
//! from its stencil figures, which were not at hand; the parity rule's two phases and the two
//! rules for quadrilaterals on short lattice edges were all tried, and these are the best.
//!
//! **Non-guarantees.** The boundary is not always a manifold: two parts of the inside that come
//! within a lattice edge of each other may touch at a vertex or an edge (the paper's topology
//! guarantee needs a surface smooth at the lattice's scale), and there the boundary, though every
//! face is wound outward from its tetrahedron, is not an oriented manifold (so `outward` is not
//! declared; the tests check it on smooth inputs). Parts of the inside thinner than the warp
//! distance vanish: their negative vertices all warp onto the surface and a tetrahedron with no
//! negative vertex is dropped (`keeps_small_parts` is not declared). Tetrahedra are uniform in size (the
//! paper's graded interior is not built). A tetrahedron whose four vertices are all zero is
//! dropped, as the paper drops every tetrahedron with no negative vertex.
//!
//! **Costs.** One pass over the lattice's tetrahedra (twelve per cube) for cut edges, one for
//! stencils, both on rayon's threads in layers joined in order (the mesh does not depend on the
//! thread count); cut points, warps and boundary faces live in maps the size of the surface.
//!
//! ```
//! use isolab_algorithms::extractors::isosurface_stuffing::IsosurfaceStuffing;
//! use isolab_algorithms::{fields, geometry::dihedral_angles, Extraction, Extractor, Grid, Samples};
//! let sphere = fields::builtin("sphere", Default::default()).unwrap();
//! let samples = Samples::sample_cubic(sphere.clone(), Grid::covering(&sphere.domain(), 24).unwrap(), 0.0).unwrap();
//! let mut out = Extraction::default();
//! IsosurfaceStuffing::default().extract(&samples, &mut out).unwrap();
//! let t = &out.volume;
//! assert!(!t.tetrahedra.is_empty());
//! // Every dihedral angle within the proven interval.
//! for tet in &t.tetrahedra {
//!     let angles = dihedral_angles(tet.map(|i| t.positions[i as usize]));
//!     assert!(angles.iter().all(|&a| (10.7..=164.8).contains(&a)));
//! }
//! ```

use crate::extract::{DihedralInterval, ExtractError, Extraction, Extractor, ExtractorInfo, Guarantees};
use crate::lattice::{Grid, Lattice};
use crate::mesh::{TetMesh, TriMesh};
use crate::options::{OptionError, Options};
use crate::samples::Samples;
use glam::{DVec3, Vec3};
use rayon::prelude::*;
use std::collections::HashMap;
use std::time::Instant;

mod root;
pub mod stencils;
#[cfg(test)]
mod tests;

use root::{refine_root, ROOT_TOLERANCE};
use stencils::Corner;

/// One line for listings.
pub const DESCRIPTION: &str =
    "Labelle & Shewchuk 2007: BCC lattice cut at the surface and warped, stencils that bound every dihedral angle (tetrahedra + boundary)";

/// Options it takes.
pub const OPTION_NAMES: &[&str] = &["alpha-long", "alpha-short"];

/// The paper's parameters for its [10.7°, 164.8°] bound (the defaults).
pub const ALPHA_LONG: f64 = 0.24999;
/// See [`ALPHA_LONG`].
pub const ALPHA_SHORT: f64 = 0.41189;
/// The interval the paper proves for its stencils with [`ALPHA_LONG`] and [`ALPHA_SHORT`].
pub const PAPER: DihedralInterval = DihedralInterval { min_degrees: 10.7, max_degrees: 164.8 };
/// The interval this implementation's stencils keep with the defaults, declared in [`INFO`]: the
/// worst angles of the exhaustive stencil test (9.317° and 161.643°), rounded outward.
pub const GUARANTEED: DihedralInterval = DihedralInterval { min_degrees: 9.3, max_degrees: 161.7 };
/// The paper's second parameter pair.
pub const ALPHA_LONG_NARROW: f64 = 0.21509;
/// See [`ALPHA_LONG_NARROW`].
pub const ALPHA_SHORT_NARROW: f64 = 0.35900;
/// The interval the paper proves for its stencils with the second pair.
pub const PAPER_NARROW: DihedralInterval = DihedralInterval { min_degrees: 8.9, max_degrees: 158.8 };
/// The interval this implementation keeps with the second pair (exhaustive test: 6.492° and
/// 164.101°, rounded outward).
pub const GUARANTEED_NARROW: DihedralInterval = DihedralInterval { min_degrees: 6.4, max_degrees: 164.2 };

/// Labelle & Shewchuk 2007, uniform isosurface stuffing.
pub const INFO: ExtractorInfo = ExtractorInfo {
    name: "isosurface-stuffing",
    description: DESCRIPTION,
    options: OPTION_NAMES,
    make: from_options,
    guarantees: Guarantees {
        cubic: true,
        bcc: true,
        closed: true,
        manifold: false,
        outward: false,
        intersection_free: false,
        trilinear_topology: false,
        keeps_small_parts: false,
        dihedral: Some(GUARANTEED),
    },
    samples: crate::extract::SampleAccess::Copies(
        "it reads f32 samples by flat lattice index, the BCC centres beside the corners",
    ),
};

/// Builds it from options (`alpha-long`, `alpha-short`: fractions of an edge in (0, 0.5)).
pub fn from_options(options: &Options) -> Result<Box<dyn Extractor>, OptionError> {
    let mut r = options.reader(INFO.name, OPTION_NAMES);
    let alpha_long = f64::from(r.number("alpha-long", ALPHA_LONG as f32, 0.0, 0.4999)?);
    let alpha_short = f64::from(r.number("alpha-short", ALPHA_SHORT as f32, 0.0, 0.4999)?);
    r.finish()?;
    // f32 options: the defaults keep the paper's decimals exactly.
    let exact = |v: f64, paper: f64| if (v - paper).abs() < 1e-6 { paper } else { v };
    Ok(Box::new(IsosurfaceStuffing {
        alpha_long: exact(exact(alpha_long, ALPHA_LONG), ALPHA_LONG_NARROW),
        alpha_short: exact(exact(alpha_short, ALPHA_SHORT), ALPHA_SHORT_NARROW),
    }))
}

/// Uniform isosurface stuffing with its two warp thresholds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IsosurfaceStuffing {
    /// Warp threshold on long edges, as a fraction of the edge.
    pub alpha_long: f64,
    /// Warp threshold on short edges.
    pub alpha_short: f64,
}

impl Default for IsosurfaceStuffing {
    fn default() -> Self {
        IsosurfaceStuffing { alpha_long: ALPHA_LONG, alpha_short: ALPHA_SHORT }
    }
}

impl Extractor for IsosurfaceStuffing {
    fn info(&self) -> &'static ExtractorInfo {
        &INFO
    }

    fn produces_volume(&self) -> bool {
        true
    }

    fn settings(&self) -> String {
        format!("alpha-long {}, alpha-short {}", self.alpha_long, self.alpha_short)
    }

    fn extract_into(&self, samples: &Samples, out: &mut Extraction) -> Result<usize, ExtractError> {
        let t = Instant::now();
        let lattice = StuffingLattice::of(samples);
        let cuts = cut_points(&lattice, samples);
        let warped = warp(&lattice, &cuts, [self.alpha_long, self.alpha_short]);
        out.stats.times.vertex = t.elapsed();
        let t = Instant::now();
        let signs = warped_signs(&lattice, &warped);
        let filled = fill_lattice(&lattice, &signs, &cuts);
        out.stats.active_cells = filled.cut_tets;
        write_meshes(&lattice, &signs, &cuts, &warped, &filled.tets, out);
        out.stats.times.geometry = t.elapsed();
        Ok(lattice.values.capacity() * 4 + lattice.signs.capacity())
    }
}

/// The BCC lattice of a sample set: corners, then centres (a BCC lattice's own, or a cubic
/// grid's cube centres), with a value per vertex relative to the iso-value.
pub struct StuffingLattice {
    /// The corner grid.
    pub grid: Grid,
    /// Value minus iso-value, corners then centres.
    pub values: Vec<f32>,
    /// Sign of each value: -1, 0 or 1.
    pub signs: Vec<i8>,
}

impl StuffingLattice {
    /// The lattice of `samples`: a BCC lattice as it is, a cubic grid with its cube centres.
    pub fn of(samples: &Samples) -> StuffingLattice {
        let grid = *samples.grid();
        let iso = samples.iso();
        let given = samples.values();
        let mut values: Vec<f32> = match samples.lattice() {
            Lattice::Bcc(_) => given.to_vec(),
            Lattice::Cubic(_) => {
                let centres = grid.centres();
                let mut v = Vec::with_capacity(grid.len() + centres.len());
                v.extend_from_slice(given);
                v.extend(cube_centre_values(&grid, given, iso, samples.field().map(|f| f.as_ref())));
                v
            }
        };
        values.iter_mut().for_each(|v| *v -= iso);
        let signs = values.iter().map(|&v| sign(v)).collect();
        StuffingLattice { grid, values, signs }
    }

    fn centres(&self) -> [usize; 3] {
        self.grid.dims.map(|d| d.saturating_sub(1))
    }

    /// The vertex at doubled coordinates `d` (even: corner, odd: centre).
    pub fn id(&self, d: [i32; 3]) -> u32 {
        let [nx, ny, _] = self.grid.dims;
        let [x, y, z] = d.map(|c| (c.div_euclid(2)) as usize);
        if d[0].rem_euclid(2) == 0 {
            (x + nx * (y + ny * z)) as u32
        } else {
            let [cx, cy, _] = self.centres();
            (self.grid.len() + x + cx * (y + cy * z)) as u32
        }
    }

    /// World position of doubled coordinates `d`, in `f64`.
    pub fn position(&self, d: [i32; 3]) -> DVec3 {
        self.grid.origin.as_dvec3() + DVec3::new(d[0] as f64, d[1] as f64, d[2] as f64) * (0.5 * f64::from(self.grid.spacing))
    }

    /// Doubled coordinates of vertex `id`.
    pub fn doubled(&self, id: u32) -> [i32; 3] {
        let id = id as usize;
        let (dims, i, odd) =
            if id < self.grid.len() { (self.grid.dims, id, 0) } else { (self.centres(), id - self.grid.len(), 1) };
        let [nx, ny, _] = dims;
        [i % nx, (i / nx) % ny, i / (nx * ny)].map(|c| 2 * c as i32 + odd)
    }

    /// The lattice's tetrahedra anchored at centre layer `z`: each pair of neighbouring centres
    /// and the four corners of the face between them close four tetrahedra (the BCC templates of
    /// [`crate::extractors::tetrahedral`]), in doubled coordinates, positively oriented.
    fn layer_tets(&self, z: usize, mut visit: impl FnMut([[i32; 3]; 4])) {
        let templates = &crate::extractors::tetrahedral::topology(crate::extractors::tetrahedral::TetKind::Bcc).templates;
        let c = self.centres();
        for y in 0..c[1] {
            for x in 0..c[0] {
                let anchor = [x, y, z];
                for axis in 0..3 {
                    if anchor[axis] + 1 >= c[axis] {
                        continue;
                    }
                    let d = anchor.map(|a| 2 * a as i32 + 1);
                    for template in &templates[4 * axis..4 * axis + 4] {
                        visit(template.map(|o| [d[0] + o[0], d[1] + o[1], d[2] + o[2]]));
                    }
                }
            }
        }
    }

    fn layers(&self) -> usize {
        self.centres()[2]
    }

    fn id_is_corner(&self, id: u32) -> bool {
        (id as usize) < self.grid.len()
    }
}

fn sign(v: f32) -> i8 {
    if v < 0.0 {
        -1
    } else if v > 0.0 {
        1
    } else {
        0
    }
}

/// Values at the centres of `grid`'s cubes: the field's where it is given (sampled for `iso`, as
/// the corners were: a mesh field's narrow band depends on it), else the mean of each cube's eight
/// corners.
fn cube_centre_values(grid: &Grid, corners: &[f32], iso: f32, field: Option<&dyn crate::field::Field>) -> Vec<f32> {
    let centres = grid.centres();
    let mut out = vec![0.0f32; centres.len()];
    if let Some(field) = field {
        field.sample_grid(&centres, iso, &mut out);
        return out;
    }
    let [nx, ny, _] = grid.dims;
    let [cx, cy, _] = centres.dims;
    out.par_chunks_mut(cx * cy).enumerate().for_each(|(z, layer)| {
        for y in 0..cy {
            for x in 0..cx {
                let mut sum = 0.0f64;
                for k in 0..8 {
                    let (dx, dy, dz) = (k & 1, (k >> 1) & 1, k >> 2);
                    sum += f64::from(corners[(x + dx) + nx * ((y + dy) + ny * (z + dz))]);
                }
                layer[x + cx * y] = (sum / 8.0) as f32;
            }
        }
    });
    out
}

/// The six edges of a tetrahedron.
const EDGES: [(usize, usize); 6] = [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)];

/// The cut points: edges between a negative and a positive vertex, sorted by their ends' ids,
/// each with its position and its fraction from the lower id.
pub struct Cuts {
    /// `(lower id, higher id)` of each cut edge, sorted.
    pub edges: Vec<(u32, u32)>,
    /// Fraction of the edge from its lower id to the cut point.
    pub fractions: Vec<f64>,
    /// World position of each cut point.
    pub positions: Vec<DVec3>,
}

impl Cuts {
    /// The index of the cut point on edge `(a, b)`, if it has one.
    pub fn find(&self, a: u32, b: u32) -> Option<usize> {
        self.edges.binary_search(&(a.min(b), a.max(b))).ok()
    }
}

/// Every cut point of the lattice ([`Cuts`]).
pub fn cut_points(lattice: &StuffingLattice, samples: &Samples) -> Cuts {
    let signs = &lattice.signs;
    let mut edges: Vec<(u32, u32)> = (0..lattice.layers())
        .into_par_iter()
        .map(|z| {
            let mut found = Vec::new();
            lattice.layer_tets(z, |d| {
                let id = d.map(|v| lattice.id(v));
                let s = id.map(|i| signs[i as usize]);
                if !(s.contains(&-1) && s.contains(&1)) {
                    return;
                }
                for (i, j) in EDGES {
                    if s[i] * s[j] < 0 {
                        found.push((id[i].min(id[j]), id[i].max(id[j])));
                    }
                }
            });
            found
        })
        .flatten()
        .collect();
    edges.par_sort_unstable();
    edges.dedup();
    let field = samples.field().map(|f| f.as_ref());
    let iso = samples.iso();
    let (fractions, positions): (Vec<f64>, Vec<DVec3>) = edges
        .par_iter()
        .map(|&(a, b)| {
            let (fa, fb) = (f64::from(lattice.values[a as usize]), f64::from(lattice.values[b as usize]));
            let (pa, pb) = (lattice.position(lattice.doubled(a)), lattice.position(lattice.doubled(b)));
            let mut t = fa / (fa - fb);
            if let Some(field) = field {
                t = refine_root(
                    |s| f64::from(field.value((pa + (pb - pa) * s).as_vec3())) - f64::from(iso),
                    (0.0, fa),
                    (1.0, fb),
                    t,
                    ROOT_TOLERANCE * (fa.abs() + fb.abs()),
                );
            }
            (t, pa + (pb - pa) * t)
        })
        .unzip();
    Cuts { edges, fractions, positions }
}

/// Which vertices moved: vertex id to the cut point it moved onto.
pub type Warps = HashMap<u32, usize>;

/// Warping ([`IsosurfaceStuffing`]'s third pass): `alpha = [long, short]`.
pub fn warp(lattice: &StuffingLattice, cuts: &Cuts, alpha: [f64; 2]) -> Warps {
    // For one end of cut `c`: its fraction from that end, if it violates it.
    let violation = |c: usize, end: u32| {
        let (a, b) = cuts.edges[c];
        let long = lattice.id_is_corner(a) == lattice.id_is_corner(b);
        let from_end = if end == a { cuts.fractions[c] } else { 1.0 - cuts.fractions[c] };
        (from_end < alpha[if long { 0 } else { 1 }]).then_some(from_end)
    };
    let mut warps = Warps::new();
    for wanted in [1i8, -1] {
        let mut best: HashMap<u32, (f64, usize)> = HashMap::new();
        for (c, &(a, b)) in cuts.edges.iter().enumerate() {
            let (end, other) = if lattice.signs[a as usize] == wanted { (a, b) } else { (b, a) };
            // A negative end is warped only onto a cut point whose positive end stayed.
            if warps.contains_key(&other) {
                continue;
            }
            if let Some(f) = violation(c, end) {
                let entry = best.entry(end).or_insert((f, c));
                if f < entry.0 {
                    *entry = (f, c);
                }
            }
        }
        warps.extend(best.into_iter().map(|(v, (_, c))| (v, c)));
    }
    warps
}

/// The stencil tetrahedra of the whole lattice, as vertex keys: a lattice id, or
/// `u32::MAX - cut` for a cut point.
struct Filled {
    tets: Vec<[u32; 4]>,
    cut_tets: usize,
}

/// The key of a cut point among vertex keys.
fn cut_key(c: usize) -> u32 {
    u32::MAX - c as u32
}

/// Each lattice vertex's sign after warping (a warped vertex is zero).
fn warped_signs(lattice: &StuffingLattice, warps: &Warps) -> Vec<i8> {
    let mut signs = lattice.signs.clone();
    for &v in warps.keys() {
        signs[v as usize] = 0;
    }
    signs
}

fn fill_lattice(lattice: &StuffingLattice, signs: &[i8], cuts: &Cuts) -> Filled {
    let sign_of = |id: u32| signs[id as usize];
    let parts: Vec<(Vec<[u32; 4]>, usize)> = (0..lattice.layers())
        .into_par_iter()
        .map(|z| {
            let (mut tets, mut cut_tets) = (Vec::new(), 0usize);
            lattice.layer_tets(z, |d| {
                let id = d.map(|v| lattice.id(v));
                let s = id.map(sign_of);
                if !s.contains(&-1) {
                    return;
                }
                if !s.contains(&1) {
                    tets.push(id);
                    return;
                }
                let fill = stencils::fill(&d, s);
                cut_tets += 1;
                for tet in fill.tets() {
                    let tet = stencils::orient(&d, tet);
                    tets.push(tet.map(|c| match c {
                        Corner::Vertex(i) => id[i as usize],
                        Corner::Cut(i, j) => {
                            cut_key(cuts.find(id[i as usize], id[j as usize]).expect("a live cut edge has a cut point"))
                        }
                    }));
                }
            });
            (tets, cut_tets)
        })
        .collect();
    let cut_tets = parts.iter().map(|p| p.1).sum();
    let tets = parts.into_iter().flat_map(|p| p.0).collect();
    Filled { tets, cut_tets }
}

/// Faces of a positively oriented tetrahedron `[a, b, c, d]`, counter-clockwise seen from outside.
const FACES: [[usize; 3]; 4] = [[1, 2, 3], [0, 3, 2], [0, 1, 3], [0, 2, 1]];

/// Compacts the vertex keys into the volume mesh and writes its boundary as the surface.
fn write_meshes(lattice: &StuffingLattice, signs: &[i8], cuts: &Cuts, warps: &Warps, tets: &[[u32; 4]], out: &mut Extraction) {
    // Vertex keys in order: lattice ids ascending, then cut points ascending.
    let is_cut = |k: u32| u64::from(k) > u64::from(u32::MAX) - cuts.edges.len() as u64;
    // Used lattice vertices and cut points, numbered in that order through dense arrays.
    let lattice_len = lattice.values.len();
    let mut used_lattice = vec![false; lattice_len];
    let mut used_cut = vec![false; cuts.edges.len()];
    for &k in tets.iter().flatten() {
        if is_cut(k) {
            used_cut[(u32::MAX - k) as usize] = true;
        } else {
            used_lattice[k as usize] = true;
        }
    }
    let mut lattice_index = vec![u32::MAX; lattice_len];
    let mut cut_index = vec![u32::MAX; cuts.edges.len()];
    let mut keys: Vec<u32> = Vec::new();
    for (k, _) in used_lattice.iter().enumerate().filter(|(_, &u)| u) {
        lattice_index[k] = keys.len() as u32;
        keys.push(k as u32);
    }
    for (c, _) in used_cut.iter().enumerate().filter(|(_, &u)| u) {
        cut_index[c] = keys.len() as u32;
        keys.push(cut_key(c));
    }
    let index_of = |k: u32| if is_cut(k) { cut_index[(u32::MAX - k) as usize] } else { lattice_index[k as usize] };
    let position = |k: u32| -> Vec3 {
        if is_cut(k) {
            cuts.positions[(u32::MAX - k) as usize].as_vec3()
        } else if let Some(&c) = warps.get(&k) {
            cuts.positions[c].as_vec3()
        } else {
            lattice.position(lattice.doubled(k)).as_vec3()
        }
    };
    let volume: &mut TetMesh = &mut out.volume;
    volume.positions.extend(keys.iter().map(|&k| position(k)));
    volume.tetrahedra.extend(tets.iter().map(|t| t.map(index_of)));
    // Boundary faces: those of one tetrahedron only. A face whose three vertices are negative
    // lattice vertices away from the lattice's border is inside (the tetrahedron across it keeps
    // that face whole), so only the others are counted.
    let [nx, ny, nz] = lattice.grid.dims;
    let special = |k: u32| -> bool {
        if is_cut(k) || signs[k as usize] >= 0 {
            return true;
        }
        let d = lattice.doubled(k);
        d[0] == 0
            || d[1] == 0
            || d[2] == 0
            || d[0] == 2 * (nx as i32 - 1)
            || d[1] == 2 * (ny as i32 - 1)
            || d[2] == 2 * (nz as i32 - 1)
    };
    let mut faces: HashMap<[u32; 3], ([u32; 3], u32)> = HashMap::new();
    let mut order = Vec::new();
    for t in &volume.tetrahedra {
        for f in FACES {
            let face = f.map(|k| t[k]);
            if !face.iter().any(|&v| special(keys[v as usize])) {
                continue;
            }
            let mut key = face;
            key.sort_unstable();
            let entry = faces.entry(key).or_insert_with(|| {
                order.push(key);
                (face, 0)
            });
            entry.1 += 1;
        }
    }
    let surface: &mut TriMesh = &mut out.surface;
    let mut surface_index: HashMap<u32, u32> = HashMap::new();
    for key in order {
        let (face, count) = faces[&key];
        if count != 1 {
            continue;
        }
        let tri = face.map(|v| {
            *surface_index.entry(v).or_insert_with(|| {
                surface.positions.push(volume.positions[v as usize]);
                (surface.positions.len() - 1) as u32
            })
        });
        surface.triangles.push(tri);
    }
}
