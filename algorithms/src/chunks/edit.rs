//! Editing: a [`ChunkedVolume`] keeps one slot per chunk and re-meshes only the chunks a
//! [`Brush`] (a sphere carving or adding, with a falloff and a material) dirtied.

use super::{apron_of, check_chunkable, chunk_counts, chunk_ids, weld, Block, ChunkSlot, ChunkStats};
use crate::extract::{Chunking, ExtractError, Extraction, Extractor};
use crate::lattice::{Grid, Lattice};
use crate::samples::Samples;
use glam::Vec3;
use rayon::prelude::*;

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
    pub(super) grid: Grid,
    pub(super) values: Vec<f32>,
    pub(super) chunk: usize,
    pub(super) chunking: Chunking,
    pub(super) counts: [usize; 3],
    /// One material id per sample, when given.
    pub(super) materials: Option<Vec<u8>>,
    pub(super) slots: Vec<ChunkSlot<'static>>,
    pub(super) dirty: Vec<bool>,
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
        let slots: Vec<ChunkSlot<'static>> =
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
    pub fn slots(&self) -> &[ChunkSlot<'static>] {
        &self.slots
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
        self.check_chunking(extractor)?;
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

    /// Refuses an extractor that chunks otherwise than the one the volume was split for.
    fn check_chunking(&self, extractor: &dyn Extractor) -> Result<(), ExtractError> {
        if extractor.chunking() != self.chunking {
            return Err(ExtractError::BadInput {
                algorithm: extractor.name(),
                reason: format!("chunks as {:?}, but the volume was split for {:?}", extractor.chunking(), self.chunking),
            });
        }
        Ok(())
    }

    /// Re-meshes the dirty chunks one after another on the calling thread (what a game's meshing
    /// worker does, one chunk per task), returning each chunk's time; run it inside a one-thread
    /// pool for the extractor's own parallelism to stay on that thread too.
    pub fn remesh_dirty_each(&mut self, extractor: &dyn Extractor) -> Result<Vec<std::time::Duration>, ExtractError> {
        self.check_chunking(extractor)?;
        let (grid, values, chunking) = (self.grid, &self.values, self.chunking);
        let mut times = Vec::new();
        for (slot, dirty) in self.slots.iter_mut().zip(self.dirty.iter_mut()) {
            if std::mem::take(dirty) {
                let start = std::time::Instant::now();
                slot.remesh(extractor, chunking, &grid, values)?;
                times.push(start.elapsed());
            }
        }
        Ok(times)
    }

    /// The welded mesh of every chunk (normals as the extractor made them: after edits the field
    /// no longer describes the samples).
    pub fn welded(&self, out: &mut Extraction) -> ChunkStats {
        out.clear();
        let mut stats = ChunkStats { chunks: self.counts, apron: apron_of(self.chunking), ..Default::default() };
        weld(self.slots.iter().map(ChunkSlot::piece), out, &mut stats);
        out.finish_counts(0);
        stats
    }

    /// The current samples, as a whole volume (to compare with a whole-volume extraction).
    pub fn samples(&self) -> Result<Samples<'static>, ExtractError> {
        Ok(Samples::from_values(
            Lattice::Cubic(self.grid),
            self.values.clone(),
            self.slots.first().map_or(0.0, |s| s.samples.iso()),
        )?)
    }
}

/// Polynomial smooth minimum (Quilez) with blend width `k` (0: plain minimum).
pub(super) fn smooth_min(a: f32, b: f32, k: f32) -> f32 {
    if k <= 0.0 {
        return a.min(b);
    }
    let h = (0.5 + 0.5 * (b - a) / k).clamp(0.0, 1.0);
    b + (a - b) * h - k * h * (1.0 - h)
}
