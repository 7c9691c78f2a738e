//! The reduced flexible body's equations, free of anything FMI: inputs (mount motion, flange
//! loads, gravity), modal state q, q', and what the flanges see.
//!
//! Equations (body frame B, modal mass I, stiffness diag(w^2), Rayleigh damping):
//!   q'' + (alpha + beta w^2) q' + w^2 q = -C_t^T a_B + sum_k Phi_k^T [A^T f_k; A^T t_k],
//!   a_B = A^T (a_mount - g).
//! This is the mount fixed or translating (any constant orientation A). The rotating-frame terms
//! (Coriolis, centrifugal, Euler) are not in these equations yet; kinematic outputs already
//! account for the mount's angular velocity and acceleration.

use crate::kinematics::{self as k3, Mat3, Vec3};
use crate::propagator::ModalPropagator;
use crate::reduced::ReducedBody;
use std::sync::Arc;

/// Prescribed motion of the mount flange, resolved in the world frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MountMotion {
    pub r: Vec3,
    /// Rotation B -> world (columns: body axes in world).
    pub rot: Mat3,
    pub v: Vec3,
    pub w: Vec3,
    pub a: Vec3,
    pub z: Vec3,
}

impl Default for MountMotion {
    fn default() -> Self {
        Self { r: [0.0; 3], rot: k3::IDENTITY, v: [0.0; 3], w: [0.0; 3], a: [0.0; 3], z: [0.0; 3] }
    }
}

/// Force and torque the host applies at a force flange, world frame; torque about the flange.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct FlangeLoad {
    pub f: Vec3,
    pub t: Vec3,
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Parameters {
    pub g: Vec3,
    pub alpha: f64,
    pub beta: f64,
}

/// Motion of a force flange, world frame except `u`, `phi` (deformation in B).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct FlangeMotion {
    pub r: Vec3,
    pub rot: Mat3,
    pub v: Vec3,
    pub w: Vec3,
    pub a: Vec3,
    pub z: Vec3,
    pub u: Vec3,
    pub phi: Vec3,
}

/// Everything that follows from state and inputs at one instant.
#[derive(Debug, Clone, Default)]
struct Evaluation {
    valid: bool,
    qdd: Vec<f64>,
    flanges: Vec<FlangeMotion>,
    mount_force: Vec3,
    mount_torque: Vec3,
}

#[derive(Debug, Clone)]
pub struct FlexibleBody {
    body: Arc<ReducedBody>,
    mount: MountMotion,
    loads: Vec<FlangeLoad>,
    params: Parameters,
    q: Vec<f64>,
    qd: Vec<f64>,
    /// Modal load p, workspace.
    load: Vec<f64>,
    eval: Evaluation,
    propagator: ModalPropagator,
}

/// Largest |A^T A - I| accepted for the mount orientation: hosts pass rotation matrices computed
/// in single steps of their own integrators, so demand orthonormality, not bit exactness.
const ROTATION_TOLERANCE: f64 = 1e-6;

impl FlexibleBody {
    pub fn new(body: Arc<ReducedBody>) -> Self {
        let n = body.n_modes();
        let nf = body.flanges.len();
        let params = Parameters { g: [0.0; 3], alpha: body.alpha, beta: body.beta };
        Self {
            mount: MountMotion::default(),
            loads: vec![FlangeLoad::default(); nf],
            params,
            q: vec![0.0; n],
            qd: vec![0.0; n],
            load: vec![0.0; n],
            eval: Evaluation {
                valid: false,
                qdd: vec![0.0; n],
                flanges: vec![FlangeMotion::default(); nf],
                mount_force: [0.0; 3],
                mount_torque: [0.0; 3],
            },
            propagator: ModalPropagator::default(),
            body,
        }
    }

    pub fn reduced(&self) -> &ReducedBody {
        &self.body
    }
    pub fn n_modes(&self) -> usize {
        self.q.len()
    }
    pub fn q(&self) -> &[f64] {
        &self.q
    }
    pub fn qd(&self) -> &[f64] {
        &self.qd
    }
    pub fn mount(&self) -> &MountMotion {
        &self.mount
    }
    pub fn loads(&self) -> &[FlangeLoad] {
        &self.loads
    }
    pub fn parameters(&self) -> &Parameters {
        &self.params
    }

    pub fn mount_mut(&mut self) -> &mut MountMotion {
        self.eval.valid = false;
        &mut self.mount
    }
    pub fn load_mut(&mut self, flange: usize) -> &mut FlangeLoad {
        self.eval.valid = false;
        &mut self.loads[flange]
    }
    pub fn parameters_mut(&mut self) -> &mut Parameters {
        self.eval.valid = false;
        &mut self.params
    }
    pub fn set_state(&mut self, q: &[f64], qd: &[f64]) {
        self.q.copy_from_slice(q);
        self.qd.copy_from_slice(qd);
        self.eval.valid = false;
    }
    pub fn q_mut(&mut self) -> &mut [f64] {
        self.eval.valid = false;
        &mut self.q
    }
    pub fn qd_mut(&mut self) -> &mut [f64] {
        self.eval.valid = false;
        &mut self.qd
    }

    fn check_inputs(&self) -> Result<(), String> {
        let defect = k3::rotation_defect(&self.mount.rot);
        if !(defect <= ROTATION_TOLERANCE) {
            return Err(format!(
                "{}.R is not a proper rotation matrix (|R^T R - I| = {defect:.3e}, det must be +1)",
                self.body.mount
            ));
        }
        Ok(())
    }

    /// p = -C_t^T a_B + sum_k Phi_k^T [A^T f_k; A^T t_k]
    fn modal_load(&mut self) {
        let a = &self.mount.rot;
        let a_b = k3::mul_t(a, k3::sub(self.mount.a, self.params.g));
        let n = self.q.len();
        for j in 0..n {
            self.load[j] = -(self.body.c_t[j] * a_b[0] + self.body.c_t[n + j] * a_b[1] + self.body.c_t[2 * n + j] * a_b[2]);
        }
        for (flange, load) in self.body.flanges.iter().zip(&self.loads) {
            let f_b = k3::mul_t(a, load.f);
            let t_b = k3::mul_t(a, load.t);
            let wrench = [f_b[0], f_b[1], f_b[2], t_b[0], t_b[1], t_b[2]];
            for (row, w) in wrench.iter().enumerate() {
                if *w != 0.0 {
                    let shape = &flange.shapes[row * n..(row + 1) * n];
                    for j in 0..n {
                        self.load[j] += shape[j] * w;
                    }
                }
            }
        }
    }

    fn evaluate(&mut self) -> Result<(), String> {
        if self.eval.valid {
            return Ok(());
        }
        self.check_inputs()?;
        self.modal_load();
        let n = self.q.len();
        let (alpha, beta) = (self.params.alpha, self.params.beta);
        for j in 0..n {
            let w2 = self.body.omega[j] * self.body.omega[j];
            self.eval.qdd[j] = self.load[j] - (alpha + beta * w2) * self.qd[j] - w2 * self.q[j];
        }
        let m = &self.mount;
        let a = &m.rot;
        let mut torque_b = [0.0; 3];
        let mut force = [0.0; 3];
        for (i, flange) in self.body.flanges.iter().enumerate() {
            let row = |r: usize, x: &[f64]| -> f64 {
                flange.shapes[r * n..(r + 1) * n].iter().zip(x).map(|(s, v)| s * v).sum()
            };
            let u = [row(0, &self.q), row(1, &self.q), row(2, &self.q)];
            let phi = [row(3, &self.q), row(4, &self.q), row(5, &self.q)];
            let ud = [row(0, &self.qd), row(1, &self.qd), row(2, &self.qd)];
            let phid = [row(3, &self.qd), row(4, &self.qd), row(5, &self.qd)];
            let udd = [row(0, &self.eval.qdd), row(1, &self.eval.qdd), row(2, &self.eval.qdd)];
            let phidd = [row(3, &self.eval.qdd), row(4, &self.eval.qdd), row(5, &self.eval.qdd)];
            let rho = k3::mul(a, k3::add(flange.position, u));
            let ud_w = k3::mul(a, ud);
            let phid_w = k3::mul(a, phid);
            let out = &mut self.eval.flanges[i];
            out.u = u;
            out.phi = phi;
            out.r = k3::add(m.r, rho);
            out.rot = k3::mat_mul(a, &k3::rotation_of(phi));
            out.v = k3::add(m.v, k3::add(k3::cross(m.w, rho), ud_w));
            out.w = k3::add(m.w, phid_w);
            out.a = k3::add(
                k3::add(m.a, k3::cross(m.z, rho)),
                k3::add(
                    k3::add(k3::cross(m.w, k3::cross(m.w, rho)), k3::scale(2.0, k3::cross(m.w, ud_w))),
                    k3::mul(a, udd),
                ),
            );
            out.z = k3::add(k3::add(m.z, k3::cross(m.w, phid_w)), k3::mul(a, phidd));
            // loads the host applies, moved to the mount point, in B
            let load = &self.loads[i];
            let f_b = k3::mul_t(a, load.f);
            force = k3::add(force, load.f);
            torque_b = k3::add(torque_b, k3::add(k3::cross(k3::add(flange.position, u), f_b), k3::mul_t(a, load.t)));
        }
        // Momentum balance of the whole body: the mount supplies what the inertia needs beyond
        // gravity and the flange loads (second-order terms in q dropped).
        let a_b = k3::mul_t(a, k3::sub(m.a, self.params.g));
        let row3 = |mat: &[f64], r: usize, x: &[f64]| -> f64 {
            mat[r * n..(r + 1) * n].iter().zip(x).map(|(s, v)| s * v).sum()
        };
        let qdd = &self.eval.qdd;
        let ct_qdd = [row3(&self.body.c_t, 0, qdd), row3(&self.body.c_t, 1, qdd), row3(&self.body.c_t, 2, qdd)];
        let cr_qdd = [row3(&self.body.c_r, 0, qdd), row3(&self.body.c_r, 1, qdd), row3(&self.body.c_r, 2, qdd)];
        let ct_q = [row3(&self.body.c_t, 0, &self.q), row3(&self.body.c_t, 1, &self.q), row3(&self.body.c_t, 2, &self.q)];
        let inertial_force_b = k3::add(k3::scale(self.body.mass, a_b), ct_qdd);
        self.eval.mount_force = k3::sub(k3::mul(a, inertial_force_b), force);
        let first_moment = k3::add(self.body.first_moment, ct_q);
        let inertial_torque_b = k3::add(k3::cross(first_moment, a_b), cr_qdd);
        self.eval.mount_torque = k3::mul(a, k3::sub(inertial_torque_b, torque_b));
        self.eval.valid = true;
        Ok(())
    }

    /// d/dt (q, q') into `dq`, `dqd`.
    pub fn derivatives(&mut self, dq: &mut [f64], dqd: &mut [f64]) -> Result<(), String> {
        self.evaluate()?;
        dq.copy_from_slice(&self.qd);
        dqd.copy_from_slice(&self.eval.qdd);
        Ok(())
    }

    pub fn qdd(&mut self) -> Result<&[f64], String> {
        self.evaluate()?;
        Ok(&self.eval.qdd)
    }

    pub fn flange_motion(&mut self, flange: usize) -> Result<&FlangeMotion, String> {
        self.evaluate()?;
        Ok(&self.eval.flanges[flange])
    }

    /// Force and torque (about the mount point) the mount applies to the body, world frame.
    pub fn mount_reaction(&mut self) -> Result<(Vec3, Vec3), String> {
        self.evaluate()?;
        Ok((self.eval.mount_force, self.eval.mount_torque))
    }

    /// Put the body at rest in the static equilibrium of the present inputs: q = K^-1 p, q' = 0.
    pub fn settle_static(&mut self) -> Result<(), String> {
        self.check_inputs()?;
        self.modal_load();
        for j in 0..self.q.len() {
            self.q[j] = self.load[j] / (self.body.omega[j] * self.body.omega[j]);
            self.qd[j] = 0.0;
        }
        self.eval.valid = false;
        Ok(())
    }

    /// Advance by h with the inputs held over the step (exact modal propagation).
    pub fn step(&mut self, h: f64) -> Result<(), String> {
        if !(h > 0.0 && h.is_finite()) {
            return Err(format!("step size {h} must be positive and finite"));
        }
        self.check_inputs()?;
        self.modal_load();
        self.propagator.prepare(&self.body.omega, self.params.alpha, self.params.beta, h);
        self.propagator.advance(&self.body.omega, &self.load, &mut self.q, &mut self.qd);
        self.eval.valid = false;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::reduced::two_mode_body;

    #[test]
    fn gravity_reaction_holds_the_weight() {
        let mut b = FlexibleBody::new(Arc::new(two_mode_body()));
        b.parameters_mut().g = [0.0, 0.0, -9.81];
        b.settle_static().unwrap();
        let (f, t) = b.mount_reaction().unwrap();
        let m = b.reduced().mass;
        // static: the elastic deflection changes the torque through C_t q only
        assert!((f[2] - m * 9.81).abs() < 1e-12, "{f:?}");
        assert!(f[0].abs() < 1e-12 && f[1].abs() < 1e-12);
        let ct_q: Vec3 = [0, 1, 2].map(|r| (0..2).map(|j| b.reduced().c_t[r * 2 + j] * b.q()[j]).sum());
        let c = k3::add(b.reduced().first_moment, ct_q);
        let expected = k3::cross(c, [0.0, 0.0, 9.81]);
        for i in 0..3 {
            assert!((t[i] - expected[i]).abs() < 1e-12, "{t:?} vs {expected:?}");
        }
    }

    #[test]
    fn static_start_has_zero_acceleration_and_stepping_keeps_it() {
        let mut b = FlexibleBody::new(Arc::new(two_mode_body()));
        b.load_mut(0).f = [0.0, 3.0, -1.0];
        b.load_mut(0).t = [0.5, 0.0, 0.0];
        b.settle_static().unwrap();
        assert!(b.qdd().unwrap().iter().all(|a| a.abs() < 1e-9));
        let q0 = b.q().to_vec();
        for _ in 0..100 {
            b.step(0.01).unwrap();
        }
        for (a, b) in q0.iter().zip(b.q()) {
            assert!((a - b).abs() <= 1e-14 * a.abs().max(1e-300));
        }
    }

    #[test]
    fn a_non_rotation_mount_is_refused_with_its_name() {
        let mut b = FlexibleBody::new(Arc::new(two_mode_body()));
        b.mount_mut().rot = [2.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0];
        let e = b.step(0.1).unwrap_err();
        assert!(e.contains("base.R"), "{e}");
    }
}
