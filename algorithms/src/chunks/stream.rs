//! Streaming a world larger than memory: chunks meshed slab by slab straight from the field, each
//! slab welded only against the previous slab's top face, and handed to a [`MeshSink`].

use super::*;

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
    let mut index: HashMap<u128, u32> = HashMap::new();
    let (mut batch_v, mut batch_t, mut remap) = (Vec::new(), Vec::new(), Vec::new());
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
            match state {
                ChunkState::Empty => stats.empty += 1,
                ChunkState::Full => stats.full += 1,
                ChunkState::Meshed => stats.meshed += 1,
            }
            batch_v.clear();
            remap.clear();
            for (i, &p) in mesh.surface.positions.iter().enumerate() {
                let next = u32::try_from(stats.vertices + batch_v.len() as u64).map_err(|_| ExtractError::TooLarge {
                    algorithm: extractor.name(),
                    vertices: (stats.vertices + batch_v.len() as u64) as usize,
                })?;
                let id = match keys[i] {
                    Some(key) => *index.entry(key).or_insert(next),
                    None => next,
                };
                if id == next {
                    batch_v.push(p);
                } else {
                    stats.welded += 1;
                }
                remap.push(id);
            }
            batch_t.clear();
            batch_t.extend(mesh.surface.triangles.iter().map(|t| t.map(|v| remap[v as usize])));
            sink.vertices(&batch_v)?;
            sink.triangles(&batch_t)?;
            stats.vertices += batch_v.len() as u64;
            stats.triangles += batch_t.len() as u64;
        }
        stats.peak_keys = stats.peak_keys.max(index.len());
        // Only the next slab shares vertices, on this slab's top face.
        let top = ((z + 1) * chunk) as f32;
        index.retain(|&key, _| key_z(key) == top);
        progress(z + 1, counts[2]);
    }
    stats.proven = proven.into_inner();
    Ok(stats)
}
