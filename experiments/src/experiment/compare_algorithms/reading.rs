//! The page's reading: what its hundreds of rows show, worded from them. Where each extractor's
//! time differs most between the built-in fields and the shipped models, which meshes' topology
//! departs from what the other extractors make of the same input at the same resolution, and
//! which are not closed, manifold and oriented where the input is closed.

use super::{leaves_domain, Data, Measured};
use crate::experiment::context::ms;
use crate::report::first_seen;
use isolab_algorithms::fields;

/// Inputs listed by name in a sentence; the rest are counted.
const MAX_LISTED: usize = 4;

/// Times on the models this many times those on the fields (medians) are called out.
const MODEL_COST_FACTOR: f64 = 5.0;

fn is_field(name: &str) -> bool {
    fields::registry().iter().any(|f| f.name == name)
}

fn median(v: Vec<f64>) -> f64 {
    crate::report::Spread::of(v).median
}

/// The most common value (the first met of the most common).
fn mode<T: PartialEq + Copy>(values: &[T]) -> Option<T> {
    values.iter().copied().max_by_key(|v| values.iter().filter(|w| *w == v).count())
}

/// The reading, three to six sentences.
pub(super) fn reading(data: &Data) -> String {
    let names: Vec<&str> = first_seen(data.rows.iter().map(|r| r.algorithm.as_str()));
    let inputs: Vec<(&str, usize)> = first_seen(data.rows.iter().map(|r| (r.field.as_str(), r.resolution)));
    if data.rows.is_empty() {
        return String::new();
    }
    let mut lines = Vec::new();
    // Cost on models against fields.
    let costly: Vec<String> = names
        .iter()
        .filter_map(|n| {
            let of = |model: bool| -> Vec<f64> {
                data.rows.iter().filter(|r| r.algorithm == *n && is_field(&r.field) != model).map(|r| r.extraction_ms).collect()
            };
            let (on_fields, on_models) = (of(false), of(true));
            let (f, m) = (median(on_fields.clone()), median(on_models.clone()));
            (m > MODEL_COST_FACTOR * f).then(|| {
                let range = |v: &[f64]| {
                    let (lo, hi) = v.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| (a.min(x), b.max(x)));
                    format!("{}-{} ms", ms(lo), ms(hi))
                };
                format!("{n} ({} on the models against {} on the fields)", range(&on_models), range(&on_fields))
            })
        })
        .collect();
    if !costly.is_empty() {
        lines.push(format!(
            "Extractors whose median time on the models is more than {MODEL_COST_FACTOR} times that on the fields: {}; they \
             ask the field for its gradient at every crossing or vertex, and a model's field answers each with a closest-point \
             query on its triangles, where a built-in field evaluates a formula.",
            costly.join("; ")
        ));
    }
    // Topology that departs from the other surface extractors' on the same input (bcc-sculpt's
    // enclosing surface is another surface by design), grouped by input.
    let surface = |name: &str| isolab_algorithms::extractors::by_name(name).is_some_and(|e| !e.produces_volume());
    let mut departs: Vec<String> = Vec::new();
    let mut departing_meshes = 0;
    for (field, resolution) in &inputs {
        let here: Vec<&Measured> =
            data.rows.iter().filter(|r| r.field == *field && r.resolution == *resolution && surface(&r.algorithm)).collect();
        let genus: Vec<Option<i64>> = here.iter().map(|r| r.metrics.topology.genus).collect();
        let components: Vec<usize> = here.iter().map(|r| r.metrics.topology.components).collect();
        let (Some(g), Some(c)) = (mode(&genus), mode(&components)) else { continue };
        let odd: Vec<String> = here
            .iter()
            .filter(|r| r.metrics.topology.genus != g || r.metrics.topology.components != c)
            .map(|r| {
                let t = &r.metrics.topology;
                format!("{} ({}, {})", r.algorithm, t.genus.map_or("-".into(), |x| format!("genus {x}")), t.components)
            })
            .collect();
        if !odd.is_empty() {
            departing_meshes += odd.len();
            departs.push(format!(
                "{field} at {resolution} against genus {} and {c} components: {}",
                g.map_or("-".into(), |x| x.to_string()),
                odd.join(", ")
            ));
        }
    }
    let surface_meshes = data.rows.iter().filter(|r| surface(&r.algorithm)).count();
    if departs.is_empty() {
        lines.push(
            "On every input at every resolution, every surface extractor's mesh has the genus and components most have.".into(),
        );
    } else {
        let shown = departs.len().min(MAX_LISTED);
        lines.push(format!(
            "Topology that departs from most surface extractors' on the same samples: {departing_meshes} of {surface_meshes} \
             meshes, on {} inputs (not investigated case by case, so unexplained); {}{}.",
            departs.len(),
            departs[..shown].join("; "),
            if departs.len() > shown {
                format!("; and {} more inputs in the tables below", departs.len() - shown)
            } else {
                String::new()
            }
        ));
    }
    // Defects where the input is closed.
    let defects: Vec<String> = data
        .rows
        .iter()
        .filter(|r| !leaves_domain(&r.field))
        .filter(|r| {
            let t = &r.metrics.topology;
            !(t.closed && t.edge_manifold && t.vertex_manifold && t.oriented)
        })
        .map(|r| format!("{} on {} at {}", r.algorithm, r.field, r.resolution))
        .collect();
    lines.push(if defects.is_empty() {
        "Every mesh of an input the domain does not cut is closed, manifold and oriented.".into()
    } else {
        format!("Not closed, manifold and oriented where the input is closed: {}.", defects.join("; "))
    });
    let intersecting: Vec<String> = names
        .iter()
        .filter_map(|n| {
            let rows: Vec<&Measured> = data.rows.iter().filter(|r| r.algorithm == *n).collect();
            let with = rows.iter().filter(|r| r.metrics.intersecting_pairs() > 0).count();
            (with > 0).then(|| format!("{n} on {with} of {}", rows.len()))
        })
        .collect();
    if !intersecting.is_empty() {
        lines.push(format!("Meshes with self-intersecting triangles: {}.", intersecting.join(", ")));
    }
    format!("**Reading.** {}\n\n", lines.join(" "))
}
