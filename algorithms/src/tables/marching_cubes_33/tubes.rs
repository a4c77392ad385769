//! Tubes: the band of triangles that joins two loops of a cell where the trilinear interpolant
//! tunnels between them (see the parent module's "Origin"), the search over bands and the runs
//! of a band fanned around the cell's centre vertex.

use crate::tables::marching_cubes::{common_face, crowded_draws, never_crosses, share_face};

/// Most band triangulations tried for one that never crosses itself before the first valid one
/// is taken.
const BAND_TRIES: usize = 400;

/// The tube between directed loops `a` and `b`, wound as the two discs it replaces were (each
/// loop side used once, in its loop's direction). First a band of `a.len() + b.len()` triangles
/// whose sides between the loops keep off the cube faces, the first that never crosses itself on
/// seeded corner-crowding draws (else the first valid one); failing that, as the polygon
/// triangulations do, sides on the cell's upper faces only (a neighbour meets those as lower
/// faces, where it draws none). Failing both (a tunnel of the outside between two corners that
/// joined faces separate), a band whose sides on faces all lie in one run of its triangles, that
/// run fanned around the cell's interior vertex `centre` instead (as Lewiner et al.'s case 6.1.2
/// is): no side of the tube then lies on a face. Failing all three, no tube.
fn tube(a: &[u8], b: &[u8], centre: u8) -> Option<Vec<[u8; 3]>> {
    band_with(a, b, &off_faces).or_else(|| band_with(a, b, &off_lower_faces)).or_else(|| centred_band(a, b, centre))
}

/// A side between two loops that lies on no cube face.
fn off_faces(p: u8, q: u8) -> bool {
    !share_face(p, q)
}

/// A side between two loops that lies on no lower cube face (`z = 0`, `y = 0`, `x = 0`).
fn off_lower_faces(p: u8, q: u8) -> bool {
    common_face(p, q).is_none_or(|f| f % 2 == 1)
}

/// Any side.
fn anywhere(_: u8, _: u8) -> bool {
    true
}

/// Most tube triangulations kept for one tunnel, and most bands they are made from.
const TUBE_VARIANTS: usize = 256;
const TUBE_BANDS: usize = 64;

/// The tube triangulations between loops `a` and `b` a cell chooses from, its own vertex positions
/// deciding ([`entry`]): [`tube`]'s first, then other valid bands (sides off the faces, failing
/// that off the lower faces), then those bands with a run of their triangles fanned around the
/// centre vertex `centre` (Lewiner et al.'s case 6.1.2 tube has that vertex); where only a
/// centred tube exists, its runs. Empty when there is no tube.
pub(super) fn tubes(a: &[u8], b: &[u8], centre: u8) -> Vec<Vec<[u8; 3]>> {
    let Some(first) = tube(a, b, centre) else {
        return Vec::new();
    };
    let mut bands = band_list(a, b, &off_faces, TUBE_BANDS);
    if bands.is_empty() {
        bands = band_list(a, b, &off_lower_faces, TUBE_BANDS);
    }
    let plain = !bands.is_empty();
    if !plain {
        bands = band_list(a, b, &anywhere, TUBE_BANDS);
    }
    let mut out = vec![first];
    if plain {
        out.extend(bands.iter().cloned());
    }
    for band in &bands {
        out.extend(fan_runs(band, centre));
    }
    let mut seen = std::collections::HashSet::new();
    out.retain(|t| {
        let mut key = t.clone();
        key.sort_unstable();
        seen.insert(key)
    });
    out.truncate(TUBE_VARIANTS);
    out
}

/// Up to `limit` bands between loops `a` and `b` whose sides between the loops are all
/// `allowed`.
fn band_list(a: &[u8], b: &[u8], allowed: &dyn Fn(u8, u8) -> bool, limit: usize) -> Vec<Vec<[u8; 3]>> {
    let (m, n) = (a.len(), b.len());
    let mut out = Vec::new();
    let mut band = Vec::with_capacity(m + n);
    for i0 in 0..m {
        for j0 in 0..n {
            if allowed(a[i0], b[j0]) {
                walk((a, b), (i0, j0 + n), (m, n), 1 << (i0 * n + j0), allowed, &mut band, &mut |t| {
                    out.push(t.to_vec());
                    out.len() >= limit
                });
            }
            if out.len() >= limit {
                return out;
            }
        }
    }
    out
}

/// A band between loops `a` and `b` with its sides on cube faces replaced by a fan around
/// `centre` (those on lower faces: sides on upper faces are allowed as above) over the shortest
/// run of band triangles that holds them all inside it (the run's outline a simple polygon, so
/// `centre` has one ring of neighbours).
fn centred_band(a: &[u8], b: &[u8], centre: u8) -> Option<Vec<[u8; 3]>> {
    let mut found = None;
    let mut band = Vec::with_capacity(a.len() + b.len());
    let (m, n) = (a.len(), b.len());
    'start: for i0 in 0..m {
        for j0 in 0..n {
            if walk((a, b), (i0, j0 + n), (m, n), 1 << (i0 * n + j0), &anywhere, &mut band, &mut |t| {
                found = fan_run(t, centre);
                found.is_some()
            }) {
                break 'start;
            }
        }
    }
    found
}

/// `band` (triangles in order around the tube; triangle `k`'s sides `(t[1], t[2])` and the
/// previous triangle's are its two sides between the loops) with the shortest run of triangles
/// that holds every side on a lower cube face strictly inside it fanned around `centre`; `None`
/// when no such run leaves its outline a simple polygon.
fn fan_run(band: &[[u8; 3]], centre: u8) -> Option<Vec<[u8; 3]>> {
    fan_runs(band, centre).into_iter().next()
}

/// Every way [`fan_run`] allows of fanning a run of `band` around `centre`, shortest run first.
fn fan_runs(band: &[[u8; 3]], centre: u8) -> Vec<Vec<[u8; 3]>> {
    let mut runs = Vec::new();
    let n = band.len();
    let side = |k: usize| {
        let t = band[k % n];
        (t[1], t[2])
    };
    // Sides on the cell's upper faces are allowed, as in the bands above.
    let on_face = |k: usize| {
        let (p, q) = side(k);
        !off_lower_faces(p, q)
    };
    for len in 1..n {
        for start in 0..n {
            // The run is triangles start..start+len; its inner sides are start..start+len-1
            // (side k between triangles k and k+1), its outer ones start-1 and start+len-1.
            let inner_ok = (0..n).filter(|&k| on_face(k)).all(|k| (0..len - 1).any(|d| (start + d) % n == k));
            if !inner_ok || on_face(start + n - 1) || on_face(start + len - 1) {
                continue;
            }
            let run: Vec<[u8; 3]> = (0..len).map(|d| band[(start + d) % n]).collect();
            let mut outline: Vec<(u8, u8)> = run
                .iter()
                .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
                .filter(|&(p, q)| !run.iter().flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])]).any(|e| e == (q, p)))
                .collect();
            let mut corners: Vec<u8> = outline.iter().map(|e| e.0).collect();
            corners.sort_unstable();
            corners.dedup();
            if corners.len() != outline.len() {
                continue;
            }
            let mut out: Vec<[u8; 3]> = (len..n).map(|d| band[(start + d) % n]).collect();
            out.extend(outline.drain(..).map(|(p, q)| [p, q, centre]));
            runs.push(out);
        }
    }
    runs
}

fn band_with(a: &[u8], b: &[u8], allowed: &dyn Fn(u8, u8) -> bool) -> Option<Vec<[u8; 3]>> {
    let (m, n) = (a.len(), b.len());
    let joined: Vec<u8> = a.iter().chain(b).copied().collect();
    let draws = crowded_draws(&joined);
    let (mut first, mut tries) = (None, 0);
    let mut band = Vec::with_capacity(m + n);
    for i0 in 0..m {
        for j0 in 0..n {
            if !allowed(a[i0], b[j0]) {
                continue;
            }
            let found = walk((a, b), (i0, j0 + n), (m, n), 1 << (i0 * n + j0), allowed, &mut band, &mut |t| {
                first.get_or_insert_with(|| t.to_vec());
                tries += 1;
                tries > BAND_TRIES || never_crosses(t, &draws)
            });
            if found {
                return Some(if tries > BAND_TRIES { first.expect("a valid band was seen") } else { band });
            }
        }
    }
    first
}

/// Extends `band` between `loops` `(a, b)` from state `(i, j)` (the side `a[i]`–`b[j]`, indices modulo the loop lengths)
/// with `left.0` more steps along `a` (forward) and `left.1` along `b` (backward), until `accept`
/// takes a finished band. `seen` holds the sides between the loops already drawn (bit
/// `i * b.len() + j`): a side drawn twice would pinch the tube.
fn walk(
    loops @ (a, b): (&[u8], &[u8]),
    (i, j): (usize, usize),
    left: (usize, usize),
    seen: u64,
    allowed: &dyn Fn(u8, u8) -> bool,
    band: &mut Vec<[u8; 3]>,
    accept: &mut dyn FnMut(&[[u8; 3]]) -> bool,
) -> bool {
    let (m, n) = (a.len(), b.len());
    if left == (0, 0) {
        return accept(band);
    }
    let last = left.0 + left.1 == 1;
    let side = |i: usize, j: usize| 1u64 << ((i % m) * n + j % n);
    let open = |i: usize, j: usize| last || (seen & side(i, j) == 0 && allowed(a[i % m], b[j % n]));
    let (ai, bj) = (a[i % m], b[j % n]);
    if left.0 > 0 && open(i + 1, j) {
        band.push([ai, a[(i + 1) % m], bj]);
        if walk(loops, (i + 1, j), (left.0 - 1, left.1), seen | side(i + 1, j), allowed, band, accept) {
            return true;
        }
        band.pop();
    }
    if left.1 > 0 && open(i, j + n - 1) {
        band.push([bj, ai, b[(j + n - 1) % n]]);
        if walk(loops, (i, j + n - 1), (left.0, left.1 - 1), seen | side(i, j + n - 1), allowed, band, accept) {
            return true;
        }
        band.pop();
    }
    false
}

/// The two halves of the tubes between loops `a` and `b` drawn through a ring of three interior
/// vertices (slots `ring`, in positive turn around the axis from `a` to `b` as
/// [`super::waist::ring`] places them): for each turn of the ring (the loops' winding decides
/// which fits), every distinct band from `a` to the ring and every one from the ring to `b`. A
/// tube is one of each; each ring side is then used once each way, so it stays a wound annulus.
pub(super) fn ring_halves(a: &[u8], b: &[u8], ring: [u8; 3]) -> [RingHalves; 2] {
    [ring, [ring[0], ring[2], ring[1]]].map(|ring| {
        let back = [ring[0], ring[2], ring[1]];
        RingHalves {
            upper: distinct(band_list(a, &ring, &anywhere, usize::MAX)),
            lower: distinct(band_list(&back, b, &anywhere, usize::MAX)),
        }
    })
}

/// The bands on each side of a waist ring ([`ring_halves`]).
pub(super) struct RingHalves {
    /// From the first loop to the ring.
    pub upper: Vec<Vec<[u8; 3]>>,
    /// From the ring to the second loop.
    pub lower: Vec<Vec<[u8; 3]>>,
}

/// `bands` without repeats (the same triangles walked from another start).
fn distinct(mut bands: Vec<Vec<[u8; 3]>>) -> Vec<Vec<[u8; 3]>> {
    let mut seen = std::collections::HashSet::new();
    bands.retain(|t| {
        let mut key = t.clone();
        key.sort_unstable();
        seen.insert(key)
    });
    bands
}
