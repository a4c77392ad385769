//! # Multi-label marching tetrahedra
//!
//! **Papers:** the multi-material marching of Z. Wu and J. M. Sullivan, "Multiple material
//! marching cubes algorithm", IJNME 58(2), 2003 (a vertex at each crossing edge's midpoint, at each
//! face centre where three materials meet and at each cell centre where three or more meet, the
//! cell's interface the cone from its centre over its faces' curves), run on the Kuhn split of
//! every cube into six tetrahedra (the split of `tetrahedral::topology`, along each cube's main
//! diagonal) instead of on cubes. A tetrahedron has no ambiguous face (any two of its corners
//! share an edge), so no case table and no decider are needed.
//!
//! **Summary.** In each tetrahedron whose corners are not all one label, each face carries the
//! curves where its labels meet: one segment between the midpoints of its two crossing edges when
//! the face has two labels, three segments from the face's centroid to its edges' midpoints when
//! it has three. A tetrahedron with two labels is cut by marching tetrahedra's triangle or quad
//! through its crossing edges' midpoints (each label's boundary at 0.5, as marching cubes on the
//! label's indicator); one with three or four labels by the cone from its centroid over its
//! faces' segments. Every triangle separates the two corners of one crossing edge and is wound so
//! that its normal points from the larger label into the smaller.
//!
//! **Guarantees.** Each label's region is, up to an isotopy inside each tetrahedron, the union of
//! the dual cells of its samples in the barycentric subdivision of the Kuhn triangulation, which
//! is a regular neighbourhood of the label's samples; its boundary is therefore a closed 2-manifold
//! (with `border=closed`) for every label map, and the meshes of two labels share their interface
//! triangles. The pieces are planar in two-label tetrahedra and cones from an interior point over
//! the tetrahedron's boundary otherwise, so no two triangles cross. Tests: every pattern of one
//! cell with up to four labels, of two cells with up to three, random maps
//! (`tests/tests/labels.rs`).
//!
//! **Non-guarantees.** No smoothing: the surface keeps the voxels' staircase (at the midpoints, a
//! chamfered one). About six times surface nets' triangles.
//!
//! **Costs.** One pass over the cells; vertices shared through a hash map of their lattice keys.
//!
//! ```
//! use isolab_algorithms::labels::{self, LabelMap, LabelSurface};
//! use isolab_algorithms::Options;
//! // One voxel of label 7 in a 3 x 3 x 3 map: a closed octahedron-like surface around it.
//! let mut map = [0u8; 27];
//! map[13] = 7;
//! let mt = labels::build("marching-tetrahedra", &Options::new()).unwrap().unwrap();
//! let mut out = LabelSurface::default();
//! mt.extract_u8(LabelMap::new([3, 3, 3], &map).unwrap(), &mut out).unwrap();
//! assert_eq!(out.labels(), [7]);
//! assert!(out.pairs.iter().all(|p| *p == [7, 0]));
//! // Every vertex is half a sample or less from the voxel's centre.
//! assert!(out.mesh.positions.iter().all(|p| (*p - glam::Vec3::ONE).abs().max_element() <= 0.5));
//! ```

use glam::DVec3;
use rustc_hash::FxHashMap;

use super::blocks::{LabelBlock, LabelFragment};
use super::{Border, Label, LabelExtractor, LabelExtractorInfo, LabelGuarantees, LabelMap, LabelSurface};
use crate::extract::ExtractError;
use crate::options::{OptionError, Options};

/// One line for listings.
pub const DESCRIPTION: &str =
    "Wu & Sullivan 2003 on Kuhn tetrahedra: edge midpoints, face and cell centres where three labels meet; every label closed and manifold";

/// Option names for [`from_options`].
pub const OPTION_NAMES: &[&str] = &["border"];

/// Multi-label marching tetrahedra.
pub const INFO: LabelExtractorInfo = LabelExtractorInfo {
    name: "marching-tetrahedra",
    description: DESCRIPTION,
    options: OPTION_NAMES,
    make: from_options,
    guarantees: LabelGuarantees { closed: true, manifold: true, outward: true, dihedral: None },
};

/// Builds multi-label marching tetrahedra from named options.
pub fn from_options(options: &Options) -> Result<Box<dyn LabelExtractor>, OptionError> {
    let mut r = options.reader(INFO.name, OPTION_NAMES);
    let border = r.choice("border", Border::Closed, &[("closed", Border::Closed), ("open", Border::Open)])?;
    r.finish()?;
    Ok(Box::new(LabelMarchingTetrahedra { border }))
}

/// Multi-label marching tetrahedra.
#[derive(Clone, Copy, Debug, Default)]
pub struct LabelMarchingTetrahedra {
    /// The map's border (default closed).
    pub border: Border,
}

impl LabelExtractor for LabelMarchingTetrahedra {
    fn info(&self) -> &'static LabelExtractorInfo {
        &INFO
    }
    fn extract_u8(&self, map: LabelMap<'_, u8>, out: &mut LabelSurface) -> Result<(), ExtractError> {
        extract(map, self.border, out)
    }
    fn extract_u16(&self, map: LabelMap<'_, u16>, out: &mut LabelSurface) -> Result<(), ExtractError> {
        extract(map, self.border, out)
    }
    fn extract_u32(&self, map: LabelMap<'_, u32>, out: &mut LabelSurface) -> Result<(), ExtractError> {
        extract(map, self.border, out)
    }
    fn apron(&self) -> usize {
        0
    }
    fn border(&self) -> Border {
        self.border
    }
    fn block_u8(&self, block: LabelBlock<'_, u8>, out: &mut LabelFragment) -> Result<(), ExtractError> {
        extract_block(&block, out);
        Ok(())
    }
    fn block_u16(&self, block: LabelBlock<'_, u16>, out: &mut LabelFragment) -> Result<(), ExtractError> {
        extract_block(&block, out);
        Ok(())
    }
    fn block_u32(&self, block: LabelBlock<'_, u32>, out: &mut LabelFragment) -> Result<(), ExtractError> {
        extract_block(&block, out);
        Ok(())
    }
}

/// The six Kuhn tetrahedra of a cube as corner indices (corner `i` at offset bits `i`): the paths
/// from corner 0 to corner 7 through one axis, then two.
const KUHN: [[u8; 4]; 6] = [[0, 1, 3, 7], [0, 1, 5, 7], [0, 2, 3, 7], [0, 2, 6, 7], [0, 4, 5, 7], [0, 4, 6, 7]];

/// The four faces of a tetrahedron (corner slots), each with the slot opposite.
const TET_FACES: [([usize; 3], usize); 4] = [([1, 2, 3], 0), ([0, 2, 3], 1), ([0, 1, 3], 2), ([0, 1, 2], 3)];

/// A point of the output, named by what it is the centre of (so neighbours name it alike).
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
enum Key {
    /// Midpoint of the edge between two samples (padded indices, smaller first).
    Edge(u64, u64),
    /// Centroid of a triangle of three samples (sorted).
    Face(u64, u64, u64),
    /// Centroid of tetrahedron `t` of the cube at padded sample `c`.
    Tet(u64, u8),
}

/// A segment on a tetrahedron's face where two labels meet: its two points and the crossing edge
/// (tetrahedron slots) whose corners it separates.
#[derive(Clone, Copy)]
struct Segment {
    ends: [Point; 2],
    edge: (usize, usize),
}

/// A point before it has an index: its key and position.
#[derive(Clone, Copy)]
struct Point {
    key: Key,
    at: DVec3,
}

struct Builder<'s> {
    index: FxHashMap<Key, u32>,
    out: &'s mut LabelSurface,
    /// Each vertex's key, when a block's fragment is made.
    keys: Option<&'s mut Vec<Key>>,
}

impl Builder<'_> {
    fn vertex(&mut self, p: Point) -> u32 {
        let positions = &mut self.out.mesh.positions;
        let keys = &mut self.keys;
        *self.index.entry(p.key).or_insert_with(|| {
            positions.push((p.at - DVec3::ONE).as_vec3());
            if let Some(keys) = keys {
                keys.push(p.key);
            }
            (positions.len() - 1) as u32
        })
    }

    /// Emits the triangle `tri`, separating the corners at `from` (label `a`) and `to` (label `b`),
    /// wound so that its normal points from the larger label's corner to the other's.
    fn triangle(&mut self, tri: [Point; 3], (from, a): (DVec3, u32), (to, b): (DVec3, u32)) {
        let n = (tri[1].at - tri[0].at).cross(tri[2].at - tri[0].at);
        let toward = if a > b { to - from } else { from - to };
        let v = tri.map(|p| self.vertex(p));
        self.out.mesh.triangles.push(if n.dot(toward) > 0.0 { v } else { [v[0], v[2], v[1]] });
        self.out.pairs.push([a.max(b), a.min(b)]);
    }
}

fn extract<T: Label>(map: LabelMap<'_, T>, border: Border, out: &mut LabelSurface) -> Result<(), ExtractError> {
    out.clear();
    let whole = LabelBlock {
        samples: map.labels,
        window_lo: [0; 3],
        window_dims: map.dims,
        map_dims: map.dims,
        cells: map.dims.map(|n| match border {
            Border::Closed => 0..n + 1,
            Border::Open => 1..n.max(1),
        }),
        apron: 0,
    };
    mesh_cells(&whole, &mut Builder { index: FxHashMap::default(), out, keys: None });
    Ok(())
}

/// Block `block`'s fragment: its cells' triangles, each vertex keyed by the samples it is the
/// centre of.
fn extract_block<T: Label>(block: &LabelBlock<'_, T>, out: &mut LabelFragment) {
    let mut keys = Vec::new();
    mesh_cells(block, &mut Builder { index: FxHashMap::default(), out: &mut out.surface, keys: Some(&mut keys) });
    let p = block.map_dims.map(|n| n as u64 + 2);
    out.keys = keys.into_iter().map(|k| weld_key(k, p)).collect();
}

/// A vertex key as an integer: the first sample's index, and what it is the centre of (the
/// other samples as corner offsets from the first, which are 0 or 1 along each axis).
fn weld_key(key: Key, p: [u64; 3]) -> u128 {
    let offset = |from: u64, to: u64| -> u64 {
        let d = to - from;
        let z = d / (p[0] * p[1]);
        let y = (d - z * p[0] * p[1]) / p[0];
        let x = d - z * p[0] * p[1] - y * p[0];
        x | y << 1 | z << 2
    };
    let (first, tag) = match key {
        Key::Edge(a, b) => (a, 1 << 8 | offset(a, b)),
        Key::Face(a, b, c) => (a, 2 << 8 | offset(a, b) << 3 | offset(a, c)),
        Key::Tet(cube, t) => (cube, 3 << 8 | u64::from(t)),
    };
    u128::from(first) << 64 | u128::from(tag)
}

/// Every cell `block` owns.
fn mesh_cells<T: Label>(block: &LabelBlock<'_, T>, b: &mut Builder<'_>) {
    let p = block.map_dims.map(|n| n + 2);
    let [xs, ys, zs] = block.cells.clone();
    for z in zs {
        for y in ys.clone() {
            for x in xs.clone() {
                let corner = |i: u8| [x + (i & 1) as usize, y + (i >> 1 & 1) as usize, z + (i >> 2 & 1) as usize];
                let labels: [T; 8] = std::array::from_fn(|i| block.padded(corner(i as u8)));
                if labels.iter().all(|&l| l == labels[0]) {
                    continue;
                }
                b.out.active_cells += 1;
                let cube = (x + p[0] * (y + p[1] * z)) as u64;
                for (t, tet) in KUHN.iter().enumerate() {
                    let ids = tet.map(|i| {
                        let c = corner(i);
                        (c[0] + p[0] * (c[1] + p[1] * c[2])) as u64
                    });
                    let at = tet.map(|i| {
                        let c = corner(i);
                        DVec3::new(c[0] as f64, c[1] as f64, c[2] as f64)
                    });
                    let l = tet.map(|i| labels[i as usize].id());
                    mesh_tetrahedron(b, ids, at, l, Key::Tet(cube, t as u8));
                }
            }
        }
    }
}

/// One tetrahedron: corner sample ids, positions and labels.
fn mesh_tetrahedron(b: &mut Builder<'_>, ids: [u64; 4], at: [DVec3; 4], l: [u32; 4], centre: Key) {
    let distinct = {
        let mut d = l;
        d.sort_unstable();
        1 + d.windows(2).filter(|w| w[0] != w[1]).count()
    };
    if distinct == 1 {
        return;
    }
    let mid = |i: usize, j: usize| Point { key: Key::Edge(ids[i].min(ids[j]), ids[i].max(ids[j])), at: (at[i] + at[j]) * 0.5 };
    let corner = |i: usize| (at[i], l[i]);
    if distinct == 2 {
        let (ones, others): (Vec<usize>, Vec<usize>) = (0..4).partition(|&i| l[i] == l[0]);
        let (lone, rest) = if ones.len() == 1 {
            (ones, others)
        } else if others.len() == 1 {
            (others, ones)
        } else {
            // Two against two: the quad of the four crossing edges, a parallelogram.
            let (a, c) = (ones[0], ones[1]);
            let (bb, d) = (others[0], others[1]);
            let quad = [mid(a, bb), mid(a, d), mid(c, d), mid(c, bb)];
            b.triangle([quad[0], quad[1], quad[2]], corner(a), corner(bb));
            b.triangle([quad[0], quad[2], quad[3]], corner(a), corner(bb));
            return;
        };
        let i = lone[0];
        b.triangle([mid(i, rest[0]), mid(i, rest[1]), mid(i, rest[2])], corner(i), corner(rest[0]));
        return;
    }
    // Three or four labels: the cone from the centroid over the faces' segments.
    let apex = Point { key: centre, at: (at[0] + at[1] + at[2] + at[3]) * 0.25 };
    for (face, _) in TET_FACES {
        let (segments, n) = face_segments(face, &ids, &at, &l);
        for s in &segments[..n] {
            let (i, j) = s.edge;
            b.triangle([apex, s.ends[0], s.ends[1]], corner(i), corner(j));
        }
    }
}

/// The segments on one face (three tetrahedron slots) where its labels meet, and how many.
fn face_segments(face: [usize; 3], ids: &[u64; 4], at: &[DVec3; 4], l: &[u32; 4]) -> ([Segment; 3], usize) {
    let [i, j, k] = face;
    let mid = |a: usize, c: usize| Point { key: Key::Edge(ids[a].min(ids[c]), ids[a].max(ids[c])), at: (at[a] + at[c]) * 0.5 };
    let (li, lj, lk) = (l[i], l[j], l[k]);
    let none = Segment { ends: [mid(i, j); 2], edge: (i, j) };
    if li == lj && lj == lk {
        return ([none; 3], 0);
    }
    if li != lj && lj != lk && li != lk {
        let mut s = [ids[i], ids[j], ids[k]];
        s.sort_unstable();
        let centre = Point { key: Key::Face(s[0], s[1], s[2]), at: (at[i] + at[j] + at[k]) / 3.0 };
        return ([(i, j), (j, k), (k, i)].map(|(a, c)| Segment { ends: [centre, mid(a, c)], edge: (a, c) }), 3);
    }
    // Two labels: the lone corner's two edges.
    let lone = if lj == lk {
        i
    } else if li == lk {
        j
    } else {
        k
    };
    let [o0, o1] = match lone {
        _ if lone == i => [j, k],
        _ if lone == j => [i, k],
        _ => [i, j],
    };
    ([Segment { ends: [mid(lone, o0), mid(lone, o1)], edge: (lone, o0) }, none, none], 1)
}
