//! Liquids and solids in chunks, for an editable terrain: [`ChunkedLayers`] keeps each chunk's
//! two layers (meshed by [`extract_layers`] on the chunk's samples, in the grid's index
//! coordinates), re-meshes only the chunks a brush touched, and welds the chunks' layers by exact
//! position into the whole grid's. The post's rule is local to a lattice edge, so it holds across
//! chunk planes as inside a chunk; the weld needs an extractor whose chunks meet exactly, vertex
//! for vertex, on their shared planes ([`Chunking::CellLocal`]: marching cubes, marching
//! tetrahedra on Kuhn cubes). The last chunk along an axis takes the cells that remain.

use super::{extract_layers, Layers, Phases};
use crate::extract::{Chunking, ExtractError, Extractor};
use crate::lattice::Grid;
use crate::mesh::TriMesh;
use glam::Vec3;
use rayon::prelude::*;

/// Two layers meshed chunk by chunk (module doc).
pub struct ChunkedLayers {
    chunk: usize,
    counts: [usize; 3],
    grid: Grid,
    /// Each chunk's layers, in index coordinates (x fastest).
    slots: Vec<Layers>,
}

fn bad(algorithm: &'static str, reason: String) -> ExtractError {
    ExtractError::BadInput { algorithm, reason }
}

impl ChunkedLayers {
    /// Meshes every chunk of `chunk` cells of `phases` with `extractor` (one whose chunks weld
    /// exactly: [`Chunking::CellLocal`]; others are refused, naming it).
    pub fn new(extractor: &dyn Extractor, phases: &Phases, chunk: usize) -> Result<ChunkedLayers, ExtractError> {
        if extractor.chunking() != Chunking::CellLocal {
            return Err(bad(
                extractor.name(),
                "chunked liquids weld chunks by exact position, which needs an extractor whose chunks meet vertex for vertex \
                 (marching cubes, marching tetrahedra on cubes)"
                    .into(),
            ));
        }
        if chunk < 2 {
            return Err(bad(extractor.name(), format!("a chunk of {chunk} cells is too small (at least 2)")));
        }
        let grid = *phases.grid();
        let counts = grid.dims.map(|d| (d - 1).div_ceil(chunk));
        let mut layers = ChunkedLayers { chunk, counts, grid, slots: Vec::new() };
        let all: Vec<usize> = (0..counts.iter().product()).collect();
        layers.slots = vec![Layers::default(); all.len()];
        layers.remesh(extractor, phases, &all)?;
        Ok(layers)
    }

    /// Chunks per axis.
    pub fn counts(&self) -> [usize; 3] {
        self.counts
    }

    /// Chunk `k`'s first sample and samples per axis.
    fn bounds(&self, k: usize) -> ([usize; 3], [usize; 3]) {
        let c = self.counts;
        let id = [k % c[0], (k / c[0]) % c[1], k / (c[0] * c[1])];
        let lo = id.map(|i| i * self.chunk);
        let dims = [0, 1, 2].map(|a| self.chunk.min(self.grid.dims[a] - 1 - lo[a]) + 1);
        (lo, dims)
    }

    /// The chunks whose samples a brush of `radius` around `centre` (world) may have changed: those
    /// whose sample box meets the brush's ([`Phases::pour`] and its kin edit the samples within
    /// the radius).
    pub fn touching(&self, centre: Vec3, radius: f32) -> Vec<usize> {
        let g = self.grid;
        let lo = ((centre - radius - g.origin) / g.spacing).floor();
        let hi = ((centre + radius - g.origin) / g.spacing).ceil();
        (0..self.slots.len())
            .filter(|&k| {
                let (k0, dims) = self.bounds(k);
                (0..3).all(|a| lo[a] <= (k0[a] + dims[a] - 1) as f32 && hi[a] >= k0[a] as f32)
            })
            .collect()
    }

    /// Re-meshes `chunks` from `phases` (the same grid), in parallel.
    pub fn remesh(&mut self, extractor: &dyn Extractor, phases: &Phases, chunks: &[usize]) -> Result<(), ExtractError> {
        if phases.grid() != &self.grid {
            return Err(bad(extractor.name(), "the phases' grid is not the one the layers were chunked on".into()));
        }
        let fresh: Vec<(usize, Layers)> = chunks
            .par_iter()
            .map(|&k| {
                let (lo, dims) = self.bounds(k);
                extract_layers(extractor, &phases.block(lo, dims)).map(|layers| (k, layers))
            })
            .collect::<Result<_, _>>()?;
        for (k, layers) in fresh {
            self.slots[k] = layers;
        }
        Ok(())
    }

    /// The whole grid's two layers: the chunks' welded by exact position on the chunk planes, in
    /// world coordinates; `contact` sums the chunks'.
    pub fn welded(&self) -> Layers {
        let weld = |layer: fn(&Layers) -> &TriMesh| {
            let mut mesh = TriMesh::default();
            crate::chunks::weld_on_chunk_planes(self.slots.iter().map(layer), self.chunk, &mut mesh);
            for p in &mut mesh.positions {
                *p = self.grid.origin + *p * self.grid.spacing;
            }
            mesh.compute_face_weighted_normals();
            mesh
        };
        let sum = |count: fn(&Layers) -> usize| self.slots.iter().map(count).sum();
        Layers {
            solid: weld(|l| &l.solid),
            liquid: weld(|l| &l.liquid),
            contact: sum(|l| l.contact),
            crossing_cells: sum(|l| l.crossing_cells),
            retiled_cells: sum(|l| l.retiled_cells),
        }
    }
}
