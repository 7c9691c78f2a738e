//! Small models solved densely. Block Lanczos needs a Krylov space several times the number of
//! wanted modes; in a model of a few dozen DoFs that space is the whole space, and an extension
//! past it orthogonalises round-off (a free 4 x 1 x 1 hex8 bar, 42 DoFs without its rigid modes,
//! "13 modes did not converge with 44 Lanczos vectors"). Below `DENSE_MAX_DOFS` every eigenpair
//! is computed at once, by Rayleigh-Ritz of the shift-invert operator on the whole space (less
//! the deflated rigid-body modes): exact up to round-off, and checked like every other solve.

use crate::error::Result;
use crate::sparse::Sparse;
use crate::symmetric_eigen::symmetric_eigen;
use faer::{Mat, MatRef};

/// Largest model solved densely: its n x n matrices are 2 MB and the decompositions take a
/// fraction of a second, where Lanczos would span most of the space anyway (it builds up to
/// 10 vectors per mode plus 200).
pub const DENSE_MAX_DOFS: usize = 500;

/// An orthonormal basis of the vectors M-orthogonal to the deflated ones Y, given M Y (the
/// null space of (M Y)^T): eigenvectors of (M Y)(M Y)^T for its n - r zero eigenvalues. The
/// identity without deflation. On it, Rayleigh-Ritz of the shift-invert operator gives every
/// eigenpair but the deflated ones exactly (the complement is invariant: Y are eigenvectors).
pub fn complement_basis(n: usize, m_deflated: Option<MatRef<'_, f64>>) -> Result<Mat<f64>> {
    let Some(my) = m_deflated.filter(|my| my.ncols() > 0) else {
        return Ok(Mat::identity(n, n));
    };
    let r = my.ncols();
    let gram = my * my.transpose();
    let eig = symmetric_eigen(&gram, "the complement of the rigid-body modes")?;
    Ok(eig.vectors.subcols(0, n - r).to_owned())
}

/// Whether the leading n x n block of M has a Cholesky factor.
/// (Rayleigh-Ritz on the whole space needs it; matrix inputs with massless DoFs lack it.)
pub fn mass_definite(m: &Sparse, n: usize) -> bool {
    let mut dense = Mat::<f64>::zeros(n, n);
    for j in 0..n.min(m.ncols()) {
        for (&i, &v) in m.row_idx_of_col_raw(j).iter().zip(m.val_of_col(j)) {
            if i < n {
                dense[(i, j)] = v;
            }
        }
    }
    dense.llt(faer::Side::Lower).is_ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_complement_is_orthonormal_and_m_orthogonal_to_the_deflated_vectors() {
        let n = 7;
        let y = Mat::<f64>::from_fn(n, 2, |i, j| ((i + 1) * (j + 2)) as f64 + if i == j { 3.0 } else { 0.0 });
        // a diagonal mass: M y is y scaled by rows
        let my = Mat::<f64>::from_fn(n, 2, |i, j| (1.0 + i as f64) * y[(i, j)]);
        assert_eq!(y.ncols(), 2);
        let z = complement_basis(n, Some(my.as_ref())).unwrap();
        assert_eq!((z.nrows(), z.ncols()), (n, n - 2));
        let ztz = z.transpose() * &z;
        let off = (ztz - Mat::<f64>::identity(n - 2, n - 2)).norm_max();
        assert!(off < 1e-13, "{off}");
        // measured ~1e-15 of |M y|: round-off of the 7 x 7 decomposition
        assert!((my.transpose() * &z).norm_max() < 1e-12 * my.norm_max());
    }
}
