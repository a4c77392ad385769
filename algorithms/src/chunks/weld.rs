//! Welding chunk meshes into one: cell-local chunks by exact position (their shared boundary
//! samples give bit-identical vertices), apron chunks by lattice key (the sample that owns each
//! vertex and its ordinal there).

use super::*;

/// A weld key from exact position bits.
pub(super) fn position_key(p: Vec3) -> u128 {
    let [x, y, z] = p.to_array().map(|c| u128::from(c.to_bits()));
    x | y << 32 | z << 64
}

/// Welds the chunks' meshes into `out` (cleared first) and fills the counts of `stats`.
pub(super) fn weld<'a>(slots: impl Iterator<Item = &'a ChunkSlot>, out: &mut Extraction, stats: &mut ChunkStats) {
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
