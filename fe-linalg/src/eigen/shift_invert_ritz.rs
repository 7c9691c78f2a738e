//! Rayleigh-Ritz of the shift-invert operator: a dense solver's vectors resolved as Lanczos
//! resolves its own.

use super::Eigenpairs;
use crate::error::{LinalgError, Result};
use crate::sparse::{Sparse, SpdSolve};
use crate::symmetric_eigen::symmetric_eigen;
use crate::symmetric_product::mul_new;
use faer::Mat;

/// Rayleigh-Ritz of the shift-invert operator on span(X): S = X^T M K^-1 M X (a refined solve)
/// against H = X^T M X, X Z with S z = theta H z, eigenvalues 1/theta - shift ascending.
///
/// Why: vectors accurate in the residual K x - lambda M x (a dense solver's, 2.5e-11 for a
/// beam's 18th mode) can hold a contamination by a low mode that the shift-invert residual
/// `checked` measures amplified by lambda/lambda_1 (1.2e-6 there, 5e4 times). The products of
/// this step resolve the low modes with the accuracy of the operator itself, as Lanczos does:
/// the same vectors then measure 1e-11.
pub(super) fn shift_invert_ritz(k: &dyn SpdSolve, m: &Sparse, x: Mat<f64>, shift: f64) -> Result<Eigenpairs> {
    let count = x.ncols();
    if count == 0 {
        return Ok(Eigenpairs { values: Vec::new(), vectors: x });
    }
    let mx = mul_new(m, x.as_ref());
    let mut y = mx.clone();
    k.solve_refined(y.as_mut());
    let s = mx.transpose() * &y;
    let h = mx.transpose() * &x;
    drop(mx);
    drop(y);
    let sym = |a: &Mat<f64>| Mat::<f64>::from_fn(count, count, |i, j| 0.5 * (a[(i, j)] + a[(j, i)]));
    let l = sym(&h).llt(faer::Side::Lower).map_err(|e| {
        LinalgError::inconsistent("eigensolver: the Ritz vectors are not independent in the mass inner product")
            .caused_by(e)
    })?;
    let l = l.L().to_owned();
    // C = L^-1 S L^-T
    let mut c = sym(&s);
    faer::linalg::triangular_solve::solve_lower_triangular_in_place(l.as_ref(), c.as_mut(), faer::Par::Seq);
    let mut ct = c.transpose().to_owned();
    faer::linalg::triangular_solve::solve_lower_triangular_in_place(l.as_ref(), ct.as_mut(), faer::Par::Seq);
    let eig = symmetric_eigen(&sym(&ct), "the shift-invert Rayleigh-Ritz step")?;
    // Z = L^-T W, theta descending = lambda ascending
    let mut w = eig.vectors.clone();
    faer::linalg::triangular_solve::solve_upper_triangular_in_place(l.transpose(), w.as_mut(), faer::Par::Seq);
    let order: Vec<usize> = {
        let mut o: Vec<usize> = (0..count).collect();
        o.sort_by(|&a, &b| eig.values[b].total_cmp(&eig.values[a]));
        o
    };
    let z = Mat::<f64>::from_fn(count, count, |i, j| w[(i, order[j])]);
    let values = order.iter().map(|&j| 1.0 / eig.values[j] - shift).collect();
    Ok(Eigenpairs { values, vectors: &x * &z })
}
