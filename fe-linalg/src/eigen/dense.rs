//! Small models: every pair at once, checked as Lanczos's are.

use super::checks::{checked, worst_of};
use super::shift_invert_ritz::shift_invert_ritz;
use super::{Deflation, Eigenpairs, MAX_MODES, Want};
use crate::error::{LinalgError, Result};
use crate::sparse::{Sparse, SpdSolve};
use crate::symmetric_product::mul_new;
use faer::Mat;

/// Largest accepted backward error |K x - lambda M x|_1 / ((|K|_1 + |lambda| |M|_1) |x|_1) of a
/// dense solve's pair. A dense symmetric solve is backward stable: its pairs are exact for
/// matrices within a few n eps of K and M (n eps is 1.1e-13 at `DENSE_MAX_DOFS`). Free hex8 bars
/// of 48 to 120 DoFs measure 9e-16 .. 2.7e-14 over their 18 lowest modes, while a vector carrying
/// 1e-6 of another mode, or an eigenvalue off by 1e-6, measures 1.4e-7 (the unit test's grid). The shift-invert
/// residual that holds the Lanczos solves (`RESIDUAL_TOL`) is not scaled to the matrices: on the
/// free 48-DoF bar it refused exact pairs (mode 17: 1.6e-7 against 1e-7; SciPy's frequencies
/// agree with the same pairs to 1.4e-12).
pub const DENSE_BACKWARD_TOL: f64 = 1e-11;

/// `search` for a small model: every pair at once (`dense_eigen`), the wanted ones kept and
/// checked as Lanczos's are; None where the dense path does not apply (M singular).
pub(super) fn dense_search(
    k: &dyn SpdSolve,
    m: &Sparse,
    want: Want,
    shift: f64,
    deflate: Option<&Deflation>,
) -> Result<Option<Eigenpairs>> {
    phases::phase("eigen-solve (dense, a small model)", || {
        let n = k.n();
        let leading;
        let m = if m.nrows() > n {
            leading = crate::sparse::block(m, 0..n, 0..n)?;
            &leading
        } else {
            m
        };
        use crate::dense_eigen::{complement_basis, mass_definite};
        let basis = complement_basis(n, deflate.map(|d| d.m_vectors.as_ref()))?;
        let all = match shift_invert_ritz(k, m, basis, shift) {
            Ok(all) => all,
            // the Ritz step's mass Gram matrix is not definite: M singular (Lanczos handles it)
            Err(_) if !mass_definite(m, n) => return Ok(None),
            Err(e) => return Err(e),
        };
        let available = all.values.len();
        let keep = match want {
            Want::Lowest(c) => c.min(available),
            Want::Below { omega_max, min_count } => {
                let below = all.values.iter().filter(|&&l| l.sqrt() < omega_max).count();
                below.max(min_count).min(available).min(MAX_MODES)
            }
        };
        let pairs =
            Eigenpairs { values: all.values[..keep].to_vec(), vectors: all.vectors.subcols(0, keep).to_owned() };
        let (pairs, _) = checked(k, m, pairs, shift, true);
        let errors = backward_errors(k, m, &pairs, shift);
        let (worst, at) = errors.iter().enumerate().fold((0.0f64, 0), worst_of);
        phases::note(|| format!("{keep} of {available} modes, {n} DoFs, backward error {worst:.1e}"));
        if worst > DENSE_BACKWARD_TOL {
            return Err(LinalgError::not_converged(format!(
                "eigensolver: mode {} of the dense solve of this {n}-DoF model has the backward error {worst:.1e} \
                 (accepted {DENSE_BACKWARD_TOL:.0e}): check the mesh for extreme element proportions",
                at + 1
            )));
        }
        Ok(Some(pairs))
    })
}

/// Every pair's backward error |K x - lambda M x|_1 / ((|K|_1 + |lambda| |M|_1) |x|_1), with `k`
/// factoring K + shift M. Scaled by the matrices' norms, it measures a rigid-body or low mode
/// (lambda ~ 0, K x ~ 0) as exactly as a high one. K is formed densely (n is at most
/// `DENSE_MAX_DOFS`) from the operator's own products, summed in double-double.
pub(super) fn backward_errors(k: &dyn SpdSolve, m: &Sparse, pairs: &Eigenpairs, shift: f64) -> Vec<f64> {
    let n = k.n();
    let identity = Mat::<f64>::identity(n, n);
    // b - A I with b = 0: -(K + shift M)
    let mut minus_a = Mat::<f64>::zeros(n, n);
    k.residual(minus_a.as_mut(), identity.as_ref());
    let md = mul_new(m, identity.as_ref());
    let kd = Mat::<f64>::from_fn(n, n, |i, j| -minus_a[(i, j)] - shift * md[(i, j)]);
    let norm_1 =
        |a: &Mat<f64>| (0..a.ncols()).map(|j| a.col(j).iter().map(|v| v.abs()).sum::<f64>()).fold(0.0, f64::max);
    let (k_norm, m_norm) = (norm_1(&kd), norm_1(&md));
    let x = &pairs.vectors;
    let (kx, mx) = (&kd * x, &md * x);
    (0..x.ncols())
        .map(|c| {
            let lambda = pairs.values[c];
            let r: f64 = kx.col(c).iter().zip(mx.col(c).iter()).map(|(a, b)| (a - lambda * b).abs()).sum();
            let x_norm: f64 = x.col(c).iter().map(|v| v.abs()).sum();
            let scale = (k_norm + lambda.abs() * m_norm) * x_norm;
            // NaN (a failed solve) and a zero vector are the largest errors
            if scale > 0.0 && r.is_finite() { r / scale } else { f64::INFINITY }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sparse::SpdSolver;
    use crate::test_grids::{diagonal, laplacian};

    /// The check refuses a wrong pair: the dense solve's own pairs pass (3e-16 .. 6e-16), and one
    /// whose vector carries 1e-6 of another mode, or whose eigenvalue is off by 1e-6, is refused
    /// (1.4e-7 both).
    #[test]
    fn the_backward_error_passes_exact_pairs_and_refuses_perturbed_ones() {
        let (k, m) = (laplacian(4, |_| 6.01), diagonal(4, |i| 1.0 + 0.5 * ((i * 7) % 5) as f64));
        let name = |d: usize| format!("row {d}");
        let solver = SpdSolver::new(std::borrow::Cow::Owned(k), "grid", &name).unwrap();
        let pairs = dense_search(&solver, &m, Want::Lowest(6), 0.0, None).unwrap().unwrap();
        assert_eq!(pairs.values.len(), 6);
        let exact = backward_errors(&solver, &m, &pairs, 0.0);
        assert!(exact.iter().all(|&e| e <= 1e-14), "exact pairs: {exact:?}");
        let mut vectors = pairs.vectors.clone();
        for i in 0..vectors.nrows() {
            vectors[(i, 5)] += 1e-6 * pairs.vectors[(i, 0)];
        }
        let mixed = Eigenpairs { values: pairs.values.clone(), vectors };
        let mixed = backward_errors(&solver, &m, &mixed, 0.0);
        assert!(mixed[5] > DENSE_BACKWARD_TOL, "a mixed vector: {:e}", mixed[5]);
        let mut values = pairs.values.clone();
        values[2] *= 1.0 + 1e-6;
        let shifted = backward_errors(&solver, &m, &Eigenpairs { values, vectors: pairs.vectors.clone() }, 0.0);
        assert!(shifted[2] > DENSE_BACKWARD_TOL, "a wrong eigenvalue: {:e}", shifted[2]);
    }
}
