//! The page's generated prose: the commands that open it, the islands table and its reading,
//! and the notes comparing marching cubes, dual contouring and the peers, each worded from the
//! run's data.

use super::data::{Data, Row};
use super::islands::{self, Islands};
use super::NAME;
use super::{lewiner, second};
use crate::experiment::context::{Context, ExperimentError};
use crate::report::markdown_table;

/// The page, from the data file alone.
pub(super) fn section(ctx: &Context) -> Result<String, ExperimentError> {
    let data: Data = ctx.read_data(NAME)?;
    let mut s = String::from("## A real MRI (`real_volumes`)\n\n");
    if data.levels.is_empty() {
        s.push_str(&format!("_Not run: {}._\n", data.skipped.join("; ")));
        return Ok(s);
    }
    s.push_str(&reading(&data));
    s.push_str(&own_scan_commands(&data));
    let [a, b, c] = data.shape;
    s.push_str(&format!(
        "The MNI ICBM152 2009a symmetric T1 template, {}: {a} x {b} x {c} voxels of {} ({:.0} x {:.0} x {:.0} mm), {:.1} MB \
         gzipped, read by isolab's NIfTI reader and meshed on its own voxel grid (no resampling) in RAS world coordinates. \
         This copy is brain-extracted ({:.0}% of its voxels are zero), so it has no skin to mesh, and the \"skin\" \
         level a scan user would ask for is the brain's outer surface here. Iso-values, computed by the experiment: {}. Inside is above the \
         iso-value (`--inside above`, the default for volume files).\n\n",
        data.source,
        data.data_type,
        data.spacing[0],
        data.spacing[1],
        data.spacing[2],
        data.file_bytes as f64 / 1e6,
        100.0 * data.zero_fraction,
        data.levels.iter().map(|l| format!("**{}** {:.1} ({})", l.name, l.iso, l.how)).collect::<Vec<_>>().join("; ")
    ));
    s.push_str(&format!(
        "Protocol: one-shot, {} alternating runs, median (min-max) in ms, on one thread and on {}: ours in a rayon pool of \
         that size, VTK's flying edges on its Sequential backend for one thread and its STDThread backend for two \
         (scikit-image is single-threaded). Extraction only: a fresh extractor and output per run for ours, a fresh \
         `vtkFlyingEdges3D` and a fresh scikit-image call on the array nibabel loaded. VTK meshes that \
         array as stored ({}); isolab's samples are f32 (four bytes a voxel), converted \
         beforehand (the conversion is in the end-to-end times below). Distance: the mean over vertices of the first-order distance \
         `|f - iso| / |grad f|` to the trilinear interpolant's level set, in voxels ({:.0} mm; the maximum is not shown: \
         where the interpolant is nearly flat this estimate is meaningless). Every mesh is measured by isolab's metrics, which the Rust tests check \
         against CGAL, pymeshlab and VTK (golden values in `tests/reference/golden/`).\n\n",
        data.repeats, data.threads, data.data_type, data.spacing[0]
    ));
    s.push_str(&crate::experiment::context::options_as_run(&data.settings));
    for level in &data.levels {
        s.push_str(&format!("**{} (iso {:.1})**\n\n", level.name, level.iso));
        let rows: Vec<Vec<String>> = data
            .rows
            .iter()
            .filter(|r| r.level == level.name)
            .map(|r| {
                vec![
                    if r.ours { r.implementation.clone() } else { format!("_{}_", r.implementation) },
                    r.triangles.to_string(),
                    format!("{:.1} ({:.1}-{:.1})", r.time_1.median, r.time_1.min, r.time_1.max),
                    r.time_2.as_ref().map_or("-".into(), |t| format!("{:.1} ({:.1}-{:.1})", t.median, t.min, t.max)),
                    format!("{:.1}", r.min_angle_deg),
                    format!("{:.2} / {:.0}", r.aspect_mean, r.aspect_max),
                    r.components.to_string(),
                    r.genus.map_or("-".into(), |g| g.to_string()),
                    yes_no(r.closed),
                    yes_no(r.manifold),
                    if r.outward {
                        "outward".into()
                    } else if r.oriented {
                        "inward".into()
                    } else {
                        "no".into()
                    },
                    r.self_intersections.to_string(),
                    format!("{:.3}", r.distance_mean),
                ]
            })
            .collect();
        s.push_str(&markdown_table(
            &[
                "implementation",
                "triangles",
                "ms, one thread",
                &format!("ms, {} threads", data.threads),
                "min angle",
                "aspect mean / max",
                "components",
                "genus",
                "closed",
                "manifold",
                "oriented",
                "self-int.",
                "mean distance",
            ],
            &rows,
        ));
        s.push('\n');
    }
    s.push_str(&comparison_notes(&data));
    s.push_str(&islands_section(&data));
    s.push_str(&lewiner::section(&data));
    let rows: Vec<Vec<String>> = data
        .end_to_end
        .iter()
        .map(|e| {
            vec![
                e.level.clone(),
                e.threads.to_string(),
                format!("{:.1} ({:.1}-{:.1})", e.ours_ms.median, e.ours_ms.min, e.ours_ms.max),
                format!("{:.1} ({:.1}-{:.1})", e.peer_ms.median, e.peer_ms.min, e.peer_ms.max),
                format!("{:.2}x", e.ratio),
                format!("{} / {}", e.ours_triangles, e.peer_triangles),
            ]
        })
        .collect();
    s.push_str(
        "End to end, one process each, one-shot: isolab reading the `.nii.gz`, taking the voxels as samples, marching cubes \
         and the map to world coordinates, against nibabel loading the same file, the array into a `vtkImageData` and \
         `vtkFlyingEdges3D`, both on the same number of threads (ratio: peer time over ours, above one when isolab is \
         faster):\n\n",
    );
    s.push_str(&markdown_table(&["level", "threads", "isolab ms", "nibabel + VTK ms", "ratio", "triangles (ours / VTK)"], &rows));
    s.push('\n');
    if let Some(second) = &data.second {
        s.push_str(&second::section(second));
    }
    for (label, path) in &data.images {
        s.push_str(&format!("![{label}]({path})\n\n_{label}_\n\n"));
    }
    if !data.skipped.is_empty() {
        s.push_str(&format!("Skipped: {}.\n\n", data.skipped.join("; ")));
    }
    s.push_str(&format!("Versions: {}.\n", data.versions.iter().map(|(k, v)| format!("{k} {v}")).collect::<Vec<_>>().join(", ")));
    Ok(s)
}

/// What opens the page: the commands that mesh one's own scan, the iso-values and threshold
/// the data used.
pub(super) fn own_scan_commands(data: &Data) -> String {
    let iso = |k: usize| data.levels.get(k).map_or(String::new(), |l| format!("{:.1}", l.iso));
    let volume = data.second.as_ref().map_or(0, |s| s.volume_index);
    format!(
        "**Meshing your own scan.** A volume file (NIfTI `.nii`/`.nii.gz`, NRRD `.nrrd`/`.nhdr`, MetaImage `.mhd`/`.mha`, \
         or a zarr store) is meshed on its own voxel grid, and the mesh is placed in world coordinates by the file's header \
         (spacing, origin, direction; RAS as 3D Slicer shows it, or `--space lps`). Inside is above the iso-value (a bright \
         object); `--inside below` for a dark one. Without `--iso` the run takes Otsu's threshold and says so. The iso-values \
         below are the ones this page computed for the MNI template:\n\n```sh\n\
         isolab extract -a marching-cubes -f scan.nii.gz -o scan.glb                 # Otsu's threshold, said on stderr\n\
         isolab extract -a marching-cubes -f scan.nii.gz --iso {} -o brain.stl      # an iso-value in the file's own units\n\
         isolab extract -a surface-nets -f scan.nrrd --iso {} -m wm.json -o wm.ply  # with every metric, as in the tables\n\
         isolab extract -a marching-cubes -f scan.mha --iso {} --post keep-components:largest={} -o one.ply    # the largest part only\n\
         isolab extract -a marching-cubes -f scan.mha --iso {} --post keep-components:largest={},min-volume={:.0} -o parts.ply  # islands dropped\n\
         isolab extract -a marching-cubes -f ct.nii.gz --iso {} --inside below -o air.ply   # a dark object: inside below\n\
         isolab extract -a marching-cubes -f fmri.nii.gz --volume {volume} -o epi.ply             # one volume of a time series\n\
         ```\n\nFrom Python, the same run on a file or on an array with its affine: \
         `isolab.extract(\"scan.nii.gz\", {}, post=[\"keep-components:largest={}\"])`, \
         `isolab.extract(array, {}, affine=img.affine, inside=\"above\")`.\n\n",
        iso(0),
        iso(1),
        iso(0),
        islands::KEEP_LARGEST,
        iso(0),
        islands::KEEP_ANY,
        islands::MIN_ISLAND_VOXELS,
        islands::AIR_ISO_HU,
        iso(0),
        islands::KEEP_LARGEST,
        iso(0),
    )
}

/// The page's opening reading: per iso-value, the fastest on one thread, who is closed and
/// manifold and who has self-intersections; the islands; the second volume's openness.
pub(super) fn reading(data: &Data) -> String {
    let mut lines = Vec::new();
    for level in &data.levels {
        let here: Vec<&Row> = data.rows.iter().filter(|r| r.level == level.name).collect();
        let Some(fastest) = here.iter().min_by(|a, b| a.time_1.median.total_cmp(&b.time_1.median)) else { continue };
        let names = |keep: &dyn Fn(&Row) -> bool| {
            crate::report::listed(&here.iter().filter(|r| keep(r)).map(|r| r.implementation.as_str()).collect::<Vec<_>>())
        };
        lines.push(format!(
            "At the {} level (iso {:.1}), fastest on one thread: {} ({} ms); not closed and manifold: {}; with \
             self-intersections: {}.",
            level.name,
            level.iso,
            fastest.implementation,
            super::super::context::ms(fastest.time_1.median),
            names(&|r| !(r.closed && r.manifold)),
            names(&|r| r.self_intersections > 0)
        ));
        let islands: Vec<(&str, &Islands)> =
            here.iter().filter_map(|r| Some((r.implementation.as_str(), r.islands.as_ref()?))).collect();
        lines.extend(islands::reading("Islands", &islands));
    }
    if let Some(v) = &data.second {
        lines.push(format!("The second volume ({}): {}", v.source, super::second::openness(v)));
    }
    if lines.is_empty() {
        return String::new();
    }
    format!("**Reading.** {}\n\n", lines.join(" "))
}

/// The islands each mesh comes with, and what `keep-components` leaves.
pub(super) fn islands_section(data: &Data) -> String {
    let mut s = String::new();
    let with: Vec<&Row> = data.rows.iter().filter(|r| r.islands.is_some()).collect();
    if with.is_empty() {
        return s;
    }
    s.push_str(&format!(
        "**Islands.** An isosurface of a real scan comes in many connected components: noise, vessels and folds cut by the \
         iso-value. `--post keep-components:largest={},min-volume={:.0}` drops the components enclosing fewer than {:.0} \
         voxels, `keep-components:largest={}` keeps the largest alone (components ranked by the volume they enclose, with \
         the post-process's own ranking):\n\n",
        islands::KEEP_ANY,
        islands::MIN_ISLAND_VOXELS,
        islands::MIN_ISLAND_VOXELS,
        islands::KEEP_LARGEST
    ));
    let mut readings = Vec::new();
    for level in &data.levels {
        let here: Vec<(&str, &Islands)> = with
            .iter()
            .filter(|r| r.level == level.name)
            .filter_map(|r| Some((r.implementation.as_str(), r.islands.as_ref()?)))
            .collect();
        let rows: Vec<Vec<String>> = here
            .iter()
            .map(|(name, i)| [vec![level.name.clone(), (*name).to_owned()], islands::cells(i).to_vec()].concat())
            .collect();
        let headers: Vec<String> =
            ["level".to_owned(), "implementation".to_owned()].into_iter().chain(islands::headers()).collect();
        s.push_str(&markdown_table(&headers.iter().map(String::as_str).collect::<Vec<_>>(), &rows));
        s.push('\n');
        readings.extend(islands::reading(&format!("At the {} level", level.name), &here));
    }
    s.push_str(&readings.join(" "));
    s.push_str("\n\n");
    s
}

/// What the tables show about marching cubes against the peers, worded from the data.
pub(super) fn comparison_notes(data: &Data) -> String {
    let find = |name: &str, level: &str| data.rows.iter().find(|r| r.implementation == name && r.level == level);
    let mut notes = vec!["Peers in italics.".to_owned()];
    let same: Vec<bool> = data
        .levels
        .iter()
        .filter_map(|l| Some((find("marching-cubes", &l.name)?, find("vtkFlyingEdges3D", &l.name)?)))
        .map(|(a, b)| a.vertices == b.vertices && a.triangles == b.triangles)
        .collect();
    if !same.is_empty() && same.iter().all(|&s| s) {
        notes.push(
            "Our marching cubes and VTK's flying edges make as many vertices and triangles at every level (their vertex \
             sets and cell polygons are checked equal on a subsampled copy of this template in `tests/reference/`)."
                .into(),
        );
    }
    for l in &data.levels {
        if let (Some(mc), Some(fe)) = (find("marching-cubes", &l.name), find("vtkFlyingEdges3D", &l.name)) {
            if mc.self_intersections > fe.self_intersections {
                notes.push(format!(
                    "At the {} level our marching cubes has {} self-intersecting triangle pairs and flying edges {}. The \
                     pairs we inspected lie within one cell: our table fans a strongly non-planar polygon, whose vertices \
                     crowd a corner near the iso-value, into triangles that cross (its rule keeps diagonals off the cube's \
                     faces, not off each other); flying edges triangulates the same polygon without crossing.",
                    l.name, mc.self_intersections, fe.self_intersections
                ));
            }
        }
    }
    for l in &data.levels {
        if let (Some(dc), Some(mdc)) = (find("dual-contouring", &l.name), find("manifold-dual-contouring", &l.name)) {
            notes.push(format!(
                "At the {} level manifold dual contouring has {} self-intersecting pairs against dual contouring's {}, for \
                 {:.2}x its triangles and {:.2}x its one-thread time; its vertices' mean distance to the trilinear level \
                 set is {:.3} voxels against {:.3}, lower because it keeps dual contouring's vertices and adds an edge \
                 point per quad, which lies on the level set.",
                l.name,
                mdc.self_intersections,
                dc.self_intersections,
                mdc.triangles as f64 / dc.triangles.max(1) as f64,
                mdc.time_1.median / dc.time_1.median.max(f64::MIN_POSITIVE),
                mdc.distance_mean,
                dc.distance_mean
            ));
        }
    }
    let inward = data
        .levels
        .iter()
        .find_map(|l| find("scikit-image (Lewiner)", &l.name).filter(|r| r.oriented && !r.outward && r.closed).map(|r| (l, r)));
    if let Some((l, sk)) = inward {
        notes.push(format!(
            "scikit-image's Lewiner variant resolves ambiguous cells by the trilinear interpolant and may add a vertex \
             inside a cell ({} vertices at the {} level), and it winds triangles by its `gradient_direction` (default \
             `descent`): for a bright object its consistently oriented mesh faces inward.",
            sk.vertices, l.name
        ));
    }
    notes.join(" ") + "\n\n"
}

pub(super) fn yes_no(b: bool) -> String {
    if b { "yes" } else { "no" }.into()
}

#[cfg(test)]
mod tests {
    use super::super::data::Level;
    use super::*;

    fn row(implementation: &str, ms: f64, closed: bool, self_intersections: usize) -> Row {
        let mut r: Row = serde_json::from_value(serde_json::json!({
            "implementation": implementation, "ours": true, "level": "brain",
            "time_1": {"median": ms, "min": ms, "max": ms, "runs": [ms]}, "time_2": null,
            "vertices": 1, "triangles": 100, "min_angle_deg": 1.0, "aspect_mean": 1.0, "aspect_max": 1.0,
            "components": 3, "genus": 0, "closed": closed, "manifold": true, "outward": true, "oriented": true,
            "self_intersections": self_intersections, "distance_mean": 0.0, "distance_max": 0.0
        }))
        .unwrap();
        r.islands = Some(Islands {
            min_volume_voxels: 100.0,
            components: 3,
            triangles: 100,
            components_after: 1,
            triangles_after: 90,
            largest_triangles: 90,
        });
        r
    }

    #[test]
    fn the_reading_follows_the_rows() {
        let mut data = Data::default();
        assert_eq!(reading(&data), "");
        data.levels = vec![Level { name: "brain".into(), iso: 89.6, how: String::new() }];
        data.rows = vec![row("marching-cubes", 20.0, true, 0), row("dual-contouring", 10.0, false, 4)];
        let r = reading(&data);
        assert!(r.contains("At the brain level (iso 89.6), fastest on one thread: dual-contouring (10"), "{r}");
        assert!(r.contains("not closed and manifold: dual-contouring; with self-intersections: dual-contouring."), "{r}");
        assert!(r.contains("Islands: 3 components per mesh"), "{r}");
        data.rows[1].closed = true;
        data.rows[1].self_intersections = 0;
        assert!(reading(&data).contains("not closed and manifold: none; with self-intersections: none."));
    }
}
