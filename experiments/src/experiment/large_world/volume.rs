//! The `large_world` page's volume files: a 1024³ `uint8` NRRD streamed and meshed whole in
//! memory where its voxels lie, the same voxels as a zarr store streamed, and a 513³ one meshed in
//! memory in chunks and streamed, alternating (the module doc of `large_world` says why).

use super::super::context::{Context, ExperimentError};
use crate::report::{markdown_table, Spread};
use serde::{Deserialize, Serialize};
use std::time::Instant;

/// The data file of the streamed volume file.
pub(super) const VOLUME_DATA: &str = "large_world_volume";
/// The streamed volume: 1024³ one-byte voxels (1 GiB), the case a native grid refuses.
const VOLUME_SIDE: usize = 1024;
/// The volume meshed both in memory and streamed, to compare like with like.
const COMPARE_SIDE: usize = 513;
/// Alternating runs of each in the comparison.
const COMPARE_RUNS: usize = 3;
/// Blocks of the streamed runs, and chunks of the in-memory one.
const VOLUME_CHUNK: usize = 64;
/// Voxel size of the volume files.
const VOXEL_SPACING: f32 = 0.5;
/// zstd's level for the zarr store (zarr-python's default, 0, is zstd's default level 3).
const ZARR_ZSTD_LEVEL: i32 = 3;
/// The iso-value of the comparison (the streamed 1024³ run takes Otsu's, as a user's would).
const COMPARE_ISO: f32 = 100.0;

/// One streamed run of a volume file (`isolab extract --stream`), in this process.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub(super) struct StreamedRun {
    pub(super) seconds: f64,
    pub(super) threshold_seconds: f64,
    pub(super) peak_rss_mib: Option<f64>,
    pub(super) peak_reset: bool,
    pub(super) vertices: u64,
    pub(super) triangles: u64,
    pub(super) output_mib: f64,
    pub(super) iso: f32,
    pub(super) iso_from: Option<String>,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
pub(super) struct VolumeData {
    pub(super) side: usize,
    pub(super) file_gib: f64,
    /// What the in-memory run's header check asks for this volume, MiB.
    pub(super) in_memory_need_mib: u64,
    pub(super) available_mib: Option<u64>,
    pub(super) chunk: usize,
    pub(super) algorithm: String,
    pub(super) streamed: StreamedRun,
    /// The same volume as a zarr store (zstd, [`VOLUME_CHUNK`]³ chunks), streamed; its bytes on
    /// disk.
    #[serde(default)]
    pub(super) zarr: Option<(StreamedRun, u64)>,
    pub(super) compare_side: usize,
    pub(super) compare_iso: f32,
    pub(super) memory_seconds: Spread,
    pub(super) memory_peak_mib: Spread,
    pub(super) stream_seconds: Spread,
    pub(super) stream_peak_mib: Spread,
    /// Triangles of the in-memory and streamed meshes of the compared volume.
    pub(super) compare_triangles: [usize; 2],
    /// The big volume meshed whole in memory on its own grid, its voxels read in their stored
    /// type and meshed where they lie (`isolab extract` without `--stream` or `--chunk`).
    #[serde(default)]
    pub(super) in_place: Option<InPlaceRun>,
}

/// One run of a volume file meshed whole in memory, where its voxels lie.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub(super) struct InPlaceRun {
    pub(super) seconds: f64,
    /// Of which reading the file.
    pub(super) reading_seconds: f64,
    pub(super) peak_rss_mib: Option<f64>,
    pub(super) peak_reset: bool,
    /// What the header check asks for now: the file's data (the mesh it checks itself).
    pub(super) need_mib: u64,
    pub(super) vertices: usize,
    pub(super) triangles: usize,
    pub(super) output_mib: f64,
    pub(super) iso: f32,
}

/// The z-slices of a `side`³ rippled ball, brighter than its background, one `side * side`
/// slice of `uint8` at a time (x fastest).
fn for_each_volume_slice(side: usize, mut each: impl FnMut(&[u8]) -> Result<(), ExperimentError>) -> Result<(), ExperimentError> {
    let axis: Vec<f32> = (0..side).map(|i| i as f32 / side as f32 - 0.5).collect();
    let (wx, wy): (Vec<f32>, Vec<f32>) = axis.iter().map(|&c| ((40.0 * c).sin(), (30.0 * c).sin())).unzip();
    let mut slice = vec![0u8; side * side];
    for &z in &axis {
        for (j, &y) in axis.iter().enumerate() {
            for (i, &x) in axis.iter().enumerate() {
                let r = (x * x + y * y + z * z).sqrt();
                slice[j * side + i] = (128.0 + 300.0 * (0.35 - r) + 20.0 * wx[i] * wy[j]).clamp(0.0, 255.0) as u8;
            }
        }
        each(&slice)?;
    }
    Ok(())
}

/// A uint8 NRRD of the rippled ball of `side`³ voxels: its size in bytes.
fn write_volume_file(path: &std::path::Path, side: usize) -> Result<u64, ExperimentError> {
    use std::io::Write;
    let err = |source| isolab_io::IoError::Write { path: path.into(), source };
    let mut f = std::io::BufWriter::new(std::fs::File::create(path).map_err(err)?);
    let (dimension, h) = (3, VOXEL_SPACING);
    write!(
        f,
        "NRRD0004\ntype: uint8\ndimension: {dimension}\nsizes: {side} {side} {side}\nspacings: {h} {h} {h}\nencoding: raw\n\n"
    )
    .map_err(err)?;
    for_each_volume_slice(side, |slice| f.write_all(slice).map_err(|e| err(e).into()))?;
    f.flush().map_err(err)?;
    Ok(std::fs::metadata(path).map_err(err)?.len())
}

/// The same rippled ball as a zarr v3 array (plain: unit spacing) in [`VOLUME_CHUNK`]³ chunks,
/// zstd-compressed (zarr-python's default codec), written a layer of chunks at a time: its size
/// on disk in bytes.
fn write_zarr_store(path: &std::path::Path, side: usize) -> Result<u64, ExperimentError> {
    use zarrs::array::{codec::ZstdCodec, ArrayBuilder, DataType};
    let fail = |e: &dyn std::fmt::Display| ExperimentError::Failed {
        what: format!("writing {}", path.display()),
        reason: e.to_string(),
    };
    let store = std::sync::Arc::new(zarrs::filesystem::FilesystemStore::new(path).map_err(|e| fail(&e))?);
    let (n, c) = (side as u64, VOLUME_CHUNK as u64);
    let array = ArrayBuilder::new(vec![n, n, n], vec![c, c, c], DataType::UInt8, 0u8)
        .bytes_to_bytes_codecs(vec![std::sync::Arc::new(ZstdCodec::new(ZARR_ZSTD_LEVEL, false))])
        .build(store, "/")
        .map_err(|e| fail(&e))?;
    array.store_metadata().map_err(|e| fail(&e))?;
    let mut layer = Vec::with_capacity(side * side * VOLUME_CHUNK);
    let mut z = 0u64;
    for_each_volume_slice(side, |slice| {
        layer.extend_from_slice(slice);
        if layer.len() == side * side * VOLUME_CHUNK || z + (layer.len() / (side * side)) as u64 == n {
            let count = (layer.len() / (side * side)) as u64;
            let subset = zarrs::array_subset::ArraySubset::new_with_ranges(&[z..z + count, 0..n, 0..n]);
            array.store_array_subset_elements::<u8>(&subset, &layer).map_err(|e| fail(&e))?;
            z += count;
            layer.clear();
        }
        Ok(())
    })?;
    Ok(dir_bytes(path))
}

/// Bytes of the files under `path`.
fn dir_bytes(path: &std::path::Path) -> u64 {
    std::fs::read_dir(path)
        .into_iter()
        .flatten()
        .flatten()
        .map(|e| match e.file_type() {
            Ok(t) if t.is_dir() => dir_bytes(&e.path()),
            _ => e.metadata().map_or(0, |m| m.len()),
        })
        .sum()
}

fn volume_config(path: &std::path::Path, iso: Option<f32>) -> isolab_pipeline::RunConfig {
    let mut config = isolab_pipeline::RunConfig::new("marching-cubes", &path.to_string_lossy(), 64);
    config.iso = iso;
    config.chunk = Some(VOLUME_CHUNK);
    config.measure = isolab_pipeline::Measure::Counts;
    config
}

/// `path` streamed into `out`, with the peak resident memory of the run alone where the OS lets
/// it be reset.
fn streamed_run(path: &std::path::Path, out: &std::path::Path, iso: Option<f32>) -> Result<StreamedRun, ExperimentError> {
    let peak_reset = crate::memory::reset_peak_rss();
    let start = Instant::now();
    let report = isolab_pipeline::stream::stream_volume_file(&volume_config(path, iso), out, &mut |_, _| {})
        .map_err(|e| ExperimentError::Failed { what: format!("streaming {}", path.display()), reason: e.to_string() })?;
    Ok(StreamedRun {
        seconds: start.elapsed().as_secs_f64(),
        threshold_seconds: report.times_ms.threshold / 1e3,
        peak_rss_mib: crate::memory::peak_rss_mib(),
        peak_reset,
        vertices: report.vertices,
        triangles: report.triangles,
        output_mib: report.output_bytes as f64 / (1u64 << 20) as f64,
        iso: report.iso,
        iso_from: report.iso_from.map(str::to_owned),
    })
}

/// `path` read whole in its stored type and meshed where it lies by marching cubes on its own grid,
/// written to `out` (what `isolab extract -f FILE -o OUT.ply` does).
fn in_place_run(path: &std::path::Path, out: &std::path::Path, side: usize) -> Result<InPlaceRun, ExperimentError> {
    let peak_reset = crate::memory::reset_peak_rss();
    let start = Instant::now();
    let mut config = isolab_pipeline::RunConfig::new("marching-cubes", &path.to_string_lossy(), 64);
    config.measure = isolab_pipeline::Measure::Counts;
    let outcome = isolab_pipeline::run(&config)
        .map_err(|e| ExperimentError::Failed { what: format!("meshing {} in place", path.display()), reason: e.to_string() })?;
    isolab_io::write_mesh_with(out, &outcome.extraction.surface, isolab_io::MeshExtras::default())?;
    let seconds = start.elapsed().as_secs_f64();
    let surface = &outcome.extraction.surface;
    Ok(InPlaceRun {
        seconds,
        reading_seconds: outcome.report.times_ms.reading / 1e3,
        peak_rss_mib: crate::memory::peak_rss_mib(),
        peak_reset,
        need_mib: (side as u64).pow(3) >> 20,
        vertices: surface.positions.len(),
        triangles: surface.triangles.len(),
        output_mib: std::fs::metadata(out).map(|m| m.len()).unwrap_or(0) as f64 / (1u64 << 20) as f64,
        iso: outcome.report.iso,
    })
}

/// `path` read whole and meshed in chunks in memory, written to `out`: seconds, peak MiB,
/// triangles.
fn in_memory_run(path: &std::path::Path, out: &std::path::Path) -> Result<(f64, Option<f64>, usize), ExperimentError> {
    crate::memory::reset_peak_rss();
    let start = Instant::now();
    let outcome = isolab_pipeline::run(&volume_config(path, Some(COMPARE_ISO)))
        .map_err(|e| ExperimentError::Failed { what: format!("meshing {} in memory", path.display()), reason: e.to_string() })?;
    isolab_io::write_mesh_with(out, &outcome.extraction.surface, isolab_io::MeshExtras::default())?;
    Ok((start.elapsed().as_secs_f64(), crate::memory::peak_rss_mib(), outcome.extraction.surface.triangles.len()))
}

/// A directory in the system's temporary one, removed with what it holds when dropped.
struct ScratchDir(std::path::PathBuf);

impl ScratchDir {
    fn new() -> Result<Self, ExperimentError> {
        let path = std::env::temp_dir().join(format!("isolab-large-volume-{}", std::process::id()));
        std::fs::create_dir_all(&path).map_err(|source| isolab_io::IoError::Write { path: path.clone(), source })?;
        Ok(ScratchDir(path))
    }
}

impl Drop for ScratchDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// The volume-file runs: a 1 GiB volume streamed, and a smaller one meshed both ways, alternating.
pub(super) fn run_volume(ctx: &Context) -> Result<(), ExperimentError> {
    let dir = ScratchDir::new()?;
    let (big, small, store) = (dir.0.join("volume.nrrd"), dir.0.join("compare.nrrd"), dir.0.join("volume.zarr"));
    let out = dir.0.join("mesh.ply");
    // A quick run: a 256³ volume, and a 129³ one compared once.
    let (volume_side, compare_side, compare_runs) =
        (ctx.pick(VOLUME_SIDE, 256), ctx.pick(COMPARE_SIDE, 129), ctx.pick(COMPARE_RUNS, 1));
    let bar = ctx.bar("large_world volume", 3 + 2 * compare_runs as u64);
    let file_bytes = write_volume_file(&big, volume_side)?;
    let streamed = streamed_run(&big, &out, None)?;
    let in_place = in_place_run(&big, &out, volume_side)?;
    std::fs::remove_file(&big).map_err(|source| isolab_io::IoError::Write { path: big.clone(), source })?;
    bar.inc(1);
    let store_bytes = write_zarr_store(&store, volume_side)?;
    let zarr = streamed_run(&store, &out, None)?;
    std::fs::remove_dir_all(&store).map_err(|source| isolab_io::IoError::Write { path: store.clone(), source })?;
    bar.inc(1);
    write_volume_file(&small, compare_side)?;
    bar.inc(1);
    let (mut memory_seconds, mut memory_peak, mut stream_seconds, mut stream_peak) = (vec![], vec![], vec![], vec![]);
    let mut compare_triangles = [0, 0];
    for _ in 0..compare_runs {
        let (seconds, peak, triangles) = in_memory_run(&small, &out)?;
        memory_seconds.push(seconds);
        memory_peak.extend(peak);
        compare_triangles[0] = triangles;
        bar.inc(1);
        let run = streamed_run(&small, &out, Some(COMPARE_ISO))?;
        stream_seconds.push(run.seconds);
        stream_peak.extend(run.peak_rss_mib);
        compare_triangles[1] = run.triangles as usize;
        bar.inc(1);
    }
    bar.finish();
    let data = VolumeData {
        side: volume_side,
        file_gib: file_bytes as f64 / (1u64 << 30) as f64,
        in_memory_need_mib: isolab_pipeline::volume_file_need([volume_side; 3], 1) >> 20,
        available_mib: isolab_pipeline::available_memory().map(|b| b >> 20),
        chunk: VOLUME_CHUNK,
        algorithm: "marching-cubes".into(),
        streamed,
        zarr: Some((zarr, store_bytes)),
        compare_side,
        compare_iso: COMPARE_ISO,
        memory_seconds: Spread::of(memory_seconds),
        memory_peak_mib: Spread::of(memory_peak),
        stream_seconds: Spread::of(stream_seconds),
        stream_peak_mib: Spread::of(stream_peak),
        compare_triangles,
        in_place: Some(in_place),
    };
    ctx.write_data(VOLUME_DATA, &data)
}

/// The section's part on volume files.
pub(super) fn volume_section(ctx: &Context) -> Result<String, ExperimentError> {
    if !ctx.data_path(VOLUME_DATA).exists() {
        return Ok(String::new());
    }
    let d: VolumeData = ctx.read_data(VOLUME_DATA)?;
    let s = &d.streamed;
    let mut md = format!(
        "\n### A volume file larger than memory, streamed block by block (`isolab extract --stream`)\n\n\
         A {side}³ `uint8` NRRD ({gib:.2} GiB, a rippled ball) written to the temporary directory, meshed by {alg} with \
         `--stream`: read z-slice by z-slice, meshed in {c}³-cell blocks one layer at a time, welded by lattice keys and \
         written to a PLY as it goes, in this process (`stream_volume_file`, what the CLI runs). An in-memory run of it \
         would ask for {need} MiB by the header check{avail}; the CLI streams such a volume on its own when the output is \
         a PLY. No iso-value was given: {iso} ({from}), from two extra passes over the file.\n\n",
        side = d.side,
        gib = d.file_gib,
        alg = d.algorithm,
        c = d.chunk,
        need = d.in_memory_need_mib,
        avail = d.available_mib.map_or(String::new(), |a| format!(" ({a} MiB were available when it ran)")),
        iso = s.iso,
        from = s.iso_from.as_deref().unwrap_or("given"),
    );
    let peak = |p: Option<f64>, reset: bool| {
        p.map_or("not reported by the OS".into(), |m| {
            format!("{m:.0} MiB{}", if reset { "" } else { " (the process's peak so far: not resettable here)" })
        })
    };
    let runs: Vec<(&StreamedRun, String)> = std::iter::once((s, format!("{:.2} GiB raw", d.file_gib)))
        .chain(d.zarr.as_ref().map(|(z, bytes)| (z, format!("{:.0} MiB in chunk files", *bytes as f64 / (1u64 << 20) as f64))))
        .collect();
    let row = |name: &str, cell: &dyn Fn(&StreamedRun, &str) -> String| {
        std::iter::once(name.to_owned()).chain(runs.iter().map(|(r, disk)| cell(r, disk))).collect::<Vec<String>>()
    };
    let rows = vec![
        row("on disk", &|_, disk| disk.to_owned()),
        row("wall time", &|r, _| format!("{:.1} s, of which {:.1} s the threshold passes", r.seconds, r.threshold_seconds)),
        row("peak resident memory", &|r, _| peak(r.peak_rss_mib, r.peak_reset)),
        row("output", &|r, _| format!("{} vertices, {} triangles, {:.0} MiB PLY", r.vertices, r.triangles, r.output_mib)),
    ];
    let mut header = vec!["measure".to_owned(), format!("{}³ NRRD streamed", d.side)];
    if let Some((z, _)) = &d.zarr {
        header.push(format!("{}³ zarr streamed", d.side));
        let same = z.vertices == s.vertices && z.triangles == s.triangles && z.iso == s.iso;
        md.push_str(&format!(
            "The same voxels as a zarr v3 store ({c}³ chunks, zstd level {level}, zarr-python's default codec; a plain \
             array, so unit spacing), streamed the same way (`-f volume.zarr --stream`: a layer of storage chunks read \
             and decoded at a time): {verdict}.\n\n",
            c = d.chunk,
            level = ZARR_ZSTD_LEVEL,
            verdict = if same {
                "the same iso-value, vertex and triangle counts as the NRRD".to_owned()
            } else {
                format!("iso-value {}, {} vertices, {} triangles: not the NRRD's", z.iso, z.vertices, z.triangles)
            },
        ));
    }
    let header: Vec<&str> = header.iter().map(String::as_str).collect();
    md.push_str(&markdown_table(&header, &rows));
    if let Some(p) = &d.in_place {
        md.push_str(&format!(
            "\nThe same {side}³ NRRD meshed whole in memory by {alg} on its own grid, as `isolab extract -f volume.nrrd -o \
             mesh.ply` does (no `--stream`, no `--chunk`): its voxels read from the file straight into `uint8` values and \
             meshed where they lie, the header check asking for the file's data ({need} MiB; before, {before} MiB, over what \
             the machine had, so such a run was refused or streamed). No iso-value was given: {iso} (Otsu's). {secs:.1} s, \
             of which {read:.1} s reading the file; peak resident memory {peak}; {v} vertices, {t} triangles, a {out:.0} MiB \
             PLY.\n\n",
            side = d.side,
            alg = d.algorithm,
            need = p.need_mib,
            before = d.in_memory_need_mib,
            iso = p.iso,
            secs = p.seconds,
            read = p.reading_seconds,
            peak = peak(p.peak_rss_mib, p.peak_reset),
            v = p.vertices,
            t = p.triangles,
            out = p.output_mib,
        ));
    }
    let spread = |x: &Spread, unit: &str, digits: usize| {
        format!("{:.*} {unit} ({:.*}-{:.*})", digits, x.median, digits, x.min, digits, x.max)
    };
    md.push_str(&format!(
        "\nLike with like, in one process, one-shot, alternating ({n} runs each, median and range): a {side}³ volume \
         of the same kind at iso-value {iso}, read whole and meshed in {c}³ chunks in memory (`--chunk`), then \
         streamed (`--stream`); both write a PLY. Peak memory is each run's own where the OS lets it be reset.\n\n",
        n = d.memory_seconds.runs.len(),
        side = d.compare_side,
        iso = d.compare_iso,
        c = d.chunk,
    ));
    let rows = vec![
        vec![
            "in memory (`--chunk`)".into(),
            spread(&d.memory_seconds, "s", 2),
            spread(&d.memory_peak_mib, "MiB", 0),
            d.compare_triangles[0].to_string(),
        ],
        vec![
            "streamed (`--stream`)".into(),
            spread(&d.stream_seconds, "s", 2),
            spread(&d.stream_peak_mib, "MiB", 0),
            d.compare_triangles[1].to_string(),
        ],
    ];
    md.push_str(&markdown_table(&["run", "wall time", "peak resident memory", "triangles"], &rows));
    md.push_str(&format!(
        "\nStreamed against in memory: {:.2}x the time, {:.2}x the peak memory (medians).\n",
        d.stream_seconds.median / d.memory_seconds.median,
        d.stream_peak_mib.median / d.memory_peak_mib.median
    ));
    Ok(md)
}
