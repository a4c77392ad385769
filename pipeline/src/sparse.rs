//! Runs meshed from evaluations near the surface only ([`extract_sparse`]): a built-in or mesh
//! field with a Lipschitz bound ([`Field::lipschitz`], or one the user gives) is sampled only in
//! the blocks the bound cannot rule out, so `isolab extract -f asteroid -r 2048` needs memory for
//! its mesh, not for 2048³ samples. The mesh is the dense run's in blocks of the same size
//! (`--chunk N`), bit for bit: the samples are evaluated where the dense grid's lie
//! ([`GridFieldEval`]) and the extractors read the field as a dense run's do. Without `--chunk`
//! a dense run meshes the grid in one piece, so its vertices come in another order.
//!
//! [`Sparse::Auto`] (the CLI's and the Python package's default) meshes sparsely wherever that is
//! certified and gives the same mesh: a cubic lattice, an extractor that meshes in blocks, a
//! field with a bound, and nothing that needs the dense samples afterwards (post-processes,
//! `--materials`, `--samples-out`), once the dense grid has more than [`AUTO_ABOVE_SAMPLES`].
//! Below that the dense run is as fast or faster (the octree and the per-block meshing cost
//! more than they save while the grid fits easily); above it memory decides.

use crate::{Input, LatticeKind, RunConfig, RunError};
use isolab_algorithms::chunks::{extract_sparse, GridFieldEval, Pruning, SparseGrid, SparseOptions, SparseStats};
use isolab_algorithms::{Chunking, Extraction, Extractor, Field, Grid};
use isolab_io::volume::Inside;
use serde::Serialize;
use std::sync::Arc;

/// Whether a run samples only near the surface.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Sparse {
    /// Where it is certified and gives the dense mesh (see the module doc); dense otherwise.
    Auto,
    /// Always; a run that cannot is refused, saying why.
    Always,
    /// Never: every sample of the grid.
    Never,
}

impl Sparse {
    /// The words that name each choice, as serialized.
    pub const CHOICES: [(&'static str, Sparse); 3] =
        [("auto", Sparse::Auto), ("always", Sparse::Always), ("never", Sparse::Never)];

    /// The CLI's rule: `--sparse` asks for always, `--dense` (or anything that needs every
    /// sample) for never, neither for auto.
    pub fn asked(sparse: bool, dense: bool) -> Sparse {
        match (sparse, dense) {
            (true, _) => Sparse::Always,
            (false, true) => Sparse::Never,
            (false, false) => Sparse::Auto,
        }
    }
}
crate::config::words!(Sparse, "sparse");

/// The dense grid's size above which [`Sparse::Auto`] meshes sparsely: 512³ samples (512 MiB
/// as `f32`). Measured with `isolab extract -a marching-cubes -o mesh.ply`, one run each: at
/// 256³ the sphere took 189 ms sparse and 84 ms dense; at 512³, 0.95 s and 1.03 s (75 and 602
/// MiB peak), the gyroid 5.9 s and 2.5 s (its surface fills the domain), the asteroid 7.3 s and
/// 14.1 s; at 1024³ the sphere 2.6 s and 5.6 s (206 MiB and 4.4 GiB).
pub const AUTO_ABOVE_SAMPLES: u64 = 1 << 27;

/// The metrics JSON's `sparse`: what a sparse run evaluated.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct SparseReport {
    /// The Lipschitz bound the pruning used.
    pub lipschitz: f64,
    /// Whether the bound was the field's own (true) or given (`--lipschitz`).
    pub field_bound: bool,
    /// Cells per block side.
    pub chunk: usize,
    /// Points evaluated, octree centres included.
    pub evaluations: u64,
    /// Of those, the points evaluated ruling blocks out (the octree's and its refinement's
    /// centres).
    pub pruning_evaluations: u64,
    /// Of the pruning's, the refinement's below the blocks.
    pub refinement_evaluations: u64,
    /// Points a dense run evaluates.
    pub dense_points: u64,
    /// Blocks of the grid.
    pub blocks: usize,
    /// Blocks sampled and meshed.
    pub sampled_blocks: usize,
    /// Time evaluating the field.
    pub evaluation_ms: f64,
    /// Time outside it (pruning, meshing, welding).
    pub other_ms: f64,
}

/// The bound a run prunes with, when it meshes sparsely; `None` for a dense run. `Always` with
/// anything that prevents it is an error naming the reason.
pub(crate) fn sparse_bound(
    config: &RunConfig,
    input: &Input,
    field: &dyn Field,
    extractor: &dyn Extractor,
    grid: Option<&Grid>,
) -> Result<Option<(f64, bool)>, RunError> {
    let small = grid.is_none_or(|g| g.dims.iter().map(|&d| d as u64).product::<u64>() <= AUTO_ABOVE_SAMPLES);
    if let Some(l) = config.lipschitz.filter(|l| !(l.is_finite() && *l > 0.0)) {
        // A bound of 0 would rule out every block: the mesh would be empty, silently.
        let reason = format!("--lipschitz {l}: a Lipschitz bound must be a positive finite number");
        return Err(RunError::Sparse { field: config.field.clone(), reason });
    }
    if config.sparse == Sparse::Never || (config.sparse == Sparse::Auto && small) {
        return Ok(None);
    }
    let bound = config.lipschitz.map(|l| (l, false)).or_else(|| field.lipschitz().map(|l| (l, true)));
    let obstacle = if input.volume.is_some() || grid.is_none() {
        Some("a volume file is meshed from its voxels (sparse runs take built-in fields and meshes)".to_owned())
    } else if config.lattice != LatticeKind::Cubic {
        Some("the BCC lattice is sampled densely".to_owned())
    } else if extractor.chunking() == Chunking::Unsupported {
        Some(format!("{} does not mesh in blocks", extractor.name()))
    } else if !config.post.is_empty() {
        Some("post-processes read the dense samples".to_owned())
    } else if config.materials {
        Some("--materials reads the dense samples".to_owned())
    } else if bound.is_none() {
        Some(format!("field '{}' has no Lipschitz bound; give one with --lipschitz L", field.name()))
    } else {
        None
    };
    match (obstacle, config.sparse) {
        (None, _) => Ok(bound),
        (Some(_), Sparse::Auto) => Ok(None),
        (Some(reason), _) => Err(RunError::Sparse { field: config.field.clone(), reason }),
    }
}

/// Meshes `field` on `grid` from the blocks a bound `lipschitz` keeps, into a new extraction
/// whose sampling time is the evaluations' and whose extraction time is the rest.
pub(crate) fn extract_sparse_run(
    extractor: &dyn Extractor,
    field: &Arc<dyn Field>,
    grid: &Grid,
    iso: f32,
    (lipschitz, field_bound): (f64, bool),
    chunk: Option<usize>,
    memory_limit: Option<u64>,
) -> Result<(Extraction, SparseReport), RunError> {
    let chunk = chunk.unwrap_or_else(|| SparseOptions::default_chunk(extractor));
    let options = SparseOptions { chunk, batch: 1 << 18, pruning: Pruning::Lipschitz(lipschitz) };
    let mut extraction = Extraction { memory_limit, ..Extraction::default() };
    let mut eval = GridFieldEval { field: field.clone(), grid: *grid };
    let stats: SparseStats = extract_sparse(extractor, &SparseGrid::of(grid), iso, &options, &mut eval, &mut extraction)
        .map_err(|e| RunError::Sparse { field: field.name().to_owned(), reason: e.to_string() })?;
    let times = &mut extraction.stats.times;
    *times = Default::default();
    times.sampling = stats.eval_time;
    times.geometry = stats.other_time;
    let report = SparseReport {
        lipschitz,
        field_bound,
        chunk,
        evaluations: stats.evaluations,
        pruning_evaluations: stats.pruning_evaluations,
        refinement_evaluations: stats.refinement_evaluations,
        dense_points: stats.dense_points,
        blocks: stats.blocks,
        sampled_blocks: stats.sampled_blocks,
        evaluation_ms: stats.eval_time.as_secs_f64() * 1e3,
        other_ms: stats.other_time.as_secs_f64() * 1e3,
    };
    Ok((extraction, report))
}

/// The grid [`crate::lattice_for`] samples, without the limit of samples a lattice held whole
/// may have (a sparse run holds blocks near the surface only).
pub(crate) fn grid_for(field: &dyn Field, config: &RunConfig) -> Result<Grid, RunError> {
    let domain = field.domain();
    Ok(match config.dims {
        Some(dims) => Grid::sparse_with_dims(&domain, dims)?,
        None => Grid::sparse_covering(&domain, config.resolution)?,
    })
}

/// The warning of an empty sparse mesh: its samples are all on one side, the first one's.
pub(crate) fn empty_warning(
    extraction: &Extraction,
    field: &dyn Field,
    grid: &Grid,
    internal_iso: f32,
    iso: f32,
    inside: Inside,
) -> Option<String> {
    if !extraction.surface.triangles.is_empty() || !extraction.volume.tetrahedra.is_empty() {
        return None;
    }
    let first_inside = field.value(grid.position(0, 0, 0)) < internal_iso;
    crate::report::empty_mesh_warning(field.name(), iso, inside, !first_inside, first_inside)
}
