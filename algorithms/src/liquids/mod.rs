//! # Liquids beside solids
//!
//! **Source:** the marching cubes terrain post (`../shared/papers/blog-marching-cubes-terrain-materials.txt`,
//! section "Viscosity"): one base density `B` in `[0, max]` and a viscosity `v` in `[0, 1]`, "the
//! percentage of density that is solid", give a solid density `v B` and a liquid density
//! `(1 − v) B`; a sample is solid where its solid density exceeds `max / 2`, liquid where its
//! liquid density does, air otherwise (at most one can, since the two sum to `B ≤ max`). Both
//! densities are meshed at `max / 2`, "and selectively choosing the solid geometry to keep when
//! two vertices coexist on an edge" joins the two meshes.
//!
//! **Summary.** [`Phases`] holds the two densities of every sample (the post's `B` and `v` are
//! [`Phases::base`] and [`Phases::viscosity`]; holding the densities themselves makes the
//! brushes' mass bookkeeping exact). [`extract_layers`] meshes the solid and the liquid densities
//! with one extractor, then applies the post's rule: every liquid vertex on a lattice edge between
//! a solid and a liquid sample takes the position of the solid mesh's vertex on that edge, so the
//! two meshes share their vertices where they touch. The brushes [`Phases::pour`],
//! [`Phases::drain`] and [`Phases::dig`] change one density each and return the mass they moved.
//!
//! **Where the rule carries over.** It needs one vertex per crossing lattice edge: marching cubes
//! (all three variants) and marching tetrahedra on Kuhn-split cubes, whose edges run from a
//! sample to a sample `+{0,1}³` (marching cubes 33's vertices inside a tunnel cell are on no edge
//! and shared with nothing). Surface nets and dual contouring put their vertices inside cells
//! and have no edge vertex to share: [`extract_layers`] refuses them with that reason (a shared
//! interface for cell-vertex extractors is the multi-label problem, [`crate::labels`]).
//!
//! **Guarantees.** Each mesh is its extractor's (closed, manifold and outward with air around the
//! domain). On marching tetrahedra the two bodies cannot overlap: inside a tetrahedron the
//! liquid's piece is the convex hull of its liquid corners and of crossings on edges where the
//! solid density is below `max / 2` at both ends or at `max / 2` exactly (the moved vertices), so
//! the whole piece has the linear solid density at most `max / 2`, while the solid's piece is
//! where it is at least that. Where a tetrahedron (or cube) has no air corner the two pieces meet
//! on one polygon that each side may split along another diagonal; the liquid then takes the
//! solid's triangles there, reversed, patch by patch where the patches' boundaries agree (so no
//! crack opens), and the contact is the same triangles in both meshes. Marching cubes' pieces are
//! not convex hulls of their crossings: a cell with solid, liquid and air corners can fill the
//! liquid's quad and the solid's pentagon along diagonals that pass through each other. So after
//! the rule, every cell where a liquid triangle crosses a solid one of the same cell (exact
//! predicates) has its polygons filled again (`untangle`: other triangulations of the same
//! outlines, liquid first, or a fan from a point inside the cell) until none crosses, checked by
//! the same predicates; [`Layers::crossing_cells`] and [`Layers::retiled_cells`] count them. What
//! is left unproved: a cell for which no filling is found (counted: the two counts differ), and
//! a crossing of the outlines on a face between two cells, which no filling can move (neither has
//! been seen: `tests/tests/liquids.rs` checks the scene and every edit of a brush script).
//!
//! **Non-guarantees.** A crossing within float rounding of a sample is stored at the sample: a
//! solid vertex there is still shared (found by its solid sample), but a liquid vertex rounded
//! onto its liquid sample cannot be told from the other edges of that sample and keeps its
//! place, leaving a sliver of air where the liquid density is within rounding of the iso-value.
//! Levels of detail for the two layers are not built.
//!
//! **Chunks.** [`ChunkedLayers`] (`chunked`) meshes the layers chunk by chunk, re-meshes only the
//! chunks a brush touched, and welds them into the whole grid's layers (tested equal).
//!
//! ```
//! use isolab_algorithms::liquids::{extract_layers, Phases};
//! use isolab_algorithms::{extractors, Grid, Options, Vec3};
//! // A pool: solid floor below z = 3.4, water above it up to z = 6.4, air around everything.
//! let grid = Grid { origin: Vec3::ZERO, spacing: 1.0, dims: [12, 12, 12] };
//! let mut phases = Phases::empty(grid, 1.0);
//! phases.fill(|p| {
//!     let inner = p.min_element() > 0.5 && p.max_element() < 10.5;
//!     let solid = if inner { (0.5 + (3.4 - p.z) / 2.0).clamp(0.0, 1.0) } else { 0.0 };
//!     let water = if inner { (0.5 + (6.4 - p.z) / 2.0).clamp(0.0, 1.0) } else { 0.0 };
//!     (solid, (water - solid).max(0.0))
//! });
//! let mc = extractors::build("marching-cubes", &Options::new()).unwrap().unwrap();
//! let layers = extract_layers(mc.as_ref(), &phases).unwrap();
//! assert!(layers.contact > 0 && !layers.liquid.triangles.is_empty());
//! ```

mod chunked;
mod untangle;

pub use chunked::ChunkedLayers;

use crate::extract::{Chunking, ExtractError, Extraction, Extractor};
use crate::lattice::{Grid, Lattice, LatticePlace};
use crate::mesh::TriMesh;
use crate::samples::Samples;
use glam::Vec3;
use petgraph::unionfind::UnionFind;
use rustc_hash::FxHashMap;

/// What a sample is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Phase {
    /// Solid density above half the maximum.
    Solid,
    /// Liquid density above half the maximum.
    Liquid,
    /// Neither.
    Air,
}

/// Solid and liquid densities on a cubic grid (index `x + nx * (y + ny * z)`), each in
/// `[0, max]`, their sum at most `max`.
#[derive(Clone, Debug)]
pub struct Phases {
    grid: Grid,
    max: f32,
    solid: Vec<f32>,
    liquid: Vec<f32>,
}

/// Total masses: density summed over the samples times the volume of a cell.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Masses {
    /// Solid mass.
    pub solid: f64,
    /// Liquid mass.
    pub liquid: f64,
}

/// Two meshes that share their vertices where solid meets liquid.
#[derive(Clone, Debug, Default)]
pub struct Layers {
    /// The solid's surface (against air and liquid).
    pub solid: TriMesh,
    /// The liquid's surface (against air and solid).
    pub liquid: TriMesh,
    /// Liquid vertices moved onto the solid's vertex of their edge (the post's rule).
    pub contact: usize,
    /// Cells where a liquid triangle crossed a solid one after the rule (marching cubes' pieces
    /// are not convex hulls of their crossings: the `untangle` rule of the module doc).
    pub crossing_cells: usize,
    /// Of those, the cells whose polygons were filled again so that none crosses.
    pub retiled_cells: usize,
}

impl Phases {
    /// All air: both densities 0 at every sample of `grid`; `max` is the densities' bound.
    pub fn empty(grid: Grid, max: f32) -> Phases {
        let n = grid.len();
        Phases { grid, max, solid: vec![0.0; n], liquid: vec![0.0; n] }
    }

    /// Phases from the post's fields: base density (clamped to `[0, max]`, as the post confines
    /// it) and viscosity (clamped to `[0, 1]`), one per sample. A non-finite value is an error
    /// naming the sample.
    pub fn from_base_viscosity(grid: Grid, max: f32, base: &[f32], viscosity: &[f32]) -> Result<Phases, ExtractError> {
        let bad = |reason: String| ExtractError::BadInput { algorithm: "liquids", reason };
        if !(max.is_finite() && max > 0.0) {
            return Err(bad(format!("the maximum density {max} is not positive and finite")));
        }
        if base.len() != grid.len() || viscosity.len() != grid.len() {
            return Err(bad(format!(
                "a {:?} grid needs {} base densities and viscosities, not {} and {}",
                grid.dims,
                grid.len(),
                base.len(),
                viscosity.len()
            )));
        }
        if let Some(i) = (0..base.len()).find(|&i| !base[i].is_finite() || !viscosity[i].is_finite()) {
            return Err(bad(format!("sample {i}: base {} and viscosity {} must be finite", base[i], viscosity[i])));
        }
        let mut phases = Phases::empty(grid, max);
        for i in 0..base.len() {
            let (b, v) = (base[i].clamp(0.0, max), viscosity[i].clamp(0.0, 1.0));
            phases.solid[i] = v * b;
            phases.liquid[i] = (b - v * b).max(0.0);
        }
        Ok(phases)
    }

    /// Sets every sample from `densities(position) = (solid, liquid)` in units of `max`
    /// (clamped so that each is in `[0, 1]` and their sum at most 1).
    pub fn fill(&mut self, densities: impl Fn(Vec3) -> (f32, f32)) {
        let [nx, ny, nz] = self.grid.dims;
        for z in 0..nz {
            for y in 0..ny {
                for x in 0..nx {
                    let (s, l) = densities(self.grid.position(x, y, z));
                    let s = if s.is_finite() { s.clamp(0.0, 1.0) } else { 0.0 };
                    let l = if l.is_finite() { l.clamp(0.0, 1.0 - s) } else { 0.0 };
                    let i = self.grid.index(x, y, z);
                    (self.solid[i], self.liquid[i]) = (s * self.max, l * self.max);
                }
            }
        }
    }

    /// The samples from `lo` (sample indices), `dims` per axis, on a grid in the whole grid's
    /// index coordinates (origin `lo`, unit spacing), so that blocks mesh to bit-equal vertices
    /// on the planes they share.
    pub fn block(&self, lo: [usize; 3], dims: [usize; 3]) -> Phases {
        let grid = Grid { origin: Vec3::new(lo[0] as f32, lo[1] as f32, lo[2] as f32), spacing: 1.0, dims };
        let mut block = Phases::empty(grid, self.max);
        for z in 0..dims[2] {
            for y in 0..dims[1] {
                for x in 0..dims[0] {
                    let (i, j) = (self.grid.index(lo[0] + x, lo[1] + y, lo[2] + z), grid.index(x, y, z));
                    (block.solid[j], block.liquid[j]) = (self.solid[i], self.liquid[i]);
                }
            }
        }
        block
    }

    /// The grid.
    pub fn grid(&self) -> &Grid {
        &self.grid
    }

    /// The densities' bound (the iso-value is half of it).
    pub fn max(&self) -> f32 {
        self.max
    }

    /// Solid densities, one per sample.
    pub fn solid(&self) -> &[f32] {
        &self.solid
    }

    /// Liquid densities, one per sample.
    pub fn liquid(&self) -> &[f32] {
        &self.liquid
    }

    /// The post's base density of sample `i`: solid plus liquid.
    pub fn base(&self, i: usize) -> f32 {
        self.solid[i] + self.liquid[i]
    }

    /// The post's viscosity of sample `i`: the solid share of its base density (1 where the
    /// base density is 0).
    pub fn viscosity(&self, i: usize) -> f32 {
        let b = self.base(i);
        if b > 0.0 {
            self.solid[i] / b
        } else {
            1.0
        }
    }

    /// What sample `i` is.
    pub fn phase(&self, i: usize) -> Phase {
        let iso = self.max / 2.0;
        if self.solid[i] > iso {
            Phase::Solid
        } else if self.liquid[i] > iso {
            Phase::Liquid
        } else {
            Phase::Air
        }
    }

    /// The total solid and liquid masses.
    pub fn masses(&self) -> Masses {
        let cell = (self.grid.spacing as f64).powi(3);
        let sum = |v: &[f32]| v.iter().map(|&d| d as f64).sum::<f64>() * cell;
        Masses { solid: sum(&self.solid), liquid: sum(&self.liquid) }
    }

    /// Adds up to `amount · max` of liquid to each sample within `radius` of `centre`, tapering
    /// linearly to 0 at the radius, never past the room a sample has (`max` minus what it
    /// holds). Returns the liquid mass added.
    pub fn pour(&mut self, centre: Vec3, radius: f32, amount: f32) -> f64 {
        self.brush(centre, radius, amount, |solid, liquid, max, add| {
            *liquid = (*liquid + add).min(max - *solid).max(*liquid);
        })
        .liquid
    }

    /// Removes up to `amount · max` of liquid from each sample within `radius` of `centre`
    /// (tapering as [`Phases::pour`]). Returns the liquid mass removed.
    pub fn drain(&mut self, centre: Vec3, radius: f32, amount: f32) -> f64 {
        -self.brush(centre, radius, amount, |_, liquid, _, take| *liquid = (*liquid - take).max(0.0)).liquid
    }

    /// Removes up to `amount · max` of solid from each sample within `radius` of `centre`
    /// (tapering as [`Phases::pour`]); the liquid stays. Returns the solid mass removed.
    pub fn dig(&mut self, centre: Vec3, radius: f32, amount: f32) -> f64 {
        -self.brush(centre, radius, amount, |solid, _, _, take| *solid = (*solid - take).max(0.0)).solid
    }

    /// Applies `edit(solid, liquid, max, change)` to the samples of the ball, returning the
    /// change of each mass (summed from the stored values, so it is exact bookkeeping).
    fn brush(&mut self, centre: Vec3, radius: f32, amount: f32, edit: impl Fn(&mut f32, &mut f32, f32, f32)) -> Masses {
        let cell = (self.grid.spacing as f64).powi(3);
        let mut change = Masses { solid: 0.0, liquid: 0.0 };
        if !(radius > 0.0 && amount.is_finite() && amount > 0.0 && centre.is_finite()) {
            return change;
        }
        let g = self.grid;
        let lo = ((centre - radius - g.origin) / g.spacing).floor().max(Vec3::ZERO);
        let hi = ((centre + radius - g.origin) / g.spacing).ceil();
        let top = |a: usize| (hi[a].max(0.0) as usize).min(g.dims[a] - 1);
        for z in lo.z as usize..=top(2) {
            for y in lo.y as usize..=top(1) {
                for x in lo.x as usize..=top(0) {
                    let d = g.position(x, y, z).distance(centre);
                    if d >= radius {
                        continue;
                    }
                    let i = g.index(x, y, z);
                    let (s0, l0) = (self.solid[i], self.liquid[i]);
                    edit(&mut self.solid[i], &mut self.liquid[i], self.max, amount * self.max * (1.0 - d / radius));
                    change.solid += (self.solid[i] as f64 - s0 as f64) * cell;
                    change.liquid += (self.liquid[i] as f64 - l0 as f64) * cell;
                }
            }
        }
        change
    }

    /// Samples of one density for an extractor: inside (below 0) where the density exceeds
    /// half the maximum.
    fn samples(&self, density: &[f32]) -> Result<Samples<'static>, ExtractError> {
        let iso = self.max / 2.0;
        Ok(Samples::from_values(Lattice::Cubic(self.grid), density.iter().map(|&d| iso - d).collect(), 0.0)?)
    }
}

/// A terrain scene of `n` x `n` x `n / 2` samples (unit spacing, from the origin): rolling ground
/// with a basin holding a lake, a ball-shaped cave under the ground with its lower half flooded,
/// and air on every border sample (so both layers close). `max` is 1.
pub fn lake_and_cave(n: usize) -> Phases {
    let grid = Grid { origin: Vec3::ZERO, spacing: 1.0, dims: [n, n, n / 2] };
    let mut phases = Phases::empty(grid, 1.0);
    let (c, h, side) = (n as f32 / 2.0, (n / 2) as f32, n as f32);
    let ramp = |d: f32| (0.5 + d / 1.5).clamp(0.0, 1.0);
    let cave = Vec3::new(0.3 * side, 0.65 * side, 0.3 * h);
    let cave_r = 0.14 * side;
    phases.fill(|p| {
        if p.min_element() < 0.5 || p.x > side - 1.5 || p.y > side - 1.5 || p.z > h - 1.5 {
            return (0.0, 0.0);
        }
        let r = ((p.x - c).powi(2) + (p.y - c).powi(2)).sqrt();
        let basin = 0.25 * h * (-(r / (0.3 * side)).powi(2)).exp();
        let ground = 0.55 * h + 0.08 * h * (p.x * 0.31).sin() * (p.y * 0.23).cos() - basin;
        let solid = ramp(ground - p.z).min(ramp(p.distance(cave) - cave_r));
        let lake = ramp(0.52 * h - p.z) * ramp(0.4 * side - r);
        let flood = ramp(cave.z - p.z) * ramp(cave_r + 1.0 - p.distance(cave));
        (solid, lake.max(flood).min(1.0 - solid))
    });
    phases
}

/// Meshes the solid and the liquid of `phases` with `extractor` and moves every liquid vertex on
/// a solid–liquid lattice edge onto the solid's vertex there (module doc); liquid vertices moved
/// onto one solid vertex become one, and where every corner of a liquid triangle was moved, the
/// liquid takes the solid's triangles there, reversed (the two quads of a cell or tetrahedron can
/// be split along different diagonals). Then every cell where a liquid triangle still crosses a
/// solid one has its polygons filled again so that none does (module doc). An extractor whose
/// vertices are not on lattice edges is refused, naming it.
pub fn extract_layers(extractor: &dyn Extractor, phases: &Phases) -> Result<Layers, ExtractError> {
    layers(extractor, phases, true)
}

/// [`extract_layers`] with the post's rule alone: no cell is filled again where the two layers
/// cross (for comparing what the untangling costs and buys).
pub fn extract_layers_without_untangling(extractor: &dyn Extractor, phases: &Phases) -> Result<Layers, ExtractError> {
    layers(extractor, phases, false)
}

fn layers(extractor: &dyn Extractor, phases: &Phases, untangle: bool) -> Result<Layers, ExtractError> {
    let mut out = Extraction::default();
    extractor.extract(&phases.samples(&phases.solid)?, &mut out)?;
    let solid = std::mem::take(&mut out.surface);
    extractor.extract(&phases.samples(&phases.liquid)?, &mut out)?;
    let liquid = std::mem::take(&mut out.surface);
    let targets = contact_targets(extractor, phases, &solid, &liquid)?;
    let contact = targets.iter().flatten().count();
    let mut liquid = share_contact(&solid, liquid, &targets);
    let mut solid = solid;
    let untangled = if untangle { untangle::untangle(phases.grid(), &mut solid, &mut liquid) } else { Default::default() };
    Ok(Layers { solid, liquid, contact, crossing_cells: untangled.crossing_cells, retiled_cells: untangled.retiled })
}

/// For each liquid vertex, the solid vertex of its lattice edge when the edge joins a solid and a
/// liquid sample (the solid's vertex rounded onto the edge's solid sample when its crossing is
/// within float rounding of it). A vertex off the lattice edges is refused unless the extractor
/// is cell-local (marching cubes 33's vertices inside tunnel cells: not on an edge, so never
/// shared).
fn contact_targets(
    extractor: &dyn Extractor,
    phases: &Phases,
    solid: &TriMesh,
    liquid: &TriMesh,
) -> Result<Vec<Option<u32>>, ExtractError> {
    let grid = phases.grid();
    let (mut on_edges, mut on_samples) = (FxHashMap::default(), FxHashMap::default());
    for (v, &p) in solid.positions.iter().enumerate() {
        match grid.place(p) {
            LatticePlace::Edge(a, b) => {
                on_edges.insert((a, b), v as u32);
            }
            LatticePlace::Sample(i) => {
                on_samples.insert(i, v as u32);
            }
            LatticePlace::Elsewhere if extractor.chunking() == Chunking::CellLocal => {}
            LatticePlace::Elsewhere => {
                return Err(ExtractError::BadInput {
                    algorithm: extractor.name(),
                    reason: format!(
                        "its vertex {v} at {p} is not on a lattice edge: the post's rule shares the vertex of an edge \
                         between solid and liquid, and this extractor places vertices inside cells (marching cubes and \
                         marching tetrahedra on cubes have edge vertices)"
                    ),
                })
            }
        }
    }
    Ok(liquid
        .positions
        .iter()
        .map(|&p| {
            let LatticePlace::Edge(a, b) = grid.place(p) else { return None };
            let solid_end = match (phases.phase(a), phases.phase(b)) {
                (Phase::Solid, Phase::Liquid) => a,
                (Phase::Liquid, Phase::Solid) => b,
                _ => return None,
            };
            on_edges.get(&(a, b)).or_else(|| on_samples.get(&solid_end)).copied()
        })
        .collect())
}

/// The liquid mesh with its contact vertices moved onto their solid targets and merged per
/// target, triangles left degenerate by the merge dropped, the all-contact triangles replaced by
/// the solid's reversed, and unused vertices removed.
fn share_contact(solid: &TriMesh, mut liquid: TriMesh, targets: &[Option<u32>]) -> TriMesh {
    let mut of_solid: FxHashMap<u32, u32> = FxHashMap::default();
    let remap: Vec<u32> = (0..liquid.positions.len() as u32)
        .map(|v| match targets[v as usize] {
            Some(s) => {
                liquid.positions[v as usize] = solid.positions[s as usize];
                *of_solid.entry(s).or_insert(v)
            }
            None => v,
        })
        .collect();
    let moved = |v: u32| targets[v as usize].is_some();
    let remapped = liquid.triangles.iter().map(|t| t.map(|v| remap[v as usize]));
    let kept = remapped.filter(|t| t[0] != t[1] && t[1] != t[2] && t[0] != t[2]);
    let (contact, mut triangles): (Vec<[u32; 3]>, Vec<[u32; 3]>) = kept.partition(|t| t.iter().all(|&v| moved(v)));
    // The all-contact triangles in solid vertex ids, and the solid's own reversed.
    let to_solid = |t: [u32; 3]| t.map(|v| targets[v as usize].unwrap_or(u32::MAX));
    let liquid_side: Vec<[u32; 3]> = contact.iter().map(|&t| to_solid(t)).collect();
    let solid_side: Vec<[u32; 3]> =
        solid.triangles.iter().filter(|t| t.iter().all(|s| of_solid.contains_key(s))).map(|&[a, b, c]| [c, b, a]).collect();
    let take_solid = matching_patches(solid.positions.len(), &liquid_side, &solid_side);
    for (t, &l) in contact.iter().zip(&liquid_side) {
        if !take_solid[l[0] as usize] {
            triangles.push(*t);
        }
    }
    triangles.extend(solid_side.iter().filter(|t| take_solid[t[0] as usize]).map(|t| t.map(|s| of_solid[&s])));
    let mut used = vec![u32::MAX; liquid.positions.len()];
    let mut positions = Vec::new();
    for t in &mut triangles {
        for v in t.iter_mut() {
            if used[*v as usize] == u32::MAX {
                used[*v as usize] = positions.len() as u32;
                positions.push(liquid.positions[*v as usize]);
            }
            *v = used[*v as usize];
        }
    }
    let mut mesh = TriMesh { positions, normals: Vec::new(), triangles };
    if !liquid.normals.is_empty() {
        mesh.compute_face_weighted_normals();
    }
    mesh
}

/// Per solid vertex: whether its patch of contact (triangles joined by shared vertices, from both
/// sides) has the same boundary on the liquid's side as the solid's reversed triangles there, so
/// that the liquid can take the solid's triangles without opening a crack. Both sides are in
/// solid vertex ids, wound as the liquid's surface.
fn matching_patches(vertices: usize, liquid_side: &[[u32; 3]], solid_side: &[[u32; 3]]) -> Vec<bool> {
    let mut patches = UnionFind::<u32>::new(vertices);
    for t in liquid_side.iter().chain(solid_side) {
        patches.union(t[0], t[1]);
        patches.union(t[1], t[2]);
    }
    // The boundary of a set of triangles: its directed edges whose reverse it does not hold.
    let boundary = |tris: &[[u32; 3]]| {
        let edges: rustc_hash::FxHashSet<(u32, u32)> = tris.iter().flat_map(|&[a, b, c]| [(a, b), (b, c), (c, a)]).collect();
        let mut by_patch: FxHashMap<u32, Vec<(u32, u32)>> = FxHashMap::default();
        for &(a, b) in edges.iter().filter(|&&(a, b)| !edges.contains(&(b, a))) {
            by_patch.entry(patches.find(a)).or_default().push((a, b));
        }
        by_patch.values_mut().for_each(|e| e.sort_unstable());
        by_patch
    };
    let (liquid_edges, solid_edges) = (boundary(liquid_side), boundary(solid_side));
    let roots: rustc_hash::FxHashSet<u32> = liquid_side.iter().chain(solid_side).map(|t| patches.find(t[0])).collect();
    let matching: rustc_hash::FxHashSet<u32> = roots.into_iter().filter(|r| liquid_edges.get(r) == solid_edges.get(r)).collect();
    (0..vertices as u32).map(|v| matching.contains(&patches.find(v))).collect()
}
