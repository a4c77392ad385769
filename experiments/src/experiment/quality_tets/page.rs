//! The page `report/quality_tets.md` and the front page's pick for tetrahedra, from the two data
//! files alone.

use super::data::{Data, LabelRow, Labels, PeerRow, Peers, Quality, Row};
use super::{NAME, PEER_CELLS, SCULPT, STUFFING};
use crate::experiment::choosing::Choice;
use crate::experiment::context::{Context, ExperimentError};
use crate::report::{and_list, first_seen, markdown_table, Spread};

/// The speed bar for stuffing: tetrahedra a second on one core.
pub(crate) const RATE_BAR: f64 = 200_000.0;

/// A mesh of the model itself (not an enclosure): every boundary vertex within this many `h` of
/// the model's surface.
pub(crate) const ON_SURFACE_H: f64 = 0.1;

/// The page, from the data files alone.
pub(super) fn section(ctx: &Context) -> Result<String, ExperimentError> {
    let data: Data = ctx.read_data(NAME)?;
    let peers: Option<Peers> = ctx.read_data("quality_tets_peers").ok();
    let mut s = String::from("## Tetrahedra with proven quality (`quality_tets`)\n\n");
    s.push_str(&format!(
        "`{STUFFING}` fills each shipped model's inside on a lattice of spacing h = longest side / {}; `{SCULPT}` encloses \
         it at h = longest side / {PEER_CELLS}; TetGen, CGAL Mesh_3, NETGEN and fTetWild mesh the model's own triangles, \
         each sized until its count is near stuffing's at h = longest side / {PEER_CELLS}. Every mesh is measured by one \
         definition; ours on one thread.\n\n",
        and_list(&data.cells.iter().map(|c| c.to_string()).collect::<Vec<_>>()),
    ));
    s.push_str(&reading(&data, peers.as_ref()));
    s.push_str(&crate::experiment::context::options_as_run(&data.settings));
    s.push_str("### Ours\n\n");
    s.push_str(&ours_table(&data.rows));
    s.push_str(
        "\nDistances are in h, sampled at vertices: \"to S\" from the boundary's vertices to the model's surface, \"from S\" \
         from the model's vertices to the boundary (the larger of the two maxima is the two-sided Hausdorff distance at \
         vertices). Radius ratio: the circumradius over three times the inradius, one for the regular tetrahedron. Times: sampling the signed distance at the \
         lattice's corners plus the extraction, median (fastest-slowest) of every run.\n\n",
    );
    match &peers {
        Some(p) => {
            s.push_str(&format!("### The peers, matched to stuffing's count at h = longest side / {PEER_CELLS}\n\n"));
            s.push_str(&peer_table(p));
            let inputs: Vec<String> =
                p.inputs.iter().map(|i| format!("`{}`: {} ({} triangles)", i.model, i.how, i.triangles)).collect();
            s.push_str(&format!(
                "\nThe surface each peer got: {}. Each peer's sizing parameter is scaled until its count is within {:.0}% of \
                 the target or its tries run out (\"tries\"); the row keeps the try nearest the target, and its time is the \
                 median (fastest-slowest) of that setting's runs. The timing protocols differ: each peer runs one-shot in a \
                 fresh process, timed around its mesher's call alone, while ours repeat in one process (the first run \
                 counted) with the signed distance's sampling included.\n\n",
                inputs.join("; "),
                100.0 * p.match_tolerance
            ));
        }
        None => s.push_str("_The peers' data (`data/quality_tets_peers.json`) is missing: run `peers.py`._\n\n"),
    }
    if let Some(figure) = &data.figure {
        s.push_str(&format!(
            "![boundaries]({figure})\n\nEach model's boundary at h = longest side / {PEER_CELLS}: `{STUFFING}` (left), \
             `{SCULPT}` (right).\n\n"
        ));
    }
    s.push_str(&labels_section(ctx.read_data("quality_tets_labels").ok().as_ref()));
    Ok(s)
}

fn median(v: &[f64]) -> Spread {
    Spread::of(v.to_vec())
}

/// Total time per run (sampling plus extraction), ms.
fn totals(r: &Row) -> Vec<f64> {
    r.sampling_ms.iter().zip(&r.extraction_ms).map(|(a, b)| a + b).collect()
}

/// Tetrahedra a second on one thread, from the median total.
fn rate(r: &Row) -> f64 {
    r.quality.tetrahedra as f64 / (median(&totals(r)).median / 1e3)
}

fn quality_cells(q: &Quality) -> Vec<String> {
    vec![
        q.tetrahedra.to_string(),
        format!("{:.1}-{:.1}°", q.dihedral[0], q.dihedral[1]),
        format!("{:.2} / {:.2}", q.radius_ratio[0], q.radius_ratio[1]),
        q.inverted.to_string(),
        format!("{:.3} / {:.3}", q.to_surface_h[0], q.to_surface_h[1]),
        format!("{:.3} / {:.3}", q.from_surface_h[0], q.from_surface_h[1]),
        format!("{:.3}", q.volume_ratio),
        if q.encloses { "yes" } else { "no" }.into(),
    ]
}

const QUALITY_HEADER: [&str; 8] = [
    "tetrahedra",
    "dihedral",
    "radius ratio mean / max",
    "inverted",
    "to S mean / max",
    "from S mean / max",
    "volume ratio",
    "encloses S",
];

fn ours_table(rows: &[Row]) -> String {
    let body: Vec<Vec<String>> = rows
        .iter()
        .map(|r| {
            let t = median(&totals(r));
            let mut cells = vec![r.model.clone(), format!("`{}`", r.tool), format!("longest side / {}", r.cells)];
            cells.extend(quality_cells(&r.quality));
            cells.push(format!("{:.1} ({:.1}-{:.1})", t.median, t.min, t.max));
            cells.push(format!("{:.0}k", rate(r) / 1e3));
            cells
        })
        .collect();
    let mut header = vec!["model", "extractor", "h"];
    header.extend(QUALITY_HEADER);
    header.extend(["ms, one thread", "tetrahedra / s"]);
    markdown_table(&header, &body)
}

fn peer_table(p: &Peers) -> String {
    let body: Vec<Vec<String>> = p
        .rows
        .iter()
        .map(|r| {
            let mut cells = vec![r.model.clone(), r.tool.clone(), r.target.to_string(), r.tries.to_string()];
            match (&r.quality, &r.error) {
                (Some(q), _) => {
                    cells.extend(quality_cells(q));
                    let t = median(&r.seconds);
                    cells.push(format!("{:.0} ({:.0}-{:.0})", 1e3 * t.median, 1e3 * t.min, 1e3 * t.max));
                    cells.push(r.settings.clone());
                }
                (None, e) => {
                    cells.extend(std::iter::repeat_n("-".to_string(), QUALITY_HEADER.len() + 1));
                    cells.push(format!("failed: {}", e.as_deref().unwrap_or("no result")));
                }
            }
            cells
        })
        .collect();
    let mut header = vec!["model", "mesher", "target", "tries"];
    header.extend(QUALITY_HEADER);
    header.extend(["ms", "setting"]);
    markdown_table(&header, &body)
}

/// `n` models, in words ("1 model", "3 models").
fn models(n: usize) -> String {
    format!("{n} model{}", if n == 1 { "" } else { "s" })
}

/// One mesher's worst dihedral angles over the models given: the smallest minimum and the
/// largest maximum.
fn worst<'a>(qs: impl Iterator<Item = &'a Quality>) -> Option<[f64; 2]> {
    qs.fold(None, |acc: Option<[f64; 2]>, q| {
        Some(match acc {
            None => q.dihedral,
            Some([lo, hi]) => [lo.min(q.dihedral[0]), hi.max(q.dihedral[1])],
        })
    })
}

/// Every mesher at the peers' size, with its measures per model: ours first, then the peers.
fn at_peer_size<'a>(data: &'a Data, peers: Option<&'a Peers>) -> Vec<(String, Vec<(&'a str, &'a Quality)>)> {
    let mut out: Vec<(String, Vec<(&str, &Quality)>)> = Vec::new();
    for tool in first_seen(data.rows.iter().map(|r| r.tool.as_str())) {
        let rows = data.rows.iter().filter(|r| r.tool == tool && r.cells == data.peer_cells);
        out.push((tool.to_owned(), rows.map(|r| (r.model.as_str(), &r.quality)).collect()));
    }
    if let Some(p) = peers {
        for tool in first_seen(p.rows.iter().map(|r| r.tool.as_str())) {
            let rows =
                p.rows.iter().filter(|r| r.tool == tool).filter_map(|r: &PeerRow| Some((r.model.as_str(), r.quality.as_ref()?)));
            out.push((tool.to_owned(), rows.collect()));
        }
    }
    out
}

/// What the tables show, worded from them.
pub(super) fn reading(data: &Data, peers: Option<&Peers>) -> String {
    let mut lines = Vec::new();
    let stuffing: Vec<&Row> = data.rows.iter().filter(|r| r.tool == STUFFING).collect();
    if let Some([lo, hi]) = worst(stuffing.iter().map(|r| &r.quality)) {
        let inside = lo >= data.declared[0] && hi <= data.declared[1];
        let inverted: usize = stuffing.iter().map(|r| r.quality.inverted).sum();
        lines.push(format!(
            "Over its {} runs, `{STUFFING}`'s dihedral angles span {lo:.1}-{hi:.1}°, {} its declared interval \
             {:.1}-{:.1}° (the paper proves {:.1}-{:.1}° for the same parameters; the extractor's module says why ours is \
             wider), with {inverted} inverted tetrahedra.",
            stuffing.len(),
            if inside { "inside" } else { "outside" },
            data.declared[0],
            data.declared[1],
            data.paper[0],
            data.paper[1],
        ));
    }
    let all = at_peer_size(data, peers);
    let scores: Vec<String> = all
        .iter()
        .filter_map(|(tool, rows)| {
            let [lo, hi] = worst(rows.iter().map(|(_, q)| *q))?;
            Some(format!("{tool} {lo:.1}-{hi:.1}° over {}", models(rows.len())))
        })
        .collect();
    if !scores.is_empty() {
        lines.push(format!("Worst dihedral angles at the peers' size: {}.", scores.join("; ")));
    }
    if let Some(c) = pick_over(data, peers) {
        lines.push(format!("Picked for simulation by the front page's rule: `{}`. {}", c.pick, c.why));
    }
    let finest = data.cells.iter().copied().max().unwrap_or(0);
    let rates: Vec<f64> = stuffing.iter().filter(|r| r.cells == finest).map(|r| rate(r)).collect();
    if let (Some(lo), Some(hi)) = (rates.iter().copied().reduce(f64::min), rates.iter().copied().reduce(f64::max)) {
        let meets = rates.iter().filter(|&&r| r >= RATE_BAR).count();
        lines.push(format!(
            "Speed at h = longest side / {finest}, one thread, the signed distance's sampling included: {:.0}k-{:.0}k \
             tetrahedra a second; {meets} of {} models reach the issue's {:.0}k.",
            lo / 1e3,
            hi / 1e3,
            rates.len(),
            RATE_BAR / 1e3
        ));
    }
    format!("**Reading.** {}\n\n", lines.join(" "))
}

/// The front page's pick for tetrahedra for simulation, from this page's data.
pub(crate) fn pick(ctx: &Context) -> Result<Choice, ExperimentError> {
    let data: Data = ctx.read_data(NAME)?;
    let peers: Peers = ctx.read_data("quality_tets_peers")?;
    pick_over(&data, Some(&peers)).ok_or_else(|| ExperimentError::Missing("a mesher of every model's own surface".into()))
}

/// The rule: among the meshers whose boundary lies on each closed model's surface (every
/// boundary vertex within [`ON_SURFACE_H`] h of it: a mesh of the model, not an enclosure; an open
/// model's holes are closed by a patch, off its surface) with no inverted tetrahedron on any
/// model, over the models every one of them meshed, the highest worst minimum
/// dihedral angle; a tie within a tenth of a degree goes to the one that declares a proven
/// interval.
pub(super) fn pick_over(data: &Data, peers: Option<&Peers>) -> Option<Choice> {
    let all = at_peer_size(data, peers);
    let on_surface = |m: &str, q: &Quality| q.to_surface_h[1] <= ON_SURFACE_H || !data.closed.iter().any(|c| c == m);
    let fit = |rows: &[(&str, &Quality)]| rows.iter().all(|(m, q)| q.inverted == 0 && on_surface(m, q));
    let candidates: Vec<&(String, Vec<(&str, &Quality)>)> =
        all.iter().filter(|(_, rows)| !rows.is_empty() && fit(rows)).collect();
    let shared: Vec<&str> = data
        .models
        .iter()
        .map(String::as_str)
        .filter(|m| candidates.iter().all(|(_, rows)| rows.iter().any(|(model, _)| model == m)))
        .collect();
    if shared.is_empty() {
        return None;
    }
    let floor = |rows: &[(&str, &Quality)]| {
        rows.iter().filter(|(m, _)| shared.contains(m)).map(|(_, q)| q.dihedral[0]).fold(f64::INFINITY, f64::min)
    };
    let declares = |tool: &str| tool == STUFFING;
    let (best, best_floor) = candidates.iter().map(|(t, rows)| (t.as_str(), floor(rows))).max_by(|a, b| {
        let key = |(t, f): &(&str, f64)| f + if declares(t) { 0.1 } else { 0.0 };
        key(a).total_cmp(&key(b))
    })?;
    let others: Vec<String> =
        candidates.iter().filter(|(t, _)| t != best).map(|(t, rows)| format!("{t} {:.1}°", floor(rows))).collect();
    let left_out: Vec<&str> = all
        .iter()
        .filter(|(t, rows)| !candidates.iter().any(|(c, _)| c == t) && !rows.is_empty())
        .map(|(t, _)| t.as_str())
        .collect();
    let mut why = format!(
        "Of the meshers whose boundary lies on each closed model's surface (every boundary vertex within {ON_SURFACE_H} h) \
         with no inverted tetrahedron, over the {} models all of them meshed, it has the highest worst minimum dihedral angle, \
         {best_floor:.1}°{}",
        shared.len(),
        if others.is_empty() { String::new() } else { format!(" ({})", others.join(", ")) }
    );
    if declares(best) {
        why.push_str(&format!(", and it declares every angle within {:.1}-{:.1}°", data.declared[0], data.declared[1]));
    }
    why.push('.');
    let failed: Vec<String> = peers
        .map(|p| p.rows.iter().filter(|r| r.quality.is_none()).map(|r| format!("{} on {}", r.tool, r.model)).collect())
        .unwrap_or_default();
    if !failed.is_empty() {
        why.push_str(&format!(" No mesh from {}.", and_list(&failed)));
    }
    if !left_out.is_empty() {
        why.push_str(&format!(" Not a mesh of the surface or inverting somewhere: {}.", left_out.join(", ")));
    }
    Some(Choice { pick: best.to_owned(), why, pages: vec![NAME] })
}

/// The label maps' part: lattice cleaving against CGAL Mesh_3 on labeled images.
fn labels_section(labels: Option<&Labels>) -> String {
    let Some(l) = labels else {
        return "_The label maps' data (`data/quality_tets_labels.json`) is missing: run \
                `tests/reference/mesh3/labeled_vs_cleaving.py`._\n\n"
            .into();
    };
    let mut s = String::from("### Label maps: `lattice-cleaving` and CGAL Mesh_3 on labeled images\n\n");
    s.push_str(&format!(
        "Run at `{}`{} on {}, {} (isolab {}{}). Each map is meshed by `isolab.mesh_labels(..., \
         algorithm=\"lattice-cleaving\")` on one thread, every run kept and timed around the whole call, and by CGAL Mesh_3's \
         labeled image domain (`tests/reference/mesh3/cgal_labeled_image.cpp`: facet angle and radius-edge bounds of its \
         example, facet size equal to the cell size), one-shot in a fresh process on one thread, timed around `make_mesh_3` \
         alone, its cell size scaled until its count is near ours. Both are measured here alike.\n\n",
        l.commit,
        if l.dirty { " (with uncommitted changes)" } else { "" },
        l.cpu,
        l.date,
        l.isolab,
        [
            ("cores", l.cores.map(|c| c.to_string())),
            ("", l.os.clone()),
            ("Python", l.python.clone()),
            ("numpy", l.numpy.clone()),
            ("", l.compiler.clone())
        ]
        .into_iter()
        .filter_map(|(k, v)| v.map(|v| if k.is_empty() { format!("; {v}") } else { format!("; {k} {v}") }))
        .collect::<String>(),
    ));
    let row = |r: &LabelRow| -> Vec<String> {
        if let Some(e) = &r.error {
            return vec![
                r.input.clone(),
                r.tool.clone(),
                format!("failed: {e}"),
                String::new(),
                String::new(),
                String::new(),
                String::new(),
            ];
        }
        let worst = r.volume_error.values().map(|v| v.abs()).fold(0.0, f64::max);
        vec![
            r.input.clone(),
            r.tool.clone(),
            r.tetrahedra.to_string(),
            format!("{:.1}-{:.1}°", r.dihedral[0], r.dihedral[1]),
            r.inverted.to_string(),
            format!("{:.1}%", 100.0 * worst),
            {
                let sp = Spread::of(r.ms.clone());
                if r.ms.len() > 1 {
                    format!("{} ({}-{})", crate::report::ms(sp.median), crate::report::ms(sp.min), crate::report::ms(sp.max))
                } else {
                    crate::report::ms(sp.median)
                }
            },
        ]
    };
    let rows: Vec<Vec<String>> = l.rows.iter().map(row).collect();
    s.push_str(&markdown_table(
        &["map", "mesher", "tetrahedra", "dihedral angles", "inverted", "largest label volume error", "time, ms"],
        &rows,
    ));
    let ratios: Vec<String> = first_seen(l.rows.iter().map(|r| r.input.as_str()))
        .into_iter()
        .filter_map(|input| {
            let ours = l.rows.iter().find(|r| r.input == input && r.tool == "lattice-cleaving" && r.error.is_none())?;
            let cgal = l.rows.iter().find(|r| r.input == input && r.tool != "lattice-cleaving" && r.error.is_none())?;
            let (a, b) = (Spread::of(ours.ms.clone()).median, Spread::of(cgal.ms.clone()).median);
            if !(a > 0.0 && b.is_finite()) {
                return None;
            }
            Some(format!(
                "{input}: CGAL's time over ours {:.0}x at {} tetrahedra against our {}",
                b / a,
                cgal.tetrahedra,
                ours.tetrahedra
            ))
        })
        .collect();
    if !ratios.is_empty() {
        s.push_str(&format!(
            "\n{}. The issue asks for at most a tenth of CGAL's time at a comparable count.\n\n",
            ratios.join("; ")
        ));
    }
    s
}
