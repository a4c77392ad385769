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
//! corners' mean weighted by the inverse distance of each corner's value from the iso-value.
//! Everything else is the face-choice table's.
//!
//! A tunnel keeps several tube triangulations (other bands, and bands with a run fanned around
//! the centre vertex); each cell takes the first that does not cross itself at its own vertex
//! positions (the exact predicate, on the crossings and centre the cell's values give), else the
//! first. Tables are built per (pattern, face choices, tunnel) the first time a cell needs them.

use super::marching_cubes::{
    chain_polygons, crosses_at, fan_around, triangulate, Case, FaceRule, AMBIGUOUS_FACES, EDGES, FACES, FACE_CHOICE_TABLE,
    MAX_TRIANGLES,
};
use std::sync::{LazyLock, OnceLock};
use tubes::tubes;

mod tubes;

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
/// corner values `g` minus the iso-value (ε: `f32::EPSILON`), in cell-local coordinates.
pub fn lewiner_centre(g: [f32; 8]) -> glam::Vec3 {
    let (mut sum, mut total) = (glam::Vec3::ZERO, 0.0f32);
    for (c, v) in g.iter().enumerate() {
        let w = 1.0 / (f32::EPSILON + v.abs());
        sum += w * glam::Vec3::from(super::marching_cubes::CORNERS[c].map(f32::from));
        total += w;
    }
    sum / total
}

/// The table entry of a cell with pattern `case` (bit `c`: corner `c` inside), face choices
/// `joins` (bit `f`: ambiguous face `f` joins its inside corners) and corner values `g` (minus
/// the iso-value).
pub fn entry(case: u8, joins: u8, g: &[f64; 8]) -> &'static Case {
    let joins = joins & AMBIGUOUS_FACES[case as usize];
    let key = case as usize * 64 + joins as usize;
    let tables = &*TABLES;
    let candidates = &tables.candidates[key];
    if candidates.is_empty() {
        if !tables.fanned[key] {
            return &FACE_CHOICE_TABLE[key];
        }
        return &tables.cases[key * (MAX_CANDIDATES + 1)].get_or_init(|| variants(case, joins, None))[0];
    }
    let components = interior_components(*g);
    let slot =
        candidates.iter().position(|c| components[c.corners.0 as usize] == components[c.corners.1 as usize]).map_or(0, |k| k + 1);
    let choices = tables.cases[key * (MAX_CANDIDATES + 1) + slot]
        .get_or_init(|| variants(case, joins, slot.checked_sub(1).map(|k| candidates[k].polygons)));
    if choices.len() == 1 {
        return &choices[0];
    }
    // A tube: the first triangulation that does not cross itself at this cell's own vertices.
    let at = cell_points(g);
    choices.iter().find(|c| !crosses_at(c.triangles(), &at)).unwrap_or(&choices[0])
}

/// A cell's vertex positions in cell-local coordinates for corner values `g` (minus the
/// iso-value): the crossing of each edge that changes sign (linear, kept 1e-4 from the edge's
/// ends as the engine keeps them by default), then the centre vertex ([`lewiner_centre`]) in
/// the four interior slots (vertex slots as [`crosses_at`] reads them).
fn cell_points(g: &[f64; 8]) -> [glam::Vec3; 16] {
    let corner = |c: u8| glam::Vec3::from(super::marching_cubes::CORNERS[c as usize].map(f32::from));
    let centre = lewiner_centre(g.map(|v| v as f32));
    std::array::from_fn(|i| match EDGES.get(i) {
        Some(&(a, b)) => {
            let (ga, gb) = (g[a as usize], g[b as usize]);
            let t = if (ga < 0.0) != (gb < 0.0) { (ga / (ga - gb)).clamp(1e-4, 1.0 - 1e-4) as f32 } else { 0.5 };
            corner(a) + (corner(b) - corner(a)) * t
        }
        None => centre,
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
        let tube = entry(case, 0, &g);
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
