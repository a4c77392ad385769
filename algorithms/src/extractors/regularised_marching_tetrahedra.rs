//! # Regularised marching tetrahedra (integrated vertex clustering)
//!
//! **Papers:** G. M. Treece, R. W. Prager and A. H. Gee, "Regularised marching tetrahedra:
//! improved iso-surface extraction", Computers & Graphics 23(4), 1999, DOI
//! 10.1016/S0097-8493(99)00076-X; specified by `../shared/papers/costen-2026-rmt-terrain.txt`,
//! section 2.4, Algorithms 2 and 3 and section 3.1.1 (the paper's `*_bi` and `*_si`
//! configurations).
//!
//! **Summary.** Marching tetrahedra ([`crate::extractors::tetrahedral`]) whose vertex pass merges, around each
//! sample, the crossings nearer that sample than the other end of their edge (its *nearby
//! intersections*, at most 14):
//! 1. their adjacency graph: two nearby crossings are joined when their edges span a face of the
//!    sample's star (bit flags, [`crate::extractors::tetrahedral::TetTopology::adjacency`]);
//! 2. merging is skipped when more than `max-nearby` (10) are nearby (a complex, concave case), or
//!    when the complement graph (the star's other neighbours) has more than one island: the nearby
//!    crossings then ring the sample, a loop such as a thin tube that merging would collapse;
//! 3. otherwise each island of the graph becomes one vertex at the mean of its crossings, its
//!    index stored on its edges;
//! 4. the geometry pass is plain marching tetrahedra reading those indices; triangles with a
//!    repeated index are discarded (counted as `discarded_triangles`).
//!
//! Samples on the lattice boundary never merge (their star is cut open), so chunk seams and
//! grid-boundary edges stay exactly as plain marching tetrahedra makes them.
//!
//! Option `project=newton` moves each merged vertex onto the level set with Newton steps along the
//! field gradient (`x -= (f(x) - iso) ∇f / |∇f|²`, at most three, never farther than half a spacing from the mean,
//! kept only if the residual drops),
//! when the samples carry their field.
//!
//! **What we add** (both can be switched off; [`RmtOptions::paper`] is the algorithm as
//! published):
//! - `boundary=merge` (default): samples on the lattice boundary merge too, their missing
//!   neighbours counting as non-nearby for the loop test. The paper leaves them as plain marching
//!   tetrahedra, whose needles then dominate mean aspect ratios wherever the surface meets the
//!   grid boundary (terrain, gyroid). `boundary=keep` makes chunk seams match exactly.
//! - `guard=true` (default): the paper's graph test is local, but two neighbouring samples can
//!   each merge safely and together collapse a narrow fold or tube (their islands touch along two
//!   separate stretches), leaving an edge with four triangles or a pinched vertex. After the
//!   geometry pass the guard lists the merged vertices where the mesh is not a consistently wound
//!   manifold ([`crate::mesh::ManifoldCheck`]), forbids merging at the samples that made them,
//!   gives their crossings one vertex each and re-emits the triangles of the tetrahedra around
//!   those samples (on cubic grids only those: [`crate::extractors::tetrahedral::regenerate_anchors`]; on the
//!   BCC lattice the whole geometry pass); plain marching tetrahedra is manifold, so this ends,
//!   usually after one or two rounds. After a repair only the vertices of the triangles it
//!   removed or made are checked again (elsewhere every link is as the last check saw it). Once
//!   the mesh is manifold the guard looks for folds ([`crate::extractors::tetrahedral::folds`]): merged
//!   vertices whose triangles cross a triangle of their two-ring, unmerged the same way
//!   (`guard=manifold` skips this). Its cost is in the geometry time.
//!
//! **Guarantees.** Every crossing belongs to exactly one sample, so merging is order independent
//! and O(samples). With the guard, the output is as manifold as plain marching tetrahedra (closed
//! inside the lattice, consistently wound); the tests check it on random fields and every
//! built-in field.
//!
//! **Non-guarantees.** As the paper says (section 3.1.1), its graph analysis alone does not
//! guarantee a manifold mesh: without the guard, some concave configurations and long, narrow
//! islands collapse a fold into back-to-back triangles or pinch a vertex (the tests count them).
//! Merging can fold a triangle over its neighbours without breaking topology; the guard
//! repairs the folds it finds in a merged vertex's two-ring where one of the vertex's triangles
//! has turned away from the rest, not crossings of two sheets further apart in the mesh (on white
//! noise some remain: `tests/tests/self_intersections.rs` holds them to what was measured).
//!
//! **Costs.** As marching tetrahedra plus, per sample with two or more nearby crossings, a few
//! bit operations per crossing (at most 14 × 14).
//!
//! ```
//! use isolab_algorithms::{extractors, fields, mesh::manifold_defects, Extraction, Grid, Lattice, Samples};
//! let asteroid = fields::builtin("asteroid", Default::default()).unwrap();
//! let grid = Grid::with_dims(&asteroid.domain(), [25, 25, 25]).unwrap();
//! let samples = Samples::sample(asteroid, Lattice::Bcc(grid), 0.0).unwrap();
//! let (mut mt, mut rmt) = (Extraction::default(), Extraction::default());
//! extractors::by_name("marching-tetrahedra").unwrap().extract(&samples, &mut mt).unwrap();
//! extractors::by_name("regularised-marching-tetrahedra").unwrap().extract(&samples, &mut rmt).unwrap();
//! // Clustering removes most of plain marching tetrahedra's triangles; the guard keeps it manifold.
//! assert!(rmt.surface.triangles.len() * 2 < mt.surface.triangles.len());
//! assert!(manifold_defects(&rmt.surface).is_empty());
//! ```

use crate::extract::{Chunking, ExtractError, Extraction, Extractor, ExtractorInfo, Guarantees, LevelsOfDetail};
use crate::extractors::tetrahedral::folds::FoldCheck;
use crate::extractors::tetrahedral::{
    compute_normals, extract_tetrahedral, finish_repair, unmerge_and_regenerate, Clustering, Islands, NoClustering, Star,
    TetScratch, TetTopology, DIRECTIONS,
};
use crate::field::Field;
use crate::lattice::Lattice;
use crate::mesh::ManifoldCheck;
use crate::options::{OptionError, Options};
use crate::samples::Samples;
use crate::sweep::slabs::ScratchPool;
use glam::Vec3;
use std::time::Instant;

/// One line for listings.
pub const DESCRIPTION: &str =
    "Treece et al. 1999 / Costen 2026: marching tetrahedra merging the crossings near each sample (graph islands, loop check), degenerate triangles dropped";

/// Options it takes.
pub const OPTION_NAMES: &[&str] = &["max-nearby", "loop-check", "project", "boundary", "guard"];

/// Where merged vertices go.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Projection {
    /// The mean of the merged crossings (the paper).
    Mean,
    /// The mean, then Newton steps onto the level set along the field gradient.
    Newton,
}

/// Options for [`RegularisedMarchingTetrahedra`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RmtOptions {
    /// Merging is skipped when more crossings than this are nearby (the paper: 10).
    pub max_nearby: u32,
    /// Skip merging when the nearby crossings ring the sample (the paper's loop test).
    pub loop_check: bool,
    /// Where merged vertices go.
    pub projection: Projection,
    /// Whether samples on the lattice boundary merge (their missing neighbours count as
    /// non-nearby for the loop test). Keeping them unmerged makes chunk seams match exactly.
    pub merge_boundary: bool,
    /// Repair: after the geometry pass, find vertices where the mesh is not manifold, forbid
    /// merging at the samples that made them, and extract again until none is left.
    pub guard: bool,
    /// With the guard: also repair the folds merging makes ([`crate::extractors::tetrahedral::folds`]).
    pub fold_check: bool,
}

impl Default for RmtOptions {
    fn default() -> Self {
        RmtOptions {
            max_nearby: 10,
            loop_check: true,
            projection: Projection::Mean,
            merge_boundary: true,
            guard: true,
            fold_check: true,
        }
    }
}

impl RmtOptions {
    /// The paper's algorithm as published: no boundary merging and no repair.
    pub fn paper() -> Self {
        RmtOptions { merge_boundary: false, guard: false, fold_check: false, ..Default::default() }
    }
}

/// Treece et al. 1999 / Costen 2026: marching tetrahedra with integrated vertex clustering.
pub const INFO: ExtractorInfo = ExtractorInfo {
    name: "regularised-marching-tetrahedra",
    description: DESCRIPTION,
    options: OPTION_NAMES,
    make: from_options,
    guarantees: Guarantees {
        cubic: true,
        bcc: true,
        closed: true,
        manifold: true,
        outward: true,
        intersection_free: false,
        trilinear_topology: false,
        keeps_small_parts: true,
        dihedral: None,
    },
    samples: crate::extract::SampleAccess::Copies("the tetrahedral engine, shared with BCC lattices (whose centre samples no array holds), reads f32 samples by flat lattice index"),
};

/// Builds it from options.
pub fn from_options(options: &Options) -> Result<Box<dyn Extractor>, OptionError> {
    let d = RmtOptions::default();
    let mut r = options.reader(INFO.name, OPTION_NAMES);
    let (guard, fold_check) = r.choice(
        "guard",
        (d.guard, d.fold_check),
        &[("true", (true, true)), ("manifold", (true, false)), ("false", (false, false))],
    )?;
    let o = RmtOptions {
        max_nearby: r.count("max-nearby", d.max_nearby as usize, DIRECTIONS)? as u32,
        loop_check: r.choice("loop-check", d.loop_check, &[("true", true), ("false", false)])?,
        projection: r.choice("project", d.projection, &[("mean", Projection::Mean), ("newton", Projection::Newton)])?,
        merge_boundary: r.choice("boundary", d.merge_boundary, &[("merge", true), ("keep", false)])?,
        guard,
        fold_check,
    };
    r.finish()?;
    Ok(Box::new(RegularisedMarchingTetrahedra::new(o)))
}

/// Regularised marching tetrahedra with the paper's integrated clustering. Keeps its scratch
/// (the engine's per-sample bookkeeping and the guard's buffers) between calls, so re-meshing a
/// same-sized chunk allocates nothing.
#[derive(Default)]
pub struct RegularisedMarchingTetrahedra {
    /// The options.
    pub options: RmtOptions,
    scratch: ScratchPool<RmtScratch>,
}

impl RegularisedMarchingTetrahedra {
    /// With `options`.
    pub fn new(options: RmtOptions) -> Self {
        Self { options, scratch: ScratchPool::default() }
    }
}

/// The buffers one extraction uses, kept between calls.
#[derive(Default)]
struct RmtScratch {
    tet: TetScratch,
    /// The guard's manifold check.
    check: ManifoldCheck,
    /// The guard's vertex renumbering.
    renumber: Vec<u32>,
    /// The guard's vertices to check again after a repair.
    recheck: Vec<bool>,
    /// The guard's fold check.
    folds: FoldCheck,
    /// The guard's vertices to unmerge this round.
    defects: Vec<u32>,
}

/// Flags in `recheck` (one per vertex of a `vertices`-vertex mesh) the vertices a repair
/// `rewritten`; returns whether every vertex must be checked instead (the repair re-ran the
/// whole geometry pass).
fn mark_rewritten(rewritten: Option<&[u32]>, vertices: usize, recheck: &mut Vec<bool>) -> bool {
    let Some(rewritten) = rewritten else { return true };
    recheck.clear();
    recheck.resize(vertices, false);
    for &v in rewritten {
        recheck[v as usize] = true;
    }
    false
}

/// The bits of `mask` reachable from `seed` through `adjacency` without leaving `mask`.
fn island(seed: u16, mask: u16, adjacency: &[u16; DIRECTIONS]) -> u16 {
    // Grown from its newest bits only: each bit's neighbours are read once.
    let (mut island, mut frontier) = (seed, seed);
    while frontier != 0 {
        let mut grown = 0;
        while frontier != 0 {
            grown |= adjacency[frontier.trailing_zeros() as usize];
            frontier &= frontier - 1;
        }
        frontier = grown & mask & !island;
        island |= frontier;
    }
    island
}

/// The islands of `mask` under `adjacency`, each as a bit mask, in order of their lowest bit.
pub fn islands_of(mask: u16, adjacency: &[u16; DIRECTIONS]) -> impl Iterator<Item = u16> + '_ {
    let mut rest = mask;
    std::iter::from_fn(move || {
        if rest == 0 {
            return None;
        }
        let found = island(rest & rest.wrapping_neg(), rest, adjacency);
        rest &= !found;
        Some(found)
    })
}

impl Clustering for RmtOptions {
    fn islands(&self, star: &Star, topology: &TetTopology) -> Islands {
        const ALL: u16 = (1 << DIRECTIONS) - 1;
        let nearby = star.nearby;
        let count = nearby.count_ones();
        let skip = count <= 1
            || (!self.merge_boundary && star.neighbours != ALL)
            || count > self.max_nearby
            || (self.loop_check && islands_of(ALL & !nearby, &topology.adjacency).nth(1).is_some());
        if skip {
            return NoClustering.islands(star, topology);
        }
        let mut slot = [u8::MAX; DIRECTIONS];
        let mut n = 0u8;
        for mut found in islands_of(nearby, &topology.adjacency) {
            while found != 0 {
                slot[found.trailing_zeros() as usize] = n;
                found &= found - 1;
            }
            n += 1;
        }
        Islands { count: n, slot }
    }

    fn place(&self, mean: Vec3, members: u32, field: Option<&dyn Field>, iso: f32, spacing: f32) -> Vec3 {
        match (self.projection, field) {
            (Projection::Newton, Some(f)) if members > 1 => newton(f, mean, iso, 0.5 * spacing),
            _ => mean,
        }
    }
}

/// Up to three Newton steps from `start` toward `f = iso` along the gradient. The vertex stays
/// within `reach` of `start` and only moves if the residual drops (a distance field's gradient
/// can point anywhere near its medial axis); otherwise `start` is kept.
fn newton(field: &dyn Field, start: Vec3, iso: f32, reach: f32) -> Vec3 {
    let r0 = (field.value(start) - iso).abs();
    let mut p = start;
    for _ in 0..3 {
        let r = field.value(p) - iso;
        let g = field.gradient(p);
        let g2 = g.length_squared();
        if g2.is_nan() || g2 <= 1e-20 || r == 0.0 {
            break;
        }
        let next = p - g * (r / g2);
        if !next.is_finite() || next.distance(start) > reach {
            break;
        }
        p = next;
    }
    if (field.value(p) - iso).abs() < r0 {
        p
    } else {
        start
    }
}

impl Extractor for RegularisedMarchingTetrahedra {
    fn info(&self) -> &'static ExtractorInfo {
        &INFO
    }

    fn levels_of_detail(&self) -> LevelsOfDetail<'_> {
        LevelsOfDetail::Unsupported("its vertex clustering merges crossings across a sample's star and moves them off the lattice edges, so no coarse seam edge has a fine path of edge crossings to be stitched to, and its BCC centres are not samples of the finer lattice")
    }

    /// A vertex merges the crossings of its sample's star, and the guard's repairs reach the
    /// stars of neighbouring samples: 3 samples.
    fn chunking(&self) -> Chunking {
        Chunking::Apron(3)
    }

    fn extract_into(&self, samples: &Samples, out: &mut Extraction) -> Result<usize, ExtractError> {
        let mut held = self.scratch.take();
        let result = self.extract_with(samples, out, &mut held);
        self.scratch.give(held);
        result
    }
}

impl RegularisedMarchingTetrahedra {
    fn extract_with(&self, samples: &Samples, out: &mut Extraction, s: &mut RmtScratch) -> Result<usize, ExtractError> {
        let counts = extract_tetrahedral(samples, &self.options, &mut s.tet, out)?;
        let first_pass_vertices = out.surface.positions.len();
        let mut repaired = false;
        if self.options.guard {
            // The checks and the re-run geometry passes count as geometry time. Only merged
            // vertices can be repaired (unmerging is all the guard does), so only they are
            // checked: the same defects the whole mesh's check lists among them.
            // After a repair that re-emitted only the tetrahedra around the unmerged samples, only
            // the vertices of the triangles it removed or made have new links: only they are
            // checked again (every other vertex passed the last check, or was at fault and is no
            // longer used).
            let (first_pass, t) = (out.stats.times.geometry, Instant::now());
            let (mut everywhere, mut folds_checked) = (true, false);
            loop {
                let (tet, recheck) = (&s.tet, &s.recheck);
                let wanted = |v: u32| (everywhere || recheck[v as usize]) && tet.is_merged(v);
                let defects = &mut s.defects;
                defects.clear();
                defects.extend_from_slice(s.check.defects_among(&out.surface, wanted));
                if defects.is_empty() && self.options.fold_check {
                    // Manifold: now the folds that merging made (module doc), at every merged
                    // vertex the first time, then where repairs rewrote the mesh.
                    let all = !folds_checked;
                    defects.extend_from_slice(s.folds.folds_among(&out.surface, |v| (all || wanted(v)) && tet.is_merged(v)));
                    folds_checked = true;
                }
                if s.defects.is_empty() || !unmerge_and_regenerate(samples, &mut s.tet, out, &s.defects) {
                    break;
                }
                repaired = true;
                everywhere = mark_rewritten(s.tet.rewritten_vertices(), out.surface.positions.len(), &mut s.recheck);
            }
            out.stats.times.geometry = first_pass + t.elapsed();
        }
        if out.origins.wanted && matches!(samples.lattice(), Lattice::Cubic(_)) {
            s.tet.fill_origins(samples.grid(), first_pass_vertices, &mut out.origins);
        }
        // A crossing's vertex whose triangles all collapsed onto a merged neighbour (a piece of
        // surface where it meets the lattice's border) is left unused: dropped here too.
        if repaired || counts.discarded > 0 {
            finish_repair(out, &mut s.renumber);
        }
        compute_normals(out);
        Ok(s.tet.bytes() + s.renumber.capacity() * 4 + s.recheck.capacity() + s.folds.bytes() + s.defects.capacity() * 4)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::extractors::tetrahedral::{topology, TetKind};

    #[test]
    fn islands_split_a_mask_into_connected_parts() {
        let t = topology(TetKind::Bcc);
        let all: u16 = (1 << DIRECTIONS) - 1;
        assert_eq!(islands_of(all, &t.adjacency).count(), 1);
        // Two opposite axis neighbours are never adjacent.
        assert_eq!(islands_of(0b11, &t.adjacency).count(), 2);
        // An axis neighbour and a diagonal on its side are.
        let k = (0..DIRECTIONS).find(|&k| t.adjacency[0] >> k & 1 == 1).unwrap();
        assert_eq!(islands_of(1 | 1 << k, &t.adjacency).count(), 1);
    }

    #[test]
    fn a_ring_of_nearby_crossings_is_not_merged() {
        let t = topology(TetKind::Bcc);
        const ALL: u16 = (1 << DIRECTIONS) - 1;
        // Everything except the two z-axis neighbours: a band around the sample.
        let band = ALL & !(0b11 << 4);
        let star = Star { nearby: band & ((1 << 10) - 1), neighbours: ALL, crossings: [Vec3::ZERO; DIRECTIONS] };
        let complement = ALL & !star.nearby;
        if islands_of(complement, &t.adjacency).count() > 1 {
            let isl = RmtOptions::default().islands(&star, t);
            assert_eq!(isl.count as u32, star.nearby.count_ones());
        }
        let polar = Star { nearby: 1 << 4, neighbours: ALL, crossings: [Vec3::ZERO; DIRECTIONS] };
        assert_eq!(RmtOptions::default().islands(&polar, t).count, 1);
    }

    /// The guard checks again only the vertices a repair rewrote (for defects and folds);
    /// checking every merged vertex each round gives the same mesh, on cubic grids (partial re-passes) and BCC lattices (whole
    /// ones), on smooth fields and on white noise (where repairs take more than one round).
    #[test]
    fn rechecking_only_rewritten_vertices_finds_every_defect() {
        use crate::extractors::tetrahedral::{compute_normals, extract_tetrahedral, finish_repair, unmerge_and_regenerate};
        let mut cases: Vec<(String, Samples)> = Vec::new();
        for name in ["thin", "gyroid", "terrain", "asteroid"] {
            let field = crate::fields::builtin(name, Default::default()).unwrap();
            let grid = crate::lattice::Grid::covering(&field.domain(), 51).unwrap();
            for lattice in [Lattice::Cubic(grid), Lattice::Bcc(grid)] {
                cases.push((format!("{name} {lattice:?}"), Samples::sample(field.clone(), lattice, 0.0).unwrap()));
            }
        }
        let mut rng = crate::random::Random::new(20261129);
        for seed in 0..6 {
            let grid = crate::lattice::Grid { origin: Vec3::ZERO, spacing: 1.0, dims: [18, 18, 18] };
            for lattice in [Lattice::Cubic(grid), Lattice::Bcc(grid)] {
                let values = (0..lattice.sample_count()).map(|_| rng.unit_f32() - 0.5).collect();
                cases.push((format!("noise {seed} {lattice:?}"), Samples::from_values(lattice, values, 0.0).unwrap()));
            }
        }
        let mut rounds_seen = [0usize; 3];
        for (name, samples) in &cases {
            let mut guarded = Extraction::default();
            RegularisedMarchingTetrahedra::default().extract(samples, &mut guarded).unwrap();
            // The guard as it was: every merged vertex checked every round.
            let (mut scratch, mut out) = (TetScratch::default(), Extraction::default());
            let counts = extract_tetrahedral(samples, &RmtOptions::default(), &mut scratch, &mut out).unwrap();
            let (mut check, mut rounds, mut folds) = (ManifoldCheck::default(), 0, FoldCheck::default());
            loop {
                let mut defects = check.defects_among(&out.surface, |v| scratch.is_merged(v)).to_vec();
                if defects.is_empty() {
                    defects = folds.folds_among(&out.surface, |v| scratch.is_merged(v)).to_vec();
                }
                if defects.is_empty() || !unmerge_and_regenerate(samples, &mut scratch, &mut out, &defects) {
                    break;
                }
                rounds += 1;
            }
            if rounds > 0 || counts.discarded > 0 {
                finish_repair(&mut out, &mut Vec::new());
            }
            compute_normals(&mut out);
            rounds_seen[rounds.min(2)] += 1;
            assert_eq!(guarded.surface, out.surface, "{name}");
            assert!(crate::mesh::manifold_defects(&guarded.surface).is_empty(), "{name}");
        }
        assert!(rounds_seen[1] > 0 && rounds_seen[2] > 0, "repairs in one and in several rounds: {rounds_seen:?}");
    }
}
