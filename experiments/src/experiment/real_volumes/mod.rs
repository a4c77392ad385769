//! `real_volumes`: a real MRI, the MNI ICBM152 2009a T1 template that `nilearn` ships (197 x 233
//! x 189 voxels, uint8, 1 mm), read from its `.nii.gz` and meshed on its own voxel grid at two
//! iso-values by every surface extractor, beside VTK's `vtkFlyingEdges3D` and scikit-image's
//! marching cubes (Lewiner) on the very array nibabel loads. Every mesh is measured by isolab's
//! metrics in world (RAS) coordinates: triangles, time, quality, topology, distance to the
//! trilinear level set; pictures of ours.
//!
//! The iso-values are computed, not chosen by hand: Otsu's threshold of all voxels, then Otsu's
//! threshold of the voxels above the first. The template nilearn ships is brain-extracted (most
//! voxels are 0; the experiment counts them), so there is no skin to mesh: the first level is
//! the brain's outer surface, the second the white matter.
//!
//! Timing protocol: one-shot for everyone. Extraction only: a fresh extractor and output for
//! each of ours; a fresh filter for VTK, a fresh call for scikit-image (their input arrays
//! prepared beforehand, as our samples are). End to end, in one process each: ours reads the
//! file, takes its voxels as samples, meshes with marching cubes and maps to world coordinates;
//! the peer's is nibabel loading the file, the array into a `vtkImageData` and flying edges.
//! Runs alternate, medians with the min-max spread. One thread for VTK (its default backend);
//! ours on rayon's pool (both cores of this machine).
//!
//! The page opens with the commands that mesh one's own scan (its iso-values the ones computed
//! here). Every mesh's islands (connected components) are counted with what the
//! `keep-components` post-process keeps of them (`islands.rs`). A second volume of another kind,
//! nibabel's oblique, anisotropic, int16 fMRI series, is meshed through the pipeline's own run
//! by every surface extractor, its world placement checked against nibabel's affine
//! (`second.rs`).
//!
//! The volumes themselves are not committed (the Python peers' environment installs them);
//! without them the section says so.

mod data;
mod page;

use super::context::{Context, Experiment, ExperimentError};
use crate::figures::plot::caption;
use crate::peers::python::{PythonPeer, PythonServer};
use crate::peers::{Job, Peer, Protocol};
use crate::report::Spread;
use data::EndToEnd;
pub(crate) use data::{Data, Level, Row};
use glam::Vec3;
use islands::islands;
use isolab_algorithms::fields::{volume::otsu_threshold, Complement, VolumeField};
use isolab_algorithms::{extractors, Extraction, Field, TriMesh};
use isolab_io::volume::{read_volume, Inside, VolumeOptions};
use isolab_metrics::MeshMetrics;
use isolab_pipeline::{volume_samples, LatticeKind};
use isolab_render::{grid, render, save_png, RenderOptions, Shading};
use std::path::Path;
use std::sync::Arc;
use std::time::Instant;

mod islands;

mod lewiner;

mod second;

/// The experiment.
pub struct RealVolumes;

const NAME: &str = "real_volumes";

/// The iso-values: Otsu of all voxels, then Otsu of the voxels above the first.
fn levels(values: &[f32]) -> Vec<Level> {
    let outer = otsu_threshold(values).unwrap_or(0.5);
    let above: Vec<f32> = values.iter().copied().filter(|&v| v > outer).collect();
    let inner = otsu_threshold(&above).unwrap_or(outer);
    vec![
        Level { name: "brain".into(), iso: outer, how: "Otsu's threshold of all voxels: background against brain".into() },
        Level {
            name: "white matter".into(),
            iso: inner,
            how: "Otsu's threshold of the voxels above the first level: the bright tissue class of a T1".into(),
        },
    ]
}

/// A mesh's row; `voxel_volume` in cubic world units.
#[allow(clippy::too_many_arguments)]
fn row(
    implementation: &str,
    ours: bool,
    level: &Level,
    times: [Vec<f64>; 2],
    mesh: &TriMesh,
    field: &dyn Field,
    iso: f32,
    voxel_volume: f64,
) -> Row {
    let m = MeshMetrics::measure(mesh, Some((field, iso)));
    let t = &m.topology;
    let d = m.surface_distance.unwrap_or_default();
    Row {
        implementation: implementation.into(),
        ours,
        level: level.name.clone(),
        time_1: Spread::of(times[0].clone()),
        time_2: (!times[1].is_empty()).then(|| Spread::of(times[1].clone())),
        vertices: m.vertices,
        triangles: m.triangles,
        min_angle_deg: m.quality.min_angle_deg,
        aspect_mean: m.quality.aspect_ratio.mean,
        aspect_max: m.quality.aspect_ratio.max,
        components: t.components,
        genus: t.genus,
        closed: t.closed,
        manifold: t.edge_manifold && t.vertex_manifold,
        outward: t.outward,
        oriented: t.oriented,
        self_intersections: m.intersecting_pairs(),
        distance_mean: d.mean,
        distance_max: d.max,
        islands: Some(islands(mesh, voxel_volume)),
    }
}

/// A head in RAS (z up) turned so the renderer's y is up and its camera sees the face.
fn for_display(mesh: &TriMesh) -> TriMesh {
    let positions = mesh.positions.iter().map(|p| Vec3::new(p.x, p.z, -p.y)).collect();
    TriMesh { positions, normals: Vec::new(), triangles: mesh.triangles.clone() }
}

fn picture_options(size: u32) -> RenderOptions {
    RenderOptions { width: size, height: size, shading: Shading::Smooth, view: Vec3::new(-0.7, 0.25, -1.0), ..Default::default() }
}

impl Experiment for RealVolumes {
    fn name(&self) -> &'static str {
        NAME
    }

    fn question(&self) -> &'static str {
        "Do the extractors mesh a real MRI cleanly, and how fast against VTK and scikit-image?"
    }

    fn peers(&self) -> &'static [&'static str] {
        &["VTK", "scikit-image", "PyMCubes", "libigl", "pymeshlab", "nibabel", "nilearn"]
    }

    fn run(&self, ctx: &Context) -> Result<(), ExperimentError> {
        let root = crate::provenance::root();
        let mut data = Data { repeats: ctx.repeats, threads: 2, ..Default::default() };
        let pools: Vec<rayon::ThreadPool> = [1, 2]
            .iter()
            .map(|&n| rayon::ThreadPoolBuilder::new().num_threads(n).build())
            .collect::<Result<_, _>>()
            .map_err(|e| ExperimentError::ThreadPool(e.to_string()))?;
        let (server, hello) = match PythonServer::start(&root) {
            Ok(p) => p,
            Err(e) => {
                data.skipped.push(format!("the MNI template and the Python peers: {e}"));
                return ctx.write_data(NAME, &data);
            }
        };
        for (k, v) in hello["available"].as_object().into_iter().flatten() {
            data.versions.insert(k.clone(), v.as_str().unwrap_or("installed").to_owned());
        }
        let Some(path) = hello["mni_t1"].as_str().map(str::to_owned) else {
            data.skipped.push(format!("the MNI T1 template: nilearn is not installed ({})", hello["errors"]));
            return ctx.write_data(NAME, &data);
        };
        let path = Path::new(&path);
        let file = read_volume(path, VolumeOptions::default())?;
        data.source = format!(
            "{} (nilearn {})",
            path.file_name().unwrap_or_default().to_string_lossy(),
            data.versions.get("nilearn").cloned().unwrap_or_default()
        );
        data.shape = file.volume.dims;
        data.data_type = file.data_type.into();
        data.spacing = file.volume.spacing();
        data.file_bytes = std::fs::metadata(path).map(|m| m.len()).unwrap_or(0);
        let values = file.volume.values_f32();
        data.levels = levels(&values);
        data.zero_fraction = values.iter().filter(|&&v| v == 0.0).count() as f64 / values.len() as f64;
        let field: Arc<dyn Field> = Arc::new(Complement(Arc::new(VolumeField::new(file.volume.clone()))));
        let voxel_volume = data.spacing.iter().product::<f64>();
        let surface: Vec<_> =
            extractors::INFOS.iter().filter(|i| extractors::by_name(i.name).is_some_and(|e| !e.produces_volume())).collect();
        data.settings = super::context::settings_of(
            surface.iter().filter_map(|i| extractors::by_name(i.name)).collect::<Vec<_>>().iter().map(|e| &**e),
        );
        let peers = [("vtk-flying-edges", "vtkFlyingEdges3D"), ("skimage-lewiner", "scikit-image (Lewiner)")];
        let mut peer_runners: Vec<PythonPeer> = peers.iter().map(|(name, _)| PythonPeer::new(&server, name)).collect();
        let mut end_to_end_peer = PythonPeer::new(&server, "vtk-flying-edges");
        let bar = ctx.bar(NAME, (data.levels.len() * (surface.len() + peers.len() + 1)) as u64);
        let tmp = tempfile_dir()?;
        let dir = ctx.figure_dir(NAME)?;
        let mut pictures = Vec::new();
        for level in data.levels.clone() {
            let (samples, to_world) = volume_samples(&file, LatticeKind::Cubic, Inside::Above, level.iso)?;
            let internal = -level.iso;
            // Ours and the peers, one run each per round, alternating; on one thread, then two.
            let slots = surface.len() + peers.len();
            let mut times: Vec<[Vec<f64>; 2]> = vec![[Vec::new(), Vec::new()]; slots];
            let mut meshes: Vec<Option<TriMesh>> = vec![None; slots];
            let mut errors: Vec<Option<String>> = vec![None; peers.len()];
            for (t, pool) in pools.iter().enumerate() {
                for round in 0..ctx.repeats {
                    let last = t == 1 && round + 1 == ctx.repeats;
                    for (k, info) in surface.iter().enumerate() {
                        let extractor = extractors::by_name(info.name)
                            .ok_or_else(|| ExperimentError::Missing(format!("extractor {}", info.name)))?;
                        let mut out = Extraction::default();
                        pool.install(|| extractor.extract(&samples, &mut out))?;
                        times[k][t].push(out.stats.times.extraction().as_secs_f64() * 1e3);
                        if last {
                            if let Some(a) = &to_world {
                                out.surface.transform(a);
                            }
                            meshes[k] = Some(out.surface);
                        }
                    }
                    for (p, (peer, _)) in peers.iter().enumerate() {
                        if t == 1 && *peer == "skimage-lewiner" && !last {
                            continue; // single-threaded: timed once per round on the one-thread pass
                        }
                        let out = tmp.join(format!("{peer}.ply"));
                        let job = Job::Scan {
                            file: path,
                            level: level.iso,
                            threads: t + 1,
                            out: last.then_some(out.as_path()),
                            end_to_end: false,
                        };
                        match peer_runners[p].run(&job, Protocol::OneShot) {
                            Ok(run) => {
                                if !(t == 1 && *peer == "skimage-lewiner") {
                                    times[surface.len() + p][t].push(run.time.as_secs_f64() * 1e3);
                                }
                                if last {
                                    meshes[surface.len() + p] = Some(isolab_io::read_mesh(&out)?);
                                }
                            }
                            Err(e) => errors[p] = Some(e.to_string()),
                        }
                    }
                }
            }
            for (k, info) in surface.iter().enumerate() {
                if let Some(mesh) = &meshes[k] {
                    let t = std::mem::take(&mut times[k]);
                    data.rows.push(row(info.name, true, &level, t, mesh, field.as_ref(), internal, voxel_volume));
                }
                bar.inc(1);
            }
            for (p, (_, label)) in peers.iter().enumerate() {
                match (&meshes[surface.len() + p], &errors[p]) {
                    (Some(mesh), None) => data.rows.push(row(
                        label,
                        false,
                        &level,
                        std::mem::take(&mut times[surface.len() + p]),
                        mesh,
                        field.as_ref(),
                        internal,
                        voxel_volume,
                    )),
                    (_, e) => {
                        data.skipped.push(format!("{label} at {}: {}", level.name, e.clone().unwrap_or_else(|| "no mesh".into())))
                    }
                }
                bar.inc(1);
            }
            // End to end, one-shot, alternating, on one thread and on two.
            for (t, pool) in pools.iter().enumerate() {
                let (mut ours, mut theirs, mut counts) = (Vec::new(), Vec::new(), (0, 0));
                for _ in 0..ctx.repeats {
                    let start = Instant::now();
                    let triangles = pool.install(|| -> Result<usize, ExperimentError> {
                        let file = read_volume(path, VolumeOptions::default())?;
                        let (samples, to_world) = volume_samples(&file, LatticeKind::Cubic, Inside::Above, level.iso)?;
                        let mut out = Extraction::default();
                        let mc = extractors::by_name("marching-cubes")
                            .ok_or_else(|| ExperimentError::Missing("extractor marching-cubes".into()))?;
                        mc.extract(&samples, &mut out)?;
                        if let Some(a) = &to_world {
                            out.surface.transform(a);
                        }
                        Ok(out.surface.triangles.len())
                    })?;
                    ours.push(start.elapsed().as_secs_f64() * 1e3);
                    counts.0 = triangles;
                    let job = Job::Scan { file: path, level: level.iso, threads: t + 1, out: None, end_to_end: true };
                    match end_to_end_peer.run(&job, Protocol::OneShot) {
                        Ok(run) => {
                            theirs.push(run.time.as_secs_f64() * 1e3);
                            counts.1 = run.triangles;
                        }
                        Err(e) => data.skipped.push(format!("end to end at {}: {e}", level.name)),
                    }
                }
                let (ours_ms, peer_ms) = (Spread::of(ours), Spread::of(theirs));
                data.end_to_end.push(EndToEnd {
                    level: level.name.clone(),
                    threads: t + 1,
                    ratio: peer_ms.median / ours_ms.median,
                    ours_ms,
                    peer_ms,
                    ours_triangles: counts.0,
                    peer_triangles: counts.1,
                });
            }
            bar.inc(1);
            // Pictures: marching cubes large, and every implementation small.
            let mc_index = surface.iter().position(|i| i.name == "marching-cubes");
            if let Some(mc) = mc_index.and_then(|k| meshes[k].as_ref()) {
                let file_name = format!("{}-marching-cubes.png", level.name.replace(' ', "-"));
                save_png(&dir.join(&file_name), &render(&for_display(mc), &picture_options(420)))?;
                data.images.push((
                    format!("marching cubes, {} (iso {:.1})", level.name, level.iso),
                    format!("figures/{NAME}/{file_name}"),
                ));
            }
            if level.name == "white matter" {
                let labels: Vec<String> =
                    surface.iter().map(|i| i.name.to_string()).chain(peers.iter().map(|p| p.1.to_string())).collect();
                for (label, mesh) in labels.iter().zip(&meshes) {
                    if let Some(mesh) = mesh {
                        let mut image = render(&for_display(mesh), &picture_options(220));
                        caption(&mut image.rgb, (image.width, image.height), label).map_err(ExperimentError::Figure)?;
                        pictures.push((label.clone(), image));
                    }
                }
            }
        }
        if !pictures.is_empty() {
            let images: Vec<_> = pictures.iter().map(|(_, i)| i).collect();
            save_png(&dir.join("white-matter-all.png"), &grid(&images, 4))?;
            let order = pictures.iter().map(|(l, _)| l.as_str()).collect::<Vec<_>>().join(", ");
            data.images.push((
                format!("white matter, each picture labelled; left to right and top to bottom: {order}"),
                format!("figures/{NAME}/white-matter-all.png"),
            ));
        }
        let _ = std::fs::remove_dir_all(&tmp);
        match (hello["epi"].as_str(), serde_json::from_value::<[[f64; 4]; 4]>(hello["epi_affine"].clone())) {
            (Some(epi), Ok(affine)) => {
                let package = format!("nibabel {}", data.versions.get("nibabel").cloned().unwrap_or_default());
                data.second =
                    Some(second::run_second(ctx, epi, &affine, hello["epi_axcodes"].as_str().unwrap_or("?"), &package)?);
            }
            _ => data.skipped.push(format!("the second volume: nibabel's example4d.nii.gz not found ({})", hello["errors"])),
        }
        let mut scans = vec![(path.to_path_buf(), None, data.levels.clone())];
        if let (Some(epi), Some(s)) = (hello["epi"].as_str(), &data.second) {
            let level = Level { name: format!("second volume, volume {}", s.volume_index), iso: s.iso, how: s.iso_from.clone() };
            scans.push((std::path::PathBuf::from(epi), Some(s.volume_index), vec![level]));
        }
        for (scan, volume, levels) in scans {
            match lewiner::classify(&root, &scan, volume, &levels) {
                Ok((rows, versions)) => {
                    data.lewiner_cells.extend(rows);
                    for (k, v) in versions {
                        data.versions.entry(k).or_insert(v);
                    }
                }
                Err(e) => data.skipped.push(format!("the cell-by-cell comparison with scikit-image's Lewiner: {e}")),
            }
        }
        bar.finish();
        ctx.write_data(NAME, &data)
    }

    fn section(&self, ctx: &Context) -> Result<String, ExperimentError> {
        page::section(ctx)
    }
}

fn tempfile_dir() -> Result<std::path::PathBuf, ExperimentError> {
    let tmp = std::env::temp_dir().join(format!("isolab-real-volumes-{}", std::process::id()));
    std::fs::create_dir_all(&tmp).map_err(|source| isolab_io::IoError::Write { path: tmp.clone(), source })?;
    Ok(tmp)
}
