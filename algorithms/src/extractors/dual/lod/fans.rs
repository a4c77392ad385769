//! Intersection-free polygons on the octree seams: manifold dual contouring's levels of detail.
//! Ju and Udeshi's construction ("Intersection-free contouring on an octree grid", Pacific
//! Graphics 2006), which [`super::super::intersection_free`] runs on one level, carried to
//! chunks of mixed levels.
//!
//! Each minimal edge's polygon (module doc of [`super`]) becomes a fan around the edge's crossing
//! point (its *edge point*, a thin margin from either end), one or two triangles per side of the
//! polygon. A side joins the vertices of two cells that share a face containing the edge; when
//! the cells are of one size and each has one piece of surface, both vertices project into the
//! face and the side's triangle stays in the two cells, as on one level. When one cell is coarser,
//! the face they share is the finer cell's, and the coarse vertex need not project into it, so
//! the side is always broken at a *face point* inside that fine face: the middle of the chord the
//! surface draws across it (its two edge points), kept in the half of the face at the corner the
//! chord cuts off when the face has two chords. Sides of cells with several pieces, and sides
//! shared by more than two polygons (where a piece passes twice through one face, the spot the
//! plain levels `pinch`), are broken the same way, one face point per chord, so no edge between
//! two cell vertices is left for four triangles to share.
//!
//! Each triangle then lies in one cell and a face of it, and inside a cell the surface is the cone
//! from the cell's vertex over a closed path on the cell's boundary (edge points joined through
//! piercing or face points). On a coarse cell's face toward a finer chunk the path runs through
//! the fine faces, each crossed by at most one chord: the restriction makes the coarse face's
//! samples bilinear with an ambiguous face's centre outside, so a fine quarter of it never has
//! four crossings. A cone over a simple path from a point inside a convex cell does not cross
//! itself, and cones of two cells meet only on their common face. Cells with several pieces have
//! a cone per piece, tested against each other with the exact predicate as on one level.

use super::super::intersection_free::{separate_cell_pieces, Region, MARGIN};
use super::Lod;
use crate::mesh::{Incidence, TriMesh};
use glam::Vec3;
use rayon::prelude::*;

/// A minimal edge: its lower sample, its axis and its length in samples.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct MinimalEdge {
    pub(super) start: [usize; 3],
    pub(super) axis: usize,
    pub(super) len: usize,
}

impl MinimalEdge {
    fn end(&self) -> [usize; 3] {
        let mut e = self.start;
        e[self.axis] += self.len;
        e
    }

    /// Whether `self` lies on `whole` (same line, within its ends).
    fn lies_on(&self, whole: &MinimalEdge) -> bool {
        self.axis == whole.axis
            && (0..3).all(|d| d == self.axis || self.start[d] == whole.start[d])
            && whole.start[self.axis] <= self.start[self.axis]
            && self.end()[self.axis] <= whole.end()[self.axis]
    }
}

/// A polygon around a minimal edge: its distinct cell vertices in winding order (`n` of them,
/// 3 or 4), the edge, and the level of the chunk that owns it.
#[derive(Clone, Copy, Debug)]
pub(super) struct FanPolygon {
    pub(super) ring: [u32; 4],
    pub(super) n: u8,
    pub(super) edge: MinimalEdge,
    pub(super) level: u8,
}

/// The face two face-neighbouring cells share (the smaller cell's face): its lower corner, side,
/// normal axis and the two axes it spans (increasing).
#[derive(Clone, Copy)]
struct Face {
    corner: [usize; 3],
    side: usize,
    span: [usize; 2],
}

impl Face {
    /// The face cells `(a, side_a)` and `(b, side_b)` share, if they touch across one.
    fn between((a, sa): ([usize; 3], usize), (b, sb): ([usize; 3], usize)) -> Option<Face> {
        let ((small, ss), (large, sl)) = if sa <= sb { ((a, sa), (b, sb)) } else { ((b, sb), (a, sa)) };
        let normal = (0..3).find(|&d| small[d] + ss == large[d] || large[d] + sl == small[d])?;
        let overlaps = |d: usize| large[d] <= small[d] && small[d] + ss <= large[d] + sl;
        if !(0..3).filter(|&d| d != normal).all(overlaps) {
            return None;
        }
        let mut corner = small;
        if small[normal] + ss == large[normal] {
            corner[normal] += ss;
        }
        let span = [(normal + 1) % 3, (normal + 2) % 3];
        Some(Face { corner, side: ss, span: [span[0].min(span[1]), span[0].max(span[1])] })
    }

    fn offset(&self, axis: usize) -> [usize; 3] {
        let mut p = self.corner;
        p[axis] += self.side;
        p
    }

    /// The face's four edges.
    fn edges(&self) -> [MinimalEdge; 4] {
        let [c, d] = self.span;
        let edge = |start, axis| MinimalEdge { start, axis, len: self.side };
        [edge(self.corner, c), edge(self.offset(d), c), edge(self.corner, d), edge(self.offset(c), d)]
    }

    /// The face corners (0 or 1 along each spanned axis) that face edge `k` joins.
    fn corners_of(k: usize) -> [(u8, u8); 2] {
        [[(0, 0), (1, 0)], [(0, 1), (1, 1)], [(0, 0), (0, 1)], [(1, 0), (1, 1)]][k]
    }

    /// The sample at face corner `(s, t)`.
    fn corner_sample(&self, (s, t): (u8, u8)) -> [usize; 3] {
        let mut p = self.corner;
        p[self.span[0]] += usize::from(s) * self.side;
        p[self.span[1]] += usize::from(t) * self.side;
        p
    }

    fn local(&self, p: Vec3) -> (f32, f32) {
        let [c, d] = self.span;
        let side = self.side as f32;
        ((p[c] - self.corner[c] as f32) / side, (p[d] - self.corner[d] as f32) / side)
    }

    fn point(&self, (s, t): (f32, f32)) -> Vec3 {
        let mut p = Vec3::from(self.corner.map(|c| c as f32));
        p[self.span[0]] += s * self.side as f32;
        p[self.span[1]] += t * self.side as f32;
        p
    }
}

/// A side's face point, if it has one: the point and its chord (a key among the side's chords).
type FacePoint = Option<(Vec3, usize)>;

/// No face point: the side is kept whole.
const WHOLE: u32 = u32::MAX;

impl Lod<'_> {
    /// Where the surface crosses `e` (linear, kept [`MARGIN`] from either end), in samples.
    fn edge_point(&self, e: &MinimalEdge) -> Vec3 {
        let (v0, v1) = (self.value(e.start), self.value(e.end()));
        let mut p = Vec3::from(e.start.map(|c| c as f32));
        p[e.axis] += ((self.g.iso - v0) / (v1 - v0)).clamp(MARGIN, 1.0 - MARGIN) * e.len as f32;
        p
    }

    fn crosses(&self, e: &MinimalEdge) -> bool {
        self.inside(e.start) != self.inside(e.end())
    }
}

/// The face point of each chord across the face of cells `(corner, side)` `cells`, for the
/// polygons sharing one side `(u, w)` that is to be broken: `members` are their slots
/// `(polygon, side)`; returns each member's point (none where the cells share no face).
fn side_points(
    lod: &Lod,
    polygons: &[FanPolygon],
    edge_points: &[Vec3],
    members: &[(usize, usize)],
    cells: ([usize; 3], usize, [usize; 3], usize),
) -> Vec<FacePoint> {
    let (cu, su, cw, sw) = cells;
    let Some(face) = Face::between((cu, su), (cw, sw)) else { return vec![None; members.len()] };
    let edges = face.edges();
    let face_edge = |e: &MinimalEdge| edges.iter().position(|f| e.lies_on(f));
    let own: Vec<Option<usize>> = members.iter().map(|&(j, _)| face_edge(&polygons[j].edge)).collect();
    let inside_corner = |k: (u8, u8)| lod.inside(face.corner_sample(k));
    let four_crossings = edges.iter().all(|e| lod.crosses(e));
    // Two polygons sharing the side are one chord's two ends. Otherwise two face edges are one
    // chord's ends when they are its only crossings, or on a face with four when they meet at an
    // inside corner (a side more than two polygons share is on a seam, where the restriction
    // keeps inside corners apart).
    let common = |a: usize, b: usize| Face::corners_of(a).into_iter().find(|k| Face::corners_of(b).contains(k));
    let pair = |a: usize, b: usize| a != b && (members.len() == 2 || !four_crossings || common(a, b).is_some_and(inside_corner));
    members
        .iter()
        .enumerate()
        .map(|(m, &(j, _))| {
            let a = own[m]?;
            let partner = (0..members.len()).find(|&o| o != m && own[o].is_some_and(|b| pair(a, b)));
            let (b, other_point) = match partner {
                Some(o) => (own[o]?, edge_points[members[o].0]),
                None => {
                    let b = (0..4).find(|&b| lod.crosses(&edges[b]) && pair(a, b))?;
                    (b, lod.edge_point(&edges[b]))
                }
            };
            let corner = if four_crossings { common(a, b) } else { None };
            let mid = face.local(0.5 * (edge_points[j] + other_point));
            // Chords are told apart by their face edges, so both ends name one point.
            Some((face.point(Region { corner }.clamp(mid)), a.min(b) * 4 + a.max(b)))
        })
        .collect()
}

/// Replaces the polygons by fans (module doc): adds an edge point per polygon and a face point per
/// chord that needs one to `mesh` (in sample coordinates, each cell vertex first kept a margin
/// inside its cell), with their cells' corners in `corners` (for normals), and writes the
/// triangles and their levels. Returns the cells whose pieces' cones still cross.
pub(super) fn triangulate(
    lod: &Lod,
    polygons: &[FanPolygon],
    mesh: &mut TriMesh,
    corners: &mut Vec<[u32; 3]>,
    side_of: impl Fn([u32; 3]) -> u32 + Sync,
    levels: &mut Vec<u8>,
) -> usize {
    let cell_vertices = mesh.positions.len();
    corners.truncate(cell_vertices);
    let cell_corners = corners.clone();
    let cell_box = |v: usize| {
        let (lo, side) = (Vec3::from(cell_corners[v].map(|c| c as f32)), side_of(cell_corners[v]) as f32);
        (lo + Vec3::splat(MARGIN * side), lo + Vec3::splat((1.0 - MARGIN) * side))
    };
    for v in 0..cell_vertices {
        let (lo, hi) = cell_box(v);
        mesh.positions[v] = mesh.positions[v].clamp(lo, hi);
    }
    let shares_cell = |v: usize| {
        (v > 0 && cell_corners[v - 1] == cell_corners[v]) || (v + 1 < cell_vertices && cell_corners[v + 1] == cell_corners[v])
    };
    let edge_points: Vec<Vec3> = polygons.par_iter().map(|p| lod.edge_point(&p.edge)).collect();
    let side = |j: usize, i: usize| {
        let p = &polygons[j];
        (p.ring[i], p.ring[(i + 1) % p.n as usize])
    };
    let mut keyed: Vec<(u64, u32)> = polygons
        .par_iter()
        .enumerate()
        .flat_map_iter(|(j, p)| {
            (0..p.n as usize).map(move |i| {
                let (u, w) = side(j, i);
                ((u64::from(u.min(w)) << 32) | u64::from(u.max(w)), (4 * j + i) as u32)
            })
        })
        .collect();
    keyed.par_sort_unstable();
    let mut groups = Vec::new();
    let mut start = 0;
    for j in 1..=keyed.len() {
        if j == keyed.len() || keyed[j].0 != keyed[start].0 {
            groups.push(start..j);
            start = j;
        }
    }
    let cell = |v: u32| {
        let c = cell_corners[v as usize];
        (c.map(|x| x as usize), side_of(c) as usize)
    };
    // `None` for a side kept whole (the common case, decided before anything is gathered): both
    // cells of one size, each with one piece, and at most two polygons on the side.
    let points: Vec<Option<Vec<FacePoint>>> = groups
        .par_iter()
        .map(|range| {
            let first = keyed[range.start].1 as usize;
            let (u, w) = side(first / 4, first % 4);
            let ((cu, su), (cw, sw)) = (cell(u), cell(w));
            let several = shares_cell(u as usize) || shares_cell(w as usize);
            if su == sw && !several && range.len() <= 2 {
                return None;
            }
            let members: Vec<(usize, usize)> =
                keyed[range.clone()].iter().map(|&(_, s)| (s as usize / 4, s as usize % 4)).collect();
            Some(side_points(lod, polygons, &edge_points, &members, (cu, su, cw, sw)))
        })
        .collect();
    // New vertices: the edge points, then one face point per chord.
    let first_edge_point = mesh.positions.len() as u32;
    mesh.positions.extend_from_slice(&edge_points);
    corners.extend(polygons.iter().map(|p| cell_corners[p.ring[0] as usize]));
    let mut side_point = vec![WHOLE; 4 * polygons.len()];
    for (range, points) in groups.iter().zip(&points) {
        let Some(points) = points else { continue };
        let mut chords: Vec<(usize, u32)> = Vec::new();
        for (&(_, slot), point) in keyed[range.clone()].iter().zip(points) {
            let Some((p, chord)) = *point else { continue };
            let index = match chords.iter().find(|c| c.0 == chord) {
                Some(&(_, index)) => index,
                None => {
                    let index = mesh.positions.len() as u32;
                    mesh.positions.push(p);
                    let (u, _) = side(slot as usize / 4, slot as usize % 4);
                    corners.push(cell_corners[u as usize]);
                    chords.push((chord, index));
                    index
                }
            };
            side_point[slot as usize] = index;
        }
    }
    mesh.triangles.clear();
    levels.clear();
    for (j, p) in polygons.iter().enumerate() {
        let centre = first_edge_point + j as u32;
        let before = mesh.triangles.len();
        for i in 0..p.n as usize {
            let (a, b) = side(j, i);
            match side_point[4 * j + i] {
                WHOLE => mesh.triangles.push([a, b, centre]),
                f => mesh.triangles.extend([[a, f, centre], [f, b, centre]]),
            }
        }
        levels.extend(std::iter::repeat_n(p.level, mesh.triangles.len() - before));
    }
    let (mut pieces, mut incidence) = (Vec::new(), Incidence::default());
    separate_cell_pieces(mesh, &cell_corners, cell_box, &mut pieces, &mut incidence, |_, _| {})
}
