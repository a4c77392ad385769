//! Sign-change summaries of x-rows of samples, shared by the cubic-grid extractors: a first pass
//! that lets them skip rows, edges and cells that cannot hold surface (the trimming idea of
//! Schroeder, Maynard & Geveci, "Flying edges", LDAV 2015).

use rayon::prelude::*;

/// Sign-change summary of one x-row of samples.
#[derive(Clone, Copy, Debug, Default)]
pub struct Row {
    /// First x whose inside/outside state differs from sample 0's (`u32::MAX` when uniform).
    pub first: u32,
    /// Last such x (`0` when uniform).
    pub last: u32,
    /// Whether sample 0 is inside.
    pub inside: bool,
}

impl Row {
    /// Whether every sample of the row has the same state.
    pub fn is_uniform(&self) -> bool {
        self.first > self.last
    }
}

/// The inclusive x-range of samples where any of `rows` may differ from the others or from
/// itself, or `None` when they are all uniform and agree.
pub fn span(rows: &[Row], nx: usize) -> Option<(usize, usize)> {
    let inside = rows[0].inside;
    if rows.iter().any(|r| r.inside != inside) {
        return Some((0, nx - 1));
    }
    let first = rows.iter().map(|r| r.first).min().unwrap_or(u32::MAX);
    let last = rows.iter().map(|r| r.last).max().unwrap_or(0);
    (first <= last).then_some((first as usize, last as usize))
}

/// Classifies every x-row of `values` (rows of `nx` samples, in order) into `rows`.
pub fn classify_rows(values: &[f32], nx: usize, iso: f32, rows: &mut Vec<Row>) {
    rows.clear();
    rows.resize(values.len() / nx, Row::default());
    rows.par_iter_mut().zip(values.par_chunks(nx)).for_each(|(row, v)| {
        let inside = v[0] < iso;
        let first = v.iter().position(|&s| (s < iso) != inside);
        *row = match first {
            None => Row { first: u32::MAX, last: 0, inside },
            Some(f) => {
                let last = v.iter().rposition(|&s| (s < iso) != inside).unwrap_or(f);
                Row { first: f as u32, last: last as u32, inside }
            }
        };
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_and_spans() {
        let mut rows = Vec::new();
        classify_rows(&[1.0, 1.0, -1.0, 1.0, /* */ 1.0, 1.0, 1.0, 1.0, /* */ -1.0, -1.0, -1.0, -1.0], 4, 0.0, &mut rows);
        assert_eq!((rows[0].first, rows[0].last, rows[0].inside), (2, 2, false));
        assert!(rows[1].is_uniform() && !rows[1].inside);
        assert!(rows[2].is_uniform() && rows[2].inside);
        assert_eq!(span(&rows[0..2], 4), Some((2, 2)));
        assert_eq!(span(&rows[1..3], 4), Some((0, 3)));
        assert_eq!(span(&rows[1..2], 4), None);
    }
}
