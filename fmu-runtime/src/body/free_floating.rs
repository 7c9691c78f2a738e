//! The free-floating body: its initial frame, and the accelerations of frame and modes coupled
//! through the inertia J(q) and C_r(q), and its energy and momenta.

use super::dense::{dot, shape_dot, solve_dense};
use super::{BodyError, FlexibleBody, FrameState, Invariants, MountMotion};
use crate::kinematics::{self as k3, Mat3, Vec3};
use crate::reduced::RotationTerms;
use crate::scalar::{Scalar, c};

impl FlexibleBody {
    /// Put a free-floating body at its initial pose and velocity.
    pub fn start_frame(&mut self) {
        let i = self.inputs.initial_frame;
        if let Some(f) = self.coords_mut().frame.as_mut() {
            let rot = k3::rotation_of(i.phi);
            *f = FrameState { r: i.r, quat: k3::quaternion_of(&rot), v: i.v, w_body: k3::mul_t(&rot, i.w) };
        }
    }
}

impl<T: Scalar> FlexibleBody<T> {
    /// Rates of the frame state (d/dt r, quaternion, v, body angular velocity).
    pub fn frame_rate(&mut self) -> Result<FrameState<T>, BodyError> {
        self.evaluate()?;
        Ok(self.derived.frame_rate)
    }

    /// Accelerations of a free-floating body: the frame's translational motion is the centre of
    /// mass's (mean axes: C_t = 0), its rotation and the modes couple through J(q) and C_r(q):
    ///   [J(q)  C_r(q)] [W']   [tau - W x h - J'(q) W                                   ]
    ///   [C_r^T   I   ] [q''] = [p - D q' - K q - 2 sum W_a G_a q' - sum W_a W_b (O_ab q + o_ab)]
    /// with h = J W + C_r q' (floating-frame invariants, exact in q to second order).
    pub(super) fn free_accelerations(&mut self) -> Result<(), BodyError> {
        let frame = self.coords.frame.ok_or(BodyError::NotFreeFloating)?;
        let n = self.coords.q.len();
        let b = self.body.clone();
        let rot_terms = b.rotation.as_ref().ok_or(BodyError::RotationInvariantsNeeded)?;
        let a = k3::rotation_of_quaternion(unit_quaternion(frame.quat)?);
        let w = frame.w_body;
        let total_force: Vec3<T> = self.inputs.loads.iter().fold([T::zero(); 3], |acc, l| k3::add(acc, l.f));
        let accel = k3::add(k3::scale(c(1.0 / b.mass), total_force), self.gravity());
        self.inputs.mount =
            MountMotion { r: frame.r, rot: a, v: frame.v, w: k3::mul(&a, w), a: accel, z: [T::zero(); 3] };
        self.derived.rot = a;
        // modal load of the flange loads and the centrifugal o_ab terms (C_t = 0, c_a = 0 here)
        self.modal_load();
        // the modes that carry the dynamics: all of them, or (Model Exchange) those below the cutoff
        let nd = if self.split.quasi_static { self.split.n_dynamic } else { n };
        if nd < n {
            self.free_quasi_static(w)?;
        }
        self.modal_right_hand_side(rot_terms, w, nd);
        let (j, j_rate) = self.inertia_in_deformation(rot_terms);
        let cr_qd: Vec3<T> = [0, 1, 2].map(|i| dot(&self.derived.cr_q[i * n..(i + 1) * n], &self.coords.qd));
        let h = k3::add(k3::mul(&j, w), cr_qd);
        let torque = self.flange_torque(&a);
        let rhs_w = k3::sub(k3::sub(torque, k3::cross(w, h)), k3::mul(&j_rate, w));
        // quasi-static modes have no acceleration: they neither load the frame nor take its share
        self.derived.eval.qdd[nd..].fill(T::zero());
        // Schur complement over the accelerated modes: (J - C_r C_r^T) W' = rhs_w - C_r rhs_q
        let mut s = j;
        let mut rhs = rhs_w;
        for p in 0..3 {
            let cp = &self.derived.cr_q[p * n..p * n + nd];
            rhs[p] -= dot(cp, &self.derived.eval.qdd[..nd]);
            for q_ in 0..3 {
                let cq = &self.derived.cr_q[q_ * n..q_ * n + nd];
                s[3 * p + q_] -= dot(cp, cq);
            }
        }
        let mut w_dot = rhs;
        solve_dense(&mut s, &mut w_dot, 3, &mut [0; 3]).map_err(|()| BodyError::SingularInertia)?;
        for r in 0..nd {
            let f = self.derived.cr_q[r] * w_dot[0]
                + self.derived.cr_q[n + r] * w_dot[1]
                + self.derived.cr_q[2 * n + r] * w_dot[2];
            self.derived.eval.qdd[r] -= f;
        }
        self.inputs.mount.z = k3::mul(&a, w_dot);
        let quat_rate = quaternion_rate(frame.quat, w);
        self.derived.frame_rate = FrameState { r: frame.v, quat: quat_rate, v: accel, w_body: w_dot };
        Ok(())
    }

    /// The modes' side of the free body's equations, before the frame's angular acceleration:
    /// p - D q' - K q - 2 sum W_a G_a q' - sum W_a W_b O_ab q, into the accelerations of the
    /// first `nd` modes.
    fn modal_right_hand_side(&mut self, rot_terms: &RotationTerms, w: Vec3<T>, nd: usize) {
        let n = self.coords.q.len();
        let nn = n * n;
        let (alpha, beta) = (self.inputs.params.alpha, self.inputs.params.beta);
        // the quasi-static rows stay at zero acceleration: no right-hand side for them
        let b = &self.body;
        let rhs_q = &mut self.derived.eval.qdd[..nd];
        for (j, rhs) in rhs_q.iter_mut().enumerate() {
            let w2 = b.omega[j] * b.omega[j];
            *rhs = self.derived.load[j]
                - self.coords.qd[j] * (alpha + beta * w2 + b.modal_damping[j])
                - self.coords.q[j] * w2;
        }
        for i in 0..3 {
            let g = &rot_terms.g[i * nn..(i + 1) * nn];
            if !w[i].is_zero() {
                for r in 0..nd {
                    let s = shape_dot(&g[r * n..(r + 1) * n], &self.coords.qd);
                    rhs_q[r] -= w[i] * 2.0 * s;
                }
            }
            for k in 0..3 {
                let ww = w[i] * w[k];
                if !ww.is_zero() {
                    let o = &rot_terms.o_mat[(3 * i + k) * nn..(3 * i + k + 1) * nn];
                    for r in 0..nd {
                        let s = shape_dot(&o[r * n..(r + 1) * n], &self.coords.q);
                        rhs_q[r] -= ww * s;
                    }
                }
            }
        }
    }

    /// C_r(q) (into `cr_q`), J(q) and J'(q) at the present deformation and its rate.
    fn inertia_in_deformation(&mut self, rot_terms: &RotationTerms) -> (Mat3<T>, Mat3<T>) {
        let b = self.body.clone();
        let n = self.coords.q.len();
        let nn = n * n;
        for i in 0..3 {
            let g = &rot_terms.g[i * nn..(i + 1) * nn];
            for col in 0..n {
                // (G_a q)_c
                let s = shape_dot(&g[col * n..(col + 1) * n], &self.coords.q);
                self.derived.cr_q[i * n + col] = s + c(b.c_r[i * n + col]);
            }
        }
        let mut j: Mat3<T> = b.inertia.map(c);
        let mut j_rate = [T::zero(); 9];
        for p in 0..3 {
            for q_ in 0..3 {
                let (o_pq, o_qp) =
                    (&rot_terms.o_vec[(3 * p + q_) * n..][..n], &rot_terms.o_vec[(3 * q_ + p) * n..][..n]);
                let o_mat = &rot_terms.o_mat[(3 * p + q_) * nn..(3 * p + q_ + 1) * nn];
                let (mut lin, mut lin_rate, mut quad, mut quad_rate) = (T::zero(), T::zero(), T::zero(), T::zero());
                for r in 0..n {
                    lin += self.coords.q[r] * (o_pq[r] + o_qp[r]);
                    lin_rate += self.coords.qd[r] * (o_pq[r] + o_qp[r]);
                    let oq = shape_dot(&o_mat[r * n..(r + 1) * n], &self.coords.q);
                    let oqd = shape_dot(&o_mat[r * n..(r + 1) * n], &self.coords.qd);
                    quad += self.coords.q[r] * oq;
                    quad_rate += self.coords.qd[r] * oq + self.coords.q[r] * oqd;
                }
                j[3 * p + q_] -= lin + quad;
                j_rate[3 * p + q_] = -(lin_rate + quad_rate);
            }
        }
        (j, j_rate)
    }

    /// Torque of the flange loads about the centre of mass, body frame.
    fn flange_torque(&self, a: &Mat3<T>) -> Vec3<T> {
        let n = self.coords.q.len();
        let mut torque = [T::zero(); 3];
        for (flange, load) in self.body.flanges.iter().zip(&self.inputs.loads) {
            let u: Vec3<T> = [0, 1, 2].map(|r| shape_dot(&flange.shapes[r * n..(r + 1) * n], &self.coords.q));
            let f_b = k3::mul_t(a, load.f);
            torque = k3::add(torque, k3::add(k3::cross(k3::add(flange.position.map(c), u), f_b), k3::mul_t(a, load.t)));
        }
        torque
    }

    /// q_s of a free body's quasi-static modes: their rows of the rotating-frame coupling at the
    /// frame's spin W (C_k = sum W_a W_b O_ab, C_d = 2 sum W_a G_a). The load of the frame's own
    /// angular acceleration through the deformation, (G_a q)_s W'_a, is of second order and left
    /// out: W' is solved after q_s and depends on it.
    fn free_quasi_static(&mut self, w: Vec3<T>) -> Result<(), BodyError> {
        if w.iter().all(|x| x.is_zero()) {
            return self.solve_quasi_static(None, None);
        }
        let (n, nd) = (self.coords.q.len(), self.split.n_dynamic);
        let nn = n * n;
        let b = self.body.clone();
        let rot_terms = b.rotation.as_ref().ok_or(BodyError::RotationInvariantsNeeded)?;
        let mut c_k = std::mem::take(&mut self.derived.qs_work.c_k);
        let mut c_d = std::mem::take(&mut self.derived.qs_work.c_d);
        c_k.fill(T::zero());
        c_d.fill(T::zero());
        for a in 0..3 {
            let g_rows = &rot_terms.g[a * nn + nd * n..(a + 1) * nn];
            for (t, g) in c_d.iter_mut().zip(g_rows) {
                *t += w[a] * 2.0 * *g;
            }
            for k in 0..3 {
                let ww = w[a] * w[k];
                let o_rows = &rot_terms.o_mat[(3 * a + k) * nn + nd * n..(3 * a + k + 1) * nn];
                for (t, o) in c_k.iter_mut().zip(o_rows) {
                    *t += ww * *o;
                }
            }
        }
        let solved = self.solve_quasi_static(Some((&c_k, &c_d)), None);
        self.derived.qs_work.c_k = c_k;
        self.derived.qs_work.c_d = c_d;
        solved
    }

    /// Energy and momenta of a free-floating body (gravity's potential included).
    pub fn invariants(&mut self) -> Result<Invariants<T>, BodyError> {
        self.evaluate()?;
        let frame = self.coords.frame.ok_or(BodyError::InvariantsOfMountedBody)?;
        let n = self.coords.q.len();
        let b = &self.body;
        let rot_terms = b.rotation.as_ref().ok_or(BodyError::RotationInvariantsMissing)?;
        let nn = n * n;
        let mut j: Mat3<T> = b.inertia.map(c);
        for p in 0..3 {
            for q_ in 0..3 {
                let (o_pq, o_qp) =
                    (&rot_terms.o_vec[(3 * p + q_) * n..][..n], &rot_terms.o_vec[(3 * q_ + p) * n..][..n]);
                let o_mat = &rot_terms.o_mat[(3 * p + q_) * nn..(3 * p + q_ + 1) * nn];
                let mut v = T::zero();
                for r in 0..n {
                    v += self.coords.q[r] * (o_pq[r] + o_qp[r]);
                    v += self.coords.q[r] * shape_dot(&o_mat[r * n..(r + 1) * n], &self.coords.q);
                }
                j[3 * p + q_] -= v;
            }
        }
        let w = frame.w_body;
        let cr_qd: Vec3<T> = [0, 1, 2].map(|i| dot(&self.derived.cr_q[i * n..(i + 1) * n], &self.coords.qd));
        let jw = k3::mul(&j, w);
        let h = k3::add(jw, cr_qd);
        let v2 = k3::dot(frame.v, frame.v);
        let mut energy = v2 * (0.5 * b.mass) + k3::dot(w, jw) * 0.5 + k3::dot(w, cr_qd);
        for r in 0..n {
            energy += self.coords.qd[r] * 0.5 * self.coords.qd[r]
                + self.coords.q[r] * (0.5 * b.omega[r] * b.omega[r]) * self.coords.q[r];
        }
        energy -= k3::dot(self.gravity(), frame.r) * b.mass;
        let momentum = k3::scale(c(b.mass), frame.v);
        let angular_momentum = k3::add(k3::cross(frame.r, momentum), k3::mul(&self.inputs.mount.rot, h));
        Ok(Invariants { energy, momentum, angular_momentum })
    }
}

/// The state's quaternion normalised. The state holds an orientation only near the unit sphere
/// (a host's integrator keeps it there to its tolerance); the rates keep the norm, so a state off
/// it is the host's.
fn unit_quaternion<T: Scalar>(quat: [T; 4]) -> Result<[T; 4], BodyError> {
    let [q0, q1, q2, q3] = quat;
    let norm = (q0 * q0 + q1 * q1 + q2 * q2 + q3 * q3).sqrt();
    if !(norm.value() > 0.5 && norm.value() < 2.0) {
        return Err(BodyError::Orientation { quat: quat.map(|x| x.value()), norm: norm.value() });
    }
    Ok(quat.map(|x| x / norm))
}

/// d/dt quat = 1/2 quat (x) (0, W) of the state's own quaternion: keeps its norm, so the frame
/// turns at exactly W whatever the norm has drifted to.
fn quaternion_rate<T: Scalar>(quat: [T; 4], w: Vec3<T>) -> [T; 4] {
    let [q0, q1, q2, q3] = quat;
    let half = [w[0] * 0.5, w[1] * 0.5, w[2] * 0.5];
    [
        -(q1 * half[0]) - q2 * half[1] - q3 * half[2],
        q0 * half[0] + q2 * half[2] - q3 * half[1],
        q0 * half[1] + q3 * half[0] - q1 * half[2],
        q0 * half[2] + q1 * half[1] - q2 * half[0],
    ]
}
