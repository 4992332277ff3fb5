//! A counting global allocator for the zero-allocation tests. It is the allocator
//! of the whole integration-test binary, so it counts per thread: only allocations
//! made on a thread that called [`measure_this_thread`] count, on that thread's own
//! counter (the harness's threads and the other tests, running in parallel, may
//! allocate at any time).

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

struct Counting;
thread_local! {
    static MEASURED: Cell<bool> = const { Cell::new(false) };
    static ALLOCS: Cell<usize> = const { Cell::new(0) };
}

fn tally() {
    if MEASURED.try_with(|m| m.get()).unwrap_or(false) {
        let _ = ALLOCS.try_with(|n| n.set(n.get() + 1));
    }
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, l: Layout) -> *mut u8 {
        tally();
        unsafe { System.alloc(l) }
    }
    unsafe fn dealloc(&self, p: *mut u8, l: Layout) {
        unsafe { System.dealloc(p, l) }
    }
    unsafe fn realloc(&self, p: *mut u8, l: Layout, n: usize) -> *mut u8 {
        tally();
        unsafe { System.realloc(p, l, n) }
    }
    unsafe fn alloc_zeroed(&self, l: Layout) -> *mut u8 {
        tally();
        unsafe { System.alloc_zeroed(l) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

/// Count allocations made on the calling thread from now on.
pub fn measure_this_thread() {
    MEASURED.with(|m| m.set(true));
}

/// Allocations counted so far on the calling thread.
pub fn allocations() -> usize {
    ALLOCS.with(|n| n.get())
}
