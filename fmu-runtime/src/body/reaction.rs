//! The mount reaction: the force and torque the mount applies to the body, from the momentum
//! balance of the whole body, evaluated on demand.

use super::dense::shape_dot;
use super::{BodyError, FlexibleBody};
use crate::kinematics::{self as k3, Mat3, Vec3};
use crate::scalar::{Scalar, c};

impl<T: Scalar> FlexibleBody<T> {
    /// Force and torque (about the mount point) the mount applies to the body, world frame.
    pub fn mount_reaction(&mut self) -> Result<(Vec3<T>, Vec3<T>), BodyError> {
        self.evaluate()?;
        self.evaluate_reaction();
        Ok((self.derived.eval.mount_force, self.derived.eval.mount_torque))
    }

    /// The mount reaction at the last evaluation (evaluate first).
    fn evaluate_reaction(&mut self) {
        if self.derived.eval.reaction_valid {
            return;
        }
        let n = self.coords.q.len();
        let a = &self.derived.rot;
        let mut torque_b = [T::zero(); 3];
        let mut force = [T::zero(); 3];
        for (i, flange) in self.body.flanges.iter().enumerate() {
            let u: Vec3<T> = [0, 1, 2].map(|r| shape_dot(&flange.shapes[r * n..(r + 1) * n], &self.coords.q));
            // loads the host applies, moved to the mount point, in B
            let load = &self.inputs.loads[i];
            let f_b = k3::mul_t(a, load.f);
            force = k3::add(force, load.f);
            torque_b =
                k3::add(torque_b, k3::add(k3::cross(k3::add(flange.position.map(c), u), f_b), k3::mul_t(a, load.t)));
        }
        // Momentum balance of the whole body about the mount point, in B: the mount supplies what
        // the inertia needs beyond gravity and the flange loads (terms of second order in q, q'
        // dropped, except where they come for free).
        let (w, z, a_b) = (self.derived.coupling.w, self.derived.coupling.z, self.derived.coupling.a);
        let b = &*self.body;
        let row3 = |mat: &[f64], x: &[T]| -> Vec3<T> { [0, 1, 2].map(|r| shape_dot(&mat[r * n..(r + 1) * n], x)) };
        let qdd = &self.derived.eval.qdd;
        let ct_qdd = row3(&b.c_t, qdd);
        let ct_qd = row3(&b.c_t, &self.coords.qd);
        let first_moment = k3::add(b.first_moment.map(c), row3(&b.c_t, &self.coords.q));
        let mut inertial_force_b = k3::add(k3::scale(c(b.mass), a_b), ct_qdd);
        inertial_force_b = k3::add(inertial_force_b, k3::cross(z, first_moment));
        inertial_force_b = k3::add(inertial_force_b, k3::cross(w, k3::cross(w, first_moment)));
        inertial_force_b = k3::add(inertial_force_b, k3::scale(c(2.0), k3::cross(w, ct_qd)));
        self.derived.eval.mount_force = k3::sub(k3::mul(a, inertial_force_b), force);

        // J(q) = J0 + J1(q), J1_ab = -(o_ab + o_ba) . q;  C_r(q) v = C_r v + [(G_a q) . v]_a
        let mut j: Mat3<T> = b.inertia.map(c);
        let mut j_rate = [T::zero(); 9];
        let mut cr_qdd = row3(&b.c_r, qdd);
        let mut cr_qd = row3(&b.c_r, &self.coords.qd);
        if let Some(rot) = &b.rotation {
            for p_ in 0..3 {
                for q_ in 0..3 {
                    let (o_pq, o_qp) = (&rot.o_vec[(3 * p_ + q_) * n..][..n], &rot.o_vec[(3 * q_ + p_) * n..][..n]);
                    let mut s = T::zero();
                    let mut sd = T::zero();
                    for k in 0..n {
                        s += self.coords.q[k] * (o_pq[k] + o_qp[k]);
                        sd += self.coords.qd[k] * (o_pq[k] + o_qp[k]);
                    }
                    j[3 * p_ + q_] -= s;
                    j_rate[3 * p_ + q_] = -sd;
                }
            }
            let nn = n * n;
            for a_ in 0..3 {
                let g = &rot.g[a_ * nn..(a_ + 1) * nn];
                let (mut s_dd, mut s_d) = (T::zero(), T::zero());
                for r in 0..n {
                    let gq = shape_dot(&g[r * n..(r + 1) * n], &self.coords.q);
                    s_dd += gq * qdd[r];
                    s_d += gq * self.coords.qd[r];
                }
                cr_qdd[a_] += s_dd;
                cr_qd[a_] += s_d;
            }
        }
        let jw = k3::mul(&j, w);
        let mut inertial_torque_b = k3::add(k3::cross(first_moment, a_b), cr_qdd);
        inertial_torque_b = k3::add(inertial_torque_b, k3::mul(&j, z));
        inertial_torque_b = k3::add(inertial_torque_b, k3::cross(w, jw));
        inertial_torque_b = k3::add(inertial_torque_b, k3::mul(&j_rate, w));
        inertial_torque_b = k3::add(inertial_torque_b, k3::cross(w, cr_qd));
        self.derived.eval.mount_torque = k3::mul(a, k3::sub(inertial_torque_b, torque_b));
        self.derived.eval.reaction_valid = true;
    }
}

#[cfg(test)]
mod tests {
    use super::super::FlexibleBody;
    use crate::kinematics::{self as k3, Vec3};
    use crate::reduced::two_mode_body;
    use std::sync::Arc;

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
}
