//! What a free-floating body's reduction needs before its basis: a definite matrix to factor
//! (its stiffness is singular in the six rigid motions) and those rigid motions to deflate.

use crate::error::Result;
use crate::linalg::eigen::Deflation;
use crate::linalg::sparse::{Sparse, add_scaled, mul_new};
use faer::{Mat, Side};

/// K + s M with s well below the lowest elastic eigenvalue (1e-9 of the largest diagonal ratio):
/// definite for a free body, and a shift that small leaves the elastic spectrum's order intact.
pub fn shifted_stiffness(k: &Sparse, m: &Sparse) -> Result<(Sparse, f64)> {
    let n = k.nrows();
    let diag = |a: &Sparse, j: usize| -> f64 {
        a.row_idx_of_col_raw(j).iter().zip(a.val_of_col(j)).filter(|(i, _)| **i == j).map(|(_, v)| *v).sum()
    };
    let ratio = (0..n).map(|j| diag(k, j) / diag(m, j).max(f64::MIN_POSITIVE)).fold(0.0f64, f64::max);
    let s = 1e-9 * ratio;
    let sum = add_scaled(k, s, m)?;
    Ok((sum, s))
}

/// The rigid-body fields `r` (one column per rigid motion), M-orthonormalised: Y = R L^-T with
/// L L^T = R^T M R.
pub fn rigid_deflation(mass: &Sparse, r: Mat<f64>) -> Result<Deflation> {
    let mr = mul_new(mass, r.as_ref());
    let gram = r.transpose() * &mr;
    let l = gram
        .llt(Side::Lower)
        .map_err(|e| crate::error::BuildError::singular(format!("the rigid-body mass matrix is singular ({e}): the part has no mass in some direction; check material.rho")).caused_by(e))?
        .L()
        .to_owned();
    let mut yt = r.transpose().to_owned();
    faer::linalg::triangular_solve::solve_lower_triangular_in_place(l.as_ref(), yt.as_mut(), faer::Par::Seq);
    let vectors = yt.transpose().to_owned();
    let m_vectors = mul_new(mass, vectors.as_ref());
    Ok(Deflation { vectors, m_vectors })
}
