//! A label map meshed block by block, for a driver that runs the blocks elsewhere (a Dask task,
//! another process, a later run), as [`crate::chunks::mesh_block`] does for volumes:
//! [`LabelBlockPlan`] splits the map's cells into blocks of `chunk`³ and says which samples each
//! block reads (its cells, the extractor's apron of cells around them, and one sample more),
//! [`mesh_label_block`] meshes one block into a [`LabelFragment`] (the triangles of the lattice
//! edges it owns, and an integer weld key for every vertex), and [`weld_label_fragments`] joins
//! fragments by those keys, never by positions, into the surface the extractor makes of the
//! whole map in one pass: the same vertices at the same positions, the same triangles with the
//! same label pairs (tested for every entry in `tests/tests/labels.rs`).
//!
//! Cells are named by their padded coordinate `c` (corners at map samples `c - 1` and `c`, the
//! samples outside the map background), as the extractors sweep them: with [`Border::Closed`]
//! `0 ..= n` along an axis of `n` samples, with [`Border::Open`] `1 .. n`. A lattice edge belongs
//! to the block holding the cell whose first corner is the edge's first end, so every interface
//! triangle is made by exactly one block.
//!
//! An extractor whose vertices depend on more than their cell says so by its apron
//! ([`super::LabelExtractor::apron`]): multi-label surface nets with smoothing reads its
//! `iterations + 1` cells beyond the block, so that the vertices of the block's triangles have
//! moved exactly as in the whole map (a vertex's neighbours are one cell away, and each pass
//! reaches one cell further).

use std::collections::BTreeMap;
use std::ops::Range;

use super::{Border, Label, LabelExtractor, LabelSamples, LabelSurface};
use crate::extract::ExtractError;

/// The samples one block reads and the cells it owns.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LabelBlockBounds {
    /// The block's index per axis.
    pub id: [usize; 3],
    /// First map sample read per axis.
    pub lo: [usize; 3],
    /// Samples read per axis.
    pub dims: [usize; 3],
    /// The cells it owns (padded cell coordinates, see the module doc).
    pub cells: [Range<usize>; 3],
    /// The map samples it counts (per axis: `chunk` from `id * chunk`, the last block to the
    /// end), so that the blocks' counts add up to the map's.
    pub owned: [Range<usize>; 3],
}

impl LabelBlockBounds {
    /// Every label's count among the samples the block owns (background included); `samples`
    /// are the block's (`dims` of them from `lo`).
    pub fn owned_counts(&self, samples: LabelSamples<'_>) -> BTreeMap<u32, usize> {
        fn count<T: Label>(b: &LabelBlockBounds, v: &[T]) -> BTreeMap<u32, usize> {
            let mut out = BTreeMap::new();
            let [wx, wy, _] = b.dims;
            for z in b.owned[2].clone() {
                for y in b.owned[1].clone() {
                    let row = wx * (y - b.lo[1] + wy * (z - b.lo[2]));
                    let xs = b.owned[0].start - b.lo[0]..b.owned[0].end - b.lo[0];
                    for (l, n) in super::LabelSamples::counts_of(&v[row + xs.start..row + xs.end]) {
                        *out.entry(l).or_insert(0) += n;
                    }
                }
            }
            out
        }
        match samples {
            LabelSamples::U8(v) => count(self, v),
            LabelSamples::U16(v) => count(self, v),
            LabelSamples::U32(v) => count(self, v),
        }
    }
}

/// How a label map of `dims` samples splits into blocks of `chunk`³ cells for one extractor.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LabelBlockPlan {
    /// Samples of the whole map per axis.
    pub dims: [usize; 3],
    /// Cells per block along each axis (the last block on an axis takes what remains).
    pub chunk: usize,
    /// Blocks per axis.
    pub counts: [usize; 3],
    /// Cells each block meshes beyond its own on every side (their triangles are discarded).
    pub apron: usize,
    /// The border rule, which decides the cells.
    pub border: Border,
}

/// The most samples per axis a plan takes (weld keys hold a cell index in 64 bits).
pub const MAX_SAMPLES_PER_AXIS: usize = 1 << 20;

impl LabelBlockPlan {
    /// The plan for `extractor` on a map of `dims` samples; an error for a chunk under 2 cells,
    /// an axis without a sample or over [`MAX_SAMPLES_PER_AXIS`].
    pub fn new(extractor: &dyn LabelExtractor, dims: [usize; 3], chunk: usize) -> Result<Self, ExtractError> {
        let algorithm = extractor.info().name;
        if chunk < 2 {
            return Err(ExtractError::BadInput {
                algorithm,
                reason: format!("a block of {chunk} cells is too small: give 2 or more"),
            });
        }
        if dims.iter().any(|&d| d == 0 || d > MAX_SAMPLES_PER_AXIS) {
            return Err(ExtractError::BadInput {
                algorithm,
                reason: format!("a {dims:?} label map: every axis needs 1 to {MAX_SAMPLES_PER_AXIS} samples"),
            });
        }
        let border = extractor.border();
        let plan = Self { dims, chunk, counts: [0; 3], apron: extractor.apron(), border };
        let counts = std::array::from_fn(|a| plan.cell_range(a).len().div_ceil(chunk).max(1));
        Ok(Self { counts, ..plan })
    }

    /// The cells the whole map has along axis `a` (padded coordinates).
    pub fn cell_range(&self, a: usize) -> Range<usize> {
        match self.border {
            Border::Closed => 0..self.dims[a] + 1,
            Border::Open => 1..self.dims[a].max(1),
        }
    }

    /// Every block, in the order [`weld_label_fragments`] takes them (x fastest).
    pub fn blocks(&self) -> impl Iterator<Item = LabelBlockBounds> + '_ {
        let [cx, cy, cz] = self.counts;
        (0..cz).flat_map(move |z| (0..cy).flat_map(move |y| (0..cx).map(move |x| self.bounds([x, y, z]))))
    }

    /// This plan with `margin` more cells read around every block: the samples
    /// [`mesh_label_block_with_margin`] needs (its blocks own the same cells).
    pub fn widened(&self, margin: usize) -> Self {
        Self { apron: self.apron + margin, ..*self }
    }

    /// The box of block `id` in map sample coordinates: the cells it owns span from the first
    /// one's low corner to the last one's high corner (padded cell `c` spans map samples
    /// `c - 1 ..= c`, so a closed border's first box starts at -1).
    pub fn block_box(&self, id: [usize; 3]) -> ([f64; 3], [f64; 3]) {
        let b = self.bounds(id);
        (std::array::from_fn(|a| b.cells[a].start as f64 - 1.0), std::array::from_fn(|a| b.cells[a].end as f64 - 1.0))
    }

    /// Number of blocks.
    pub fn len(&self) -> usize {
        self.counts.iter().product()
    }

    /// Whether the plan has no blocks (never: every plan has one at least).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The block `id`, or `None` outside the plan.
    pub fn block(&self, id: [usize; 3]) -> Option<LabelBlockBounds> {
        (0..3).all(|a| id[a] < self.counts[a]).then(|| self.bounds(id))
    }

    fn bounds(&self, id: [usize; 3]) -> LabelBlockBounds {
        let cells: [Range<usize>; 3] = std::array::from_fn(|a| {
            let all = self.cell_range(a);
            let start = (all.start + id[a] * self.chunk).min(all.end);
            start..(start + self.chunk).min(all.end)
        });
        // Cells computed: the owned ones and the apron, within the map's; samples: their
        // corners and one sample beyond (the ring rule looks at the next cell), within the map.
        let (mut lo, mut dims) = ([0; 3], [0; 3]);
        for a in 0..3 {
            let all = self.cell_range(a);
            let first = cells[a].start.saturating_sub(self.apron).max(all.start);
            let end = (cells[a].end + self.apron).min(all.end);
            // Padded samples first - 1 ..= end + 1 are map samples first - 2 ..= end.
            let from = first.saturating_sub(2);
            let to = end.min(self.dims[a] - 1);
            lo[a] = from.min(to);
            dims[a] = to + 1 - lo[a];
        }
        let owned = std::array::from_fn(|a| {
            let start = (id[a] * self.chunk).min(self.dims[a]);
            start..if id[a] + 1 == self.counts[a] { self.dims[a] } else { ((id[a] + 1) * self.chunk).min(self.dims[a]) }
        });
        LabelBlockBounds { id, lo, dims, cells, owned }
    }
}

/// What one block hands back: its triangles and a weld key per vertex.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LabelFragment {
    /// The block's index per axis.
    pub id: [usize; 3],
    /// The triangles of the edges it owns (positions in the map's sample coordinates), their
    /// label pairs, and its surface cells.
    pub surface: LabelSurface,
    /// Per vertex: its key, the same in every block that makes the vertex.
    pub keys: Vec<u128>,
}

/// A block as an extractor sees it: the samples read, where they sit in the map, and the cells
/// whose triangles it keeps.
#[derive(Clone, Debug)]
pub struct LabelBlock<'a, T> {
    /// The samples read, x fastest: `window_dims` of them from map sample `window_lo`.
    pub samples: &'a [T],
    /// First map sample read per axis.
    pub window_lo: [usize; 3],
    /// Samples read per axis.
    pub window_dims: [usize; 3],
    /// The whole map's samples per axis.
    pub map_dims: [usize; 3],
    /// The cells owned (padded coordinates).
    pub cells: [Range<usize>; 3],
    /// Cells meshed beyond the owned ones, on every side.
    pub apron: usize,
}

impl<T: Label> LabelBlock<'_, T> {
    /// The label at padded sample `p` (background outside the map); `p` must be in the window
    /// or outside the map.
    pub fn padded(&self, p: [usize; 3]) -> T {
        let mut i = 0;
        let mut stride = 1;
        for (a, &at) in p.iter().enumerate() {
            if at == 0 || at > self.map_dims[a] {
                return T::default();
            }
            i += (at - 1 - self.window_lo[a]) * stride;
            stride *= self.window_dims[a];
        }
        self.samples[i]
    }

    /// The cells meshed along axis `a`: the owned ones and the apron, within `all`.
    pub fn computed(&self, a: usize, all: &Range<usize>) -> Range<usize> {
        self.cells[a].start.saturating_sub(self.apron).max(all.start)..(self.cells[a].end + self.apron).min(all.end)
    }
}

/// Meshes block `id` of `plan` from its samples (`plan.block(id)`'s `dims`, x fastest). A block
/// outside the plan or a sample count that does not match is an error naming it.
pub fn mesh_label_block(
    extractor: &dyn LabelExtractor,
    plan: &LabelBlockPlan,
    id: [usize; 3],
    samples: LabelSamples<'_>,
    out: &mut LabelFragment,
) -> Result<(), ExtractError> {
    mesh_label_block_with_margin(extractor, plan, id, 0, samples, out)
}

/// Meshes block `id` of `plan` and the `margin` cells around it on every side (within the map):
/// the triangles of every lattice edge those cells own, each exactly as the whole map has it. A
/// driver that cuts the surface at the block's faces (`isolab labels --format neuroglancer`)
/// takes a margin of one cell, so that every triangle crossing a face reaches both blocks. The
/// samples are those `plan.widened(margin).block(id)` reads.
pub fn mesh_label_block_with_margin(
    extractor: &dyn LabelExtractor,
    plan: &LabelBlockPlan,
    id: [usize; 3],
    margin: usize,
    samples: LabelSamples<'_>,
    out: &mut LabelFragment,
) -> Result<(), ExtractError> {
    let algorithm = extractor.info().name;
    let wide = plan.widened(margin);
    let bounds = wide.block(id).ok_or_else(|| ExtractError::BadInput {
        algorithm,
        reason: format!("block {id:?} is outside the plan's {:?} blocks", plan.counts),
    })?;
    let want: usize = bounds.dims.iter().product();
    if samples.len() != want {
        return Err(ExtractError::BadInput {
            algorithm,
            reason: format!("block {id:?} reads {:?} samples ({want}), but {} were given", bounds.dims, samples.len()),
        });
    }
    if extractor.apron() != plan.apron || extractor.border() != plan.border {
        return Err(ExtractError::BadInput { algorithm, reason: "the plan was made for other options".into() });
    }
    let cells: [Range<usize>; 3] = std::array::from_fn(|a| {
        let all = plan.cell_range(a);
        bounds.cells[a].start.saturating_sub(margin).max(all.start)..(bounds.cells[a].end + margin).min(all.end)
    });
    out.id = id;
    out.keys.clear();
    out.surface.clear();
    macro_rules! run {
        ($v:expr, $method:ident) => {{
            let block = LabelBlock {
                samples: $v,
                window_lo: bounds.lo,
                window_dims: bounds.dims,
                map_dims: plan.dims,
                cells: cells.clone(),
                apron: plan.apron,
            };
            extractor.$method(block, out)
        }};
    }
    match samples {
        LabelSamples::U8(v) => run!(v, block_u8),
        LabelSamples::U16(v) => run!(v, block_u16),
        LabelSamples::U32(v) => run!(v, block_u32),
    }
}

/// Joins fragments by their vertex keys into one surface: vertices in increasing key order (for
/// multi-label surface nets, the order of the whole map's sweep), triangles block by block in the
/// order given. The surface cells add up.
pub fn weld_label_fragments<'a>(fragments: impl IntoIterator<Item = &'a LabelFragment>) -> LabelSurface {
    let fragments: Vec<&LabelFragment> = fragments.into_iter().collect();
    let mut all: Vec<(u128, u32, u32)> = Vec::new();
    for (f, fragment) in fragments.iter().enumerate() {
        all.extend(fragment.keys.iter().enumerate().map(|(v, &k)| (k, f as u32, v as u32)));
    }
    all.sort_unstable();
    let mut remap: Vec<Vec<u32>> = fragments.iter().map(|f| vec![0; f.keys.len()]).collect();
    let mut out = LabelSurface::default();
    let mut last = None;
    for &(key, f, v) in &all {
        if last != Some(key) {
            out.mesh.positions.push(fragments[f as usize].surface.mesh.positions[v as usize]);
            last = Some(key);
        }
        remap[f as usize][v as usize] = (out.mesh.positions.len() - 1) as u32;
    }
    for (fragment, remap) in fragments.iter().zip(&remap) {
        out.mesh.triangles.extend(fragment.surface.mesh.triangles.iter().map(|t| t.map(|v| remap[v as usize])));
        out.pairs.extend_from_slice(&fragment.surface.pairs);
        out.active_cells += fragment.surface.active_cells;
        out.tetrahedra.extend(fragment.surface.tetrahedra.iter().map(|t| t.map(|v| remap[v as usize])));
        out.tetrahedron_labels.extend_from_slice(&fragment.surface.tetrahedron_labels);
    }
    out
}

/// A weld key from a padded cell (or sample) index in a grid of `sizes` and a small tag.
pub(crate) fn key(at: [usize; 3], sizes: [usize; 3], tag: u64) -> u128 {
    let linear = at[0] as u128 + sizes[0] as u128 * (at[1] as u128 + sizes[1] as u128 * at[2] as u128);
    linear << 64 | u128::from(tag)
}
