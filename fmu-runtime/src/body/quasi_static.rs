//! Quasi-static modes: in Model Exchange the modes above the dynamic cutoff carry no states.
//! They are solved at every evaluation from the present loads and the dynamic modes,
//!   (Omega_s^2 + C_k,ss) q_s = p_s - C_k,sd q_d - C_d,sd q'_d,   q'_s = q''_s = 0,
//! which drops only their inertia and damping: the static response stays that of every mode
//! (rotating mounts, gravity and geometric stiffening included), while the host's integrator sees
//! no frequency above the cutoff. Without coupling terms the solve is diagonal.

use super::FlexibleBody;
use super::dense::solve_dense;
use crate::scalar::{Scalar, c};

/// Workspace of the quasi-static solve, allocated once with the body.
#[derive(Debug, Clone, Default)]
pub(super) struct QuasiStaticWork<T> {
    /// n_s x n_s system matrix, destroyed by each solve.
    matrix: Vec<T>,
    /// Rows s of C_k and C_d (n_s x n) where the body assembles them per evaluation (a free body).
    pub(super) c_k: Vec<T>,
    pub(super) c_d: Vec<T>,
}

impl<T: Scalar> QuasiStaticWork<T> {
    pub(super) fn new(n: usize, n_dynamic: usize, free_floating: bool) -> Self {
        let ns = n - n_dynamic;
        let rows = if free_floating { ns * n } else { 0 };
        Self { matrix: vec![T::zero(); ns * ns], c_k: vec![T::zero(); rows], c_d: vec![T::zero(); rows] }
    }
}

impl<T: Scalar> FlexibleBody<T> {
    /// Number of modes that are states in Model Exchange.
    pub fn n_dynamic(&self) -> usize {
        self.n_dynamic
    }

    /// Whether the modes above the cutoff are solved algebraically (Model Exchange) rather than
    /// integrated with the others (Co-Simulation's exact propagation).
    pub fn quasi_static(&self) -> bool {
        self.quasi_static
    }

    /// Put the quasi-static modes in equilibrium with the present inputs and dynamic modes, at
    /// rest: how both interfaces start, so that Co-Simulation begins where Model Exchange does
    /// (their start values are calculated, not set).
    pub fn settle_quasi_static(&mut self) -> Result<(), String> {
        if self.n_dynamic == self.q.len() {
            return Ok(());
        }
        let was = self.quasi_static;
        self.quasi_static = true;
        self.eval.valid = false;
        let settled = self.evaluate();
        self.quasi_static = was;
        self.eval.valid = false;
        settled
    }

    pub fn set_quasi_static(&mut self, on: bool) {
        self.quasi_static = on;
        self.eval.valid = false;
    }

    /// Solve q_s from the modal load in `self.load` and the rows s of the coupling (`rows`: C_k and
    /// C_d, n_s x n each; None: no coupling), then q'_s = 0.
    pub(super) fn solve_quasi_static(&mut self, rows: Option<(&[T], &[T])>) -> Result<(), String> {
        let (n, nd) = (self.q.len(), self.n_dynamic);
        let ns = n - nd;
        if ns == 0 {
            return Ok(());
        }
        let omega = &self.body.omega;
        self.qd[nd..].fill(T::zero());
        let Some((c_k, c_d)) = rows else {
            for j in nd..n {
                self.q[j] = self.load[j] / (omega[j] * omega[j]);
            }
            return Ok(());
        };
        let a = &mut self.qs_work.matrix;
        for i in 0..ns {
            let (rk, rd) = (&c_k[i * n..(i + 1) * n], &c_d[i * n..(i + 1) * n]);
            let mut rhs = self.load[nd + i];
            for j in 0..nd {
                rhs -= rk[j] * self.q[j] + rd[j] * self.qd[j];
            }
            self.q[nd + i] = rhs;
            a[i * ns..(i + 1) * ns].copy_from_slice(&rk[nd..]);
            a[i * ns + i] += c(omega[nd + i] * omega[nd + i]);
        }
        solve_dense(a, &mut self.q[nd..], ns).map_err(|_| {
            "the quasi-static modes have no equilibrium: the effective stiffness above the dynamic cutoff is singular \
             at the present spin and loads (raise reduction.dynamic_cutoff so that these modes are integrated)"
                .to_string()
        })
    }
}
