//! Streaming a world or a volume larger than memory: chunks meshed slab by slab, straight from
//! the field ([`stream_chunked`]) or from a volume read z-slice by z-slice ([`stream_blocks`]),
//! each slab welded only against the previous slab's top face, and handed to a [`MeshSink`].

use super::{chunk_counts, mesh_block, Block, BlockBounds, BlockPlan, ChunkSlot, ChunkState, Fragment};
use crate::extract::{Chunking, ExtractError, Extraction, Extractor};
use crate::field::{BlockSide, Field};
use crate::lattice::Grid;
use glam::Vec3;
use rayon::prelude::*;
use std::collections::HashMap;

/// Receives a mesh streamed chunk by chunk: new vertices (world space), then triangles in global
/// vertex indices (every index refers to a vertex already received).
pub trait MeshSink {
    /// New vertices, numbered on from the ones received before.
    fn vertices(&mut self, positions: &[Vec3]) -> std::io::Result<()>;
    /// Triangles.
    fn triangles(&mut self, triangles: &[[u32; 3]]) -> std::io::Result<()>;
}

/// What [`stream_chunked`] did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct StreamStats {
    /// Chunks per axis.
    pub chunks: [usize; 3],
    /// Chunks meshed, skipped empty, skipped full.
    pub meshed: usize,
    /// Chunks skipped because every sample was outside.
    pub empty: usize,
    /// Chunks skipped because every sample was inside.
    pub full: usize,
    /// Of the empty and full chunks, those skipped unsampled because the field proved their side
    /// ([`crate::field::Field::block_side`]).
    pub proven: usize,
    /// Vertices and triangles written.
    pub vertices: u64,
    /// Triangles written.
    pub triangles: u64,
    /// Vertices merged at seams.
    pub welded: u64,
    /// Most seam keys held at once (vertices on one slab's faces).
    pub peak_keys: usize,
    /// Most mesh bytes held at once (one slab of chunks).
    pub peak_slab_bytes: usize,
}

/// Errors streaming a world.
#[derive(Debug, thiserror::Error)]
pub enum StreamError {
    /// Meshing failed (bad chunk size, a non-finite sample, ...).
    #[error(transparent)]
    Extract(#[from] ExtractError),
    /// The sink failed.
    #[error("writing the mesh: {0}")]
    Io(#[from] std::io::Error),
    /// The samples could not be read.
    #[error("{0}")]
    Read(String),
}

/// The index-coordinate z of a weld key (position bits or lattice key).
pub(super) fn key_z(key: u128) -> f32 {
    let z = (key >> 64) as u32;
    if key >> 127 == 1 {
        z as f32
    } else {
        f32::from_bits(z)
    }
}

/// Meshes a world of `grid` samples of `field` that need never exist as a dense grid: slabs of
/// chunks along z are sampled straight from the field and meshed in parallel, welded against the
/// previous slab's top face (the only vertices kept between slabs), and written to `sink`. Chunks
/// the field proves empty or full ([`crate::field::Field::block_side`]) are not sampled.
/// Memory is one slab of chunk meshes plus one face of seam keys. Cell-local extractors only
/// (their chunks need no apron). `progress(done, total)` is called after each slab.
pub fn stream_chunked(
    extractor: &dyn Extractor,
    field: &dyn Field,
    grid: Grid,
    iso: f32,
    chunk: usize,
    sink: &mut dyn MeshSink,
    mut progress: impl FnMut(usize, usize),
) -> Result<StreamStats, StreamError> {
    let chunking = extractor.chunking();
    if chunking != Chunking::CellLocal {
        return Err(ExtractError::BadInput {
            algorithm: extractor.name(),
            reason: "streaming needs a cell-local extractor (marching-cubes, marching-cubes-decider, marching-tetrahedra)".into(),
        }
        .into());
    }
    let counts = chunk_counts(&grid, chunk, extractor.name())?;
    let mut stats = StreamStats { chunks: counts, ..Default::default() };
    let mut seams = SeamWeld::new(extractor.name());
    let proven = std::sync::atomic::AtomicUsize::new(0);
    for z in 0..counts[2] {
        let ids: Vec<[usize; 3]> = (0..counts[0] * counts[1]).map(|k| [k % counts[0], k / counts[0], z]).collect();
        let meshed: Vec<(ChunkState, Extraction, Vec<Option<u128>>)> = ids
            .par_iter()
            .map(|&id| {
                let block = Block::new(id, chunk, 0, grid.dims);
                if let Some(side) = field.block_side(&grid, block.lo, block.dims, iso) {
                    proven.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                    let state = match side {
                        BlockSide::Outside => ChunkState::Empty,
                        BlockSide::Inside => ChunkState::Full,
                    };
                    return Ok((state, Extraction::default(), Vec::new()));
                }
                let mut slot = ChunkSlot::new(id, block, &grid, iso, None);
                slot.sample_and_mesh(extractor, chunking, &grid, field)?;
                Ok((slot.state, slot.mesh, slot.keys))
            })
            .collect::<Result<_, ExtractError>>()?;
        stats.peak_slab_bytes =
            stats.peak_slab_bytes.max(meshed.iter().map(|m| m.1.surface.capacity_bytes() + 16 * m.2.capacity()).sum());
        for (state, mesh, keys) in &meshed {
            seams.push(*state, &mesh.surface, keys, &|p| p, false, &mut stats, sink)?;
        }
        // Only the next slab shares vertices, on this slab's top face.
        seams.end_layer(((z + 1) * chunk) as f32, &mut stats);
        progress(z + 1, counts[2]);
    }
    stats.proven = proven.into_inner();
    Ok(stats)
}

/// The weld of a stream: the seam keys of the layer of blocks just written, each block's new
/// vertices and its triangles in global indices sent to the sink as they come.
struct SeamWeld {
    algorithm: &'static str,
    index: HashMap<u128, u32>,
    vertices: Vec<Vec3>,
    triangles: Vec<[u32; 3]>,
    remap: Vec<u32>,
}

impl SeamWeld {
    fn new(algorithm: &'static str) -> Self {
        Self { algorithm, index: HashMap::new(), vertices: Vec::new(), triangles: Vec::new(), remap: Vec::new() }
    }

    /// Welds one block's mesh (its vertices mapped by `map`, its triangles reversed when
    /// `mirror`) onto what was written, and writes its new vertices and its triangles.
    #[allow(clippy::too_many_arguments)]
    fn push(
        &mut self,
        state: ChunkState,
        surface: &crate::mesh::TriMesh,
        keys: &[Option<u128>],
        map: &dyn Fn(Vec3) -> Vec3,
        mirror: bool,
        stats: &mut StreamStats,
        sink: &mut dyn MeshSink,
    ) -> Result<(), StreamError> {
        match state {
            ChunkState::Empty => stats.empty += 1,
            ChunkState::Full => stats.full += 1,
            ChunkState::Meshed => stats.meshed += 1,
        }
        self.vertices.clear();
        self.remap.clear();
        for (i, &p) in surface.positions.iter().enumerate() {
            let count = stats.vertices + self.vertices.len() as u64;
            let next = u32::try_from(count)
                .map_err(|_| ExtractError::TooLarge { algorithm: self.algorithm, vertices: count as usize })?;
            let id = match keys[i] {
                Some(key) => *self.index.entry(key).or_insert(next),
                None => next,
            };
            if id == next {
                self.vertices.push(map(p));
            } else {
                stats.welded += 1;
            }
            self.remap.push(id);
        }
        self.triangles.clear();
        let remap = &self.remap;
        self.triangles.extend(surface.triangles.iter().map(|t| {
            let t = t.map(|v| remap[v as usize]);
            if mirror {
                [t[0], t[2], t[1]]
            } else {
                t
            }
        }));
        sink.vertices(&self.vertices)?;
        sink.triangles(&self.triangles)?;
        stats.vertices += self.vertices.len() as u64;
        stats.triangles += self.triangles.len() as u64;
        Ok(())
    }

    /// After a layer of blocks: keeps only the keys a later layer can make (index z at least
    /// `top`, the layer's upper face: every vertex of a later layer lies there or above).
    fn end_layer(&mut self, top: f32, stats: &mut StreamStats) {
        stats.peak_keys = stats.peak_keys.max(self.index.len());
        self.index.retain(|&key, _| key_z(key) >= top);
    }
}

/// Appends the next `count` z-slices of a volume to `out`, or says why it cannot.
pub type SliceReader<'a> = dyn FnMut(usize, &mut Vec<f32>) -> Result<(), String> + 'a;

/// Meshes a volume of `plan.dims` samples read z-slice by z-slice, block by block, straight
/// into `sink`: `read(count, out)` appends the next `count` slices (x fastest, inside where a
/// value is below `iso`) and is asked for each slice once, in order. Each layer of blocks along z
/// is meshed in parallel ([`mesh_block`], the extractor's apron included) and welded onto the
/// previous layer's top face by the fragments' keys, in the plan's order: the mesh written is
/// [`weld_fragments`](super::blocks::weld_fragments) of every block's fragment (same vertices in the same order, same
/// triangles; tested), with `map` applied to each vertex (index coordinates to the world) and
/// the winding reversed when `mirror`. Memory: the slices one layer of blocks reads, one copy of
/// them in blocks, one layer's meshes and one face of seam keys. `progress(done, total)` is
/// called after each layer.
#[allow(clippy::too_many_arguments)]
pub fn stream_blocks(
    extractor: &dyn Extractor,
    plan: &BlockPlan,
    iso: f32,
    read: &mut SliceReader<'_>,
    map: &dyn Fn(Vec3) -> Vec3,
    mirror: bool,
    sink: &mut dyn MeshSink,
    mut progress: impl FnMut(usize, usize),
) -> Result<StreamStats, StreamError> {
    let [nx, ny, nz] = plan.dims;
    let slice = nx * ny;
    let mut stats = StreamStats { chunks: plan.counts, ..Default::default() };
    let mut seams = SeamWeld::new(extractor.name());
    // Slices `first..first + window.len() / slice` of the volume.
    let (mut window, mut first, mut read_to) = (Vec::<f32>::new(), 0usize, 0usize);
    for z in 0..plan.counts[2] {
        let ids: Vec<[usize; 3]> =
            (0..plan.counts[0] * plan.counts[1]).map(|k| [k % plan.counts[0], k / plan.counts[0], z]).collect();
        let bounds: Vec<BlockBounds> = ids.iter().filter_map(|&id| plan.block(id)).collect();
        let (lo, hi) = (bounds[0].lo[2], bounds[0].lo[2] + bounds[0].dims[2]);
        if lo > first {
            window.drain(..(lo - first).min(window.len() / slice) * slice);
            first = lo;
        }
        if hi > read_to {
            read(hi - read_to, &mut window).map_err(StreamError::Read)?;
            read_to = hi;
        }
        if window.len() != (read_to - first) * slice || read_to > nz {
            return Err(StreamError::Read(format!(
                "the reader gave {} values for slices {first}..{read_to} of {nx}x{ny}",
                window.len()
            )));
        }
        let window = &window;
        let fragments: Vec<Fragment> = bounds
            .par_iter()
            .map(|b| {
                let mut values = Vec::with_capacity(b.dims.iter().product());
                for k in 0..b.dims[2] {
                    for j in 0..b.dims[1] {
                        let row = ((b.lo[2] + k - first) * ny + b.lo[1] + j) * nx + b.lo[0];
                        values.extend_from_slice(&window[row..row + b.dims[0]]);
                    }
                }
                mesh_block(extractor, plan, b.id, values, iso)
            })
            .collect::<Result<_, ExtractError>>()?;
        stats.peak_slab_bytes = stats
            .peak_slab_bytes
            .max(window.len() * 4 + fragments.iter().map(|f| f.surface.capacity_bytes() + 16 * f.keys.capacity()).sum::<usize>());
        for f in &fragments {
            seams.push(f.state, &f.surface, &f.keys, map, mirror, &mut stats, sink)?;
        }
        seams.end_layer(((z + 1) * plan.chunk) as f32, &mut stats);
        progress(z + 1, plan.counts[2]);
    }
    Ok(stats)
}
