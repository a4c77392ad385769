//! The page `report/stuart_tables.md`, rendered from the data file alone.

use super::checks::{ablation_table, checks};
use super::data::{Data, Peers};
use super::table_one::{against_table_one, table_one};
use super::table_two::table_two;
use super::{reading, relaxation};
use super::{CELLS, NAME, PAPER_RUNS, RATIOS};
use crate::experiment::context::{Context, ExperimentError};
use isolab_algorithms::extractors::bcc_sculpt::SculptOptions;

/// The page, from the data file alone.
pub(super) fn section(ctx: &Context) -> Result<String, ExperimentError> {
    let data: Data = ctx.read_data(NAME)?;
    let mut md = String::from("## Coarse enclosing tetrahedral meshes: Stuart et al. 2013 (`stuart_tables`)\n\n");
    md.push_str(&format!(
        "`bcc-sculpt` on the shipped models: a BCC lattice sculpted to the surface, bombs defused with the fewest \
         snowflakes, then ODT relaxation that never lets the boundary cross the surface (exact collision tests on the \
         swept region), until every boundary vertex is within `d_offset = ratio · h`. Each configuration is the best of \
         {} lattices (the first unperturbed, the others randomly rotated and shifted; the paper ran {} to {}). \
         One addition to the paper's relaxation is on by default: a step never leaves a tetrahedron it changes below \
         {}° of dihedral angle (`quality-floor`; the paper has none, and its unguarded update lowers the worst minimum \
         dihedral angle to {:.1}° in the ablation below). Two more are options, off by default because the ablation shows \
         no gain: a boundary vertex keeping a clearance from the surface (`clearance`), and a boundary vertex whose ODT \
         step fails stepping toward the surface instead (`attract`). Sculpting's pinches (parts touching along an edge or at a vertex) are repaired by \
         completing snowflakes, so every boundary is a closed manifold. Distances are in model units, as in the paper; \
         `h` is the model's longest side over {}. A dash marks a configuration that did not converge \
         (the paper's dashes); its mesh is still produced and listed below the table.\n\n",
        data.perturbations,
        PAPER_RUNS.0,
        PAPER_RUNS.1,
        SculptOptions::default().quality_floor,
        data.ablation
            .iter()
            .filter(|a| a.variant.starts_with("the paper's update"))
            .map(|a| a.dihedral[0])
            .fold(f64::INFINITY, f64::min),
        CELLS.map(|c| c.to_string()).join(", "),
    ));
    let peers: Option<Peers> = ctx.read_data("stuart_tables_peers").ok();
    md.push_str(&reading::reading(&data));
    md.push_str(&table_one(&data.rows));
    md.push_str(&checks(&data));
    md.push_str(&against_table_one(&data));
    md.push_str(&ablation_table(&data.ablation));
    if !data.relaxation.is_empty() {
        md.push_str(&relaxation::section(
            &data.relaxation,
            SculptOptions::default().quality_floor,
            data.relaxation_plot.as_deref(),
        ));
    }
    md.push_str(&table_two(ctx, &data.rows));
    md.push_str(&reading::differences(&data, peers.as_ref()));
    md.push_str(&format!(
        "\n**Figures 7-10 of the paper, for our models**: boundary surfaces, spacing from coarse (top) to fine, offset ratio {} (left) to {}.\n\n",
        RATIOS[RATIOS.len() - 1],
        RATIOS[0]
    ));
    for (model, link) in &data.figures {
        md.push_str(&format!("_{model}_\n\n![{model}: bcc-sculpt grid]({link})\n\n"));
    }
    Ok(md)
}
