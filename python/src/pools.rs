//! `threads=N`: a rayon pool of N threads per N asked for, built on first use and kept (a pool
//! per call would start N threads every call); `None` is rayon's global pool.

use pyo3::exceptions::PyValueError;
use pyo3::PyResult;
use std::sync::{Arc, Mutex};

static POOLS: Mutex<Vec<(usize, Arc<rayon::ThreadPool>)>> = Mutex::new(Vec::new());

/// The kept pool of `threads` threads (`None`: the global pool, returned as `None`).
pub fn pool(threads: Option<usize>) -> PyResult<Option<Arc<rayon::ThreadPool>>> {
    let Some(n) = threads else { return Ok(None) };
    if n == 0 {
        return Err(PyValueError::new_err("threads must be at least 1"));
    }
    let mut pools = POOLS.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
    if let Some((_, p)) = pools.iter().find(|(k, _)| *k == n) {
        return Ok(Some(p.clone()));
    }
    let built = rayon::ThreadPoolBuilder::new()
        .num_threads(n)
        .thread_name(move |i| format!("isolab-{n}-{i}"))
        .build()
        .map_err(|e| PyValueError::new_err(format!("cannot start {n} threads: {e}")))?;
    let built = Arc::new(built);
    pools.push((n, built.clone()));
    Ok(Some(built))
}

/// Runs `f` on `pool`, or where it is called (the global pool) without one.
pub fn install<R: Send>(pool: Option<&rayon::ThreadPool>, f: impl FnOnce() -> R + Send) -> R {
    match pool {
        Some(p) => p.install(f),
        None => f(),
    }
}
