//! How far the coupling has moved from the one the coupled transition was made for, bounded
//! from the few coefficients the coupling matrices are combined with (the body-frame spin w,
//! its rate z, the mount's acceleration a_B and the flange wrenches; see `coupling_terms`).
//!
//! A spin-up step keeps the exact transition of a reference coupling and treats the difference
//! dC as a load (the predictor-corrector of `cosim_step`), which is accurate while h |dC| is
//! small in the norm of the transition's own state [Omega q; q'], the energy norm: the spectral
//! norm of [dC_k Omega^-1, dC_d]. Each coefficient c_k multiplies fixed matrices S_k (in C_k)
//! and D_k (in C_d), so
//!   |[dC_k Omega^-1, dC_d]| <= sqrt((sum |dc_k| |S_k Omega^-1|)^2 + (sum |dc_k| |D_k|)^2)
//! (`CouplingTerms::drift_bound`), with the norms of the terms computed here once per body
//! ([`energy_norm`]): a test of a few dozen
//! multiply-adds per step in place of a norm of two n x n matrices. The matrices' largest row
//! sums, which the test used before, exceed the spectral norm 2.5 times on a spinning beam, so
//! the reference was renewed (one exponential) 2.5 times as often as the energy needs.

/// The spectral norms are estimated by power iteration, which approaches from below; the
/// estimate is raised by this factor (the iteration stops once it changes by less than 1e-6 of
/// itself; on the unit test's 12-mode body it is then within 1e-6 of the exact norm).
pub(super) const ESTIMATE_MARGIN: f64 = 1.05;

/// An upper bound of the spectral norm of the n x n row-major `matrix` as the transition's state
/// sees it: a term of C_k acts on q = Omega^-1 (Omega q), its columns divided by `omega`
/// (`Some`); a term of C_d on q' as it is (`None`). Zero for an empty matrix.
pub(super) fn energy_norm(n: usize, matrix: &[f64], omega: Option<&[f64]>, scratch: &mut (Vec<f64>, Vec<f64>)) -> f64 {
    if matrix.len() != n * n || n == 0 {
        return 0.0;
    }
    let mut scaled = matrix.to_vec();
    if let Some(omega) = omega {
        for row in scaled.chunks_exact_mut(n) {
            for (m, w) in row.iter_mut().zip(omega) {
                *m /= w;
            }
        }
    }
    let estimate = spectral_norm(n, &scaled, scratch);
    // a start vector the matrix maps to zero leaves the estimate at zero for a matrix that is
    // not: the term would then never count as drift (nor its force be added). The Frobenius
    // norm bounds the spectral norm from above.
    if estimate > 0.0 { ESTIMATE_MARGIN * estimate } else { scaled.iter().map(|v| v * v).sum::<f64>().sqrt() }
}

/// Largest singular value of the n x n row-major `b`: power iteration on b^T b from a vector
/// with no symmetry of its own, until the estimate changes by less than 1e-6 of itself.
fn spectral_norm(n: usize, b: &[f64], (v, u): &mut (Vec<f64>, Vec<f64>)) -> f64 {
    for (j, x) in v.iter_mut().enumerate() {
        *x = 1.0 + ((j * 7919) % 31) as f64 / 31.0;
    }
    let mut estimate = 0.0;
    for _ in 0..1000 {
        let norm_v = v.iter().map(|x| x * x).sum::<f64>().sqrt();
        if norm_v == 0.0 || !norm_v.is_finite() {
            return estimate;
        }
        for x in v.iter_mut() {
            *x /= norm_v;
        }
        // u = b v, |u| the estimate; v = b^T u
        for (i, ui) in u.iter_mut().enumerate() {
            *ui = b[i * n..(i + 1) * n].iter().zip(v.iter()).map(|(x, y)| x * y).sum();
        }
        let next = u.iter().map(|x| x * x).sum::<f64>().sqrt();
        v.fill(0.0);
        for (i, ui) in u.iter().enumerate() {
            for (x, bij) in v.iter_mut().zip(&b[i * n..(i + 1) * n]) {
                *x += bij * ui;
            }
        }
        let settled = (next - estimate).abs() <= 1e-6 * next;
        estimate = next;
        if settled {
            break;
        }
    }
    estimate
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The estimate is the margin times the largest singular value: of a diagonal matrix its
    /// largest |entry|, of a rank-one u v^T the product of the norms (both exact: the iteration
    /// converges to them to its 1e-6 stopping rule); with the columns divided by omega. Never
    /// zero for a matrix that is not, even one that maps the iteration's start vector to zero.
    #[test]
    fn the_estimate_is_the_margin_over_the_largest_singular_value() {
        let n = 5;
        let mut scratch = (vec![0.0; n], vec![0.0; n]);
        let diagonal: Vec<f64> =
            (0..n * n).map(|k| if k % (n + 1) == 0 { [2.0, -7.0, 3.0, 0.5, 1.0][k / n] } else { 0.0 }).collect();
        let found = energy_norm(n, &diagonal, None, &mut scratch);
        assert!((found / ESTIMATE_MARGIN - 7.0).abs() <= 7.0 * 1e-5, "diagonal: {found}");
        let omega = [1.0, 2.0, 4.0, 8.0, 16.0];
        // columns / omega: diag(2, -3.5, 0.75, 0.0625, 0.0625)
        let found = energy_norm(n, &diagonal, Some(&omega), &mut scratch);
        assert!((found / ESTIMATE_MARGIN - 3.5).abs() <= 3.5 * 1e-5, "scaled diagonal: {found}");
        let (u, v) = ([1.0, 2.0, -1.0, 0.5, 3.0], [0.3, -0.2, 0.1, 1.0, 0.4]);
        let rank_one: Vec<f64> = (0..n * n).map(|k| u[k / n] * v[k % n]).collect();
        let exact = u.iter().map(|x| x * x).sum::<f64>().sqrt() * v.iter().map(|x| x * x).sum::<f64>().sqrt();
        let found = energy_norm(n, &rank_one, None, &mut scratch);
        assert!((found / ESTIMATE_MARGIN - exact).abs() <= exact * 1e-5, "rank one: {found} against {exact}");
        assert_eq!(energy_norm(n, &[], None, &mut scratch), 0.0);
        assert_eq!(energy_norm(n, &vec![0.0; n * n], None, &mut scratch), 0.0);
        // rank one, its row orthogonal to the iteration's start vector: the start maps to zero,
        // the bound falls back to the Frobenius norm (here the exact norm)
        let start: Vec<f64> = (0..n).map(|j| 1.0 + ((j * 7919) % 31) as f64 / 31.0).collect();
        let mut row = vec![0.0; n];
        (row[0], row[1]) = (start[1], -start[0]);
        let blind: Vec<f64> = (0..n * n).map(|k| if k < n { row[k] } else { 0.0 }).collect();
        let exact = row.iter().map(|x| x * x).sum::<f64>().sqrt();
        let found = energy_norm(n, &blind, None, &mut scratch);
        assert!(found >= exact * (1.0 - 1e-12), "a matrix blind to the start vector: {found} below {exact}");
    }
}
