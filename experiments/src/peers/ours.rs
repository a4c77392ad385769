//! One of our registered extractors, run the way the peers are, so a comparison is like for like.
//!
//! One-shot: the extractor is built from the registry and the output is `Extraction::default()`
//! on every call (what `isolab extract` does once). Steady state: both are kept between calls, so
//! output vectors and scratch are reused.
//!
//! Threads: on one, the extractor runs with `parallelism=serial` on the calling thread. On more,
//! the experiment's thread calls it directly on rayon's global pool when that pool has that many
//! threads ([`caller_outside`]), as the command line and a program calling isolab from its own
//! thread do: the slab phases then wake every pool thread at once and the caller sleeps until
//! they are done (`slabs::for_each_slab`), as VTK's caller does with its SMP pool. Otherwise it
//! runs inside a pool of its own of that many threads, where rayon's work stealing wakes the
//! second thread from a working one.
//!
//! Why: on the machine the report runs on, a thread woken by a thread that keeps working lands on
//! the waker's CPU and waits there until the scheduler moves it (in a side harness, 15 of 15
//! wakes after 1 ms idle; the kernel is booted with `sched_vcpu_pack=15`, which is not an
//! upstream option). Threads woken by a caller that then sleeps start on both CPUs within tens of
//! microseconds. Earlier runs of this experiment used one pool that counted the experiment's
//! thread as one of its two threads, so the caller worked while it woke the other; after the
//! pool slept, its second thread often started milliseconds late, and two-thread marching cubes
//! was slower than one thread on three of the four 64³ grids of the run committed before this
//! change. Set-ups tried on the way, each in five runs of this experiment cut to 64³ and 128³ (the
//! median over the runs of marching cubes' two-thread ratio against flying edges on two threads,
//! gyroid 64³; sphere, gyroid, asteroid and terrain 128³), all with the wake-one-at-a-time
//! parallel iterator:
//! - one pool with the caller as a thread: 0.87x; 2.07, 1.37, 1.54, 1.23x;
//! - a pool leaving the caller out, not pinned: 0.71x; 0.99, 1.08, 0.92, 0.97x (the first woken
//!   thread wakes the second while it works);
//! - a new two-thread pool for every one-shot call, its start-up inside the timing: 1.12x; 1.58,
//!   0.78, 1.45, 1.33x;
//! - a pool leaving the caller out with its two threads pinned: 1.18x; 1.71, 1.44, 1.47, 1.71x,
//!   but two-thread surface nets on the 128³ gyroid no faster than one thread.

use super::{Job, Peer, PeerError, PeerRun, Protocol};
use isolab_algorithms::extractors;
use isolab_algorithms::{Extraction, Extractor, Options};
use std::collections::HashMap;
use std::sync::{Arc, Mutex, OnceLock};

/// Whether a call from this thread with `threads` threads runs on rayon's global pool with the
/// caller outside it: the thread is in no pool and the global pool has exactly `threads` threads.
pub fn caller_outside(threads: usize) -> bool {
    rayon::current_thread_index().is_none() && rayon::current_num_threads() == threads
}

/// The pool of `threads` threads for calls that cannot use the global pool, shared by every
/// [`Ours`].
fn own_pool(threads: usize) -> Result<Arc<rayon::ThreadPool>, rayon::ThreadPoolBuildError> {
    static POOLS: OnceLock<Mutex<HashMap<usize, Arc<rayon::ThreadPool>>>> = OnceLock::new();
    let mut pools = POOLS.get_or_init(Default::default).lock().unwrap_or_else(|e| e.into_inner());
    if let Some(pool) = pools.get(&threads) {
        return Ok(pool.clone());
    }
    let pool = Arc::new(rayon::ThreadPoolBuilder::new().num_threads(threads).build()?);
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

    /// The extractor's settings in words, as a run on more than one thread builds it.
    pub fn settings(&self) -> String {
        self.build(2).map(|e| e.settings()).unwrap_or_default()
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
            n if caller_outside(n) => extractor.extract(samples, &mut out),
            _ => own_pool(threads)
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
