//! # Label maps to surfaces
//!
//! A label map (a segmentation: every sample an integer label, `0` the background) meshed into
//! the interfaces between its labels, after S. F. Frisken, "SurfaceNets for Multi-Label
//! Segmentations with Preservation of Sharp Boundaries", JCGT 11(1), 2022.
//!
//! One pass gives one surface of every interface ([`LabelSurface`]): each triangle carries the
//! pair of labels it separates, `[inside, outside]` with `inside > outside`, wound so that its
//! normal points from `inside` into `outside`. Each label's own closed mesh
//! ([`LabelSurface::label_mesh`]) is the triangles that name it, those where it is `outside`
//! reversed: the interface between two labels is the same triangles, reversed, in both meshes,
//! so neighbouring labels meet with no gap and no overlap by construction.
//!
//! The extractors behind [`LabelExtractor`] are registered in [`LABEL_INFOS`], one line each, as
//! the intensity extractors are in `extractors::INFOS`; each states its guarantees as data
//! ([`LabelGuarantees`]), which `tests/tests/labels.rs` checks for every entry.
//!
//! Coordinates: sample `(x, y, z)` is at `(x, y, z)` (voxel index coordinates); the front ends map
//! meshes to the world by the volume's affine.

pub mod blocks;
pub mod cell;
pub mod cleaving;
pub mod marching_tetrahedra;
pub mod surface_nets;
pub mod values;

use std::collections::BTreeMap;

use crate::extract::{DihedralInterval, ExtractError};
use crate::mesh::TriMesh;
use crate::options::{OptionError, Options};
pub use blocks::{LabelBlock, LabelBlockPlan, LabelFragment};
pub use values::{LabelSamples, LabelValues};

/// A label map: `dims` samples, `labels[x + nx * (y + ny * z)]`, `0` the background.
#[derive(Clone, Copy, Debug)]
pub struct LabelMap<'a, T> {
    /// Samples along x, y and z.
    pub dims: [usize; 3],
    /// One label per sample, x fastest.
    pub labels: &'a [T],
}

impl<'a, T: Label> LabelMap<'a, T> {
    /// Checks that `labels` holds one label per sample and that every axis has a sample.
    pub fn new(dims: [usize; 3], labels: &'a [T]) -> Result<Self, ExtractError> {
        let count = dims.iter().try_fold(1usize, |n, &d| n.checked_mul(d));
        if dims.contains(&0) || count != Some(labels.len()) {
            return Err(ExtractError::BadInput {
                algorithm: "labels",
                reason: format!("a {dims:?} label map needs one label per sample, but {} were given", labels.len()),
            });
        }
        Ok(Self { dims, labels })
    }

    /// The distinct labels present, the background included if present, in increasing order.
    pub fn present(&self) -> Vec<u32> {
        let mut seen = std::collections::BTreeSet::new();
        let mut last = None;
        for &l in self.labels {
            if last != Some(l) {
                seen.insert(l.id());
                last = Some(l);
            }
        }
        seen.into_iter().collect()
    }
}

/// A label value: an unsigned integer that names its label.
pub trait Label: Copy + Eq + Send + Sync + Default + 'static {
    /// The label's number.
    fn id(self) -> u32;
}

impl Label for u8 {
    fn id(self) -> u32 {
        u32::from(self)
    }
}
impl Label for u16 {
    fn id(self) -> u32 {
        u32::from(self)
    }
}
impl Label for u32 {
    fn id(self) -> u32 {
        self
    }
}

/// What happens where a label touches the edge of the map.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Border {
    /// Outside the map is background: every label's mesh is closed (the default).
    #[default]
    Closed,
    /// Nothing outside the map: meshes are open where a label reaches the border.
    Open,
}

/// Every interface of a label map in one mesh, each triangle tagged with its label pair.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LabelSurface {
    /// The interfaces; each triangle's normal points from `pairs[t][0]` into `pairs[t][1]`.
    pub mesh: TriMesh,
    /// `[inside, outside]` of each triangle, `inside > outside`.
    pub pairs: Vec<[u32; 2]>,
    /// Surface cells (cells whose corners are not all one label).
    pub active_cells: usize,
    /// Tetrahedra filling the labels, from an extractor that makes them (empty otherwise), on
    /// `mesh.positions`; each is positively oriented.
    pub tetrahedra: Vec<[u32; 4]>,
    /// Each tetrahedron's label.
    pub tetrahedron_labels: Vec<u32>,
}

impl LabelSurface {
    /// Empties the surface, keeping capacity.
    pub fn clear(&mut self) {
        self.mesh.clear();
        self.pairs.clear();
        self.active_cells = 0;
        self.tetrahedra.clear();
        self.tetrahedron_labels.clear();
    }

    /// The labels that have a mesh (every label named by a triangle, the background excluded),
    /// in increasing order.
    pub fn labels(&self) -> Vec<u32> {
        let mut seen = rustc_hash::FxHashSet::default();
        let mut last = [u32::MAX; 2];
        for p in &self.pairs {
            if *p != last {
                seen.extend(p.iter().copied().filter(|&l| l != 0));
                last = *p;
            }
        }
        let mut all: Vec<u32> = seen.into_iter().collect();
        all.sort_unstable();
        all
    }

    /// Label `label`'s mesh: the triangles that name it, wound outward from it (those where it is
    /// `outside` reversed), with only the vertices they use, in their first-use order (normals
    /// from the faces when the surface has normals).
    pub fn label_mesh(&self, label: u32) -> TriMesh {
        let mut map = vec![u32::MAX; self.mesh.positions.len()];
        let mut out = TriMesh::default();
        for (t, pair) in self.triangles_of(label) {
            let tri = if pair[0] == label { t } else { [t[0], t[2], t[1]] };
            out.triangles.push(tri.map(|v| {
                let m = &mut map[v as usize];
                if *m == u32::MAX {
                    *m = out.positions.len() as u32;
                    out.positions.push(self.mesh.positions[v as usize]);
                }
                *m
            }));
        }
        if !self.mesh.normals.is_empty() {
            out.compute_face_weighted_normals();
        }
        out
    }

    /// Every label's mesh ([`Self::label_mesh`]), by label. The labels are dealt to one group
    /// per thread; each group is one pass over the triangles, each triangle going to the meshes
    /// of its labels in the group, each vertex numbered in a mesh where it is first used there.
    pub fn label_meshes(&self) -> BTreeMap<u32, TriMesh> {
        use rayon::prelude::*;
        let labels = self.labels();
        let groups = rayon::current_num_threads().clamp(1, labels.len().max(1));
        let mut meshes: Vec<(usize, TriMesh)> = (0..groups)
            .into_par_iter()
            .flat_map_iter(|g| {
                let mine: Vec<u32> = labels.iter().copied().skip(g).step_by(groups).collect();
                let places: Vec<usize> = (g..labels.len()).step_by(groups).collect();
                places.into_iter().zip(self.meshes_of(&mine))
            })
            .collect();
        meshes.sort_unstable_by_key(|(k, _)| *k);
        labels.into_iter().zip(meshes.into_iter().map(|(_, m)| m)).collect()
    }

    /// The meshes of `mine` (sorted labels, the background not among them), in its order: one
    /// pass over the triangles (and one over their pairs, to allocate each mesh once).
    fn meshes_of(&self, mine: &[u32]) -> Vec<TriMesh> {
        const NONE: u32 = u32::MAX;
        // Each label's place in `mine`, by a table when the labels are small.
        let max = mine.last().copied().unwrap_or(0) as usize;
        let table: Option<Vec<u32>> = (max < 1 << 20).then(|| {
            let mut table = vec![NONE; max + 1];
            for (k, &l) in mine.iter().enumerate() {
                table[l as usize] = k as u32;
            }
            table
        });
        // (The background and the run counter's start are in no slot.)
        let slot = |l: u32| match &table {
            Some(t) => t.get(l as usize).copied().unwrap_or(NONE),
            None => mine.binary_search(&l).map_or(NONE, |k| k as u32),
        };
        // Each mesh's triangles, counted a run of one pair at a time, to allocate once.
        let mut counts = vec![0usize; mine.len()];
        let mut run = ([NONE; 2], 0usize);
        for pair in self.pairs.iter().chain([&[NONE; 2]]) {
            if *pair != run.0 {
                for k in run.0.map(slot) {
                    if k != NONE {
                        counts[k as usize] += run.1;
                    }
                }
                run = (*pair, 0);
            }
            run.1 += 1;
        }
        // A closed mesh has about half as many vertices as triangles.
        let mut out: Vec<TriMesh> = counts
            .iter()
            .map(|&n| TriMesh {
                triangles: Vec::with_capacity(n),
                positions: Vec::with_capacity(n / 2 + 8),
                ..TriMesh::default()
            })
            .collect();
        // Each vertex's number in the first two meshes it is used in, `[slot, number, slot,
        // number]`; in any further one (a junction of three or more of `mine`) by a map.
        let mut numbers = vec![[NONE; 4]; self.mesh.positions.len()];
        let mut more: rustc_hash::FxHashMap<(u32, u32), u32> = rustc_hash::FxHashMap::default();
        let positions = &self.mesh.positions;
        let mut last_pair = [NONE; 2];
        let mut sides = [NONE; 2];
        for (t, pair) in self.mesh.triangles.iter().zip(&self.pairs) {
            if *pair != last_pair {
                last_pair = *pair;
                sides = pair.map(slot);
            }
            for (side, &k) in sides.iter().enumerate() {
                if k == NONE {
                    continue;
                }
                let [a, b, c] = *t;
                let order = if side == 1 { [a, c, b] } else { [a, b, c] };
                let mesh = &mut out[k as usize];
                let tri = order.map(|v| {
                    let n = &mut numbers[v as usize];
                    if n[0] == k {
                        return n[1];
                    }
                    if n[2] == k {
                        return n[3];
                    }
                    let full = n[2] != NONE;
                    if full {
                        if let Some(&m) = more.get(&(v, k)) {
                            return m;
                        }
                    }
                    let m = mesh.positions.len() as u32;
                    mesh.positions.push(positions[v as usize]);
                    if n[0] == NONE {
                        *n = [k, m, NONE, NONE];
                    } else if !full {
                        n[2] = k;
                        n[3] = m;
                    } else {
                        more.insert((v, k), m);
                    }
                    m
                });
                mesh.triangles.push(tri);
            }
        }
        if !self.mesh.normals.is_empty() {
            for mesh in &mut out {
                mesh.compute_face_weighted_normals();
            }
        }
        out
    }

    fn triangles_of(&self, label: u32) -> impl Iterator<Item = ([u32; 3], [u32; 2])> + '_ {
        self.mesh.triangles.iter().zip(&self.pairs).filter(move |(_, p)| p[0] == label || p[1] == label).map(|(t, p)| (*t, *p))
    }
}

/// What a label extractor promises, as data (checked for every entry by `tests/tests/labels.rs`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LabelGuarantees {
    /// Every label's mesh is closed with the default [`Border::Closed`].
    pub closed: bool,
    /// Every label's mesh is edge- and vertex-manifold.
    pub manifold: bool,
    /// Every label's mesh is wound outward (positive signed volume when closed).
    pub outward: bool,
    /// Fills every label with tetrahedra, every dihedral angle in this interval and none
    /// inverted (`None`: surfaces only).
    pub dihedral: Option<DihedralInterval>,
}

/// A registry entry: the name, what it does, its options and its constructor.
#[derive(Clone, Copy, Debug)]
pub struct LabelExtractorInfo {
    /// The name used on the command line and in Python.
    pub name: &'static str,
    /// One line for listings.
    pub description: &'static str,
    /// Option names accepted by `make`.
    pub options: &'static [&'static str],
    /// Builds the extractor from named options.
    pub make: fn(&Options) -> Result<Box<dyn LabelExtractor>, OptionError>,
    /// What it promises.
    pub guarantees: LabelGuarantees,
}

/// A label-map extractor. Label maps come as `u8`, `u16` or `u32` samples; the three methods are
/// the same algorithm.
pub trait LabelExtractor: Send + Sync {
    /// The entry it was built from.
    fn info(&self) -> &'static LabelExtractorInfo;
    /// Meshes a `u8` label map into `out` (cleared first).
    fn extract_u8(&self, map: LabelMap<'_, u8>, out: &mut LabelSurface) -> Result<(), ExtractError>;
    /// Meshes a `u16` label map into `out` (cleared first).
    fn extract_u16(&self, map: LabelMap<'_, u16>, out: &mut LabelSurface) -> Result<(), ExtractError>;
    /// Meshes a `u32` label map into `out` (cleared first).
    fn extract_u32(&self, map: LabelMap<'_, u32>, out: &mut LabelSurface) -> Result<(), ExtractError>;
    /// Cells beyond a block's own that it meshes so that its triangles equal the whole map's
    /// ([`blocks`]): 0 for an extractor whose vertices depend only on their cell.
    fn apron(&self) -> usize;
    /// Its border rule, which decides the map's cells.
    fn border(&self) -> Border;
    /// Meshes one block of a `u8` map into `out` (empty on entry): [`blocks::mesh_label_block`].
    fn block_u8(&self, block: LabelBlock<'_, u8>, out: &mut LabelFragment) -> Result<(), ExtractError>;
    /// Meshes one block of a `u16` map into `out` (empty on entry).
    fn block_u16(&self, block: LabelBlock<'_, u16>, out: &mut LabelFragment) -> Result<(), ExtractError>;
    /// Meshes one block of a `u32` map into `out` (empty on entry).
    fn block_u32(&self, block: LabelBlock<'_, u32>, out: &mut LabelFragment) -> Result<(), ExtractError>;
}

/// Every label extractor, one line each.
pub const LABEL_INFOS: &[LabelExtractorInfo] = &[surface_nets::INFO, marching_tetrahedra::INFO, cleaving::INFO];

/// The label extractor called `name`, built from `options`; `Ok(None)` for an unknown name.
pub fn build(name: &str, options: &Options) -> Result<Option<Box<dyn LabelExtractor>>, OptionError> {
    match LABEL_INFOS.iter().find(|i| i.name == name) {
        Some(info) => (info.make)(options).map(Some),
        None => Ok(None),
    }
}

/// The registered names, for messages.
pub fn names() -> Vec<&'static str> {
    LABEL_INFOS.iter().map(|i| i.name).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_entry_builds_and_names_itself() {
        for info in LABEL_INFOS {
            let e = (info.make)(&Options::new()).unwrap();
            assert_eq!(e.info().name, info.name);
        }
        assert!(build("no-such", &Options::new()).unwrap().is_none());
    }

    #[test]
    fn all_label_meshes_at_once_equal_each_alone() {
        let mut random = crate::random::Random::new(5);
        // Six labels: vertices where three or more of one thread's labels meet (numbered by the
        // map, not the two slots), on one thread and on three (labels dealt to groups).
        let map: Vec<u8> = (0..7 * 6 * 5).map(|_| (random.next_u64() % 7) as u8).collect();
        for threads in [1, 3] {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            for info in LABEL_INFOS {
                let mut out = LabelSurface::default();
                (info.make)(&Options::new()).unwrap().extract_u8(LabelMap::new([7, 6, 5], &map).unwrap(), &mut out).unwrap();
                let all = pool.install(|| out.label_meshes());
                assert_eq!(all.keys().copied().collect::<Vec<_>>(), out.labels());
                for (&l, mesh) in &all {
                    assert_eq!(*mesh, out.label_mesh(l), "{} label {l}, {threads} threads", info.name);
                }
            }
        }
    }

    #[test]
    fn a_map_of_the_wrong_size_is_refused() {
        let err = LabelMap::new([2, 2, 2], &[0u8; 7]).unwrap_err().to_string();
        assert!(err.contains("[2, 2, 2]") && err.contains('7'), "{err}");
    }
}
