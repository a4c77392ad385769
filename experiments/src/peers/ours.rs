//! One of our registered extractors, run the way the peers are, so a comparison is like for like.
//!
//! One-shot: the extractor is built from the registry and the output is `Extraction::default()`
//! on every call (what `isolab extract` does once). Steady state: both are kept between calls, so
//! output vectors and scratch are reused. On one thread the extractor runs with
//! `parallelism=serial`; on more, on a rayon pool of that many threads.

use super::{Job, Peer, PeerError, PeerRun, Protocol};
use isolab_algorithms::extractors;
use isolab_algorithms::{Extraction, Extractor, Options};
use std::collections::HashMap;

/// Our extractor `name` with `options` (jobs: [`Job::Grid`]).
pub struct Ours {
    name: &'static str,
    options: Vec<(&'static str, &'static str)>,
    pools: HashMap<usize, rayon::ThreadPool>,
    kept: HashMap<usize, (Box<dyn Extractor>, Extraction)>,
}

impl Ours {
    /// Our registered extractor `name`, built with `options` (`name=value` pairs) on every run.
    pub fn new(name: &'static str, options: &[(&'static str, &'static str)]) -> Ours {
        Ours { name, options: options.to_vec(), pools: HashMap::new(), kept: HashMap::new() }
    }

    fn build(&self, threads: usize) -> Result<Box<dyn Extractor>, PeerError> {
        let mut options = Options::new();
        for (k, v) in &self.options {
            options.set(k, v);
        }
        if threads == 1 {
            options.set("parallelism", "serial");
        }
        let failed = |message: String| PeerError::Failed { peer: self.name(), message };
        extractors::build(self.name, &options)
            .map_err(|e| failed(e.to_string()))?
            .ok_or_else(|| failed("not in the registry".into()))
    }
}

impl Peer for Ours {
    fn name(&self) -> String {
        format!("isolab {}", self.name)
    }

    fn run(&mut self, job: &Job<'_>, protocol: Protocol) -> Result<PeerRun, PeerError> {
        let Job::Grid { samples, threads, .. } = job else { return Err(self.unsupported()) };
        let threads = (*threads).max(1);
        if !self.pools.contains_key(&threads) {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .map_err(|e| PeerError::Failed { peer: self.name(), message: format!("thread pool: {e}") })?;
            self.pools.insert(threads, pool);
        }
        let (extractor, mut out) = match (protocol, self.kept.remove(&threads)) {
            (Protocol::SteadyState, Some(kept)) => kept,
            _ => (self.build(threads)?, Extraction::default()),
        };
        let pool = &self.pools[&threads];
        pool.install(|| extractor.extract(samples, &mut out))
            .map_err(|e| PeerError::Failed { peer: self.name(), message: e.to_string() })?;
        let run = PeerRun {
            time: out.stats.times.extraction(),
            vertices: out.surface.positions.len(),
            triangles: out.surface.triangles.len(),
            ..PeerRun::default()
        };
        if protocol == Protocol::SteadyState {
            self.kept.insert(threads, (extractor, out));
        }
        Ok(run)
    }
}
