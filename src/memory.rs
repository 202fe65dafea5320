//! The process's memory, as training sees it: mimalloc as the allocator, told to keep
//! what is freed (and, under an address-space limit, to reserve none ahead), counting
//! its calls while asked to, and the minor page faults so far.
//! `bench` prints both counts per training step; a test holds the page faults of a warm
//! step at zero.

use mimalloc::MiMalloc;
use std::alloc::{GlobalAlloc, Layout};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

/// mimalloc's option number for the delay before it gives freed pages back to the kernel
/// (`mi_option_purge_delay` in its header; the crate does not name it).
const PURGE_DELAY: libmimalloc_sys::mi_option_t = 15;

/// mimalloc's option number for the address space it reserves ahead for its arenas,
/// KiB (`mi_option_arena_reserve` in its header, 1 GiB by default; the crate does not
/// name it).
const ARENA_RESERVE: libmimalloc_sys::mi_option_t = 23;

/// Under an address-space limit (`ulimit -v`), tells the allocator to reserve no arena
/// ahead: it otherwise reserves 1 GiB of address space at its first allocation where
/// the limit leaves room for it and none where it does not, so that the address space
/// left for a command swung by a gigabyte with the limit, and a command could not tell
/// what it may use. Without one, nothing changes. The binary calls it before the
/// process's first allocation (a constructor of its own).
pub extern "C" fn reserve_no_arena_under_an_address_limit() {
    if address_space_limit().is_some() {
        // SAFETY: mi_option_set only sets one of the allocator's parameters.
        unsafe { libmimalloc_sys::mi_option_set(ARENA_RESERVE, 0) };
        // glibc's allocator, which the C libraries and the threads' own bookkeeping
        // use, reserves 64 MiB of address space for each thread's arena: one arena
        // for them all serves their few allocations.
        // SAFETY: mallopt only sets one of glibc's allocator parameters.
        #[cfg(all(target_os = "linux", target_env = "gnu"))]
        unsafe {
            libc::mallopt(libc::M_ARENA_MAX, 1);
        }
    }
}

/// The process's address-space limit (`ulimit -v`), bytes; `None` where there is none.
pub fn address_space_limit() -> Option<u64> {
    #[cfg(unix)]
    {
        let mut limit = libc::rlimit {
            rlim_cur: 0,
            rlim_max: 0,
        };
        // SAFETY: getrlimit writes one rlimit, which `limit` is.
        let read = unsafe { libc::getrlimit(libc::RLIMIT_AS, &mut limit) };
        if read == 0 && limit.rlim_cur != libc::RLIM_INFINITY {
            return Some(limit.rlim_cur);
        }
    }
    None
}

/// Tells the allocator to keep what is freed. A training step still makes about 850
/// short-lived allocations that are not ours (burn's tensors and autodiff nodes, the
/// matrix products' scratch). glibc's allocator served them among the step's
/// longer-lived buffers from a heap that crept up by a few fresh pages now and then for
/// thousands of steps, each a page fault; mimalloc serves each size from its own pages,
/// so a warm step reuses the blocks the last one freed, and with purging off the pages
/// stay mapped.
pub fn keep_freed_memory() {
    // SAFETY: mi_option_set only sets one of the allocator's parameters.
    unsafe { libmimalloc_sys::mi_option_set(PURGE_DELAY, -1) };
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

/// mimalloc, counting its calls (allocations and reallocations) while
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

// SAFETY: every call goes to mimalloc unchanged; counting touches only atomics.
unsafe impl GlobalAlloc for CountingAllocator {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        count();
        unsafe { MiMalloc.alloc(layout) }
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        count();
        unsafe { MiMalloc.alloc_zeroed(layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        count();
        unsafe { MiMalloc.realloc(ptr, layout, new_size) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { MiMalloc.dealloc(ptr, layout) }
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
