//! A second volume of another kind: the functional MRI (EPI) series nibabel ships as test data,
//! `example4d.nii.gz`: signed 16-bit voxels, anisotropic (2 x 2 x 2.2 mm) and oblique (its
//! slices tilted against the scanner's axes), stored left-to-right flipped, two volumes in one
//! 4-D file. What a scan user meets beyond a tidy template. Every surface extractor meshes its
//! first volume as `isolab extract -f example4d.nii.gz --volume 0` does (the pipeline's own run,
//! Otsu's threshold), and our index-to-world map is compared with the affine nibabel reads.

use super::islands::{islands, Islands};
use crate::experiment::context::{Context, ExperimentError};
use crate::report::{markdown_table, Spread};
use isolab_algorithms::extractors;
use isolab_io::volume::VolumeOptions;
use isolab_metrics::MeshMetrics;
use isolab_pipeline::{run, Measure, RunConfig};
use serde::{Deserialize, Serialize};

/// Which volume of the 4-D file is meshed.
pub(crate) const VOLUME_INDEX: usize = 0;

/// One extractor's mesh of the volume.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub(crate) struct SecondRow {
    pub(crate) implementation: String,
    /// Extraction time, ms, over the runs.
    pub(crate) time: Spread,
    pub(crate) triangles: usize,
    pub(crate) closed: bool,
    pub(crate) manifold: bool,
    pub(crate) outward: bool,
    pub(crate) oriented: bool,
    /// Edges of one triangle, and those of them not in the volume's outermost layer of cells.
    pub(crate) open_edges: usize,
    pub(crate) open_edges_inside: usize,
    pub(crate) min_angle_deg: f64,
    pub(crate) aspect_mean: f64,
    pub(crate) islands: Islands,
}

/// The volume and its meshes.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub(crate) struct SecondVolume {
    /// The file's name and the package it ships with.
    pub(crate) source: String,
    pub(crate) shape: [usize; 3],
    pub(crate) volume_index: usize,
    pub(crate) data_type: String,
    pub(crate) spacing: [f64; 3],
    /// nibabel's orientation codes of the stored axes (`aff2axcodes`).
    pub(crate) axcodes: String,
    /// The angle between the slice normal and the nearest world axis, degrees.
    pub(crate) obliquity_deg: f64,
    /// The iso-value the run took (Otsu's threshold) and how it says so.
    pub(crate) iso: f32,
    pub(crate) iso_from: String,
    /// Largest difference between our index-to-world map and nibabel's affine, mm.
    pub(crate) affine_difference_mm: f64,
    pub(crate) rows: Vec<SecondRow>,
}

/// Meshes the volume at `path` with every surface extractor; `affine` is nibabel's (row-major
/// 4 x 4), `axcodes` its orientation codes.
pub(crate) fn run_second(
    ctx: &Context,
    path: &str,
    affine: &[[f64; 4]; 4],
    axcodes: &str,
    package: &str,
) -> Result<SecondVolume, ExperimentError> {
    let surface: Vec<&str> = extractors::INFOS
        .iter()
        .filter(|i| extractors::by_name(i.name).is_some_and(|e| !e.produces_volume()))
        .map(|i| i.name)
        .collect();
    let mut rows = Vec::new();
    let mut second: Option<SecondVolume> = None;
    for name in surface {
        let mut config = RunConfig::new(name, path, 0);
        config.volume = VolumeOptions { index: Some(VOLUME_INDEX) };
        config.measure = Measure::Counts;
        let mut times = Vec::new();
        let mut last = None;
        for _ in 0..ctx.repeats {
            let outcome = run(&config)?;
            times.push(outcome.report.times_ms.extraction);
            last = Some(outcome);
        }
        let outcome = last.ok_or_else(|| ExperimentError::Missing("a run of the second volume (no repeats asked)".into()))?;
        let input = &outcome.report.input;
        let spacing = input.spacing.unwrap_or([1.0; 3]);
        if second.is_none() {
            let ours = outcome.samples_to_world.ok_or_else(|| ExperimentError::Failed {
                what: format!("meshing {path}"),
                reason: "the run gave no index-to-world map for a volume on its own grid".into(),
            })?;
            let m = ours.matrix3.to_cols_array_2d();
            let t = ours.translation;
            let mut difference = 0.0f64;
            for r in 0..3 {
                for c in 0..3 {
                    difference = difference.max((m[c][r] - affine[r][c]).abs());
                }
                difference = difference.max((t[r] - affine[r][3]).abs());
            }
            let normal = glam::DVec3::new(affine[0][2], affine[1][2], affine[2][2]).normalize();
            let nearest = normal.abs().max_element().clamp(-1.0, 1.0);
            second = Some(SecondVolume {
                source: format!("{} ({package})", std::path::Path::new(path).file_name().unwrap_or_default().to_string_lossy()),
                shape: input.shape.unwrap_or_default(),
                volume_index: VOLUME_INDEX,
                data_type: input.data_type.unwrap_or("unknown").to_owned(),
                spacing,
                axcodes: axcodes.to_owned(),
                obliquity_deg: nearest.acos().to_degrees(),
                iso: outcome.report.iso,
                iso_from: input.iso_from.unwrap_or("given").to_owned(),
                affine_difference_mm: difference,
                rows: Vec::new(),
            });
        }
        let mesh = &outcome.extraction.surface;
        let m = MeshMetrics::measure(mesh, None);
        let to_index = outcome.samples_to_world.map(|a| a.inverse());
        let dims = outcome.report.dims;
        let (open_edges, open_edges_inside) = open_edges(mesh, |p| {
            let q = to_index.map_or(p.as_dvec3(), |a| a.transform_point3(p.as_dvec3()));
            (0..3).any(|k| q[k] <= 1.0 + BORDER_TOLERANCE || q[k] >= (dims[k] - 2) as f64 - BORDER_TOLERANCE)
        });
        let t = &m.topology;
        rows.push(SecondRow {
            implementation: name.to_owned(),
            time: Spread::of(times),
            triangles: m.triangles,
            closed: t.closed,
            manifold: t.edge_manifold && t.vertex_manifold,
            outward: t.outward,
            oriented: t.oriented,
            open_edges,
            open_edges_inside,
            min_angle_deg: m.quality.min_angle_deg,
            aspect_mean: m.quality.aspect_ratio.mean,
            islands: islands(mesh, spacing.iter().product()),
        });
    }
    let mut second = second.ok_or_else(|| ExperimentError::Missing("a surface extractor".into()))?;
    second.rows = rows;
    Ok(second)
}

/// A vertex in the volume's outermost layer of cells (within this many voxels) is at the border:
/// the layer where marching methods put a border vertex on the border and dual methods put it
/// inside the cell.
const BORDER_TOLERANCE: f64 = 1e-3;

/// The mesh's edges of one triangle, and how many of them have an end not `on_border`.
fn open_edges(mesh: &isolab_algorithms::TriMesh, on_border: impl Fn(glam::Vec3) -> bool) -> (usize, usize) {
    let mut uses: std::collections::HashMap<(u32, u32), u32> = std::collections::HashMap::new();
    for t in &mesh.triangles {
        for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
            *uses.entry((a.min(b), a.max(b))).or_default() += 1;
        }
    }
    let open: Vec<(u32, u32)> = uses.into_iter().filter(|&(_, n)| n == 1).map(|(e, _)| e).collect();
    let inside =
        open.iter().filter(|(a, b)| !(on_border(mesh.positions[*a as usize]) && on_border(mesh.positions[*b as usize]))).count();
    (open.len(), inside)
}

/// The page's part on the second volume.
pub(crate) fn section(v: &SecondVolume) -> String {
    let [a, b, c] = v.shape;
    let mut s = format!(
        "### A second volume: an oblique, anisotropic fMRI series\n\n{}: a functional MRI (EPI) series, {a} x {b} x {c} voxels \
         of {} ({:.1} x {:.1} x {:.1} mm), stored with axes {} and its slices tilted {:.1}° from the nearest world axis; a \
         time series in one file whose volume {} is meshed (`--volume {}`), at {} ({:.1}). Our index-to-world map {}, so the meshes \
         below overlay the scan where nibabel-based tools put it. {}\n\n",
        v.source,
        v.data_type,
        v.spacing[0],
        v.spacing[1],
        v.spacing[2],
        v.axcodes,
        v.obliquity_deg,
        v.volume_index,
        v.volume_index,
        v.iso_from,
        v.iso,
        if v.affine_difference_mm == 0.0 {
            "equals the affine nibabel reads, to the last digit".to_owned()
        } else {
            format!("differs from the affine nibabel reads by at most {:.1e} mm", v.affine_difference_mm)
        },
        openness(v)
    );
    let rows: Vec<Vec<String>> = v
        .rows
        .iter()
        .map(|r| {
            vec![
                r.implementation.clone(),
                r.triangles.to_string(),
                format!("{:.2} ({:.2}-{:.2})", r.time.median, r.time.min, r.time.max),
                format!("{:.1}", r.min_angle_deg),
                format!("{:.2}", r.aspect_mean),
                if r.manifold { "yes".into() } else { "no".into() },
                format!("{} ({})", r.open_edges, r.open_edges_inside),
                if r.outward {
                    "outward".into()
                } else if r.oriented {
                    "consistent".into()
                } else {
                    "no".into()
                },
            ]
            .into_iter()
            .chain(super::islands::cells(&r.islands))
            .collect()
        })
        .collect();
    let headers: Vec<String> = [
        "implementation",
        "triangles",
        "extraction ms",
        "min angle",
        "aspect mean",
        "manifold",
        "open edges (off the border cells)",
        "oriented",
    ]
    .map(String::from)
    .into_iter()
    .chain(super::islands::headers())
    .collect();
    s.push_str(&markdown_table(&headers.iter().map(String::as_str).collect::<Vec<_>>(), &rows));
    s.push('\n');
    let islands: Vec<(&str, &Islands)> = v.rows.iter().map(|r| (r.implementation.as_str(), &r.islands)).collect();
    if let Some(r) = super::islands::reading("On this series", &islands) {
        s.push_str(&r);
        s.push_str("\n\n");
    }
    s
}

/// Whether the meshes are open, and where, worded from the rows.
pub(super) fn openness(v: &SecondVolume) -> String {
    let open = v.rows.iter().filter(|r| r.open_edges > 0).count();
    let off_border = v.rows.iter().filter(|r| r.open_edges_inside > 0).count();
    match (open, off_border) {
        (0, _) => "Every mesh is closed.".into(),
        (n, 0) => format!(
            "{n} of {} meshes are open, every open edge in the volume's outermost layer of cells: the head leaves the series' field of view \
             ({:.0} mm across {} slices), and the extractors mesh inside the volume only.",
            v.rows.len(),
            v.spacing[2] * v.shape[2] as f64,
            v.shape[2]
        ),
        (n, m) => {
            format!(
            "{n} of {} meshes are open, {m} of them with open edges off the volume's outermost layer of cells (unexplained).",
            v.rows.len()
        )
        }
    }
}
