//! Solves with the leading block K_ii of a factored K = [K_ii K_ib; K_bi K_bb], the trailing
//! DoFs held at zero, from the factor of K and a rank-h correction: no second factorisation.
//!
//! With G = K^-1 E (E the unit columns of the h held DoFs) and S = E^T G (their compliance),
//! z = K^-1 [b; 0] and f = -S^-1 z_b, the vector z + G f vanishes at the held DoFs and
//! K (z + G f) = [b; 0] + E f: its leading part x solves K_ii x = b exactly. Craig-Bampton
//! (flanges held) then shares the mounted body's factor, which on a 249k-DoF bracket saved two
//! factorisations of 10-13 s and 1.3 GB each.

use crate::error::{LinalgError, Result};
use crate::sparse::{SpdSolve, SpdSolver};
use crate::symmetric_product::subtract_compensated;
use faer::linalg::solvers::Solve;
use faer::reborrow::{Reborrow, ReborrowMut};
use faer::{Mat, MatMut, MatRef, Side};
use petsc_backend::Session;
use std::borrow::Cow;

pub struct HeldSolver<'a> {
    whole: &'a SpdSolver<'a>,
    /// Rows kept free (the leading ones).
    n: usize,
    /// K^-1 E, n_whole x h: borrowed where the caller keeps it anyway (a mounted body's flange
    /// shapes, 47 MiB at 1e6 DoFs, held beside the eigen-solve's peak).
    g: Cow<'a, Mat<f64>>,
    /// Cholesky factor of the held DoFs' compliance S = E^T K^-1 E.
    compliance: faer::linalg::solvers::Llt<f64>,
}

impl<'a> HeldSolver<'a> {
    /// Hold every row of `whole`'s matrix from `n` on.
    pub fn new(whole: &'a SpdSolver<'a>, n: usize) -> Result<Self> {
        Self::with_shapes(whole, n, Cow::Owned(Self::unit_responses(whole, n)))
    }

    /// K^-1 E for the rows from `n` on, refined: the static shapes of unit loads at the held DoFs
    /// (for a mounted body's force flanges, what the compliance comparison solves for too).
    pub fn unit_responses(whole: &SpdSolver, n: usize) -> Mat<f64> {
        let total = whole.n();
        let mut g = Mat::<f64>::zeros(total, total - n);
        for j in 0..total - n {
            g[(n + j, j)] = 1.0;
        }
        whole.solve_refined(g.as_mut());
        g
    }

    /// As `new`, with `g` = K^-1 E already solved (`unit_responses`: column j the response to a
    /// unit load at row n + j).
    pub fn with_shapes(whole: &'a SpdSolver<'a>, n: usize, g: Cow<'a, Mat<f64>>) -> Result<Self> {
        let total = whole.n();
        let h = total - n;
        if g.nrows() != total || g.ncols() != h {
            return Err(LinalgError::inconsistent(format!(
                "held solves: {} x {} unit responses for {total} rows with {h} held",
                g.nrows(),
                g.ncols()
            )));
        }
        let s = Mat::<f64>::from_fn(h, h, |i, j| 0.5 * (g[(n + i, j)] + g[(n + j, i)]));
        let compliance = s.llt(Side::Lower).map_err(|e| {
            LinalgError::singular(
                "the compliance of the held flange DoFs is not positive definite: a flange master without stiffness",
            )
            .caused_by(e)
        })?;
        Ok(Self { whole, n, g, compliance })
    }

    /// G = K^-1 E, the unit-load responses of the held DoFs (all rows).
    pub fn unit_shapes(&self) -> &Mat<f64> {
        &self.g
    }

    /// x = S^-1 x in place for h rows (S = E^T G, the held DoFs' compliance).
    pub fn compliance_solve(&self, x: MatMut<'_, f64>) {
        self.compliance.solve_in_place(x);
    }

    /// The constraint modes [-K_ii^-1 K_ib; I] (all rows, one column per held DoF): the response
    /// to unit displacements of the held DoFs with no load on the others, G S^-1, since K G S^-1
    /// = E S^-1 loads the held DoFs only and E^T G S^-1 = I. No solve beyond those of G.
    pub fn constraint_modes(&self) -> Mat<f64> {
        let mut psi = self.g.transpose().to_owned();
        self.compliance.solve_in_place(psi.as_mut());
        psi.transpose().to_owned()
    }

    /// x = K_ii^-1 b for the columns of `rhs` (n rows), without refinement.
    fn solve(&self, mut rhs: MatMut<'_, f64>) {
        let (n, total) = (self.n, self.whole.n());
        let mut z = Mat::<f64>::zeros(total, rhs.ncols());
        z.as_mut().subrows_mut(0, n).copy_from(rhs.as_ref());
        self.whole.solve_in_place(z.as_mut());
        let zb = z.subrows(n, total - n).to_owned();
        let f = self.compliance.solve(&zb);
        // in place: the product of G (n x h) would be one more n-row matrix
        faer::linalg::matmul::matmul(z.as_mut(), faer::Accum::Add, self.g.as_ref(), f.as_ref(), -1.0, faer::Par::Seq);
        rhs.copy_from(z.subrows(0, n));
    }
}

impl SpdSolve for HeldSolver<'_> {
    fn n(&self) -> usize {
        self.n
    }

    fn solve_plain(&self, rhs: MatMut<'_, f64>) {
        self.solve(rhs);
    }

    fn residual(&self, b: MatMut<'_, f64>, x: MatRef<'_, f64>) {
        // the leading block's product: K_ii x, the residual of the held system
        subtract_compensated(b, self.whole.matrix(), x);
    }

    fn distributed_session(&self) -> Option<&Session> {
        self.whole.session()
    }
}

/// The whole matrix's solves for the first `whole` columns and the held problem's for the
/// others, all of the whole's rows (the held problem's zero at the held rows), in one pass
/// through the factor: the eigen-solver checks both sets of Craig-Bampton's modes at once
/// (249k DoFs: 26 and 20 columns 2 x 0.55 s, 46 together 0.8 s).
pub struct WholeAndHeld<'a> {
    pub held: &'a HeldSolver<'a>,
    pub whole: usize,
}

impl SpdSolve for WholeAndHeld<'_> {
    fn n(&self) -> usize {
        self.held.whole.n()
    }

    fn solve_plain(&self, mut rhs: MatMut<'_, f64>) {
        let held = &self.held;
        let (n, total) = (held.n, held.whole.n());
        held.whole.solve_in_place(rhs.rb_mut());
        let first = self.whole.min(rhs.ncols());
        let columns = rhs.ncols() - first;
        let mut z = rhs.subcols_mut(first, columns);
        let f = held.compliance.solve(z.rb().subrows(n, total - n));
        faer::linalg::matmul::matmul(z.rb_mut(), faer::Accum::Add, held.g.as_ref(), f.as_ref(), -1.0, faer::Par::Seq);
        z.subrows_mut(n, total - n).fill(0.0);
    }

    fn distributed_session(&self) -> Option<&Session> {
        self.held.whole.session()
    }

    fn residual(&self, mut b: MatMut<'_, f64>, x: MatRef<'_, f64>) {
        let held = &self.held;
        let (n, total) = (held.n, held.whole.n());
        subtract_compensated(b.rb_mut(), held.whole.matrix(), x);
        // at the held rows a held problem's residual is the reaction that holds them: no error
        let first = self.whole.min(b.ncols());
        let columns = b.ncols() - first;
        b.subcols_mut(first, columns).subrows_mut(n, total - n).fill(0.0);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sparse::block;

    /// A 3D grid Laplacian plus a diagonal: solves with its leading block through the whole
    /// factor equal solves with the block's own factor to round-off (consistency: both are ours;
    /// the physics of the held flanges is checked against CalculiX in the Python tests).
    #[test]
    fn held_solves_equal_the_blocks_own_factor() {
        let k = 9;
        let total = k * k * k;
        let a = crate::test_grids::laplacian(k, |i| 6.0 + 1e-3 * i as f64);
        let n = total - 7;
        let a_ii = block(&a, 0..n, 0..n).unwrap();
        let name = |d: usize| format!("row {d}");
        let whole = SpdSolver::new(std::borrow::Cow::Owned(a), "whole", &name).unwrap();
        let own = SpdSolver::new(std::borrow::Cow::Owned(a_ii), "block", &name).unwrap();
        let held = HeldSolver::new(&whole, n).unwrap();
        assert_eq!(held.n(), n);
        let b = Mat::<f64>::from_fn(n, 3, |i, j| ((i * 7 + 3 * j) % 11) as f64 - 5.0);
        let mut x_held = b.clone();
        held.solve_refined(x_held.as_mut());
        let mut x_own = b.clone();
        own.solve_refined(x_own.as_mut());
        let scale = x_own.norm_max();
        let diff = (&x_held - &x_own).norm_max();
        // both refined in double-double to round-off of the solution (measured 1e-16 relative);
        // a wrong correction (held rows not zero) shows as order 1
        assert!(diff <= 1e-13 * scale, "held vs own factor: {diff:e} of {scale:e}");
    }

    /// The constraint modes from the unit-load responses (G S^-1) equal -K_ii^-1 K_ib solved with
    /// the block's own factor, and are the identity at the held rows (consistency of two routes
    /// of ours; Craig-Bampton's physics is checked against CalculiX in the Python tests).
    #[test]
    fn constraint_modes_equal_the_interior_solve() {
        let k = 8;
        let total = k * k * k;
        let a = crate::test_grids::laplacian(k, |i| 6.0 + 1e-3 * i as f64);
        let n = total - 6;
        let a_ii = block(&a, 0..n, 0..n).unwrap();
        let a_ib = block(&a, 0..n, n..total).unwrap();
        let name = |d: usize| format!("row {d}");
        let whole = SpdSolver::new(std::borrow::Cow::Borrowed(&a), "whole", &name).unwrap();
        let own = SpdSolver::new(std::borrow::Cow::Owned(a_ii), "block", &name).unwrap();
        let psi = HeldSolver::new(&whole, n).unwrap().constraint_modes();
        assert_eq!((psi.nrows(), psi.ncols()), (total, 6));
        let mut direct = crate::sparse::mul_new(&a_ib, Mat::<f64>::identity(6, 6).as_ref());
        own.solve_refined(direct.as_mut());
        let scale = direct.norm_max();
        for j in 0..6 {
            for i in 0..n {
                // both refined to round-off (measured 1e-16 of the largest entry); a wrong sign or
                // a missing S^-1 shows as order 1
                assert!((psi[(i, j)] + direct[(i, j)]).abs() <= 1e-13 * scale, "({i}, {j})");
            }
            for h in 0..6 {
                let expected = if h == j { 1.0 } else { 0.0 };
                assert!((psi[(n + h, j)] - expected).abs() <= 1e-13, "held row {h} of mode {j}");
            }
        }
    }
}
