//! A label map to a neuroglancer precomputed multi-resolution mesh source, block by block, no
//! label ever held whole: the steps `isolab.dask.mesh_labels(..., format="neuroglancer")` runs
//! as Dask tasks and `isolab labels --format neuroglancer` runs in one process.
//!
//! 1. **Level 0** ([`level0_box`]): each block of the label map ([`LabelBlockPlan`]) meshes its
//!    cells and a margin of one cell around them
//!    ([`isolab_algorithms::labels::blocks::mesh_label_block_with_margin`]), so that every
//!    triangle crossing the block's faces reaches it, exactly as the whole map has it; each
//!    label's triangles are cut at the block's box ([`cut::clip_to_box`]: the same cut points,
//!    bit for bit, in both blocks beside a face). The block's box is its level-0 fragment box.
//! 2. **Coarser levels** ([`coarser_box`]): a box at level `k` is its eight children at level
//!    `k - 1`, each simplified on its own (meshoptimizer, [`cut::simplify_locked`]) with every
//!    vertex on its box's faces locked. So no triangle crosses the 2x2x2 grid of a box (the
//!    spec's rule), and the vertices on every face of every box are the level-0 ones at every
//!    level: levels meet without cracks, within the quantization. (Meshing mode-pooled
//!    downsampled labels, the other way, cannot share boundary vertices between levels.)
//! 3. Each box's label meshes are quantized into its box and Draco-encoded
//!    ([`isolab_io::neuroglancer`]), and kept with their float meshes in a box file
//!    ([`boxfile`]) under the work folder, for the next level and the segments.
//! 4. **Segments** ([`write_segments`], [`write_shard`]): a segment's fragment data is its
//!    fragments' encoded bytes, level by level in Z-curve order, copied from the box files
//!    (never decoded or gathered as a mesh), and its manifest; unsharded as `<id>` and
//!    `<id>.index`, or into `neuroglancer_uint64_sharded_v1` shards.
//!
//! Coordinates: the stored model is the label map's sample indices (x the fastest axis, as
//! every isolab label mesh), the octree's origin the first cell's low corner; the `info`'s
//! transform takes them to the caller's world (spacing or affine).

pub mod boxfile;
pub mod cut;
pub mod run;

use std::collections::BTreeMap;
use std::io::{self, Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

use glam::Vec3;
use isolab_algorithms::labels::blocks::mesh_label_block_with_margin;
use isolab_algorithms::labels::{LabelBlockPlan, LabelExtractor, LabelFragment, LabelSamples};
use isolab_algorithms::{ExtractError, TriMesh};
use isolab_io::neuroglancer::{self as ng, Manifest, MultilodInfo, ShardingSpec};
use isolab_io::{write_atomic, IoError};
use rayon::prelude::*;

pub use boxfile::{BoxIndex, BoxMeshes};
pub use run::{write_source, NgConfig, NgReport};

/// Cells of margin a level-0 block meshes around its own (a triangle crossing a block face has
/// its anchor within one cell of it).
pub const MARGIN: usize = 1;

/// The octree: level-0 boxes are the plan's blocks.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Layout {
    /// Cells per level-0 box along each axis.
    pub chunk: usize,
    /// The octree's origin (the first cell's low corner), map sample coordinates.
    pub origin: [f64; 3],
    /// Level-0 boxes per axis.
    pub counts: [usize; 3],
    /// Levels of detail (1: level 0 only).
    pub lods: usize,
    /// Bits per quantized coordinate: 10 or 16.
    pub bits: u32,
}

impl Layout {
    /// The layout of `plan`'s blocks with `lods` levels and `bits` quantization bits; an error
    /// names a bad setting.
    pub fn new(plan: &LabelBlockPlan, lods: usize, bits: u32) -> Result<Self, String> {
        if bits != 10 && bits != 16 {
            return Err(format!("vertex quantization bits must be 10 or 16, not {bits}"));
        }
        if !(1..=16).contains(&lods) {
            return Err(format!("lods must be 1 to 16 levels of detail, not {lods}"));
        }
        let (lo, _) = plan.block_box([0; 3]);
        Ok(Self { chunk: plan.chunk, origin: lo, counts: plan.counts, lods, bits })
    }

    /// Boxes per axis at `level`.
    pub fn counts_at(&self, level: usize) -> [usize; 3] {
        self.counts.map(|c| c.div_ceil(1 << level))
    }

    /// Box `position` at `level`: its low corner and size (map sample coordinates).
    pub fn box_at(&self, level: usize, position: [u32; 3]) -> ([f64; 3], [f64; 3]) {
        let size = (self.chunk << level) as f64;
        (std::array::from_fn(|a| self.origin[a] + f64::from(position[a]) * size), [size; 3])
    }

    /// The children (level `level - 1`) of box `position` at `level`, within the map.
    pub fn children(&self, level: usize, position: [u32; 3]) -> Vec<[u32; 3]> {
        let below = self.counts_at(level - 1);
        let mut out = Vec::with_capacity(8);
        for dz in 0..2 {
            for dy in 0..2 {
                for dx in 0..2 {
                    let c = [2 * position[0] + dx, 2 * position[1] + dy, 2 * position[2] + dz];
                    if (0..3).all(|a| (c[a] as usize) < below[a]) {
                        out.push(c);
                    }
                }
            }
        }
        out
    }

    /// The scale of each level (stored-model units): `2^level` samples.
    pub fn lod_scales(&self) -> Vec<f32> {
        (0..self.lods).map(|l| (1u32 << l) as f32).collect()
    }
}

/// Where a level's box file lies in the work folder.
pub fn box_path(work: &Path, level: usize, position: [u32; 3]) -> PathBuf {
    work.join(format!("lod{level}")).join(format!("{}_{}_{}.box", position[0], position[1], position[2]))
}

/// An error of a neuroglancer step, naming what failed.
#[derive(Debug, thiserror::Error)]
pub enum NgError {
    /// The extractor refused the block.
    #[error(transparent)]
    Extract(#[from] ExtractError),
    /// A file could not be read or written.
    #[error(transparent)]
    Io(#[from] IoError),
    /// A file operation on `path` failed.
    #[error("{path}: {source}")]
    File {
        /// The file.
        path: PathBuf,
        /// Why.
        source: io::Error,
    },
    /// Bad settings or inconsistent work files.
    #[error("{0}")]
    Invalid(String),
}

fn file_error(path: &Path) -> impl FnOnce(io::Error) -> NgError + '_ {
    move |source| NgError::File { path: path.to_path_buf(), source }
}

/// Level 0 of block `id`: the block's samples (those `plan.widened(MARGIN).block(id)` reads)
/// meshed with a margin, each label's triangles cut at the block's box, quantized and encoded;
/// written to its box file unless that exists (a rerun resumes). Returns the box's index.
pub fn level0_box(
    extractor: &dyn LabelExtractor,
    plan: &LabelBlockPlan,
    layout: &Layout,
    id: [usize; 3],
    samples: LabelSamples<'_>,
    work: &Path,
) -> Result<BoxIndex, NgError> {
    let position = id.map(|v| v as u32);
    let path = box_path(work, 0, position);
    if let Some(index) = boxfile::read_index_if_complete(&path) {
        return Ok(index);
    }
    let meshes = block_meshes(extractor, plan, id, samples)?;
    encode_and_write(layout, 0, position, meshes, &path)
}

/// Every label's triangles of block `id`, cut at the block's box (the samples are those
/// `plan.widened(MARGIN).block(id)` reads).
pub fn block_meshes(
    extractor: &dyn LabelExtractor,
    plan: &LabelBlockPlan,
    id: [usize; 3],
    samples: LabelSamples<'_>,
) -> Result<BTreeMap<u32, TriMesh>, NgError> {
    let mut fragment = LabelFragment::default();
    mesh_label_block_with_margin(extractor, plan, id, MARGIN, samples, &mut fragment)?;
    let (lo, hi) = plan.block_box(id);
    let (lo, hi) = (lo.map(|v| v as f32), hi.map(|v| v as f32));
    Ok(fragment
        .surface
        .label_meshes()
        .into_iter()
        .map(|(l, m)| (l, cut::clip_to_box(&m, lo, hi)))
        .filter(|(_, m)| !m.triangles.is_empty())
        .collect())
}

/// The legacy single-resolution format, block by block: block `id`'s label meshes (cut at its
/// box, placed in model coordinates by `transform`) as fragment files `<label>:0:<x>_<y>_<z>`
/// in `out`, each written atomically. Returns `(label, triangles)` of the fragments written.
pub fn legacy_block(
    extractor: &dyn LabelExtractor,
    plan: &LabelBlockPlan,
    id: [usize; 3],
    samples: LabelSamples<'_>,
    transform: [f64; 12],
    out: &Path,
) -> Result<Vec<(u32, u32)>, NgError> {
    let meshes = block_meshes(extractor, plan, id, samples)?;
    std::fs::create_dir_all(out).map_err(file_error(out))?;
    // A mirroring transform reverses the winding, as it does for every isolab mesh.
    let t = transform;
    let mirrored =
        t[0] * (t[5] * t[10] - t[6] * t[9]) - t[1] * (t[4] * t[10] - t[6] * t[8]) + t[2] * (t[4] * t[9] - t[5] * t[8]) < 0.0;
    let mut written = Vec::with_capacity(meshes.len());
    for (label, mesh) in meshes {
        let model: Vec<Vec3> = mesh
            .positions
            .iter()
            .map(|p| {
                let p = p.as_dvec3();
                let row = |r: usize| {
                    transform[4 * r] * p.x + transform[4 * r + 1] * p.y + transform[4 * r + 2] * p.z + transform[4 * r + 3]
                };
                glam::DVec3::new(row(0), row(1), row(2)).as_vec3()
            })
            .collect();
        let triangles: Vec<[u32; 3]> =
            if mirrored { mesh.triangles.iter().map(|t| [t[0], t[2], t[1]]).collect() } else { mesh.triangles.clone() };
        let path = out.join(legacy_fragment_name(label, id.map(|v| v as u32)));
        write_atomic(&path, |w| w.write_all(&ng::legacy_fragment(&model, &triangles)))?;
        written.push((label, triangles.len() as u32));
    }
    Ok(written)
}

/// A legacy fragment's file name.
pub fn legacy_fragment_name(label: u32, position: [u32; 3]) -> String {
    format!("{label}:0:{}_{}_{}", position[0], position[1], position[2])
}

/// The legacy format's `<label>:0` files (each naming the label's fragments) and `info`.
pub fn write_legacy_manifests(out: &Path, segments: &BTreeMap<u32, Vec<[u32; 3]>>) -> Result<(), NgError> {
    std::fs::create_dir_all(out).map_err(file_error(out))?;
    for (&label, positions) in segments {
        let names: Vec<String> = positions.iter().map(|&p| legacy_fragment_name(label, p)).collect();
        let json = ng::legacy_manifest(&names);
        write_atomic(&out.join(format!("{label}:0")), |w| serde_json::to_writer(w, &json).map_err(io::Error::other))?;
    }
    let info = ng::legacy_info_json();
    write_atomic(&out.join("info"), |w| serde_json::to_writer_pretty(w, &info).map_err(io::Error::other))?;
    Ok(())
}

/// Box `position` at `level` (1 or more) from its children's box files: each child's label
/// meshes simplified with their box faces locked, joined; written unless its file exists.
pub fn coarser_box(layout: &Layout, level: usize, position: [u32; 3], work: &Path) -> Result<BoxIndex, NgError> {
    let path = box_path(work, level, position);
    if let Some(index) = boxfile::read_index_if_complete(&path) {
        return Ok(index);
    }
    // A child at a time (its meshes read, then dropped: memory holds one child's and the
    // simplified parts), its labels simplified in parallel on the pool the caller installed (one
    // thread unless told: a Dask task's), then joined in the children's order: the same box as
    // serially.
    let mut parts: BTreeMap<u32, Vec<TriMesh>> = BTreeMap::new();
    for child in layout.children(level, position) {
        let meshes = boxfile::read_meshes(&box_path(work, level - 1, child))?;
        let (lo, size) = layout.box_at(level - 1, child);
        let lo32 = lo.map(|v| v as f32);
        let hi32 = std::array::from_fn(|a| (lo[a] + size[a]) as f32);
        let simplified: Vec<(u32, TriMesh)> =
            meshes.par_iter().map(|(label, mesh)| (*label, cut::simplify_locked(mesh, lo32, hi32, level))).collect();
        drop(meshes);
        for (label, mesh) in simplified {
            parts.entry(label).or_default().push(mesh);
        }
    }
    let meshes = parts.into_par_iter().map(|(l, ms)| (l, cut::join_welded(&ms))).collect();
    encode_and_write(layout, level, position, meshes, &path)
}

fn encode_and_write(
    layout: &Layout,
    level: usize,
    position: [u32; 3],
    meshes: BTreeMap<u32, TriMesh>,
    path: &Path,
) -> Result<BoxIndex, NgError> {
    let (lo, size) = layout.box_at(level, position);
    let labels = meshes
        .into_par_iter()
        .map(|(label, mesh)| {
            let q = ng::quantize_fragment(&mesh.positions, lo, size, layout.bits);
            let draco = ng::encode_fragment(&q, &mesh.triangles).map_err(NgError::Invalid)?;
            Ok((label, mesh, draco))
        })
        .collect::<Result<Vec<_>, NgError>>()?;
    let b = BoxMeshes { level: level as u32, position, labels };
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir).map_err(file_error(dir))?;
    }
    write_atomic(path, |w| boxfile::write(w, &b))?;
    Ok(b.index())
}

/// One segment's fragments: `(level, position, encoded bytes)` of every box holding it.
pub type SegmentFragments = Vec<(usize, [u32; 3], u64)>;

/// Every segment's fragments from the boxes' indices (`(level, position, index)`).
pub fn segments_of(boxes: &[(usize, [u32; 3], BoxIndex)]) -> BTreeMap<u32, SegmentFragments> {
    let mut out: BTreeMap<u32, SegmentFragments> = BTreeMap::new();
    for (level, position, index) in boxes {
        for &(label, _, len) in &index.labels {
            out.entry(label).or_default().push((*level, *position, len));
        }
    }
    out
}

/// A segment's manifest from its fragments (sorted into Z-curve order per level).
pub fn manifest(layout: &Layout, fragments: &SegmentFragments) -> Manifest {
    let mut per_level = vec![Vec::new(); layout.lods];
    for &(level, position, len) in fragments {
        per_level[level].push((position, len as u32));
    }
    let mut m = Manifest {
        chunk_shape: [layout.chunk as f32; 3],
        grid_origin: layout.origin.map(|v| v as f32),
        lod_scales: layout.lod_scales(),
        vertex_offsets: vec![[0.0; 3]; layout.lods],
        fragments: per_level,
    };
    m.sort_z_order();
    m
}

/// Copies a segment's fragment bytes, in its manifest's order, from the box files.
fn copy_fragments(work: &Path, label: u32, m: &Manifest, w: &mut impl Write) -> Result<(), NgError> {
    for (level, fragments) in m.fragments.iter().enumerate() {
        for &(position, len) in fragments {
            let path = box_path(work, level, position);
            let mut f = std::fs::File::open(&path).map_err(file_error(&path))?;
            let (offset, stored) = boxfile::draco_range(&mut f, label).map_err(file_error(&path))?;
            if stored != u64::from(len) {
                return Err(NgError::Invalid(format!(
                    "{}: segment {label} has {stored} bytes there, {len} were planned (work files from another run?)",
                    path.display()
                )));
            }
            f.seek(SeekFrom::Start(offset)).map_err(file_error(&path))?;
            io::copy(&mut (&mut f).take(stored), w).map_err(file_error(&path))?;
        }
    }
    Ok(())
}

/// Writes the unsharded files of `segments` (`<id>` with the fragment data, `<id>.index` with
/// the manifest), each atomically; a segment whose two files exist is kept (a rerun resumes).
pub fn write_segments(
    layout: &Layout,
    work: &Path,
    out: &Path,
    segments: &BTreeMap<u32, SegmentFragments>,
) -> Result<(), NgError> {
    for (&label, fragments) in segments {
        let (data, index) = (out.join(label.to_string()), out.join(format!("{label}.index")));
        if data.is_file() && index.is_file() {
            continue;
        }
        let m = manifest(layout, fragments);
        write_atomic(&data, |w| copy_fragments(work, label, &m, w).map_err(io::Error::other))?;
        write_atomic(&index, |w| w.write_all(&m.to_bytes()))?;
    }
    Ok(())
}

/// Writes shard `shard` of `spec` holding `segments` (all of this shard's), atomically.
pub fn write_shard(
    layout: &Layout,
    spec: &ShardingSpec,
    shard: u64,
    work: &Path,
    out: &Path,
    segments: &BTreeMap<u32, SegmentFragments>,
) -> Result<(), NgError> {
    let path = out.join(spec.file_name(shard));
    let manifests: BTreeMap<u64, Manifest> = segments.iter().map(|(&l, f)| (u64::from(l), manifest(layout, f))).collect();
    let entries: Vec<ng::sharded::ShardEntry> = manifests
        .iter()
        .map(|(&id, m)| ng::sharded::ShardEntry { id, prefix_len: m.data_len(), len: m.to_bytes().len() as u64 })
        .collect();
    write_atomic(&path, |w| {
        ng::sharded::write_shard(w, spec, &entries, |e, w| {
            let m = &manifests[&e.id];
            copy_fragments(work, e.id as u32, m, w).map_err(io::Error::other)?;
            w.write_all(&m.to_bytes())
        })
    })?;
    Ok(())
}

/// Writes the source's `info` (and `segment_properties/info` when `names` are given).
pub fn write_info(
    layout: &Layout,
    out: &Path,
    transform: [f64; 12],
    sharding: Option<ShardingSpec>,
    names: &[(u64, String)],
) -> Result<(), NgError> {
    std::fs::create_dir_all(out).map_err(file_error(out))?;
    let props = (!names.is_empty()).then(|| "segment_properties".to_string());
    if let Some(p) = &props {
        let dir = out.join(p);
        std::fs::create_dir_all(&dir).map_err(file_error(&dir))?;
        let json = ng::segment_properties_json(names);
        write_atomic(&dir.join("info"), |w| serde_json::to_writer_pretty(w, &json).map_err(io::Error::other))?;
    }
    let info = MultilodInfo {
        vertex_quantization_bits: layout.bits,
        transform,
        lod_scale_multiplier: 1.0,
        sharding,
        segment_properties: props,
    };
    write_atomic(&out.join("info"), |w| serde_json::to_writer_pretty(w, &info.to_json()).map_err(io::Error::other))?;
    Ok(())
}

/// The shard of each segment, and the segments grouped by shard.
pub fn by_shard(
    spec: &ShardingSpec,
    segments: BTreeMap<u32, SegmentFragments>,
) -> BTreeMap<u64, BTreeMap<u32, SegmentFragments>> {
    let mut out: BTreeMap<u64, BTreeMap<u32, SegmentFragments>> = BTreeMap::new();
    for (label, f) in segments {
        out.entry(spec.shard(u64::from(label))).or_default().insert(label, f);
    }
    out
}

/// The stored-model-to-model transform (3 rows of 4) of an index-to-world affine in isolab's
/// (x, y, z) order.
pub fn transform_of(affine: &glam::DAffine3) -> [f64; 12] {
    let m = affine.matrix3;
    let t = affine.translation;
    [m.x_axis.x, m.y_axis.x, m.z_axis.x, t.x, m.x_axis.y, m.y_axis.y, m.z_axis.y, t.y, m.x_axis.z, m.y_axis.z, m.z_axis.z, t.z]
}

/// Positions of a mesh as `[f32; 3]`.
pub(crate) fn as_arrays(positions: &[Vec3]) -> Vec<[f32; 3]> {
    positions.iter().map(|p| p.to_array()).collect()
}
