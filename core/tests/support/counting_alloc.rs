//! A counting global allocator for the no-allocation tests, installed for the whole
//! binary by `core/tests/main.rs`. Its counters are per thread, so a test counts only its own allocations, and
//! also process-wide, for a test that runs alone in a process of its own and must see what
//! helper threads allocate ([`count_all_threads`]).

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::sync::atomic::{AtomicIsize, AtomicUsize, Ordering};

pub struct Counting;

thread_local! {
    static ALLOCATIONS: Cell<usize> = const { Cell::new(0) };
    static LIVE_BYTES: Cell<isize> = const { Cell::new(0) };
}

static ALL_ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);
static ALL_LIVE_BYTES: AtomicIsize = AtomicIsize::new(0);

// SAFETY: defers to the system allocator; the thread-local counters are const-initialised
// `Cell`s without destructors, so touching them never allocates or re-enters the allocator.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.with(|n| n.set(n.get() + 1));
        LIVE_BYTES.with(|b| b.set(b.get() + layout.size() as isize));
        ALL_ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        ALL_LIVE_BYTES.fetch_add(layout.size() as isize, Ordering::Relaxed);
        unsafe { System.alloc(layout) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        LIVE_BYTES.with(|b| b.set(b.get() - layout.size() as isize));
        ALL_LIVE_BYTES.fetch_sub(layout.size() as isize, Ordering::Relaxed);
        unsafe { System.dealloc(ptr, layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        ALLOCATIONS.with(|n| n.set(n.get() + 1));
        let grown = new_size as isize - layout.size() as isize;
        LIVE_BYTES.with(|b| b.set(b.get() + grown));
        ALL_ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        ALL_LIVE_BYTES.fetch_add(grown, Ordering::Relaxed);
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

/// (allocations, net bytes still live) made by `f` on this thread.
pub fn count(f: impl FnOnce()) -> (usize, isize) {
    let (n0, b0) = (ALLOCATIONS.with(Cell::get), LIVE_BYTES.with(Cell::get));
    f();
    (
        ALLOCATIONS.with(Cell::get) - n0,
        LIVE_BYTES.with(Cell::get) - b0,
    )
}

/// (allocations, net bytes still live) made by every thread of the process while `f` runs:
/// only meaningful when nothing else runs in the process (a test re-run alone in a child
/// process, see `sac_no_alloc.rs`). A helper's counts are seen because it hands its work back
/// to `f`'s thread with release/acquire (the kernels' team) before `f` returns.
pub fn count_all_threads(f: impl FnOnce()) -> (usize, isize) {
    let (n0, b0) = (
        ALL_ALLOCATIONS.load(Ordering::Acquire),
        ALL_LIVE_BYTES.load(Ordering::Acquire),
    );
    f();
    (
        ALL_ALLOCATIONS.load(Ordering::Acquire) - n0,
        ALL_LIVE_BYTES.load(Ordering::Acquire) - b0,
    )
}
