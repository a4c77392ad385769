//! The geometry pass (Costen 2026, Algorithm 3): every tetrahedron with a sign change emits its
//! case's triangle or quad (split along the shorter diagonal) from the vertex pass's slots, in
//! slabs of anchor layers joined in order; triangles collapsed by clustering are counted and
//! dropped.

use super::{owns, topology, Addresser, Plan, TetCounts, TetKind, TetScratch, MT_TABLE};
use crate::extract::Extraction;
use crate::samples::Samples;
use crate::sweep::sign_rows::{range_mask, surface_cell_word};
use rayon::prelude::*;
use std::time::Instant;

/// The geometry pass (Algorithm 3) over the vertex indices in `scratch`, replacing
/// `out.surface.triangles`; sets the geometry time and the counts in `out.stats`. Records each
/// surface anchor's first triangle in `scratch`, so that a repair can re-emit only the anchors it
/// touched ([`regenerate_anchors`]).
pub fn geometry_pass(samples: &Samples, scratch: &mut TetScratch, out: &mut Extraction) -> TetCounts {
    run_geometry(samples, scratch, out, None)
}

/// After the vertex indices of the samples `changed` were rewritten (a repair), re-emits the
/// triangles of the anchors whose tetrahedra contain one of them and keeps every other anchor's
/// triangles as the last pass made them: the same triangles, in the same order, as
/// [`geometry_pass`] would make (every tetrahedron using a crossing owned by a sample contains
/// that sample). Kuhn lattices after a geometry pass on the same samples; otherwise the whole
/// pass runs again.
pub fn regenerate_anchors(samples: &Samples, scratch: &mut TetScratch, out: &mut Extraction, changed: &[usize]) -> TetCounts {
    let lattice = *samples.lattice();
    let dims = lattice.grid().dims;
    if TetKind::of(&lattice) != TetKind::Kuhn || !scratch.anchors_valid || !scratch.signs.holds(dims) {
        return run_geometry(samples, scratch, out, None);
    }
    // The cubes around each changed corner sample, by their low corner's flat index.
    let grid = lattice.grid();
    let mut affected = std::mem::take(&mut scratch.affected);
    affected.clear();
    for &i in changed {
        let (x, y, z) = (i % dims[0], (i / dims[0]) % dims[1], i / (dims[0] * dims[1]));
        for (a, b, c) in (0..8).map(|k| (k & 1, k >> 1 & 1, k >> 2)) {
            let (cx, cy, cz) = (x.wrapping_sub(a), y.wrapping_sub(b), z.wrapping_sub(c));
            if cx + 1 < dims[0] && cy + 1 < dims[1] && cz + 1 < dims[2] {
                affected.push(grid.index(cx, cy, cz) as u32);
            }
        }
    }
    affected.sort_unstable();
    affected.dedup();
    let counts = run_geometry(samples, scratch, out, Some(&affected));
    scratch.affected = affected;
    counts
}

/// The geometry pass over every anchor (`only: None`) or, re-using the last pass's triangles
/// elsewhere, over the anchors `only` (sorted flat indices).
fn run_geometry(samples: &Samples, scratch: &mut TetScratch, out: &mut Extraction, only: Option<&[u32]>) -> TetCounts {
    let (mut anchors, mut next) = (std::mem::take(&mut scratch.anchors), std::mem::take(&mut scratch.next_triangles));
    let mut rewritten = std::mem::take(&mut scratch.rewritten);
    rewritten.clear();
    let counts = geometry_with(samples, scratch, out, only, &mut anchors, &mut next, &mut rewritten);
    (scratch.anchors, scratch.next_triangles, scratch.anchors_valid) = (anchors, next, true);
    (scratch.rewritten, scratch.rewritten_valid) = (rewritten, only.is_some());
    counts
}

/// [`run_geometry`] with the anchors' record, the spare triangle buffer and the list of
/// rewritten vertices (filled by a partial pass) held apart.
fn geometry_with(
    samples: &Samples,
    scratch: &TetScratch,
    out: &mut Extraction,
    only: Option<&[u32]>,
    anchors: &mut Vec<(u32, u32)>,
    next: &mut Vec<[u32; 3]>,
    rewritten: &mut Vec<u32>,
) -> TetCounts {
    let lattice = *samples.lattice();
    let topo = topology(TetKind::of(&lattice));
    let at = Addresser::new(&lattice);
    let made_here;
    let plan = match &scratch.plan {
        Some(plan) if plan.fits(&lattice) => plan,
        _ => {
            made_here = Plan::new(&lattice);
            &made_here
        }
    };
    let layout = &plan.layout;
    let values = samples.values();
    let iso = samples.iso();
    let t = Instant::now();
    let mut counts = TetCounts::default();
    let vertex_of = |a: usize, va: f32, b: usize, vb: f32, dir_ab: u8| -> u32 {
        let (o, k) = if owns(a, va, b, vb, iso) { (a, dir_ab) } else { (b, dir_ab ^ 1) };
        scratch.base[o] + ((scratch.slots[o] >> (4 * k)) & 0xf) as u32
    };
    // Anchors: BCC cell centres (every tetrahedron around a centre contains it), or cubes' low
    // corners (every Kuhn tetrahedron of a cube contains it). An anchor with no sign change on
    // its edges has no surface in any of its tetrahedra.
    let anchor_part = match topo.kind {
        TetKind::Bcc => &layout.parts[1],
        TetKind::Kuhn => &layout.parts[0],
    };
    let anchor_dims = match topo.kind {
        TetKind::Bcc => anchor_part.dims,
        TetKind::Kuhn => anchor_part.dims.map(|d| d - 1),
    };
    counts.total = match topo.kind {
        TetKind::Bcc => {
            let d = anchor_dims;
            4 * ((d[0].saturating_sub(1)) * d[1] * d[2]
                + d[0] * d[1].saturating_sub(1) * d[2]
                + d[0] * d[1] * d[2].saturating_sub(1))
        }
        TetKind::Kuhn => 6 * anchor_dims.iter().product::<usize>(),
    };
    let template_offsets = &plan.template_offsets;
    let positions = &out.surface.positions;
    let [ax, ay, az] = anchor_dims;
    let kuhn_signs = (topo.kind == TetKind::Kuhn && scratch.signs.holds(at.corners.dims)).then_some(&scratch.signs);
    let [dx, dy, _] = anchor_part.dims;
    // The triangles of the anchor at (x, y, z) of the anchor grid, appended to `triangles`.
    let anchor = |x: usize, y: usize, z: usize, triangles: &mut Vec<[u32; 3]>, counts: &mut TetCounts| {
        let row_same = anchor_part.start + dx * (y + dy * z);
        let row_cross = anchor_part.cross_start + anchor_part.cross_dims[0] * (y + anchor_part.cross_dims[1] * z);
        // BCC: every template exists when the anchor's +x, +y, +z neighbours do.
        let row_full = topo.kind == TetKind::Kuhn || (y + 1 < ay && z + 1 < az);
        let i = row_same + x;
        let full = row_full && (topo.kind == TetKind::Kuhn || x + 1 < ax);
        let q = [2 * x as i32 + anchor_part.odd, 2 * y as i32 + anchor_part.odd, 2 * z as i32 + anchor_part.odd];
        for (t, offsets) in template_offsets.iter().enumerate() {
            let idx = if full {
                offsets.map(|(cross, off)| ((if cross { row_cross + x } else { i }) as isize + off) as usize)
            } else {
                let template = &topo.templates[t];
                let mut idx = [0usize; 4];
                let mut valid = true;
                for (v, d) in idx.iter_mut().zip(template) {
                    match at.index([q[0] + d[0], q[1] + d[1], q[2] + d[2]]) {
                        Some(j) => *v = j,
                        None => valid = false,
                    }
                }
                if !valid {
                    continue;
                }
                idx
            };
            let v = crate::geometry::gather(values, &idx);
            let case = usize::from(v[0] < iso)
                | usize::from(v[1] < iso) << 1
                | usize::from(v[2] < iso) << 2
                | usize::from(v[3] < iso) << 3;
            let entry = &MT_TABLE[case];
            if entry.count == 0 {
                continue;
            }
            counts.active += 1;
            let dirs = &topo.edge_directions[t];
            let mut ids = [0u32; 4];
            for (k, &(a, b)) in entry.edges[..entry.count as usize].iter().enumerate() {
                let (a, b) = (a as usize, b as usize);
                ids[k] = vertex_of(idx[a], v[a], idx[b], v[b], dirs[a][b]);
            }
            if entry.count == 3 {
                push_triangle([ids[0], ids[1], ids[2]], triangles, &mut counts.discarded);
            } else {
                let [a, b, c, d] = ids;
                let along_ac = if a == c {
                    true
                } else if b == d {
                    false
                } else {
                    let p = |i: u32| positions[i as usize];
                    p(a).distance_squared(p(c)) <= p(b).distance_squared(p(d))
                };
                let halves = if along_ac { [[a, b, c], [a, c, d]] } else { [[a, b, d], [b, c, d]] };
                for h in halves {
                    push_triangle(h, triangles, &mut counts.discarded);
                }
            }
        }
    };
    // The triangles of anchor layers `z0..z1`, in order, their counts, and each surface anchor's
    // (flat index, first triangle).
    let layers = |z0: usize, z1: usize, triangles: &mut Vec<[u32; 3]>, counts: &mut TetCounts, anchors: &mut Vec<(u32, u32)>| {
        for z in z0..z1 {
            for y in 0..ay {
                let row_same = anchor_part.start + dx * (y + dy * z);
                // Kuhn: only cubes whose corners disagree hold surface, found 64 at a time; BCC:
                // anchors with a sign change on one of their edges.
                let candidates = |w: usize| match kuhn_signs {
                    Some(signs) => {
                        let rows = [signs.bits(y, z), signs.bits(y + 1, z), signs.bits(y, z + 1), signs.bits(y + 1, z + 1)];
                        surface_cell_word(rows, w, 0, ax - 1)
                    }
                    None => range_mask(w, 0, ax - 1),
                };
                for (w, mut m) in (0..ax.div_ceil(64)).map(|w| (w, candidates(w))) {
                    while m != 0 {
                        let x = 64 * w + m.trailing_zeros() as usize;
                        m &= m - 1;
                        if !scratch.touch[row_same + x] {
                            continue;
                        }
                        anchors.push(((row_same + x) as u32, triangles.len() as u32));
                        anchor(x, y, z, triangles, counts);
                    }
                }
            }
        }
    };
    let mut triangles = std::mem::take(&mut out.surface.triangles);
    match only {
        Some(only) => {
            // Re-emit the anchors in `only`; copy the runs of triangles between them whole,
            // shifting the other anchors' first triangles by what the re-emitted ones changed.
            counts.active = out.stats.active_cells;
            counts.discarded = out.stats.discarded_triangles;
            next.clear();
            let (mut copied, mut from) = (0usize, 0usize);
            let shift = |run: &mut [(u32, u32)], by: isize| run.iter_mut().for_each(|a| a.1 = (a.1 as isize + by) as u32);
            for &i in only {
                // Cubes in `only` without surface have no triangles, before or now.
                let Ok(k) = anchors[from..].binary_search_by_key(&i, |a| a.0).map(|k| from + k) else { continue };
                let (first, end) = (anchors[k].1 as usize, anchors.get(k + 1).map_or(triangles.len(), |a| a.1 as usize));
                shift(&mut anchors[from..k], next.len() as isize - copied as isize);
                next.extend_from_slice(&triangles[copied..first]);
                anchors[k].1 = next.len() as u32;
                let (ii, g) = (i as usize - anchor_part.start, [dx, dy]);
                let (x, y, z) = (ii % g[0], (ii / g[0]) % g[1], ii / (g[0] * g[1]));
                // Same tetrahedra and cases: every triangle not emitted now that was before is
                // one more discarded, and the other way round.
                anchor(x, y, z, next, &mut TetCounts::default());
                let made = &next[anchors[k].1 as usize..];
                rewritten.extend(triangles[first..end].iter().chain(made).flatten());
                counts.discarded = (counts.discarded + (end - first)).saturating_sub(made.len());
                (copied, from) = (end, k + 1);
            }
            shift(&mut anchors[from..], next.len() as isize - copied as isize);
            next.extend_from_slice(&triangles[copied..]);
            std::mem::swap(&mut triangles, next);
        }
        None => {
            anchors.clear();
            let tasks = crate::sweep::slabs::task_count(crate::sweep::slabs::Parallelism::Rayon, ax * ay * az, az);
            triangles.clear();
            if tasks <= 1 {
                layers(0, az, &mut triangles, &mut counts, anchors);
            } else {
                // Slabs of anchor layers, joined in order: the serial pass's triangles.
                let slabs: Vec<SlabTriangles> = (0..tasks)
                    .into_par_iter()
                    .map(|k| {
                        let (mut part, mut c, mut a) = (Vec::new(), TetCounts::default(), Vec::new());
                        layers(k * az / tasks, (k + 1) * az / tasks, &mut part, &mut c, &mut a);
                        (part, c, a)
                    })
                    .collect();
                for (part, c, a) in slabs {
                    let offset = triangles.len() as u32;
                    anchors.extend(a.iter().map(|&(i, first)| (i, first + offset)));
                    triangles.extend_from_slice(&part);
                    counts.active += c.active;
                    counts.discarded += c.discarded;
                }
            }
        }
    }
    out.surface.triangles = triangles;
    out.stats.times.geometry = t.elapsed();
    out.stats.discarded_triangles = counts.discarded;
    out.stats.active_cells = counts.active;
    counts
}

/// One slab's triangles, counts and surface anchors (flat index, first triangle in the slab).
type SlabTriangles = (Vec<[u32; 3]>, TetCounts, Vec<(u32, u32)>);

#[inline]
pub(super) fn push_triangle(t: [u32; 3], triangles: &mut Vec<[u32; 3]>, discarded: &mut usize) {
    if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
        *discarded += 1;
    } else {
        triangles.push(t);
    }
}
