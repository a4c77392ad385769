//! Chunked extraction: a cubic grid split into chunks of `N`³ cells that share their boundary
//! samples, meshed independently and in parallel (rayon), then welded into one mesh. Chunks whose
//! samples are all inside or all outside are skipped from their min/max without meshing.
//!
//! Each chunk is meshed in exact local coordinates (origin 0, spacing 1) and moved to world space
//! as `origin + (local + chunk offset) · spacing`, so a vertex on a face, edge or corner shared by
//! several chunks gets bitwise the same position in each of them, and welding by position is exact.
//! This holds for extractors whose output is local to the cell (every triangle from one cell's
//! samples, every vertex from one lattice edge): marching cubes and its decider variant
//! ([`Extractor::supports_chunks`]). Their welded output has exactly the vertices and triangles of
//! the single-volume extraction (tested). Dual methods (surface nets, dual contouring, with
//! smoothing) and the tetrahedral lattices need cells or tetrahedra that straddle chunk faces,
//! hence an apron and ownership rules inside the extractor; they refuse chunking for now.

use crate::extract::{ExtractError, Extraction, Extractor};
use crate::lattice::{Grid, Lattice};
use crate::samples::Samples;
use glam::Vec3;
use rayon::prelude::*;
use std::collections::HashMap;
use std::time::Instant;

/// What chunked extraction did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ChunkStats {
    /// Chunks per axis.
    pub chunks: [usize; 3],
    /// Chunks meshed.
    pub meshed: usize,
    /// Chunks skipped because every sample was outside.
    pub empty: usize,
    /// Chunks skipped because every sample was inside.
    pub full: usize,
    /// Vertices merged at seams.
    pub welded: usize,
}

/// Chunks per axis for chunks of `chunk` cells, or an error naming what does not fit.
pub fn chunk_counts(grid: &Grid, chunk: usize, algorithm: &'static str) -> Result<[usize; 3], ExtractError> {
    if chunk < 2 {
        return Err(ExtractError::BadInput { algorithm, reason: format!("chunk size {chunk} is below 2 cells") });
    }
    let cells = grid.dims.map(|d| d.saturating_sub(1));
    if cells.iter().any(|&c| c % chunk != 0) {
        return Err(ExtractError::BadInput {
            algorithm,
            reason: format!(
                "chunk size {chunk} does not divide the grid's cells {}x{}x{} (samples {}x{}x{}); pick dimensions of k·{chunk} + 1 samples",
                cells[0], cells[1], cells[2], grid.dims[0], grid.dims[1], grid.dims[2]
            ),
        });
    }
    Ok(cells.map(|c| c / chunk))
}

/// Meshes `samples` in chunks of `chunk`³ cells with `extractor` and welds the result into `out`.
pub fn extract_chunked(
    extractor: &dyn Extractor,
    samples: &Samples,
    chunk: usize,
    out: &mut Extraction,
) -> Result<ChunkStats, ExtractError> {
    let algorithm = extractor.name();
    if !extractor.supports_chunks() {
        return Err(ExtractError::BadInput {
            algorithm,
            reason: "chunked extraction is not supported yet (marching-cubes and marching-cubes-decider support it)".into(),
        });
    }
    let Lattice::Cubic(grid) = *samples.lattice() else {
        return Err(ExtractError::UnsupportedLattice { algorithm, lattice: "bcc", supported: "cubic (for --chunk)" });
    };
    let counts = chunk_counts(&grid, chunk, algorithm)?;
    let start = Instant::now();
    let iso = samples.iso();
    let chunk_ids: Vec<[usize; 3]> =
        (0..counts[2]).flat_map(|z| (0..counts[1]).flat_map(move |y| (0..counts[0]).map(move |x| [x, y, z]))).collect();
    // Each chunk: its (N+1)³ samples in local coordinates, skipped when it cannot hold surface.
    let meshed: Vec<Result<ChunkMesh, ExtractError>> = chunk_ids
        .par_iter()
        .map(|&id| {
            let k0 = id.map(|c| c * chunk);
            let n = chunk + 1;
            let mut values = Vec::with_capacity(n * n * n);
            let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
            for z in 0..n {
                for y in 0..n {
                    let row = grid.index(k0[0], k0[1] + y, k0[2] + z);
                    let slice = &samples.values()[row..row + n];
                    for &v in slice {
                        lo = lo.min(v);
                        hi = hi.max(v);
                    }
                    values.extend_from_slice(slice);
                }
            }
            if lo >= iso {
                return Ok(ChunkMesh::Empty);
            }
            if hi < iso {
                return Ok(ChunkMesh::Full);
            }
            let local = Grid { origin: Vec3::ZERO, spacing: 1.0, dims: [n, n, n] };
            let chunk_samples = Samples::from_values(Lattice::Cubic(local), values, iso)?;
            let mut e = Extraction::default();
            extractor.extract(&chunk_samples, &mut e)?;
            // Vertices on the chunk's faces (a local coordinate exactly 0 or N) are the only ones
            // another chunk can share.
            let last = chunk as f32;
            let on_face = e.surface.positions.iter().map(|p| p.to_array().iter().any(|&c| c == 0.0 || c == last)).collect();
            let offset = Vec3::new(k0[0] as f32, k0[1] as f32, k0[2] as f32);
            for p in &mut e.surface.positions {
                *p = grid.origin + (*p + offset) * grid.spacing;
            }
            Ok(ChunkMesh::Mesh(Box::new(e), on_face))
        })
        .collect();
    out.clear();
    out.stats.times.sampling = samples.sampling_time();
    let mut stats = ChunkStats { chunks: counts, ..Default::default() };
    let mut index: HashMap<[u32; 3], u32> = HashMap::new();
    for m in meshed {
        match m? {
            ChunkMesh::Empty => stats.empty += 1,
            ChunkMesh::Full => stats.full += 1,
            ChunkMesh::Mesh(e, on_face) => {
                stats.meshed += 1;
                let e = *e;
                out.stats.discarded_triangles += e.stats.discarded_triangles;
                out.stats.active_cells += e.stats.active_cells;
                let has_normals = e.surface.normals.len() == e.surface.positions.len();
                let remap: Vec<u32> = e
                    .surface
                    .positions
                    .iter()
                    .enumerate()
                    .map(|(i, &p)| {
                        let next = out.surface.positions.len() as u32;
                        let id = if on_face[i] { *index.entry(p.to_array().map(f32::to_bits)).or_insert(next) } else { next };
                        if id == next {
                            out.surface.positions.push(p);
                            if has_normals {
                                out.surface.normals.push(e.surface.normals[i]);
                            }
                        } else {
                            stats.welded += 1;
                        }
                        id
                    })
                    .collect();
                out.surface.triangles.extend(e.surface.triangles.iter().map(|t| t.map(|v| remap[v as usize])));
            }
        }
    }
    if out.surface.normals.len() != out.surface.positions.len() {
        out.surface.normals.clear();
    }
    if let Some(field) = samples.field().filter(|f| f.has_analytic_gradient()) {
        out.surface.normals = out.surface.positions.iter().map(|&p| field.gradient(p).normalize_or_zero()).collect();
    }
    out.stats.times.geometry = start.elapsed();
    out.finish_counts(0);
    Ok(stats)
}

enum ChunkMesh {
    Empty,
    Full,
    /// The chunk's mesh in world space, and which of its vertices lie on the chunk's faces.
    Mesh(Box<Extraction>, Vec<bool>),
}
