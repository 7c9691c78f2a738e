//! Large buffers whose pages are touched on every core before the work that fills them.
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
}
