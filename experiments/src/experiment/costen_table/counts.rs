//! Our counts against the paper's Appendix B, and why the tetrahedra differ more than the
//! triangles.

use super::{PaperRow, Row};
use crate::report::Spread;

/// Our tetrahedron and triangle counts over the paper's, row by row: their median and range.
pub(super) fn ratios(rows: &[Row], paper: impl Fn(&str) -> Option<PaperRow>) -> Option<(Spread, Spread)> {
    let ratio = |ours: &dyn Fn(&Row) -> f64, theirs: &dyn Fn(&PaperRow) -> f64| {
        Spread::of(rows.iter().filter_map(|r| paper(&r.id).map(|p| ours(r) / theirs(&p).max(f64::MIN_POSITIVE))).collect())
    };
    let tets = ratio(&|r| r.n_tetrahedra as f64, &|p| p.n_tetrahedra as f64);
    let tris = ratio(&|r| r.n_triangles as f64, &|p| p.n_triangles as f64);
    (tets.median.is_finite() && tris.median.is_finite()).then_some((tets, tris))
}

/// Our tetrahedron and triangle counts against the paper's, as medians of the row ratios, and
/// why the first differ more.
pub(super) fn count_ratios(rows: &[Row], paper: impl Fn(&str) -> Option<PaperRow>) -> String {
    let Some((tets, tris)) = ratios(rows, paper) else { return String::new() };
    format!(
        "\nOur tetrahedron counts are {:.2}x the paper's and our triangle counts {:.2}x (medians over the rows; {:.2}-{:.2}x \
         and {:.2}-{:.2}x). The tetrahedra are counted differently: ours are the tetrahedra with a sign change, while the \
         paper's geometry pass skips only whole cubes without an intersection, all their tetrahedra at once (its \
         section 3.1.2), so its count most likely includes every tetrahedron of a cube it enters; the \
         paper does not define N_tetrahedra, so this is our reading, not a check.\n",
        tets.median, tris.median, tets.min, tets.max, tris.min, tris.max
    )
}
