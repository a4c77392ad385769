//! The `terrain_liquids` page: the method paragraph, the reading and the untangling's cost
//! (generated from the rows), the scene's table and the edit script's.

use super::data::{Data, EditRun, Row};
use super::{EDIT_CHUNK, NAME, RUNS};
use crate::experiment::context::{Context, ExperimentError};
use crate::report::markdown_table;
use isolab_metrics::layers::LayerContact;

/// The page, from the data file alone.
pub(super) fn section(ctx: &Context) -> Result<String, ExperimentError> {
    Ok(page(&ctx.read_data(NAME)?))
}

/// The page's opening reading: who keeps the layers clean with the rule, what the naive two
/// meshes leave, and what the edit script keeps (closed layers, crossings, the mass books).
fn reading(d: &Data) -> String {
    if d.rows.is_empty() {
        return String::new();
    }
    let clean = |c: &LayerContact| c.unshared == 0 && c.crossing_pairs == 0 && c.liquid_inside_solid == 0;
    let said = |v: Vec<String>| crate::report::listed(&v);
    let mut lines = vec![format!(
        "With the shared-vertex rule, layers that share every contact vertex, never cross and hold no liquid inside the \
         solid: {}; layers that cross: {}.",
        said(d.rows.iter().filter(|r| clean(&r.contact)).map(|r| r.method.clone()).collect()),
        said(
            d.rows
                .iter()
                .filter(|r| r.contact.crossing_pairs > 0)
                .map(|r| format!("{} ({} pairs)", r.method, r.contact.crossing_pairs))
                .collect()
        )
    )];
    let n = &d.naive.contact;
    lines.push(format!(
        "Two independent meshes leave {} of {} contact vertices unshared, {} crossing pairs and {} liquid vertices inside the \
         solid.",
        n.unshared, n.contact_vertices, n.crossing_pairs, n.liquid_inside_solid
    ));
    for e in &d.edits {
        lines.push(format!(
            "Over {} edits by {}: a layer open or non-manifold after {} of them, at most {} crossing pairs and {} unshared \
             contact vertices after one, {}.",
            e.edits,
            e.extractor,
            e.open_after,
            e.worst.crossing_pairs,
            e.worst.unshared,
            if e.mass_drift == 0.0 {
                "the masses equal to the brushes' books".to_owned()
            } else {
                format!("the masses within {:.1e} (relative) of the brushes' books", e.mass_drift)
            }
        ));
    }
    format!("**Reading.** {}\n\n", lines.join(" "))
}

/// What filling the crossing cells again bought and cost, beside the rule alone (empty without
/// such rows).
fn untangling(d: &Data) -> String {
    let pairs: Vec<String> = d
        .rule_alone
        .iter()
        .filter_map(|alone| {
            let name = alone.method.split(',').next()?;
            let with = d.rows.iter().find(|r| r.method == name)?;
            Some(format!(
                "{name}: {} crossing pairs with the rule alone, {} after filling {} of {} cells again, {:.1} ms against {:.1} \
                 ({:.2}×, {} / {} triangles against {} / {})",
                alone.contact.crossing_pairs,
                with.contact.crossing_pairs,
                with.retiled_cells,
                with.crossing_cells,
                with.median_ms,
                alone.median_ms,
                with.median_ms / alone.median_ms,
                with.solid_triangles,
                with.liquid_triangles,
                alone.solid_triangles,
                alone.liquid_triangles,
            ))
        })
        .collect();
    if pairs.is_empty() {
        return String::new();
    }
    format!(" What the untangling buys and costs (median of {RUNS} runs each, alternating): {}.", pairs.join("; "))
}

/// One cell of the edit table: a measure of one extractor's run.
type Cell = dyn Fn(&EditRun) -> String;

/// The page's Markdown from the run's data.
pub(super) fn page(d: &Data) -> String {
    let [sx, sy, sz] = d.scene;
    let mut md = format!(
        "## Liquids beside solids: the marching cubes terrain post's viscosity (`{NAME}`)\n\n\
         The post keeps one base density and a viscosity in the unit interval, \"the percentage of density that is solid\": the \
         solid density is viscosity × base, the liquid density the rest, both meshed at half the maximum, and \"choosing \
         the solid geometry to keep when two vertices coexist on an edge\" joins the two meshes. Here both densities of \
         a {sx} × {sy} × {sz}-sample terrain with a lake and a half-flooded cave (`liquids::lake_and_cave`) are meshed by \
         each extractor with a vertex on every crossing lattice edge (`liquids::extract_layers`: the liquid's vertex on a \
         solid–liquid edge takes the solid's; where every corner of a liquid patch moved, the liquid takes the solid's \
         triangles there, reversed, when the patches' boundaries agree; then every cell where a liquid triangle still \
         crosses a solid one of the cell has its polygons filled again, by other triangulations of the same outlines or \
         a fan from a point inside the cell, until none crosses by exact predicates). Where that untangling acts, the \
         rule alone is run beside it, timed alternating. Checked with `metrics::layers`: contact vertices \
         (liquid vertices on a solid–liquid lattice edge), those not bit-equal to a solid vertex, triangle pairs of the two \
         meshes that cross (exact predicates), liquid vertices inside the solid. Median of {RUNS} runs; the naive row is \
         one run.\n\n"
    );
    md.push_str(&reading(d));
    md.push_str(&super::super::context::options_as_run(&d.settings));
    let yes = |b: bool| if b { "yes" } else { "**no**" }.to_owned();
    let rows: Vec<Vec<String>> = d
        .rows
        .iter()
        .chain(&d.rule_alone)
        .chain(std::iter::once(&d.naive))
        .map(|r| {
            let filled =
                if r.crossing_cells == 0 { "–".to_owned() } else { format!("{} of {}", r.retiled_cells, r.crossing_cells) };
            vec![
                r.method.clone(),
                format!("{} / {}", r.solid_triangles, r.liquid_triangles),
                format!("{} / {}", yes(r.solid_closed_manifold), yes(r.liquid_closed_manifold)),
                r.contact.contact_vertices.to_string(),
                r.contact.unshared.to_string(),
                r.contact.crossing_pairs.to_string(),
                r.contact.liquid_inside_solid.to_string(),
                filled,
                format!("{:.1}", r.median_ms),
            ]
        })
        .collect();
    md.push_str(&markdown_table(
        &[
            "method",
            "triangles (solid / liquid)",
            "closed, manifold (solid / liquid)",
            "contact vertices",
            "unshared",
            "crossing pairs",
            "liquid inside solid",
            "cells filled again (of those crossing)",
            "ms (both layers)",
        ],
        &rows,
    ));
    let shared: Vec<&Row> = d.rows.iter().collect();
    let unshared: Vec<&str> = shared.iter().filter(|r| r.contact.unshared > 0).map(|r| r.method.as_str()).collect();
    let crossing: Vec<&str> = shared.iter().filter(|r| r.contact.crossing_pairs > 0).map(|r| r.method.as_str()).collect();
    let clean: Vec<&str> = shared
        .iter()
        .filter(|r| r.contact.unshared == 0 && r.contact.crossing_pairs == 0 && r.contact.liquid_inside_solid == 0)
        .map(|r| r.method.as_str())
        .collect();
    let list = |names: &[&str]| if names.is_empty() { "none".to_owned() } else { names.join(", ") };
    md.push_str(&format!(
        "\nWith the rule, contact vertices left unshared: {}; triangles of one layer crossing the other: {}; neither, \
         and no liquid inside the solid: {}.",
        list(&unshared),
        list(&crossing),
        list(&clean),
    ));
    if !crossing.is_empty() {
        md.push_str(&format!(
            " Sharing the vertices does not keep the layers of {} apart: their pieces in a cell are not the convex hulls \
             of their crossings (marching tetrahedra's are, which is why no overlap is proved for it alone: the \
             `liquids` module doc).",
            list(&crossing)
        ));
    }
    md.push_str(&untangling(d));
    md.push('\n');
    let naive = &d.naive;
    md.push_str(&format!(
        "\nWith two independent meshes, {} of {} contact vertices are not the solid's: where the base density is full \
         at both ends of an edge the two crossings coincide anyway (viscosity one half is both densities at half the \
         maximum), elsewhere the layers part or cross ({} crossing pairs, {} liquid vertices inside the solid).\n",
        naive.contact.unshared, naive.contact.contact_vertices, naive.contact.crossing_pairs, naive.contact.liquid_inside_solid,
    ));
    if !d.refused.is_empty() {
        md.push_str(&format!(
            "\nRefused by `extract_layers`, their vertices being off the lattice edges (the rule has no edge vertex to \
             share): {}.\n",
            d.refused.join(", ")
        ));
    }
    let [ex, ey, ez] = d.edit_scene;
    let names: Vec<&str> = d.edits.iter().map(|e| e.extractor.as_str()).collect();
    let [cx, cy, cz] = d.edits.first().map_or([0; 3], |e| e.chunk_counts);
    md.push_str(&format!(
        "\n### Dig, pour, drain\n\n{n} brushes in turn dig solid, pour liquid and drain it on a {ex} × {ey} × {ez}-sample \
         scene in {EDIT_CHUNK}³-cell chunks ({cx} × {cy} × {cz}; `liquids::ChunkedLayers`, the last chunk along an axis \
         taking the cells that remain). After every edit the chunks whose samples the brush may have changed are \
         re-meshed, both layers, and the chunks' layers welded by exact position are checked, by {alg}; the pictures \
         show the first. The welded layers are the whole grid's, triangle for triangle (`tests/tests/liquids.rs`, \
         after every edit of a brush script).\n\n",
        n = d.edits.first().map_or(0, |e| e.edits),
        alg = names.join(" and by "),
    ));
    let percentiles = |e: &EditRun| {
        let mut ms = e.remesh_ms.clone();
        ms.sort_by(f64::total_cmp);
        let pct = |q: f64| ms.get(((ms.len() as f64 - 1.0) * q).round() as usize).copied().unwrap_or(f64::NAN);
        format!("{:.1}, {:.1}, {:.1}", pct(0.5), pct(0.99), pct(1.0))
    };
    let mean_chunks =
        |e: &EditRun| format!("{:.1}", e.chunks_remeshed.iter().sum::<usize>() as f64 / e.chunks_remeshed.len().max(1) as f64);
    let measures: [(&str, &Cell); 11] = [
        ("edits after which a layer was open or non-manifold", &|e| e.open_after.to_string()),
        ("contact vertices (fewest and most after an edit)", &|e| format!("{}–{}", e.fewest_contact, e.worst.contact_vertices)),
        ("most unshared contact vertices after an edit", &|e| e.worst.unshared.to_string()),
        ("most crossing pairs after an edit", &|e| e.worst.crossing_pairs.to_string()),
        ("most cells filled again after an edit (where the layers crossed after the rule)", &|e| {
            e.most_retiled_cells.to_string()
        }),
        ("most liquid vertices inside the solid after an edit", &|e| e.worst.liquid_inside_solid.to_string()),
        ("solid mass: start, dug, end", &|e| format!("{:.1}, {:.1}, {:.1}", e.solid_mass[0], e.dug, e.solid_mass[1])),
        ("liquid mass: start, poured, drained, end", &|e| {
            format!("{:.1}, {:.1}, {:.1}, {:.1}", e.liquid_mass[0], e.poured, e.drained, e.liquid_mass[1])
        }),
        ("largest relative gap between a mass and its books", &|e| format!("{:.1e}", e.mass_drift)),
        ("chunks re-meshed per edit (mean)", &mean_chunks),
        ("re-mesh of the touched chunks, both layers, ms (median, p99, max)", &percentiles),
    ];
    let rows: Vec<Vec<String>> = measures
        .iter()
        .map(|(label, cell)| std::iter::once(label.to_string()).chain(d.edits.iter().map(cell)).collect())
        .collect();
    let header: Vec<&str> = std::iter::once("measure").chain(names.iter().copied()).collect();
    md.push_str(&markdown_table(&header, &rows));
    md.push_str(&format!("\n![both layers after the edits]({})\n\n![the edits]({})\n", d.picture, d.gif));
    let drift = d.edits.iter().map(|e| e.mass_drift).fold(0.0, f64::max);
    let books = if drift == 0.0 {
        "the masses equal the brushes' books after every edit, for every extractor".to_owned()
    } else {
        format!("the masses differ from the brushes' books by at most {drift:.1e} (relative)")
    };
    md.push_str(&format!(
        "\n### Where we differ from the post: its claims beside ours\n\n\
         - *Layered meshes for liquids without overlap, connected where they meet*: the rows above (contact vertices \
         shared, crossing pairs). No overlap is proved for marching tetrahedra (`liquids` module doc); for marching \
         cubes the cells where the layers crossed are filled again, checked by exact predicates; crossing pairs left: \
         {}.\n\
         - *Solid and liquid mass conservation still works*: each brush changes one density and returns what it moved; \
         {books}.\n\
         - *Both marches in parallel*: on the whole scene the two layers are meshed one after the other, each by the \
         extractor's own parallel pass (the time is for both); in the edit script each touched chunk meshes both \
         layers in one task, the chunks in parallel.\n\
         - *Duplicate vertices removed by keeping one corner's vertices and a later index pass*: isolab's extractors make \
         one vertex per lattice edge as they go (the closed, manifold columns), and chunks weld by exact position; not \
         compared with the post's scheme.\n\
         - Not built: levels of detail for the two layers, the liquid's own material in the chunked terrain editor \
         (`terrain_edit`), and the extractors `extract_layers` refuses (listed above).\n",
        list(&crossing),
    ));
    md
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(method: &str, unshared: usize, crossing: usize) -> Row {
        Row {
            method: method.into(),
            solid_triangles: 1,
            liquid_triangles: 1,
            solid_closed_manifold: true,
            liquid_closed_manifold: true,
            contact: LayerContact { contact_vertices: 10, unshared, crossing_pairs: crossing, liquid_inside_solid: 0 },
            median_ms: 1.0,
            crossing_cells: 0,
            retiled_cells: 0,
        }
    }

    /// A run's data with `rows` and nothing else.
    fn data(rows: Vec<Row>) -> Data {
        Data {
            scene: [1, 1, 1],
            rows,
            naive: row("naive", 3, 4),
            rule_alone: Vec::new(),
            refused: Vec::new(),
            edits: Vec::new(),
            edit_scene: [1, 1, 1],
            picture: String::new(),
            gif: String::new(),
            settings: Vec::new(),
        }
    }

    #[test]
    fn the_reading_follows_the_rows() {
        let mut d = data(Vec::new());
        assert_eq!(reading(&d), "");
        d.rows = vec![row("mc", 0, 6), row("mt", 0, 0)];
        d.edits = vec![EditRun { extractor: "mt".into(), edits: 200, open_after: 0, mass_drift: 0.0, ..EditRun::default() }];
        let r = reading(&d);
        assert!(r.contains("hold no liquid inside the solid: mt; layers that cross: mc (6 pairs)."), "{r}");
        assert!(r.contains("leave 3 of 10 contact vertices unshared, 4 crossing pairs"), "{r}");
        assert!(r.contains("Over 200 edits by mt: a layer open or non-manifold after 0 of them"), "{r}");
        assert!(r.contains("the masses equal to the brushes' books"), "{r}");
        d.edits[0].mass_drift = 2e-7;
        assert!(reading(&d).contains("the masses within 2.0e-7 (relative)"));
    }

    #[test]
    fn the_untangling_sentence_pairs_each_row_with_its_rule_alone() {
        let mut d = data(vec![Row { crossing_cells: 3, retiled_cells: 3, median_ms: 3.0, ..row("mc", 0, 0) }]);
        assert_eq!(untangling(&d), "");
        d.rule_alone = vec![Row { median_ms: 2.0, ..row("mc, the post's rule alone", 0, 6) }];
        let s = untangling(&d);
        assert!(
            s.contains("mc: 6 crossing pairs with the rule alone, 0 after filling 3 of 3 cells again, 3.0 ms against 2.0 (1.50×"),
            "{s}"
        );
    }
}
