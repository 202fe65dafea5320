//! The process's memory, as training sees it: glibc's allocator told to keep what is
//! freed, an allocator that counts its calls while asked to, and the minor page faults
//! so far. `bench` prints both counts per training step; a test holds the page faults
//! of a warm step at zero.

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

/// glibc's allocator gives a freed block of over 128 KiB back to the kernel and maps
/// fresh zeroed pages for the next one, a page fault for every page touched again.
/// Training allocates buffers of that size thousands of times a second, so freed memory
/// stays in the heap instead: `dcnet-exp run experiments/paper.toml --set
/// training.epochs=2` measured 38.6 s with glibc's defaults and 34.8 s with these, for
/// 3 % more memory. A no-op on other C libraries.
pub fn keep_freed_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: mallopt only sets the allocator's parameters.
    unsafe {
        libc::mallopt(libc::M_MMAP_THRESHOLD, 256 << 20);
        libc::mallopt(libc::M_TRIM_THRESHOLD, 1 << 30);
    }
}

/// Asks the kernel to back `values` with 2 MiB pages where it can (Linux with
/// transparent huge pages in `madvise` mode; a no-op elsewhere). Call it before the
/// values are first written, so that the pages are huge from their first touch. Training
/// reads its windows from a set of hundreds of MB in random order, and with 4 KiB pages
/// nearly every window read missed the TLB.
pub fn prefer_huge_pages(values: &mut [f32]) {
    #[cfg(target_os = "linux")]
    {
        const HUGE: usize = 2 << 20;
        let start = values.as_mut_ptr() as usize;
        let end = start + std::mem::size_of_val(values);
        let (first, last) = (start.next_multiple_of(HUGE), end / HUGE * HUGE);
        if last > first {
            // SAFETY: the range lies inside `values`, which this thread borrows mutably;
            // the advice changes how its pages are backed, never its contents.
            unsafe {
                libc::madvise(
                    first as *mut libc::c_void,
                    last - first,
                    libc::MADV_HUGEPAGE,
                );
            }
        }
    }
    #[cfg(not(target_os = "linux"))]
    let _ = values;
}

/// The system allocator, counting its calls (allocations and reallocations) while
/// [`count_allocations`] runs. Outside that, each call reads one flag that no thread
/// writes, so it costs nothing measurable and no cache line moves between cores.
pub struct CountingAllocator;

static COUNTING: AtomicBool = AtomicBool::new(false);
static CALLS: AtomicU64 = AtomicU64::new(0);

fn count() {
    if COUNTING.load(Ordering::Relaxed) {
        CALLS.fetch_add(1, Ordering::Relaxed);
    }
}

// SAFETY: every call goes to `System` unchanged; counting touches only atomics.
unsafe impl GlobalAlloc for CountingAllocator {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        count();
        unsafe { System.alloc(layout) }
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        count();
        unsafe { System.alloc_zeroed(layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        count();
        unsafe { System.realloc(ptr, layout, new_size) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
}

/// `f`'s result and the allocator calls made while it ran, by every thread; `None` where
/// the process's allocator is not a [`CountingAllocator`].
pub fn count_allocations<R>(f: impl FnOnce() -> R) -> (R, Option<u64>) {
    let start = CALLS.load(Ordering::Relaxed);
    COUNTING.store(true, Ordering::Relaxed);
    let probe = std::hint::black_box(Box::new(0u8));
    let installed = CALLS.load(Ordering::Relaxed) > start;
    drop(probe);
    let start = CALLS.load(Ordering::Relaxed);
    let result = f();
    let calls = CALLS.load(Ordering::Relaxed) - start;
    COUNTING.store(false, Ordering::Relaxed);
    (result, installed.then_some(calls))
}

/// The process's minor page faults so far (a page mapped on first touch), all threads;
/// `None` where the system does not say.
pub fn minor_page_faults() -> Option<u64> {
    #[cfg(unix)]
    {
        // SAFETY: getrusage fills the struct it is given.
        let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
        (unsafe { libc::getrusage(libc::RUSAGE_SELF, &mut usage) } == 0)
            .then_some(usage.ru_minflt as u64)
    }
    #[cfg(not(unix))]
    None
}
