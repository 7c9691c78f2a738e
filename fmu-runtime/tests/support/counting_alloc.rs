//! A counting global allocator for no-allocation tests, shared by fmu-runtime's and
//! fmu-builder's tests/no_alloc.rs (`#[path]`-included: each test binary needs its own
//! `#[global_allocator]`). Counts per thread, so the test harness's other threads do not count.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

struct Counting;

thread_local! {
    static COUNTING: Cell<bool> = const { Cell::new(false) };
    static COUNT: Cell<usize> = const { Cell::new(0) };
}

fn note() {
    let _ = COUNTING.try_with(|on| {
        if on.get() {
            // nothing below may allocate: report the first offender's stack, once, untracked
            on.set(false);
            let first = COUNT.with(|c| {
                c.set(c.get() + 1);
                c.get() == 1
            });
            if first {
                eprintln!("first allocation at:\n{}", std::backtrace::Backtrace::force_capture());
            }
            on.set(true);
        }
    });
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        note();
        unsafe { System.alloc(layout) }
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        note();
        unsafe { System.alloc_zeroed(layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        note();
        unsafe { System.realloc(ptr, layout, new_size) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

/// Heap allocations (alloc, alloc_zeroed, realloc) made by this thread inside `f`.
pub fn allocations<R>(f: impl FnOnce() -> R) -> (usize, R) {
    COUNT.with(|c| c.set(0));
    COUNTING.with(|c| c.set(true));
    let r = f();
    COUNTING.with(|c| c.set(false));
    (COUNT.with(|c| c.get()), r)
}

/// `f`'s result; panics (with the count) if `f` allocated on this thread.
pub fn assert_no_allocation<R>(what: &str, f: impl FnOnce() -> R) -> R {
    let (n, r) = allocations(f);
    assert_eq!(n, 0, "{what}: {n} heap allocations (first one's stack on stderr)");
    r
}
