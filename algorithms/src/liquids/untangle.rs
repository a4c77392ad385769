//! Solid and liquid kept apart cell by cell, for extractors whose pieces in a cell are not the
//! convex hulls of their crossings (marching cubes).
//!
//! **The defect.** Sharing the contact vertices (the post's rule) makes the two meshes meet on
//! the lattice edges, but marching cubes triangulates each layer's polygons in a cell on its own:
//! where a cell holds solid, liquid and air corners, the liquid's quad and the solid's pentagon
//! can be split along diagonals that pass through each other (`tests/tests/liquids.rs` found every
//! crossing of the `lake_and_cave` scene in such cells).
//!
//! **The rule.** Every triangle of a cell-local extractor lies in its cell, and the polygons'
//! outlines on the cell's faces are fixed by the neighbours; only how each polygon is filled is
//! free. Triangles of two cells meet only on the face between them, along those outlines, so a
//! crossing that a filling can undo is one inside a cell. For every cell where a liquid triangle
//! crosses a solid one of the same cell (exact predicates), the
//! patches of the cell (its triangles joined by shared edges; those with one boundary loop and
//! the Euler characteristic of a disk) are filled again, first the liquid's, then the solid's,
//! then both, through every triangulation of their loops (up to [`crate::geometry::ALL_TRIANGULATIONS_UP_TO`]
//! corners, fans from each corner beyond), and last as fans from a point of a lattice inside the
//! cell. The first filling under which no triangle of the cell crosses another of either layer
//! (a liquid triangle that is a solid one reversed is the shared contact, as the metric counts
//! it), no new edge lies on a face of the cell (so the neighbours cannot be touched) and no edge
//! is held by more than two triangles is kept. A cell for which none is found keeps its
//! triangles and is counted.
//!
//! The decision reads only the cell's own triangles (and any of a neighbour's lying within the
//! cell's closed box), so chunks that mesh a terrain piecewise decide as the whole grid does.

use crate::geometry::all_triangulations;
use crate::lattice::Grid;
use crate::mesh::TriMesh;
use crate::predicates::{has_zero_area, indexed_triangles_intersect};
use glam::{DVec3, Vec3};
use petgraph::unionfind::UnionFind;
use rayon::prelude::*;
use rustc_hash::{FxHashMap, FxHashSet};

/// Fan centres per axis of the lattice inside a cell (tried nearest the loop's centroid first).
const FAN_LATTICE: usize = 8;
/// Fillings tried per cell and phase at most.
const MOST_FILLINGS: usize = 20_000;

/// What [`untangle`] did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Untangled {
    /// Cells where a liquid triangle crossed a solid one.
    pub crossing_cells: usize,
    /// Of those, the cells filled again without a crossing.
    pub retiled: usize,
}

type Cell = [i64; 3];
type Tri = [u32; 3];

/// A cell's triangles of both layers (and of its neighbours within its box) on one local vertex
/// numbering, positions equal bit for bit being one vertex.
#[derive(Default)]
struct Local {
    positions: Vec<Vec3>,
}

impl Local {
    fn vertex(&mut self, p: Vec3) -> u32 {
        let bits = p.to_array().map(f32::to_bits);
        let k = self.positions.iter().position(|q| q.to_array().map(f32::to_bits) == bits).unwrap_or_else(|| {
            self.positions.push(p);
            self.positions.len() - 1
        });
        k as u32
    }

    fn triangle(&mut self, mesh: &TriMesh, t: Tri) -> Tri {
        t.map(|v| self.vertex(mesh.positions[v as usize]))
    }
}

fn sorted(t: Tri) -> Tri {
    let mut k = t;
    k.sort_unstable();
    k
}

/// The cells of a grid, numbered x fastest.
struct Cells<'a> {
    grid: &'a Grid,
    counts: [i64; 3],
    /// `1 / (3 spacing)`: from a sum of three corners to index coordinates.
    scale: f64,
}

impl Cells<'_> {
    /// The cell holding a triangle: the one its centroid is in (index coordinates, in `f64`),
    /// clamped to the grid's cells.
    fn of(&self, p: [Vec3; 3]) -> Cell {
        let sum = p[0].as_dvec3() + p[1].as_dvec3() + p[2].as_dvec3();
        let q = ((sum - 3.0 * self.grid.origin.as_dvec3()) * self.scale).to_array();
        // Truncation is the floor here: below 0 clamps to the first cell anyway.
        std::array::from_fn(|a| (q[a].max(0.0) as i64).min(self.counts[a] - 1))
    }

    fn key(&self, c: Cell) -> Option<u64> {
        (0..3)
            .all(|a| c[a] >= 0 && c[a] < self.counts[a])
            .then(|| (c[0] + self.counts[0] * (c[1] + self.counts[1] * c[2])) as u64)
    }

    fn count(&self) -> u64 {
        self.counts.iter().product::<i64>() as u64
    }

    fn cell(&self, key: u64) -> Cell {
        let k = key as i64;
        [k % self.counts[0], (k / self.counts[0]) % self.counts[1], k / (self.counts[0] * self.counts[1])]
    }

    /// `(cell key, triangle)` for the triangles of `mesh` whose cell `keep` accepts, sorted.
    fn sorted_triangles(&self, mesh: &TriMesh, keep: impl Fn(u64) -> bool) -> Vec<(u64, u32)> {
        let mut keyed: Vec<(u64, u32)> = (0..mesh.triangles.len() as u32)
            .filter_map(|i| {
                let p = mesh.triangles[i as usize].map(|v| mesh.positions[v as usize]);
                let key = self.key(self.of(p)).unwrap_or(u64::MAX);
                keep(key).then_some((key, i))
            })
            .collect();
        keyed.sort_unstable_by_key(|&(k, _)| k);
        keyed
    }
}

/// A set of cell keys: a bit per cell while the grid has at most [`DENSE_CELLS`] cells (a
/// lookup per solid triangle is most of the untangling's cost where nothing crosses).
enum CellSet {
    Dense(Vec<u64>),
    Sparse(FxHashSet<u64>),
}

/// Grids up to this many cells keep a bit per cell (8 MB).
const DENSE_CELLS: u64 = 1 << 26;

impl CellSet {
    fn new(cells: u64, keys: impl Iterator<Item = u64>) -> CellSet {
        if cells <= DENSE_CELLS {
            let mut bits = vec![0u64; cells.div_ceil(64) as usize];
            keys.filter(|&k| k < cells).for_each(|k| bits[(k / 64) as usize] |= 1 << (k % 64));
            CellSet::Dense(bits)
        } else {
            CellSet::Sparse(keys.collect())
        }
    }

    fn contains(&self, key: u64) -> bool {
        match self {
            CellSet::Dense(bits) => bits.get((key / 64) as usize).is_some_and(|w| w & (1 << (key % 64)) != 0),
            CellSet::Sparse(set) => set.contains(&key),
        }
    }
}

/// The triangles of `keyed` (sorted) in the cell with `key`.
fn in_cell(keyed: &[(u64, u32)], key: u64) -> impl Iterator<Item = u32> + '_ {
    let start = keyed.partition_point(|&(k, _)| k < key);
    keyed[start..].iter().take_while(move |&&(k, _)| k == key).map(|&(_, i)| i)
}

/// Which of the cell's six faces (bits: x low, x high, y low, ...) a point lies on.
fn faces_of(grid: &Grid, cell: Cell, p: Vec3) -> u8 {
    let q = grid.index_coords(p);
    let mut mask = 0;
    for a in 0..3 {
        mask |= u8::from(q[a] == cell[a] as f32) << (2 * a);
        mask |= u8::from(q[a] == (cell[a] + 1) as f32) << (2 * a + 1);
    }
    mask
}

/// Whether a point lies in the cell's closed box (index coordinates).
fn in_closed_cell(grid: &Grid, cell: Cell, p: Vec3) -> bool {
    let q = grid.index_coords(p);
    (0..3).all(|a| q[a] >= cell[a] as f32 && q[a] <= (cell[a] + 1) as f32)
}

/// Fills again, cell by cell, the patches of the cells where a liquid triangle crosses a solid
/// one of the same cell (module doc); both meshes are rewritten where a cell is retiled.
pub fn untangle(grid: &Grid, solid: &mut TriMesh, liquid: &mut TriMesh) -> Untangled {
    let counts = grid.dims.map(|d| d.saturating_sub(1).max(1) as i64);
    let cells = Cells { grid, counts, scale: 1.0 / (3.0 * grid.spacing as f64) };
    let liquid_keyed = cells.sorted_triangles(liquid, |_| true);
    let liquid_cells = CellSet::new(cells.count(), liquid_keyed.iter().map(|&(k, _)| k));
    let mut keyed = [cells.sorted_triangles(solid, |k| liquid_cells.contains(k)), liquid_keyed];
    let meshes = [&*solid, &*liquid];
    // The cells holding triangles of both layers, and of those the ones where they cross.
    let mut both: Vec<(u64, [std::ops::Range<usize>; 2])> = Vec::new();
    let (mut i, mut j) = (0, 0);
    while i < keyed[0].len() && j < keyed[1].len() {
        let (ks, kl) = (keyed[0][i].0, keyed[1][j].0);
        if ks != kl {
            if ks < kl {
                i += 1;
            } else {
                j += 1;
            }
            continue;
        }
        let (s_end, l_end) = (i + in_cell(&keyed[0][i..], ks).count(), j + in_cell(&keyed[1][j..], kl).count());
        if ks != u64::MAX {
            both.push((ks, [i..s_end, j..l_end]));
        }
        (i, j) = (s_end, l_end);
    }
    let crossing: Vec<u64> = both
        .par_iter()
        .map_init(CrossScratch::default, |scratch, (k, [s, l])| {
            scratch.crosses(meshes, &keyed[0][s.clone()], &keyed[1][l.clone()]).then_some(*k)
        })
        .flatten()
        .collect();
    let mut report = Untangled { crossing_cells: crossing.len(), retiled: 0 };
    if crossing.is_empty() {
        return report;
    }
    // The neighbours' solid triangles too, for the cells to retile.
    keyed[0] = cells.sorted_triangles(solid, |_| true);
    let mut drop = [vec![false; solid.triangles.len()], vec![false; liquid.triangles.len()]];
    let mut added: [Vec<[Vec3; 3]>; 2] = [Vec::new(), Vec::new()];
    for &key in &crossing {
        let cell = cells.cell(key);
        let mut local = Local::default();
        // The cell's triangles in an order of their own (by position), so that the search
        // decides the same whatever the meshes' order (a chunk's or the whole grid's).
        let own: [Vec<u32>; 2] = [0, 1].map(|m| by_position(meshes[m], in_cell(&keyed[m], key).collect()));
        let tris: [Vec<Tri>; 2] =
            [0, 1].map(|m| own[m].iter().map(|&t| local.triangle(meshes[m], meshes[m].triangles[t as usize])).collect());
        let mut obstacles: [Vec<Tri>; 2] = [Vec::new(), Vec::new()];
        for near in neighbours(cell).filter(|&n| n != cell).filter_map(|n| cells.key(n)) {
            for m in 0..2 {
                for t in by_position(meshes[m], in_cell(&keyed[m], near).collect()) {
                    let t = meshes[m].triangles[t as usize];
                    if t.iter().all(|&v| in_closed_cell(grid, cell, meshes[m].positions[v as usize])) {
                        obstacles[m].push(local.triangle(meshes[m], t));
                    }
                }
            }
        }
        let [obstacles_solid, obstacles_liquid] = obstacles;
        let problem = CellProblem { grid, cell, obstacles: (obstacles_solid, obstacles_liquid) };
        if let Some((s2, l2)) = problem.retile(&mut local.positions, &tris[0], &tris[1]) {
            report.retiled += 1;
            for m in 0..2 {
                own[m].iter().for_each(|&t| drop[m][t as usize] = true);
            }
            added[0].extend(s2.iter().map(|t| t.map(|v| local.positions[v as usize])));
            added[1].extend(l2.iter().map(|t| t.map(|v| local.positions[v as usize])));
        }
    }
    let [added_solid, added_liquid] = added;
    if report.retiled > 0 {
        rebuild(solid, &drop[0], &added_solid);
        rebuild(liquid, &drop[1], &added_liquid);
    }
    report
}

/// Triangles of `mesh` sorted by their corners' positions (each triangle from its least corner,
/// its winding kept).
fn by_position(mesh: &TriMesh, mut tris: Vec<u32>) -> Vec<u32> {
    let key = |t: u32| {
        let p = mesh.triangles[t as usize].map(|v| mesh.positions[v as usize].to_array().map(f32::to_bits));
        let first = (0..3).min_by_key(|&k| p[k]).unwrap_or(0);
        [p[first], p[(first + 1) % 3], p[(first + 2) % 3]]
    };
    tris.sort_by_cached_key(|&t| key(t));
    tris
}

/// Buffers for [`CrossScratch::crosses`], kept per thread across the cells it tests.
#[derive(Default)]
struct CrossScratch {
    local: Local,
    solid: Vec<Tri>,
    liquid: Vec<Tri>,
}

impl CrossScratch {
    /// Whether a liquid triangle of the cell crosses a solid one of it (a liquid triangle that
    /// is a solid one reversed is the shared contact).
    fn crosses(&mut self, meshes: [&TriMesh; 2], solid: &[(u64, u32)], liquid: &[(u64, u32)]) -> bool {
        let CrossScratch { local, solid: s, liquid: l } = self;
        local.positions.clear();
        s.clear();
        l.clear();
        s.extend(solid.iter().map(|&(_, t)| local.triangle(meshes[0], meshes[0].triangles[t as usize])));
        l.extend(liquid.iter().map(|&(_, t)| local.triangle(meshes[1], meshes[1].triangles[t as usize])));
        let at = |v: u32| local.positions[v as usize];
        let shared = |t: Tri| s.iter().any(|&o| sorted(o) == sorted(t));
        l.iter().filter(|&&t| !shared(t)).any(|&lt| s.iter().any(|&st| indexed_triangles_intersect(st, lt, at)))
    }
}

/// The cell and its 26 neighbours.
fn neighbours(cell: Cell) -> impl Iterator<Item = Cell> {
    (0..27).map(move |k| [cell[0] + k % 3 - 1, cell[1] + (k / 3) % 3 - 1, cell[2] + k / 9 - 1])
}

/// `mesh` without its `dropped` triangles and with `added` ones (by position: a position bit-equal
/// to one of its vertices is that vertex; others are appended, with the normal of the triangles
/// around them when the mesh has normals).
fn rebuild(mesh: &mut TriMesh, dropped: &[bool], added: &[[Vec3; 3]]) {
    let mut id: FxHashMap<[u32; 3], u32> = FxHashMap::default();
    for t in mesh.triangles.iter().zip(dropped).filter(|(_, &d)| d).map(|(t, _)| t) {
        for &v in t {
            id.insert(mesh.positions[v as usize].to_array().map(f32::to_bits), v);
        }
    }
    let first_new = mesh.positions.len();
    let mut kept: Vec<Tri> = mesh.triangles.iter().zip(dropped).filter(|(_, &d)| !d).map(|(&t, _)| t).collect();
    for t in added {
        kept.push(t.map(|p| {
            *id.entry(p.to_array().map(f32::to_bits)).or_insert_with(|| {
                mesh.positions.push(p);
                mesh.positions.len() as u32 - 1
            })
        }));
    }
    mesh.triangles = kept;
    if !mesh.normals.is_empty() && mesh.positions.len() > first_new {
        let mut sums = vec![Vec3::ZERO; mesh.positions.len() - first_new];
        for t in &mesh.triangles {
            let p = t.map(|v| mesh.positions[v as usize]);
            let n = (p[1] - p[0]).cross(p[2] - p[0]);
            for &v in t.iter().filter(|&&v| v as usize >= first_new) {
                sums[v as usize - first_new] += n;
            }
        }
        mesh.normals.extend(sums.into_iter().map(|n| n.normalize_or_zero()));
    }
}

/// One cell to fill again.
struct CellProblem<'a> {
    grid: &'a Grid,
    cell: Cell,
    /// Neighbours' solid and liquid triangles within the cell's closed box.
    obstacles: (Vec<Tri>, Vec<Tri>),
}

/// A patch of one layer in the cell: its triangles, and its boundary loop when it is a disk.
struct Patch {
    triangles: Vec<Tri>,
    ring: Option<Vec<u32>>,
}

impl CellProblem<'_> {
    /// New solid and liquid triangles for the cell, or `None` when no filling keeps them apart.
    fn retile(&self, positions: &mut Vec<Vec3>, solid: &[Tri], liquid: &[Tri]) -> Option<(Vec<Tri>, Vec<Tri>)> {
        let sp = self.patches(positions, solid);
        let lp = self.patches(positions, liquid);
        let triangulations = |ps: &[Patch]| -> Vec<Vec<Vec<Tri>>> {
            ps.iter().map(|p| p.ring.as_ref().map_or_else(|| vec![p.triangles.clone()], |r| all_triangulations(r))).collect()
        };
        let kept = |ps: &[Patch]| -> Vec<Vec<Vec<Tri>>> { ps.iter().map(|p| vec![p.triangles.clone()]).collect() };
        let (st, lt) = (triangulations(&sp), triangulations(&lp));
        let old = (edge_set(solid), edge_set(liquid));
        let phases = [(kept(&sp), lt.clone()), (st.clone(), kept(&lp)), (st, lt)];
        for (s_choices, l_choices) in &phases {
            if let Some(found) = self.search(positions, s_choices, l_choices, &old) {
                return Some(found);
            }
        }
        // Fans from a point inside the cell: one patch at a time, the other layer as it was.
        for liquid_side in [true, false] {
            let (ps, other) = if liquid_side { (&lp, &sp) } else { (&sp, &lp) };
            for k in 0..ps.len() {
                let Some(ring) = &ps[k].ring else { continue };
                for centre in self.fan_centres(positions, ring) {
                    positions.push(centre);
                    let c = positions.len() as u32 - 1;
                    let mut choices = kept(ps);
                    choices[k] = vec![fan(c, ring)];
                    let (s_choices, l_choices) = if liquid_side { (kept(other), choices) } else { (choices, kept(other)) };
                    if let Some(found) = self.search(positions, &s_choices, &l_choices, &old) {
                        return Some(found);
                    }
                    positions.pop();
                }
            }
        }
        None
    }

    /// The first combination of the patches' fillings (every patch one of its choices) that
    /// keeps the cell apart, trying at most [`MOST_FILLINGS`].
    fn search(
        &self,
        positions: &[Vec3],
        s: &[Vec<Vec<Tri>>],
        l: &[Vec<Vec<Tri>>],
        old: &(FxHashSet<[u32; 2]>, FxHashSet<[u32; 2]>),
    ) -> Option<(Vec<Tri>, Vec<Tri>)> {
        let radix: Vec<usize> = s.iter().chain(l).map(Vec::len).collect();
        let mut digits = vec![0usize; radix.len()];
        for _ in 0..MOST_FILLINGS {
            let pick = |choices: &[Vec<Vec<Tri>>], offset: usize| -> Vec<Tri> {
                choices.iter().enumerate().flat_map(|(k, c)| c[digits[offset + k]].iter().copied()).collect()
            };
            let (s2, l2) = (pick(s, 0), pick(l, s.len()));
            if self.apart(positions, &s2, &l2, old) {
                return Some((s2, l2));
            }
            // Next combination (mixed radix); done when it wraps.
            let mut k = 0;
            loop {
                if k == digits.len() {
                    return None;
                }
                digits[k] += 1;
                if digits[k] < radix[k] {
                    break;
                }
                digits[k] = 0;
                k += 1;
            }
        }
        None
    }

    /// Whether the cell's solid `s` and liquid `l` (with the neighbours' triangles in the cell)
    /// keep apart: no new triangle without area, no new edge on a face of the cell or held by
    /// more than two triangles of its layer, no two triangles of a layer crossing, no liquid
    /// triangle crossing a solid one unless it is that triangle reversed.
    fn apart(&self, positions: &[Vec3], s: &[Tri], l: &[Tri], old: &(FxHashSet<[u32; 2]>, FxHashSet<[u32; 2]>)) -> bool {
        let at = |v: u32| positions[v as usize];
        for (tris, old) in [(s, &old.0), (l, &old.1)] {
            let mut uses: FxHashMap<[u32; 2], u32> = FxHashMap::default();
            for &t in tris {
                if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
                    return false;
                }
                for e in edges(t) {
                    *uses.entry(e).or_default() += 1;
                }
            }
            for (e, &n) in &uses {
                if n > 2 || (!old.contains(e) && self.faces(at(e[0])) & self.faces(at(e[1])) != 0) {
                    return false;
                }
            }
            if tris.iter().any(|t| !old_triangle(t, old) && has_zero_area(t.map(at))) {
                return false;
            }
        }
        let meet = |a: Tri, b: Tri| indexed_triangles_intersect(a, b, at);
        let pairwise_apart = |tris: &[Tri], others: &[Tri]| {
            tris.iter().enumerate().all(|(i, &a)| {
                tris[i + 1..].iter().all(|&b| !meet(a, b)) && others.iter().all(|&b| sorted(a) == sorted(b) || !meet(a, b))
            })
        };
        if !pairwise_apart(s, &self.obstacles.0) || !pairwise_apart(l, &self.obstacles.1) {
            return false;
        }
        let solid_keys: FxHashSet<Tri> = s.iter().chain(&self.obstacles.0).map(|&t| sorted(t)).collect();
        let all_solid: Vec<Tri> = s.iter().chain(&self.obstacles.0).copied().collect();
        l.iter().filter(|&&t| !solid_keys.contains(&sorted(t))).all(|&a| all_solid.iter().all(|&b| !meet(a, b)))
            && self.obstacles.1.iter().filter(|&&t| !solid_keys.contains(&sorted(t))).all(|&a| s.iter().all(|&b| !meet(a, b)))
    }

    fn faces(&self, p: Vec3) -> u8 {
        faces_of(self.grid, self.cell, p)
    }

    /// The layer's triangles of the cell as patches joined by shared edges; a patch gets its
    /// loop when it has one boundary loop, is a disk (V − E + F = 1) and does not lie on a face.
    fn patches(&self, positions: &[Vec3], tris: &[Tri]) -> Vec<Patch> {
        let mut by_edge: FxHashMap<[u32; 2], Vec<usize>> = FxHashMap::default();
        for (i, &t) in tris.iter().enumerate() {
            for e in edges(t) {
                by_edge.entry(e).or_default().push(i);
            }
        }
        let mut joined = UnionFind::<usize>::new(tris.len());
        for users in by_edge.values() {
            for w in users.windows(2) {
                joined.union(w[0], w[1]);
            }
        }
        let mut groups: Vec<Vec<Tri>> = Vec::new();
        let mut group_of: FxHashMap<usize, usize> = FxHashMap::default();
        for (i, &t) in tris.iter().enumerate() {
            let g = *group_of.entry(joined.find(i)).or_insert_with(|| {
                groups.push(Vec::new());
                groups.len() - 1
            });
            groups[g].push(t);
        }
        groups
            .into_iter()
            .map(|triangles| {
                let ring = disk_ring(&triangles).filter(|ring| {
                    let on_face =
                        triangles.iter().any(|t| t.iter().fold(0x3f, |m, &v| m & self.faces(positions[v as usize])) != 0);
                    !on_face && ring.len() >= 3
                });
                Patch { triangles, ring }
            })
            .collect()
    }

    /// Fan centres: a lattice of points strictly inside the cell, nearest the loop's centroid
    /// first.
    fn fan_centres(&self, positions: &[Vec3], ring: &[u32]) -> Vec<Vec3> {
        let centroid = ring.iter().map(|&v| positions[v as usize].as_dvec3()).sum::<DVec3>() / ring.len() as f64;
        let n = FAN_LATTICE;
        let mut points: Vec<Vec3> = (0..n * n * n)
            .map(|k| {
                let f = [k % n, (k / n) % n, k / (n * n)].map(|i| (i as f32 + 0.5) / n as f32);
                let q = Vec3::new(self.cell[0] as f32 + f[0], self.cell[1] as f32 + f[1], self.cell[2] as f32 + f[2]);
                self.grid.origin + q * self.grid.spacing
            })
            .collect();
        points.sort_by(|a, b| a.as_dvec3().distance_squared(centroid).total_cmp(&b.as_dvec3().distance_squared(centroid)));
        points
    }
}

/// The undirected edges of the triangles.
fn edge_set(tris: &[Tri]) -> FxHashSet<[u32; 2]> {
    tris.iter().flat_map(|&t| edges(t)).collect()
}

/// Whether every edge of `t` is one of the cell's original edges (a triangle it had).
fn old_triangle(t: &Tri, old: &FxHashSet<[u32; 2]>) -> bool {
    edges(*t).iter().all(|e| old.contains(e))
}

fn edges(t: Tri) -> [[u32; 2]; 3] {
    let e = |a: u32, b: u32| [a.min(b), a.max(b)];
    [e(t[0], t[1]), e(t[1], t[2]), e(t[2], t[0])]
}

/// The boundary loop of a patch that is a disk with one boundary loop, in the direction its
/// triangles wind; `None` otherwise.
fn disk_ring(tris: &[Tri]) -> Option<Vec<u32>> {
    let directed: FxHashSet<(u32, u32)> = tris.iter().flat_map(|&[a, b, c]| [(a, b), (b, c), (c, a)]).collect();
    if directed.len() != 3 * tris.len() {
        return None;
    }
    let boundary: Vec<(u32, u32)> = directed.iter().copied().filter(|&(a, b)| !directed.contains(&(b, a))).collect();
    let next: FxHashMap<u32, u32> = boundary.iter().copied().collect();
    if next.len() != boundary.len() || boundary.is_empty() {
        return None;
    }
    let start = boundary.iter().map(|e| e.0).min()?;
    let mut ring = vec![start];
    let mut v = next[&start];
    while v != start {
        if ring.len() > boundary.len() {
            return None;
        }
        ring.push(v);
        v = *next.get(&v)?;
    }
    let vertices: FxHashSet<u32> = tris.iter().flatten().copied().collect();
    let edges = (directed.len() + boundary.len()) / 2;
    let euler = vertices.len() as i64 - edges as i64 + tris.len() as i64;
    (ring.len() == boundary.len() && euler == 1).then_some(ring)
}

/// The fan from `centre` over a loop.
fn fan(centre: u32, ring: &[u32]) -> Vec<Tri> {
    (0..ring.len()).map(|i| [centre, ring[i], ring[(i + 1) % ring.len()]]).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_disk_has_its_loop_and_a_tube_has_none() {
        let square = [[0, 1, 2], [0, 2, 3]];
        assert_eq!(disk_ring(&square), Some(vec![0, 1, 2, 3]));
        // An open tube of two squares' sides: two boundary loops.
        let tube = [[0, 1, 5], [0, 5, 4], [1, 2, 6], [1, 6, 5], [2, 3, 7], [2, 7, 6], [3, 0, 4], [3, 4, 7]];
        assert_eq!(disk_ring(&tube), None);
    }
}
