//! The data file `report/data/peers.json`: what the run writes and the page reads.

use super::wake::Wake;
use crate::peers::Protocol;
use crate::report::Spread;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// One implementation on one grid under one protocol.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Timing {
    /// Implementation label, threads included.
    pub implementation: String,
    /// Field.
    pub field: String,
    /// Samples along each side.
    pub n: usize,
    /// How it was timed.
    pub protocol: Protocol,
    /// Extraction time, ms: median and spread over every run, in rounds until one was not wide.
    pub ms: Spread,
    /// Whether its last round was still wide after the most rounds ([`crate::report::MAX_ROUNDS`]).
    #[serde(default)]
    pub wide: bool,
    /// Vertices of its output.
    pub vertices: usize,
    /// Triangles.
    pub triangles: usize,
}

/// The memory floor of one grid.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Floor {
    /// Field.
    pub field: String,
    /// Samples along each side.
    pub n: usize,
    /// One streaming read of every sample, ms (median).
    pub read_ms: f64,
    /// Writing marching cubes' output bytes once, ms (median).
    pub write_ms: f64,
}

#[derive(Serialize, Deserialize)]
pub(super) struct Data {
    pub(super) repeats: usize,
    pub(super) timings: Vec<Timing>,
    pub(super) floors: Vec<Floor>,
    /// Peer package versions, or why a peer was skipped.
    pub(super) versions: BTreeMap<String, String>,
    pub(super) skipped: Vec<String>,
    /// How long our two-thread pool's second thread takes to start work after idling.
    #[serde(default)]
    pub(super) wake: Vec<Wake>,
    /// Whether our two-thread runs called from the experiment's thread on rayon's global pool of
    /// two threads (absent from runs before they did; they used a pool counting the caller).
    #[serde(default)]
    pub(super) two_threads_global: Option<bool>,
    /// Idle before each recorded call, ms (absent from runs before there was one).
    #[serde(default)]
    pub(super) idle_before_call_ms: Option<u64>,
    /// Our extractors' settings as they ran (absent from runs before they were recorded).
    #[serde(default)]
    pub(super) settings: Vec<(String, String)>,
}
