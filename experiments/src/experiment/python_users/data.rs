//! The data file `report/data/python_users.json`: what the run writes and the page reads.

use super::default_environment;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// One implementation on one input on some threads, as `bench.py` writes it.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub(super) struct Row {
    pub(super) implementation: String,
    pub(super) input: String,
    pub(super) n: usize,
    pub(super) threads: usize,
    /// How the Python process was started: "default", or [`HUGE_PAGES`].
    #[serde(default = "default_environment")]
    pub(super) environment: String,
    /// Every recorded call, ms, in the order run.
    pub(super) ms: Vec<f64>,
    pub(super) vertices: usize,
    pub(super) triangles: usize,
    /// What the call converts on the way in and out.
    pub(super) converts: String,
    /// The arrays the call returns.
    #[serde(default)]
    pub(super) returns: String,
    /// Blocks of rounds run (`bench.py` adds a block while one is wide; absent in older data).
    #[serde(default)]
    pub(super) blocks: Option<usize>,
    /// Whether its last block was still wide (slowest call over [`crate::report::WIDE`] times the
    /// fastest) after the last block allowed.
    #[serde(default)]
    pub(super) wide: Option<bool>,
}

/// One call's peak memory in a process of its own, as `bench.py` writes it.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub(super) struct Peak {
    pub(super) implementation: String,
    pub(super) input: String,
    pub(super) n: usize,
    /// The resident high-water mark during the call above the resident memory before it.
    pub(super) peak_bytes: i64,
    /// Bytes of the arrays the call returned.
    pub(super) output_bytes: i64,
    /// Bytes of the input array.
    pub(super) input_bytes: i64,
}

/// The floor of a call on an input: one read of the array, one write of our output.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub(super) struct Floor {
    pub(super) input: String,
    pub(super) n: usize,
    pub(super) output_bytes: u64,
    pub(super) read_ms: f64,
    pub(super) write_ms: f64,
    /// The write into fresh memory (its page faults included).
    pub(super) first_touch_write_ms: f64,
}

/// An input as `bench.py` describes it.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub(super) struct Input {
    pub(super) input: String,
    pub(super) n: usize,
    pub(super) dtype: String,
    pub(super) order: String,
    pub(super) shape: Vec<usize>,
    pub(super) level: f64,
}

#[derive(Serialize, Deserialize)]
pub(super) struct Data {
    #[serde(default)]
    pub(super) repeats: usize,
    #[serde(default)]
    pub(super) large_repeats: usize,
    pub(super) versions: BTreeMap<String, String>,
    pub(super) notes: Vec<String>,
    pub(super) inputs: Vec<Input>,
    pub(super) rows: Vec<Row>,
    #[serde(default)]
    pub(super) peaks: Vec<Peak>,
    #[serde(default)]
    pub(super) floors: Vec<Floor>,
}
