//! The one-shot protocol the criterion benches share with the `peers` experiment.

use criterion::{BatchSize, Bencher};

/// Times `call` one-shot: every timed call makes its output from nothing, and that output is
/// dropped right after its call, outside the timing, before the next call starts. This is what
/// `peers` does (every one-shot output is freed when its call returns), so a call can get pages
/// the allocator kept from the previous call's output, as repeated one-shot calls in a live
/// process do. `iter_with_large_drop`, used before, kept a whole batch of outputs alive, so every
/// call faulted in fresh pages, as only a process's very first call does, and our one-thread
/// one-shot times were a third to a half longer here than in `peers`.
///
/// Whether the pages come back is still glibc's choice, and it differs by implementation:
/// `fast-surface-nets` grows its buffers by doubling at the top of the heap, and in a loop that
/// does nothing else glibc trims that top after every call, so each call faults it in again. Its
/// one-shot time here is therefore longer than in `peers`, where (my reading) the other work
/// between its calls keeps the heap from shrinking; with `MALLOC_TOP_PAD_=67108864` (the heap
/// keeps 64 MiB) the two agree. The ratio against it in `peers` is the lower, conservative one.
pub fn one_shot<O>(b: &mut Bencher<'_>, mut call: impl FnMut() -> O) {
    b.iter_batched(|| (), |()| call(), BatchSize::PerIteration);
}
