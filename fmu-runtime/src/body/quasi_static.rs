//! Quasi-static modes: in Model Exchange the modes above the dynamic cutoff carry no states.
//! They are solved at every evaluation from the present loads and the dynamic modes,
//!   (Omega_s^2 + C_k,ss) q_s = p_s - C_k,sd q_d - C_d,sd q'_d,   q'_s = q''_s = 0,
//! which drops only their inertia and damping: the static response stays that of every mode
//! (rotating mounts, gravity and geometric stiffening included), while the host's integrator sees
//! no frequency above the cutoff. Without coupling terms the solve is diagonal.

use super::dense::{dot, lu_factor, lu_solve};
use super::{BodyError, Change, FlexibleBody};
use crate::reduced::ReducedBody;
use crate::scalar::{Scalar, c};

/// Which modes carry the dynamics: modes 0..n_dynamic are below the dynamic cutoff; with
/// `quasi_static` (Model Exchange) the others are solved algebraically at every evaluation
/// instead of integrated. Fixed by the reduced body except the interface's choice.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct ModeSplit {
    pub(super) n_dynamic: usize,
    /// Quasi-static modes nd..nd + n_relaxing settle through their damping (first-order states
    /// in Model Exchange); the rest are algebraic.
    pub(super) n_relaxing: usize,
    pub(super) quasi_static: bool,
    /// Set while the quasi-static modes are put in equilibrium (relaxing ones included).
    pub(super) settling: bool,
}

impl ModeSplit {
    pub(super) fn of(body: &ReducedBody) -> Self {
        Self { n_dynamic: body.n_dynamic(), n_relaxing: body.n_relaxing(), quasi_static: false, settling: false }
    }
}

/// Workspace of the quasi-static solve, allocated once with the body.
#[derive(Debug, Clone, Default)]
pub(super) struct QuasiStaticWork<T> {
    /// LU factors of the algebraic modes' n_a x n_a matrix (Omega_a^2 + C_k,aa) and their row
    /// exchanges, kept for the coupling coefficients and the first algebraic mode they were made
    /// for: a host's evaluations at one spin (every Model Exchange call between input changes)
    /// solve with them instead of factoring again (n_a^3 / 3 of an evaluation's n_a^2).
    matrix: Vec<T>,
    pivots: Vec<usize>,
    factored_coef: Vec<f64>,
    factored_from: Option<usize>,
    /// Rows s of C_k and C_d (n_s x n) where the body assembles them per evaluation (a free body).
    pub(super) c_k: Vec<T>,
    pub(super) c_d: Vec<T>,
}

impl<T: Scalar> QuasiStaticWork<T> {
    /// For `n` modes, `n_dynamic` of them dynamic, and `coefficients` coupling coefficients.
    pub(super) fn new(n: usize, n_dynamic: usize, free_floating: bool, coefficients: usize) -> Self {
        let ns = n - n_dynamic;
        let rows = if free_floating { ns * n } else { 0 };
        Self {
            matrix: vec![T::zero(); ns * ns],
            pivots: vec![0; ns],
            factored_coef: vec![0.0; coefficients],
            factored_from: None,
            c_k: vec![T::zero(); rows],
            c_d: vec![T::zero(); rows],
        }
    }

    /// Whether the factors held are those of the coupling of `coef` with the algebraic modes
    /// from `first` on. Never for dual numbers: their factors carry the derivative's direction.
    fn holds(&self, coef: Option<&[T]>, first: usize) -> bool {
        !T::CARRIES_DERIVATIVE
            && self.factored_from == Some(first)
            && coef.is_some_and(|c| {
                c.len() == self.factored_coef.len() && c.iter().zip(&self.factored_coef).all(|(a, b)| a.value() == *b)
            })
    }
}

impl<T: Scalar> FlexibleBody<T> {
    /// Number of modes that are states in Model Exchange.
    pub fn n_dynamic(&self) -> usize {
        self.split.n_dynamic
    }

    /// Whether the modes above the cutoff are solved algebraically (Model Exchange) rather than
    /// integrated with the others (Co-Simulation's exact propagation).
    pub fn quasi_static(&self) -> bool {
        self.split.quasi_static
    }

    /// The algebraic modes: quasi-static modes that are no state in Model Exchange.
    pub(super) fn algebraic_range(&self) -> std::ops::Range<usize> {
        self.split.n_dynamic + self.split.n_relaxing..self.coords.q.len()
    }

    /// The quasi-static solve of Model Exchange applied to the body's own state; `settling`: the
    /// relaxing modes are put in equilibrium too instead of keeping their q.
    pub(super) fn equilibrate_quasi_static(&mut self, settling: bool) -> Result<(), BodyError> {
        if self.split.n_dynamic == self.coords.q.len() {
            return Ok(());
        }
        let was = self.split.quasi_static;
        self.split.settling = settling;
        self.set_quasi_static(true);
        let settled = self.evaluate();
        self.split.settling = false;
        self.set_quasi_static(was);
        settled
    }

    pub fn set_quasi_static(&mut self, on: bool) {
        self.split.quasi_static = on;
        self.derived.invalidate(Change::Coordinates);
    }

    /// Solve the quasi-static modes from the modal load in `self.derived.load` and the rows s of the
    /// coupling (`rows`: C_k and C_d, n_s x n each; None: no coupling). The algebraic ones get
    /// q_a from their equilibrium with every other coordinate and q'_a = 0; the relaxing ones
    /// (states in Model Exchange) keep their q_r and get the rate of their damping without
    /// inertia, d_r q'_r = p_r - omega_r^2 q_r - (C_k q)_r - (C_d q'_d)_r. The spin's
    /// gyroscopic coupling among the quasi-static modes' own rates is left out (their creep is
    /// slow, the spin's coupling of it second order); statics are exact.
    pub(super) fn solve_quasi_static(
        &mut self,
        rows: Option<(&[T], &[T])>,
        coef: Option<&[T]>,
    ) -> Result<(), BodyError> {
        let (n, nd) = (self.coords.q.len(), self.split.n_dynamic);
        if nd == n {
            return Ok(());
        }
        // settling puts every quasi-static mode in equilibrium, the relaxing ones included
        let nr = if self.split.settling { 0 } else { self.split.n_relaxing };
        let known = nd + nr;
        let na = n - known;
        let omega = &self.body.omega;
        self.coords.qd[nd..].fill(T::zero());
        match rows {
            None => {
                for j in known..n {
                    self.coords.q[j] = self.derived.load[j] / (omega[j] * omega[j]);
                }
            }
            Some((c_k, c_d)) if na > 0 => {
                let held = self.derived.qs_work.holds(coef, known);
                let work = &mut self.derived.qs_work;
                let a = &mut work.matrix;
                for i in 0..na {
                    let row = (nr + i) * n;
                    let (rk, rd) = (&c_k[row..row + n], &c_d[row..row + n]);
                    self.coords.q[known + i] = self.derived.load[known + i]
                        - dot(&rk[..known], &self.coords.q[..known])
                        - dot(&rd[..nd], &self.coords.qd[..nd]);
                    if !held {
                        a[i * na..(i + 1) * na].copy_from_slice(&rk[known..]);
                        a[i * na + i] += c(omega[known + i] * omega[known + i]);
                    }
                }
                if !held {
                    work.factored_from = None;
                    lu_factor(&mut a[..na * na], na, &mut work.pivots[..na])
                        .map_err(|()| BodyError::NoQuasiStaticEquilibrium)?;
                    if let Some(coef) = coef.filter(|c| !T::CARRIES_DERIVATIVE && c.len() == work.factored_coef.len()) {
                        for (f, v) in work.factored_coef.iter_mut().zip(coef) {
                            *f = v.value();
                        }
                        work.factored_from = Some(known);
                    }
                }
                lu_solve(&a[..na * na], na, &work.pivots[..na], &mut self.coords.q[known..]);
            }
            Some(_) => {}
        }
        let (alpha, beta) = (self.inputs.params.alpha, self.inputs.params.beta);
        let cutoff = self.body.dynamic_cutoff;
        for l in 0..nr {
            let j = nd + l;
            let w2 = omega[j] * omega[j];
            let mut force = self.derived.load[j] - self.coords.q[j] * w2;
            if let Some((c_k, c_d)) = rows {
                let (rk, rd) = (&c_k[l * n..(l + 1) * n], &c_d[l * n..(l + 1) * n]);
                force -= dot(rk, &self.coords.q) + dot(&rd[..nd], &self.coords.qd[..nd]);
            }
            // a mode whose damping was lowered at run time (alpha, beta are parameters)
            // settles at the cutoff's rate at most: the host never sees a faster one
            let d = (alpha + beta * w2 + self.body.modal_damping[j]).max(w2 / cutoff);
            self.coords.qd[j] = force / d;
        }
        Ok(())
    }

    /// Number of relaxing modes (first-order states of Model Exchange after the dynamic ones).
    pub fn n_relaxing(&self) -> usize {
        self.split.n_relaxing
    }

    /// Set the relaxing modes' q (Model Exchange's states after the dynamic modes' q, q').
    pub fn set_relaxing(&mut self, q: &[T]) {
        let nd = self.split.n_dynamic;
        self.coords_mut().q[nd..nd + q.len()].copy_from_slice(q);
    }
}

#[cfg(test)]
mod tests {
    use super::super::FlexibleBody;
    use crate::reduced::{ReducedBody, RotationTerms, two_mode_body};
    use std::sync::Arc;

    /// Three modes, the upper two above the cutoff, with rotating-frame terms that couple them.
    fn spinning_body() -> ReducedBody {
        let mut b = two_mode_body();
        b.omega = vec![10.0, 2000.0, 5000.0];
        b.modal_damping = vec![0.0; 3];
        b.c_t = vec![0.0, 0.1, 0.02, 0.3, 0.0, -0.01, 0.0, 0.2, 0.05];
        b.c_r = vec![0.0, 0.0, 0.01, 0.0, 0.0, 0.0, -0.2, 0.0, 0.0];
        b.flanges[0].shapes = (0..18).map(|k| 0.1 * ((k * 7 % 11) as f64 - 5.0)).collect();
        let (n, nn) = (3, 9);
        let mut g = vec![0.0; 3 * nn];
        for a in 0..3 {
            for (i, j, v) in [(0, 1, 0.3), (0, 2, -0.2), (1, 2, 0.1 * (a + 1) as f64)] {
                g[a * nn + i * n + j] = v;
                g[a * nn + j * n + i] = -v;
            }
        }
        let mut o_mat = vec![0.0; 9 * nn];
        for k in 0..9 {
            for i in 0..n {
                for j in 0..n {
                    o_mat[k * nn + i * n + j] = if i == j { 0.4 } else { 0.05 };
                }
            }
        }
        b.rotation = Some(RotationTerms { g, o_mat, o_vec: (0..27).map(|k| 0.01 * (k % 5) as f64).collect() });
        b.dynamic_cutoff = 100.0;
        b
    }

    /// Static exactness kept: at the full model's static equilibrium (every mode, spin and
    /// gravity included) the quasi-static solve returns the same q_s and the dynamic modes feel
    /// no acceleration; the coupled solve is what makes this hold (a diagonal one misses C_k).
    #[test]
    fn the_static_equilibrium_of_all_modes_is_kept() {
        let mut b = FlexibleBody::new(Arc::new(spinning_body()));
        assert_eq!(b.n_dynamic(), 1);
        b.mount_mut().w = [0.5, -1.0, 30.0];
        b.parameters_mut().g = [0.0, -9.81, 0.0];
        b.load_mut(0).f = [2.0, -1.0, 4.0];
        b.settle_static().unwrap();
        let full = b.q().to_vec();
        b.set_quasi_static(true);
        b.set_state(&[full[0]], &[0.0]);
        let qdd = b.qdd().unwrap().to_vec();
        assert_eq!(qdd.len(), 3);
        // measured 0 and 1e-19 (round-off of the 2 x 2 solve against the 3 x 3 one)
        assert!(qdd.iter().all(|a| a.abs() < 1e-12), "{qdd:?}");
        for (j, (x, y)) in b.q().iter().zip(&full).enumerate() {
            assert!((x - y).abs() <= 1e-12 * y.abs().max(1e-300), "q[{j}] {x} vs {y}");
        }
        assert_eq!(b.qd()[1..], [0.0, 0.0]);
    }

    /// The algebraic modes' factors are kept for the coupling they were made for: evaluations at
    /// one spin give the bits of a body that factors afresh, a new spin factors again (the same
    /// bits as a fresh body at that spin), and so does the way back.
    #[test]
    fn kept_factors_give_the_bits_of_fresh_ones() {
        let qdd_at = |b: &mut FlexibleBody, w: f64| {
            b.mount_mut().w = [0.5, -1.0, w];
            b.set_state(&[2e-3], &[0.1]);
            (b.qdd().unwrap().to_vec(), b.q().to_vec())
        };
        let fresh = |w: f64| {
            let mut b = FlexibleBody::new(Arc::new(spinning_body()));
            b.load_mut(0).f = [2.0, -1.0, 4.0];
            b.set_quasi_static(true);
            qdd_at(&mut b, w)
        };
        let mut b = FlexibleBody::new(Arc::new(spinning_body()));
        b.load_mut(0).f = [2.0, -1.0, 4.0];
        b.set_quasi_static(true);
        let first = qdd_at(&mut b, 30.0);
        assert_eq!(first.0.len(), 3);
        assert_eq!(qdd_at(&mut b, 30.0), first, "a second evaluation at the same spin");
        assert_eq!(qdd_at(&mut b, 45.0), fresh(45.0), "a new spin");
        assert_eq!(qdd_at(&mut b, 30.0), first, "back to the first spin");
        assert_ne!(fresh(45.0).1[1], first.1[1], "the spin moves the quasi-static modes");
    }

    /// Co-Simulation starts where Model Exchange does: its quasi-static modes in equilibrium with
    /// the start values of the dynamic ones, at rest.
    #[test]
    fn both_interfaces_start_from_the_same_quasi_static_modes() {
        let mut me = FlexibleBody::new(Arc::new(spinning_body()));
        me.mount_mut().w = [0.0, 0.0, 20.0];
        me.load_mut(0).f = [0.0, 3.0, 0.0];
        let mut cs = me.clone();
        me.set_quasi_static(true);
        me.set_state(&[1e-3], &[0.2]);
        cs.set_state(&[1e-3, 1.0, 1.0], &[0.2, 5.0, 5.0]);
        cs.settle_quasi_static().unwrap();
        assert!(!cs.quasi_static());
        me.qdd().unwrap();
        assert_eq!(me.q(), cs.q());
        assert_eq!(cs.qd(), [0.2, 0.0, 0.0]);
    }

    /// Relaxing modes: stiffness-proportional damping that makes the quasi-static modes settle
    /// at about 1/beta, below the cutoff. They keep q as a state whose rate is that of their
    /// damping without inertia, d q' = p - omega^2 q: zero at the static equilibrium (statics
    /// exact), -omega^2 dq / d off it.
    #[test]
    fn relaxing_modes_creep_at_the_rate_of_their_damping() {
        let mut reduced = spinning_body();
        reduced.rotation = None;
        reduced.alpha = 0.5;
        reduced.beta = 1e-2;
        reduced.dynamic_cutoff = 200.0;
        assert_eq!((reduced.n_dynamic(), reduced.n_relaxing()), (1, 2));
        reduced.beta = 1e-4; // settling at about 1e4 1/s, above the cutoff: algebraic
        assert_eq!(reduced.n_relaxing(), 0);
        reduced.beta = 1e-2;
        let mut b = FlexibleBody::new(Arc::new(reduced));
        b.load_mut(0).f = [2.0, -1.0, 4.0];
        b.settle_static().unwrap();
        let statics = b.q().to_vec();
        b.set_quasi_static(true);
        b.qdd().unwrap();
        assert_eq!(b.q().len(), 3);
        // measured 0 (the diagonal solve returns the same quotient)
        assert!(b.qd()[1..].iter().all(|v| v.abs() < 1e-12), "{:?}", b.qd());
        let dq = 1e-3 * statics[2].abs().max(1e-6);
        b.set_relaxing(&[statics[1], statics[2] + dq]);
        b.qdd().unwrap();
        let w2 = 5000.0f64 * 5000.0;
        let expected = -w2 * dq / (0.5 + 1e-2 * w2);
        // measured 0 and round-off relative to the rate
        assert!(b.qd()[1].abs() < 1e-12, "{}", b.qd()[1]);
        assert!((b.qd()[2] - expected).abs() < 1e-9 * expected.abs(), "{} vs {expected}", b.qd()[2]);
        assert_eq!(b.q()[2], statics[2] + dq, "a relaxing mode keeps its state");
    }
}
