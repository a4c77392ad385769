//! The registry as the front ends list it: every extractor, post-process and label extractor
//! with its options and what it promises ([`listing`]), and the built-in fields
//! ([`field_listing`]). `isolab list` prints these entries and `isolab.algorithms()` returns
//! them as dictionaries (their JSON), so the two cannot drift apart.

use isolab_algorithms::extract::Guarantees;
use isolab_algorithms::{extractors, fields, labels, post, Chunking, Options};
use serde::Serialize;
use serde_json::{json, Value};

/// What kind of thing an entry is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum EntryKind {
    /// A surface or volume extractor (`isolab extract -a`).
    Extractor,
    /// A post-process (`--post`).
    PostProcess,
    /// A label-map extractor (`isolab labels -a`).
    Labels,
}

/// One registered algorithm, as listed.
#[derive(Clone, Debug, Serialize)]
pub struct Entry {
    /// Its registry name.
    pub name: &'static str,
    /// What kind it is.
    pub kind: EntryKind,
    /// One line saying what it does.
    pub description: &'static str,
    /// The options it takes (`--set NAME=VALUE`, `options={...}`).
    pub options: Vec<&'static str>,
    /// Its promises as data: for extractors the lattices it meshes, `closed`, `manifold`,
    /// `outward`, `intersection_free`, `trilinear_topology`, `keeps_small_parts` and
    /// `dihedral_degrees` (`[min, max]` or null); for post-processes what they keep; for label
    /// extractors whether every label's mesh is closed, manifold and outward.
    pub guarantees: Value,
    /// The same promises as one line (what `isolab list` prints).
    pub promises: String,
    /// Extractors: how they read a caller's samples, `borrowed` or `copies: REASON`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub samples: Option<String>,
    /// Extractors: how they mesh in blocks with their default options: `cell-local`, `apron`
    /// or `unsupported`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub chunking: Option<&'static str>,
    /// Extractors: the samples of each neighbour a block also reads (0 unless `apron`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub apron: Option<usize>,
}

/// One built-in field, as listed.
#[derive(Clone, Debug, Serialize)]
pub struct FieldEntry {
    /// Its name (`-f NAME`).
    pub name: &'static str,
    /// One line saying what it is.
    pub description: &'static str,
    /// Its Lipschitz bound, which lets a large grid of it be sampled near its surface only.
    pub lipschitz: Option<f64>,
}

/// The names whose flag is set, joined, or `none` when no flag is.
fn promised(flags: &[(&str, bool)], none: &str) -> String {
    let on: Vec<&str> = flags.iter().filter(|(_, on)| *on).map(|(name, _)| *name).collect();
    if on.is_empty() {
        none.into()
    } else {
        on.join(", ")
    }
}

fn extractor_promises(g: &Guarantees) -> String {
    let flags = [
        ("closed", g.closed),
        ("manifold", g.manifold),
        ("outward", g.outward),
        ("free of self-intersections", g.intersection_free),
        ("the trilinear interpolant's topology in every cell", g.trilinear_topology),
        ("every part of the inside, however small", g.keeps_small_parts),
    ];
    let dihedral = g
        .dihedral
        .map_or(String::new(), |d| format!("; every dihedral angle in [{}°, {}°], none inverted", d.min_degrees, d.max_degrees));
    format!("lattices: {}; guarantees: {}{dihedral}", g.lattices().join(", "), promised(&flags, "none"))
}

fn extractor_entry(e: &isolab_algorithms::extract::ExtractorInfo) -> Entry {
    let g = &e.guarantees;
    let chunking = extractors::build(e.name, &Options::new()).ok().flatten().map(|x| x.chunking());
    let (chunking, apron) = match chunking {
        Some(Chunking::CellLocal) => ("cell-local", 0),
        Some(Chunking::Apron(a)) => ("apron", a),
        _ => ("unsupported", 0),
    };
    Entry {
        name: e.name,
        kind: EntryKind::Extractor,
        description: e.description,
        options: e.options.to_vec(),
        guarantees: json!({
            "lattices": g.lattices(),
            "closed": g.closed,
            "manifold": g.manifold,
            "outward": g.outward,
            "intersection_free": g.intersection_free,
            "trilinear_topology": g.trilinear_topology,
            "keeps_small_parts": g.keeps_small_parts,
            "dihedral_degrees": g.dihedral.map(|d| [d.min_degrees, d.max_degrees]),
        }),
        promises: extractor_promises(g),
        samples: Some(e.samples.describe()),
        chunking: Some(chunking),
        apron: Some(apron),
    }
}

fn post_entry(p: &isolab_algorithms::extract::PostInfo) -> Entry {
    let g = &p.guarantees;
    let flags = [
        ("closed manifold", g.keeps_closed_manifold),
        ("every component (so the Euler characteristic)", g.keeps_every_component),
        ("orientation", g.keeps_outward),
        ("no new self-intersection", g.adds_no_intersection),
    ];
    Entry {
        name: p.name,
        kind: EntryKind::PostProcess,
        description: p.description,
        options: p.options.to_vec(),
        guarantees: json!({
            "keeps_closed_manifold": g.keeps_closed_manifold,
            "keeps_outward": g.keeps_outward,
            "adds_no_intersection": g.adds_no_intersection,
            "keeps_every_component": g.keeps_every_component,
        }),
        promises: format!("keeps: {}", promised(&flags, "nothing promised")),
        samples: None,
        chunking: None,
        apron: None,
    }
}

fn label_entry(e: &labels::LabelExtractorInfo) -> Entry {
    let g = &e.guarantees;
    let flags = [("closed", g.closed), ("manifold", g.manifold), ("outward", g.outward)];
    let dihedral = g.dihedral.map_or(String::new(), |d| {
        format!(
            "; tetrahedra filling every label, every dihedral angle in [{}°, {}°], none inverted",
            d.min_degrees, d.max_degrees
        )
    });
    Entry {
        name: e.name,
        kind: EntryKind::Labels,
        description: e.description,
        options: e.options.to_vec(),
        guarantees: json!({
            "closed": g.closed,
            "manifold": g.manifold,
            "outward": g.outward,
            "dihedral_degrees": g.dihedral.map(|d| [d.min_degrees, d.max_degrees]),
        }),
        promises: format!("every label's mesh: {}{dihedral}", promised(&flags, "nothing promised")),
        samples: None,
        chunking: None,
        apron: None,
    }
}

/// Every registered extractor, then every post-process, then every label extractor, in
/// registry order.
pub fn listing() -> Vec<Entry> {
    let extractors = extractors::INFOS.iter().map(extractor_entry);
    let posts = post::POST_INFOS.iter().map(post_entry);
    extractors.chain(posts).chain(labels::LABEL_INFOS.iter().map(label_entry)).collect()
}

/// Every built-in field, in registry order.
pub fn field_listing() -> Vec<FieldEntry> {
    fields::registry()
        .iter()
        .map(|f| FieldEntry {
            name: f.name,
            description: f.description,
            lipschitz: (f.make)(fields::FieldParams::default()).lipschitz(),
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_listing_has_every_registered_name_once_with_its_kind() {
        let entries = listing();
        let names = |kind| entries.iter().filter(|e| e.kind == kind).map(|e| e.name).collect::<Vec<_>>();
        assert_eq!(names(EntryKind::Extractor), extractors::INFOS.iter().map(|e| e.name).collect::<Vec<_>>());
        assert_eq!(names(EntryKind::PostProcess), post::POST_INFOS.iter().map(|e| e.name).collect::<Vec<_>>());
        assert_eq!(names(EntryKind::Labels), labels::LABEL_INFOS.iter().map(|e| e.name).collect::<Vec<_>>());
        assert_eq!(field_listing().len(), fields::registry().len());
    }

    #[test]
    fn entries_say_their_promises_as_data_and_as_the_line_the_cli_prints() {
        let entries = listing();
        let mc = entries.iter().find(|e| e.name == "marching-cubes").expect("marching cubes is registered");
        let json = serde_json::to_value(mc).unwrap();
        assert_eq!(json["kind"], "extractor");
        assert_eq!(json["chunking"], "cell-local");
        assert_eq!(json["guarantees"]["closed"], Value::Bool(mc.promises.contains("closed")));
        let stuffing = entries.iter().find(|e| e.guarantees["dihedral_degrees"].is_array()).expect("a volume extractor");
        assert!(stuffing.promises.contains("every dihedral angle in"), "{}", stuffing.promises);
        let post = entries.iter().find(|e| e.kind == EntryKind::PostProcess).unwrap();
        let json = serde_json::to_value(post).unwrap();
        assert_eq!((json["kind"].as_str(), json.get("chunking")), (Some("post-process"), None));
    }
}
