//! The page's opening reading and the list of where we differ from the paper, worded from the
//! rows: convergence against Table 1, enclosure, the quality floor's part in the angles, the
//! paper's own update without the floor (the ablation), and Table 2's claim against CGAL.

use super::table_one::{paper_converged, FLOOR_BINDS_WITHIN};
use super::table_two::cgal_count_against_paper;
use super::{Data, Peers, RATIOS};
use isolab_algorithms::extractors::bcc_sculpt::SculptOptions;

/// The reading (empty without rows).
pub(super) fn reading(data: &Data) -> String {
    if data.rows.is_empty() {
        return String::new();
    }
    let n = data.rows.len();
    let converged: Vec<_> = data.rows.iter().filter(|r| r.converged).collect();
    let (pc, pn) = (0..RATIOS.len()).map(paper_converged).fold((0, 0), |(a, b), (c, d)| (a + c, b + d));
    let encloses = data.rows.iter().filter(|r| r.encloses).count();
    let floor = f64::from(SculptOptions::default().quality_floor);
    let held = converged.iter().filter(|r| r.min_dihedral < floor + FLOOR_BINDS_WITHIN).count();
    let angles = converged.iter().map(|r| r.min_dihedral);
    let (lo, hi) = angles.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), a| (lo.min(a), hi.max(a)));
    let mut lines = vec![format!(
        "`bcc-sculpt` converges on {} of {n} configurations (the paper's Table 1: {pc} of {pn}); every mesh encloses its \
         surface on {encloses} of {n}.",
        converged.len()
    )];
    if !converged.is_empty() {
        lines.push(format!(
            "The converged meshes' minimum dihedral angles span {lo:.1}° to {hi:.1}°; on {held} of {} our {floor}° quality \
             floor, not the relaxation, sets it.",
            converged.len()
        ));
    }
    let paper_update = data
        .ablation
        .iter()
        .filter(|a| a.variant.starts_with("the paper's update"))
        .map(|a| a.dihedral[0])
        .fold(f64::INFINITY, f64::min);
    if paper_update.is_finite() {
        lines.push(format!("The paper's own update, without the floor, goes down to {paper_update:.1}° (the ablation)."));
    }
    format!("**Reading.** {} Where we differ from the paper is listed after Table 2.\n\n", lines.join(" "))
}

/// Where we differ from the paper, each with its reason or "unexplained" (empty without rows).
pub(super) fn differences(data: &Data, peers: Option<&Peers>) -> String {
    if data.rows.is_empty() {
        return String::new();
    }
    let n = data.rows.len();
    let converged = data.rows.iter().filter(|r| r.converged).count();
    let (pc, pn) = (0..RATIOS.len()).map(paper_converged).fold((0, 0), |(a, b), (c, d)| (a + c, b + d));
    let floor = f64::from(SculptOptions::default().quality_floor);
    let cgal = peers.and_then(|p| cgal_count_against_paper(&data.rows, p));
    let mut md = String::from("\n### Where we differ from the paper\n\n");
    if converged * pn != pc * n {
        md.push_str(&format!(
            "- **Convergence**: {} of {n} here against {pc} of {pn}: unexplained (our models are not the paper's, and our \
             relaxation is guarded where the paper's is not).\n",
            converged
        ));
    }
    md.push_str(&format!(
        "- **A quality floor**: a step here never leaves a tetrahedron below {floor}° of dihedral angle; the paper has no \
         floor, and its update alone leaves slivers (*Why the paper's update makes slivers here*).\n\
         - **Lattices**: each configuration is the best of {} lattices.\n",
        data.perturbations
    ));
    if let Some(c) = cgal {
        md.push_str(&format!("- **Table 2**: {c}\n"));
    }
    md.push('\n');
    md
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_reading_follows_the_rows() {
        let text =
            std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../report/data/stuart_tables.json")).expect("data");
        let mut data: Data = serde_json::from_str(&text).expect("stuart_tables data");
        let n = data.rows.len();
        let converged = data.rows.iter().filter(|r| r.converged).count();
        let r = reading(&data);
        assert!(r.contains(&format!("converges on {converged} of {n} configurations")), "{r}");
        assert!(differences(&data, None).contains("**A quality floor**"));
        for row in &mut data.rows {
            row.converged = true;
            row.encloses = false;
        }
        let r = reading(&data);
        assert!(
            r.contains(&format!("converges on {n} of {n}")) && r.contains(&format!("encloses its surface on 0 of {n}")),
            "{r}"
        );
        data.rows.clear();
        assert_eq!((reading(&data), differences(&data, None)), (String::new(), String::new()));
    }
}
