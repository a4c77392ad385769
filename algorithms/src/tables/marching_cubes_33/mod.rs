//! Marching cubes 33: the cell tables that give each cell the topology of the trilinear
//! interpolant's level set (Chernyaev 1995, "Marching cubes 33: construction of topologically
//! correct isosurfaces", CERN CN/95-17; Lewiner, Lopes, Vieira and Tavares 2003, "Efficient
//! implementation of marching cubes' cases with topological guarantees", DOI
//! 10.1080/10867651.2003.10487582; Custodio, Etiene, Pesco and Silva 2013, "Practical
//! considerations on Marching Cubes 33 topological correctness", DOI 10.1016/j.cag.2013.04.004).
//!
//! ## Origin
//! **Generated, not copied**, from two facts about a trilinear function on a cube:
//! - On each face it is bilinear, and the asymptotic decider tells exactly whether the face's
//!   diagonal corners of one sign are joined ([`super::marching_cubes::decider_joins_inside`]). The
//!   six decisions give the polygons on the cube's boundary (the face-choice tables of
//!   [`super::marching_cubes::FACE_CHOICE_TABLE`]).
//! - Inside, two regions of one sign that the boundary keeps apart may still be joined through
//!   the cell: a **tunnel**, the interior ambiguity of Chernyaev's cases 4, 6, 7, 10, 12 and 13.
//!   [`interior_components`] decides it exactly. Every horizontal slice of the cube is a bilinear
//!   square, each of whose regions of one sign holds a point of a vertical edge (a bilinear
//!   function has its extremes at corners); so two vertical edges are joined through the cell
//!   exactly when, at some height where both have the sign, they are side by side, or diagonal
//!   with the slice's saddle on their side: a quadratic in the height, `a c - b d > 0`, maximised
//!   over an interval. Lewiner et al. test one chosen slice instead; Custodio et al. show where
//!   that errs.
//!
//! A tunnel turns the two loops that bound the joined regions into one tube: a band of
//! triangles between the two loops, with every triangle side between the loops off the cube
//! faces (as the polygon triangulations are), chosen so that it never crosses itself on seeded
//! corner-crowding draws. Where no band keeps its sides off the faces (a tunnel of the outside
//! between corners that joined faces separate), the run of band triangles holding the sides on
//! faces is fanned around one vertex inside the cell instead, as Lewiner et al.'s case 6.1.2 is.
//! Where a polygon has eight or more vertices it is fanned around that vertex too, as their
//! tables do (their cases 7.3, 10.2, 12.2, 13.3 and 13.4). The vertex is at their centre: the
//! corners' mean weighted by the inverse distance of each corner's value from the iso-value,
//! kept a thousandth of the cell inside its faces (where a corner lies at the iso-value,
//! Lewiner's centre is that corner, where the neighbouring cells' triangles cross its fan).
//! Everything else is the face-choice table's.
//!
//! **No tube crosses itself.** A tunnel keeps several tube triangulations (other bands, and
//! bands with a run fanned around the centre vertex); each cell takes the first that does not
//! cross or fold onto itself at its own vertex positions (the exact predicate, on the crossings
//! and centre the cell's values give, computed as the engine computes them). Where none does
//! (a thin tunnel between skewed loops, as a few cells of the MNI T1 template in `real_volumes`
//! have), the tube is drawn through the tunnel's **waist**: a ring of three
//! level-set points around the interpolant's body saddle (`waist.rs`), a band from each loop to
//! the ring, the first pair of bands that keeps off itself and the cell's other triangles.
//! Failing that, the tube's own vertex moves from Lewiner's centre to the nearest point of an
//! 8³ lattice in the cell where a fanned tube keeps off itself. Failing all (a tunnel too thin
//! to draw: at a critical value of the interpolant its walls touch), the tunnel is left out and
//! the cell keeps the two discs; the topology tests allow a cell to differ from the
//! interpolant only within a hair of a critical value.
//! `tests/tests/marching_cubes_33.rs` and `tests/tests/self_intersections.rs` hold the whole
//! mesh to no crossing on every sign pattern (tunnel draws and corner-crowding draws), and the
//! contract test on corners at the iso-value. Tables are built per (pattern, face choices,
//! tunnel) the first time a cell needs them; waist tubes per (pattern, face choices, tunnel,
//! bands) the first time one is chosen.

use super::marching_cubes::{
    chain_polygons, fan_around, triangulate, Case, FaceRule, AMBIGUOUS_FACES, EDGES, FACES, FACE_CHOICE_TABLE, MAX_TRIANGLES,
};
use std::sync::{LazyLock, OnceLock};
use tubes::tubes;

mod tubes;
mod waist;

/// Polygons of at least this many vertices are fanned around the cell's centre vertex.
pub const CENTRE_FAN_VERTICES: usize = 8;

/// Most tunnels a (pattern, face choices) can have a choice of.
const MAX_CANDIDATES: usize = 6;

/// A possible tunnel: two boundary regions of one sign, named by a corner of each, and the two
/// polygons the tube joins.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Candidate {
    /// A corner of each of the two regions.
    pub corners: (u8, u8),
    /// The polygons (indices in [`chain_polygons`]' order) that become one tube.
    pub polygons: (u8, u8),
}

/// The regions of one sign on the cube's boundary: a region id (a corner of it) for each corner.
/// Corners of one sign are joined along cube edges and, on an ambiguous face, across its
/// diagonal of the sign the face's choice joins (bit `f` of `joins`: the inside corners).
pub fn boundary_regions(case: u8, joins: u8) -> [u8; 8] {
    let mut parent: [u8; 8] = std::array::from_fn(|c| c as u8);
    let inside = |c: u8| case >> c & 1 == 1;
    for &(a, b) in &EDGES {
        if inside(a) == inside(b) {
            union(&mut parent, a, b);
        }
    }
    for (f, (cycle, _)) in FACES.iter().enumerate() {
        if AMBIGUOUS_FACES[case as usize] >> f & 1 == 1 {
            let join_inside = joins >> f & 1 == 1;
            let (p, q) = if inside(cycle[0]) == join_inside { (cycle[0], cycle[2]) } else { (cycle[1], cycle[3]) };
            union(&mut parent, p, q);
        }
    }
    std::array::from_fn(|c| find(&mut parent, c as u8))
}

/// The regions of one sign inside the closed cube, exactly, for corner values `g` (minus the
/// iso-value; a corner is inside when its value is negative, as the case index counts it): a
/// component id (a corner of it) for each corner. See the module doc for the slice argument.
pub fn interior_components(g: [f64; 8]) -> [u8; 8] {
    let mut parent: [u8; 8] = std::array::from_fn(|c| c as u8);
    for inside in [true, false] {
        let has = |v: f64| (v < 0.0) == inside;
        // Vertical edge k joins corner k (z = 0) to corner k + 4 (z = 1); the heights where it
        // has the sign form one interval.
        let interval = |k: usize| -> Option<(f64, f64)> {
            let (lo, hi) = (g[k], g[k + 4]);
            match (has(lo), has(hi)) {
                (true, true) => Some((0.0, 1.0)),
                (false, false) => None,
                (true, false) => Some((0.0, lo / (lo - hi))),
                (false, true) => Some((lo / (lo - hi), 1.0)),
            }
        };
        let corner_of = |k: usize| if has(g[k]) { k as u8 } else { k as u8 + 4 };
        let runs: [Option<(f64, f64)>; 4] = std::array::from_fn(interval);
        for k in 0..4 {
            if has(g[k]) && has(g[k + 4]) {
                union(&mut parent, k as u8, k as u8 + 4);
            }
        }
        // Side by side (a face of the cube): joined at any common height.
        for k in 0..4 {
            let l = (k + 1) % 4;
            if overlap(runs[k], runs[l]).is_some() {
                union(&mut parent, corner_of(k), corner_of(l));
            }
        }
        // Diagonal: joined where the slice's saddle has the sign and the other two edges do not.
        for (k, l, m, n) in [(0, 2, 1, 3), (1, 3, 0, 2)] {
            let Some((z0, z1)) = overlap(runs[k], runs[l]) else { continue };
            let line = |c: usize| (g[c], g[c + 4] - g[c]);
            if saddle_joins(line(k), line(l), line(m), line(n), z0, z1, &has) {
                union(&mut parent, corner_of(k), corner_of(l));
            }
        }
    }
    std::array::from_fn(|c| find(&mut parent, c as u8))
}

/// Whether, at some height in `[z0, z1]` where neither `m` nor `n` has the sign (where one has,
/// the side-by-side rule already joins), `a c - b d > 0` for the lines `a` (`k`), `c` (`l`), `b`
/// (`m`), `d` (`n`), each `(value at 0, slope)`: the slice's saddle lies on the side of `k` and
/// `l`.
fn saddle_joins(
    a: (f64, f64),
    c: (f64, f64),
    b: (f64, f64),
    d: (f64, f64),
    z0: f64,
    z1: f64,
    has: &impl Fn(f64) -> bool,
) -> bool {
    let at = |line: (f64, f64), z: f64| line.0 + line.1 * z;
    let q = |z: f64| at(a, z) * at(c, z) - at(b, z) * at(d, z);
    // Split [z0, z1] where m or n changes sign.
    // (On the hot path: a fixed array, no allocation per cell.)
    let (mut cuts, mut len) = ([z0, z1, z1, z1], 2);
    for line in [b, d] {
        if line.1 != 0.0 {
            let t = -line.0 / line.1;
            if t > z0 && t < z1 {
                cuts[len] = t;
                len += 1;
            }
        }
    }
    let cuts = &mut cuts[..len];
    cuts.sort_by(f64::total_cmp);
    let qa = a.1 * c.1 - b.1 * d.1;
    let qb = a.0 * c.1 + a.1 * c.0 - b.0 * d.1 - b.1 * d.0;
    cuts.windows(2).any(|w| {
        let (lo, hi) = (w[0], w[1]);
        let mid = 0.5 * (lo + hi);
        if hi <= lo || has(at(b, mid)) || has(at(d, mid)) {
            return false;
        }
        let mut best = q(lo).max(q(hi));
        if qa < 0.0 {
            let vertex = -qb / (2.0 * qa);
            if vertex > lo && vertex < hi {
                best = best.max(q(vertex));
            }
        }
        best > 0.0
    })
}

fn overlap(a: Option<(f64, f64)>, b: Option<(f64, f64)>) -> Option<(f64, f64)> {
    let ((a0, a1), (b0, b1)) = (a?, b?);
    let (lo, hi) = (a0.max(b0), a1.min(b1));
    (lo < hi).then_some((lo, hi))
}

fn find(parent: &mut [u8; 8], mut c: u8) -> u8 {
    while parent[c as usize] != c {
        parent[c as usize] = parent[parent[c as usize] as usize];
        c = parent[c as usize];
    }
    c
}

fn union(parent: &mut [u8; 8], a: u8, b: u8) {
    let (ra, rb) = (find(parent, a), find(parent, b));
    if ra != rb {
        parent[ra.max(rb) as usize] = ra.min(rb);
    }
}

fn face_rule(joins: u8) -> impl Fn(u8, usize) -> FaceRule {
    move |_, f| if joins >> f & 1 == 1 { FaceRule::JoinInside } else { FaceRule::SeparateInside }
}

/// The tunnels a cell of pattern `case` with face choices `joins` could have: pairs of boundary
/// regions of one sign whose loops border one region of the other sign (a tube between them
/// would then cut that region's passage in two, as Chernyaev's tunnels do).
pub fn candidates(case: u8, joins: u8) -> Vec<Candidate> {
    let regions = boundary_regions(case, joins);
    let (_, _, polygons) = chain_polygons(case, face_rule(joins));
    // Each polygon's inside and outside region (every crossing edge joins one of each).
    let sides: Vec<(u8, u8)> = polygons
        .iter()
        .map(|p| {
            let (a, b) = EDGES[p[0] as usize];
            let (i, o) = if case >> a & 1 == 1 { (a, b) } else { (b, a) };
            (regions[i as usize], regions[o as usize])
        })
        .collect();
    let mut out = Vec::new();
    for p in 0..polygons.len() {
        for q in p + 1..polygons.len() {
            let ((pi, po), (qi, qo)) = (sides[p], sides[q]);
            // Inside regions joined, the outside one shared; or the other way round.
            let pair = if pi != qi && po == qo {
                Some((pi, qi))
            } else if po != qo && pi == qi {
                Some((po, qo))
            } else {
                None
            };
            if let Some(corners) = pair {
                out.push(Candidate { corners, polygons: (p as u8, q as u8) });
            }
        }
    }
    out
}

/// Each (pattern, face choices)'s candidates, and the tables for each choice of tunnel (slot 0:
/// none; slot `1 + k`: candidate `k`), built when first used.
struct Tables {
    /// The possible tunnels of each (pattern, face choices).
    candidates: Vec<Vec<Candidate>>,
    /// Whether the face-choice table's entry has a polygon of [`CENTRE_FAN_VERTICES`] or more.
    fanned: Vec<bool>,
    /// Entries, per (pattern, face choices, tunnel slot), generated when first needed: one, or
    /// one per tube triangulation ([`variants`]).
    cases: Vec<OnceLock<Vec<Case>>>,
}

static TABLES: LazyLock<Tables> = LazyLock::new(|| {
    let candidates: Vec<Vec<Candidate>> = (0..256 * 64)
        .map(|i| {
            let (case, joins) = ((i / 64) as u8, (i % 64) as u8 & AMBIGUOUS_FACES[i / 64]);
            let c = candidates(case, joins);
            assert!(c.len() <= MAX_CANDIDATES, "case {case} joins {joins}: {} possible tunnels", c.len());
            c
        })
        .collect();
    let fanned = FACE_CHOICE_TABLE
        .iter()
        .map(|plain| (0..plain.polygons).any(|p| plain.edge_polygon.iter().filter(|&&q| q == p).count() >= CENTRE_FAN_VERTICES))
        .collect();
    let cases = (0..256 * 64 * (MAX_CANDIDATES + 1)).map(|_| OnceLock::new()).collect();
    Tables { candidates, fanned, cases }
});

/// Whether a cell of pattern `case` with no ambiguous face may still tunnel (Chernyaev's case 4
/// and its complement: two corners of one sign at the ends of a cube diagonal).
pub fn may_tunnel(case: u8) -> bool {
    static TUNNELS: LazyLock<[bool; 256]> = LazyLock::new(|| std::array::from_fn(|c| !TABLES.candidates[c * 64].is_empty()));
    TUNNELS[case as usize]
}

/// The vertex inside a cell that Lewiner et al.'s tables fan polygons around (scikit-image's
/// `calculate_center_vertex`): the cell's corners averaged with weights `1 / (ε + |g|)` for
/// corner values `g` minus the iso-value (ε: `f32::EPSILON`), in cell-local coordinates, kept
/// [`CENTRE_MARGIN`] inside the cell's faces. (Unclamped, a corner at the iso-value takes all
/// the weight and the vertex lands on that corner, shared with seven other cells, where their
/// triangles cross its fan: scikit-image's does.)
pub fn lewiner_centre(g: [f32; 8]) -> glam::Vec3 {
    let (mut sum, mut total) = (glam::Vec3::ZERO, 0.0f32);
    for (c, v) in g.iter().enumerate() {
        let w = 1.0 / (f32::EPSILON + v.abs());
        sum += w * glam::Vec3::from(super::marching_cubes::CORNERS[c].map(f32::from));
        total += w;
    }
    (sum / total).clamp(glam::Vec3::splat(CENTRE_MARGIN), glam::Vec3::splat(1.0 - CENTRE_MARGIN))
}

/// How far inside the cell's faces [`lewiner_centre`] stays (in cell widths): ten times as far
/// as an edge crossing is kept from a corner (the engine's default, `1e-4`).
pub const CENTRE_MARGIN: f32 = 1e-3;

/// Interior vertices a cell places elsewhere than [`lewiner_centre`]: bit `k` of `mask` for slot
/// `12 + k`, at `at[k]` (cell-local coordinates).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Placed {
    /// The slots placed here.
    pub mask: u8,
    /// Their positions.
    pub at: [glam::Vec3; 4],
}

/// Where a cell lies, so that its vertex positions are checked exactly as the engine computes
/// them (in `f32`, from its grid: rounding can move a vertex onto another triangle): its grid
/// and the sample index of its corner 0.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CellFrame {
    /// The cell's grid.
    pub grid: crate::Grid,
    /// The sample index of its corner 0.
    pub cell: [usize; 3],
}

impl CellFrame {
    /// The unit cell at the origin.
    pub const UNIT: CellFrame =
        CellFrame { grid: crate::Grid { origin: glam::Vec3::ZERO, spacing: 1.0, dims: [2, 2, 2] }, cell: [0, 0, 0] };

    /// The position of corner `c`, as the engine computes a sample's.
    fn corner(&self, c: u8) -> glam::Vec3 {
        let [x, y, z] = super::marching_cubes::CORNERS[c as usize].map(usize::from);
        self.grid.position(self.cell[0] + x, self.cell[1] + y, self.cell[2] + z)
    }

    /// The position of cell-local point `p`, as the engine computes an interior vertex's.
    fn place(&self, p: glam::Vec3) -> glam::Vec3 {
        self.grid.position(self.cell[0], self.cell[1], self.cell[2]) + p * self.grid.spacing
    }
}

/// A cell's table entry and the interior vertices its tube places itself ([`Placed`]).
pub type CellEntry = (&'static Case, Option<Placed>);

/// The table entry of a cell with pattern `case` (bit `c`: corner `c` inside), face choices
/// `joins` (bit `f`: ambiguous face `f` joins its inside corners) and corner values `g` (minus
/// the iso-value), placed at `frame`, with the tube's own interior vertices where it needs them
/// ([`CellEntry`]).
///
/// A tube takes, in this order, the first triangulation that does not cross itself (the exact
/// predicate, at the cell's own vertex positions): around Lewiner's centre (as scikit-image
/// places it); else drawn through the tunnel's waist, a ring of three level-set points around its
/// body saddle (`waist.rs`); else fanned around the nearest point of a lattice inside the
/// cell where it keeps off itself. Failing all, no tube: the discs.
pub fn entry(case: u8, joins: u8, g: &[f64; 8], frame: &CellFrame) -> CellEntry {
    let joins = joins & AMBIGUOUS_FACES[case as usize];
    let key = case as usize * 64 + joins as usize;
    let tables = &*TABLES;
    let candidates = &tables.candidates[key];
    let discs =
        || fans_kept_off(&tables.cases[key * (MAX_CANDIDATES + 1)].get_or_init(|| variants(case, joins, None))[0], g, frame);
    if candidates.is_empty() {
        if !tables.fanned[key] {
            return (&FACE_CHOICE_TABLE[key], None);
        }
        return discs();
    }
    let components = interior_components(*g);
    let Some(k) = candidates.iter().position(|c| components[c.corners.0 as usize] == components[c.corners.1 as usize]) else {
        return discs();
    };
    let tunnel = candidates[k];
    let choices = tables.cases[key * (MAX_CANDIDATES + 1) + k + 1].get_or_init(|| variants(case, joins, Some(tunnel.polygons)));
    let piece = tunnel.polygons.0;
    let mut at = cell_points(g, frame);
    if let Some(c) = choices.iter().find(|c| !meets_at(c.triangles(), &at)) {
        return (c, None);
    }
    // Through the tunnel's waist.
    if let Some(found) = waist::through_waist(case, joins, g, (key, k), tunnel, frame, &mut at) {
        return found;
    }
    at = cell_points(g, frame);
    // Around another place of the tube's own vertex.
    let slot = 12 + usize::from(piece);
    let fanned: Vec<&Case> = choices.iter().filter(|c| c.interior >> piece & 1 == 1).collect();
    for centre in centre_candidates(lewiner_centre(g.map(|v| v as f32))) {
        at[slot] = frame.place(centre);
        if let Some(c) = fanned.iter().find(|c| !meets_at(c.triangles(), &at)) {
            let mut placed = Placed { mask: 1 << piece, ..Placed::default() };
            placed.at[usize::from(piece)] = centre;
            return (c, Some(placed));
        }
    }
    // A tunnel too thin to draw (at a critical value, where it has no thickness): left out, the
    // two discs as the boundary has them.
    discs()
}

/// `entry` (no tube) with its fanned polygons' vertex kept off the cell's other triangles: at
/// Lewiner's centre where the fans meet nothing there (the exact predicate, at the cell's own
/// vertex positions), else at the nearest lattice point where they meet nothing
/// ([`centre_candidates`]; every fan around the one point).
fn fans_kept_off(entry: &'static Case, g: &[f64; 8], frame: &CellFrame) -> CellEntry {
    if entry.interior == 0 {
        return (entry, None);
    }
    let mut at = cell_points(g, frame);
    if !meets_at(entry.triangles(), &at) {
        return (entry, None);
    }
    for centre in centre_candidates(lewiner_centre(g.map(|v| v as f32))) {
        at[12..].fill(frame.place(centre));
        if !meets_at(entry.triangles(), &at) {
            return (entry, Some(Placed { mask: entry.interior, at: [centre; 4] }));
        }
    }
    (entry, None)
}

/// Points per axis of the lattice [`centre_candidates`] tries.
const CENTRE_LATTICE: usize = 8;

/// The places a tube's interior vertex is tried at when Lewiner's centre `from` gives no tube
/// free of crossings: the points of a lattice of [`CENTRE_LATTICE`]³ inside the cell (each at
/// least half a lattice step from its faces), nearest `from` first (ties in lattice order).
fn centre_candidates(from: glam::Vec3) -> impl Iterator<Item = glam::Vec3> {
    let n = CENTRE_LATTICE;
    let mut points: Vec<glam::Vec3> = (0..n * n * n)
        .map(|i| (glam::Vec3::new((i % n) as f32, (i / n % n) as f32, (i / (n * n)) as f32) + 0.5) / n as f32)
        .collect();
    points.sort_by(|a, b| a.distance_squared(from).total_cmp(&b.distance_squared(from)));
    points.into_iter()
}

/// A cell's vertex positions for corner values `g` (minus the iso-value) at `frame`, as the
/// engine computes them: the crossing of each edge that changes sign, in `f32` from the edge's
/// lower end (linear, kept 1e-4 from the edge's ends as the engine keeps them by default), then
/// the centre vertex ([`lewiner_centre`]) in the four interior slots (vertex slots as
/// [`meets_at`] reads them).
fn cell_points(g: &[f64; 8], frame: &CellFrame) -> [glam::Vec3; 16] {
    let centre = frame.place(lewiner_centre(g.map(|v| v as f32)));
    let spacing = frame.grid.spacing;
    std::array::from_fn(|i| match EDGES.get(i) {
        Some(&(a, b)) => {
            let (pa, pb) = (frame.corner(a), frame.corner(b));
            let (lo, hi) = if pa.cmple(pb).all() { (a, b) } else { (b, a) };
            let (ga, gb) = (g[lo as usize] as f32, g[hi as usize] as f32);
            let t = if (ga < 0.0) != (gb < 0.0) { (-ga / (gb - ga)).clamp(1e-4, 1.0 - 1e-4) } else { 0.5 };
            let mut p = frame.corner(lo);
            let axis = (frame.corner(hi) - p).abs().max_position();
            p[axis] += t * spacing;
            p
        }
        None => centre,
    })
}

/// Whether any two triangles of `t` (vertex slots into `at`) meet beyond what they share, as
/// the self-intersection metric counts it: crossings, and triangles sharing a side folded
/// onto each other.
fn meets_at(t: &[[u8; 3]], at: &[glam::Vec3; 16]) -> bool {
    (0..t.len()).any(|i| {
        (i + 1..t.len())
            .any(|j| crate::predicates::indexed_triangles_intersect(t[i].map(u32::from), t[j].map(u32::from), |v| at[v as usize]))
    })
}

/// The entries for `case` with face choices `joins` and, if any, a tube joining `tunnel`'s two
/// polygons, one per tube triangulation of `tubes` (in its order); one entry with no tunnel,
/// or where the two loops have no tube (a tunnel the trilinear interpolant cannot make there,
/// such as one in Chernyaev's case 7.2: the discs stay).
pub fn variants(case: u8, joins: u8, tunnel: Option<(u8, u8)>) -> Vec<Case> {
    let (edge_mask, next, polygons) = chain_polygons(case, face_rule(joins));
    let tubes = tunnel.map_or_else(Vec::new, |(p, q)| tubes(&polygons[p as usize], &polygons[q as usize], 12 + p));
    if tubes.is_empty() {
        return vec![assemble(case, (edge_mask, next, &polygons), None)];
    }
    let (p, q) = tunnel.expect("tubes only for a tunnel");
    tubes.iter().map(|t| assemble(case, (edge_mask, next, &polygons), Some(((p, q), t.as_slice())))).collect()
}

/// A tube in a table entry: the two polygons it joins and its triangles.
type Tube<'a> = ((u8, u8), &'a [[u8; 3]]);

/// A table entry from the chained polygons: the tube, if any, in place of its two polygons, the
/// others triangulated (or fanned around their centre).
fn assemble(case: u8, (edge_mask, next, polygons): (u16, [u8; 12], &[Vec<u8>]), tunnel: Option<Tube<'_>>) -> Case {
    let mut triangles = Vec::with_capacity(MAX_TRIANGLES);
    let mut edge_polygon = [u8::MAX; 12];
    let mut interior = 0u8;
    for (piece, polygon) in polygons.iter().enumerate() {
        for &e in polygon {
            edge_polygon[e as usize] = piece as u8;
        }
        let piece = piece as u8;
        match tunnel {
            Some(((p, _), band)) if piece == p => {
                if band.iter().flatten().any(|&v| v == 12 + piece) {
                    interior |= 1 << piece;
                }
                triangles.extend(band.iter().copied());
            }
            Some(((_, q), _)) if piece == q => {}
            _ if polygon.len() >= CENTRE_FAN_VERTICES => {
                interior |= 1 << piece;
                triangles.extend(fan_around(polygon, 12 + piece));
            }
            _ => match triangulate(polygon) {
                Some(t) => triangles.extend(t),
                None => {
                    interior |= 1 << piece;
                    triangles.extend(fan_around(polygon, 12 + piece));
                }
            },
        }
    }
    assert!(triangles.len() <= MAX_TRIANGLES, "case {case}: {} triangles", triangles.len());
    // Every interior slot a triangle uses (a waist ring's too).
    interior |= triangles.iter().flatten().filter(|&&v| v >= 12).fold(0u8, |m, &v| m | 1 << (v - 12));
    let mut fixed = [[0u8; 3]; MAX_TRIANGLES];
    fixed[..triangles.len()].copy_from_slice(&triangles);
    Case {
        edge_mask,
        count: triangles.len() as u8,
        triangles: fixed,
        polygons: polygons.len() as u8,
        edge_polygon,
        next,
        interior,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_diagonal_of_case_four_tunnels_only_when_the_centre_is_inside() {
        // Corners 0 and 6 inside (case 4 of Chernyaev): no face is ambiguous; the interior joins
        // them when the value along the diagonal stays inside.
        let mut g = [1.0f64; 8];
        g[0] = -1.0;
        g[6] = -1.0;
        let c = interior_components(g);
        assert_ne!(c[0], c[6], "the trilinear centre is 0.5 > 0: apart");
        // Outside corners barely outside: the middle of the cell is inside, a tube.
        let mut g = [0.05f64; 8];
        g[0] = -1.0;
        g[6] = -1.0;
        let c = interior_components(g);
        assert_eq!(c[0], c[6]);
        let case = 1 | 1 << 6;
        assert_eq!(candidates(case, 0).len(), 1);
        let (tube, placed) = entry(case, 0, &g, &CellFrame::UNIT);
        assert_eq!(placed, None, "Lewiner's centre serves");
        assert_eq!((tube.count, tube.interior), (6, 0), "two triangles become a tube of six");
    }

    #[test]
    fn boundary_regions_follow_the_face_choice() {
        // Corners 0 and 2 inside: the bottom face is ambiguous.
        let r = boundary_regions(0b101, 0);
        assert_ne!(r[0], r[2]);
        let r = boundary_regions(0b101, 1);
        assert_eq!(r[0], r[2]);
    }

    #[test]
    fn every_tunnel_table_is_a_tube_wound_as_its_loops() {
        for case in 0..=255u8 {
            for joins in 0..64u8 {
                if joins & !AMBIGUOUS_FACES[case as usize] != 0 {
                    continue;
                }
                for (k, c) in candidates(case, joins).iter().enumerate() {
                    for t in variants(case, joins, Some(c.polygons)) {
                        let plain = &FACE_CHOICE_TABLE[case as usize * 64 + joins as usize];
                        // Every directed loop side is used once, as in the discs.
                        let sides = |tri: &[[u8; 3]]| {
                            let mut s: Vec<(u8, u8)> = tri
                                .iter()
                                .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
                                .filter(|&(p, q)| p < 12 && plain.next[p as usize] == q)
                                .collect();
                            s.sort_unstable();
                            s
                        };
                        let disc_sides = sides(plain.triangles());
                        assert_eq!(sides(t.triangles()), disc_sides, "case {case} joins {joins} tunnel {k}");
                    }
                }
            }
        }
    }
}
