//! Sparse LU of a general matrix.

use super::Sparse;
use super::mul_compensated;
use crate::error::{LinalgError, Result};
use crate::faer_error;
use faer::MatMut;
use faer::linalg::solvers::Solve;
use faer::reborrow::{Reborrow, ReborrowMut};

/// Sparse LU of a general (here: symmetric indefinite, K - w^2 M above the first eigenvalue)
/// matrix, with the same double-double refinement as the Cholesky solver.
pub struct LuSolver {
    lu: faer::sparse::linalg::solvers::Lu<usize, f64>,
    matrix: Sparse,
}

impl LuSolver {
    pub fn new(a: &Sparse, what: &str) -> Result<Self> {
        let lu = phases::phase(format!("LU factorisation: {what}"), || {
            phases::note(|| format!("n {}, nnz(A) {}", a.nrows(), a.compute_nnz()));
            a.sp_lu()
        })
        .map_err(|e| LinalgError::singular(format!("{what} is {}", faer_error::lu(&e))).caused_by(e))?;
        Ok(Self { lu, matrix: a.clone() })
    }

    pub fn solve_refined(&self, mut rhs: MatMut<'_, f64>) {
        let b = rhs.to_owned();
        self.lu.solve_in_place(rhs.rb_mut());
        for _ in 0..2 {
            let mut r = mul_compensated(Some(b.as_ref()), -1.0, &self.matrix, rhs.rb());
            self.lu.solve_in_place(r.as_mut());
            for j in 0..r.ncols() {
                for i in 0..r.nrows() {
                    rhs[(i, j)] += r[(i, j)];
                }
            }
        }
    }
}
