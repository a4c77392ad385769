//! Chunked extraction: a cubic grid split into chunks of `N`³ cells that share their boundary
//! samples, meshed independently and in parallel (rayon), then welded into one mesh. Chunks whose
//! samples are all inside or all outside are skipped from their min/max without meshing.
//!
//! Every chunk is meshed in the grid's **index coordinates** (sample `(x, y, z)` at `(x, y, z)`,
//! exact in `f32` up to 2²⁴ samples per axis), so two chunks computing the same vertex from the
//! same samples get bitwise the same position; positions go to world space as
//! `origin + index · spacing` afterwards. What a chunk reads and how chunks weld depends on the
//! extractor's [`Chunking`]:
//! - [`Chunking::CellLocal`] (marching cubes, Kuhn marching tetrahedra): a chunk reads exactly
//!   its `(N + 1)`³ samples; vertices on its faces are welded with the neighbours' by position
//!   bits, or by lattice key where the extractor reports vertex origins (marching tetrahedra,
//!   whose crossings can coincide at a sample equal to the iso-value; marching cubes keeps its
//!   crossings off the samples). The welded output has exactly the vertices and triangles of the single-volume
//!   extraction (tested).
//! - [`Chunking::Apron`]`(a)` (surface nets, dual contouring, regularised marching tetrahedra):
//!   a chunk also reads `a` samples of each neighbour (the *apron*: a dual quad needs its edge's
//!   four cells, a cell's pieces its face neighbours, each smoothing iteration one more cell, a
//!   merged vertex its sample's star). The extractor reports each vertex's lattice origin (owning
//!   sample and ordinal, [`crate::extract::Origins`]); a triangle's *anchor* is the
//!   componentwise minimum of its vertices' owning samples, and each chunk keeps only the
//!   triangles whose anchor lies in its own samples, so every triangle is made by exactly one
//!   chunk, far enough from that chunk's apron edge to be computed as the whole volume would.
//!   Vertices weld by lattice key, so the welded mesh has the whole-volume topology whatever the
//!   rounding (tested: counts and closedness equal the whole-volume extraction).
//!
//! When the samples carry their field, each chunk gets it re-expressed in index coordinates
//! ([`IndexSpaceField`]), so dual contouring's Hermite normals and projections see the true field.
//!
//! [`ChunkedVolume`] keeps the samples and one persistent slot per chunk (its samples and mesh
//! buffers), so editing with a [`Brush`] re-meshes only the chunks whose samples (apron included)
//! changed, and re-meshing a chunk reuses its buffers.

use crate::extract::{Chunking, ExtractError, Extraction, Extractor};
use crate::field::Field;
use crate::geometry::Aabb;
use crate::lattice::{Grid, Lattice};
use crate::samples::Samples;
use glam::Vec3;
use rayon::prelude::*;
use std::collections::HashMap;
use std::sync::Arc;
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
    /// Apron width in samples (0 for cell-local extractors).
    pub apron: usize,
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
    if grid.dims.iter().any(|&d| d > 1 << 24) {
        return Err(ExtractError::BadInput {
            algorithm,
            reason: format!(
                "grid {}x{}x{} is above 2^24 samples on an axis (index coordinates would not be exact)",
                grid.dims[0], grid.dims[1], grid.dims[2]
            ),
        });
    }
    Ok(cells.map(|c| c / chunk))
}

/// How `extractor` meshes chunks, and the grid of `samples` (cubic only).
fn check_chunkable(extractor: &dyn Extractor, samples: &Samples) -> Result<(Grid, Chunking), ExtractError> {
    let algorithm = extractor.name();
    let chunking = extractor.chunking();
    if chunking == Chunking::Unsupported {
        return Err(ExtractError::BadInput {
            algorithm,
            reason: "it cannot mesh in chunks (its output is a volume or depends on the whole grid)".into(),
        });
    }
    match *samples.lattice() {
        Lattice::Cubic(grid) => Ok((grid, chunking)),
        Lattice::Bcc(_) => Err(ExtractError::UnsupportedLattice { algorithm, lattice: "bcc", supported: "cubic (for --chunk)" }),
    }
}

/// A field seen in a grid's index coordinates: `f'(p) = f(origin + p · spacing)`.
pub struct IndexSpaceField {
    inner: Arc<dyn Field>,
    origin: Vec3,
    spacing: f32,
}

impl IndexSpaceField {
    /// `inner` in the index coordinates of `grid`.
    pub fn new(inner: Arc<dyn Field>, grid: &Grid) -> Self {
        Self { inner, origin: grid.origin, spacing: grid.spacing }
    }

    fn world(&self, p: Vec3) -> Vec3 {
        self.origin + p * self.spacing
    }
}

impl Field for IndexSpaceField {
    fn name(&self) -> &str {
        self.inner.name()
    }

    fn value(&self, p: Vec3) -> f32 {
        self.inner.value(self.world(p))
    }

    fn domain(&self) -> Aabb {
        let d = self.inner.domain();
        Aabb::new((d.min - self.origin) / self.spacing, (d.max - self.origin) / self.spacing)
    }

    fn has_analytic_gradient(&self) -> bool {
        self.inner.has_analytic_gradient()
    }

    fn gradient(&self, p: Vec3) -> Vec3 {
        self.inner.gradient(self.world(p)) * self.spacing
    }

    fn difference_step(&self) -> f32 {
        self.inner.difference_step() / self.spacing
    }

    fn distance_to_surface(&self, p: Vec3, iso: f32) -> f32 {
        self.inner.distance_to_surface(self.world(p), iso) / self.spacing
    }
}

/// What a chunk holds after meshing.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ChunkState {
    /// Every sample outside: no mesh.
    #[default]
    Empty,
    /// Every sample inside: no mesh.
    Full,
    /// A mesh (possibly with no triangles).
    Meshed,
}

/// The samples a chunk reads and the anchors it owns, in world sample indices.
#[derive(Clone, Copy, Debug)]
struct Block {
    /// First sample read per axis.
    lo: [usize; 3],
    /// Samples read per axis.
    dims: [usize; 3],
    /// Owned anchors: `own_lo[a] <= anchor[a] < own_hi[a]`.
    own_lo: [usize; 3],
    own_hi: [usize; 3],
}

impl Block {
    fn new(id: [usize; 3], chunk: usize, apron: usize, world: [usize; 3]) -> Self {
        let k0 = id.map(|c| c * chunk);
        let lo = k0.map(|k| k.saturating_sub(apron));
        let dims: [usize; 3] = std::array::from_fn(|a| (k0[a] + chunk + apron).min(world[a] - 1) - lo[a] + 1);
        // The last chunk on an axis also owns the grid's last sample.
        let own_hi = std::array::from_fn(|a| if k0[a] + chunk + 1 >= world[a] { world[a] } else { k0[a] + chunk });
        Self { lo, dims, own_lo: k0, own_hi }
    }

    fn hi(&self, a: usize) -> usize {
        self.lo[a] + self.dims[a] - 1
    }
}

/// A lattice key: a vertex's owning sample (world indices) and ordinal, tagged apart from
/// position keys by the top bit.
fn lattice_key(o: [u32; 4], lo: [usize; 3]) -> u128 {
    let g = |a: usize| u128::from(o[a]) + lo[a] as u128;
    g(0) | g(1) << 32 | g(2) << 64 | u128::from(o[3] & 0x7FFF_FFFF) << 96 | 1 << 127
}

/// One chunk's persistent buffers: its samples in index coordinates and its mesh in world space.
pub struct ChunkSlot {
    /// Chunk index per axis.
    pub id: [usize; 3],
    block: Block,
    samples: Samples,
    /// The chunk's mesh (world space), valid when `state` is `Meshed`.
    pub mesh: Extraction,
    /// Per vertex: its weld key (position bits or lattice key), or `None` for vertices no other
    /// chunk can have.
    keys: Vec<Option<u128>>,
    /// Scratch for compacting owned vertices.
    remap: Vec<u32>,
    /// What the last meshing found.
    pub state: ChunkState,
}

impl ChunkSlot {
    /// A slot for chunk `id` reading `block` of `world`'s samples; `field` is the world's field.
    fn new(id: [usize; 3], block: Block, world: &Grid, iso: f32, field: Option<&Arc<dyn Field>>) -> Self {
        let local = Grid {
            origin: Vec3::new(block.lo[0] as f32, block.lo[1] as f32, block.lo[2] as f32),
            spacing: 1.0,
            dims: block.dims,
        };
        let n = block.dims.iter().product();
        let mut samples = Samples::from_values(Lattice::Cubic(local), vec![0.0; n], iso).expect("zeros are finite");
        if let Some(f) = field {
            samples = samples.with_field(Arc::new(IndexSpaceField::new(f.clone(), world)));
        }
        Self { id, block, samples, mesh: Extraction::default(), keys: Vec::new(), remap: Vec::new(), state: ChunkState::Empty }
    }

    /// Copies the chunk's samples out of the world's and meshes them (or records it empty/full).
    fn remesh(&mut self, extractor: &dyn Extractor, chunking: Chunking, grid: &Grid, values: &[f32]) -> Result<(), ExtractError> {
        let b = self.block;
        let [nx, ny, nz] = b.dims;
        let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
        let local = self.samples.values_mut();
        for z in 0..nz {
            for y in 0..ny {
                let row = grid.index(b.lo[0], b.lo[1] + y, b.lo[2] + z);
                let src = &values[row..row + nx];
                for &v in src {
                    lo = lo.min(v);
                    hi = hi.max(v);
                }
                local[(z * ny + y) * nx..(z * ny + y + 1) * nx].copy_from_slice(src);
            }
        }
        self.mesh_loaded(extractor, chunking, grid, lo, hi)
    }

    /// Samples the chunk's block from `field` (world grid `grid`) and meshes it; a non-finite
    /// value is an error naming where.
    fn sample_and_mesh(
        &mut self,
        extractor: &dyn Extractor,
        chunking: Chunking,
        grid: &Grid,
        field: &dyn Field,
    ) -> Result<(), ExtractError> {
        let b = self.block;
        let [nx, ny, nz] = b.dims;
        let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
        let local = self.samples.values_mut();
        for z in 0..nz {
            for y in 0..ny {
                for x in 0..nx {
                    let p = grid.position(b.lo[0] + x, b.lo[1] + y, b.lo[2] + z);
                    let v = field.value(p);
                    if !v.is_finite() {
                        return Err(crate::samples::SampleError::NonFinite {
                            field: field.name().to_owned(),
                            position: p.to_array(),
                            index: grid.index(b.lo[0] + x, b.lo[1] + y, b.lo[2] + z),
                            value: v,
                        }
                        .into());
                    }
                    lo = lo.min(v);
                    hi = hi.max(v);
                    local[(z * ny + y) * nx + x] = v;
                }
            }
        }
        self.mesh_loaded(extractor, chunking, grid, lo, hi)
    }

    /// Meshes the loaded samples (whose range is `lo..=hi`), keys its shareable vertices, and
    /// moves the mesh to world space.
    fn mesh_loaded(
        &mut self,
        extractor: &dyn Extractor,
        chunking: Chunking,
        grid: &Grid,
        lo: f32,
        hi: f32,
    ) -> Result<(), ExtractError> {
        let b = self.block;
        let iso = self.samples.iso();
        self.mesh.clear();
        self.keys.clear();
        if lo >= iso {
            self.state = ChunkState::Empty;
            return Ok(());
        }
        if hi < iso {
            self.state = ChunkState::Full;
            return Ok(());
        }
        self.state = ChunkState::Meshed;
        self.mesh.origins.wanted = true;
        extractor.extract(&self.samples, &mut self.mesh)?;
        let with_origins = self.mesh.origins.vertices.len() == self.mesh.surface.positions.len();
        match chunking {
            Chunking::Apron(_) => self.keep_owned(extractor.name())?,
            // Cell-local with origins: every vertex welds by lattice key (exact even where
            // crossings coincide).
            _ if with_origins => {
                let lo = b.lo;
                self.keys.extend(self.mesh.origins.vertices.iter().map(|&o| Some(lattice_key(o, lo))));
            }
            _ => {
                let bounds = [0, 1, 2].map(|a| (b.lo[a] as f32, b.hi(a) as f32));
                self.keys.extend(self.mesh.surface.positions.iter().map(|p| {
                    let on_face = (0..3).any(|a| p[a] == bounds[a].0 || p[a] == bounds[a].1);
                    on_face.then(|| position_key(*p))
                }));
            }
        }
        for p in &mut self.mesh.surface.positions {
            *p = grid.origin + *p * grid.spacing;
        }
        Ok(())
    }

    /// Keeps the triangles whose anchor this chunk owns and the vertices they use, keyed by
    /// their lattice origin.
    fn keep_owned(&mut self, algorithm: &'static str) -> Result<(), ExtractError> {
        let b = self.block;
        let mesh = &mut self.mesh;
        let origins = &mesh.origins.vertices;
        if origins.len() != mesh.surface.positions.len() {
            return Err(ExtractError::BadInput {
                algorithm,
                reason: format!(
                    "reported {} vertex origins for {} vertices; it cannot mesh in chunks",
                    origins.len(),
                    mesh.surface.positions.len()
                ),
            });
        }
        let owned = |t: &[u32; 3]| {
            (0..3).all(|a| {
                let anchor = t.iter().map(|&v| origins[v as usize][a] as usize).min().unwrap_or(0) + b.lo[a];
                (b.own_lo[a]..b.own_hi[a]).contains(&anchor)
            })
        };
        mesh.surface.triangles.retain(owned);
        self.remap.clear();
        self.remap.resize(mesh.surface.positions.len(), u32::MAX);
        for t in &mesh.surface.triangles {
            for &v in t {
                self.remap[v as usize] = 0;
            }
        }
        let with_normals = mesh.surface.normals.len() == mesh.surface.positions.len();
        let mut next = 0usize;
        for (v, (slot, &origin)) in self.remap.iter_mut().zip(origins).enumerate() {
            if *slot == 0 {
                *slot = next as u32;
                mesh.surface.positions[next] = mesh.surface.positions[v];
                if with_normals {
                    mesh.surface.normals[next] = mesh.surface.normals[v];
                }
                self.keys.push(Some(lattice_key(origin, b.lo)));
                next += 1;
            }
        }
        mesh.surface.positions.truncate(next);
        mesh.surface.normals.truncate(if with_normals { next } else { 0 });
        for t in &mut mesh.surface.triangles {
            *t = t.map(|v| self.remap[v as usize]);
        }
        Ok(())
    }
}

/// A weld key from exact position bits.
fn position_key(p: Vec3) -> u128 {
    let [x, y, z] = p.to_array().map(|c| u128::from(c.to_bits()));
    x | y << 32 | z << 64
}

/// Welds the chunks' meshes into `out` (cleared first) and fills the counts of `stats`.
fn weld<'a>(slots: impl Iterator<Item = &'a ChunkSlot>, out: &mut Extraction, stats: &mut ChunkStats) {
    out.surface.clear();
    let mut index: HashMap<u128, u32> = HashMap::new();
    let mut with_normals = true;
    for slot in slots {
        match slot.state {
            ChunkState::Empty => stats.empty += 1,
            ChunkState::Full => stats.full += 1,
            ChunkState::Meshed => {
                stats.meshed += 1;
                let e = &slot.mesh;
                out.stats.discarded_triangles += e.stats.discarded_triangles;
                out.stats.active_cells += e.stats.active_cells;
                with_normals &= e.surface.normals.len() == e.surface.positions.len();
                let remap: Vec<u32> = e
                    .surface
                    .positions
                    .iter()
                    .enumerate()
                    .map(|(i, &p)| {
                        let next = out.surface.positions.len() as u32;
                        let id = match slot.keys[i] {
                            Some(key) => *index.entry(key).or_insert(next),
                            None => next,
                        };
                        if id == next {
                            out.surface.positions.push(p);
                            if let Some(&n) = e.surface.normals.get(i) {
                                out.surface.normals.push(n);
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
    if !with_normals || out.surface.normals.len() != out.surface.positions.len() {
        out.surface.normals.clear();
    }
}

/// Normals from the field's analytic gradient, where it has one.
fn field_normals(field: Option<&Arc<dyn Field>>, out: &mut Extraction) {
    if let Some(field) = field.filter(|f| f.has_analytic_gradient()) {
        out.surface.normals.clear();
        out.surface.normals.extend(out.surface.positions.iter().map(|&p| field.gradient(p).normalize_or_zero()));
    }
}

/// The apron a chunking needs.
fn apron_of(chunking: Chunking) -> usize {
    match chunking {
        Chunking::Apron(a) => a,
        _ => 0,
    }
}

/// Meshes `samples` in chunks of `chunk`³ cells with `extractor` and welds the result into `out`.
pub fn extract_chunked(
    extractor: &dyn Extractor,
    samples: &Samples,
    chunk: usize,
    out: &mut Extraction,
) -> Result<ChunkStats, ExtractError> {
    let (grid, chunking) = check_chunkable(extractor, samples)?;
    let counts = chunk_counts(&grid, chunk, extractor.name())?;
    let apron = apron_of(chunking);
    let start = Instant::now();
    let mut slots: Vec<ChunkSlot> = chunk_ids(counts)
        .map(|id| ChunkSlot::new(id, Block::new(id, chunk, apron, grid.dims), &grid, samples.iso(), samples.field()))
        .collect();
    slots.par_iter_mut().try_for_each(|slot| slot.remesh(extractor, chunking, &grid, samples.values()))?;
    out.clear();
    out.stats.times.sampling = samples.sampling_time();
    let mut stats = ChunkStats { chunks: counts, apron, ..Default::default() };
    weld(slots.iter(), out, &mut stats);
    field_normals(samples.field(), out);
    out.stats.times.geometry = start.elapsed();
    out.finish_counts(0);
    Ok(stats)
}

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
fn key_z(key: u128) -> f32 {
    let z = (key >> 64) as u32;
    if key >> 127 == 1 {
        z as f32
    } else {
        f32::from_bits(z)
    }
}

/// Meshes a world of `grid` samples of `field` that need never exist as a dense grid: slabs of
/// chunks along z are sampled straight from the field and meshed in parallel, welded against the
/// previous slab's top face (the only vertices kept between slabs), and written to `sink`.
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
    for z in 0..counts[2] {
        let ids: Vec<[usize; 3]> = (0..counts[0] * counts[1]).map(|k| [k % counts[0], k / counts[0], z]).collect();
        let meshed: Vec<(ChunkState, Extraction, Vec<Option<u128>>)> = ids
            .par_iter()
            .map(|&id| {
                let mut slot = ChunkSlot::new(id, Block::new(id, chunk, 0, grid.dims), &grid, iso, None);
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
    Ok(stats)
}

/// Chunk indices, x fastest.
fn chunk_ids(counts: [usize; 3]) -> impl Iterator<Item = [usize; 3]> {
    (0..counts[2]).flat_map(move |z| (0..counts[1]).flat_map(move |y| (0..counts[0]).map(move |x| [x, y, z])))
}

/// A spherical brush: adds material (`add`) or removes it within `radius` of `centre`, blended
/// into the field over `falloff` (a smooth minimum / maximum with the sphere's distance, so the
/// edit has no crease where it meets the terrain).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Brush {
    /// Centre, world coordinates.
    pub centre: Vec3,
    /// Radius, world units (above 0).
    pub radius: f32,
    /// Blend width, world units (0: a hard union or difference).
    pub falloff: f32,
    /// Add material (true) or carve it (false).
    pub add: bool,
    /// The material an adding brush paints into the samples it makes solid
    /// ([`crate::materials`]); carving leaves materials alone.
    pub material: u8,
}

/// Errors editing a [`ChunkedVolume`].
#[derive(Debug, thiserror::Error)]
pub enum EditError {
    /// The brush does not touch the world.
    #[error("brush at ({x}, {y}, {z}) with radius {radius} lies outside the world {min:?}..{max:?}")]
    Outside {
        /// Centre x.
        x: f32,
        /// Centre y.
        y: f32,
        /// Centre z.
        z: f32,
        /// Radius.
        radius: f32,
        /// World minimum corner.
        min: [f32; 3],
        /// World maximum corner.
        max: [f32; 3],
    },
    /// A radius of zero or below, or a non-finite brush.
    #[error("brush radius {radius} and falloff {falloff} must be finite, the radius above 0 and the falloff at least 0")]
    BadBrush {
        /// Radius given.
        radius: f32,
        /// Falloff given.
        falloff: f32,
    },
    /// Re-meshing failed.
    #[error(transparent)]
    Extract(#[from] ExtractError),
}

/// A world of samples meshed in chunks, editable with brushes; only changed chunks are re-meshed.
pub struct ChunkedVolume {
    grid: Grid,
    values: Vec<f32>,
    chunk: usize,
    chunking: Chunking,
    counts: [usize; 3],
    /// One material id per sample, when given.
    materials: Option<Vec<u8>>,
    slots: Vec<ChunkSlot>,
    dirty: Vec<bool>,
}

impl ChunkedVolume {
    /// Takes `samples` (cubic) apart into chunks of `chunk`³ cells for `extractor`; every chunk
    /// starts dirty. Edits change the samples, so the field is not kept: extractors see raw
    /// samples (dual contouring takes its normals from them).
    pub fn new(extractor: &dyn Extractor, samples: Samples, chunk: usize) -> Result<Self, ExtractError> {
        let (grid, chunking) = check_chunkable(extractor, &samples)?;
        let counts = chunk_counts(&grid, chunk, extractor.name())?;
        let iso = samples.iso();
        let apron = apron_of(chunking);
        let slots: Vec<ChunkSlot> =
            chunk_ids(counts).map(|id| ChunkSlot::new(id, Block::new(id, chunk, apron, grid.dims), &grid, iso, None)).collect();
        let dirty = vec![true; slots.len()];
        Ok(Self { grid, values: samples.values().to_vec(), chunk, chunking, counts, materials: None, slots, dirty })
    }

    /// Gives every sample a material id (x fastest, as the samples), for
    /// [`ChunkedVolume::vertex_materials`]; adding brushes paint theirs.
    pub fn with_materials(mut self, materials: Vec<u8>) -> Result<Self, ExtractError> {
        if materials.len() != self.values.len() {
            return Err(ExtractError::BadInput {
                algorithm: "materials",
                reason: format!("{} material ids given for {} samples", materials.len(), self.values.len()),
            });
        }
        self.materials = Some(materials);
        Ok(self)
    }

    /// The material of every vertex of `mesh` (the welded mesh, world space) from the current
    /// samples ([`crate::materials::vertex_material`]); rock everywhere without materials.
    pub fn vertex_materials(&self, mesh: &crate::mesh::TriMesh, out: &mut Vec<u8>) {
        match &self.materials {
            Some(m) => {
                let iso = self.slots.first().map_or(0.0, |s| s.samples.iso());
                crate::materials::vertex_materials(&self.grid, &self.values, iso, m, &mesh.positions, out);
            }
            None => {
                out.clear();
                out.resize(mesh.positions.len(), crate::materials::ROCK);
            }
        }
    }

    /// Chunks per axis.
    pub fn counts(&self) -> [usize; 3] {
        self.counts
    }

    /// The chunks (their state and mesh).
    pub fn slots(&self) -> &[ChunkSlot] {
        &self.slots
    }

    /// Chunks waiting to be re-meshed.
    pub fn dirty_count(&self) -> usize {
        self.dirty.iter().filter(|&&d| d).count()
    }

    /// Applies `brush` to the samples and marks every chunk holding a changed sample dirty;
    /// returns how many chunks it dirtied.
    pub fn apply(&mut self, brush: &Brush) -> Result<usize, EditError> {
        let valid = brush.radius > 0.0
            && brush.radius.is_finite()
            && brush.falloff >= 0.0
            && brush.falloff.is_finite()
            && brush.centre.is_finite();
        if !valid {
            return Err(EditError::BadBrush { radius: brush.radius, falloff: brush.falloff });
        }
        let bounds = self.grid.bounds();
        let reach = brush.radius + brush.falloff;
        if bounds.distance_squared(brush.centre) > reach * reach {
            return Err(EditError::Outside {
                x: brush.centre.x,
                y: brush.centre.y,
                z: brush.centre.z,
                radius: brush.radius,
                min: bounds.min.to_array(),
                max: bounds.max.to_array(),
            });
        }
        let g = self.grid;
        let iso = self.slots.first().map_or(0.0, |s| s.samples.iso());
        let to_index = |p: f32, o: f32, n: usize, f: fn(f32) -> f32| (f((p - o) / g.spacing).max(0.0) as usize).min(n - 1);
        let lo: [usize; 3] = std::array::from_fn(|a| to_index(brush.centre[a] - reach, g.origin[a], g.dims[a], f32::floor));
        let hi: [usize; 3] = std::array::from_fn(|a| to_index(brush.centre[a] + reach, g.origin[a], g.dims[a], f32::ceil));
        let (mut changed_lo, mut changed_hi) = ([usize::MAX; 3], [0usize; 3]);
        for z in lo[2]..=hi[2] {
            for y in lo[1]..=hi[1] {
                for x in lo[0]..=hi[0] {
                    let i = g.index(x, y, z);
                    let d = g.position(x, y, z).distance(brush.centre) - brush.radius;
                    let old = self.values[i];
                    let new = if brush.add { smooth_min(old, d, brush.falloff) } else { -smooth_min(-old, d, brush.falloff) };
                    if new != old {
                        self.values[i] = new;
                        if let Some(m) = self.materials.as_mut().filter(|_| brush.add && new < old && new < iso) {
                            m[i] = brush.material;
                        }
                        for (a, c) in [x, y, z].into_iter().enumerate() {
                            changed_lo[a] = changed_lo[a].min(c);
                            changed_hi[a] = changed_hi[a].max(c);
                        }
                    }
                }
            }
        }
        if changed_lo[0] == usize::MAX {
            return Ok(0);
        }
        // A chunk reads its samples plus its apron; a sample on a chunk face belongs to both sides.
        let apron = apron_of(self.chunking);
        let first = changed_lo.map(|c| c.saturating_sub(apron + 1) / self.chunk);
        let last: [usize; 3] = std::array::from_fn(|a| ((changed_hi[a] + apron) / self.chunk).min(self.counts[a] - 1));
        let mut dirtied = 0;
        for z in first[2]..=last[2] {
            for y in first[1]..=last[1] {
                for x in first[0]..=last[0] {
                    let k = x + self.counts[0] * (y + self.counts[1] * z);
                    let b = self.slots[k].block;
                    let touches = (0..3).all(|a| changed_lo[a] <= b.hi(a) && changed_hi[a] >= b.lo[a]);
                    if touches && !self.dirty[k] {
                        self.dirty[k] = true;
                        dirtied += 1;
                    }
                }
            }
        }
        Ok(dirtied)
    }

    /// Re-meshes the dirty chunks (in parallel) with `extractor` (which must chunk as the one
    /// the volume was made for) and returns how many.
    pub fn remesh_dirty(&mut self, extractor: &dyn Extractor) -> Result<usize, ExtractError> {
        if extractor.chunking() != self.chunking {
            return Err(ExtractError::BadInput {
                algorithm: extractor.name(),
                reason: format!("chunks as {:?}, but the volume was split for {:?}", extractor.chunking(), self.chunking),
            });
        }
        let (grid, values, chunking) = (self.grid, &self.values, self.chunking);
        let dirty = &self.dirty;
        let count = dirty.iter().filter(|&&d| d).count();
        self.slots
            .par_iter_mut()
            .zip(dirty.par_iter())
            .filter(|(_, &d)| d)
            .try_for_each(|(slot, _)| slot.remesh(extractor, chunking, &grid, values))?;
        self.dirty.iter_mut().for_each(|d| *d = false);
        Ok(count)
    }

    /// The welded mesh of every chunk (normals as the extractor made them: after edits the field
    /// no longer describes the samples).
    pub fn welded(&self, out: &mut Extraction) -> ChunkStats {
        out.clear();
        let mut stats = ChunkStats { chunks: self.counts, apron: apron_of(self.chunking), ..Default::default() };
        weld(self.slots.iter(), out, &mut stats);
        out.finish_counts(0);
        stats
    }

    /// The current samples, as a whole volume (to compare with a whole-volume extraction).
    pub fn samples(&self) -> Result<Samples, ExtractError> {
        Ok(Samples::from_values(
            Lattice::Cubic(self.grid),
            self.values.clone(),
            self.slots.first().map_or(0.0, |s| s.samples.iso()),
        )?)
    }
}

/// Polynomial smooth minimum (Quilez) with blend width `k` (0: plain minimum).
fn smooth_min(a: f32, b: f32, k: f32) -> f32 {
    if k <= 0.0 {
        return a.min(b);
    }
    let h = (0.5 + 0.5 * (b - a) / k).clamp(0.0, 1.0);
    b + (a - b) * h - k * h * (1.0 - h)
}
