//! How soon a two-thread pool's second thread works on a job handed to it after the caller
//! idled, three ways of asking: what decides whether a short one-shot extraction gets any help
//! from a second thread on this machine.

use super::TWO;
use crate::experiment::context::ExperimentError;
use crate::report::{markdown_table, Spread};
use serde::{Deserialize, Serialize};
use std::time::{Duration, Instant};

/// A two-thread pool asked for work after the experiment's thread ran alone (and the pool slept)
/// for `idle_ms`: when both threads were working, microseconds after the request.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub(super) struct Wake {
    idle_ms: u64,
    /// A pool that counts the caller as one of its threads ([`WakeCaller::Inside`]; the pool our
    /// two-thread runs used before they called from outside).
    start_us: Spread,
    /// A pool that leaves the caller out, which waits ([`WakeCaller::Outside`]; absent from runs
    /// before it was measured).
    #[serde(default)]
    caller_outside_us: Option<Spread>,
    /// The caller outside wakes every thread and waits ([`WakeCaller::Broadcast`]; absent from
    /// runs before it was measured).
    #[serde(default)]
    broadcast_us: Option<Spread>,
}

/// Where the thread asking a two-thread pool for work is, and how it asks.
#[derive(Clone, Copy, Debug)]
enum WakeCaller {
    /// One of the pool's threads (`use_current_thread`): it runs its half of a `join` while the
    /// other thread is woken.
    Inside,
    /// Not one of them: it hands the pool a `join` and waits; the thread that takes it wakes the
    /// other (rayon's parallel iterators called from outside a pool).
    Outside,
    /// Not one of them: it wakes every thread with a broadcast and waits (our slab phases called
    /// from outside a pool, as our two-thread runs and the command line call them; VTK's caller).
    Broadcast,
}

/// Idle times before the request, ms, and requests per idle time.
const WAKE_IDLE_MS: [u64; 4] = [0, 1, 5, 20];
const WAKE_REQUESTS: usize = 9;

/// When both threads of a two-thread pool work on a job a caller hands it after idling `idle`,
/// microseconds after the request, per request. For `Inside` and `Outside` the job is a `join`
/// whose first half spins until the second half has started (at most 50 ms); for `Broadcast`, the
/// later of the two threads' start times. Each way runs on a thread and a pool of its own, so the
/// experiment's thread stays in no pool.
fn second_thread_start(idle: Duration, caller: WakeCaller) -> Result<Vec<f64>, ExperimentError> {
    use std::sync::atomic::{AtomicBool, Ordering};
    let join_start = |pool: &rayon::ThreadPool| {
        let started = AtomicBool::new(false);
        let asked = Instant::now();
        let mut waited = Duration::ZERO;
        pool.install(|| {
            rayon::join(
                || {
                    while !started.load(Ordering::Acquire) && asked.elapsed() < Duration::from_millis(50) {
                        std::hint::spin_loop();
                    }
                    waited = asked.elapsed();
                },
                || started.store(true, Ordering::Release),
            )
        });
        waited
    };
    let broadcast_start = |pool: &rayon::ThreadPool| {
        let asked = Instant::now();
        pool.broadcast(|_| asked.elapsed()).into_iter().max().unwrap_or_default()
    };
    let measure = |pool: &rayon::ThreadPool| {
        (0..WAKE_REQUESTS)
            .map(|_| {
                std::thread::sleep(idle);
                let waited = match caller {
                    WakeCaller::Broadcast => broadcast_start(pool),
                    WakeCaller::Inside | WakeCaller::Outside => join_start(pool),
                };
                waited.as_secs_f64() * 1e6
            })
            .collect::<Vec<f64>>()
    };
    std::thread::scope(|s| {
        s.spawn(|| {
            let builder = rayon::ThreadPoolBuilder::new().num_threads(TWO);
            let builder = if matches!(caller, WakeCaller::Inside) { builder.use_current_thread() } else { builder };
            let pool = builder.build().map_err(|e| ExperimentError::ThreadPool(e.to_string()))?;
            Ok(measure(&pool))
        })
        .join()
        .map_err(|_| ExperimentError::Failed {
            what: "measuring a second thread's start".into(),
            reason: "the measuring thread panicked".into(),
        })?
    })
}

/// The pools' wake-up times, measured before the grids on the pool our two-thread runs use.
pub(super) fn measure() -> Result<Vec<Wake>, ExperimentError> {
    WAKE_IDLE_MS
        .iter()
        .map(|&ms| {
            let idle = Duration::from_millis(ms);
            Ok(Wake {
                idle_ms: ms,
                start_us: Spread::of(second_thread_start(idle, WakeCaller::Inside)?),
                caller_outside_us: Some(Spread::of(second_thread_start(idle, WakeCaller::Outside)?)),
                broadcast_us: Some(Spread::of(second_thread_start(idle, WakeCaller::Broadcast)?)),
            })
        })
        .collect()
}

/// The page's paragraph and table on the pools' wake-up times (empty for runs before they were
/// measured).
pub(super) fn section(wake: &[Wake]) -> String {
    let mut md = String::new();
    if wake.is_empty() {
        return md;
    }
    md.push_str(
        "\nIn this run every call follows an idle, so every pool has slept when a call comes. \
         How soon both of a two-thread pool's threads work on a job handed to it after the caller idled, measured before \
         the grids (µs: median (fastest-slowest) of the requests), three ways: the caller inside the pool works its half \
         while it wakes the other thread; the caller outside the pool hands it a job and waits, and the thread that takes \
         the job wakes the other (rayon's parallel iterators called from outside a pool); the caller outside wakes both \
         threads at once and waits (a broadcast: our slab phases called from outside a pool, and VTK's caller; here the \
         time is when the later thread started, which does not show whether the two share a CPU at first). On this \
         machine a thread woken by a working thread can start milliseconds late; a one-shot extraction shorter than that \
         is over before the second thread helps.\n\n",
    );
    let rows: Vec<Vec<String>> = wake
        .iter()
        .map(|w| {
            let cell = |s: &Spread| format!("{:.0} ({:.0}-{:.0})", s.median, s.min, s.max);
            let optional = |s: &Option<Spread>| s.as_ref().map_or_else(|| "-".into(), cell);
            vec![format!("{}", w.idle_ms), cell(&w.start_us), optional(&w.caller_outside_us), optional(&w.broadcast_us)]
        })
        .collect();
    md.push_str(&markdown_table(
        &[
            "idle before the request (ms)",
            "both threads working after (µs): caller inside, working",
            "caller outside, waiting",
            "caller outside, waking both",
        ],
        &rows,
    ));
    md
}
