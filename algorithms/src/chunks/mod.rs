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
//!
//! Files: this one (chunk counts, slots, [`extract_chunked`]); [`lod`] (chunks at several
//! levels of detail, stitched); `weld` (joining chunk meshes);
//! `stream` ([`stream_chunked`], [`MeshSink`]); `edit` ([`ChunkedVolume`], [`Brush`]); `blocks`
//! (one block meshed on its own into a [`Fragment`], and [`weld_fragments`]: a distributed driver's
//! two steps); `sparse` ([`extract_sparse`]: a field evaluated in batches only in the blocks a
//! Lipschitz bound or a coarse sign change keeps, meshed and welded as blocks).

use crate::extract::{Chunking, ExtractError, Extraction, Extractor};
use crate::field::Field;
use crate::geometry::Aabb;
use crate::lattice::{Grid, Lattice};
use crate::samples::Samples;
use glam::Vec3;
use rayon::prelude::*;
use std::sync::Arc;
use std::time::Instant;

mod blocks;
mod edit;
pub mod lod;
mod shared_samples;
mod sparse;
mod stream;
mod weld;

pub use blocks::{mesh_block, mesh_block_view, mesh_block_view_of, weld_fragments, BlockBounds, BlockPlan, Fragment};
pub use edit::{Brush, ChunkedVolume, EditError};
pub use sparse::{
    extract_sparse, BatchEval, EvalError, FieldEval, GridFieldEval, Pruning, SparseError, SparseGrid, SparseOptions, SparseStats,
};
pub use stream::{stream_blocks, stream_chunked, MeshSink, SliceReader, StreamError, StreamStats};
pub use weld::weld_on_chunk_planes;
use weld::{position_key, weld, WeldPiece, Welder};

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
    check_chunk_and_size(grid.dims, chunk, algorithm)?;
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

/// A chunk of at least 2 cells, and a grid whose index coordinates are exact in `f32`.
fn check_chunk_and_size(dims: [usize; 3], chunk: usize, algorithm: &'static str) -> Result<(), ExtractError> {
    if chunk < 2 {
        return Err(ExtractError::BadInput { algorithm, reason: format!("chunk size {chunk} is below 2 cells") });
    }
    if dims.iter().any(|&d| d > 1 << 24) {
        return Err(ExtractError::BadInput {
            algorithm,
            reason: format!(
                "grid {}x{}x{} is above 2^24 samples on an axis (index coordinates would not be exact)",
                dims[0], dims[1], dims[2]
            ),
        });
    }
    Ok(())
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

/// One chunk's persistent buffers: its samples in index coordinates (its own, or for `'a` a
/// caller's block read where it lies) and its mesh in world space.
pub struct ChunkSlot<'a> {
    /// Chunk index per axis.
    pub id: [usize; 3],
    block: Block,
    samples: Samples<'a>,
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

impl ChunkSlot<'static> {
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
}

impl<'a> ChunkSlot<'a> {
    /// A slot for chunk `id` reading its block's samples where they lie (index coordinates),
    /// with `field` (the world's field and grid) when there is one; `None` when the view is not
    /// the block's size.
    fn with_view(
        id: [usize; 3],
        block: Block,
        values: crate::samples::AnyView<'a>,
        iso: f32,
        field: Option<(&Arc<dyn Field>, &Grid)>,
    ) -> Option<Self> {
        let local = Grid {
            origin: Vec3::new(block.lo[0] as f32, block.lo[1] as f32, block.lo[2] as f32),
            spacing: 1.0,
            dims: block.dims,
        };
        let mut samples = Samples::borrowed(local, values, iso).ok()?;
        if let Some((f, world)) = field {
            samples = samples.with_field(Arc::new(IndexSpaceField::new(f.clone(), world)));
        }
        Some(Self {
            id,
            block,
            samples,
            mesh: Extraction::default(),
            keys: Vec::new(),
            remap: Vec::new(),
            state: ChunkState::Empty,
        })
    }

    /// What the weld reads of this slot.
    fn piece(&self) -> WeldPiece<'_> {
        WeldPiece {
            state: self.state,
            surface: &self.mesh.surface,
            keys: &self.keys,
            active_cells: self.mesh.stats.active_cells,
            discarded_triangles: self.mesh.stats.discarded_triangles,
        }
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
        let local = self.samples.values_mut();
        field.sample_block(grid, b.lo, b.dims, local);
        let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
        for (i, &v) in local.iter().enumerate() {
            if !v.is_finite() {
                let [nx, ny, _] = b.dims;
                let (x, y, z) = (i % nx, i / nx % ny, i / (nx * ny));
                return Err(crate::samples::SampleError::NonFinite {
                    field: field.name().to_owned(),
                    position: grid.position(b.lo[0] + x, b.lo[1] + y, b.lo[2] + z).to_array(),
                    index: grid.index(b.lo[0] + x, b.lo[1] + y, b.lo[2] + z),
                    value: v,
                }
                .into());
            }
            lo = lo.min(v);
            hi = hi.max(v);
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
    let mut slots: Vec<ChunkSlot<'static>> = chunk_ids(counts)
        .map(|id| ChunkSlot::new(id, Block::new(id, chunk, apron, grid.dims), &grid, samples.iso(), samples.field()))
        .collect();
    slots.par_iter_mut().try_for_each(|slot| slot.remesh(extractor, chunking, &grid, samples.values()))?;
    out.clear();
    out.stats.times.sampling = samples.sampling_time();
    let mut stats = ChunkStats { chunks: counts, apron, ..Default::default() };
    weld(slots.iter().map(ChunkSlot::piece), out, &mut stats);
    field_normals(samples.field(), out);
    out.stats.times.geometry = start.elapsed();
    out.finish_counts(0);
    Ok(stats)
}

/// Chunk indices, x fastest.
fn chunk_ids(counts: [usize; 3]) -> impl Iterator<Item = [usize; 3]> {
    (0..counts[2]).flat_map(move |z| (0..counts[1]).flat_map(move |y| (0..counts[0]).map(move |x| [x, y, z])))
}
