//! Dense kernels of the body's equations: dot products of a constant row or a state vector, and
//! a small dense solver. None allocates: they work on the caller's slices.

use crate::scalar::{Scalar, four_sums};

/// sum_j s_j x_j of a constant row and a state vector.
#[inline]
pub(crate) fn shape_dot<T: Scalar>(s: &[f64], x: &[T]) -> T {
    let mut sum = T::zero();
    for (s, x) in s.iter().zip(x) {
        sum += *x * *s;
    }
    sum
}

/// a . b over the shorter length, in four interleaved partial sums: independent chains the
/// processor keeps in flight (one chain waits on each add: the quasi-static right-hand sides,
/// rows of n values for each algebraic mode, took most of a spinning Model Exchange evaluation).
#[inline]
pub(crate) fn dot<T: Scalar>(a: &[T], b: &[T]) -> T {
    four_sums(a, b, |x, y| x * y)
}

/// Solve A x = b in place (A row-major n x n, destroyed) by Gaussian elimination with partial
/// pivoting ([`lu_factor`], [`lu_solve`]); Err on a singular matrix. Allocation-free, so fit for a
/// step: every evaluation of a free-floating body solves its 3 x 3 Schur complement for the
/// angular acceleration here (on stack arrays), and `settle_static` the n x n static equilibrium
/// (on copies it makes at initialisation). `pivots` holds n values.
pub(super) fn solve_dense<T: Scalar>(a: &mut [T], b: &mut [T], n: usize, pivots: &mut [usize]) -> Result<(), ()> {
    lu_factor(a, n, pivots)?;
    lu_solve(a, n, pivots, b);
    Ok(())
}

/// A = P^T L U in place (row-major n x n): the unit lower factor's multipliers below the
/// diagonal, U on and above it, and in pivots[c] the row exchanged with row c before column c
/// was eliminated (partial pivoting). Err on a singular matrix: a pivot at most 1e-14 of A's
/// largest entry, or NaN.
pub(crate) fn lu_factor<T: Scalar>(a: &mut [T], n: usize, pivots: &mut [usize]) -> Result<(), ()> {
    let scale = a.iter().fold(0.0f64, |m, v| m.max(v.value().abs()));
    for col in 0..n {
        let piv =
            (col..n).max_by(|&i, &j| a[i * n + col].value().abs().total_cmp(&a[j * n + col].value().abs())).ok_or(())?;
        // a NaN pivot is singular too (scale, a max ignoring NaN, is never NaN)
        let pivot = a[piv * n + col].value().abs();
        if pivot.is_nan() || pivot <= 1e-14 * scale {
            return Err(());
        }
        pivots[col] = piv;
        if piv != col {
            for k in 0..n {
                a.swap(piv * n + k, col * n + k);
            }
        }
        let d = a[col * n + col];
        // the pivot row apart from the rows below it: slices the compiler vectorises (indexing
        // both in one slice kept every update a bounds-checked scalar)
        let (top, below) = a[..n * n].split_at_mut((col + 1) * n);
        let pivot_row = &top[col * n + col + 1..];
        for row in below.chunks_exact_mut(n) {
            let f = row[col] / d;
            row[col] = f;
            if !f.is_zero() {
                for (x, p) in row[col + 1..].iter_mut().zip(pivot_row) {
                    let v = f * *p;
                    *x -= v;
                }
            }
        }
    }
    Ok(())
}

/// b = A^-1 b in place, from [`lu_factor`]'s factors of A.
pub(crate) fn lu_solve<T: Scalar>(a: &[T], n: usize, pivots: &[usize], b: &mut [T]) {
    // the exchanges first (the factorisation exchanged whole rows, the multipliers of earlier
    // columns with them), then the unit lower factor
    for (col, &piv) in pivots[..n].iter().enumerate() {
        b.swap(col, piv);
    }
    // row by row: contiguous rows of the row-major factor (a column walk strides by n)
    for i in 1..n {
        let s = dot(&a[i * n..i * n + i], &b[..i]);
        b[i] -= s;
    }
    for col in (0..n).rev() {
        let s = dot(&a[col * n + col + 1..(col + 1) * n], &b[col + 1..n]);
        b[col] = (b[col] - s) / a[col * n + col];
    }
}
