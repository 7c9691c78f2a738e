//! An allocation that fails despite the size check (the estimate is an estimate, and other
//! processes take memory meanwhile) ends the build with an error that says what was estimated
//! and what was available, instead of Rust's abort (SIGABRT, "memory allocation failed").
//!
//! The builder's binary installs [`ReportingAllocator`] as its global allocator; it forwards
//! to the system allocator and only acts when that returns null. The report is written without
//! allocating (a fixed buffer, `write(2)`), then the process exits with status 1.

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::Mutex;
use std::sync::atomic::{AtomicU64, Ordering};

static ESTIMATE_BYTES: AtomicU64 = AtomicU64::new(0);
static AVAILABLE_BYTES: AtomicU64 = AtomicU64::new(0);
/// Where the available figure comes from (a static sentence of `input::size::Memory`).
static SOURCE: Mutex<&'static str> = Mutex::new("");

/// Keeps the latest size check's figures for the report of a failed allocation.
pub fn record_estimate(estimate_bytes: f64, available_bytes: f64, source: &'static str) {
    ESTIMATE_BYTES.store(estimate_bytes.max(0.0) as u64, Ordering::Relaxed);
    AVAILABLE_BYTES.store(available_bytes.max(0.0) as u64, Ordering::Relaxed);
    if let Ok(mut s) = SOURCE.try_lock() {
        *s = source;
    }
}

/// The system allocator, reporting a failed allocation as a build error (see the module text).
pub struct ReportingAllocator;

// SAFETY: every method forwards to `System` unchanged; the null case does not return
unsafe impl GlobalAlloc for ReportingAllocator {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        // SAFETY: the caller's contract is passed on
        let p = unsafe { System.alloc(layout) };
        if p.is_null() {
            report_and_exit(layout.size());
        }
        p
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        // SAFETY: the caller's contract is passed on
        let p = unsafe { System.alloc_zeroed(layout) };
        if p.is_null() {
            report_and_exit(layout.size());
        }
        p
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: the caller's contract is passed on
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        // SAFETY: the caller's contract is passed on
        let p = unsafe { System.realloc(ptr, layout, new_size) };
        if p.is_null() {
            report_and_exit(new_size);
        }
        p
    }
}

/// A `fmt::Write` into a fixed buffer: formatting without the heap.
struct FixedBuffer {
    bytes: [u8; 1024],
    len: usize,
}

impl std::fmt::Write for FixedBuffer {
    fn write_str(&mut self, s: &str) -> std::fmt::Result {
        let n = s.len().min(self.bytes.len() - self.len);
        self.bytes[self.len..self.len + n].copy_from_slice(&s.as_bytes()[..n]);
        self.len += n;
        Ok(())
    }
}

/// The message for a failed allocation of `size` bytes (estimate and availability as recorded).
pub fn message(size: usize, out: &mut impl std::fmt::Write) -> std::fmt::Result {
    let gib = |b: u64| b as f64 / (1u64 << 30) as f64;
    write!(out, "error: out of memory: an allocation of {:.2} GiB failed", gib(size as u64))?;
    let estimate = ESTIMATE_BYTES.load(Ordering::Relaxed);
    if estimate > 0 {
        let source = SOURCE.try_lock().map(|s| *s).unwrap_or("");
        write!(
            out,
            "; the model was estimated to need about {:.1} GiB and {:.1} GiB were available ({source}), so the \
             estimate fell short or other processes took memory meanwhile",
            gib(estimate),
            gib(AVAILABLE_BYTES.load(Ordering::Relaxed)),
        )?;
    }
    writeln!(out, ". Use fewer elements, or free or raise the memory limit (ulimit -v, the cgroup's memory.max)")
}

fn report_and_exit(size: usize) -> ! {
    let mut buffer = FixedBuffer { bytes: [0; 1024], len: 0 };
    let _ = message(size, &mut buffer);
    // SAFETY: write(2) of our own buffer to stderr, then _exit(2): no allocation, no unwinding,
    // no atexit handlers that might allocate
    unsafe {
        libc::write(2, buffer.bytes.as_ptr().cast(), buffer.len);
        libc::_exit(1)
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn the_message_names_the_allocation_the_estimate_and_the_limit() {
        super::record_estimate(3.5 * (1u64 << 30) as f64, 3.0 * (1u64 << 30) as f64, "a test's limit");
        let mut m = String::new();
        super::message(1 << 30, &mut m).unwrap();
        assert!(m.starts_with("error: out of memory: an allocation of 1.00 GiB failed"), "{m}");
        assert!(m.contains("about 3.5 GiB and 3.0 GiB were available (a test's limit)"), "{m}");
        assert!(m.contains("ulimit -v"), "{m}");
    }
}
