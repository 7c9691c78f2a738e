//! What follows from the coordinates and inputs: the evaluation's results (q'', flange motion,
//! mount reaction, stresses), the coupling terms, and the workspaces they are computed in, behind
//! one cache with one way to make it stale.

use super::coupling_terms::term_count;
use super::quasi_static::QuasiStaticWork;
use super::{FlangeMotion, FrameState};
use crate::kinematics::{self as k3, Mat3, Vec3};
use crate::reduced::ReducedBody;
use crate::scalar::{Scalar, c};

/// What changed since the derived values were computed, the one argument of
/// [`Derived::invalidate`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Change {
    /// The coordinates (q, q', the frame) or how the modes are split (quasi-static or not): the
    /// evaluation is stale; the coupling, a function of the inputs alone, is kept.
    Coordinates,
    /// The inputs (mount, loads, parameters): the coupling is stale as well.
    Inputs,
}

/// Everything a [`FlexibleBody`](super::FlexibleBody) computes from its coordinates and inputs,
/// and the scratch it computes it in. None of it is state: a body rebuilt from its saved state
/// recomputes it on demand, bit-identically. [`invalidate`](Self::invalidate) is the only place
/// the cache's flags are cleared: the body's setters of coordinates and inputs (`coords_mut`,
/// `inputs_mut`, `set_quasi_static`) call it, and so do the few solves that write the
/// coordinates in place (a step, once at its end, and each of a free body's substeps; the static
/// start; the quasi-static shift). The evaluation sets the flags again (`evaluated`).
#[derive(Debug, Clone)]
pub(super) struct Derived<T> {
    pub(super) eval: Evaluation<T>,
    pub(super) coupling: Coupling<T>,
    /// The mount orientation in use: the input made exactly orthonormal.
    pub(super) rot: Mat3<T>,
    /// 3 x n workspace: C_r(q) = C_r + [G_a q]^T
    pub(super) cr_q: Vec<T>,
    /// Modal load p, workspace.
    pub(super) load: Vec<T>,
    /// The modal load's rate the input rates give (Co-Simulation, `f64` only).
    pub(super) load_rate: Vec<f64>,
    /// Free-floating bodies only: the rates of the frame state.
    pub(super) frame_rate: FrameState<T>,
    /// The quasi-static solve's workspace and kept factors.
    pub(super) qs_work: QuasiStaticWork<T>,
}

impl<T: Scalar> Derived<T> {
    /// Empty (stale) derived values of `body`, `n_dynamic` of its modes dynamic.
    pub(super) fn for_body(body: &ReducedBody, n_dynamic: usize) -> Self {
        let n = body.n_modes();
        let nf = body.flanges.len();
        let zeros = |len: usize| vec![T::zero(); len];
        Self {
            eval: Evaluation {
                valid: false,
                qdd: zeros(n),
                flanges: vec![FlangeMotion::default(); nf],
                reaction_valid: false,
                mount_force: [T::zero(); 3],
                mount_torque: [T::zero(); 3],
                generation: 0,
                stresses: vec![([T::zero(); 7], 0); body.stress_points.len()],
            },
            coupling: Coupling {
                c_d: zeros(n * n),
                c_k: zeros(n * n),
                force: zeros(n),
                coef: zeros(term_count(nf)),
                ..Coupling::default()
            },
            rot: k3::IDENTITY.map(c),
            cr_q: zeros(3 * n),
            load: zeros(n),
            load_rate: vec![0.0; n],
            frame_rate: FrameState::default(),
            qs_work: QuasiStaticWork::new(n, n_dynamic, body.free_floating, term_count(nf)),
        }
    }
}

impl<T> Derived<T> {
    /// The one entry point that makes the cache stale: what `change` affects is recomputed on
    /// demand.
    pub(super) fn invalidate(&mut self, change: Change) {
        self.eval.valid = false;
        if change == Change::Inputs {
            self.coupling.valid = false;
        }
    }

    /// The evaluation is complete: valid until the next [`invalidate`](Self::invalidate), its
    /// on-demand results (reaction, stresses) not yet computed for it.
    pub(super) fn evaluated(&mut self) {
        self.eval.reaction_valid = false;
        self.eval.generation += 1;
        self.eval.valid = true;
    }
}

/// Everything that follows from state and inputs at one instant.
#[derive(Debug, Clone, Default)]
pub(super) struct Evaluation<T> {
    pub(super) valid: bool,
    pub(super) qdd: Vec<T>,
    pub(super) flanges: Vec<FlangeMotion<T>>,
    /// The mount reaction is evaluated on demand: hosts that read only flange outputs skip its
    /// n^2 terms.
    pub(super) reaction_valid: bool,
    pub(super) mount_force: Vec3<T>,
    pub(super) mount_torque: Vec3<T>,
    /// Counts the evaluations: results computed on demand remember the one they belong to.
    pub(super) generation: u64,
    /// Stresses at the recovery points (xx .. zx, von Mises), each with the generation it was
    /// computed at (0: never): a host reads a point's seven outputs one by one.
    pub(super) stresses: Vec<([T; 7], u64)>,
}

/// Terms that couple the modes, for the present inputs: q'' = ... - C_d q' - C_k q.
#[derive(Debug, Clone, Default)]
pub(super) struct Coupling<T> {
    /// The coefficients (and `active`) are those of the present inputs.
    pub(super) valid: bool,
    pub(super) active: bool,
    /// The rows of C_d, C_k from this one on are those of the coefficients (None: no row). They
    /// are filled only where needed: the rows of Model Exchange's algebraic modes, all of them for
    /// the static start.
    pub(super) rows_from: Option<usize>,
    pub(super) c_d: Vec<T>,
    pub(super) c_k: Vec<T>,
    /// (C_d q' + C_k q) of an evaluation (n).
    pub(super) force: Vec<T>,
    /// Body-frame angular velocity, angular acceleration and a_B of the present inputs.
    pub(super) w: Vec3<T>,
    pub(super) z: Vec3<T>,
    pub(super) a: Vec3<T>,
    /// The coefficients c_d and c_k combine the body's matrices with (see `coupling_terms`).
    pub(super) coef: Vec<T>,
}

#[cfg(test)]
mod tests {
    use super::super::FlexibleBody;
    use crate::reduced::{free_two_mode_body, rotating_two_mode_body};
    use std::sync::Arc;

    /// What a body reads out after an evaluation: q'', every flange's motion, the reaction.
    fn outputs(b: &mut FlexibleBody) -> Vec<u64> {
        let mut out: Vec<f64> = b.qdd().unwrap().to_vec();
        for f in 0..b.reduced().flanges.len() {
            let m = *b.flange_motion(f).unwrap();
            out.extend(m.r.iter().chain(&m.rot).chain(&m.v).chain(&m.w).chain(&m.a).chain(&m.z));
        }
        let (force, torque) = b.mount_reaction().unwrap();
        out.extend(force.iter().chain(&torque));
        out.iter().map(|x| x.to_bits()).collect()
    }

    /// Every setter makes the derived values stale: a body evaluated, then changed through a
    /// setter, reads out what a body changed before its first evaluation reads, bit for bit.
    #[test]
    fn every_setter_makes_the_derived_values_stale() {
        type Change = fn(&mut FlexibleBody);
        let mounted: [(&str, Change); 10] = [
            ("mount_mut", |b| b.mount_mut().w = [0.1, 0.2, 3.0]),
            ("set_mount_spin", |b| b.set_mount_spin(2, 4.0)),
            ("set_mount_rotation", |b| {
                let (s, c) = 0.2f64.sin_cos();
                for (k, v) in [c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0].into_iter().enumerate() {
                    b.set_mount_rotation(k, v);
                }
            }),
            ("load_mut", |b| b.load_mut(0).f = [0.0, 2.0, -1.0]),
            ("parameters_mut", |b| b.parameters_mut().g = [0.0, 0.0, -9.81]),
            ("set_state", |b| b.set_state(&[1e-3, -2e-4], &[0.1, 0.0])),
            ("q_mut", |b| b.q_mut()[0] = 2e-3),
            ("qd_mut", |b| b.qd_mut()[1] = 0.3),
            ("set_quasi_static", |b| b.set_quasi_static(true)),
            ("a step", |b| b.step(1e-3).unwrap()),
        ];
        let free: [(&str, Change); 2] = [
            ("frame_mut", |b| b.frame_mut().unwrap().w_body = [0.0, 0.5, 2.0]),
            ("start_frame", |b| {
                b.initial_frame_mut().w = [1.0, 0.0, 0.0];
                b.start_frame();
            }),
        ];
        for (reduced, changes) in [(rotating_two_mode_body(), &mounted[..]), (free_two_mode_body(), &free[..])] {
            let start = |b: &mut FlexibleBody| {
                b.load_mut(0).t = [0.1, 0.0, 0.0];
                if b.frame().is_none() {
                    b.mount_mut().w = [0.0, 0.0, 1.0];
                }
            };
            for (name, change) in changes {
                let mut evaluated = FlexibleBody::new(Arc::new(reduced.clone()));
                start(&mut evaluated);
                let mut fresh = evaluated.clone();
                outputs(&mut evaluated);
                change(&mut evaluated);
                change(&mut fresh);
                assert_eq!(outputs(&mut evaluated), outputs(&mut fresh), "{name}");
            }
        }
    }
}
