//! The process's resident memory, from `/proc/self/status` (Linux; `None` elsewhere), and the
//! memory floor a grid's extraction cannot beat (`peers` and `scaling` measure it).

use std::time::{Duration, Instant};

/// The process's peak resident memory (`VmHWM`), MiB, where the OS reports it.
pub fn peak_rss_mib() -> Option<f64> {
    proc_status_kib("VmHWM:").map(|k| k as f64 / 1024.0)
}

/// The process's resident memory now (`VmRSS`), MiB.
pub fn rss_mib() -> Option<f64> {
    proc_status_kib("VmRSS:").map(|k| k as f64 / 1024.0)
}

/// Resets the peak resident memory to the current one (Linux `clear_refs` 5); false if the OS
/// does not allow it.
pub fn reset_peak_rss() -> bool {
    std::fs::write("/proc/self/clear_refs", "5").is_ok()
}

fn proc_status_kib(key: &str) -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    status.lines().find(|l| l.starts_with(key))?.split_whitespace().nth(1)?.parse().ok()
}

/// The memory floor: one read of every sample (a sum the optimiser cannot drop) and one write of
/// `bytes` (filling a buffer allocated beforehand).
pub fn floor(values: &[f32], bytes: usize) -> (Duration, Duration) {
    // Eight independent lanes so the sum is limited by memory, not by the adder's latency.
    let t = Instant::now();
    let mut lanes = [0.0f32; 8];
    let chunks = values.chunks_exact(8);
    let rest: f32 = chunks.remainder().iter().sum();
    for c in chunks {
        for (l, v) in lanes.iter_mut().zip(c) {
            *l += v;
        }
    }
    let read = t.elapsed();
    std::hint::black_box((lanes, rest));
    // The buffer is touched once first: page faults are an allocator's cost, not the floor's.
    let mut buffer = vec![0u8; bytes];
    buffer.iter_mut().for_each(|b| *b = 2);
    std::hint::black_box(&buffer);
    let t = Instant::now();
    buffer.iter_mut().for_each(|b| *b = 1);
    let write = t.elapsed();
    std::hint::black_box(&buffer);
    (read, write)
}
