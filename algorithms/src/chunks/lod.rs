//! Levels of detail without cracks: chunks meshed by marching cubes (or, below, the dual methods)
//! at full resolution (level 0), at half resolution (level 1, every other sample), at a quarter
//! (level 2) and so on, meet watertight.
//!
//! Where chunks of different levels meet, their contours on the shared face differ (the fine one
//! sees samples the coarse one skips), which leaves the classic LOD crack (the marching cubes
//! terrain post's "Level of Detail"; Lengyel's Transvoxel is the reference fix, with transition
//! cells and their 512-case table, and the `terrain_lod` experiment runs the `transvoxel` crate
//! beside this). As there, neighbouring chunks (sharing a face, an edge or a corner) may differ
//! by one level at most. We close the seams without a new table, in two steps:
//!
//! 1. **Restriction.** Every sample on the boundary of a chunk at level `L ≥ 1` (cells of
//!    `s = 2^L` samples) takes, for the finer chunks, the value the chunk implies: samples on a
//!    coarse edge the linear interpolation of its two ends, samples inside a coarse face square
//!    the bilinear one of its four corners, except on an ambiguous square (diagonal corners
//!    inside), where marching cubes keeps the inside corners apart, so they stay outside.
//!    Chunks are restricted coarsest first, each from the values the coarser ones left, so a
//!    level-1 chunk next to a level-2 one passes the level-2 seam on to nobody (no level-0 chunk
//!    touches it). Linear interpolation puts the fine crossing on a coarse edge where the coarse
//!    one is, and the fine contour inside each coarse square joins the same crossings as the
//!    coarse segment (the restricted values have no interior extremum, and the forced centre
//!    agrees with the coarse face's resolution). Fine chunks touching the same samples restrict
//!    them alike, so fine-fine seams stay exact.
//! 2. **Stitching**, one pair of levels at a time (`L - 1` beside `L`, for `L = 1, 2, ...`): each
//!    level-`L` triangle with a boundary edge `P → Q` on the seam becomes a polygon, its corners
//!    off the seam and the fine boundary path from `P` to `Q` (the fine vertices on the same
//!    coarse edges, and the fine contour's vertices inside the square between them), so every
//!    seam edge ends up with exactly two triangles. The polygon is filled by the candidate with
//!    the largest smallest angle among every triangulation of it (up to
//!    [`crate::geometry::ALL_TRIANGULATIONS_UP_TO`] corners) and fans from a new vertex between
//!    the seam path and the other corners: the path runs close to the coarse edge it replaces,
//!    so a fan from the third corner (this module's first rule) made slivers, and folded over
//!    the coarse cell's other triangles (the `terrain_lod` checkerboards crossed themselves). A
//!    candidate is taken only when its triangles have area, add no edge the mesh already has,
//!    and cross neither each other nor any triangle near them (exact predicates); where none
//!    passes the polygon is fanned from its third corner and counted in [`LodStats::fanned`]
//!    (0 in every test).
//!
//! The result is closed and manifold across every LOD seam, and for marching cubes free of
//! self-intersections (tested over random terrains and random balanced level patterns of up to
//! four levels: the only boundary edges left lie on the world's boundary). Geometry near a seam is the fine chunk's, coarsened to the coarse contour
//! on the seam face itself, as Transvoxel does.
//!
//! The dual methods (surface nets, dual contouring) take the same restriction and then octree
//! dual contouring's rule instead of step 2: a polygon per minimal crossing edge, joining the
//! vertices of the cells around it whatever their levels
//! ([`crate::extractors::dual::lod`]). Which extractors take which method is their
//! [`Extractor::levels_of_detail`].

use crate::extract::{ExtractError, Extraction, Extractor, LevelsOfDetail};
use crate::lattice::{Grid, Lattice};
use crate::samples::Samples;
use glam::Vec3;
use rayon::prelude::*;
use std::collections::{HashMap, HashSet};

mod dual;
mod seam_fill;

pub use dual::{DualLevels, DualLodCounts, LodGrid};
use seam_fill::SeamNeighbourhood;

/// The coarsest level [`extract_lod`] meshes: 1/16 of the samples per axis.
pub const MAX_LEVEL: u8 = 4;

/// What [`extract_lod`] did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LodStats {
    /// Chunks per axis.
    pub chunks: [usize; 3],
    /// Chunks at each level (index 0: full resolution).
    pub per_level: [usize; MAX_LEVEL as usize + 1],
    /// Samples restricted on coarser chunks' boundaries.
    pub restricted: usize,
    /// Coarse seam edges stitched to the finer side.
    pub stitched: usize,
    /// Coarse seam edges whose fine path was not found (left open; 0 in every test).
    pub unmatched: usize,
    /// Vertices added to repair a seam where two rings met (the dual methods' `pinch`; 0 for
    /// marching cubes).
    pub pinched: usize,
    /// Stitched triangles (marching cubes) left as a fan from their corner off the seam, no
    /// better-shaped filling of their seam polygon keeping off every triangle near it.
    pub fanned: usize,
}

fn bad(reason: String) -> ExtractError {
    ExtractError::BadInput { algorithm: "lod", reason }
}

/// The chunk id (x fastest) of flat chunk index `k`.
fn chunk_id(k: usize, counts: [usize; 3]) -> [usize; 3] {
    [k % counts[0], (k / counts[0]) % counts[1], k / (counts[0] * counts[1])]
}

/// Checks the levels: one per chunk, at most [`MAX_LEVEL`], each level's cells at least two per
/// chunk, and chunks that share a sample at most one level apart (the error names the pair).
fn check_levels(chunk: usize, counts: [usize; 3], levels: &[u8]) -> Result<(), ExtractError> {
    let total: usize = counts.iter().product();
    if levels.len() != total {
        return Err(bad(format!("{} levels given for {total} chunks", levels.len())));
    }
    if let Some(l) = levels.iter().find(|&&l| l > MAX_LEVEL) {
        return Err(bad(format!("level {l} is not supported (0: full resolution, up to {MAX_LEVEL}: 1/{})", 1 << MAX_LEVEL)));
    }
    let top = levels.iter().copied().max().unwrap_or(0);
    if top >= 1 && (chunk < 4 || chunk % 2 != 0) {
        return Err(bad(format!("chunk size {chunk} must be even and at least 4 for half-resolution chunks")));
    }
    let step = 1usize << top;
    if chunk % step != 0 || chunk / step < 2 {
        return Err(bad(format!(
            "chunk size {chunk} cannot be meshed at level {top}: it must be a multiple of {step} with at least 2 cells at that level"
        )));
    }
    for k in 0..total {
        if let Some(other) = neighbours(chunk_id(k, counts), counts).find(|&o| levels[k].abs_diff(levels[o]) > 1) {
            return Err(bad(format!(
                "chunks {:?} (level {}) and {:?} (level {}) touch but differ by more than one level (lod::balance_levels makes a pattern valid)",
                chunk_id(k, counts),
                levels[k],
                chunk_id(other, counts),
                levels[other]
            )));
        }
    }
    Ok(())
}

/// Lowers levels until every two chunks that share a sample are at most one level apart (what
/// [`extract_lod`] requires), keeping each chunk as coarse as that allows: a level pattern from
/// viewer distance or from a budget, made valid. `levels` has one entry per chunk, x fastest.
pub fn balance_levels(counts: [usize; 3], levels: &mut [u8]) {
    let total: usize = counts.iter().product();
    if levels.len() != total {
        return;
    }
    loop {
        let mut changed = false;
        for k in 0..total {
            let id = chunk_id(k, counts);
            for other in neighbours(id, counts) {
                if levels[k] > levels[other] + 1 {
                    levels[k] = levels[other] + 1;
                    changed = true;
                }
            }
        }
        if !changed {
            return;
        }
    }
}

/// The flat indices of the chunks sharing a sample with chunk `id` (up to 26).
fn neighbours(id: [usize; 3], counts: [usize; 3]) -> impl Iterator<Item = usize> {
    (0..27usize).filter(|&d| d != 13).filter_map(move |d| {
        let offset = [d % 3, (d / 3) % 3, d / 9];
        let mut n = [0usize; 3];
        for a in 0..3 {
            n[a] = (id[a] + offset[a]).checked_sub(1).filter(|&c| c < counts[a])?;
        }
        Some(n[0] + counts[0] * (n[1] + counts[1] * n[2]))
    })
}

/// Meshes `samples` (cubic) in chunks of `chunk` cells with `extractor` (one whose
/// [`Extractor::levels_of_detail`] is not [`LevelsOfDetail::Unsupported`]), chunk `k` (x fastest) at
/// level `levels[k]` (0: full resolution, `L`: every `2^L`-th sample), neighbours at most one
/// level apart, and stitches the LOD seams. The output is in world space with one triangle list;
/// `levels_out` (if given) receives each triangle's level.
pub fn extract_lod(
    extractor: &dyn Extractor,
    samples: &Samples,
    chunk: usize,
    levels: &[u8],
    out: &mut Extraction,
    levels_out: Option<&mut Vec<u8>>,
) -> Result<LodStats, ExtractError> {
    let method = extractor.levels_of_detail();
    if let LevelsOfDetail::Unsupported(why) = method {
        return Err(bad(format!("levels of detail are not supported for {}: {why}", extractor.name())));
    }
    let Lattice::Cubic(grid) = *samples.lattice() else {
        return Err(ExtractError::UnsupportedLattice { algorithm: "lod", lattice: "bcc", supported: "cubic" });
    };
    let counts = crate::chunks::chunk_counts(&grid, chunk, "lod")?;
    check_levels(chunk, counts, levels)?;
    let total = levels.len();
    let iso = samples.iso();
    let (restricted_values, restricted) = restrict(&grid, samples.values(), iso, chunk, counts, levels);
    let mut per_level = [0; MAX_LEVEL as usize + 1];
    for &l in levels {
        per_level[l as usize] += 1;
    }
    if let LevelsOfDetail::Dual(engine) = method {
        out.clear();
        let field = samples.field().map(|f| f.as_ref());
        let g = LodGrid { grid, values: &restricted_values, iso, field, chunk, counts, levels };
        let made = engine.extract_lod(g, &mut out.surface, levels_out);
        out.finish_counts(0);
        if made.crossing_cells > 0 {
            out.stats.warnings.push(format!(
                "{}: {} cells with two pieces of surface whose triangles cross (please report the input)",
                extractor.name(),
                made.crossing_cells
            ));
        }
        return Ok(LodStats {
            chunks: counts,
            per_level,
            restricted,
            stitched: made.seam_polygons,
            unmatched: made.unmatched,
            pinched: made.pinched,
            fanned: 0,
        });
    }
    let ids: Vec<[usize; 3]> = (0..total).map(|k| chunk_id(k, counts)).collect();
    let meshes: Vec<Extraction> = ids
        .par_iter()
        .zip(levels.par_iter())
        .map(|(&id, &level)| mesh_chunk(extractor, &grid, &restricted_values, iso, chunk, id, level))
        .collect::<Result<_, _>>()?;
    // Weld same-position vertices (exact: index coordinates), remembering each triangle's level.
    out.clear();
    let counts_per_chunk = super::weld_on_chunk_planes(meshes.iter().map(|m| &m.surface), chunk, &mut out.surface);
    let mut triangle_levels: Vec<u8> =
        counts_per_chunk.iter().zip(levels).flat_map(|(&n, &level)| std::iter::repeat_n(level, n)).collect();
    let top = levels.iter().copied().max().unwrap_or(0);
    let (mut stitched, mut unmatched, mut fanned) = (0, 0, 0);
    for coarse in 1..=top {
        let (s, u, f) =
            stitch(&mut out.surface.positions, &mut out.surface.triangles, &mut triangle_levels, coarse, chunk, &grid);
        stitched += s;
        unmatched += u;
        fanned += f;
    }
    for p in &mut out.surface.positions {
        *p = grid.origin + *p * grid.spacing;
    }
    out.surface.compute_face_weighted_normals();
    out.finish_counts(0);
    if let Some(l) = levels_out {
        *l = triangle_levels;
    }
    Ok(LodStats { chunks: counts, per_level, restricted, stitched, unmatched, pinched: 0, fanned })
}

/// The samples the finer chunks see: those on a coarser chunk's boundary restricted to what that
/// chunk implies, coarsest chunks first (module doc). Returns the values and how many changed.
fn restrict<'a>(
    grid: &Grid,
    values: &'a [f32],
    iso: f32,
    chunk: usize,
    counts: [usize; 3],
    levels: &[u8],
) -> (std::borrow::Cow<'a, [f32]>, usize) {
    // Only chunks with a finer neighbour have samples a finer chunk reads.
    let mut order: Vec<usize> =
        (0..levels.len()).filter(|&k| neighbours(chunk_id(k, counts), counts).any(|o| levels[o] < levels[k])).collect();
    if order.is_empty() {
        return (std::borrow::Cow::Borrowed(values), 0);
    }
    let mut out = values.to_vec();
    let mut changed = 0;
    order.sort_by_key(|&k| std::cmp::Reverse(levels[k]));
    for k in order {
        let s = 1usize << levels[k];
        let k0 = chunk_id(k, counts).map(|c| c * chunk);
        for z in k0[2]..=k0[2] + chunk {
            for y in k0[1]..=k0[1] + chunk {
                // Only the chunk's boundary samples: whole rows on its y and z faces, the two
                // ends of the others.
                let whole_row = z == k0[2] || z == k0[2] + chunk || y == k0[1] || y == k0[1] + chunk;
                let step = if whole_row { 1 } else { chunk };
                for x in (k0[0]..=k0[0] + chunk).step_by(step) {
                    if let Some(value) = restricted_value(grid, &out, iso, [x, y, z], s) {
                        let i = grid.index(x, y, z);
                        if out[i] != value {
                            out[i] = value;
                            changed += 1;
                        }
                    }
                }
            }
        }
    }
    (std::borrow::Cow::Owned(out), changed)
}

/// The value a chunk with cells of `s` samples implies at boundary sample `c`: linear along a
/// coarse edge (one coordinate off the coarse lattice), bilinear in a coarse face square (two;
/// an ambiguous square's interior kept outside), `None` on the coarse lattice or inside.
fn restricted_value(grid: &Grid, values: &[f32], iso: f32, c: [usize; 3], s: usize) -> Option<f32> {
    let at = |q: [usize; 3]| values[grid.index(q[0], q[1], q[2])];
    // The axes on which `c` is off the coarse lattice (no allocation: called per boundary sample).
    let mut off_axes = [0usize; 3];
    let mut n_off = 0;
    for (a, &coordinate) in c.iter().enumerate() {
        if coordinate % s != 0 {
            off_axes[n_off] = a;
            n_off += 1;
        }
    }
    let off = &off_axes[..n_off];
    let lower = |q: [usize; 3], a: usize| {
        let mut q = q;
        q[a] -= q[a] % s;
        q
    };
    let fraction = |a: usize| (c[a] % s) as f32 / s as f32;
    match *off {
        [a] => {
            let lo = lower(c, a);
            let mut hi = lo;
            hi[a] += s;
            let t = fraction(a);
            Some(at(lo) * (1.0 - t) + at(hi) * t)
        }
        [a, b] => {
            let base = lower(lower(c, a), b);
            let corner = |da: usize, db: usize| {
                let mut q = base;
                q[a] += s * da;
                q[b] += s * db;
                at(q)
            };
            let v = [corner(0, 0), corner(1, 0), corner(1, 1), corner(0, 1)];
            let (t, u) = (fraction(a), fraction(b));
            let value = (v[0] * (1.0 - t) + v[1] * t) * (1.0 - u) + (v[3] * (1.0 - t) + v[2] * t) * u;
            let inside = v.map(|x| x < iso);
            let ambiguous = inside[0] == inside[2] && inside[1] == inside[3] && inside[0] != inside[1];
            // Marching cubes keeps ambiguous faces' inside corners apart: the interior stays
            // outside.
            Some(if ambiguous { value.max(iso) } else { value })
        }
        // On the coarse lattice, or off it on all three axes (inside the chunk).
        _ => None,
    }
}

/// Meshes chunk `id` at `level` in index coordinates.
fn mesh_chunk(
    extractor: &dyn Extractor,
    grid: &Grid,
    values: &[f32],
    iso: f32,
    chunk: usize,
    id: [usize; 3],
    level: u8,
) -> Result<Extraction, ExtractError> {
    let step = 1usize << level;
    let n = chunk / step + 1;
    let k0 = id.map(|c| c * chunk);
    let mut local = Vec::with_capacity(n * n * n);
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                local.push(values[grid.index(k0[0] + x * step, k0[1] + y * step, k0[2] + z * step)]);
            }
        }
    }
    let origin = Vec3::new(k0[0] as f32, k0[1] as f32, k0[2] as f32);
    let chunk_grid = Grid { origin, spacing: step as f32, dims: [n, n, n] };
    let samples = Samples::from_values(Lattice::Cubic(chunk_grid), local, iso)?;
    let mut out = Extraction::default();
    let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
    for &v in samples.values() {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if lo < iso && hi >= iso {
        extractor.extract(&samples, &mut out)?;
    }
    Ok(out)
}

/// The coarse lattice edge (cells of `s` samples) a vertex at `p` (index coordinates) lies on:
/// two coordinates integer multiples of `s`, the third strictly between two. Returns (axis,
/// lower sample).
fn coarse_edge(p: Vec3, s: usize) -> Option<(usize, [u32; 3])> {
    let c = p.to_array();
    let on_lattice = |v: f32| v.fract() == 0.0 && (v as usize) % s == 0;
    let mut free = (0..3).filter(|&a| !on_lattice(c[a]));
    let (Some(a), None) = (free.next(), free.next()) else { return None };
    let mut lower = c.map(|v| v as u32);
    lower[a] = ((c[a] / s as f32).floor() as usize * s) as u32;
    Some((a, lower))
}

/// Stitches the seam edges of level-`coarse` triangles to the boundary paths of level
/// `coarse - 1` (module doc). Returns (stitched, unmatched, left as fans).
fn stitch(
    positions: &mut Vec<Vec3>,
    triangles: &mut Vec<[u32; 3]>,
    levels: &mut Vec<u8>,
    coarse: u8,
    chunk: usize,
    grid: &Grid,
) -> (usize, usize, usize) {
    let (seams, unresolved) = stitch_seams(positions, triangles, levels, coarse, chunk, grid);
    positions.extend(unresolved.1);
    (seams.0, seams.1, unresolved.0)
}

/// [`stitch`] but for the vertices it adds (returned with the fans left, after the seam counts).
fn stitch_seams(
    positions: &[Vec3],
    triangles: &mut Vec<[u32; 3]>,
    levels: &mut Vec<u8>,
    coarse: u8,
    chunk: usize,
    grid: &Grid,
) -> ((usize, usize), (usize, Vec<Vec3>)) {
    let s = 1usize << coarse;
    let fine = coarse - 1;
    // Interior chunk planes only (the world boundary stays open).
    let last = grid.dims.map(|d| (d - 1) as f32);
    let on_interior_plane = |p: Vec3, q: Vec3| {
        (0..3).any(|a| p[a] == q[a] && p[a] > 0.0 && p[a] < last[a] && (p[a] as usize) % chunk == 0 && p[a].fract() == 0.0)
    };
    // Edge uses, counted only for edges lying in an interior chunk plane (the only candidates).
    let in_plane = |a: u32, b: u32| on_interior_plane(positions[a as usize], positions[b as usize]);
    let uses = edge_uses(triangles, in_plane);
    let is_boundary = |a: u32, b: u32| uses.get(&(a.min(b), a.max(b))) == Some(&1);
    // Fine boundary: next vertex along each directed boundary edge, and vertices on coarse edges.
    let mut next_fine: HashMap<u32, Vec<u32>> = HashMap::new();
    let mut fine_on_edge: HashMap<(usize, [u32; 3]), u32> = HashMap::new();
    for (t, &level) in triangles.iter().zip(levels.iter()) {
        if level != fine {
            continue;
        }
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            if is_boundary(a, b) && on_interior_plane(positions[a as usize], positions[b as usize]) {
                next_fine.entry(a).or_default().push(b);
                for v in [a, b] {
                    if let Some(key) = coarse_edge(positions[v as usize], s) {
                        fine_on_edge.insert(key, v);
                    }
                }
            }
        }
    }
    // Coarse seam vertices become their fine counterparts (same coarse edge) in every triangle.
    let mut remap: HashMap<u32, u32> = HashMap::new();
    for (t, &level) in triangles.iter().zip(levels.iter()) {
        for k in (0..3).filter(|_| level == coarse) {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            if is_boundary(a, b) && on_interior_plane(positions[a as usize], positions[b as usize]) {
                for v in [a, b] {
                    if let Some(&f) = coarse_edge(positions[v as usize], s).and_then(|key| fine_on_edge.get(&key)) {
                        remap.insert(v, f);
                    }
                }
            }
        }
    }
    for t in triangles.iter_mut() {
        *t = t.map(|v| remap.get(&v).copied().unwrap_or(v));
    }
    let uses = edge_uses(triangles, in_plane);
    let is_boundary = |a: u32, b: u32| uses.get(&(a.min(b), a.max(b))) == Some(&1);
    let (mut stitched, mut unmatched) = (0, 0);
    let mut fans: Vec<(usize, Vec<(u32, bool)>)> = Vec::new();
    // Seam edges toward the finer level join two of its boundary vertices (others face a coarser
    // chunk, stitched in a later pass).
    let fine_boundary: HashSet<u32> =
        next_fine.iter().flat_map(|(&a, next)| std::iter::once(a).chain(next.iter().copied())).collect();
    for (ti, t) in triangles.iter().enumerate() {
        if levels[ti] != coarse {
            continue;
        }
        // The triangle as a cycle, each seam edge replaced by its fine path; path vertices are
        // marked so the fan's apex is the corner off the seam.
        let mut cycle: Vec<(u32, bool)> = Vec::new();
        let mut changed = false;
        for k in 0..3 {
            let (p, q) = (t[k], t[(k + 1) % 3]);
            if cycle.last().map(|c| c.0) != Some(p) {
                cycle.push((p, false));
            }
            let toward_finer = fine_boundary.contains(&p) && fine_boundary.contains(&q);
            if !toward_finer || !is_boundary(p, q) || !on_interior_plane(positions[p as usize], positions[q as usize]) {
                continue;
            }
            // Both ends are fine vertices now; the fine side runs from Q back to P.
            let path = fine_path(q, p, &next_fine, positions, s);
            match path {
                Some(path) => {
                    // path runs Q' → ... → P'; the coarse side needs P' → ... → Q'.
                    cycle.pop();
                    cycle.extend(path.iter().rev().map(|&v| (v, true)));
                    changed = true;
                    stitched += 1;
                }
                None => unmatched += 1,
            }
        }
        if changed {
            // Consecutive paths share their ends; the last may end where the cycle starts.
            cycle.dedup_by_key(|c| c.0);
            if cycle.len() > 1 && cycle[0].0 == cycle[cycle.len() - 1].0 {
                let end = cycle.pop().expect("non-empty");
                cycle[0].1 |= end.1;
            }
            fans.push((ti, cycle));
        }
    }
    // Replace each stitched coarse triangle by the best-shaped filling of its cycle that crosses
    // nothing near it (module doc); the fan from its corner off the seam where none does.
    let mut remove = vec![false; triangles.len()];
    fans.iter().for_each(|(ti, _)| remove[*ti] = true);
    let mut near = SeamNeighbourhood::new(positions, s);
    near.bucket(triangles, &remove, fans.iter().map(|(ti, _)| triangles[*ti]));
    for (_, cycle) in fans {
        let ring: Vec<u32> = cycle.iter().map(|c| c.0).collect();
        let off_seam: Vec<u32> = cycle.iter().filter(|c| !c.1).map(|c| c.0).collect();
        let fill = near.best_fill(&ring, &off_seam).unwrap_or_else(|| {
            near.unresolved += 1;
            let apex = cycle.iter().position(|c| !c.1).unwrap_or(0);
            let n = ring.len();
            (1..n.saturating_sub(1)).map(|i| [ring[apex], ring[(apex + i) % n], ring[(apex + i + 1) % n]]).collect()
        });
        for t in fill {
            near.add(t);
            triangles.push(t);
            levels.push(coarse);
        }
    }
    let unresolved = (near.unresolved, std::mem::take(&mut near.added));
    remove.resize(triangles.len(), false);
    let mut k = 0;
    triangles.retain(|_| {
        k += 1;
        !remove[k - 1]
    });
    let mut k = 0;
    levels.retain(|_| {
        k += 1;
        !remove[k - 1]
    });
    ((stitched, unmatched), unresolved)
}

/// Boundary edges (used by one triangle) whose two ends do not lie on one face of `bounds` (the
/// world's box): the cracks a seam leaves. 0 for a stitched mesh.
pub fn open_edges_off_bounds(mesh: &crate::mesh::TriMesh, bounds: &crate::geometry::Aabb) -> usize {
    let (lo, hi) = (bounds.min, bounds.max);
    let eps = 1e-4 * (hi - lo).max_element();
    let on_face = |p: Vec3, a: usize| (p[a] - lo[a]).abs() < eps || (p[a] - hi[a]).abs() < eps;
    open_edges_where(mesh, |p, q| !(0..3).any(|k| on_face(p, k) && on_face(q, k)))
}

/// Boundary edges with an end farther than `margin` from every face of `bounds` (a point at
/// `margin` exactly is near). Dual extractors
/// (surface nets, dual contouring) end their mesh inside the outermost cells, not on the box: a
/// margin of one cell lets their open border at the world's box pass while a crack between chunks
/// away from the box still counts.
pub fn open_edges_away_from_bounds(mesh: &crate::mesh::TriMesh, bounds: &crate::geometry::Aabb, margin: f32) -> usize {
    let reach = margin * (1.0 + 1e-4);
    let near_box = |p: Vec3| (p - bounds.min).min_element() <= reach || (bounds.max - p).min_element() <= reach;
    open_edges_where(mesh, |p, q| !(near_box(p) && near_box(q)))
}

/// Boundary edges (used by one triangle) whose ends `counts` selects.
fn open_edges_where(mesh: &crate::mesh::TriMesh, counts: impl Fn(Vec3, Vec3) -> bool) -> usize {
    edge_uses(&mesh.triangles, |_, _| true)
        .iter()
        .filter(|(_, &n)| n == 1)
        .filter(|((a, b), _)| counts(mesh.positions[*a as usize], mesh.positions[*b as usize]))
        .count()
}

/// How many triangles use each undirected edge that `keep` selects.
fn edge_uses(triangles: &[[u32; 3]], keep: impl Fn(u32, u32) -> bool) -> HashMap<(u32, u32), u32> {
    let mut uses: HashMap<(u32, u32), u32> = HashMap::new();
    for t in triangles {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            if keep(a, b) {
                *uses.entry((a.min(b), a.max(b))).or_default() += 1;
            }
        }
    }
    uses
}

/// The fine boundary path from `from` to `to` along directed boundary edges, at most 64 steps,
/// within the coarse face square (`s` samples a side) holding the segment between them (where
/// seam planes meet, a vertex can start boundary paths into two squares).
fn fine_path(from: u32, to: u32, next: &HashMap<u32, Vec<u32>>, positions: &[Vec3], s: usize) -> Option<Vec<u32>> {
    let side = s as f32;
    let mid = (positions[from as usize] + positions[to as usize]) * 0.5;
    let lo = (mid / side).floor() * side;
    let inside = |p: Vec3| (0..3).all(|a| p[a] >= lo[a] && p[a] <= lo[a] + side);
    let mut path = vec![from];
    let mut v = from;
    for _ in 0..64 {
        v = *next.get(&v)?.iter().find(|&&n| inside(positions[n as usize]))?;
        path.push(v);
        if v == to {
            return Some(path);
        }
        if coarse_edge(positions[v as usize], s).is_some() {
            return None;
        }
    }
    None
}
