//! The data file `report/data/compare_algorithms.json`: what the run writes and the page reads.

use crate::experiment::context::Measured;
use serde::{Deserialize, Serialize};

#[derive(Serialize, Deserialize)]
pub(crate) struct Data {
    pub(crate) field_levels: Vec<usize>,
    pub(crate) model_levels: Vec<usize>,
    pub(crate) repeats: usize,
    pub(crate) rows: Vec<Measured>,
    /// (algorithm, field, image path relative to the report)
    pub(crate) images: Vec<(String, String, String)>,
    /// (algorithm, path) of turntable GIFs and flat/smooth pairs.
    pub(crate) turntables: Vec<(String, String)>,
    pub(crate) pairs: Vec<(String, String)>,
    pub(crate) scatter: String,
    pub(crate) overshading: String,
    pub(crate) bars: String,
    pub(crate) histograms: Vec<String>,
    /// Each extractor's options as it ran, in words (its `settings()`; absent from runs before
    /// they were recorded).
    #[serde(default)]
    pub(crate) settings: Vec<(String, String)>,
}

impl Data {
    /// The middle of the resolutions run, fields' and models' (the second of three; the only
    /// one of a quick run): the glance table's and the front figure's.
    pub(crate) fn middle_levels(&self) -> (usize, usize) {
        let middle = |levels: &[usize]| levels.get(levels.len() / 2).copied().unwrap_or(0);
        (middle(&self.field_levels), middle(&self.model_levels))
    }
}

/// An extractor's self-intersecting triangle pairs over the compared inputs: at the middle
/// resolution (the glance table's rows) and over every resolution run.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct Intersections {
    /// Pairs over the inputs at the middle resolution.
    pub(crate) middle_pairs: usize,
    /// Inputs at the middle resolution with any pair.
    pub(crate) middle_hit: usize,
    /// Inputs at the middle resolution.
    pub(crate) middle_inputs: usize,
    /// Pairs over every mesh, every resolution.
    pub(crate) all_pairs: usize,
    /// Meshes, every resolution, with any pair.
    pub(crate) all_hit: usize,
    /// Meshes, every resolution.
    pub(crate) all_meshes: usize,
}

impl Data {
    /// `algorithm`'s self-intersections ([`Intersections`]).
    pub(crate) fn intersections(&self, algorithm: &str) -> Intersections {
        let (level, model_level) = self.middle_levels();
        let is_field = |name: &str| isolab_algorithms::fields::registry().iter().any(|f| f.name == name);
        let mut out = Intersections::default();
        for r in self.rows.iter().filter(|r| r.algorithm == algorithm) {
            let pairs = r.metrics.intersecting_pairs();
            out.all_pairs += pairs;
            out.all_hit += usize::from(pairs > 0);
            out.all_meshes += 1;
            if r.resolution == if is_field(&r.field) { level } else { model_level } {
                out.middle_pairs += pairs;
                out.middle_hit += usize::from(pairs > 0);
                out.middle_inputs += 1;
            }
        }
        out
    }
}
