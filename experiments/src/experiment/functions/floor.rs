//! The samples a cell-by-cell Lipschitz test cannot rule out ([`cell_floor`]): every cell's
//! centre is tested against the bound (`|f(c)| > L h √3 / 2`), and the corners of the cells it
//! cannot rule out must be evaluated whatever the block size. The tests' own evaluations are
//! not counted, nor the neighbours that sample-gradient normals read: the count is a floor on
//! what any pruning from one value per cell evaluates, which the blocks' count is read against.

use isolab_algorithms::{Field, Grid};
use rayon::prelude::*;

/// Cells the test cannot rule out, and the samples that are corners of at least one of them, on
/// `grid` for a field of bound `l` at level 0. Streamed one layer of cells at a time.
pub(super) fn cell_floor(field: &dyn Field, grid: &Grid, l: f64) -> (u64, u64) {
    let [nx, ny, nz] = grid.dims;
    let (cx, cy, cz) = (nx - 1, ny - 1, nz - 1);
    let radius = l * f64::from(grid.spacing) * 3f64.sqrt() / 2.0;
    let layer = |k: usize| -> Vec<bool> {
        (0..cx * cy)
            .into_par_iter()
            .map(|ij| {
                let (i, j) = (ij % cx, ij / cx);
                let c = grid.origin + glam::Vec3::new(i as f32 + 0.5, j as f32 + 0.5, k as f32 + 0.5) * grid.spacing;
                f64::from(field.value(c)).abs() <= radius
            })
            .collect()
    };
    let (mut cells, mut samples) = (0u64, 0u64);
    let mut below = vec![false; cx * cy];
    for k in 0..nz {
        let above = if k < cz { layer(k) } else { vec![false; cx * cy] };
        cells += above.iter().filter(|&&b| b).count() as u64;
        // Sample (i, j, k) is a corner of the cells (i - 1..=i, j - 1..=j) of the layers below and above it.
        samples += (0..nx * ny)
            .into_par_iter()
            .filter(|&ij| {
                let (i, j) = (ij % nx, ij / nx);
                (i.saturating_sub(1)..=i.min(cx - 1))
                    .any(|ci| (j.saturating_sub(1)..=j.min(cy - 1)).any(|cj| below[cj * cx + ci] || above[cj * cx + ci]))
            })
            .count() as u64;
        below = above;
    }
    (cells, samples)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashSet;

    #[test]
    fn the_floor_counts_each_corner_of_the_cells_no_centre_rules_out_once() {
        let sphere = isolab_algorithms::fields::builtin("sphere", Default::default()).expect("sphere");
        let grid = Grid::sparse_covering(&sphere.domain(), 29).expect("grid");
        let l = 1.0;
        let radius = l * f64::from(grid.spacing) * 3f64.sqrt() / 2.0;
        let [nx, ny, nz] = grid.dims;
        let (mut cells, mut corners) = (0u64, HashSet::new());
        for k in 0..nz - 1 {
            for j in 0..ny - 1 {
                for i in 0..nx - 1 {
                    let c = grid.origin + glam::Vec3::new(i as f32 + 0.5, j as f32 + 0.5, k as f32 + 0.5) * grid.spacing;
                    if f64::from(sphere.value(c)).abs() <= radius {
                        cells += 1;
                        for d in 0..8 {
                            corners.insert([i + (d & 1), j + (d >> 1 & 1), k + (d >> 2)]);
                        }
                    }
                }
            }
        }
        assert!(cells > 0 && (corners.len() as u64) < (nx * ny * nz) as u64);
        assert_eq!(cell_floor(sphere.as_ref(), &grid, l), (cells, corners.len() as u64));
    }
}
