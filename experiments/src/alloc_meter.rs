//! Peak heap memory for the `scaling` experiment: the `peakmem-alloc` crate's counting wrapper
//! around the system allocator. A binary that wants the numbers installs it with
//! `install_meter!` (the `report` and `scaling` binaries do; the library cannot, or test
//! binaries with their own counting allocator would clash); elsewhere [`peak_since`] says `None`.

use peakmem_alloc::{PeakMemAllocTrait, INSTRUMENTED_SYSTEM};

/// Installs the counting allocator as this binary's global allocator.
#[macro_export]
macro_rules! install_meter {
    () => {
        #[global_allocator]
        static METER: &peakmem_alloc::PeakMemAlloc<std::alloc::System> = &peakmem_alloc::INSTRUMENTED_SYSTEM;
    };
}

/// Whether the counting allocator is this process's allocator.
pub fn installed() -> bool {
    INSTRUMENTED_SYSTEM.reset_peak_memory();
    drop(std::hint::black_box(vec![1u8; 4096]));
    INSTRUMENTED_SYSTEM.get_peak_memory() >= 4096
}

/// Runs `work` and returns its result with the most heap bytes it held at once beyond what was
/// held before (other threads' allocations in the meantime count too), or `None` when the
/// counting allocator is not installed.
pub fn peak_since<T>(work: impl FnOnce() -> T) -> (T, Option<usize>) {
    let metered = installed();
    INSTRUMENTED_SYSTEM.reset_peak_memory();
    let result = work();
    (result, metered.then(|| INSTRUMENTED_SYSTEM.get_peak_memory()))
}
