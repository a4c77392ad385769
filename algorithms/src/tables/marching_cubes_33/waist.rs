//! The waist of a tunnel: three points of the trilinear interpolant's level set around the
//! tunnel at its narrowest place, the ring a tube is drawn through where no tube fanned around
//! one interior vertex keeps off itself (see the parent module's "Origin").
//!
//! A tunnel through a cell passes a **body saddle** of the trilinear interpolant, a point where
//! its gradient vanishes (Nielson 2003, "On marching cubes", IEEE TVCG 9(3), DOI
//! 10.1109/TVCG.2003.1207437: the interior ambiguity is decided there). With
//! `f = a0 + a1 x + a2 y + a3 z + a4 xy + a5 xz + a6 yz + a7 xyz`, the gradient's first two
//! components give `x` and `y` as functions of `z`, and the third becomes the quadratic
//! `a7 K z² + 2 a4 K z + a3 a4² − a2 a4 a5 − a1 a4 a6 + a1 a2 a7 = 0` with
//! `K = a3 a7 − a5 a6`. From the saddle, three rays at 120° in the plane across the tunnel's axis
//! each meet the level set (bisection on the exact trilinear value): the ring. A tube through it
//! is a band from each loop to the ring ([`through_waist`]).

use super::tubes::{ring_halves, RingHalves};
use super::{
    assemble, chain_polygons, face_rule, meets_at, Candidate, CellEntry, CellFrame, Placed, FACE_CHOICE_TABLE, MAX_TRIANGLES,
};
use crate::tables::marching_cubes::Case;
use glam::{DVec3, Vec3};
use std::collections::HashMap;
use std::sync::{Arc, LazyLock, Mutex, PoisonError};

/// The trilinear interpolant's coefficients `[a0, .., a7]` for corner values `g` (corner order
/// of [`super::super::marching_cubes::CORNERS`]).
fn coefficients(g: &[f64; 8]) -> [f64; 8] {
    let [g000, g100, g110, g010, g001, g101, g111, g011] = *g;
    [
        g000,
        g100 - g000,
        g010 - g000,
        g001 - g000,
        g110 - g100 - g010 + g000,
        g101 - g100 - g001 + g000,
        g011 - g010 - g001 + g000,
        g111 - g110 - g101 - g011 + g100 + g010 + g001 - g000,
    ]
}

/// The trilinear interpolant of corner values `g` at cell-local point `p`.
pub(super) fn trilinear(g: &[f64; 8], p: DVec3) -> f64 {
    let a = coefficients(g);
    let (x, y, z) = (p.x, p.y, p.z);
    a[0] + a[1] * x + a[2] * y + a[3] * z + a[4] * x * y + a[5] * x * z + a[6] * y * z + a[7] * x * y * z
}

/// The points strictly inside the cell where the interpolant's gradient vanishes (none, one or
/// two; none when the quadratic degenerates).
pub(super) fn body_saddles(g: &[f64; 8]) -> Vec<DVec3> {
    let a = coefficients(g);
    let k = a[3] * a[7] - a[5] * a[6];
    let (qa, qb, qc) =
        (a[7] * k, 2.0 * a[4] * k, a[3] * a[4] * a[4] - a[2] * a[4] * a[5] - a[1] * a[4] * a[6] + a[1] * a[2] * a[7]);
    let scale = a.iter().fold(0.0f64, |m, v| m.max(v.abs())).powi(3);
    let heights: Vec<f64> = if qa.abs() > 1e-12 * scale {
        let disc = qb * qb - 4.0 * qa * qc;
        if disc < 0.0 {
            return Vec::new();
        }
        let root = disc.sqrt();
        vec![(-qb - root) / (2.0 * qa), (-qb + root) / (2.0 * qa)]
    } else if qb.abs() > 1e-12 * scale {
        // `a7 K = 0`: the quadratic is linear.
        vec![-qc / qb]
    } else {
        return Vec::new();
    };
    heights
        .into_iter()
        .filter_map(|z| {
            let p = a[4] + a[7] * z;
            (p != 0.0).then(|| DVec3::new(-(a[2] + a[6] * z) / p, -(a[1] + a[5] * z) / p, z))
        })
        .filter(|s| s.cmpgt(DVec3::ZERO).all() && s.cmplt(DVec3::ONE).all())
        .collect()
}

/// How far from `from` along `dir` the ray stays in the closed cell.
fn exit_distance(from: DVec3, dir: DVec3) -> f64 {
    (0..3)
        .map(|i| match dir[i] {
            d if d > 0.0 => (1.0 - from[i]) / d,
            d if d < 0.0 => -from[i] / d,
            _ => f64::INFINITY,
        })
        .fold(f64::INFINITY, f64::min)
}

/// Where a ray leaves the cell before it meets the level set, the ring point is this far along
/// it (a fraction of the way to the cell's face).
const RIM: f64 = 0.9;

/// The ring around a tunnel of the sign `inside` (negative values) for corner values `g` (minus
/// the iso-value), across `axis` (from one of the tunnel's loops to the other): three level-set
/// points, in positive turn around `axis` (where the tube is wider than the cell, a point short
/// of the face instead, [`RIM`]). `None` where no body saddle has the tunnel's sign.
pub(super) fn ring(g: &[f64; 8], inside: bool, axis: Vec3) -> Option<[Vec3; 3]> {
    let axis = axis.as_dvec3().try_normalize()?;
    let has = |v: f64| (v < 0.0) == inside;
    let u = axis.any_orthonormal_vector();
    let v = axis.cross(u);
    body_saddles(g).into_iter().filter(|&s| has(trilinear(g, s))).find_map(|s| {
        let mut out = [Vec3::ZERO; 3];
        for (k, slot) in out.iter_mut().enumerate() {
            let angle = std::f64::consts::TAU * k as f64 / 3.0;
            let dir = angle.cos() * u + angle.sin() * v;
            let (mut lo, mut hi) = (0.0, exit_distance(s, dir));
            if has(trilinear(g, s + hi * dir)) {
                // The tube is wider than the cell this way: the ring point stays just inside.
                lo = RIM * hi;
                hi = lo;
            }
            for _ in 0..60 {
                let mid = 0.5 * (lo + hi);
                if has(trilinear(g, s + mid * dir)) {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            let p = (s + 0.5 * (lo + hi) * dir).as_vec3();
            // Strictly inside the cell, as every interior vertex is.
            if !(p.cmpgt(Vec3::ZERO).all() && p.cmplt(Vec3::ONE).all()) {
                return None;
            }
            *slot = p;
        }
        Some(out)
    })
}

/// The halves of each waist-ring tube, and the triangles of the entry's other polygons, per
/// (pattern, face choices, tunnel), built when a cell first needs them.
struct Waist {
    /// The ring's slots.
    slots: [u8; 3],
    /// Per turn of the ring.
    halves: [RingHalves; 2],
    /// The other polygons' triangles.
    others: Vec<[u8; 3]>,
    /// The entry's crossing edges, successors and polygons ([`chain_polygons`]).
    chained: (u16, [u8; 12], Vec<Vec<u8>>),
}

/// [`Waist`]s built so far, by (table key, tunnel): few cells need one, so a map.
static WAISTS: LazyLock<Mutex<HashMap<TunnelKey, Option<Arc<Waist>>>>> = LazyLock::new(Default::default);

/// A tunnel of a table entry: (table key `case * 64 + joins`, index among its candidates).
type TunnelKey = (usize, usize);

/// A waist tube of a tunnel: (its [`TunnelKey`], turn of the ring, upper band, lower band).
type WaistKey = (TunnelKey, usize, usize, usize);

/// Entries of waist-ring tubes chosen so far, by (table key, tunnel, turn, upper band, lower
/// band): made when first chosen and kept for the process (at most one per combination).
static WAIST_ENTRIES: LazyLock<Mutex<HashMap<WaistKey, &'static Case>>> = LazyLock::new(Default::default);

/// A tube through the tunnel's waist for a cell (key and tunnel index `k` into [`TABLES`]) at
/// `frame` whose vertex positions are `at`: the ring placed ([`ring`]), then the first pair of halves
/// ([`ring_halves`]) that keeps off itself and the cell's other triangles. `None` where the
/// entry has no room for a ring, there is no waist, or no pair keeps off.
pub(super) fn through_waist(
    case: u8,
    joins: u8,
    g: &[f64; 8],
    (key, k): (usize, usize),
    tunnel: Candidate,
    frame: &CellFrame,
    at: &mut [glam::Vec3; 16],
) -> Option<CellEntry> {
    let waist = WAISTS
        .lock()
        .unwrap_or_else(PoisonError::into_inner)
        .entry((key, k))
        .or_insert_with(|| {
            let slots = ring_slots(case, joins, tunnel.polygons)?;
            let (edge_mask, next, polygons) = chain_polygons(case, face_rule(joins));
            let (p, q) = tunnel.polygons;
            let others = assemble(case, (edge_mask, next, &polygons), Some(((p, q), &[]))).triangles().to_vec();
            let halves = ring_halves(&polygons[p as usize], &polygons[q as usize], slots);
            Some(Arc::new(Waist { slots, halves, others, chained: (edge_mask, next, polygons) }))
        })
        .clone()?;
    let (edge_mask, next, polygons) = &waist.chained;
    let centroid =
        |p: u8| polygons[p as usize].iter().map(|&e| at[e as usize]).sum::<glam::Vec3>() / polygons[p as usize].len() as f32;
    let inside = case >> tunnel.corners.0 & 1 == 1;
    let ring = ring(g, inside, centroid(tunnel.polygons.1) - centroid(tunnel.polygons.0))?;
    let mut placed = Placed::default();
    for (&slot, p) in waist.slots.iter().zip(ring) {
        at[slot as usize] = frame.place(p);
        placed.mask |= 1 << (slot - 12);
        placed.at[slot as usize - 12] = p;
    }
    // The triangles checked: the bands' first, the other polygons' after (one buffer).
    let mut checked: Vec<[u8; 3]> = Vec::with_capacity(2 * MAX_TRIANGLES);
    let mut meets = |bands: &[&[[u8; 3]]]| {
        checked.clear();
        bands.iter().for_each(|b| checked.extend_from_slice(b));
        checked.extend_from_slice(&waist.others);
        meets_at(&checked, at)
    };
    for (turn, halves) in waist.halves.iter().enumerate() {
        let upper: Vec<usize> = (0..halves.upper.len()).filter(|&i| !meets(&[&halves.upper[i]])).collect();
        let lower: Vec<usize> = (0..halves.lower.len()).filter(|&j| !meets(&[&halves.lower[j]])).collect();
        for &i in &upper {
            for &j in &lower {
                let (u, l) = (&halves.upper[i], &halves.lower[j]);
                if u.len() + l.len() + waist.others.len() > MAX_TRIANGLES || meets(&[u, l]) {
                    continue;
                }
                let entry =
                    *WAIST_ENTRIES.lock().unwrap_or_else(PoisonError::into_inner).entry(((key, k), turn, i, j)).or_insert_with(
                        || {
                            let tube: Vec<[u8; 3]> = u.iter().chain(l).copied().collect();
                            Box::leak(Box::new(assemble(case, (*edge_mask, *next, polygons), Some((tunnel.polygons, &tube)))))
                        },
                    );
                return Some((entry, Some(placed)));
            }
        }
    }
    None
}

/// The three interior slots a tube between polygons `tunnel` of (`case`, `joins`) draws its
/// waist ring in: the highest three of the slots no other polygon's fan can take (the two
/// polygons' own, and those past the last polygon); `None` with fewer free.
fn ring_slots(case: u8, joins: u8, tunnel: (u8, u8)) -> Option<[u8; 3]> {
    let count = FACE_CHOICE_TABLE[case as usize * 64 + joins as usize].polygons;
    let free: Vec<u8> = (0..4u8).filter(|&k| k == tunnel.0 || k == tunnel.1 || k >= count).map(|k| 12 + k).collect();
    (free.len() >= 3).then(|| [free[free.len() - 3], free[free.len() - 2], free[free.len() - 1]])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_body_saddle_has_no_gradient_and_the_ring_lies_on_the_level_set() {
        // Corners 0 and 6 inside, the others outside but not by much: a thin tube along the
        // diagonal.
        let mut g = [0.3f64; 8];
        g[0] = -1.0;
        g[6] = -1.0;
        let saddles = body_saddles(&g);
        assert!(!saddles.is_empty());
        for s in &saddles {
            let h = 1e-6;
            for i in 0..3 {
                let mut d = DVec3::ZERO;
                d[i] = h;
                let slope = (trilinear(&g, *s + d) - trilinear(&g, *s - d)) / (2.0 * h);
                assert!(slope.abs() < 1e-6, "saddle {s:?}: slope {slope} along axis {i}");
            }
        }
        let ring = ring(&g, true, Vec3::ONE).expect("a ring around the diagonal tube");
        assert_eq!(saddles, [DVec3::splat(0.5)], "by symmetry, the centre");
        for p in ring {
            assert!(trilinear(&g, p.as_dvec3()).abs() < 1e-5, "{p:?} off the level set");
        }
        // In positive turn around the axis.
        let turn = (ring[1] - ring[0]).cross(ring[2] - ring[0]).dot(Vec3::ONE);
        assert!(turn > 0.0);
        // No tunnel of the outside there: the saddle is inside.
        assert!(super::ring(&g, false, Vec3::ONE).is_none());
    }
}
