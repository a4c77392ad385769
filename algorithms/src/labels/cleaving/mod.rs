//! # `lattice-cleaving`: tetrahedra for every label of a label map
//!
//! **Papers:** J. R. Bronson, J. A. Levine and R. T. Whitaker, "Lattice Cleaving: Conforming
//! Tetrahedral Meshes of Multimaterial Domains with Bounded Quality", Proc. 21st International
//! Meshing Roundtable, 2012, and its journal version ("Lattice Cleaving: A Multimaterial
//! Tetrahedral Meshing Algorithm with Guarantees", IEEE TVCG 20(2), 2014): a body-centred cubic
//! lattice, one label per lattice vertex, cut points where an edge's two labels' indicator
//! functions cross, and each lattice tetrahedron *cleaved* into tetrahedra of its labels, with
//! interfaces that conform by construction. Two-label isosurface stuffing (F. Labelle and J. R.
//! Shewchuk, SIGGRAPH 2007; `extractors::isosurface_stuffing`) is its special case.
//!
//! **Summary.** The lattice's corners are the map's samples (and one ring of background around
//! it), its centres the cells' centres:
//! 1. **Labels.** A corner takes its sample's label; a centre the label most of its cell's eight
//!    corners have (a tie alternately to the smallest and the largest by the cell's parity). A
//!    label's
//!    indicator is one-hot at a corner and the share of the cell's corners at a centre.
//! 2. **Cut points.** On an edge between two labels `a` and `b`, where the linear interpolation of
//!    `λa - λb` along the edge is zero, clamped to `[alpha, 1 - alpha]` of the edge from either
//!    end ([`ALPHA`]). A corner-corner edge is cut at its midpoint, as the voxels' own boundary
//!    is; an edge to a centre where its cell's corners tie is cut `alpha` short of the centre.
//! 3. **Cleaving** ([`stencil::cleave`]): every lattice tetrahedron whose corners differ is split
//!    into the dual cells of its corners in its barycentric subdivision, moved onto the cut
//!    points: each face split by the segments where its labels meet (from a face point, the mean
//!    of its three cut points, when it has three labels), every piece coned to one apex (the mean
//!    of the tetrahedron's cut and face points). Each cone tetrahedron takes its corner's label;
//!    the background's are dropped.
//!
//! **Where we differ from the paper.** Cleaving *warps*: a lattice vertex too close to a cut point
//! moves onto it, which keeps the interface where the indicators put it and is what its angle
//! proof needs. Here cut points are clamped instead (no vertex moves), and every multi-label
//! tetrahedron is cut by one universal stencil, the cone over its faces' pieces, rather than the
//! paper's case stencils. The clamp keeps every point a fixed share of an edge or face away from
//! the lattice's other features, which bounds every angle (below) and keeps each label's region
//! isotopic to the union of its vertices' dual cells, so manifold; it costs accuracy: an
//! interface within `alpha` of a lattice vertex is moved out to `alpha` (at most `alpha` of a
//! lattice edge; with the default 0.3, at most 0.26 of a sample spacing on an edge to a centre).
//!
//! **Guarantees.** Every dihedral angle in [`GUARANTEED`] and no tetrahedron inverted, declared as
//! [`super::LabelGuarantees::dihedral`] and held by the exhaustive stencil test (every pattern of
//! up to four labels on a lattice tetrahedron, every cut parameter at the clamp's two ends and
//! three points between) and by the contract test on every map it is given; measured over those
//! positions, not proved over the continuum. The tetrahedra conform (faces shared whole), every
//! interface triangle is a face of exactly two tetrahedra of its two labels (one for the
//! background), each label's boundary (the interface triangles that name it) is closed, manifold
//! and outward, and contains its samples: every cut on a corner's edges is at least half the edge
//! from it (its indicator is one-hot, and the other end's own label leads there), so every sample
//! lies strictly inside its label's tetrahedra.
//!
//! **Non-guarantees.** No grading: every lattice tetrahedron is a cell's size, so a label's
//! tetrahedron count grows with its volume, not its surface. No smoothing of the voxels'
//! staircase beyond the centres' votes. Only a closed border (labels end inside a ring of
//! background). Volumes follow the voxel counts to within the clamp's shift and the staircase's
//! chamfer (measured in the tests, not bounded).
//!
//! **Costs.** One pass over the cells, three faces of the lattice per cell, four tetrahedra per
//! face; uniform pairs of cells take a fast path. Slabs of cells run on rayon's threads and are
//! welded by their points' keys, so the mesh does not depend on the thread count.
//!
//! ```
//! use isolab_algorithms::labels::{self, LabelMap, LabelSurface};
//! use isolab_algorithms::Options;
//! // A 6 x 6 x 6 block of label 3 in an 8 x 8 x 8 map.
//! let mut map = [0u8; 512];
//! for z in 1..7 { for y in 1..7 { for x in 1..7 { map[x + 8 * (y + 8 * z)] = 3; } } }
//! let cleaving = labels::build("lattice-cleaving", &Options::new()).unwrap().unwrap();
//! let mut out = LabelSurface::default();
//! cleaving.extract_u8(LabelMap::new([8, 8, 8], &map).unwrap(), &mut out).unwrap();
//! assert!(out.tetrahedron_labels.iter().all(|&l| l == 3));
//! // The label's volume is near its 216 voxels' (its edges chamfered, its faces flat).
//! let volume: f64 = out.tetrahedra.iter().map(|t| {
//!     let [a, b, c, d] = t.map(|v| out.mesh.positions[v as usize].as_dvec3());
//!     (b - a).dot((c - a).cross(d - a)) / 6.0
//! }).sum();
//! assert!((volume - 216.0).abs() < 0.1 * 216.0, "{volume}");
//! ```

pub mod stencil;
#[cfg(test)]
mod tests;

use glam::DVec3;
use rustc_hash::FxHashMap;

use super::blocks::{weld_label_fragments, LabelBlock, LabelFragment};
use super::{Border, Label, LabelExtractor, LabelExtractorInfo, LabelGuarantees, LabelMap, LabelSurface};
use crate::extract::{DihedralInterval, ExtractError};
use crate::options::{OptionError, Options};
use stencil::{Corner, Keys, Point, Sink};

/// How close to a lattice vertex a cut point may come, as a share of its edge.
pub const ALPHA: f64 = 0.3;

/// The dihedral angles every tetrahedron keeps with [`ALPHA`] (measured by the exhaustive stencil
/// test, rounded outward to a tenth of a degree).
pub const GUARANTEED: DihedralInterval = DihedralInterval { min_degrees: 5.1, max_degrees: 168.1 };

/// One line for listings.
pub const DESCRIPTION: &str =
    "Bronson et al. 2012 lattice cleaving on the BCC lattice: tetrahedra for every label, interfaces conforming, dihedral angles bounded";

/// Lattice cleaving.
pub const INFO: LabelExtractorInfo = LabelExtractorInfo {
    name: "lattice-cleaving",
    description: DESCRIPTION,
    options: OPTION_NAMES,
    make: from_options,
    guarantees: LabelGuarantees { closed: true, manifold: true, outward: true, dihedral: Some(GUARANTEED) },
};

/// Option names for [`from_options`]: `border`, which takes `closed` only (tetrahedra fill
/// labels that end inside the map's ring of background).
pub const OPTION_NAMES: &[&str] = &["border"];

/// Builds lattice cleaving.
pub fn from_options(options: &Options) -> Result<Box<dyn LabelExtractor>, OptionError> {
    let mut r = options.reader(INFO.name, OPTION_NAMES);
    r.choice("border", Border::Closed, &[("closed", Border::Closed)])?;
    r.finish()?;
    Ok(Box::new(LatticeCleaving))
}

/// Lattice cleaving.
#[derive(Clone, Copy, Debug, Default)]
pub struct LatticeCleaving;

impl LabelExtractor for LatticeCleaving {
    fn info(&self) -> &'static LabelExtractorInfo {
        &INFO
    }
    fn extract_u8(&self, map: LabelMap<'_, u8>, out: &mut LabelSurface) -> Result<(), ExtractError> {
        extract(map, out)
    }
    fn extract_u16(&self, map: LabelMap<'_, u16>, out: &mut LabelSurface) -> Result<(), ExtractError> {
        extract(map, out)
    }
    fn extract_u32(&self, map: LabelMap<'_, u32>, out: &mut LabelSurface) -> Result<(), ExtractError> {
        extract(map, out)
    }
    fn apron(&self) -> usize {
        0
    }
    fn border(&self) -> Border {
        Border::Closed
    }
    fn block_u8(&self, block: LabelBlock<'_, u8>, out: &mut LabelFragment) -> Result<(), ExtractError> {
        mesh_block(&block, out);
        Ok(())
    }
    fn block_u16(&self, block: LabelBlock<'_, u16>, out: &mut LabelFragment) -> Result<(), ExtractError> {
        mesh_block(&block, out);
        Ok(())
    }
    fn block_u32(&self, block: LabelBlock<'_, u32>, out: &mut LabelFragment) -> Result<(), ExtractError> {
        mesh_block(&block, out);
        Ok(())
    }
}

/// Cells per slab of the whole-map pass.
const SLAB: usize = 8;

fn extract<T: Label>(map: LabelMap<'_, T>, out: &mut LabelSurface) -> Result<(), ExtractError> {
    use rayon::prelude::*;
    let slabs = (map.dims[2] + 1).div_ceil(SLAB);
    let fragments: Vec<LabelFragment> = (0..slabs)
        .into_par_iter()
        .map(|s| {
            let block = LabelBlock {
                samples: map.labels,
                window_lo: [0; 3],
                window_dims: map.dims,
                map_dims: map.dims,
                cells: [0..map.dims[0] + 1, 0..map.dims[1] + 1, s * SLAB..((s + 1) * SLAB).min(map.dims[2] + 1)],
                apron: 0,
            };
            let mut f = LabelFragment::default();
            mesh_block(&block, &mut f);
            f
        })
        .collect();
    *out = weld_label_fragments(&fragments);
    Ok(())
}

/// Points named by where they sit on the lattice, in half-cell units (a corner at padded sample
/// `p` is at `2p`, the centre of cell `c` at `2c + 1`): a vertex by its place, a cut, face or
/// apex point by its first vertex (in place order) and the directions to the others.
#[derive(Clone, Copy)]
struct KeySpace {
    sizes: [u128; 3],
}

impl KeySpace {
    fn new(map_dims: [usize; 3]) -> Self {
        // Places from the centre of cell -1 (at -1) to that of cell n + 1 (at 2n + 3), shifted
        // by one.
        Self { sizes: map_dims.map(|n| 2 * n as u128 + 5) }
    }
    fn place(&self, h: [i64; 3]) -> u128 {
        let [x, y, z] = h.map(|v| (v + 1) as u128);
        x + self.sizes[0] * (y + self.sizes[1] * z)
    }
    fn vertex(&self, h: [i64; 3]) -> u128 {
        self.place(h) << 24
    }
    /// `kind` and the directions from the first of `hs` (in place order) to the others.
    fn compound(&self, kind: u128, hs: &mut [[i64; 3]]) -> u128 {
        hs.sort_unstable_by_key(|&h| self.place(h));
        let first = hs[0];
        let mut tag = kind << 21;
        for (k, h) in hs[1..].iter().enumerate() {
            let d = [0, 1, 2].map(|a| (h[a] - first[a] + 2) as u128);
            tag |= (d[0] + 5 * d[1] + 25 * d[2]) << (7 * (hs.len() - 2 - k));
        }
        self.place(first) << 24 | tag
    }
}

/// A lattice vertex: where it is (half-cell units), its label and what its indicators read.
#[derive(Clone, Copy)]
struct Vertex {
    h: [i64; 3],
    label: u32,
    /// A centre's cell corners' labels (`None` for a corner).
    votes: Option<[u32; 8]>,
}

impl Vertex {
    /// Label `l`'s indicator here.
    fn indicator(&self, l: u32) -> f64 {
        match &self.votes {
            None => f64::from(u8::from(self.label == l)),
            Some(v) => v.iter().filter(|&&x| x == l).count() as f64 / 8.0,
        }
    }
}

/// The cut parameter from `u` toward `v` (labels differ): where `λa - λb` interpolates to zero.
fn cut_parameter(u: &Vertex, v: &Vertex) -> f64 {
    let (a, b) = (u.label, v.label);
    let du = u.indicator(a) - u.indicator(b);
    let dv = v.indicator(a) - v.indicator(b);
    if du - dv > 0.0 {
        du / (du - dv)
    } else {
        0.5
    }
}

/// The label most of `votes` have; a tie goes to the smallest of the tied labels in cells of
/// even parity (`x + y + z`) and to the largest in odd ones, so that neither of two labels gains
/// on the other along a flat interface (the background, outside the map too, included).
fn majority(votes: &[u32; 8], odd: bool) -> u32 {
    let mut best = (0usize, 0u32);
    for &l in votes {
        let n = votes.iter().filter(|&&x| x == l).count();
        let wins_tie = if odd { l > best.1 } else { l < best.1 };
        if n > best.0 || (n == best.0 && wins_tie) {
            best = (n, l);
        }
    }
    best.1
}

/// Collects a block's tetrahedra and interface triangles, numbering points by key.
struct Builder<'s> {
    index: FxHashMap<u128, u32>,
    out: &'s mut LabelSurface,
    keys: &'s mut Vec<u128>,
}

impl Builder<'_> {
    fn vertex(&mut self, p: Point) -> u32 {
        let positions = &mut self.out.mesh.positions;
        let keys = &mut *self.keys;
        *self.index.entry(p.key).or_insert_with(|| {
            positions.push((p.at * 0.5 - DVec3::ONE).as_vec3());
            keys.push(p.key);
            (positions.len() - 1) as u32
        })
    }
}

impl Sink for Builder<'_> {
    fn tetrahedron(&mut self, points: [Point; 4], label: u32) {
        let t = points.map(|p| self.vertex(p));
        self.out.tetrahedra.push(t);
        self.out.tetrahedron_labels.push(label);
    }
    fn triangle(&mut self, points: [Point; 3], pair: [u32; 2]) {
        let t = points.map(|p| self.vertex(p));
        self.out.mesh.triangles.push(t);
        self.out.pairs.push(pair);
    }
}

/// Meshes the faces `block`'s cells own: each cell owns the lattice face it shares with the next
/// cell along each axis, and the four lattice tetrahedra around it.
fn mesh_block<T: Label>(block: &LabelBlock<'_, T>, out: &mut LabelFragment) {
    let space = KeySpace::new(block.map_dims);
    let mut keys = Vec::new();
    let mut b = Builder { index: FxHashMap::default(), out: &mut out.surface, keys: &mut keys };
    let [xs, ys, zs] = block.cells.clone();
    let cell_votes = |c: [usize; 3]| -> [u32; 8] {
        std::array::from_fn(|i| block.padded([c[0] + (i & 1), c[1] + (i >> 1 & 1), c[2] + (i >> 2 & 1)]).id())
    };
    for z in zs {
        for y in ys.clone() {
            for x in xs.clone() {
                let c = [x, y, z];
                let here = cell_votes(c);
                if here.iter().any(|&l| l != here[0]) {
                    b.out.active_cells += 1;
                }
                let ci = c.map(|v| v as i64);
                for d in 0..3 {
                    // The face to the next cell (the last cell's next lies outside the map, all
                    // background), and for the first cell along `d` the face to the one before
                    // (outside too), so that a border cell's centre may take a label.
                    let mut next = c;
                    next[d] += 1;
                    mesh_face(&mut b, &space, ci, d, &here, &cell_votes(next));
                    if c[d] == 0 {
                        let mut before = ci;
                        before[d] -= 1;
                        mesh_face(&mut b, &space, before, d, &[0; 8], &here);
                    }
                }
            }
        }
    }
    out.keys = keys;
}

/// The four lattice tetrahedra around the face between cell `c` and the next along axis `d`, as
/// slots (half-cell places): the two centres, then two corners of the face, neighbours on it.
fn face_tetrahedra(ci: [i64; 3], d: usize) -> [[[i64; 3]; 4]; 4] {
    let (u, v) = ((d + 1) % 3, (d + 2) % 3);
    let mut a = ci.map(|x| 2 * x + 1);
    let here = a;
    a[d] += 2;
    let there = a;
    let ring = [(0, 0), (1, 0), (1, 1), (0, 1)].map(|(ou, ov): (i64, i64)| {
        let mut h = ci.map(|x| 2 * x);
        h[d] += 2;
        h[u] += 2 * ou;
        h[v] += 2 * ov;
        h
    });
    std::array::from_fn(|k| [here, there, ring[k], ring[(k + 1) % 4]])
}

/// The keys of the points a lattice tetrahedron (slots `h`, labels `l`) may make.
fn tetrahedron_keys(space: &KeySpace, h: &[[i64; 3]; 4], l: &[u32; 4]) -> Keys {
    let mut keys = Keys::default();
    for (e, &(i, j)) in stencil::EDGES.iter().enumerate() {
        if l[i] != l[j] {
            keys.edges[e] = space.compound(1, &mut [h[i], h[j]]);
        }
    }
    for (f, key) in keys.faces.iter_mut().enumerate() {
        let [a, b, c] = [[1, 2, 3], [0, 2, 3], [0, 1, 3], [0, 1, 2]][f];
        *key = space.compound(2, &mut [h[a], h[b], h[c]]);
    }
    keys.apex = space.compound(3, &mut h.clone());
    keys
}

/// A lattice vertex's position (half-cell units).
fn position(h: [i64; 3]) -> DVec3 {
    DVec3::new(h[0] as f64, h[1] as f64, h[2] as f64)
}

/// The four lattice tetrahedra around the face between cell `c` and the next along axis `d`
/// (`here` and `there` the two cells' corner labels).
fn mesh_face(b: &mut Builder<'_>, space: &KeySpace, c: [i64; 3], d: usize, here: &[u32; 8], there: &[u32; 8]) {
    let odd = (c[0] + c[1] + c[2]).rem_euclid(2) == 1;
    let (centre_here, centre_there) = (majority(here, odd), majority(there, !odd));
    let (u, v) = ((d + 1) % 3, (d + 2) % 3);
    let ring = [(0, 0), (1, 0), (1, 1), (0, 1)].map(|(ou, ov): (usize, usize)| here[1 << d | ou << u | ov << v]);
    for (k, h) in face_tetrahedra(c, d).iter().enumerate() {
        let slots = [
            Vertex { h: h[0], label: centre_here, votes: Some(*here) },
            Vertex { h: h[1], label: centre_there, votes: Some(*there) },
            Vertex { h: h[2], label: ring[k], votes: None },
            Vertex { h: h[3], label: ring[(k + 1) % 4], votes: None },
        ];
        let l = slots.map(|s| s.label);
        let corners = slots.map(|s| Corner { key: space.vertex(s.h), at: position(s.h), label: s.label });
        if l.iter().all(|&x| x == l[0]) {
            stencil::cleave(&corners, &[0.5; 6], ALPHA, &Keys::default(), b);
            continue;
        }
        let t = std::array::from_fn(|e| {
            let (i, j) = stencil::EDGES[e];
            if l[i] != l[j] {
                cut_parameter(&slots[i], &slots[j])
            } else {
                0.5
            }
        });
        stencil::cleave(&corners, &t, ALPHA, &tetrahedron_keys(space, h, &l), b);
    }
}
