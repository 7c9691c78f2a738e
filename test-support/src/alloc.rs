//! The counting global allocator behind the "no heap allocation per step" checks.
//!
//! A binary installs it with
//! `#[global_allocator] static ALLOCATOR: test_support::alloc::Counting = test_support::alloc::Counting;`
//! (each test binary needs its own, which is why this is not declared here: a library's
//! `#[global_allocator]` would be forced on every binary that links it). It then counts two ways:
//! - [`allocations`] / [`assert_no_allocation`]: this thread's allocations inside a closure, so
//!   the test harness's other threads do not count; the first offender's stack goes to stderr;
//! - [`total`]: every allocation of the process so far, for a driver whose work may use other
//!   threads (the benchmark's loops).
//!
//! Only the process's own allocator is seen: a dlopen'ed FMU binary has its own.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::sync::atomic::{AtomicUsize, Ordering};

/// The system allocator, counting alloc, alloc_zeroed and realloc (not dealloc).
pub struct Counting;

static TOTAL: AtomicUsize = AtomicUsize::new(0);

thread_local! {
    // const-initialised and without destructors: touching them never allocates
    static COUNTING: Cell<bool> = const { Cell::new(false) };
    static COUNT: Cell<usize> = const { Cell::new(0) };
}

fn note() {
    TOTAL.fetch_add(1, Ordering::Relaxed);
    // try_with: allocations during thread teardown, after the thread-locals are gone
    let _ = COUNTING.try_with(|on| {
        if on.get() {
            // the backtrace allocates: count it neither here nor anywhere
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

// SAFETY: every call is forwarded unchanged to the system allocator; counting touches no memory
// the allocator hands out.
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

/// Heap allocations of the whole process so far (every thread), through [`Counting`].
pub fn total() -> usize {
    TOTAL.load(Ordering::Relaxed)
}

/// Whether [`Counting`] is this process's global allocator: a probe allocation must be counted.
/// Without it every count would be a silent zero.
pub fn installed() -> bool {
    let before = total();
    drop(std::hint::black_box(Box::new(std::hint::black_box(0u64))));
    total() > before
}

/// Heap allocations (alloc, alloc_zeroed, realloc) made by this thread inside `f`, and its result.
///
/// Panics if [`Counting`] is not the global allocator.
pub fn allocations<R>(f: impl FnOnce() -> R) -> (usize, R) {
    assert!(installed(), "test_support::alloc::Counting is not this binary's #[global_allocator]");
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_this_threads_allocations_only() {
        assert!(installed());
        let (n, v) = allocations(|| vec![1u8; 100]);
        assert!(n >= 1, "{n}");
        assert_eq!(v.len(), 100);
        let before = total();
        let (n, ()) = allocations(|| {
            std::thread::scope(|s| {
                // spawning allocates on this thread too: the other thread's own vector is what
                // the per-thread count must leave out and the process's total must see
                s.spawn(|| std::hint::black_box(vec![0u64; 1 << 10]).len());
            })
        });
        let (spawn_only, ()) = allocations(|| std::thread::scope(|s| drop(s.spawn(|| 0))));
        assert!(n <= spawn_only + 1, "{n} allocations counted for spawning ({spawn_only} without the vector)");
        assert!(total() > before);
    }

    #[test]
    fn arithmetic_passes() {
        let x = assert_no_allocation("sum", || (0..1000u64).map(|k| k * k).sum::<u64>());
        assert_eq!(x, 332_833_500);
    }

    #[test]
    #[should_panic(expected = "boxed: 1 heap allocations")]
    fn an_allocation_fails() {
        assert_no_allocation("boxed", || drop(std::hint::black_box(Box::new(1u64))));
    }
}
