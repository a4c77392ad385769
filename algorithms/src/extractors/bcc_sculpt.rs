//! `bcc-sculpt`: a coarse tetrahedral mesh that encloses and approximates a surface, after
//! Stuart, Levine, Jones & Bargteil 2013, "Automatic construction of coarse, high-quality
//! tetrahedralizations that enclose and approximate surfaces for animation" (MIG '13), sections 3
//! and 4 (`../shared/papers/stuart-bcc-sculpting-odt-tetrahedralization.txt`).
//!
//! The input surface `S` is the field's own triangle mesh for mesh fields (OBJ input), and the
//! marching cubes surface of the samples for any other field. Four phases, one function each:
//! 1. **Lattice** ([`bcc_lattice`], §3.1): the BCC tetrahedralization of `S`'s bounding box plus a
//!    margin, every tetrahedron alike (two long edges between points of one grid, four short
//!    edges; dihedral angles 60° and 90°), optionally rotated and translated (§3.4).
//! 2. **Sculpting** ([`sculpt`], §3.2): a tetrahedron is kept when it overlaps the volume bounded
//!    by `S`: one of its vertices is inside `S` (the generalized winding number decides, so open or
//!    self-intersecting inputs have a defined inside), or it meets a triangle of `S`. The paper's
//!    second and third tests (a vertex of `S` inside the tetrahedron; an edge of the tetrahedron
//!    crossing a triangle) plus the one they miss (an edge of a triangle crossing a face) make an
//!    exact closed triangle-tetrahedron test; candidates come from `S`'s bounding volume hierarchy
//!    instead of the paper's all-pairs loops.
//! 3. **Defusing bombs** ([`defuse_bombs`], §3.2): a kept tetrahedron with two or more faces on
//!    the boundary flattens into a sliver under relaxation. Each bomb gets one complete snowflake
//!    (the 24 tetrahedra around one of its vertices), the combination chosen for the fewest added
//!    tetrahedra. The paper searches all combinations; we split the bombs into independent groups
//!    (bombs interact only when their candidate snowflakes share a missing tetrahedron or a vertex)
//!    and run an exact branch-and-bound per group, seeded with a greedy cover and capped at
//!    [`COVER_NODE_LIMIT`] search nodes, past which the best cover found is kept and the result
//!    says the search was not exhaustive. Tetrahedra of a complete snowflake have at most one
//!    boundary face and adding tetrahedra only removes boundary faces, so one round removes every
//!    bomb (tested).
//!    Sculpting can also leave parts that touch only along an edge or at a vertex (thin features);
//!    [`repair_boundary`] completes the snowflakes of such vertices so the boundary is a manifold
//!    (not in the paper, whose tables do not report the boundary's topology).
//! 4. **Variational vertex adjustment** ([`relax`], §3.3): every vertex moves by a time step toward
//!    the volume-weighted mean of its incident tetrahedra's circumcentres (the ODT update of
//!    Alliez et al. 2005). A step that would invert a tetrahedron is halved; a boundary vertex's
//!    step is also halved while the region its boundary triangles sweep (for a single moving vertex,
//!    exactly the tetrahedra `(p, p', a, b)` over its boundary faces `(p, a, b)`) meets `S` - exact
//!    continuous collision detection for one moving vertex, in place of the paper's El Topo. So
//!    `∂V` never crosses `S` and `V` keeps enclosing it. Iterations stop when every boundary vertex
//!    is within `d_offset = offset-ratio * h` of `S` (converged), at `max-iterations`, when no
//!    boundary vertex can move any more, or at the time budget; the last three report
//!    non-convergence (the paper's dashes) and keep the mesh reached.
//!
//! **Perturbation** (§3.4): `perturbations = K` runs the pipeline on K lattices, the first as is,
//! the others randomly rotated and translated (seeded), in parallel, and keeps the best: converged
//! before not converged, then the largest minimum dihedral angle. With `budget-ms`, attempts not
//! started by then are skipped and a running relaxation stops, so the result is the best so far.
//!
//! Output: the tetrahedra in [`Extraction::volume`] and their boundary (outward, counter-clockwise)
//! in [`Extraction::surface`]; [`sculpt_surface`] also returns a [`SculptReport`] with the counts of
//! every phase. Costs: O(lattice) for the lattice and sculpting (winding numbers and BVH queries,
//! in parallel), O(iterations × boundary vertices × nearby triangles of S) for the relaxation.

use crate::bvh::TriangleBvh;
use crate::extract::{ExtractError, Extraction, Extractor, ExtractorInfo};
use crate::geometry::{circumcentre, dihedral_angles, Aabb};
use crate::mesh::{manifold_defects, TetMesh, TriMesh};
use crate::options::{OptionError, Options};
use crate::predicates::triangle_meets_tetrahedron;
use crate::samples::Samples;
use glam::{DQuat, DVec3, Vec3};
use rayon::prelude::*;
use std::collections::HashMap;
use std::time::{Duration, Instant};

/// One line for the registry.
pub const DESCRIPTION: &str =
    "BCC lattice sculpted to the surface, bombs defused with snowflakes, ODT relaxation that keeps enclosing (tetrahedra + boundary)";

/// Options `bcc-sculpt` takes.
pub const OPTION_NAMES: &[&str] = &[
    "spacing",
    "cells",
    "offset-ratio",
    "perturbations",
    "seed",
    "time-step",
    "max-iterations",
    "budget-ms",
    "quality-floor",
    "attract",
    "clearance",
];

/// Search nodes per group of interacting bombs before the best cover found so far is kept.
pub const COVER_NODE_LIMIT: usize = 200_000;

/// Lattice cells of margin around the surface's bounding box (so every kept vertex has a complete
/// snowflake).
const MARGIN_CELLS: f64 = 3.0;

/// Tetrahedra around one interior lattice vertex (a snowflake).
const SNOWFLAKE: usize = 24;

/// Faces of tetrahedron `[a, b, c, d]` opposite each vertex, counter-clockwise seen from outside
/// when the tetrahedron is positively oriented.
const FACES: [[usize; 3]; 4] = [[1, 2, 3], [0, 3, 2], [0, 1, 3], [0, 2, 1]];

/// Settings of `bcc-sculpt`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SculptOptions {
    /// Lattice spacing `h` (corner-grid cell width); `None`: the surface's longest side / `cells`.
    pub spacing: Option<f32>,
    /// Cells along the longest side when no spacing is given.
    pub cells: usize,
    /// `d_offset / h`: relaxation stops when every boundary vertex is this close to `S`.
    pub offset_ratio: f32,
    /// Lattices tried (the first unperturbed); the best result is kept.
    pub perturbations: usize,
    /// Seed of the perturbations.
    pub seed: u64,
    /// Fraction of the way to the ODT position a vertex moves per iteration.
    pub time_step: f32,
    /// Relaxation iterations before giving up (non-convergence).
    pub max_iterations: usize,
    /// Wall-time budget for all attempts (`None`: unlimited).
    pub budget: Option<Duration>,
    /// Fraction of `d_offset` a boundary vertex keeps from `S` (0: may touch it).
    pub clearance: f32,
    /// Boundary vertices farther than `d_offset` whose ODT step fails step toward `S` instead.
    pub attract: bool,
    /// Smallest dihedral angle, degrees, a relaxation step may leave in a tetrahedron it changes
    /// (0: the paper's unguarded update).
    pub quality_floor: f32,
}

impl Default for SculptOptions {
    fn default() -> Self {
        Self {
            spacing: None,
            cells: 10,
            offset_ratio: 0.6,
            perturbations: 1,
            seed: 1,
            time_step: 0.25,
            max_iterations: 1000,
            budget: None,
            quality_floor: 20.0,
            attract: false,
            clearance: 0.0,
        }
    }
}

/// The `bcc-sculpt` extractor.
#[derive(Clone, Debug, Default)]
pub struct BccSculpt {
    /// Its settings.
    pub options: SculptOptions,
}

/// Stuart et al. 2013: BCC lattice sculpted to the surface, snowflakes, ODT relaxation (volume).
pub const INFO: ExtractorInfo =
    ExtractorInfo { name: "bcc-sculpt", description: DESCRIPTION, options: OPTION_NAMES, make: from_options };

/// Builds `bcc-sculpt` from named options.
pub fn from_options(options: &Options) -> Result<Box<dyn Extractor>, OptionError> {
    let d = SculptOptions::default();
    let mut r = options.reader(INFO.name, OPTION_NAMES);
    let positive = |v: &str| match v.trim().parse::<f32>() {
        Ok(x) if x.is_finite() && x > 0.0 => Ok(x),
        Ok(_) => Err("must be a finite number above 0".to_string()),
        Err(_) => Err("is not a number".to_string()),
    };
    let spacing = r.parse("spacing", None, |v| positive(v).map(Some))?;
    let cells = r.count("cells", d.cells, 1000)?;
    let offset_ratio = r.parse("offset-ratio", d.offset_ratio, positive)?;
    let perturbations = r.count("perturbations", d.perturbations, 10_000)?;
    let seed = r.count("seed", d.seed as usize, usize::MAX)? as u64;
    let time_step = r.number("time-step", d.time_step, 0.01, 1.0)?;
    let max_iterations = r.count("max-iterations", d.max_iterations, 1_000_000)?;
    let budget = r.parse("budget-ms", None, |v| positive(v).map(|ms| Some(Duration::from_secs_f64(f64::from(ms) / 1e3))))?;
    let quality_floor = r.number("quality-floor", d.quality_floor, 0.0, 60.0)?;
    let attract = r.choice("attract", d.attract, &[("true", true), ("false", false)])?;
    let clearance = r.number("clearance", d.clearance, 0.0, 0.95)?;
    r.finish()?;
    let bad = |option: &str, value: usize, reason: &str| OptionError::BadValue {
        algorithm: INFO.name,
        option: option.into(),
        value: value.to_string(),
        reason: reason.into(),
    };
    if perturbations == 0 {
        return Err(bad("perturbations", 0, "must be at least 1 (the unperturbed lattice)"));
    }
    if cells < 2 {
        return Err(bad("cells", cells, "must be at least 2"));
    }
    let options = SculptOptions {
        spacing,
        cells,
        offset_ratio,
        perturbations,
        seed,
        time_step,
        max_iterations,
        budget,
        quality_floor,
        attract,
        clearance,
    };
    Ok(Box::new(BccSculpt { options }))
}

/// What one run of the pipeline did, phase by phase.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SculptReport {
    /// Which attempt this is (0: the unperturbed lattice).
    pub attempt: usize,
    /// Lattice spacing used.
    pub spacing: f32,
    /// Tetrahedra of the whole lattice.
    pub lattice_tetrahedra: usize,
    /// Tetrahedra kept by sculpting.
    pub sculpted_tetrahedra: usize,
    /// Bombs found after sculpting.
    pub bombs: usize,
    /// Tetrahedra added back to complete snowflakes.
    pub restored: usize,
    /// Whether every group of bombs was searched exhaustively.
    pub exhaustive: bool,
    /// Tetrahedra added to make the boundary a manifold (snowflakes around pinched vertices).
    pub manifold_restored: usize,
    /// Boundary vertices still not manifold after repair (0 unless a pinch sits at the lattice edge).
    pub manifold_defects_left: usize,
    /// Bombs left after defusing (0 by construction; checked).
    pub bombs_left: usize,
    /// Relaxation iterations run.
    pub iterations: usize,
    /// Whether every boundary vertex came within `d_offset` of `S`.
    pub converged: bool,
    /// Largest distance of a boundary vertex to `S` at the end.
    pub max_distance: f32,
    /// Smallest and largest dihedral angle at the end, degrees.
    pub dihedral_deg: [f64; 2],
    /// Tetrahedra at the end.
    pub tetrahedra: usize,
    /// Attempts run in all (on the chosen result only).
    pub attempts_run: usize,
    /// Time of each phase: lattice + sculpting, defusing + compaction, relaxation.
    pub times: [Duration; 3],
}

/// A sculpted, relaxed tetrahedral mesh.
#[derive(Clone, Debug, Default)]
pub struct Sculpted {
    /// The tetrahedra (positively oriented).
    pub volume: TetMesh,
    /// Their boundary, outward.
    pub boundary: TriMesh,
    /// What happened.
    pub report: SculptReport,
}

impl Extractor for BccSculpt {
    fn name(&self) -> &'static str {
        INFO.name
    }

    fn description(&self) -> &'static str {
        DESCRIPTION
    }

    fn produces_volume(&self) -> bool {
        true
    }

    fn extract(&self, samples: &Samples, out: &mut Extraction) -> Result<(), ExtractError> {
        out.clear();
        out.stats.times.sampling = samples.sampling_time();
        let owned;
        let surface: &TriangleBvh = match samples.field().and_then(|f| f.surface_mesh()) {
            Some(bvh) => bvh,
            None => {
                owned = surface_of_samples(samples)?;
                &owned
            }
        };
        let name = samples.field().map_or("samples".to_string(), |f| f.name().to_string());
        out.stats.warnings = input_warnings(&name, surface);
        let sculpted = sculpt_surface(surface, &name, &self.options)?;
        let r = &sculpted.report;
        out.stats.times.vertex = r.times[0];
        out.stats.times.geometry = r.times[1];
        out.stats.times.smoothing = r.times[2];
        out.stats.converged = Some(r.converged);
        if !r.converged {
            out.stats.warnings.push(format!(
                "{name}: relaxation did not bring every boundary vertex within d_offset = {} of the surface \
                 (farthest {:.4} after {} iterations); the mesh reached is returned",
                self.options.offset_ratio * r.spacing,
                r.max_distance,
                r.iterations
            ));
        }
        out.volume = sculpted.volume;
        out.surface = sculpted.boundary;
        out.finish_counts(0);
        Ok(())
    }
}

/// The marching cubes surface of samples that carry no triangle mesh.
fn surface_of_samples(samples: &Samples) -> Result<TriangleBvh, ExtractError> {
    let mc = crate::extractors::MarchingCubes::default();
    let mut e = Extraction::default();
    mc.extract(samples, &mut e)?;
    let p = &e.surface.positions;
    Ok(TriangleBvh::new(e.surface.triangles.iter().map(|t| t.map(|i| p[i as usize])).collect()))
}

/// Warnings about the input surface: open edges (the winding number then decides the inside).
pub fn input_warnings(name: &str, surface: &TriangleBvh) -> Vec<String> {
    let key = |p: Vec3| p.to_array().map(f32::to_bits);
    let mut edges: HashMap<([u32; 3], [u32; 3]), i32> = HashMap::new();
    for t in surface.triangles() {
        for k in 0..3 {
            let (a, b) = (key(t[k]), key(t[(k + 1) % 3]));
            *edges.entry(if a < b { (a, b) } else { (b, a) }).or_default() += 1;
        }
    }
    let open = edges.values().filter(|&&n| n == 1).count();
    let non_manifold = edges.values().filter(|&&n| n > 2).count();
    let mut warnings = Vec::new();
    if open > 0 || non_manifold > 0 {
        warnings.push(format!(
            "input surface '{name}' is not closed ({open} boundary edges, {non_manifold} edges with more than two triangles): \
             the generalized winding number decides what is inside"
        ));
    }
    if surface.is_empty() {
        warnings.push(format!("input surface '{name}' has no triangles"));
    }
    warnings
}

/// Runs the whole pipeline on surface `S` (`name` is used in errors), trying
/// `options.perturbations` lattices and keeping the best.
pub fn sculpt_surface(surface: &TriangleBvh, name: &str, options: &SculptOptions) -> Result<Sculpted, ExtractError> {
    let bounds = surface.bounds();
    if surface.is_empty() {
        return Err(ExtractError::BadInput { algorithm: INFO.name, reason: format!("'{name}' has no surface to enclose") });
    }
    let longest = bounds.longest_side();
    let h = options.spacing.unwrap_or(longest / options.cells as f32);
    if !(h > 0.0 && h.is_finite()) || h > longest {
        return Err(ExtractError::BadInput {
            algorithm: INFO.name,
            reason: format!("spacing {h} is larger than '{name}' (longest side {longest}); use a spacing below {longest}"),
        });
    }
    let cells = (bounds.extent() / h).ceil() + 2.0 * MARGIN_CELLS as f32;
    let lattice_cells = cells.x as f64 * cells.y as f64 * cells.z as f64;
    if lattice_cells > 2e7 {
        return Err(ExtractError::BadInput {
            algorithm: INFO.name,
            reason: format!("spacing {h} makes a lattice of {lattice_cells:.0} cells for '{name}'; use a larger spacing"),
        });
    }
    let deadline = options.budget.map(|b| Instant::now() + b);
    let attempts: Vec<Sculpted> = (0..options.perturbations)
        .into_par_iter()
        .filter_map(|attempt| {
            if attempt > 0 && deadline.is_some_and(|d| Instant::now() >= d) {
                return None;
            }
            let (rotation, shift) = perturbation(options.seed, attempt);
            Some(run_attempt(surface, f64::from(h), rotation, shift, options, deadline, attempt))
        })
        .collect();
    let attempts_run = attempts.len();
    let mut best = attempts
        .into_iter()
        .max_by(|a, b| {
            (a.report.converged, a.report.dihedral_deg[0])
                .partial_cmp(&(b.report.converged, b.report.dihedral_deg[0]))
                .unwrap_or(std::cmp::Ordering::Equal)
                .then(b.report.attempt.cmp(&a.report.attempt))
        })
        .expect("attempt 0 always runs");
    best.report.attempts_run = attempts_run;
    Ok(best)
}

/// One attempt: lattice, sculpting, defusing, relaxation, output.
fn run_attempt(
    surface: &TriangleBvh,
    h: f64,
    rotation: DQuat,
    shift: DVec3,
    options: &SculptOptions,
    deadline: Option<Instant>,
    attempt: usize,
) -> Sculpted {
    let mut report = SculptReport { attempt, spacing: h as f32, exhaustive: true, ..Default::default() };
    let start = Instant::now();
    let lattice = bcc_lattice(surface.bounds(), h, rotation, shift);
    report.lattice_tetrahedra = lattice.tets.len();
    let mut keep = sculpt(&lattice, surface);
    report.sculpted_tetrahedra = keep.iter().filter(|&&k| k).count();
    report.times[0] = start.elapsed();

    let start = Instant::now();
    let defused = defuse_bombs(&lattice, &mut keep);
    report.bombs = defused.bombs;
    report.restored = defused.restored;
    report.exhaustive = defused.exhaustive;
    let repaired = repair_boundary(&lattice, &mut keep);
    report.manifold_restored = repaired.restored;
    report.manifold_defects_left = repaired.defects_left;
    report.bombs_left = bombs(&lattice, &keep).len();
    let mut mesh = VolumeMesh::from_lattice(&lattice, &keep);
    report.times[1] = start.elapsed();

    let start = Instant::now();
    let relaxed = relax(&mut mesh, surface, h, options, deadline);
    report.iterations = relaxed.iterations;
    report.converged = relaxed.converged;
    report.max_distance = relaxed.max_distance;
    report.times[2] = start.elapsed();
    let (volume, boundary) = mesh.into_meshes();
    report.tetrahedra = volume.tetrahedra.len();
    report.dihedral_deg = dihedral_range(&volume);
    Sculpted { volume, boundary, report }
}

/// Rotation and translation (as a fraction of a cell) of attempt `attempt`: none for attempt 0,
/// else a uniformly random rotation (Shoemake 1992) and shift, from a SplitMix64 stream.
pub fn perturbation(seed: u64, attempt: usize) -> (DQuat, DVec3) {
    if attempt == 0 {
        return (DQuat::IDENTITY, DVec3::ZERO);
    }
    let mut random = crate::random::Random::new(seed ^ (attempt as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15));
    let mut next = || random.unit();
    let (u1, u2, u3) = (next(), next(), next());
    let tau = std::f64::consts::TAU;
    let q = DQuat::from_xyzw(
        (1.0 - u1).sqrt() * (tau * u2).sin(),
        (1.0 - u1).sqrt() * (tau * u2).cos(),
        u1.sqrt() * (tau * u3).sin(),
        u1.sqrt() * (tau * u3).cos(),
    )
    .normalize();
    (q, DVec3::new(next(), next(), next()))
}

/// A BCC lattice: positions (world frame), positively oriented tetrahedra, the neighbour across
/// each face (`u32::MAX`: none) and each vertex's incident tetrahedra.
pub struct BccLattice {
    /// Vertex positions.
    pub positions: Vec<Vec3>,
    /// Tetrahedra, positively oriented.
    pub tets: Vec<[u32; 4]>,
    /// Neighbour across the face opposite each vertex.
    pub neighbours: Vec<[u32; 4]>,
    /// `star[star_start[v]..star_start[v + 1]]` are the tetrahedra around vertex `v`.
    pub star_start: Vec<u32>,
    /// Incident tetrahedra, grouped by vertex.
    pub star: Vec<u32>,
}

impl BccLattice {
    /// Tetrahedra incident to vertex `v`.
    pub fn star(&self, v: u32) -> &[u32] {
        &self.star[self.star_start[v as usize] as usize..self.star_start[v as usize + 1] as usize]
    }
}

/// The BCC tetrahedralization, spacing `h`, of `bounds` plus [`MARGIN_CELLS`], built in a frame
/// rotated by `rotation` and shifted by `shift` cells. Tetrahedra are generated around each edge
/// between adjacent centres: the four corners of the face they straddle close four tetrahedra
/// (twelve per cell).
pub fn bcc_lattice(bounds: Aabb, h: f64, rotation: DQuat, shift: DVec3) -> BccLattice {
    // The surface's bounds in the lattice frame (rotate the box's corners back).
    let inverse = rotation.inverse();
    let mut local = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
    for k in 0..8 {
        let c = DVec3::new(
            if k & 1 == 0 { bounds.min.x } else { bounds.max.x } as f64,
            if k & 2 == 0 { bounds.min.y } else { bounds.max.y } as f64,
            if k & 4 == 0 { bounds.min.z } else { bounds.max.z } as f64,
        );
        let l = inverse * c;
        local = (local.0.min(l), local.1.max(l));
    }
    let origin = ((local.0 / h).floor() - DVec3::splat(MARGIN_CELLS) - shift) * h;
    let n = ((local.1 - origin) / h).ceil() + DVec3::splat(MARGIN_CELLS);
    let [nx, ny, nz] = [n.x as usize, n.y as usize, n.z as usize];
    let corner = |i: usize, j: usize, k: usize| (i + (nx + 1) * (j + (ny + 1) * k)) as u32;
    let corners = (nx + 1) * (ny + 1) * (nz + 1);
    let centre = |i: usize, j: usize, k: usize| (corners + i + nx * (j + ny * k)) as u32;
    let mut positions = Vec::with_capacity(corners + nx * ny * nz);
    let world = |l: DVec3| (rotation * l).as_vec3();
    for k in 0..=nz {
        for j in 0..=ny {
            for i in 0..=nx {
                positions.push(world(origin + DVec3::new(i as f64, j as f64, k as f64) * h));
            }
        }
    }
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                positions.push(world(origin + (DVec3::new(i as f64, j as f64, k as f64) + 0.5) * h));
            }
        }
    }
    let dims = [nx, ny, nz];
    let mut tets = Vec::with_capacity(12 * nx * ny * nz);
    for axis in 0..3 {
        let (b, c) = ((axis + 1) % 3, (axis + 2) % 3);
        for k in 0..nz {
            for j in 0..ny {
                for i in 0..nx {
                    let cell = [i, j, k];
                    if cell[axis] + 1 >= dims[axis] {
                        continue;
                    }
                    let mut next = cell;
                    next[axis] += 1;
                    let (c0, c1) = (centre(i, j, k), centre(next[0], next[1], next[2]));
                    // The face between the two centres' cells, at corner index cell[axis] + 1.
                    let ring = [(0, 0), (1, 0), (1, 1), (0, 1)].map(|(db, dc)| {
                        let mut p = cell;
                        p[axis] += 1;
                        p[b] += db;
                        p[c] += dc;
                        corner(p[0], p[1], p[2])
                    });
                    for m in 0..4 {
                        tets.push([c0, c1, ring[m], ring[(m + 1) % 4]]);
                    }
                }
            }
        }
    }
    for t in &mut tets {
        if signed_volume(t.map(|v| positions[v as usize])) < 0.0 {
            t.swap(2, 3);
        }
    }
    let neighbours = face_neighbours(&tets);
    let crate::mesh::Incidence { start: star_start, items: star } = crate::mesh::Incidence::of(positions.len(), &tets);
    BccLattice { positions, tets, neighbours, star_start, star }
}

/// Six times the signed volume, in `f64`.
fn signed_volume(p: [Vec3; 4]) -> f64 {
    let d = p.map(|v| v.as_dvec3());
    (d[1] - d[0]).dot((d[2] - d[0]).cross(d[3] - d[0]))
}

/// The tetrahedron across each face (`u32::MAX` where none).
fn face_neighbours(tets: &[[u32; 4]]) -> Vec<[u32; 4]> {
    let mut first: HashMap<[u32; 3], (u32, usize)> = HashMap::with_capacity(2 * tets.len());
    let mut neighbours = vec![[u32::MAX; 4]; tets.len()];
    for (t, tet) in tets.iter().enumerate() {
        for (f, face) in FACES.iter().enumerate() {
            let mut key = face.map(|k| tet[k]);
            key.sort_unstable();
            if let Some((u, g)) = first.remove(&key) {
                neighbours[t][f] = u;
                neighbours[u as usize][g] = t as u32;
            } else {
                first.insert(key, (t as u32, f));
            }
        }
    }
    neighbours
}

/// Sculpting: which lattice tetrahedra overlap the volume bounded by `S`.
pub fn sculpt(lattice: &BccLattice, surface: &TriangleBvh) -> Vec<bool> {
    let bounds = surface.bounds();
    let near = |p: Vec3| bounds.distance_squared(p) == 0.0;
    // Vertices outside the surface's box are outside; the winding number decides the rest.
    let inside: Vec<bool> = lattice.positions.par_iter().map(|&p| near(p) && surface.winding_number(p) >= 0.5).collect();
    lattice
        .tets
        .par_iter()
        .map(|tet| {
            if tet.iter().any(|&v| inside[v as usize]) {
                return true;
            }
            let p = tet.map(|v| lattice.positions[v as usize]);
            let mut b = Aabb::empty();
            p.iter().for_each(|&v| b.grow(v));
            let mut meets = false;
            surface.for_each_overlapping(&b, |_, tri| meets = meets || triangle_meets_tetrahedron(tri, &p));
            meets
        })
        .collect()
}

/// Kept tetrahedra with two or more faces on the boundary.
pub fn bombs(lattice: &BccLattice, keep: &[bool]) -> Vec<u32> {
    (0..lattice.tets.len() as u32).filter(|&t| keep[t as usize] && boundary_faces(lattice, keep, t) >= 2).collect()
}

/// Faces of kept tetrahedron `t` with no kept neighbour.
fn boundary_faces(lattice: &BccLattice, keep: &[bool], t: u32) -> usize {
    lattice.neighbours[t as usize].iter().filter(|&&u| u == u32::MAX || !keep[u as usize]).count()
}

/// What defusing did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Defused {
    /// Bombs found.
    pub bombs: usize,
    /// Tetrahedra added back.
    pub restored: usize,
    /// Whether every group was searched exhaustively.
    pub exhaustive: bool,
}

/// Completes one snowflake per bomb, choosing the combination that adds the fewest tetrahedra.
pub fn defuse_bombs(lattice: &BccLattice, keep: &mut [bool]) -> Defused {
    let found = bombs(lattice, keep);
    let mut result = Defused { bombs: found.len(), restored: 0, exhaustive: true };
    if found.is_empty() {
        return result;
    }
    // Candidate vertices: those of the bomb with a complete snowflake.
    let candidates: Vec<Vec<u32>> = found
        .iter()
        .map(|&b| lattice.tets[b as usize].iter().copied().filter(|&v| lattice.star(v).len() == SNOWFLAKE).collect())
        .collect();
    for group in interacting_groups(lattice, keep, &candidates) {
        let problem = CoverProblem::new(lattice, keep, group.iter().map(|&i| candidates[i].as_slice()));
        let (chosen, exhaustive) = problem.solve(COVER_NODE_LIMIT);
        result.exhaustive &= exhaustive;
        for v in chosen {
            for &t in lattice.star(v) {
                if !keep[t as usize] {
                    keep[t as usize] = true;
                    result.restored += 1;
                }
            }
        }
    }
    result
}

/// What the boundary repair did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Repaired {
    /// Tetrahedra added.
    pub restored: usize,
    /// Offending vertices left.
    pub defects_left: usize,
}

/// Rounds of boundary repair before giving up.
const REPAIR_ROUNDS: usize = 16;

/// Makes the boundary of the kept tetrahedra a 2-manifold: where two parts touch only along an
/// edge or at a vertex (thin features, like cheburashka's ears, sculpt into such pinches), the
/// snowflake of the offending vertex is completed, which makes that vertex interior. Complete
/// snowflakes hold no bombs and adding tetrahedra turns none into a bomb, so the defusing stays
/// valid. Repeats until no pinch is left (each round can expose new boundary vertices).
pub fn repair_boundary(lattice: &BccLattice, keep: &mut [bool]) -> Repaired {
    let mut result = Repaired::default();
    let mut mesh = TriMesh { positions: vec![Vec3::ZERO; lattice.positions.len()], ..Default::default() };
    for round in 0..=REPAIR_ROUNDS {
        mesh.triangles.clear();
        for (t, tet) in lattice.tets.iter().enumerate().filter(|(t, _)| keep[*t]) {
            for (f, face) in FACES.iter().enumerate() {
                let u = lattice.neighbours[t][f];
                if u == u32::MAX || !keep[u as usize] {
                    mesh.triangles.push(face.map(|k| tet[k]));
                }
            }
        }
        let defects = manifold_defects(&mesh);
        result.defects_left = defects.len();
        if round == REPAIR_ROUNDS {
            break;
        }
        let mut changed = false;
        for v in defects.into_iter().filter(|&v| lattice.star(v).len() == SNOWFLAKE) {
            for &t in lattice.star(v) {
                if !keep[t as usize] {
                    keep[t as usize] = true;
                    result.restored += 1;
                    changed = true;
                }
            }
        }
        if !changed {
            break;
        }
    }
    result
}

/// Groups of bombs (indices into `candidates`) whose candidate snowflakes share a vertex or a
/// missing tetrahedron; groups are independent of each other.
fn interacting_groups(lattice: &BccLattice, keep: &[bool], candidates: &[Vec<u32>]) -> Vec<Vec<usize>> {
    let mut sets = petgraph::unionfind::UnionFind::<usize>::new(candidates.len());
    let mut owner: HashMap<u64, usize> = HashMap::new();
    for (i, c) in candidates.iter().enumerate() {
        for &v in c {
            let keys = std::iter::once(u64::from(v) | 1 << 63)
                .chain(lattice.star(v).iter().filter(|&&t| !keep[t as usize]).map(|&t| u64::from(t)));
            for key in keys {
                match owner.get(&key) {
                    Some(&j) => {
                        sets.union(i, j);
                    }
                    None => {
                        owner.insert(key, i);
                    }
                }
            }
        }
    }
    let mut groups: HashMap<usize, Vec<usize>> = HashMap::new();
    for i in 0..candidates.len() {
        let root = sets.find_mut(i);
        groups.entry(root).or_default().push(i);
    }
    let mut groups: Vec<Vec<usize>> = groups.into_values().collect();
    groups.sort();
    groups
}

/// Choose one vertex per bomb minimising the number of distinct missing tetrahedra in the chosen
/// vertices' snowflakes. Vertices and tetrahedra are renumbered locally.
struct CoverProblem {
    /// Global id of each local vertex.
    vertices: Vec<u32>,
    /// Missing tetrahedra (local ids) of each local vertex's snowflake.
    cost: Vec<Vec<u32>>,
    /// Candidate local vertices of each bomb.
    bombs: Vec<Vec<u32>>,
    /// Local tetrahedra.
    tets: usize,
}

impl CoverProblem {
    fn new<'a>(lattice: &BccLattice, keep: &[bool], bombs: impl Iterator<Item = &'a [u32]>) -> Self {
        let mut vertex_id: HashMap<u32, u32> = HashMap::new();
        let mut tet_id: HashMap<u32, u32> = HashMap::new();
        let mut vertices = Vec::new();
        let mut cost = Vec::new();
        let bombs = bombs
            .map(|c| {
                c.iter()
                    .map(|&v| {
                        *vertex_id.entry(v).or_insert_with(|| {
                            vertices.push(v);
                            let missing = lattice.star(v).iter().filter(|&&t| !keep[t as usize]);
                            cost.push(
                                missing
                                    .map(|&t| {
                                        let next = tet_id.len() as u32;
                                        *tet_id.entry(t).or_insert(next)
                                    })
                                    .collect(),
                            );
                            vertices.len() as u32 - 1
                        })
                    })
                    .collect()
            })
            .collect();
        Self { vertices, cost, bombs, tets: tet_id.len() }
    }

    /// The chosen vertices (global ids) and whether the search finished within `node_limit`.
    fn solve(&self, node_limit: usize) -> (Vec<u32>, bool) {
        let greedy = self.greedy();
        let mut search = Search {
            problem: self,
            count: vec![0; self.tets],
            cost: 0,
            chosen: vec![false; self.vertices.len()],
            best_cost: self.cover_cost(&greedy),
            best: greedy,
            nodes: 0,
            limit: node_limit,
        };
        search.descend(0);
        let exhaustive = search.nodes <= node_limit;
        let chosen = search.best.iter().enumerate().filter(|(_, &c)| c).map(|(v, _)| self.vertices[v]).collect();
        (chosen, exhaustive)
    }

    /// Repeatedly picks the vertex covering the most uncovered bombs per added tetrahedron.
    fn greedy(&self) -> Vec<bool> {
        let mut chosen = vec![false; self.vertices.len()];
        let mut added = vec![false; self.tets];
        loop {
            let uncovered: Vec<&Vec<u32>> = self.bombs.iter().filter(|c| !c.iter().any(|&v| chosen[v as usize])).collect();
            if uncovered.is_empty() {
                return chosen;
            }
            let score = |v: u32| {
                let covers = uncovered.iter().filter(|c| c.contains(&v)).count() as f64;
                let new = self.cost[v as usize].iter().filter(|&&t| !added[t as usize]).count() as f64;
                covers / (1.0 + new)
            };
            let best = uncovered
                .iter()
                .flat_map(|c| c.iter().copied())
                .max_by(|&a, &b| score(a).total_cmp(&score(b)).then(b.cmp(&a)))
                .expect("bombs have candidates");
            chosen[best as usize] = true;
            self.cost[best as usize].iter().for_each(|&t| added[t as usize] = true);
        }
    }

    fn cover_cost(&self, chosen: &[bool]) -> usize {
        let mut added = vec![false; self.tets];
        for (v, _) in chosen.iter().enumerate().filter(|(_, &c)| c) {
            self.cost[v].iter().for_each(|&t| added[t as usize] = true);
        }
        added.iter().filter(|&&a| a).count()
    }
}

/// Depth-first branch and bound over the bombs in order.
struct Search<'a> {
    problem: &'a CoverProblem,
    count: Vec<u32>,
    cost: usize,
    chosen: Vec<bool>,
    best: Vec<bool>,
    best_cost: usize,
    nodes: usize,
    limit: usize,
}

impl Search<'_> {
    fn descend(&mut self, bomb: usize) {
        self.nodes += 1;
        if self.nodes > self.limit || self.cost >= self.best_cost {
            return;
        }
        let Some(candidates) = self.problem.bombs.get(bomb) else {
            self.best_cost = self.cost;
            self.best.clone_from(&self.chosen);
            return;
        };
        if candidates.iter().any(|&v| self.chosen[v as usize]) {
            return self.descend(bomb + 1);
        }
        for &v in candidates {
            self.choose(v, true);
            self.descend(bomb + 1);
            self.choose(v, false);
        }
    }

    fn choose(&mut self, v: u32, on: bool) {
        self.chosen[v as usize] = on;
        for &t in &self.problem.cost[v as usize] {
            let c = &mut self.count[t as usize];
            if on {
                *c += 1;
                self.cost += usize::from(*c == 1);
            } else {
                *c -= 1;
                self.cost -= usize::from(*c == 0);
            }
        }
    }
}

/// The kept tetrahedra as a mesh of their own, with boundary faces and stars.
struct VolumeMesh {
    positions: Vec<Vec3>,
    tets: Vec<[u32; 4]>,
    star_start: Vec<u32>,
    star: Vec<u32>,
    /// Boundary triangles, outward.
    boundary: Vec<[u32; 3]>,
    /// `face_star[face_start[v]..face_start[v + 1]]`: boundary triangles around vertex `v`.
    face_start: Vec<u32>,
    face_star: Vec<u32>,
}

impl VolumeMesh {
    fn from_lattice(lattice: &BccLattice, keep: &[bool]) -> Self {
        let mut index = vec![u32::MAX; lattice.positions.len()];
        let mut positions = Vec::new();
        let mut tets = Vec::new();
        let mut boundary = Vec::new();
        for (t, tet) in lattice.tets.iter().enumerate().filter(|(t, _)| keep[*t]) {
            let local = tet.map(|v| {
                if index[v as usize] == u32::MAX {
                    index[v as usize] = positions.len() as u32;
                    positions.push(lattice.positions[v as usize]);
                }
                index[v as usize]
            });
            tets.push(local);
            for (f, face) in FACES.iter().enumerate() {
                let u = lattice.neighbours[t][f];
                if u == u32::MAX || !keep[u as usize] {
                    boundary.push(face.map(|k| local[k]));
                }
            }
        }
        let crate::mesh::Incidence { start: star_start, items: star } = crate::mesh::Incidence::of(positions.len(), &tets);
        let crate::mesh::Incidence { start: face_start, items: face_star } =
            crate::mesh::Incidence::of(positions.len(), &boundary);
        Self { positions, tets, star_start, star, boundary, face_start, face_star }
    }

    fn star(&self, v: usize) -> &[u32] {
        &self.star[self.star_start[v] as usize..self.star_start[v + 1] as usize]
    }

    fn faces(&self, v: usize) -> &[u32] {
        &self.face_star[self.face_start[v] as usize..self.face_start[v + 1] as usize]
    }

    fn is_boundary(&self, v: usize) -> bool {
        self.face_start[v] != self.face_start[v + 1]
    }

    fn into_meshes(self) -> (TetMesh, TriMesh) {
        let mut index = vec![u32::MAX; self.positions.len()];
        let mut surface = TriMesh::default();
        for tri in &self.boundary {
            let local = tri.map(|v| {
                if index[v as usize] == u32::MAX {
                    index[v as usize] = surface.positions.len() as u32;
                    surface.positions.push(self.positions[v as usize]);
                }
                index[v as usize]
            });
            surface.triangles.push(local);
        }
        surface.compute_face_weighted_normals();
        (TetMesh { positions: self.positions, tetrahedra: self.tets }, surface)
    }
}

/// How relaxation ended.
struct Relaxed {
    iterations: usize,
    converged: bool,
    max_distance: f32,
}

/// Iterations in a row without the farthest boundary vertex coming [`STALL_PROGRESS`] `h` closer
/// before relaxation gives up.
const STALL_ITERATIONS: usize = 25;

/// Progress, in lattice spacings, that resets the stall count.
const STALL_PROGRESS: f32 = 1e-3;

/// Variational vertex adjustment (section 3.3): ODT steps that keep every tetrahedron positive
/// and the boundary off `S`.
fn relax(mesh: &mut VolumeMesh, surface: &TriangleBvh, h: f64, options: &SculptOptions, deadline: Option<Instant>) -> Relaxed {
    let offset = (f64::from(options.offset_ratio) * h) as f32;
    // A tetrahedron may not shrink below this volume (a BCC tetrahedron has h³/12).
    let min_volume = 1e-4 * h * h * h;
    let still = (1e-6 * h) as f32;
    let mut stalled = 0;
    let mut iterations = 0;
    let mut best_distance = f32::INFINITY;
    let limits = StepLimits { min_volume, still, quality_floor: options.quality_floor, clearance: options.clearance * offset };
    loop {
        let max_distance = (0..mesh.positions.len())
            .into_par_iter()
            .filter(|&v| mesh.is_boundary(v))
            .map(|v| surface.closest_point(mesh.positions[v]).map_or(f32::INFINITY, |(_, d2)| d2.sqrt()))
            .reduce(|| 0.0, f32::max);
        let converged = max_distance <= offset;
        if max_distance < best_distance - STALL_PROGRESS * h as f32 {
            best_distance = max_distance;
            stalled = 0;
        } else {
            stalled += 1;
        }
        let out_of_time = deadline.is_some_and(|d| Instant::now() >= d);
        if converged || iterations >= options.max_iterations || stalled >= STALL_ITERATIONS || out_of_time {
            return Relaxed { iterations, converged, max_distance };
        }
        iterations += 1;
        let targets = odt_targets(mesh);
        for (v, &target) in targets.iter().enumerate() {
            let p = mesh.positions[v];
            let step = (target - p.as_dvec3()) * f64::from(options.time_step);
            if try_step(mesh, surface, v, step, &limits) || !options.attract {
                continue;
            }
            // A boundary vertex the ODT step cannot bring closer: step toward its closest point on
            // S instead, under the same tests.
            if !mesh.is_boundary(v) {
                continue;
            }
            let Some((c, d2)) = surface.closest_point(p) else { continue };
            let d = d2.sqrt();
            if d > offset {
                let pull = (c - p).as_dvec3() * f64::from(options.time_step * (d - 0.5 * offset) / d);
                try_step(mesh, surface, v, pull, &limits);
            }
        }
    }
}

/// What a relaxation step must respect.
#[derive(Clone, Copy)]
struct StepLimits {
    /// Smallest volume a tetrahedron may keep.
    min_volume: f64,
    /// Moves shorter than this are not made.
    still: f32,
    /// Quality floor, degrees of dihedral angle.
    quality_floor: f32,
    /// Distance a boundary vertex keeps from `S`.
    clearance: f32,
}

/// Moves `v` by `step`, halving it up to four times until the move keeps every tetrahedron
/// positive and above the quality floor and (on the boundary) sweeps clear of `S`. Whether it moved.
fn try_step(mesh: &mut VolumeMesh, surface: &TriangleBvh, v: usize, step: DVec3, limits: &StepLimits) -> bool {
    let StepLimits { min_volume, still, quality_floor, clearance } = *limits;
    let p = mesh.positions[v];
    let boundary = mesh.is_boundary(v);
    let mut scale = 1.0;
    for _ in 0..5 {
        let q = (p.as_dvec3() + step * scale).as_vec3();
        if q.distance(p) <= still {
            return false;
        }
        if star_stays_positive(mesh, v, q, min_volume)
            && keeps_quality(mesh, v, q, quality_floor)
            && (!boundary || keeps_clearance(surface, p, q, clearance))
            && (!boundary || sweep_is_clear(mesh, surface, v, q))
        {
            mesh.positions[v] = q;
            return true;
        }
        scale *= 0.5;
    }
    false
}

/// Each vertex's ODT position: the volume-weighted mean of its tetrahedra's circumcentres
/// (equation 2 of the paper, from Alliez et al. 2005).
fn odt_targets(mesh: &VolumeMesh) -> Vec<DVec3> {
    let centres: Vec<(f64, DVec3)> = mesh
        .tets
        .par_iter()
        .map(|t| {
            let p = t.map(|v| mesh.positions[v as usize].as_dvec3());
            let volume = (p[1] - p[0]).dot((p[2] - p[0]).cross(p[3] - p[0])) / 6.0;
            match circumcentre(p) {
                Some(c) if volume > 0.0 => (volume, c * volume),
                _ => (0.0, DVec3::ZERO),
            }
        })
        .collect();
    (0..mesh.positions.len())
        .into_par_iter()
        .map(|v| {
            let (w, sum) = mesh.star(v).iter().fold((0.0, DVec3::ZERO), |(w, s), &t| {
                let (vol, c) = centres[t as usize];
                (w + vol, s + c)
            });
            if w > 0.0 {
                sum / w
            } else {
                mesh.positions[v].as_dvec3()
            }
        })
        .collect()
}

/// A boundary vertex may not come closer to `S` than `clearance` (unless it is moving away): a
/// vertex glued to `S` would pin the triangles around it, so that its neighbours could not
/// approach `S` without their triangles' sweep touching it.
fn keeps_clearance(surface: &TriangleBvh, p: Vec3, q: Vec3, clearance: f32) -> bool {
    if clearance <= 0.0 {
        return true;
    }
    let d = |x: Vec3| surface.closest_point(x).map_or(f32::INFINITY, |(_, d2)| d2.sqrt());
    let after = d(q);
    after >= clearance || after >= d(p)
}

/// Whether every tetrahedron around `v` keeps at least `min_volume` with `v` at `q`.
fn star_stays_positive(mesh: &VolumeMesh, v: usize, q: Vec3, min_volume: f64) -> bool {
    mesh.star(v).iter().all(|&t| {
        let p = mesh.tets[t as usize].map(|u| if u as usize == v { q } else { mesh.positions[u as usize] });
        signed_volume(p) / 6.0 > min_volume
    })
}

/// Whether moving `v` to `q` keeps every tetrahedron around it at or above `floor` degrees of
/// dihedral angle, or no worse than it was (so the mesh's minimum never drops below the floor).
fn keeps_quality(mesh: &VolumeMesh, v: usize, q: Vec3, floor: f32) -> bool {
    if floor <= 0.0 {
        return true;
    }
    let floor = f64::from(floor);
    let min_angle = |p: [Vec3; 4]| dihedral_angles(p).iter().copied().fold(180.0, f64::min);
    mesh.star(v).iter().all(|&t| {
        let tet = mesh.tets[t as usize];
        let after = min_angle(tet.map(|u| if u as usize == v { q } else { mesh.positions[u as usize] }));
        after >= floor || after >= min_angle(tet.map(|u| mesh.positions[u as usize]))
    })
}

/// Whether moving boundary vertex `v` to `q` keeps every boundary triangle around it off `S`:
/// the region a triangle `(p, a, b)` sweeps when `p` moves to `q` is the tetrahedron
/// `(p, q, a, b)`, tested exactly against the nearby triangles of `S`.
fn sweep_is_clear(mesh: &VolumeMesh, surface: &TriangleBvh, v: usize, q: Vec3) -> bool {
    let p = mesh.positions[v];
    mesh.faces(v).iter().all(|&f| {
        let tri = mesh.boundary[f as usize];
        let k = tri.iter().position(|&u| u as usize == v).unwrap_or(0);
        let (a, b) = (mesh.positions[tri[(k + 1) % 3] as usize], mesh.positions[tri[(k + 2) % 3] as usize]);
        let swept = [p, q, a, b];
        let mut b = Aabb::empty();
        swept.iter().for_each(|&x| b.grow(x));
        let planes = SeparatingPlanes::of(&swept);
        let mut clear = true;
        surface.for_each_overlapping(&b, |_, s| {
            clear = clear && (planes.separates(s) || !triangle_meets_tetrahedron(s, &swept));
        });
        clear
    })
}

/// The outward face planes of a tetrahedron, for a fast conservative "clearly apart" test before
/// the exact one.
struct SeparatingPlanes {
    planes: [(Vec3, f32); 4],
    valid: bool,
}

impl SeparatingPlanes {
    fn of(t: &[Vec3; 4]) -> Self {
        let sign = signed_volume(*t).signum() as f32;
        let planes = FACES.map(|f| {
            let n = (t[f[1]] - t[f[0]]).cross(t[f[2]] - t[f[0]]) * sign;
            let n = n.normalize_or_zero();
            (n, n.dot(t[f[0]]))
        });
        let scale = t.iter().map(|p| p.abs().max_element()).fold(0.0, f32::max);
        let valid = signed_volume(*t).abs() > 1e-9 * f64::from(scale).powi(3) && planes.iter().all(|(n, _)| *n != Vec3::ZERO);
        Self { planes, valid }
    }

    /// True only when every vertex of `s` lies clearly outside one face plane.
    fn separates(&self, s: &[Vec3; 3]) -> bool {
        self.valid && self.planes.iter().any(|(n, d)| s.iter().all(|p| n.dot(*p) - d > 1e-5 * (1.0 + d.abs())))
    }
}

/// Smallest and largest dihedral angle over all tetrahedra, degrees.
fn dihedral_range(mesh: &TetMesh) -> [f64; 2] {
    mesh.tetrahedra
        .par_iter()
        .map(|t| {
            let a = dihedral_angles(t.map(|v| mesh.positions[v as usize]));
            [a.iter().copied().fold(180.0, f64::min), a.iter().copied().fold(0.0, f64::max)]
        })
        .reduce(|| [180.0, 0.0], |a, b| [a[0].min(b[0]), a[1].max(b[1])])
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Distinct vertices of the surface's triangles.
    fn surface_vertices(surface: &TriangleBvh) -> Vec<Vec3> {
        let mut seen = std::collections::HashSet::new();
        surface.triangles().iter().flatten().copied().filter(|p| seen.insert(p.to_array().map(f32::to_bits))).collect()
    }

    fn octahedron(r: f32) -> TriangleBvh {
        let v = [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z].map(|p| p * r);
        let faces = [[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]];
        TriangleBvh::new(faces.iter().map(|f: &[usize; 3]| f.map(|i| v[i])).collect())
    }

    #[test]
    fn lattice_tetrahedra_are_alike_and_fill_the_box() {
        let lattice = bcc_lattice(Aabb::cube(1.0), 0.5, DQuat::IDENTITY, DVec3::ZERO);
        let volume: f64 = lattice.tets.iter().map(|t| signed_volume(t.map(|v| lattice.positions[v as usize])) / 6.0).sum();
        for t in &lattice.tets {
            let p = t.map(|v| lattice.positions[v as usize]);
            assert!((signed_volume(p) / 6.0 - 0.125 / 12.0).abs() < 1e-9, "every tetrahedron has h³/12");
            let mut a = dihedral_angles(p);
            a.sort_by(f64::total_cmp);
            let expect = [60.0, 60.0, 60.0, 60.0, 90.0, 90.0];
            assert!(a.iter().zip(expect).all(|(x, e)| (x - e).abs() < 1e-4), "{a:?}");
        }
        assert!(volume > 8.0, "the lattice covers the box and its margin: {volume}");
        let interior = (0..lattice.positions.len() as u32).filter(|&v| lattice.star(v).len() == SNOWFLAKE).count();
        assert!(interior > 0 && lattice.star_start.windows(2).all(|w| w[1] - w[0] <= SNOWFLAKE as u32));
        // Faces pair up: every interior face has a neighbour that points back.
        for (t, n) in lattice.neighbours.iter().enumerate() {
            for &u in n.iter().filter(|&&u| u != u32::MAX) {
                assert!(lattice.neighbours[u as usize].contains(&(t as u32)));
            }
        }
    }

    #[test]
    fn sculpting_keeps_every_overlapping_tetrahedron_and_defusing_leaves_no_bomb() {
        let surface = octahedron(1.0);
        for attempt in 0..4 {
            let (rotation, shift) = perturbation(7, attempt);
            let lattice = bcc_lattice(surface.bounds(), 0.37, rotation, shift);
            let mut keep = sculpt(&lattice, &surface);
            // Every kept tetrahedron overlaps the octahedron |x|+|y|+|z| <= 1, and every lattice
            // tetrahedron containing a point of it is kept.
            for (t, tet) in lattice.tets.iter().enumerate() {
                let p = tet.map(|v| lattice.positions[v as usize]);
                let centroid = (p[0] + p[1] + p[2] + p[3]) / 4.0;
                if centroid.abs().element_sum() < 0.999 {
                    assert!(keep[t], "tetrahedron {t} holds interior point {centroid}");
                }
                if keep[t] {
                    let nearest = p.iter().map(|q| q.abs().element_sum()).fold(f32::INFINITY, f32::min);
                    assert!(nearest < 1.0 + 0.37 * 1.5, "kept tetrahedron {t} is far outside");
                }
            }
            let defused = defuse_bombs(&lattice, &mut keep);
            assert!(bombs(&lattice, &keep).is_empty(), "attempt {attempt}: {defused:?}");
        }
    }

    #[test]
    fn the_cover_search_finds_the_cheapest_combination() {
        // Two bombs; vertex 2 covers both and costs 4 (greedy's pick); 0 and 1 cost 2 each but
        // share a tetrahedron, 3 together.
        let problem = CoverProblem {
            vertices: vec![10, 11, 12],
            cost: vec![vec![0, 1], vec![1, 2], vec![3, 4, 5, 6]],
            bombs: vec![vec![0, 2], vec![1, 2]],
            tets: 7,
        };
        let (mut chosen, exhaustive) = problem.solve(1000);
        chosen.sort();
        assert!(exhaustive);
        assert_eq!(chosen, vec![10, 11], "3 tetrahedra through the shared one beat greedy's 4");
        let problem = CoverProblem { cost: vec![vec![0, 1], vec![2, 3], vec![4, 5]], ..problem };
        let (chosen, _) = problem.solve(1000);
        assert_eq!(chosen, vec![12], "one snowflake of 2 beats two of 2 each");
    }

    #[test]
    fn relaxed_mesh_encloses_and_approaches_the_surface() {
        let surface = octahedron(1.0);
        let options = SculptOptions { spacing: Some(0.4), offset_ratio: 0.6, ..Default::default() };
        let result = sculpt_surface(&surface, "octahedron", &options).unwrap();
        let r = &result.report;
        assert!(r.converged, "{r:?}");
        assert!(r.max_distance <= 0.24 + 1e-6);
        assert!(r.dihedral_deg[0] > 0.0, "no inverted tetrahedron: {r:?}");
        for t in &result.volume.tetrahedra {
            assert!(signed_volume(t.map(|v| result.volume.positions[v as usize])) > 0.0);
        }
        // Enclosure: no boundary vertex inside S, and S's vertices inside the boundary.
        let boundary = TriangleBvh::new(
            result.boundary.triangles.iter().map(|t| t.map(|i| result.boundary.positions[i as usize])).collect(),
        );
        for &p in &result.boundary.positions {
            assert!(surface.winding_number(p) < 0.5, "boundary vertex {p} went inside S");
        }
        for p in surface_vertices(&surface) {
            assert!(boundary.winding_number(p) > 0.5, "S vertex {p} is outside the tetrahedral mesh");
        }
    }

    #[test]
    fn bad_settings_are_refused_by_name() {
        let surface = octahedron(1.0);
        let options = SculptOptions { spacing: Some(5.0), ..Default::default() };
        let err = sculpt_surface(&surface, "octahedron", &options).unwrap_err().to_string();
        assert!(err.contains("spacing 5") && err.contains("octahedron"), "{err}");
        let mut o = Options::new();
        o.set("offset-ratio", "0");
        assert!(from_options(&o).err().unwrap().to_string().contains("offset-ratio"));
        let mut o = Options::new();
        o.set("perturbations", "0");
        assert!(from_options(&o).err().unwrap().to_string().contains("perturbations"));
    }
}
