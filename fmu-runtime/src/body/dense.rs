//! Dense kernels of the body's equations: dot products of a constant row or a state vector, and
//! a small dense solver. None allocates: they work on the caller's slices.

use crate::scalar::Scalar;

/// sum_j s_j x_j of a constant row and a state vector.
#[inline]
pub(super) fn shape_dot<T: Scalar>(s: &[f64], x: &[T]) -> T {
    let mut sum = T::zero();
    for (s, x) in s.iter().zip(x) {
        sum += *x * *s;
    }
    sum
}

#[inline]
pub(super) fn dot<T: Scalar>(a: &[T], b: &[T]) -> T {
    let mut sum = T::zero();
    for (a, b) in a.iter().zip(b) {
        sum += *a * *b;
    }
    sum
}

/// Solve A x = b in place (A row-major n x n, destroyed) by Gaussian elimination with partial
/// pivoting; Err on a singular matrix. Allocation-free, so fit for a step: every evaluation of a
/// free-floating body solves its 3 x 3 Schur complement for the angular acceleration here (on
/// stack arrays), and `settle_static` the n x n static equilibrium (on copies it makes at
/// initialisation).
pub(super) fn solve_dense<T: Scalar>(a: &mut [T], b: &mut [T], n: usize) -> Result<(), ()> {
    let scale = a.iter().fold(0.0f64, |m, v| m.max(v.value().abs()));
    for col in 0..n {
        let piv =
            (col..n).max_by(|&i, &j| a[i * n + col].value().abs().total_cmp(&a[j * n + col].value().abs())).ok_or(())?;
        // a NaN pivot is singular too (scale, a max ignoring NaN, is never NaN)
        let pivot = a[piv * n + col].value().abs();
        if pivot.is_nan() || pivot <= 1e-14 * scale {
            return Err(());
        }
        if piv != col {
            for k in 0..n {
                a.swap(piv * n + k, col * n + k);
            }
            b.swap(piv, col);
        }
        let d = a[col * n + col];
        for i in col + 1..n {
            let f = a[i * n + col] / d;
            if !f.is_zero() {
                for k in col..n {
                    let v = f * a[col * n + k];
                    a[i * n + k] -= v;
                }
                let v = f * b[col];
                b[i] -= v;
            }
        }
    }
    for col in (0..n).rev() {
        let mut s = T::zero();
        for k in col + 1..n {
            s += a[col * n + k] * b[k];
        }
        b[col] = (b[col] - s) / a[col * n + col];
    }
    Ok(())
}
