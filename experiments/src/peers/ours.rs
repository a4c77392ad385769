//! One of our registered extractors, run the way the peers are, so a comparison is like for like.
//!
//! One-shot: the extractor is built from the registry and the output is `Extraction::default()`
//! on every call (what `isolab extract` does once). Steady state: both are kept between calls, so
//! output vectors and scratch are reused.
//!
//! Threads: on one, the extractor runs with `parallelism=serial` on the calling thread. On more,
//! it runs on a rayon pool of that many threads, one pool per thread count shared by every `Ours`
//! and built with the thread that first asks as one of its threads (the experiment's), so a call
//! works on the calling thread and wakes one thread fewer. With a pool per implementation, our
//! two-thread runs were often no faster than one thread; most likely the threads of the pool that
//! ran last were still spinning, idle, on one of the two cores. Measured alternating four of our
//! implementations (marching cubes and surface nets, one and two threads) on a 128³ gyroid,
//! medians of 7: two-thread marching cubes took 11.9 ms with a pool each, 7.6 ms with this pool,
//! 6.7 ms alone; but one-thread surface nets varied between 18.9 and 28 ms from one arrangement to
//! another, so some cross-talk between runs remains on this machine.
//!
//! Tried and dropped: a pool that leaves the calling thread out, which then hands it the job and
//! waits, as VTK's caller waits for its `STDThread` pool. In a side harness (one-shot marching
//! cubes after 5 or 20 ms idle, medians of 31) it was faster than this pool (gyroid 64³ 1.9-2.0
//! against 2.8-3.1 ms; sphere 128³ 2.0-2.3 against 3.9-4.5 ms), but in one full `peers` run it was
//! slower: two-thread marching cubes at 128³ took 3.71 ms (sphere), 10.9 (gyroid), 4.00 (asteroid)
//! against 2.26, 7.06 and 2.21 ms in the run before with this pool; the wake-up measurement of
//! that run saw its threads working 2.9 ms after a request that followed 1 ms idle, where this
//! pool's were after 26 µs (later runs of this pool vary as much: the report's table). `peers`
//! measures both before the grids (see `second_thread_start`).
//!
//! Why the second thread starts late here: a thread woken while its waker keeps running lands on
//! the waker's CPU (in a side harness, 15 of 15 wakes after a 1 ms idle) and waits there until the
//! scheduler moves it, on this machine one to four milliseconds later. Pinning the pool's two
//! threads to two CPUs removed the delay: in a side harness, after 20 ms idle, the second thread
//! started after 77 µs against 1555 µs unpinned, and two 1 ms halves joined in 1.1 ms against
//! 2.0 ms. In one full `peers` run with this pool pinned (not committed), marching cubes on two
//! threads against flying edges was 1.27-2.43x at 64³ and 1.37-1.65x at 128³. Not adopted: the
//! pools of programs calling isolab are not pinned, this experiment measures what they meet, and
//! pinned threads cannot be moved off a CPU something else is using.
//!
//! Four pool set-ups compared later, five runs each of this experiment cut to the 64³ and 128³
//! grids (not committed; the median over the five runs of marching cubes' two-thread ratio
//! against flying edges on two threads, gyroid 64³, then sphere, gyroid, asteroid and terrain at
//! 128³):
//! - this pool: 0.87x; 2.07, 1.37, 1.54, 1.23x;
//! - a pool leaving the caller out, not pinned: 0.71x; 0.99, 1.08, 0.92, 0.97x (worse everywhere);
//! - a new two-thread pool for every one-shot call, its start-up inside the timing (new threads
//!   are placed on an idle CPU, not woken onto a busy one): 1.12x; 1.58, 0.78, 1.45, 1.33x; at
//!   gyroid 128³ it was slower than one thread, which I did not explain;
//! - a pool leaving the caller out with its two threads pinned: 1.18x; 1.71, 1.44, 1.47, 1.71x,
//!   every 64³ ratio of every run at least 1.04x; but two-thread surface nets on the 128³ gyroid
//!   took 20.0 ms (median of the runs' medians), against 10.7 with this pool, and gained next to
//!   nothing over one thread (22.2 ms in the same runs).
//!
//! So this pool stays: no set-up that a library caller would meet meets every target, and the
//! one nearest (pinned) makes another implementation slower than one thread.

use super::{Job, Peer, PeerError, PeerRun, Protocol};
use isolab_algorithms::extractors;
use isolab_algorithms::{Extraction, Extractor, Options};
use std::collections::HashMap;
use std::sync::{Arc, Mutex, OnceLock};

/// The rayon pool with `threads` threads that every [`Ours`] uses; the thread that first asks is
/// one of them.
pub(crate) fn shared_pool(threads: usize) -> Result<Arc<rayon::ThreadPool>, rayon::ThreadPoolBuildError> {
    static POOLS: OnceLock<Mutex<HashMap<usize, Arc<rayon::ThreadPool>>>> = OnceLock::new();
    let mut pools = POOLS.get_or_init(Default::default).lock().unwrap_or_else(|e| e.into_inner());
    if let Some(pool) = pools.get(&threads) {
        return Ok(pool.clone());
    }
    let pool = Arc::new(rayon::ThreadPoolBuilder::new().num_threads(threads).use_current_thread().build()?);
    pools.insert(threads, pool.clone());
    Ok(pool)
}

/// Our extractor `name` with `options` (jobs: [`Job::Grid`]).
pub struct Ours {
    name: &'static str,
    options: Vec<(&'static str, &'static str)>,
    kept: HashMap<usize, (Box<dyn Extractor>, Extraction)>,
}

impl Ours {
    /// Our registered extractor `name`, built with `options` (`name=value` pairs) on every run.
    pub fn new(name: &'static str, options: &[(&'static str, &'static str)]) -> Ours {
        Ours { name, options: options.to_vec(), kept: HashMap::new() }
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
        let (extractor, mut out) = match (protocol, self.kept.remove(&threads)) {
            (Protocol::SteadyState, Some(kept)) => kept,
            _ => (self.build(threads)?, Extraction::default()),
        };
        // One thread runs serial on the calling thread: no pool thread to wake.
        let result = match threads {
            1 => extractor.extract(samples, &mut out),
            _ => shared_pool(threads)
                .map_err(|e| PeerError::Failed { peer: self.name(), message: format!("thread pool: {e}") })?
                .install(|| extractor.extract(samples, &mut out)),
        };
        result.map_err(|e| PeerError::Failed { peer: self.name(), message: e.to_string() })?;
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
