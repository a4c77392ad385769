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
//! 2. **Sculpting** ([`sculpt()`], §3.2): a tetrahedron is kept when it overlaps the volume bounded
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
//!
//! **Guarantees.** Every tetrahedron is positively oriented; the volume encloses `S` (sculpting
//! keeps every tetrahedron that overlaps it, and no relaxation step lets a boundary triangle sweep
//! across it: exact tests); no bomb is left; the boundary is closed, and manifold unless the
//! repair reports defects left. With the default quality floor (20°) no dihedral angle falls below
//! it (the lattice starts at 60° and steps below the floor are refused). Tests: random blobs,
//! the shipped models, perturbed lattices.
//!
//! **Non-guarantees.** Reaching `d_offset` (the relaxation may stop first, reported as not
//! converged); the fewest tetrahedra (CGAL's Mesh_3 gives fewer on the report's models); quality
//! without the floor (the paper's unguarded update made slivers here).
//!
//! ```
//! use isolab_algorithms::extractors::bcc_sculpt::{BccSculpt, SculptOptions};
//! use isolab_algorithms::{fields, Extraction, Extractor, Grid, Samples};
//! let sphere = fields::builtin("sphere", Default::default()).unwrap();
//! let samples = Samples::sample_cubic(sphere.clone(), Grid::covering(&sphere.domain(), 16).unwrap(), 0.0).unwrap();
//! let mut out = Extraction::default();
//! BccSculpt { options: SculptOptions { cells: 6, ..Default::default() } }.extract(&samples, &mut out).unwrap();
//! let t = &out.volume;
//! assert!(!t.tetrahedra.is_empty());
//! // Positively oriented, and enclosing: more volume than the sphere (radius 0.4) it wraps.
//! let volumes: Vec<f32> = t.tetrahedra.iter().map(|&[a, b, c, d]| {
//!     let [a, b, c, d] = [a, b, c, d].map(|i| t.positions[i as usize]);
//!     (b - a).cross(c - a).dot(d - a) / 6.0
//! }).collect();
//! assert!(volumes.iter().all(|&v| v > 0.0));
//! assert!(volumes.iter().sum::<f32>() > 4.0 / 3.0 * std::f32::consts::PI * 0.4f32.powi(3));
//! ```

use crate::bvh::TriangleBvh;
use crate::extract::{ExtractError, Extraction, Extractor, ExtractorInfo, Guarantees};
use crate::geometry::dihedral_angles;
use crate::mesh::{TetMesh, TriMesh};
use crate::options::{OptionError, Options};
use crate::samples::Samples;
use glam::{DQuat, DVec3, Vec3};
use rayon::prelude::*;
use std::collections::HashMap;
use std::time::{Duration, Instant};

pub mod cover;
pub mod lattice;
pub mod relax;
pub mod sculpt;

pub use lattice::{bcc_lattice, perturbation, BccLattice};
use relax::{relax, VolumeMesh};
pub use sculpt::{bombs, defuse_bombs, repair_boundary, sculpt, Defused, Repaired};

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
    /// Record every relaxation iteration in [`SculptReport::trace`] (for studies of the
    /// relaxation; a library setting, not an option name).
    pub trace: bool,
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
            trace: false,
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
pub const INFO: ExtractorInfo = ExtractorInfo {
    name: "bcc-sculpt",
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
    // On a cubic grid with no surface mesh, its input surface is marching cubes' of the samples,
    // which reads them in place.
    samples: crate::extract::SampleAccess::Borrowed,
};

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
        trace: false,
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
    /// One entry per relaxation iteration when [`SculptOptions::trace`] is set (the state before
    /// the iteration's steps, then what the steps did).
    pub trace: Vec<RelaxIteration>,
}

/// One relaxation iteration, recorded with [`SculptOptions::trace`].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RelaxIteration {
    /// Farthest boundary vertex from `S` before the iteration, in `h`.
    pub max_distance_h: f32,
    /// Smallest dihedral angle of the mesh before the iteration, degrees.
    pub min_dihedral: f64,
    /// Boundary vertices that moved.
    pub boundary_moved: usize,
    /// Boundary vertices whose step was refused after halving (a step too short to make counts
    /// as neither moved nor refused).
    pub boundary_refused: usize,
    /// Interior vertices that moved.
    pub interior_moved: usize,
    /// Interior vertices whose step was refused.
    pub interior_refused: usize,
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
    fn info(&self) -> &'static ExtractorInfo {
        &INFO
    }

    fn produces_volume(&self) -> bool {
        true
    }

    fn extract_into(&self, samples: &Samples, out: &mut Extraction) -> Result<usize, ExtractError> {
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
        if surface.is_empty() {
            // Nothing to enclose: an empty volume, as every extractor gives where the field keeps its sign.
            return Ok(0);
        }
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
        Ok(0)
    }
}

/// The surface of samples that carry no triangle mesh: marching cubes on a cubic grid, marching
/// tetrahedra on a BCC lattice.
fn surface_of_samples(samples: &Samples) -> Result<TriangleBvh, ExtractError> {
    // Marching cubes on a cubic grid; marching tetrahedra on a BCC lattice (which marching
    // cubes refuses).
    let mut e = Extraction::default();
    match samples.lattice() {
        crate::lattice::Lattice::Cubic(_) => crate::extractors::MarchingCubes::default().extract(samples, &mut e)?,
        crate::lattice::Lattice::Bcc(_) => crate::extractors::MarchingTetrahedra::default().extract(samples, &mut e)?,
    }
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
    report.trace = relaxed.trace;
    report.times[2] = start.elapsed();
    let (volume, boundary) = mesh.into_meshes();
    report.tetrahedra = volume.tetrahedra.len();
    report.dihedral_deg = dihedral_range(&volume);
    Sculpted { volume, boundary, report }
}

/// Smallest and largest dihedral angle over all tetrahedra, degrees.
fn dihedral_range(mesh: &TetMesh) -> [f64; 2] {
    tets_dihedral_range(&mesh.positions, &mesh.tetrahedra)
}

/// Smallest and largest dihedral angle over the tetrahedra `tets` of `positions`, degrees.
fn tets_dihedral_range(positions: &[Vec3], tets: &[[u32; 4]]) -> [f64; 2] {
    tets.par_iter()
        .map(|t| {
            let a = dihedral_angles(t.map(|v| positions[v as usize]));
            [a.iter().copied().fold(180.0, f64::min), a.iter().copied().fold(0.0, f64::max)]
        })
        .reduce(|| [180.0, 0.0], |a, b| [a[0].min(b[0]), a[1].max(b[1])])
}

#[cfg(test)]
mod tests;
