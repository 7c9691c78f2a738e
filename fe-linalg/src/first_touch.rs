//! Large buffers whose pages are touched on every core before the work that fills them, and
//! given back to the system when a buffer's tail is no longer needed.
//!
//! A fresh allocation of many megabytes is mapped but not backed: each 4 KiB page is backed at
//! its first touch, by a page fault. Faults taken where a scatter happens to write (pages in
//! random order, one at a time, between the work) are slow, and on a virtual machine slower
//! still when two threads take them at once. The assembly's adding step on the 2.4e5-DoF
//! bracket (2 cores): 0.54-0.64 s on one thread, 0.66-1.02 s on two; with its 170 MB of values
//! touched first, in order and in parallel, 0.40-0.49 s on one and 0.22-0.30 s on two (the
//! touch itself 0.13 s on one, 0.06 s on two). The factor's values were the first case found:
//! 1.27 GB took 3 s touched from one thread, one supernode at a time.

use rayon::prelude::*;

/// Pages touched by one task: 2 MiB, a huge page's worth, so that a gigabyte makes some five
/// hundred tasks for the cores to share.
const CHUNK: usize = 1 << 18;

/// Writes zeros over `buffer` in parallel chunks, in order within each: every page is backed
/// before the buffer is used.
pub fn touch_zeroed(buffer: &mut [f64]) {
    buffer.par_chunks_mut(CHUNK).for_each(|c| c.fill(0.0));
}

/// `len` zeros whose pages are already backed (see [`touch_zeroed`]).
pub fn touched_zeros(len: usize) -> Vec<f64> {
    let mut v = vec![0.0; len];
    touch_zeroed(&mut v);
    v
}

/// Gives the memory pages wholly inside the `len` values from `start` back to the system, without
/// freeing the allocation they belong to: the values there are lost (read again, they are
/// zeros). For the tail of a large matrix whose allocation cannot shrink (faer's `Mat` keeps its
/// capacity): the Ritz vectors formed in the Lanczos space's storage leave most of it unused.
///
/// # Safety
/// `start .. start + len` must lie within one live allocation that nothing reads or writes
/// until it is written again or freed.
pub unsafe fn give_back(start: *mut f64, len: usize) {
    #[cfg(target_os = "linux")]
    {
        // SAFETY: sysconf has no preconditions
        let page = unsafe { libc::sysconf(libc::_SC_PAGESIZE) }.max(4096) as usize;
        let begin = (start as usize).next_multiple_of(page);
        let end = start as usize + len * std::mem::size_of::<f64>();
        let end = end - end % page;
        if end > begin {
            // SAFETY: whole pages inside the caller's range (its safety contract): MADV_DONTNEED
            // on private anonymous or heap memory makes them read as zeros from now on, which
            // the caller does not rely on either way
            unsafe {
                libc::madvise(begin as *mut libc::c_void, end - begin, libc::MADV_DONTNEED);
            }
        }
    }
    #[cfg(not(target_os = "linux"))]
    let _ = (start, len);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn touched_zeros_are_zeros_of_the_asked_length() {
        for len in [0, 1, CHUNK - 1, CHUNK, 3 * CHUNK + 7] {
            let v = touched_zeros(len);
            assert_eq!(v.len(), len);
            assert!(v.iter().all(|&x| x == 0.0), "len {len}");
        }
    }

    #[test]
    fn touching_overwrites_every_value_with_zero() {
        let mut v: Vec<f64> = (0..2 * CHUNK + 5).map(|i| i as f64 + 1.0).collect();
        touch_zeroed(&mut v);
        assert!(v.iter().all(|&x| x == 0.0));
    }

    /// The pages inside the range read as zeros after (Linux), the values around it are kept.
    #[test]
    fn given_back_pages_read_as_zeros_and_the_rest_is_kept() {
        let len = 4 * CHUNK;
        let mut v: Vec<f64> = (0..len).map(|i| i as f64 + 1.0).collect();
        let from = CHUNK + 3;
        // SAFETY: the range lies within v, which nothing reads until the checks below
        unsafe { give_back(v.as_mut_ptr().add(from), len - from) };
        assert!(v[..from].iter().enumerate().all(|(i, &x)| x == i as f64 + 1.0));
        if cfg!(target_os = "linux") {
            // from the first page boundary after `from` to the last before the end, every value
            // is gone (pages of 4 KiB to 64 KiB: at most 8192 values kept at either end)
            let zeros = v[from..].iter().filter(|&&x| x == 0.0).count();
            assert!(zeros >= len - from - 2 * 8192, "{zeros} of {}", len - from);
            assert_eq!(v[len / 2], 0.0);
        }
    }
}
