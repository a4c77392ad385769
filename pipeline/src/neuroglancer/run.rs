//! The whole neuroglancer run in one process (`isolab labels --format neuroglancer`): the same
//! steps the Dask driver runs as tasks, here on the rayon pool, level by level.

use std::collections::BTreeMap;
use std::path::Path;

use isolab_algorithms::labels::{LabelBlockPlan, LabelExtractor, LabelSamples, LabelValues};
use isolab_io::neuroglancer::ShardingSpec;
use rayon::prelude::*;
use serde::Serialize;

use super::{
    by_shard, coarser_box, level0_box, segments_of, write_info, write_segments, write_shard, BoxIndex, Layout, NgError, MARGIN,
};

/// What to write.
#[derive(Clone, Debug)]
pub struct NgConfig {
    /// Levels of detail.
    pub lods: usize,
    /// Bits per quantized coordinate (10 or 16).
    pub bits: u32,
    /// Shards instead of a file pair per segment.
    pub sharded: bool,
    /// Stored model (sample indices) to model (world) transform, 3 rows of 4.
    pub transform: [f64; 12],
    /// Segment names for `segment_properties` (none: not written).
    pub names: Vec<(u64, String)>,
    /// Keep the work folder (the box files) after the run.
    pub keep_work: bool,
    /// The legacy single-resolution format instead (level 0 only, float fragments).
    pub legacy: bool,
}

/// What was written.
#[derive(Clone, Debug, Default, Serialize, PartialEq)]
pub struct NgReport {
    /// Segments written.
    pub segments: usize,
    /// Per level: boxes holding a fragment.
    pub boxes: Vec<usize>,
    /// Per level: fragments (a segment in a box).
    pub fragments: Vec<usize>,
    /// Per level: triangles.
    pub triangles: Vec<u64>,
    /// Per level: encoded bytes.
    pub bytes: Vec<u64>,
    /// Shard files written (0 unsharded).
    pub shards: usize,
    /// Seconds per step: each level's boxes, then the segments (files or shards).
    pub seconds: Vec<f64>,
}

/// The report of every level's box indices.
pub fn report(levels: &[Vec<([u32; 3], BoxIndex)>], segments: usize, shards: usize) -> NgReport {
    let mut r = NgReport { segments, shards, ..NgReport::default() };
    for boxes in levels {
        r.boxes.push(boxes.iter().filter(|(_, i)| !i.labels.is_empty()).count());
        r.fragments.push(boxes.iter().map(|(_, i)| i.labels.len()).sum());
        r.triangles.push(boxes.iter().flat_map(|(_, i)| &i.labels).map(|&(_, t, _)| u64::from(t)).sum());
        r.bytes.push(boxes.iter().flat_map(|(_, i)| &i.labels).map(|&(_, _, b)| b).sum());
    }
    r
}

/// The samples of a window (`lo`, `dims`) of a whole map of `map_dims`, x fastest.
pub fn window(values: LabelSamples<'_>, map_dims: [usize; 3], lo: [usize; 3], dims: [usize; 3]) -> LabelValues {
    fn cut<T: Copy>(v: &[T], map_dims: [usize; 3], lo: [usize; 3], dims: [usize; 3]) -> Vec<T> {
        let mut out = Vec::with_capacity(dims.iter().product());
        for z in lo[2]..lo[2] + dims[2] {
            for y in lo[1]..lo[1] + dims[1] {
                let row = map_dims[0] * (y + map_dims[1] * z);
                out.extend_from_slice(&v[row + lo[0]..row + lo[0] + dims[0]]);
            }
        }
        out
    }
    match values {
        LabelSamples::U8(v) => LabelValues::U8(cut(v, map_dims, lo, dims)),
        LabelSamples::U16(v) => LabelValues::U16(cut(v, map_dims, lo, dims)),
        LabelSamples::U32(v) => LabelValues::U32(cut(v, map_dims, lo, dims)),
    }
}

/// Block `id`'s window of the whole map (what `plan.widened(MARGIN).block(id)` reads), labels
/// outside `keep` as background when given.
fn block_window(
    plan: &LabelBlockPlan,
    values: LabelSamples<'_>,
    keep: Option<&[u32]>,
    id: [usize; 3],
) -> Result<LabelValues, NgError> {
    let b = plan.widened(MARGIN).block(id).ok_or_else(|| NgError::Invalid(format!("block {id:?} is outside the plan")))?;
    let samples = window(values, plan.dims, b.lo, b.dims);
    Ok(match keep {
        Some(keep) => samples.as_slice().keep_only(keep),
        None => samples,
    })
}

/// Writes a multi-resolution source of the map `values` (`plan.dims` samples, labels outside
/// `keep` as background when given) into `out`.
pub fn write_source(
    extractor: &dyn LabelExtractor,
    plan: &LabelBlockPlan,
    values: LabelSamples<'_>,
    keep: Option<&[u32]>,
    out: &Path,
    config: &NgConfig,
) -> Result<NgReport, NgError> {
    if config.legacy {
        return write_legacy(extractor, plan, values, keep, out, config);
    }
    let layout = Layout::new(plan, config.lods, config.bits).map_err(NgError::Invalid)?;
    let work = out.join(".isolab-work");
    let mut seconds = Vec::new();
    let mut clock = std::time::Instant::now();
    let mut lap = |seconds: &mut Vec<f64>| {
        seconds.push(clock.elapsed().as_secs_f64());
        clock = std::time::Instant::now();
    };
    let blocks: Vec<[usize; 3]> = plan.blocks().map(|b| b.id).collect();
    let level0: Vec<([u32; 3], BoxIndex)> = blocks
        .par_iter()
        .map(|&id| {
            let samples = block_window(plan, values, keep, id)?;
            let index = level0_box(extractor, plan, &layout, id, samples.as_slice(), &work)?;
            Ok((id.map(|v| v as u32), index))
        })
        .collect::<Result<_, NgError>>()?;
    lap(&mut seconds);
    let mut levels = vec![level0];
    for level in 1..layout.lods {
        let [cx, cy, cz] = layout.counts_at(level);
        let positions: Vec<[u32; 3]> =
            (0..cz).flat_map(|z| (0..cy).flat_map(move |y| (0..cx).map(move |x| [x as u32, y as u32, z as u32]))).collect();
        let boxes = positions
            .par_iter()
            .map(|&p| coarser_box(&layout, level, p, &work).map(|i| (p, i)))
            .collect::<Result<Vec<_>, NgError>>()?;
        levels.push(boxes);
        lap(&mut seconds);
    }
    let flat: Vec<(usize, [u32; 3], BoxIndex)> =
        levels.iter().enumerate().flat_map(|(l, boxes)| boxes.iter().map(move |(p, i)| (l, *p, i.clone()))).collect();
    let segments = segments_of(&flat);
    let count = segments.len();
    let sharding = config.sharded.then(|| ShardingSpec::for_segments(count));
    std::fs::create_dir_all(out).map_err(super::file_error(out))?;
    let shards = match &sharding {
        Some(spec) => {
            let groups: Vec<(u64, BTreeMap<u32, super::SegmentFragments>)> = by_shard(spec, segments).into_iter().collect();
            groups.par_iter().try_for_each(|(shard, segs)| write_shard(&layout, spec, *shard, &work, out, segs))?;
            groups.len()
        }
        None => {
            let all: Vec<(u32, super::SegmentFragments)> = segments.into_iter().collect();
            all.par_chunks(64).try_for_each(|part| {
                let part: BTreeMap<u32, super::SegmentFragments> = part.iter().cloned().collect();
                write_segments(&layout, &work, out, &part)
            })?;
            0
        }
    };
    write_info(&layout, out, config.transform, sharding, &config.names)?;
    lap(&mut seconds);
    if !config.keep_work {
        std::fs::remove_dir_all(&work).map_err(super::file_error(&work))?;
    }
    Ok(NgReport { seconds, ..report(&levels, count, shards) })
}

/// A block's position and its legacy fragments' `(label, triangles)`.
type BlockFragments = ([u32; 3], Vec<(u32, u32)>);

/// The legacy format: each block's fragments, then each label's `<label>:0` and the `info`.
fn write_legacy(
    extractor: &dyn LabelExtractor,
    plan: &LabelBlockPlan,
    values: LabelSamples<'_>,
    keep: Option<&[u32]>,
    out: &Path,
    config: &NgConfig,
) -> Result<NgReport, NgError> {
    let started = std::time::Instant::now();
    let blocks: Vec<[usize; 3]> = plan.blocks().map(|b| b.id).collect();
    let written: Vec<BlockFragments> = blocks
        .par_iter()
        .map(|&id| {
            let samples = block_window(plan, values, keep, id)?;
            let rows = super::legacy_block(extractor, plan, id, samples.as_slice(), config.transform, out)?;
            Ok((id.map(|v| v as u32), rows))
        })
        .collect::<Result<_, NgError>>()?;
    let mut segments: BTreeMap<u32, Vec<[u32; 3]>> = BTreeMap::new();
    let mut triangles = 0u64;
    for (p, rows) in &written {
        for &(label, t) in rows {
            segments.entry(label).or_default().push(*p);
            triangles += u64::from(t);
        }
    }
    super::write_legacy_manifests(out, &segments)?;
    Ok(NgReport {
        segments: segments.len(),
        boxes: vec![written.iter().filter(|(_, r)| !r.is_empty()).count()],
        fragments: vec![segments.values().map(Vec::len).sum()],
        triangles: vec![triangles],
        bytes: Vec::new(),
        shards: 0,
        seconds: vec![started.elapsed().as_secs_f64()],
    })
}
