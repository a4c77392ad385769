//! The 256-case marching cubes table (Lorensen & Cline 1987, "Marching cubes: a high resolution
//! 3D surface construction algorithm", DOI 10.1145/37402.37422).
//!
//! ## Origin
//! The table is **generated**, not copied: for each of the 256 sign patterns the isoline
//! segments on the six cube faces are chained into closed polygons, which are triangulated
//! without a diagonal on a cube face, fans first.
//!
//! A polygon of five or more vertices is skew, and where its crossings crowd the cube's corners at
//! unequal rates (a corner's value near the iso-value, its neighbours' not) some fans fold over
//! themselves: two of their triangles cross. The first fan the rule found for the heptagons of
//! cases 109, 151, 186 and 203 did so in about one cell in ten of random values, which is where
//! the self-intersections of marching cubes on MRI volumes came from (flying edges, with other
//! triangulations of the same vertices, had none). Each polygon's triangulation is therefore the
//! first valid one that does not cross itself on a fixed set of seeded, corner-crowding vertex
//! placements (`CROWDED_DRAWS` of them, a private constant); `tests/tests/self_intersections.rs` then meshes every
//! case with thousands of such corner values, and values exactly at the iso-value, and finds no
//! crossing pair with the exact predicate. Triangle counts and vertices are unchanged.
//! Corner and edge numbering follow the widely used convention of Paul Bourke's "Polygonising a
//! scalar field" (1994), so edge `e` here is edge `e` there.
//!
//! On an ambiguous face (two diagonal corners inside) a [`FaceRule`] decides which corners the
//! surface separates. [`FaceRule::SeparateInside`] (the default table) always separates the
//! inside corners, a rule that depends only on the face's own four signs, so the two cells sharing
//! a face always agree and the surface is closed and manifold for every pattern (the original
//! Lorensen table was not; its complementary cases disagreed). Every edge crossing is one polygon
//! vertex in exactly two face segments, so polygons are disjoint simple cycles.
//!
//! Orientation: each face segment is directed so that the triangle it bounds faces the outside
//! corners; hence triangles are counter-clockwise seen from outside (`f > iso`).

use std::sync::LazyLock;

/// Corner `i` of the unit cell, as `(x, y, z)` offsets.
pub const CORNERS: [[u8; 3]; 8] = [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]];

/// Edge `e` joins corners `EDGES[e].0` and `EDGES[e].1`.
pub const EDGES: [(u8, u8); 12] =
    [(0, 1), (1, 2), (2, 3), (3, 0), (4, 5), (5, 6), (6, 7), (7, 4), (0, 4), (1, 5), (2, 6), (3, 7)];

/// Each face: its corners in cyclic order and its outward normal.
pub const FACES: [([u8; 4], [i8; 3]); 6] = [
    ([0, 1, 2, 3], [0, 0, -1]),
    ([4, 5, 6, 7], [0, 0, 1]),
    ([0, 1, 5, 4], [0, -1, 0]),
    ([3, 2, 6, 7], [0, 1, 0]),
    ([0, 3, 7, 4], [-1, 0, 0]),
    ([1, 2, 6, 5], [1, 0, 0]),
];

/// Most triangles any case produces (marching cubes 33's tubes fanned around the centre make up
/// to fourteen).
pub const MAX_TRIANGLES: usize = 16;

/// How an ambiguous face (diagonal corners inside) is resolved.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FaceRule {
    /// The inside corners are separated (the outside region is connected across the face).
    SeparateInside,
    /// The inside corners are joined (the outside corners are separated).
    JoinInside,
}

/// One table entry.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Case {
    /// Bit `e` set when edge `e` crosses the surface.
    pub edge_mask: u16,
    /// Number of triangles.
    pub count: u8,
    /// Triangles as edge numbers; the first `count` are used.
    pub triangles: [[u8; 3]; MAX_TRIANGLES],
    /// Number of separate surface pieces (polygons) in the cell.
    pub polygons: u8,
    /// Which polygon each crossing edge belongs to (`u8::MAX` for edges that do not cross).
    /// Dual methods use it to give each piece its own vertex.
    pub edge_polygon: [u8; 12],
    /// The next crossing edge around each crossing edge's polygon (`u8::MAX` for edges that do
    /// not cross): the polygon's cycle, which the dual methods walk to split a piece that the
    /// domain boundary cuts into separate fans.
    pub next: [u8; 12],
    /// Bit `p` set when polygon `p` is fanned around an interior vertex at the mean of its edge
    /// crossings, referred to in `triangles` as `12 + p` (only some joined ambiguous faces need
    /// it; the default table never does). Marching cubes 33's tubes also set the bits of the
    /// slots their waist ring takes (`crate::tables::marching_cubes_33`).
    pub interior: u8,
}

impl Case {
    /// The used triangles.
    pub fn triangles(&self) -> &[[u8; 3]] {
        &self.triangles[..self.count as usize]
    }
}

/// The default table: [`FaceRule::SeparateInside`] on every face. Case index bit `c` is set when
/// corner `c` is inside (`f < iso`).
pub static TABLE: LazyLock<[Case; 256]> =
    LazyLock::new(|| std::array::from_fn(|c| generate_case(c as u8, |_, _| FaceRule::SeparateInside)));

/// Bit `f` set when face `f` of the case is ambiguous (two diagonal corners inside, two outside).
pub static AMBIGUOUS_FACES: LazyLock<[u8; 256]> = LazyLock::new(|| {
    std::array::from_fn(|c| {
        (0..6).fold(0u8, |mask, f| {
            let cyc = FACES[f].0;
            let inside = |k: usize| c >> cyc[k] & 1 == 1;
            let ambiguous = inside(0) == inside(2) && inside(1) == inside(3) && inside(0) != inside(1);
            mask | (u8::from(ambiguous) << f)
        })
    })
});

/// Bit `f` set when face `f` of the case is ambiguous and, in the default table, both of its
/// segments lie on one polygon: the inside corners the face separates are joined through the
/// cell's other faces, so one piece of surface wraps the outside passage across the face. A dual
/// method with one vertex per piece pinches that passage when the cell on the other side of the
/// face does the same; [`crate::extractors::surface_nets`] then joins the face's inside corners
/// in both cells instead. That changes no other face's status: the joined corners were already
/// connected.
pub static RING_FACES: LazyLock<[u8; 256]> = LazyLock::new(|| {
    std::array::from_fn(|c| {
        let entry = &TABLE[c];
        (0..6).fold(0u8, |mask, f| {
            let pieces = face_edges(f).map(|e| entry.edge_polygon[e as usize]);
            let ring = AMBIGUOUS_FACES[c] >> f & 1 == 1 && pieces.iter().all(|&p| p == pieces[0]);
            mask | (u8::from(ring) << f)
        })
    })
});

/// The four edges of face `f`, in the face's cyclic order.
pub fn face_edges(f: usize) -> [u8; 4] {
    let cyc = FACES[f].0;
    std::array::from_fn(|k| edge_between(cyc[k], cyc[(k + 1) % 4]))
}

/// The face of the neighbouring cell that coincides with face `f` (the one with opposite normal).
pub fn opposite_face(f: usize) -> usize {
    f ^ 1
}

/// Tables for every choice on the ambiguous faces: entry `case * 64 + joins`, where bit `f` of
/// `joins` set means face `f` joins its inside corners ([`FaceRule::JoinInside`]) and clear means
/// it separates them. Bits of unambiguous faces are ignored. Used with the asymptotic decider.
pub static FACE_CHOICE_TABLE: LazyLock<Vec<Case>> = LazyLock::new(|| {
    (0..256 * 64)
        .map(|i| {
            let (case, joins) = ((i / 64) as u8, (i % 64) as u8);
            generate_case(case, |_, f| if joins >> f & 1 == 1 { FaceRule::JoinInside } else { FaceRule::SeparateInside })
        })
        .collect()
});

/// The asymptotic decider (Nielson & Hamann 1991, "The asymptotic decider: resolving the ambiguity
/// in marching cubes", DOI 10.1109/VISUAL.1991.175782) on an ambiguous face with corner values
/// `v` (in the face's cyclic order, minus the iso-value): the bilinear interpolant's saddle value
/// `(v0 v2 - v1 v3) / (v0 + v2 - v1 - v3)`; the inside corners are joined across the face when it
/// is inside (negative). Both cells of a face compute it from the same four values in the same
/// order, so they always agree.
pub fn decider_joins_inside(v: [f64; 4]) -> bool {
    let num = v[0] * v[2] - v[1] * v[3];
    let den = v[0] + v[2] - v[1] - v[3];
    den != 0.0 && num / den < 0.0
}

fn edge_between(a: u8, b: u8) -> u8 {
    EDGES.iter().position(|&(p, q)| (p, q) == (a, b) || (p, q) == (b, a)).expect("adjacent corners") as u8
}

fn corner_pos(c: u8) -> [f32; 3] {
    CORNERS[c as usize].map(f32::from)
}

fn edge_mid(e: u8) -> [f32; 3] {
    let (a, b) = EDGES[e as usize];
    let (pa, pb) = (corner_pos(a), corner_pos(b));
    [0, 1, 2].map(|i| 0.5 * (pa[i] + pb[i]))
}

fn sub(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn cross(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

fn dot(a: [f32; 3], b: [f32; 3]) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn centroid(corners: impl Iterator<Item = u8>) -> [f32; 3] {
    let (mut s, mut n) = ([0.0; 3], 0.0);
    for c in corners {
        let p = corner_pos(c);
        for i in 0..3 {
            s[i] += p[i];
        }
        n += 1.0;
    }
    s.map(|v| v / n)
}

/// The directed segments `(from_edge, to_edge)` on one face, for a case.
pub fn face_segments(case: u8, face: usize, rule: FaceRule) -> Vec<(u8, u8)> {
    let (cyc, normal) = FACES[face];
    let inside = |k: usize| case >> cyc[k % 4] & 1 == 1;
    let face_edge = |k: usize| edge_between(cyc[k % 4], cyc[(k + 1) % 4]);
    let crossing: Vec<usize> = (0..4).filter(|&k| inside(k) != inside(k + 1)).collect();
    // Pairs of face-edge positions (i, j): the segment cuts off corners i+1..=j.
    let pairs: Vec<(usize, usize)> = match crossing.len() {
        2 => vec![(crossing[0], crossing[1])],
        4 => {
            // Corners k and k+2 share a state; cut off the ones the rule separates.
            let separate_inside = rule == FaceRule::SeparateInside;
            (0..4).filter(|&k| inside(k) == separate_inside).map(|k| ((k + 3) % 4, k)).collect()
        }
        _ => vec![],
    };
    let n = normal.map(f32::from);
    pairs
        .into_iter()
        .map(|(i, j)| {
            let span = (j + 4 - i) % 4;
            let side_a: Vec<u8> = (1..=span).map(|s| cyc[(i + s) % 4]).collect();
            let side_b: Vec<u8> = cyc.iter().copied().filter(|c| !side_a.contains(c)).collect();
            let a_inside = case >> side_a[0] & 1 == 1;
            let (from_in, to_out) = if a_inside { (&side_a, &side_b) } else { (&side_b, &side_a) };
            let d = sub(centroid(to_out.iter().copied()), centroid(from_in.iter().copied()));
            let (ea, eb) = (face_edge(i), face_edge(j));
            if dot(cross(n, sub(edge_mid(eb), edge_mid(ea))), d) > 0.0 {
                (ea, eb)
            } else {
                (eb, ea)
            }
        })
        .collect()
}

/// The polygons of a case: its crossing edges' mask, each crossing edge's successor around its
/// polygon, and the polygons as cycles of edge numbers (in edge order of their first edge);
/// `rule(case, face)` resolves each ambiguous face.
pub fn chain_polygons(case: u8, rule: impl Fn(u8, usize) -> FaceRule) -> (u16, [u8; 12], Vec<Vec<u8>>) {
    let mut next = [u8::MAX; 12];
    let mut edge_mask = 0u16;
    for face in 0..6 {
        for (a, b) in face_segments(case, face, rule(case, face)) {
            debug_assert_eq!(next[a as usize], u8::MAX, "case {case}: edge {a} has two successors");
            next[a as usize] = b;
            edge_mask |= 1 << a | 1 << b;
        }
    }
    let mut visited = 0u16;
    let mut polygons = Vec::new();
    for start in 0..12u8 {
        if edge_mask >> start & 1 == 0 || visited >> start & 1 == 1 {
            continue;
        }
        let mut polygon = Vec::with_capacity(12);
        let mut e = start;
        while visited >> e & 1 == 0 {
            visited |= 1 << e;
            polygon.push(e);
            e = next[e as usize];
        }
        polygons.push(polygon);
    }
    (edge_mask, next, polygons)
}

/// The triangles fanning `polygon` around the interior vertex `centre` (`12 + piece`).
pub fn fan_around(polygon: &[u8], centre: u8) -> impl Iterator<Item = [u8; 3]> + '_ {
    (0..polygon.len()).map(move |k| [polygon[k], polygon[(k + 1) % polygon.len()], centre])
}

/// Builds one table entry; `rule(case, face)` resolves each ambiguous face.
pub fn generate_case(case: u8, rule: impl Fn(u8, usize) -> FaceRule) -> Case {
    let (edge_mask, next, polygons) = chain_polygons(case, rule);
    let mut triangles = [[0u8; 3]; MAX_TRIANGLES];
    let mut count = 0;
    let mut edge_polygon = [u8::MAX; 12];
    let mut interior = 0u8;
    for (piece, polygon) in polygons.iter().enumerate() {
        for &e in polygon {
            edge_polygon[e as usize] = piece as u8;
        }
        let triangulation = triangulate(polygon).unwrap_or_else(|| {
            interior |= 1 << piece;
            fan_around(polygon, 12 + piece as u8).collect()
        });
        for t in triangulation {
            triangles[count] = t;
            count += 1;
        }
    }
    Case { edge_mask, count: count as u8, triangles, polygons: polygons.len() as u8, edge_polygon, next, interior }
}

/// The face cube edges `a` and `b` both lie on, if any (two edges share at most one face).
pub(crate) fn common_face(a: u8, b: u8) -> Option<usize> {
    FACES.iter().position(|(cyc, _)| {
        let on = |e: u8| {
            let (p, q) = EDGES[e as usize];
            cyc.contains(&p) && cyc.contains(&q)
        };
        on(a) && on(b)
    })
}

/// Whether cube edges `a` and `b` lie on a common face.
pub(crate) fn share_face(a: u8, b: u8) -> bool {
    common_face(a, b).is_some()
}

/// Triangulates a polygon of edge vertices so that no diagonal joins two vertices on a common cube
/// face. Such a diagonal would lie on (or cut through) the face, where the neighbouring cell may
/// place its own edge between the same two vertices: the edge would then have four triangles.
/// Among the valid triangulations, the first found trying fans early that never folds onto
/// itself ([`never_crosses`]) is taken.
pub(crate) fn triangulate(polygon: &[u8]) -> Option<Vec<[u8; 3]>> {
    /// Each polygon's triangulation, once chosen (the face-choice tables meet the same polygons
    /// many times).
    type Chosen = std::collections::HashMap<Vec<u8>, Option<Vec<[u8; 3]>>>;
    static CHOSEN: LazyLock<std::sync::Mutex<Chosen>> = LazyLock::new(Default::default);
    if let Some(known) = CHOSEN.lock().unwrap_or_else(std::sync::PoisonError::into_inner).get(polygon) {
        return known.clone();
    }
    // First no diagonal on any face; failing that (some joined ambiguous faces need one), diagonals
    // only on the cell's upper faces (z = 1, y = 1, x = 1). A neighbour meets such a face as its
    // lower face, where it never draws one, so no edge can gain four triangles.
    let on_no_face = |a: u8, b: u8| !share_face(a, b);
    let on_upper_faces = |a: u8, b: u8| common_face(a, b).is_none_or(|f| f % 2 == 1);
    let draws = crowded_draws(polygon);
    let chosen = [&on_no_face as &dyn Fn(u8, u8) -> bool, &on_upper_faces].into_iter().find_map(|allowed| {
        let mut first = None;
        let safe = triangulate_with(polygon, allowed, &mut |t: &[[u8; 3]]| {
            first.get_or_insert_with(|| t.to_vec());
            never_crosses(t, &draws)
        });
        safe.or(first)
    });
    CHOSEN.lock().unwrap_or_else(std::sync::PoisonError::into_inner).insert(polygon.to_vec(), chosen.clone());
    chosen
}

/// Every valid triangulation of `polygon` in turn, fans from its first vertex first, until
/// `accept` takes one.
fn triangulate_with(
    polygon: &[u8],
    allowed: &dyn Fn(u8, u8) -> bool,
    accept: &mut dyn FnMut(&[[u8; 3]]) -> bool,
) -> Option<Vec<[u8; 3]>> {
    // Splits the polygons in `todo` one at a time: the triangle on the first one's closing edge
    // (p[0], p[n-1]) has apex p[k], and its two other sides are diagonals unless polygon edges.
    fn rec(
        todo: &mut Vec<Vec<u8>>,
        out: &mut Vec<[u8; 3]>,
        allowed: &dyn Fn(u8, u8) -> bool,
        accept: &mut dyn FnMut(&[[u8; 3]]) -> bool,
    ) -> bool {
        let Some(p) = todo.pop() else { return accept(out) };
        let n = p.len();
        if n < 3 {
            let done = rec(todo, out, allowed, accept);
            todo.push(p);
            return done;
        }
        for k in (1..n - 1).rev() {
            let ok_left = k == 1 || allowed(p[0], p[k]);
            let ok_right = k == n - 2 || allowed(p[k], p[n - 1]);
            if !(ok_left && ok_right) {
                continue;
            }
            let mark = (out.len(), todo.len());
            out.push([p[0], p[k], p[n - 1]]);
            todo.push(p[k..].to_vec());
            todo.push(p[..=k].to_vec());
            if rec(todo, out, allowed, accept) {
                return true;
            }
            out.truncate(mark.0);
            todo.truncate(mark.1);
        }
        todo.push(p);
        false
    }
    let mut out = Vec::with_capacity(polygon.len() - 2);
    let mut todo = vec![polygon.to_vec()];
    rec(&mut todo, &mut out, allowed, accept).then_some(out)
}

/// Draws of the polygon's vertex positions (one per cube edge, `12` slots) for [`never_crosses`]:
/// each crossing at `a / (a + b)` of its edge for corner distances `a` and `b` from the
/// iso-value drawn over six orders of magnitude, so that crossings crowd corners at unequal
/// rates (where a fan of a skew polygon can fold over itself), seeded by the polygon.
pub(crate) fn crowded_draws(polygon: &[u8]) -> Vec<[glam::Vec3; 12]> {
    if polygon.len() < 5 {
        return Vec::new();
    }
    let seed = polygon.iter().fold(0x9e37_79b9_u64, |h, &e| h.wrapping_mul(31).wrapping_add(u64::from(e)));
    let mut random = crate::random::Random::new(seed);
    let mut distance = move || {
        let u = random.unit_f32();
        if random.next_u64() % 3 == 0 {
            0.5 + u
        } else {
            10f32.powf(-6.0 * u)
        }
    };
    (0..CROWDED_DRAWS)
        .map(|_| {
            std::array::from_fn(|e| {
                let (a, b) = EDGES[e];
                let (da, db) = (distance(), distance());
                let (pa, pb) = (glam::Vec3::from(corner_pos(a)), glam::Vec3::from(corner_pos(b)));
                pa + (pb - pa) * (da / (da + db))
            })
        })
        .collect()
}

/// Draws per polygon of five or more vertices: a fold that appears in one cell in ten (the rate
/// of the fans this replaces) is missed with odds below one in ten thousand.
const CROWDED_DRAWS: usize = 96;

/// Whether no two triangles of `t` (cube edge numbers) cross in any of `draws`: only triangles
/// that share at most a vertex can, so pairs sharing a side are skipped.
pub(crate) fn never_crosses(t: &[[u8; 3]], draws: &[[glam::Vec3; 12]]) -> bool {
    draws.iter().all(|at| !crosses_at(t, at))
}

/// Whether two triangles of `t` (vertex slots into `at`) that share at most a vertex cross at
/// positions `at`.
pub(crate) fn crosses_at(t: &[[u8; 3]], at: &[glam::Vec3]) -> bool {
    (0..t.len()).any(|i| {
        (i + 1..t.len()).any(|j| {
            let shared = t[i].iter().filter(|v| t[j].contains(v)).count();
            shared < 2
                && crate::predicates::indexed_triangles_intersect(t[i].map(u32::from), t[j].map(u32::from), |v| at[v as usize])
        })
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn edge_masks_are_exactly_the_sign_changes() {
        for (c, case) in TABLE.iter().enumerate() {
            for (e, &(a, b)) in EDGES.iter().enumerate() {
                let crosses = (c >> a & 1) != (c >> b & 1);
                assert_eq!(case.edge_mask >> e & 1 == 1, crosses, "case {c} edge {e}");
            }
        }
    }

    #[test]
    fn complements_have_as_many_triangles_or_differ_only_on_ambiguous_faces() {
        assert_eq!(TABLE[0].count, 0);
        assert_eq!(TABLE[255].count, 0);
        assert_eq!(TABLE[1].count, 1);
        assert_eq!(TABLE[254].count, 1);
        // Case 3 (corners 0 and 1): one quad, two triangles.
        assert_eq!(TABLE[3].count, 2);
        // Case 5 (corners 0 and 2, diagonal on the bottom face): inside corners separated.
        assert_eq!(TABLE[5].count, 2);
        // Its complement (corners 0 and 2 outside): the six-sided tube, four triangles.
        assert_eq!(TABLE[250].count, 4);
    }

    #[test]
    fn no_triangle_side_joins_two_vertices_of_a_face_unless_it_is_a_face_segment() {
        for (c, case) in TABLE.iter().enumerate() {
            let segments: Vec<(u8, u8)> = (0..6).flat_map(|f| face_segments(c as u8, f, FaceRule::SeparateInside)).collect();
            for t in case.triangles() {
                for k in 0..3 {
                    let (a, b) = (t[k], t[(k + 1) % 3]);
                    if share_face(a, b) {
                        assert!(segments.iter().any(|&(p, q)| (p, q) == (a, b) || (p, q) == (b, a)), "case {c}: side {a}-{b}");
                    }
                }
            }
        }
    }

    #[test]
    fn polygons_cover_the_crossing_edges() {
        for (c, case) in TABLE.iter().enumerate() {
            for e in 0..12 {
                let crosses = case.edge_mask >> e & 1 == 1;
                assert_eq!(case.edge_polygon[e] != u8::MAX, crosses, "case {c} edge {e}");
                assert!(!crosses || case.edge_polygon[e] < case.polygons);
            }
            // Every triangle's edges belong to one polygon.
            for t in case.triangles() {
                assert!(t.iter().all(|&e| case.edge_polygon[e as usize] == case.edge_polygon[t[0] as usize]));
            }
        }
        assert_eq!(TABLE[5].polygons, 2);
        assert_eq!(TABLE[250].polygons, 1);
    }

    #[test]
    fn every_face_choice_gives_a_consistent_table() {
        for i in 0..256 * 64 {
            let case = &FACE_CHOICE_TABLE[i];
            let c = i / 64;
            assert_eq!(case.edge_mask, TABLE[c].edge_mask, "case {c}");
            if i % 64 == 0 {
                assert_eq!(case, &TABLE[c]);
            }
        }
        assert!(TABLE.iter().all(|c| c.interior == 0), "the default table needs no interior vertex");
        // Case 5 (corners 0 and 2 inside): the bottom face (face 0) is ambiguous.
        assert_eq!(AMBIGUOUS_FACES[5], 1);
        assert_eq!(FACE_CHOICE_TABLE[5 * 64].polygons, 2);
        assert_eq!(FACE_CHOICE_TABLE[5 * 64 + 1].polygons, 1, "joined: one tube");
    }

    #[test]
    fn decider_follows_the_saddle() {
        // Inside corners 0 and 2 strongly inside: the saddle is inside, they join.
        assert!(decider_joins_inside([-1.0, 0.5, -1.0, 0.5]));
        assert!(!decider_joins_inside([-0.5, 1.0, -0.5, 1.0]));
    }

    #[test]
    fn single_corner_triangle_faces_away_from_the_corner() {
        // Corner 0 inside: the triangle's normal must point toward +x+y+z (away from corner 0).
        let t = TABLE[1].triangles()[0].map(edge_mid);
        let n = cross(sub(t[1], t[0]), sub(t[2], t[0]));
        assert!(dot(n, [1.0, 1.0, 1.0]) > 0.0, "{n:?}");
    }
}
