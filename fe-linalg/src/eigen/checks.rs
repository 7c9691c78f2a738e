//! Every returned pair measured with a solve of its own.

use super::Eigenpairs;
use super::block_lanczos::column_dots;
use crate::sparse::{Sparse, SpdSolve};
use crate::symmetric_product::mul_new;

/// The pairs with their eigenvalues from a fresh solve (refined as the Lanczos solves were), and
/// every pair's residual in the shift-invert operator's own norm: for each column x, y = A^-1 M x (A the factored
/// K + shift M), mu = 1/theta with theta = x^T M y / x^T M x the operator's Rayleigh quotient,
/// and |x - mu y|_M / |x|_M, what the Lanczos estimate claims, measured (a solve of its own: the
/// check must not share the Lanczos solves' round-off).
///
/// Unlike |K x - lambda M x| / |K x|, the residual does not grow with cond(K) for the lowest
/// modes of slender parts, and it bounds the eigenvalue's error (relative, about its square) and
/// the vector's angle (over the gap). The quotient's error is the residual's square too (high
/// modes in x weigh 1/mu_i in it, not mu_i as in x^T K x / x^T M x), it sums M-weighted terms
/// without cancellation, and costs no product with K; the projection's own values carry the
/// Lanczos solves' round-off (2e-12 on a refined cube with plain solves).
///
/// `refine`: one refinement step for the solve. Where the Lanczos solves went without (their
/// first block's correction was below 1e-10 of the solution: 1e-12 .. 1e-11 on the tet10
/// bracket), a plain solve is as exact here, perturbing the residual by that much against the
/// accepted 1e-7; the refinement's residual and second solve cost 1.4 s of 3.1 at 249k DoFs.
pub(super) fn checked(
    k: &dyn SpdSolve,
    m: &Sparse,
    pairs: Eigenpairs,
    shift: f64,
    refine: bool,
) -> (Eigenpairs, Vec<f64>) {
    let x = &pairs.vectors;
    let count = x.ncols();
    if count == 0 {
        return (pairs, Vec::new());
    }
    // at most two n x count matrices beside x at a time: M x (then the residual, then the
    // correction, in place) and y, then y (the residual x - mu y) and M y or M r
    let mut mx = mul_new(m, x.as_ref());
    let x2 = column_dots(x, &mx);
    let mut y = mx.clone();
    k.solve_plain(y.as_mut());
    if refine {
        // the correction is solved in place of M x
        k.residual(mx.as_mut(), y.as_ref());
        k.solve_plain(mx.as_mut());
        y += &mx;
    }
    drop(mx);
    // x^T M y = y^T (M x) by a product with y: M x was overwritten to save its memory
    let xmy = column_dots(x, &mul_new(m, y.as_ref()));
    let mut values = Vec::with_capacity(count);
    for c in 0..count {
        let mu = if xmy[c] > 0.0 && x2[c] > 0.0 { x2[c] / xmy[c] } else { pairs.values[c] + shift };
        values.push(mu - shift);
        // y becomes the residual x - mu y
        for (r, x) in y.col_mut(c).iter_mut().zip(x.col(c).iter()) {
            *r = x - mu * *r;
        }
    }
    let r2 = column_dots(&y, &mul_new(m, y.as_ref()));
    let residuals = (0..count)
        .map(|c| if x2[c] > 0.0 && xmy[c] > 0.0 { (r2[c].max(0.0) / x2[c]).sqrt() } else { f64::INFINITY })
        .collect();
    (Eigenpairs { values, vectors: pairs.vectors }, residuals)
}

/// Fold step for the largest residual and its index (NaN counts as largest).
pub(super) fn worst_of(worst: (f64, usize), (c, &r): (usize, &f64)) -> (f64, usize) {
    if !(r <= worst.0) { (r, c) } else { worst }
}
