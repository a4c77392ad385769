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
//!
//! [`ChunkedVolume`] keeps the samples and one persistent slot per chunk (its local samples and
//! mesh buffers), so editing with a [`Brush`] re-meshes only the chunks whose samples changed, and
//! re-meshing a chunk reuses its buffers.

use crate::extract::{ExtractError, Extraction, Extractor};
use crate::field::Field;
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

/// Whether `extractor` can mesh chunks, and the grid of `samples` (cubic only).
fn check_chunkable(extractor: &dyn Extractor, samples: &Samples) -> Result<Grid, ExtractError> {
    let algorithm = extractor.name();
    if !extractor.supports_chunks() {
        return Err(ExtractError::BadInput {
            algorithm,
            reason: "chunked extraction is not supported yet (marching-cubes and marching-cubes-decider support it)".into(),
        });
    }
    match *samples.lattice() {
        Lattice::Cubic(grid) => Ok(grid),
        Lattice::Bcc(_) => Err(ExtractError::UnsupportedLattice { algorithm, lattice: "bcc", supported: "cubic (for --chunk)" }),
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

/// One chunk's persistent buffers: its samples in local coordinates and its mesh in world space.
pub struct ChunkSlot {
    /// Chunk index per axis.
    pub id: [usize; 3],
    samples: Samples,
    /// The chunk's mesh (world space), valid when `state` is `Meshed`.
    pub mesh: Extraction,
    /// Which mesh vertices lie on the chunk's faces (the only ones a neighbour can share).
    on_face: Vec<bool>,
    /// What the last meshing found.
    pub state: ChunkState,
}

impl ChunkSlot {
    fn new(id: [usize; 3], chunk: usize, iso: f32) -> Self {
        let n = chunk + 1;
        let local = Grid { origin: Vec3::ZERO, spacing: 1.0, dims: [n, n, n] };
        let samples = Samples::from_values(Lattice::Cubic(local), vec![0.0; n * n * n], iso).expect("zeros are finite");
        Self { id, samples, mesh: Extraction::default(), on_face: Vec::new(), state: ChunkState::Empty }
    }

    /// Copies the chunk's samples out of the world's and meshes them (or records it empty/full).
    fn remesh(&mut self, extractor: &dyn Extractor, grid: &Grid, values: &[f32], chunk: usize) -> Result<(), ExtractError> {
        let n = chunk + 1;
        let k0 = self.id.map(|c| c * chunk);
        let iso = self.samples.iso();
        let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
        let local = self.samples.values_mut();
        for z in 0..n {
            for y in 0..n {
                let row = grid.index(k0[0], k0[1] + y, k0[2] + z);
                let src = &values[row..row + n];
                for &v in src {
                    lo = lo.min(v);
                    hi = hi.max(v);
                }
                local[(z * n + y) * n..(z * n + y + 1) * n].copy_from_slice(src);
            }
        }
        self.mesh.clear();
        self.on_face.clear();
        if lo >= iso {
            self.state = ChunkState::Empty;
            return Ok(());
        }
        if hi < iso {
            self.state = ChunkState::Full;
            return Ok(());
        }
        self.state = ChunkState::Meshed;
        extractor.extract(&self.samples, &mut self.mesh)?;
        let last = chunk as f32;
        self.on_face.extend(self.mesh.surface.positions.iter().map(|p| p.to_array().iter().any(|&c| c == 0.0 || c == last)));
        let offset = Vec3::new(k0[0] as f32, k0[1] as f32, k0[2] as f32);
        for p in &mut self.mesh.surface.positions {
            *p = grid.origin + (*p + offset) * grid.spacing;
        }
        Ok(())
    }
}

/// Welds the chunks' meshes into `out` (cleared first) and fills the counts of `stats`.
fn weld<'a>(slots: impl Iterator<Item = &'a ChunkSlot>, out: &mut Extraction, stats: &mut ChunkStats) {
    out.surface.clear();
    let mut index: HashMap<[u32; 3], u32> = HashMap::new();
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
                        let id =
                            if slot.on_face[i] { *index.entry(p.to_array().map(f32::to_bits)).or_insert(next) } else { next };
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

/// Meshes `samples` in chunks of `chunk`³ cells with `extractor` and welds the result into `out`.
pub fn extract_chunked(
    extractor: &dyn Extractor,
    samples: &Samples,
    chunk: usize,
    out: &mut Extraction,
) -> Result<ChunkStats, ExtractError> {
    let grid = check_chunkable(extractor, samples)?;
    let counts = chunk_counts(&grid, chunk, extractor.name())?;
    let start = Instant::now();
    let mut slots: Vec<ChunkSlot> = chunk_ids(counts).map(|id| ChunkSlot::new(id, chunk, samples.iso())).collect();
    slots.par_iter_mut().try_for_each(|slot| slot.remesh(extractor, &grid, samples.values(), chunk))?;
    out.clear();
    out.stats.times.sampling = samples.sampling_time();
    let mut stats = ChunkStats { chunks: counts, ..Default::default() };
    weld(slots.iter(), out, &mut stats);
    field_normals(samples.field(), out);
    out.stats.times.geometry = start.elapsed();
    out.finish_counts(0);
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
    counts: [usize; 3],
    slots: Vec<ChunkSlot>,
    dirty: Vec<bool>,
}

impl ChunkedVolume {
    /// Takes `samples` (cubic) apart into chunks of `chunk`³ cells for `extractor`; every chunk
    /// starts dirty.
    pub fn new(extractor: &dyn Extractor, samples: Samples, chunk: usize) -> Result<Self, ExtractError> {
        let grid = check_chunkable(extractor, &samples)?;
        let counts = chunk_counts(&grid, chunk, extractor.name())?;
        let iso = samples.iso();
        let slots: Vec<ChunkSlot> = chunk_ids(counts).map(|id| ChunkSlot::new(id, chunk, iso)).collect();
        let dirty = vec![true; slots.len()];
        Ok(Self { grid, values: samples.values().to_vec(), chunk, counts, slots, dirty })
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
        // A sample on a chunk face belongs to the chunks on both sides.
        let first = changed_lo.map(|c| c.saturating_sub(1) / self.chunk);
        let last: [usize; 3] = std::array::from_fn(|a| (changed_hi[a] / self.chunk).min(self.counts[a] - 1));
        let mut dirtied = 0;
        for z in first[2]..=last[2] {
            for y in first[1]..=last[1] {
                for x in first[0]..=last[0] {
                    let k = x + self.counts[0] * (y + self.counts[1] * z);
                    let k0 = [x, y, z].map(|c| c * self.chunk);
                    let touches = (0..3).all(|a| changed_lo[a] <= k0[a] + self.chunk && changed_hi[a] >= k0[a]);
                    if touches && !self.dirty[k] {
                        self.dirty[k] = true;
                        dirtied += 1;
                    }
                }
            }
        }
        Ok(dirtied)
    }

    /// Re-meshes the dirty chunks (in parallel) and returns how many.
    pub fn remesh_dirty(&mut self, extractor: &dyn Extractor) -> Result<usize, ExtractError> {
        let (grid, values, chunk) = (self.grid, &self.values, self.chunk);
        let dirty = &self.dirty;
        let count = dirty.iter().filter(|&&d| d).count();
        self.slots
            .par_iter_mut()
            .zip(dirty.par_iter())
            .filter(|(_, &d)| d)
            .try_for_each(|(slot, _)| slot.remesh(extractor, &grid, values, chunk))?;
        self.dirty.iter_mut().for_each(|d| *d = false);
        Ok(count)
    }

    /// The welded mesh of every chunk (normals as the extractor made them: after edits the field
    /// no longer describes the samples).
    pub fn welded(&self, out: &mut Extraction) -> ChunkStats {
        out.clear();
        let mut stats = ChunkStats { chunks: self.counts, ..Default::default() };
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
