//! The page `report/viewer.md`, rendered from the data file alone.

use super::data::{Data, Mesh};
use super::{MESH_BUDGET_BYTES, NAME};
use crate::experiment::context::{Context, ExperimentError};
use crate::report::markdown_table;

/// The page, from the data file alone.
pub(super) fn section(ctx: &Context) -> Result<String, ExperimentError> {
    let data: Data = ctx.read_data(NAME)?;
    let mut md = String::from("## Meshes to turn in 3D (`viewer`)\n\n");
    let total: usize = data.meshes.iter().map(|m| m.bytes).sum();
    md.push_str(&format!(
        "[`index.html`](index.html) shows the front page beside a viewer that turns any two of these meshes side by side \
         (wireframe on or off, both sides of open meshes shaded), with each mesh's measures; it colours triangles by \
         shape or marks the boundary, non-manifold and self-intersecting ones, and keeps what it shows in the address, \
         so a view can be linked. Each is an extractor's mesh of an input at the lowest resolution `compare_algorithms` \
         pictures, as binary glTF with {}-bit quantized positions (`KHR_mesh_quantization`), {} meshes and {:.1} MB in all \
         (budget {:.1} MB). The page loads them with `fetch`, which browsers refuse for `file://` pages: serve the \
         directory, for example `python3 -m http.server --directory report`, and open the address it prints.\n\n",
        isolab_io::gltf::QUANT_BITS,
        data.meshes.len(),
        total as f64 / 1e6,
        MESH_BUDGET_BYTES as f64 / 1e6,
    ));
    md.push_str(&reading(&data));
    let names: Vec<&str> = crate::report::first_seen(data.meshes.iter().map(|m| m.algorithm.as_str()));
    md.push_str(&crate::experiment::context::default_options(&names));
    if !data.left_out.is_empty() {
        md.push_str(&format!(
            "Left out by the budget: {}.\n\n",
            data.left_out.iter().map(|(n, b)| format!("`{n}` ({:.1} MB)", *b as f64 / 1e6)).collect::<Vec<_>>().join(", ")
        ));
    }
    let rows: Vec<Vec<String>> = data
        .meshes
        .iter()
        .map(|m| {
            let yes = |b: bool| if b { "yes" } else { "no" }.to_owned();
            vec![
                m.input.clone(),
                m.algorithm.clone(),
                m.resolution.to_string(),
                m.triangles.to_string(),
                yes(m.closed),
                yes(m.manifold),
                m.intersecting_pairs.to_string(),
                format!("{:.2} / {:.1}", m.aspect[0], m.aspect[1]),
                format!("[{:.0} KB]({})", m.bytes as f64 / 1e3, m.path),
            ]
        })
        .collect();
    md.push_str(&markdown_table(
        &[
            "input",
            "extractor",
            "samples",
            "triangles",
            "closed",
            "manifold",
            "self-intersecting pairs",
            "aspect mean / max",
            "glb",
        ],
        &rows,
    ));
    Ok(md)
}

/// The page's opening reading: what the viewer offers, by input, and what the budget left out.
pub(super) fn reading(data: &Data) -> String {
    if data.meshes.is_empty() {
        return String::new();
    }
    let inputs = crate::report::first_seen(data.meshes.iter().map(|m| m.input.as_str()));
    let extractors = crate::report::first_seen(data.meshes.iter().map(|m| m.algorithm.as_str()));
    let largest = data
        .meshes
        .iter()
        .max_by_key(|m| m.triangles)
        .map_or(String::new(), |m| format!(" The largest is {} of {} ({} triangles).", m.algorithm, m.input, m.triangles));
    let count = |keep: &dyn Fn(&Mesh) -> bool| data.meshes.iter().filter(|m| keep(m)).count();
    let coarser: Vec<String> = inputs
        .iter()
        .filter_map(|i| {
            let m = data.meshes.iter().find(|m| m.input == *i)?;
            let lowest = crate::experiment::context::compared_inputs().into_iter().find(|c| c.0 == *i).map(|c| c.2[0])?;
            (m.resolution < lowest).then(|| format!("{i} at {} instead of {lowest}", m.resolution))
        })
        .collect();
    format!(
        "**Reading.** {} meshes: {} inputs ({}) by up to {} extractors.{largest} Closed: {} of them; manifold: {}; \
         with self-intersections: {}. Meshed coarser to fit the budget: {}. Inputs left out by the budget: {}.\n\n",
        data.meshes.len(),
        inputs.len(),
        inputs.join(", "),
        extractors.len(),
        count(&|m| m.closed),
        count(&|m| m.manifold),
        count(&|m| m.intersecting_pairs > 0),
        crate::report::listed(&coarser),
        crate::report::listed(&data.left_out.iter().map(|(n, _)| n.as_str()).collect::<Vec<_>>())
    )
}
