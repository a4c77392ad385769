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
