//! Solves with a symmetric positive definite matrix, refined in double-double.

use faer::reborrow::{Reborrow, ReborrowMut};
use faer::{MatMut, MatRef};
use petsc_backend::session::Session;

/// A refinement correction below this (relative, per column) leaves the next one at round-off:
/// the refinement stops there.
const SETTLED: f64 = 1e-8;

/// Solves with a symmetric positive definite matrix, as the eigen-solver and the static shapes
/// need them: the factored matrix itself (`SpdSolver`) or a part of it (`held::HeldSolver`).
pub trait SpdSolve {
    /// Rows of the matrix solved with.
    fn n(&self) -> usize;

    /// One solve through the factor, without refinement.
    fn solve_plain(&self, rhs: MatMut<'_, f64>);

    /// b - A x in place of b, every entry summed in double-double
    /// (`symmetric_product::subtract_compensated`): what iterative refinement corrects with.
    fn residual(&self, b: MatMut<'_, f64>, x: MatRef<'_, f64>);

    /// Solve, then `steps` rounds of iterative refinement on residuals computed in
    /// double-double: static shapes of slender parts lose digits to the stiffness's condition
    /// number (~1e10), and the flange compliance must be exact to round-off; an
    /// extended-precision residual restores them. Returns the last correction's size relative
    /// to the solution (max norms; 0 without refinement): how far a plain solve is off.
    fn solve_refined_steps(&self, mut rhs: MatMut<'_, f64>, steps: usize) -> f64 {
        if steps == 0 {
            self.solve_plain(rhs);
            return 0.0;
        }
        let b = rhs.to_owned();
        self.solve_plain(rhs.rb_mut());
        let mut correction = 0.0;
        for _ in 0..steps {
            let mut r = b.clone();
            self.residual(r.as_mut(), rhs.rb());
            self.solve_plain(r.as_mut());
            correction = r.norm_max() / rhs.norm_max();
            // the worst column's correction relative to that column (stiff directions' static
            // shapes are 1e-9 of the others)
            let mut worst_column = 0.0f64;
            for j in 0..r.ncols() {
                worst_column = worst_column.max(r.col(j).norm_max() / rhs.rb().col(j).norm_max());
                for i in 0..r.nrows() {
                    rhs[(i, j)] += r[(i, j)];
                }
            }
            // refinement contracts the error by about the size of the correction it made: after
            // one below SETTLED the next would change the solution below round-off (the
            // 249k-DoF bracket's flange shapes: 1e-12, one solve and product saved)
            if worst_column < SETTLED {
                break;
            }
        }
        correction
    }

    fn solve_refined(&self, rhs: MatMut<'_, f64>) {
        self.solve_refined_steps(rhs, 2);
    }

    /// The distributed back-end's session behind these solves, if they run there: a solve
    /// that fails there leaves NaN and its reason with the session (`Session::health`).
    fn distributed_session(&self) -> Option<&Session> {
        None
    }
}
