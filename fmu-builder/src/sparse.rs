//! Sparse helpers over faer: leading blocks, symmetric products and a factor-once solver.

use crate::error::{BuildError, Result};
use faer::linalg::solvers::Solve;
use faer::sparse::linalg::solvers::Llt;
use faer::sparse::{SparseColMat, Triplet};
use faer::{Mat, MatMut, MatRef, Par, Side};

pub type Sparse = SparseColMat<usize, f64>;

/// The block A[rows, cols] for index ranges.
pub fn block(a: &Sparse, rows: std::ops::Range<usize>, cols: std::ops::Range<usize>) -> Result<Sparse> {
    let mut trip = Vec::new();
    for j in cols.clone() {
        let rows_j = a.row_idx_of_col_raw(j);
        let vals = a.val_of_col(j);
        for (&i, &v) in rows_j.iter().zip(vals) {
            if rows.contains(&i) {
                trip.push(Triplet::new(i - rows.start, j - cols.start, v));
            }
        }
    }
    SparseColMat::try_new_from_triplets(rows.len(), cols.len(), &trip)
        .map_err(|e| BuildError::Numerical(format!("extracting a sparse block: {e:?}")))
}

/// out = A x
pub fn mul(out: MatMut<'_, f64>, a: &Sparse, x: MatRef<'_, f64>) {
    faer::sparse::linalg::matmul::sparse_dense_matmul(out, faer::Accum::Replace, a.as_ref(), x, 1.0, Par::Seq);
}

pub fn mul_new(a: &Sparse, x: MatRef<'_, f64>) -> Mat<f64> {
    let mut out = Mat::zeros(a.nrows(), x.ncols());
    mul(out.as_mut(), a, x);
    out
}

/// Sparse Cholesky of a symmetric positive definite matrix (fill-reducing ordering inside faer).
pub struct SpdSolver {
    llt: Llt<usize, f64>,
    n: usize,
}

impl SpdSolver {
    pub fn new(a: &Sparse, what: &str) -> Result<Self> {
        let llt = a.sp_cholesky(Side::Lower).map_err(|e| {
            BuildError::Numerical(format!(
                "{what} is not positive definite ({e:?}): the part may be under-constrained (a region not connected to the mount?)"
            ))
        })?;
        Ok(Self { llt, n: a.nrows() })
    }

    pub fn n(&self) -> usize {
        self.n
    }

    pub fn solve_in_place(&self, rhs: MatMut<'_, f64>) {
        self.llt.solve_in_place(rhs);
    }
}
