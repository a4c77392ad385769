//! The front page's "Choosing an extractor": one recommendation per use case, each picked from
//! the experiments' data files by a rule the sentence states, with the numbers behind it.
//!
//! Every use case is a pure function from the data of the experiments it draws on to a
//! [`Choice`]; [`section`] reads the data and renders them. A use case whose data is missing says
//! so instead of recommending. Nothing here is measured: rerun the experiments to change a pick.

use super::context::{Context, ExperimentError};
use super::{
    compare_algorithms, decimation, real_volumes, segmentations, sharp_features, sphere_convergence, stuart_tables, terrain_edit,
};
use crate::report::first_seen;

/// The bound on the sphere's relative volume error used to compare triangle counts at equal
/// accuracy (use case "fewest triangles").
pub const VOLUME_ERROR_TARGET: f64 = 1e-3;

/// One use case's recommendation.
#[derive(Clone, Debug, PartialEq)]
pub struct Choice {
    /// The extractor (or mesher) recommended.
    pub pick: String,
    /// The sentences that justify it, with their numbers (Markdown).
    pub why: String,
    /// The report pages the numbers come from.
    pub pages: Vec<&'static str>,
}

/// A use case: its heading and how it picks.
struct UseCase {
    title: &'static str,
    choose: fn(&Context) -> Result<Choice, ExperimentError>,
}

const USE_CASES: [UseCase; 8] = [
    UseCase { title: "Deformable game terrain", choose: |ctx| terrain(&ctx.read_data("terrain_edit")?) },
    UseCase { title: "Scans (a real MRI)", choose: |ctx| scans(&ctx.read_data("real_volumes")?) },
    UseCase { title: "Segmentations (label maps)", choose: |ctx| label_maps(&ctx.read_data("segmentations")?) },
    UseCase {
        title: "Sharp CAD shapes",
        choose: |ctx| sharp(&ctx.read_data("sharp_features")?, &ctx.read_data("compare_algorithms")?),
    },
    UseCase {
        title: "Coarse tetrahedral volumes",
        choose: |ctx| tetrahedra(&ctx.read_data("stuart_tables")?, &ctx.read_data("stuart_tables_peers")?),
    },
    UseCase { title: "Tetrahedra for simulation", choose: super::quality_tets::pick },
    UseCase { title: "Tetrahedra for a whole segmentation", choose: super::quality_tets::pick_labels },
    UseCase {
        title: "Fewest triangles at a given error",
        choose: |ctx| {
            fewest(&ctx.read_data("sphere_convergence")?, &ctx.read_data("decimation")?, &ctx.read_data("compare_algorithms")?)
        },
    },
];

/// The front page's section.
pub fn section(ctx: &Context) -> String {
    let mut md = String::from("## Choosing an extractor\n\n");
    md.push_str(
        "Each recommendation is picked from the experiments' data by the rule it states; the numbers behind it \
         link to the page that measured them.\n\n",
    );
    for case in &USE_CASES {
        match (case.choose)(ctx) {
            Ok(c) => {
                let links: Vec<String> = c.pages.iter().map(|p| format!("[{p}]({p}.md)")).collect();
                md.push_str(&format!("- **{}: `{}`.** {} ({})\n", case.title, c.pick, c.why, links.join(", ")));
            }
            Err(e) => md.push_str(&format!("- **{}:** _no recommendation yet: {e}_\n", case.title)),
        }
    }
    md.push('\n');
    md
}

fn missing(what: &str) -> ExperimentError {
    ExperimentError::Missing(format!("the data has no {what}"))
}

/// A game terrain: after every one of the scripted edits the chunk seams stay closed (no open
/// seam edge) and the welded mesh manifold, and one chunk re-meshes within the per-chunk budget on
/// one thread (p99) at some chunk size (the largest that fits is the one to use); among those, the
/// best-shaped triangles on the chunked, edited mesh itself (lowest mean aspect ratio), fewer
/// triangles on a tie. The pick's levels of detail and liquids are tried, not looked up.
fn terrain(edits: &terrain_edit::Data) -> Result<Choice, ExperimentError> {
    let fitting = |r: &terrain_edit::Run| {
        r.chunk_runs.iter().filter(|c| c.chunk_ms[1] <= terrain_edit::CHUNK_BUDGET_MS).max_by_key(|c| c.chunk).cloned()
    };
    let closed = |r: &terrain_edit::Run| {
        r.manifold_after && r.open_seam_edges_max == 0 && r.chunk_runs.iter().all(|c| c.open_seam_edges == 0)
    };
    let candidates: Vec<_> = edits.runs.iter().filter(|r| closed(r)).filter_map(|r| fitting(r).map(|c| (r, c))).collect();
    let (run, chunk) = candidates
        .iter()
        .min_by(|(a, _), (b, _)| {
            let key = |r: &terrain_edit::Run| (r.quality_after[0], r.triangles[1]);
            key(a).partial_cmp(&key(b)).unwrap_or(std::cmp::Ordering::Equal)
        })
        .ok_or_else(|| missing("extractor whose edited terrain stays closed within the per-chunk budget"))?;
    let sizes: Vec<String> = candidates.iter().map(|(r, c)| format!("`{}` {}³", r.algorithm, c.chunk)).collect();
    let mut why = format!(
        "Of the {} extractors whose chunk seams stay closed after each of {} brush edits (no open seam edge) and that \
         re-mesh one chunk within {:.1} ms on one thread (p99) at some chunk size (the largest that fits: {}), it has the \
         best-shaped triangles on the edited, chunked mesh (mean aspect ratio {:.2}, smallest angle {:.1}°); at {}³ cells \
         one chunk takes {:.2} ms median, {:.2} ms p99 on one thread.",
        candidates.len(),
        run.edit_ms.len(),
        terrain_edit::CHUNK_BUDGET_MS,
        sizes.join(", "),
        run.quality_after[0],
        run.quality_after[1],
        chunk.chunk,
        chunk.chunk_ms[0],
        chunk.chunk_ms[1],
    );
    let lightest = edits.runs.iter().filter(|r| closed(r)).min_by_key(|r| r.triangles[1]);
    if let Some(l) = lightest.filter(|l| l.algorithm != run.algorithm) {
        why.push_str(&format!(
            " `{}` makes the fewest triangles ({:.2}x as many; mean aspect ratio {:.2}).",
            l.algorithm,
            l.triangles[1] as f64 / run.triangles[1].max(1) as f64,
            l.quality_after[0],
        ));
    }
    let pick = isolab_algorithms::extractors::by_name(&run.algorithm).ok_or_else(|| missing("the pick in the registry"))?;
    let lod = lod_support(pick.as_ref());
    let liquids =
        isolab_algorithms::liquids::extract_layers(pick.as_ref(), &isolab_algorithms::liquids::lake_and_cave(LIQUID_PROBE))
            .map_or("no (its vertices are inside cells)", |_| "yes (`terrain_liquids`)");
    if !run.settings.is_empty() {
        why.push_str(&format!(" It ran with {}.", run.settings));
    }
    why.push_str(&format!(" Crack-free levels of detail (`terrain_lod`): {lod}. Liquids beside the solid: {liquids}."));
    Ok(Choice { pick: run.algorithm.clone(), why, pages: vec!["terrain_edit", "terrain_lod", "terrain_liquids"] })
}

/// Samples along x and y of the scene the liquids probe meshes.
const LIQUID_PROBE: usize = 12;

/// Whether `chunks::lod` stitches `extractor`'s levels of detail, from its declared capability
/// (which `tests/tests/lod.rs` checks against what `extract_lod` does).
fn lod_support(extractor: &dyn isolab_algorithms::Extractor) -> String {
    match extractor.levels_of_detail() {
        isolab_algorithms::LevelsOfDetail::Unsupported(why) => format!("no ({why})"),
        method => format!("yes ({})", method.method()),
    }
}

/// A scan: the fastest of our extractors (one thread, every iso-level summed) whose meshes are
/// closed, manifold, outward and free of self-intersections at every level; the best-shaped of
/// those and the reasons the others fail are named.
fn scans(data: &real_volumes::Data) -> Result<Choice, ExperimentError> {
    let ours = first_seen(data.rows.iter().filter(|r| r.ours).map(|r| r.implementation.as_str()));
    let rows = |name: &str| -> Vec<&real_volumes::Row> { data.rows.iter().filter(|r| r.implementation == name).collect() };
    let clean = |r: &real_volumes::Row| r.closed && r.manifold && r.outward && r.self_intersections == 0;
    let total_ms = |name: &str| rows(name).iter().map(|r| r.time_1.median).sum::<f64>();
    let mean_aspect = |name: &str| {
        let (n, s) = rows(name).iter().fold((0usize, 0.0), |(n, s), r| (n + 1, s + r.aspect_mean));
        s / n.max(1) as f64
    };
    let good: Vec<&str> = ours.iter().copied().filter(|&n| rows(n).iter().all(|r| clean(r))).collect();
    let pick = *good
        .iter()
        .min_by(|a, b| total_ms(a).total_cmp(&total_ms(b)))
        .ok_or_else(|| missing("extractor with clean meshes at every level"))?;
    let levels: Vec<&str> = data.levels.iter().map(|l| l.name.as_str()).collect();
    let mut why = format!(
        "On the MNI152 T1 brain at its {} iso-levels ({}), the fastest of our extractors whose meshes are closed, \
         manifold, outward and free of self-intersections at every level: {:.1} ms on one thread for all levels",
        levels.len(),
        levels.join(", "),
        total_ms(pick),
    );
    let peers = first_seen(data.rows.iter().filter(|r| !r.ours).map(|r| r.implementation.as_str()));
    if let Some(peer) = peers.iter().min_by(|a, b| total_ms(a).total_cmp(&total_ms(b))) {
        why.push_str(&format!(" (`{peer}`: {:.1} ms).", total_ms(peer)));
    } else {
        why.push('.');
    }
    if let Some(shaped) = good.iter().min_by(|a, b| mean_aspect(a).total_cmp(&mean_aspect(b))) {
        if *shaped != pick {
            why.push_str(&format!(
                " `{shaped}` has the best-shaped triangles of those (mean aspect ratio {:.2} against {:.2}) at {:.1} ms.",
                mean_aspect(shaped),
                mean_aspect(pick),
                total_ms(shaped),
            ));
        }
    }
    // Topology inside the cells: whether the pick follows the trilinear interpolant's (each
    // extractor's registered guarantee), and the fastest clean one that does if it does not.
    let trilinear =
        |name: &str| isolab_algorithms::extractors::INFOS.iter().any(|i| i.name == name && i.guarantees.trilinear_topology);
    if trilinear(pick) {
        why.push_str(" Every cell of it has the topology of the trilinear interpolant's level set.");
    } else if let Some(faithful) = good.iter().filter(|n| trilinear(n)).min_by(|a, b| total_ms(a).total_cmp(&total_ms(b))) {
        why.push_str(&format!(
            " Where every cell must have the topology of the trilinear interpolant's level set (its tunnels included),              `{faithful}`, clean at every level too: {:.1} ms.",
            total_ms(faithful)
        ));
    }
    let failed: Vec<String> = ours
        .iter()
        .filter(|n| !good.contains(n))
        .filter_map(|n| rows(n).into_iter().find(|r| !clean(r)).map(|r| (n, r)))
        .map(|(n, r)| format!("`{n}` at {}: {}", r.level, defect(r)))
        .collect();
    if !failed.is_empty() {
        why.push_str(&format!(" Left out: {}.", failed.join("; ")));
    }
    Ok(Choice { pick: pick.into(), why, pages: vec!["real_volumes"] })
}

/// Label maps: among our label extractors, the fastest (total one-thread median over the inputs)
/// whose every label's mesh is closed and manifold on every input (ours share their interfaces by
/// construction); a faster one of ours that is not is named with its non-manifold count.
fn label_maps(data: &segmentations::Data) -> Result<Choice, ExperimentError> {
    let one: Vec<&segmentations::Row> = data.rows.iter().filter(|r| r.threads == 1).collect();
    let ours = first_seen(one.iter().filter(|r| r.implementation.starts_with("isolab ")).map(|r| r.implementation.as_str()));
    let rows = |name: &str| -> Vec<&segmentations::Row> { one.iter().copied().filter(|r| r.implementation == name).collect() };
    let total_ms = |name: &str| rows(name).iter().map(|r| segmentations::median_ms(r)).sum::<f64>();
    let clean = |r: &segmentations::Row| r.labels_closed == Some(r.labels) && r.labels_manifold == Some(r.labels);
    let good: Vec<&str> = ours.iter().copied().filter(|&n| rows(n).iter().all(|r| clean(r))).collect();
    let pick = *good
        .iter()
        .min_by(|a, b| total_ms(a).total_cmp(&total_ms(b)))
        .ok_or_else(|| missing("label extractor closed and manifold on every map"))?;
    let inputs = first_seen(one.iter().map(|r| r.input.as_str()));
    let mut why = format!(
        "On {} label maps ({}), the fastest of our label extractors whose every label's mesh is closed and manifold (the \
         meshes of two labels share their interface triangles): {:.1} ms on one thread for all maps",
        inputs.len(),
        inputs.join(", "),
        total_ms(pick)
    );
    let faster: Vec<String> = ours
        .iter()
        .filter(|n| !good.contains(n) && total_ms(n) < total_ms(pick))
        .map(|n| {
            let defects: usize = rows(n).iter().filter_map(|r| r.non_manifold).sum();
            format!("`{n}` ({:.1} ms) leaves {defects} non-manifold edges and vertices where three labels meet", total_ms(n))
        })
        .collect();
    why.push_str(if faster.is_empty() { "." } else { "; faster, " });
    if !faster.is_empty() {
        why.push_str(&format!("{}.", faster.join("; ")));
    }
    Ok(Choice { pick: pick.into(), why, pages: vec!["segmentations"] })
}

/// What makes a real-volume mesh unclean, in words.
fn defect(r: &real_volumes::Row) -> String {
    let mut d = Vec::new();
    if r.self_intersections > 0 {
        d.push(format!("{} self-intersecting pairs", r.self_intersections));
    }
    if !r.closed {
        d.push("open".into());
    }
    if !r.manifold {
        d.push("not manifold".into());
    }
    if !r.outward {
        d.push("inward".into());
    }
    d.join(", ")
}

/// Sharp CAD: among manifold meshes free of self-intersections on the `csg` shape in every
/// placement at the finest resolution (each extractor's worst placement), those as sharp as the
/// sharpest (every corner within [`sharp_features::CORNER_KEPT_H`], or within [`SHARP_TIE`] of the
/// sharpest's worst corner); of these, the sharpest free of self-intersections on every compared
/// input too, else the sharpest overall. The self-intersections of a pick that has some are
/// stated, since sharpness is bought with vertex placement.
fn sharp(data: &sharp_features::Data, compared: &compare_algorithms::Data) -> Result<Choice, ExperimentError> {
    let finest = data.rows.iter().map(|r| r.resolution).max().ok_or_else(|| missing("sharp-feature rows"))?;
    let worst = sharp_features::worst_over_shapes(&data.rows, finest);
    let shapes = first_seen(data.rows.iter().map(|r| r.shape.as_str()));
    let on = if shapes.len() > 1 {
        format!("On the `csg` shape in its {} placements ({}), the worst of them,", shapes.len(), shapes.join(", "))
    } else {
        "On the `csg` shape".to_owned()
    };
    let mut at: Vec<&sharp_features::Row> = worst.iter().filter(|r| r.manifold && r.self_intersections == 0).collect();
    at.sort_by(|a, b| a.worst_corner_h.total_cmp(&b.worst_corner_h));
    let sharpest = *at.first().ok_or_else(|| missing("clean sharp-feature row"))?;
    let clean_everywhere = |r: &&&sharp_features::Row| compared.intersections(&r.algorithm).all_pairs == 0;
    // As sharp as the sharpest: within the kept-corner bound, or within a tenth of the sharpest's
    // worst corner when no mesh keeps every corner.
    let threshold = sharp_features::CORNER_KEPT_H.max(sharpest.worst_corner_h * (1.0 + SHARP_TIE));
    let keeping: Vec<&sharp_features::Row> = at.iter().copied().filter(|r| r.worst_corner_h <= threshold).collect();
    let best = keeping.iter().find(clean_everywhere).copied().unwrap_or(sharpest);
    let mut why = if best.algorithm == sharpest.algorithm {
        format!(
            "{on} at {finest} samples, the smallest distance from a true corner to the mesh among clean \
             meshes: {} h at the worst corner",
            spacings(best.worst_corner_h)
        )
    } else {
        format!(
            "{on} at {finest} samples, of the clean meshes that come within {} h of every corner, the one \
             free of self-intersections on every compared input at every resolution too: {} h at the worst corner (`{}`, \
             the sharpest, {} h, has {} self-intersecting pairs on the compared inputs at the middle resolution, {} over \
             every resolution)",
            spacings(threshold),
            spacings(best.worst_corner_h),
            sharpest.algorithm,
            spacings(sharpest.worst_corner_h),
            compared.intersections(&sharpest.algorithm).middle_pairs,
            compared.intersections(&sharpest.algorithm).all_pairs
        )
    };
    if let Some(next) = at.iter().find(|r| r.worst_corner_h > threshold.max(best.worst_corner_h)) {
        why.push_str(&format!(", against {} h for the next best, `{}`.", spacings(next.worst_corner_h), next.algorithm));
    } else {
        why.push('.');
    }
    why.push_str(&intersection_caveat(&best.algorithm, compared));
    why.push_str(&time_split(&best.algorithm, compared));
    Ok(Choice { pick: best.algorithm.clone(), why, pages: vec!["sharp_features", "compare_algorithms"] })
}

/// Meshes whose worst corner is within this fraction of the sharpest's count as sharp as it (the
/// sharp-CAD pick then prefers one free of self-intersections).
const SHARP_TIE: f64 = 0.1;

/// A sentence on `algorithm`'s self-intersecting pairs over the compared inputs, at the middle
/// resolution and over every resolution, or nothing when it has none.
fn intersection_caveat(algorithm: &str, compared: &compare_algorithms::Data) -> String {
    let i = compared.intersections(algorithm);
    if i.all_pairs == 0 {
        return String::new();
    }
    format!(
        " Its vertex placement costs self-intersections elsewhere: {} pairs on {} of the {} compared inputs at the middle \
         resolution, {} pairs on {} of its {} meshes over every resolution.",
        i.middle_pairs, i.middle_hit, i.middle_inputs, i.all_pairs, i.all_hit, i.all_meshes
    )
}

/// A sentence splitting `algorithm`'s median extraction time at the middle resolution between its
/// field queries and the rest (the glance table's two time columns), or nothing when the data has
/// no split.
fn time_split(algorithm: &str, compared: &compare_algorithms::Data) -> String {
    let (level, model_level) = compared.middle_levels();
    let rows: Vec<&super::Measured> = compared
        .rows
        .iter()
        .filter(|r| r.algorithm == algorithm && (r.resolution == level || r.resolution == model_level))
        .filter(|r| r.without_field_ms.is_some())
        .collect();
    if rows.is_empty() {
        return String::new();
    }
    let with = crate::report::Spread::of(rows.iter().map(|r| r.extraction_ms).collect()).median;
    let without = crate::report::Spread::of(rows.iter().filter_map(|r| r.without_field_ms).collect()).median;
    format!(
        " Its median extraction time over the {} compared inputs at the middle resolution, {} ms, is {} ms on the same \
         samples with the field withheld (gradients from the samples' interpolant): the rest is its queries of the field.",
        rows.len(),
        super::ms(with),
        super::ms(without)
    )
}

/// A distance in grid spacings: two decimals, or two significant digits when smaller.
fn spacings(v: f64) -> String {
    if v == 0.0 || v >= 0.01 {
        format!("{v:.2}")
    } else {
        format!("{v:.1e}")
    }
}

/// Coarse tetrahedral volumes: the mesher whose worst minimum dihedral angle over the models every
/// mesher meshed is highest; tetrahedron counts against each peer are stated (every peer meshes the
/// offset surface ours stops within).
fn tetrahedra(data: &stuart_tables::Data, peers: &stuart_tables::Peers) -> Result<Choice, ExperimentError> {
    let ours: Vec<&stuart_tables::Row> =
        data.rows.iter().filter(|r| r.cells == stuart_tables::TABLE2_CELLS && r.ratio == stuart_tables::TABLE2_RATIO).collect();
    // The CGAL run matched to our count is the same mesher at another size: it speaks in the
    // against-the-paper sentence, not as a mesher of its own.
    let tools: Vec<&str> = first_seen(peers.rows.iter().map(|p| p.tool.as_str()))
        .into_iter()
        .filter(|t| *t != stuart_tables::CGAL_MATCHED)
        .collect();
    let peer = |tool: &str, model: &str| {
        peers.rows.iter().find(|p| p.tool == tool && p.model == model).and_then(|p| Some((p.tetrahedra?, p.dihedral_min?)))
    };
    let shared: Vec<&stuart_tables::Row> =
        ours.iter().copied().filter(|r| tools.iter().all(|t| peer(t, &r.model).is_some())).collect();
    if shared.is_empty() {
        return Err(missing("model meshed by every tetrahedral mesher"));
    }
    let worst = |v: &mut dyn Iterator<Item = f64>| v.fold(f64::INFINITY, f64::min);
    let mut scores: Vec<(String, f64)> = vec![("bcc-sculpt".into(), worst(&mut shared.iter().map(|r| r.min_dihedral)))];
    for t in &tools {
        scores.push((t.to_string(), worst(&mut shared.iter().filter_map(|r| peer(t, &r.model)).map(|p| p.1))));
    }
    let (pick, floor) = scores.iter().max_by(|a, b| a.1.total_cmp(&b.1)).cloned().ok_or_else(|| missing("scores"))?;
    let mut why = format!(
        "Over the {} of the {} shipped models every mesher meshed{}, the highest worst minimum dihedral angle: {floor:.1}°",
        shared.len(),
        ours.len(),
        unmeshed(&ours, &tools, &|t, m| peer(t, m).is_some())
    );
    let others: Vec<String> = scores.iter().filter(|s| s.0 != pick).map(|(t, f)| format!("{t} {f:.1}°")).collect();
    why.push_str(&format!(" ({}).", others.join(", ")));
    if pick == "bcc-sculpt" {
        for t in &tools {
            let ratios = stuart_tables::tet_ratios(&data.rows, peers, t);
            if let (Some(lo), Some(hi)) = (ratios.iter().copied().reduce(f64::min), ratios.iter().copied().reduce(f64::max)) {
                why.push_str(&format!(" Tetrahedra, ours / {t}'s: {lo:.2}-{hi:.2}x."));
            }
        }
        why.push_str(&format!(
            " Ours at h = longest side / {}, offset ratio {}; the peers mesh the offset surface at that distance.",
            stuart_tables::TABLE2_CELLS,
            stuart_tables::TABLE2_RATIO
        ));
        let unfloored = worst(
            &mut data
                .ablation
                .iter()
                .filter(|a| a.variant == stuart_tables::NO_FLOOR_VARIANT && shared.iter().any(|r| r.model == a.model))
                .map(|a| a.dihedral[0]),
        );
        if unfloored.is_finite() {
            why.push_str(&format!(
                " That angle is bought by our relaxation's {}° quality floor (`quality-floor`), which the paper does not have: \
                 the paper's update alone reaches {unfloored:.1}° worst over the same models (one unperturbed lattice each, \
                 the page's ablation).",
                isolab_algorithms::extractors::bcc_sculpt::SculptOptions::default().quality_floor
            ));
        }
        if let Some(c) = stuart_tables::cgal_count_against_paper(&data.rows, peers) {
            why.push_str(&format!(" Against the paper, over all {} models: {c}", ours.len()));
        }
        why.push_str(&convergence_misses(&stuart_tables::convergence_short_of_paper(&data.rows)));
    }
    Ok(Choice { pick, why, pages: vec!["stuart_tables"] })
}

/// `" (not the stanford-bunny: NETGEN failed)"`-style clause naming the models some mesher did not
/// mesh, empty when every mesher meshed every model.
fn unmeshed(ours: &[&stuart_tables::Row], tools: &[&str], meshed: &dyn Fn(&str, &str) -> bool) -> String {
    let missed: Vec<String> = ours
        .iter()
        .filter_map(|r| {
            let failed: Vec<&str> = tools.iter().copied().filter(|t| !meshed(t, &r.model)).collect();
            (!failed.is_empty()).then(|| format!("`{}`: no mesh from {}", r.model, failed.join(", ")))
        })
        .collect();
    if missed.is_empty() {
        String::new()
    } else {
        format!(" (left out: {})", missed.join("; "))
    }
}

/// The sentence on where `bcc-sculpt` converges less often than the paper's Table 1, from
/// [`stuart_tables::convergence_short_of_paper`]; empty when it falls short nowhere.
fn convergence_misses(short: &[(f32, usize, usize, usize, usize)]) -> String {
    if short.is_empty() {
        return String::new();
    }
    let ours: Vec<String> =
        short.iter().map(|(ratio, oc, on, _, _)| format!("at offset ratio {ratio} on {oc} of {on} runs")).collect();
    let paper: Vec<String> = short.iter().map(|(_, _, _, pc, pn)| format!("{pc} of {pn}")).collect();
    format!(
        " Where it falls short: over the paper's Table 1 grid (every model, spacing and ratio) it converges {}, against the \
         paper's {}; an unconverged run keeps the best mesh it reached.",
        crate::report::and_list(&ours),
        crate::report::and_list(&paper)
    )
}

/// Triangles an extractor needs on the sphere for `|volume error| <= target`, by log-log
/// interpolation between the two resolutions that bracket it; `None` if no resolution reaches it.
/// The second value says whether the coarsest resolution already did (then the count is an upper
/// bound).
pub fn triangles_at_error(points: &[(usize, f64)], target: f64) -> Option<(f64, bool)> {
    let mut pts: Vec<(f64, f64)> = points.iter().map(|&(t, e)| (t as f64, e.abs())).collect();
    pts.sort_by(|a, b| a.0.total_cmp(&b.0));
    let first = *pts.first()?;
    if first.1 <= target {
        return Some((first.0, true));
    }
    pts.windows(2).find(|w| w[0].1 > target && w[1].1 <= target).map(|w| {
        let (t0, e0, t1, e1) = (w[0].0.ln(), w[0].1.ln(), w[1].0.ln(), w[1].1.max(f64::MIN_POSITIVE).ln());
        let s = if (e1 - e0).abs() > 0.0 { (target.ln() - e0) / (e1 - e0) } else { 1.0 };
        ((t0 + s * (t1 - t0)).exp(), false)
    })
}

/// Fewest triangles at a given error: on the sphere, the extractor needing the fewest triangles to
/// bring the volume error under [`VOLUME_ERROR_TARGET`]; for reducing a finished mesh, the
/// decimator with the smallest Hausdorff distance on the most objects at equal count.
fn fewest(
    convergence: &sphere_convergence::Data,
    decimation: &decimation::Data,
    compared: &compare_algorithms::Data,
) -> Result<Choice, ExperimentError> {
    let names = first_seen(convergence.rows.iter().map(|r| r.algorithm.as_str()));
    let mut needs: Vec<(&str, f64, bool)> = names
        .iter()
        .filter_map(|&n| {
            let pts: Vec<(usize, f64)> =
                convergence.rows.iter().filter(|r| r.algorithm == n).map(|r| (r.triangles, r.volume_error)).collect();
            triangles_at_error(&pts, VOLUME_ERROR_TARGET).map(|(t, bound)| (n, t, bound))
        })
        .collect();
    needs.sort_by(|a, b| a.1.total_cmp(&b.1));
    let (pick, t, bound) = *needs.first().ok_or_else(|| missing("sphere row within the volume-error target"))?;
    let mut why = format!(
        "To bring the sphere's volume within {}% of the analytic volume it needs {}{:.0} triangles",
        VOLUME_ERROR_TARGET * 100.0,
        if bound { "at most " } else { "about " },
        t
    );
    let others: Vec<String> =
        needs.iter().skip(1).map(|(n, tn, _)| format!("`{n}` {:.0} ({:.1}x)", tn, tn / t.max(1.0))).collect();
    if !others.is_empty() {
        why.push_str(&format!(", against {}", others.join(", ")));
    }
    why.push_str(" (interpolated between resolutions in log-log).");
    why.push_str(&intersection_caveat(pick, compared));
    why.push_str(&time_split(pick, compared));
    let objects = first_seen(decimation.rows.iter().map(|r| (r.object.as_str(), r.target)));
    let mut wins: Vec<(&str, usize)> = Vec::new();
    for (object, target) in &objects {
        let best = decimation
            .rows
            .iter()
            .filter(|r| r.object == *object && r.target == *target && r.manifold && r.self_intersections == 0)
            .min_by(|a, b| a.hausdorff_h.total_cmp(&b.hausdorff_h));
        if let Some(b) = best {
            match wins.iter_mut().find(|w| w.0 == b.decimator) {
                Some(w) => w.1 += 1,
                None => wins.push((&b.decimator, 1)),
            }
        }
    }
    if let Some((d, k)) = wins.iter().max_by_key(|w| w.1) {
        why.push_str(&format!(
            " To reduce a finished mesh, {d} has the smallest Hausdorff distance at equal triangle count, among \
             manifold results free of self-intersections, in {k} of {} decimations.",
            objects.len()
        ));
        why.push_str(&sliver_caveat(d, &decimation.rows));
    }
    Ok(Choice { pick: pick.into(), why, pages: vec!["sphere_convergence", "decimation", "compare_algorithms"] })
}

/// The smallest triangle angle `decimator` leaves over every decimation, where, and the
/// decimator whose worst smallest angle is largest: a decimator picked for its distance can
/// still leave slivers.
fn sliver_caveat(decimator: &str, rows: &[decimation::Row]) -> String {
    let worst_of =
        |name: &str| rows.iter().filter(|r| r.decimator == name).min_by(|a, b| a.min_angle_deg.total_cmp(&b.min_angle_deg));
    let Some(worst) = worst_of(decimator) else { return String::new() };
    let mut s = format!(
        " Its smallest triangle angle falls to {:.3}° at worst ({}, {} triangles)",
        worst.min_angle_deg, worst.object, worst.target
    );
    let best = first_seen(rows.iter().map(|r| r.decimator.as_str()))
        .into_iter()
        .filter_map(worst_of)
        .max_by(|a, b| a.min_angle_deg.total_cmp(&b.min_angle_deg));
    match best {
        Some(b) if b.decimator != decimator => {
            s.push_str(&format!(", where {} keeps {:.1}° at its worst ({}).", b.decimator, b.min_angle_deg, b.object))
        }
        _ => s.push('.'),
    }
    s
}

#[cfg(test)]
mod tests;
