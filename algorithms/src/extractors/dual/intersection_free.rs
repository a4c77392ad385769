//! Intersection-free polygons for the dual engine, after T. Ju and T. Udeshi, "Intersection-free
//! contouring on an octree grid", Pacific Graphics 2006: every triangle is kept inside the cell
//! or the pair of face-neighbouring cells it belongs to, so triangles of different cells can meet
//! only on the faces they share.
//!
//! The engine's quad of a crossing edge joins the vertices of its four cells; split along a
//! diagonal, each of its two triangles spans three cells, and dual contouring's vertices, pulled
//! to features, fold such triangles through their neighbours'. Here the quad becomes a fan of
//! four triangles around the edge's crossing point (its *edge point*, kept a thin margin from
//! either sample). Each triangle joins the vertices of two cells that share a face, and the edge
//! point on that face. Both vertices lie strictly inside their cells and so project into the
//! square the cells share; the segment between them pierces that square inside, and the
//! triangle meets the face only in the segment from the edge point to the piercing point.
//!
//! Why it cannot cross: inside one cell the surface is then the cone from the cell's vertex over
//! a closed path on the cell's boundary (edge points joined through piercing points across the
//! faces). A ray from an interior point leaves a convex cell once, so a cone over a simple path
//! does not cross itself, and two cells' cones meet only on their shared face, along the path
//! they share. A cell with two or more pieces of surface (and the faces with four crossings,
//! whose cells always have two pieces on one side or the other) has a cone per piece; there each
//! side is broken at a *face point* instead, the middle of its chord across the face, kept in the
//! half of the face at the corner the chord cuts off when the face has two chords, so the two
//! chords' paths cannot meet and the cell's cones depend on its own vertices only. Those cones
//! are tested against each other with the exact predicate; where they cross (not seen in the
//! tests), the cell's vertices move to the centroids of their paths and are tested again, and a
//! crossing left is returned.

use crate::extract::ExtractError;
use crate::geometry::trilinear_gradient;
use crate::lattice::Grid;
use crate::mesh::{Incidence, TriMesh};
use crate::predicates::indexed_triangles_intersect;
use glam::Vec3;
use rayon::prelude::*;

/// How far inside its cell a cell vertex is kept, and inside its face region a piercing or face
/// point, as a fraction of the spacing: room for rounding, so every strict inequality the proof
/// needs holds in floating point.
pub(super) const MARGIN: f32 = 1e-3;

/// What the sweep keeps for [`triangulate`] (each quad's four sides in order, as the engine's
/// smoothing links, and each vertex's cell corner) and the pass's own buffers, kept between calls
/// so that re-meshing a chunk allocates nothing once they have grown.
#[derive(Default)]
pub(super) struct Scratch {
    sides: Vec<(u32, u32)>,
    cell_min: Vec<Vec3>,
    cells: Vec<[usize; 3]>,
    quads: Vec<Quad>,
    edge_points: Vec<Vec3>,
    /// Every quad side as (vertex pair key, `4 * quad + side`), sorted by key.
    keyed: Vec<(u64, u32)>,
    /// Runs of `keyed` with one key: the quads that share a side.
    groups: Vec<(u32, u32)>,
    face_points: Vec<Option<(Vec3, [u32; 4])>>,
    side_point: Vec<u32>,
    pieces: Vec<(u32, u32)>,
    incidence: Incidence,
}

impl Scratch {
    /// Takes the sweep's buffers (and gives it the ones it had before, to refill).
    pub(super) fn swap_with(&mut self, sides: &mut Vec<(u32, u32)>, cell_min: &mut Vec<Vec3>) {
        std::mem::swap(&mut self.sides, sides);
        std::mem::swap(&mut self.cell_min, cell_min);
    }

    /// Bytes held.
    pub(super) fn bytes(&self) -> usize {
        8 * self.sides.capacity()
            + 12 * (self.cell_min.capacity() + self.edge_points.capacity())
            + 24 * self.cells.capacity()
            + std::mem::size_of::<Quad>() * self.quads.capacity()
            + 16 * self.keyed.capacity()
            + 8 * (self.groups.capacity() + self.pieces.capacity())
            + std::mem::size_of::<Option<(Vec3, [u32; 4])>>() * self.face_points.capacity()
            + 4 * (self.side_point.capacity() + self.incidence.start.capacity() + self.incidence.items.capacity())
    }
}

/// The samples [`triangulate`] reads.
pub(super) struct Input<'a> {
    pub(super) values: &'a [f32],
    pub(super) grid: Grid,
    pub(super) iso: f32,
}

/// A lattice edge: its lower sample and its axis.
type Edge = ([usize; 3], usize);

/// A quad with its cycle wound outward and the lattice edge it crosses.
struct Quad {
    cycle: [u32; 4],
    edge: Edge,
}

impl Input<'_> {
    fn inside(&self, s: [usize; 3]) -> bool {
        self.values[self.grid.index(s[0], s[1], s[2])] < self.iso
    }

    fn crosses(&self, (s, axis): Edge) -> bool {
        self.inside(s) != self.inside(step(s, axis))
    }

    /// Where the surface crosses `edge` (linear interpolation, kept [`MARGIN`] from either end),
    /// with its other two coordinates exactly the lattice's.
    fn edge_point(&self, (s, axis): Edge) -> Vec3 {
        let g = &self.grid;
        let (v0, v1) = (self.values[g.index(s[0], s[1], s[2])], {
            let e = step(s, axis);
            self.values[g.index(e[0], e[1], e[2])]
        });
        let mut p = g.position(s[0], s[1], s[2]);
        // Strictly inside the edge: a sample at the iso-value would otherwise put the crossings
        // of all its edges on one point, as separate vertices that touch.
        p[axis] += ((self.iso - v0) / (v1 - v0)).clamp(MARGIN, 1.0 - MARGIN) * g.spacing;
        p
    }

    /// The unit normal at `p`: the gradient of the trilinear interpolant of the cell holding `p`,
    /// as the engine's vertex normals.
    fn normal_at(&self, p: Vec3) -> Vec3 {
        let g = &self.grid;
        let local = (p - g.origin) / g.spacing;
        let cell: [usize; 3] = std::array::from_fn(|k| (local[k].floor().max(0.0) as usize).min(g.dims[k] - 2));
        let [nx, ny, _] = g.dims;
        let i = g.index(cell[0], cell[1], cell[2]);
        let (sx, sxy) = (nx, nx * ny);
        let idx = [i, i + 1, i + 1 + sx, i + sx, i + sxy, i + 1 + sxy, i + 1 + sx + sxy, i + sx + sxy];
        let corner = Vec3::new(cell[0] as f32, cell[1] as f32, cell[2] as f32);
        trilinear_gradient(&crate::geometry::gather(self.values, &idx), local - corner).normalize_or_zero()
    }
}

/// `s` one sample along `axis`.
fn step(mut s: [usize; 3], axis: usize) -> [usize; 3] {
    s[axis] += 1;
    s
}

/// The cell whose lower corner is `min`.
fn cell_of(grid: &Grid, min: Vec3) -> [usize; 3] {
    let c = ((min - grid.origin) / grid.spacing).round();
    [c.x as usize, c.y as usize, c.z as usize]
}

/// The face two face-neighbouring cells share: its lower corner sample, its normal axis and the
/// two axes it spans.
#[derive(Clone, Copy)]
struct Face {
    corner: [usize; 3],
    normal: usize,
    span: [usize; 2],
}

impl Face {
    fn between(a: [usize; 3], b: [usize; 3]) -> Option<Face> {
        let normal = (0..3).find(|&k| a[k] != b[k])?;
        if a[normal].abs_diff(b[normal]) != 1 || (0..3).any(|k| k != normal && a[k] != b[k]) {
            return None;
        }
        let mut corner = a;
        corner[normal] = a[normal].max(b[normal]);
        let span = [(normal + 1) % 3, (normal + 2) % 3];
        let span = [span[0].min(span[1]), span[0].max(span[1])];
        Some(Face { corner, normal, span })
    }

    /// The face's four edges.
    fn edges(&self) -> [Edge; 4] {
        let [c, d] = self.span;
        [(self.corner, c), (step(self.corner, d), c), (self.corner, d), (step(self.corner, c), d)]
    }

    /// The face corners (in face coordinates, 0 or 1 along each spanned axis) that `edge` joins.
    fn corners_of(&self, (s, axis): Edge) -> [(u8, u8); 2] {
        let [c, d] = self.span;
        let at = |k: usize| (s[k] - self.corner[k]) as u8;
        if axis == c {
            [(0, at(d)), (1, at(d))]
        } else {
            [(at(c), 0), (at(c), 1)]
        }
    }

    /// `p` in face coordinates (units of the spacing from the face's lower corner).
    fn local(&self, grid: &Grid, p: Vec3) -> (f32, f32) {
        let o = grid.position(self.corner[0], self.corner[1], self.corner[2]);
        let [c, d] = self.span;
        ((p[c] - o[c]) / grid.spacing, (p[d] - o[d]) / grid.spacing)
    }

    /// The point at face coordinates `(s, t)`, exactly on the face's plane.
    fn point(&self, grid: &Grid, (s, t): (f32, f32)) -> Vec3 {
        let mut p = grid.position(self.corner[0], self.corner[1], self.corner[2]);
        let [c, d] = self.span;
        p[c] += s * grid.spacing;
        p[d] += t * grid.spacing;
        p
    }
}

/// Where on a face one piece's path may run: the face, or the half of it at a corner (face
/// coordinates) that the piece cuts off from the other three.
#[derive(Clone, Copy)]
pub(super) struct Region {
    pub(super) corner: Option<(u8, u8)>,
}

impl Region {
    fn contains(&self, (s, t): (f32, f32), margin: f32) -> bool {
        let in_face = (margin..=1.0 - margin).contains(&s) && (margin..=1.0 - margin).contains(&t);
        in_face && self.corner.is_none_or(|(kx, ky)| (s - f32::from(kx)).abs() + (t - f32::from(ky)).abs() <= 1.0 - margin)
    }

    /// A point well inside the region.
    fn centre(&self) -> (f32, f32) {
        let quarter = |k: u8| if k == 0 { 0.25 } else { 0.75 };
        self.corner.map_or((0.5, 0.5), |(kx, ky)| (quarter(kx), quarter(ky)))
    }

    /// `p` if it lies inside with twice the margin, else the farthest point toward it from the
    /// centre that does (the region is convex).
    pub(super) fn clamp(&self, p: (f32, f32)) -> (f32, f32) {
        let margin = 2.0 * MARGIN;
        if self.contains(p, margin) {
            return p;
        }
        let c = self.centre();
        let at = |l: f32| (c.0 + l * (p.0 - c.0), c.1 + l * (p.1 - c.1));
        let (mut lo, mut hi) = (0.0f32, 1.0f32);
        for _ in 0..24 {
            let mid = 0.5 * (lo + hi);
            if self.contains(at(mid), margin) {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        at(lo)
    }
}

/// No face point: the side is kept whole.
const WHOLE: u32 = u32::MAX;

/// Ordinals of the added vertices among their owner sample's vertices in [`crate::Origins`]
/// (cell vertices count from 0, one per piece): an edge point is owned by its edge's lower
/// sample, `EDGE_ORDINAL + axis`; a face point by its face's lower corner, `FACE_ORDINAL + 5 *
/// normal axis + corner` (corner 0 for a face with one chord, else 1 + the corner its chord cuts
/// off), so every added vertex has a lattice key and chunks weld them.
const EDGE_ORDINAL: u32 = 16;
const FACE_ORDINAL: u32 = 32;

/// Replaces the engine's quads in `mesh` (two triangles per quad, in the order of the scratch's
/// sides) by fans that keep each triangle in its cells, adding an edge point per quad and a face
/// point per side of a cell with several pieces, and their origins when `origins` holds one per
/// cell vertex. Returns the cells whose pieces' cones still cross after the fallback (none has
/// been seen; the tests hold it at none).
pub(super) fn triangulate(
    input: &Input,
    scratch: &mut Scratch,
    mesh: &mut TriMesh,
    origins: Option<&mut Vec<[u32; 4]>>,
    name: &'static str,
) -> Result<usize, ExtractError> {
    let grid = input.grid;
    let h = grid.spacing;
    let Scratch { sides, cell_min, cells, quads, edge_points, keyed, groups, face_points, side_point, pieces, incidence } =
        scratch;
    let n = sides.len() / 4;
    debug_assert_eq!(mesh.triangles.len(), 2 * n, "two triangles per quad");
    debug_assert_eq!(cell_min.len(), mesh.positions.len(), "a cell per vertex");
    // Vertex indices, and the side slots `4 * quad + side`, fit in 32 bits.
    if mesh.positions.len() + 3 * n >= u32::MAX as usize / 2 || 4 * n >= u32::MAX as usize {
        return Err(ExtractError::TooLarge { algorithm: name, vertices: mesh.positions.len() + 3 * n });
    }
    cells.clear();
    cells.par_extend(cell_min.par_iter().map(|&m| cell_of(&grid, m)));
    // Every cell vertex strictly inside its cell.
    for (p, &m) in mesh.positions.iter_mut().zip(cell_min.iter()) {
        *p = p.clamp(m + Vec3::splat(MARGIN * h), m + Vec3::splat((1.0 - MARGIN) * h));
    }
    let cells = &*cells;
    // A cell's vertices are consecutive: a vertex shares its cell when a neighbour in the list does.
    let shares_cell = |v: usize| (v > 0 && cells[v - 1] == cells[v]) || (v + 1 < cells.len() && cells[v + 1] == cells[v]);
    let (sides, triangles) = (&*sides, &mesh.triangles);
    quads.clear();
    quads.par_extend((0..n).into_par_iter().map(|k| {
        let c = [0, 1, 2, 3].map(|i| sides[4 * k + i].0);
        let t = triangles[2 * k];
        let i = c.iter().position(|&v| v == t[0]).unwrap_or(0);
        let cycle = if c[(i + 1) % 4] == t[1] { c } else { [c[0], c[3], c[2], c[1]] };
        let cs = c.map(|v| cells[v as usize]);
        let axis = (0..3).find(|&a| cs.iter().all(|x| x[a] == cs[0][a])).unwrap_or(0);
        let start = std::array::from_fn(|b| cs.iter().map(|x| x[b]).max().unwrap_or(0));
        Quad { cycle, edge: (start, axis) }
    }));
    let quads = &*quads;
    edge_points.clear();
    edge_points.par_extend(quads.par_iter().map(|q| input.edge_point(q.edge)));

    // Each side (u, w) with the quads that have it: one or two (two faces' chords never share
    // both cells' pieces in the engine's manifold output; more would be broken at face points).
    keyed.clear();
    keyed.par_extend((0..4 * n).into_par_iter().map(|j| {
        let c = quads[j / 4].cycle;
        let (u, w) = (c[j % 4], c[(j % 4 + 1) % 4]);
        ((u64::from(u.min(w)) << 32) | u64::from(u.max(w)), j as u32)
    }));
    keyed.par_sort_unstable();
    groups.clear();
    let mut start = 0;
    for j in 1..=keyed.len() {
        if j == keyed.len() || keyed[j].0 != keyed[start].0 {
            groups.push((start as u32, j as u32));
            start = j;
        }
    }
    let (keyed, edge_points) = (&*keyed, &*edge_points);
    face_points.clear();
    face_points.par_extend(groups.par_iter().map(|&(lo, hi)| {
        let group = &keyed[lo as usize..hi as usize];
        let slot = |e: &(u64, u32)| (e.1 as usize / 4, e.1 as usize % 4);
        let (k1, i1) = slot(&group[0]);
        let c = quads[k1].cycle;
        let (u, w) = (c[i1] as usize, c[(i1 + 1) % 4] as usize);
        // A side between two single-piece cells is kept whole: both vertices project into the
        // square the cells share, so the segment pierces it inside.
        if group.len() <= 2 && !shares_cell(u) && !shares_cell(w) {
            return None;
        }
        let face = Face::between(cells[u], cells[w])?;
        let e1 = quads[k1].edge;
        let e2 = match *group {
            [_, second] => Some(quads[slot(&second).0].edge),
            [_] => other_end(input, &face, e1),
            _ => None,
        };
        let four_crossings = face.edges().iter().filter(|&&e| input.crosses(e)).count() == 4;
        let corner = e2.filter(|_| four_crossings).and_then(|e2| {
            let other = face.corners_of(e2);
            face.corners_of(e1).into_iter().find(|k| other.contains(k))
        });
        let (p1, p2) = (edge_points[k1], e2.map_or(edge_points[k1], |e2| input.edge_point(e2)));
        let point = face.point(&grid, Region { corner }.clamp(face.local(&grid, 0.5 * (p1 + p2))));
        let ordinal = FACE_ORDINAL + 5 * face.normal as u32 + corner.map_or(0, |(kx, ky)| 1 + u32::from(kx + 2 * ky));
        let [x, y, z] = face.corner.map(|c| c as u32);
        Some((point, [x, y, z, ordinal]))
    }));

    // New vertices: the edge points, then the face points.
    let first_edge_point = mesh.positions.len();
    let first_face_point = first_edge_point + n;
    side_point.clear();
    side_point.resize(4 * n, WHOLE);
    let mut extra = 0u32;
    for (&(lo, hi), point) in groups.iter().zip(face_points.iter()) {
        if point.is_some() {
            for e in &keyed[lo as usize..hi as usize] {
                side_point[e.1 as usize] = first_face_point as u32 + extra;
            }
            extra += 1;
        }
    }
    let has_normals = mesh.normals.len() == mesh.positions.len();
    mesh.positions.extend_from_slice(edge_points);
    mesh.positions.extend(face_points.iter().flatten().map(|f| f.0));
    if has_normals {
        let (positions, normals) = (&mesh.positions, &mut mesh.normals);
        normals.par_extend(positions[first_edge_point..].par_iter().map(|&p| input.normal_at(p)));
    }
    if let Some(origins) = origins {
        if origins.len() == first_edge_point {
            origins.extend(quads.iter().map(|q| {
                let [x, y, z] = q.edge.0.map(|c| c as u32);
                [x, y, z, EDGE_ORDINAL + q.edge.1 as u32]
            }));
            origins.extend(face_points.iter().flatten().map(|f| f.1));
        }
    }
    mesh.triangles.clear();
    for (k, q) in quads.iter().enumerate() {
        let centre = (first_edge_point + k) as u32;
        for i in 0..4 {
            let (a, b) = (q.cycle[i], q.cycle[(i + 1) % 4]);
            match side_point[4 * k + i] {
                WHOLE => mesh.triangles.push([a, b, centre]),
                f => mesh.triangles.extend([[a, f, centre], [f, b, centre]]),
            }
        }
    }
    Ok(separate_pieces(input, mesh, cells, pieces, incidence, has_normals))
}

/// The other end of the chord from `e1` across `face` when no second quad names it: the face's
/// other crossing edge, or on a face with four, the neighbouring one on the domain boundary
/// (where an edge has no quad).
fn other_end(input: &Input, face: &Face, e1: Edge) -> Option<Edge> {
    let crossing = face.edges().map(|e| (e != e1 && input.crosses(e)).then_some(e));
    if crossing.iter().flatten().count() == 1 {
        return crossing.into_iter().flatten().next();
    }
    let corners = face.corners_of(e1);
    let dims = input.grid.dims;
    let on_boundary = |(s, axis): Edge| (0..3).any(|k| k != axis && (s[k] == 0 || s[k] + 1 == dims[k]));
    crossing.into_iter().flatten().filter(|&e| face.corners_of(e).iter().any(|k| corners.contains(k))).find(|&e| on_boundary(e))
}

/// Tests the cones of every cell with several pieces against each other with the exact
/// predicate and moves the vertices of cells whose cones cross to the centroids of their paths;
/// returns the cells still crossing.
fn separate_pieces(
    input: &Input,
    mesh: &mut TriMesh,
    cells: &[[usize; 3]],
    pieces: &mut Vec<(u32, u32)>,
    incidence: &mut Incidence,
    has_normals: bool,
) -> usize {
    let h = input.grid.spacing;
    let cell_box = |v: usize| {
        let min = input.grid.origin + Vec3::from(cells[v].map(|c| c as f32)) * h;
        (min + Vec3::splat(MARGIN * h), min + Vec3::splat((1.0 - MARGIN) * h))
    };
    let moved = |mesh: &mut TriMesh, v: usize| {
        if has_normals {
            mesh.normals[v] = input.normal_at(mesh.positions[v]);
        }
    };
    separate_cell_pieces(mesh, cells, cell_box, pieces, incidence, moved)
}

/// [`separate_pieces`] for any cells: `cells[v]` names vertex `v`'s cell (a cell's vertices are
/// consecutive), `cell_box(v)` the box its vertex must stay in, and `moved` hears of each vertex
/// moved. Returns the cells still crossing.
pub(super) fn separate_cell_pieces<C: PartialEq>(
    mesh: &mut TriMesh,
    cells: &[C],
    cell_box: impl Fn(usize) -> (Vec3, Vec3),
    pieces: &mut Vec<(u32, u32)>,
    incidence: &mut Incidence,
    mut moved: impl FnMut(&mut TriMesh, usize),
) -> usize {
    pieces.clear();
    let mut start = 0;
    for v in 1..=cells.len() {
        if v == cells.len() || cells[v] != cells[start] {
            if v - start > 1 {
                pieces.push((start as u32, v as u32));
            }
            start = v;
        }
    }
    if pieces.is_empty() {
        return 0;
    }
    incidence.rebuild(mesh.positions.len(), &mesh.triangles);
    let incidence = &*incidence;
    let crossing = |mesh: &TriMesh, (lo, hi): (u32, u32)| {
        let at = |v: u32| mesh.positions[v as usize];
        (lo..hi).any(|a| {
            (a + 1..hi).any(|b| {
                incidence.of_vertex(a).iter().any(|&ta| {
                    incidence
                        .of_vertex(b)
                        .iter()
                        .any(|&tb| indexed_triangles_intersect(mesh.triangles[ta as usize], mesh.triangles[tb as usize], at))
                })
            })
        })
    };
    let mut unresolved = 0;
    for &(lo, hi) in pieces.iter() {
        if !crossing(mesh, (lo, hi)) {
            continue;
        }
        for v in lo..hi {
            let ring = incidence.of_vertex(v);
            let (sum, count) = ring
                .iter()
                .flat_map(|&t| mesh.triangles[t as usize])
                .filter(|&x| x != v)
                .fold((Vec3::ZERO, 0.0f32), |(s, c), x| (s + mesh.positions[x as usize], c + 1.0));
            if count > 0.0 {
                let (min, max) = cell_box(v as usize);
                mesh.positions[v as usize] = (sum / count).clamp(min, max);
                moved(mesh, v as usize);
            }
        }
        if crossing(mesh, (lo, hi)) {
            unresolved += 1;
        }
    }
    unresolved
}
