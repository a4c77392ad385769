//! Welding chunk meshes into one: cell-local chunks by exact position (their shared boundary
//! samples give bit-identical vertices), apron chunks by lattice key (the sample that owns each
//! vertex and its ordinal there).

use super::{ChunkState, ChunkStats};
use crate::extract::Extraction;
use crate::mesh::TriMesh;
use glam::Vec3;
use rustc_hash::FxHashMap;

/// A weld key from exact position bits.
pub(super) fn position_key(p: Vec3) -> u128 {
    let [x, y, z] = p.to_array().map(|c| u128::from(c.to_bits()));
    x | y << 32 | z << 64
}

/// What the weld needs of one chunk: a persistent slot's mesh or a block's [`Fragment`].
pub(super) struct WeldPiece<'a> {
    pub state: ChunkState,
    pub surface: &'a TriMesh,
    pub keys: &'a [Option<u128>],
    pub active_cells: usize,
    pub discarded_triangles: usize,
}

/// Welds the chunks' meshes into `out` (cleared first) and fills the counts of `stats`.
pub(super) fn weld<'a>(pieces: impl Iterator<Item = WeldPiece<'a>>, out: &mut Extraction, stats: &mut ChunkStats) {
    let mut welder = Welder::new(out);
    for piece in pieces {
        welder.add(piece, out, stats);
    }
    welder.finish(out);
}

/// A weld that takes its pieces one at a time, in order. Keys live in two generations: those
/// added since the last [`Welder::retire`] and those of the generation before; a retire drops
/// the older. A driver that adds its blocks a layer at a time and retires at each new layer
/// holds the keys of two layers only, which is enough when no vertex is made by blocks two
/// layers apart (blocks thicker than twice their apron). Without retires, every key is kept.
pub(super) struct Welder {
    index: FxHashMap<u128, u32>,
    older: FxHashMap<u128, u32>,
    with_normals: bool,
    /// A piece's vertices to the welded mesh's, reused from piece to piece.
    remap: Vec<u32>,
}

impl Welder {
    /// A weld into `out`, which it clears.
    pub(super) fn new(out: &mut Extraction) -> Welder {
        out.surface.clear();
        Welder { index: FxHashMap::default(), older: FxHashMap::default(), with_normals: true, remap: Vec::new() }
    }

    /// Drops the keys of the generation before the current one.
    pub(super) fn retire(&mut self) {
        self.older = std::mem::take(&mut self.index);
    }

    /// Adds one piece: its vertices whose keys were seen become those vertices.
    pub(super) fn add(&mut self, piece: WeldPiece<'_>, out: &mut Extraction, stats: &mut ChunkStats) {
        match piece.state {
            ChunkState::Empty => stats.empty += 1,
            ChunkState::Full => stats.full += 1,
            ChunkState::Meshed => {
                stats.meshed += 1;
                let e = piece.surface;
                out.stats.discarded_triangles += piece.discarded_triangles;
                out.stats.active_cells += piece.active_cells;
                self.with_normals &= e.normals.len() == e.positions.len();
                let mut remap = std::mem::take(&mut self.remap);
                remap.clear();
                remap.extend(e.positions.iter().enumerate().map(|(i, &p)| {
                    let next = out.surface.positions.len() as u32;
                    let id = match piece.keys[i] {
                        Some(key) => match self.older.get(&key) {
                            Some(&id) => id,
                            None => *self.index.entry(key).or_insert(next),
                        },
                        None => next,
                    };
                    if id == next {
                        out.surface.positions.push(p);
                        if let Some(&n) = e.normals.get(i) {
                            out.surface.normals.push(n);
                        }
                    } else {
                        stats.welded += 1;
                    }
                    id
                }));
                out.surface.triangles.extend(e.triangles.iter().map(|t| t.map(|v| remap[v as usize])));
                self.remap = remap;
            }
        }
    }

    /// Ends the weld: normals are kept only if every piece had them.
    pub(super) fn finish(self, out: &mut Extraction) {
        if !self.with_normals || out.surface.normals.len() != out.surface.positions.len() {
            out.surface.normals.clear();
        }
    }
}

/// Joins meshes made in a grid's index coordinates, chunk by chunk (`chunk` cells), into `out`
/// (cleared first): a vertex on a chunk plane is one with every vertex at the same position bits
/// (only there can two chunks make the same vertex); others stay their own. Returns each part's
/// triangle count, in order. Used by the levels of detail and the chunked liquids, whose parts
/// keep no weld keys.
pub fn weld_on_chunk_planes<'a>(parts: impl IntoIterator<Item = &'a TriMesh>, chunk: usize, out: &mut TriMesh) -> Vec<usize> {
    out.clear();
    let mut index: FxHashMap<u128, u32> = FxHashMap::default();
    let mut triangles = Vec::new();
    for part in parts {
        let remap: Vec<u32> = part
            .positions
            .iter()
            .map(|&p| {
                let next = out.positions.len() as u32;
                let on_plane = (0..3).any(|a| p[a].fract() == 0.0 && (p[a] as usize) % chunk == 0);
                let id = if on_plane { *index.entry(position_key(p)).or_insert(next) } else { next };
                if id == next {
                    out.positions.push(p);
                }
                id
            })
            .collect();
        out.triangles.extend(part.triangles.iter().map(|t| t.map(|v| remap[v as usize])));
        triangles.push(part.triangles.len());
    }
    triangles
}
