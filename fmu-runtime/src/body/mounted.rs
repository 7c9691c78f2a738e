//! The equations of a body on a prescribed mount: the mount inputs' check, the modal load p, the
//! coupling terms C_d, C_k of rotation and stiffening, and q''.

use super::coupling_terms::{CouplingTerms, coefficients};
use super::{BodyError, Coupling, FlangeLoad, FlexibleBody, MountMotion};
use crate::kinematics::{self as k3, Mat3, Vec3};
use crate::reduced::ReducedBody;
use crate::scalar::{Scalar, c};

/// Largest entry of |A^T A - I| accepted for the mount orientation (absolute: a rotation's
/// entries are of order one). Hosts interpolate rotation-matrix inputs entry by entry (FMPy
/// between samples, masters with first-order hold: the mean of two rotations 0.1 rad apart is
/// off by 1e-3), which leaves them slightly off orthonormal; within this tolerance the nearest
/// rotation is used. A matrix beyond it is no orientation (a unit, transposition or indexing
/// error of the host) and is refused.
pub const ROTATION_TOLERANCE: f64 = 1e-2;

impl FlexibleBody {
    /// The mount orientation as the host last set it (not the pose a step turned it to).
    pub fn host_rotation(&self) -> [f64; 9] {
        self.inputs.host.rot.unwrap_or(self.inputs.mount.rot)
    }

    /// Err with the reason unless `rot` is a rotation within [`ROTATION_TOLERANCE`].
    pub fn check_rotation(&self, rot: &[f64; 9]) -> Result<(), BodyError> {
        rotation_refusal(&self.body.mount, k3::rotation_defect(rot))
    }
}

fn rotation_refusal(mount: &str, defect: f64) -> Result<(), BodyError> {
    // a NaN defect (non-finite entries) is refused too
    if defect.is_nan() || defect > ROTATION_TOLERANCE {
        return Err(BodyError::NotARotation { mount: mount.to_owned(), defect });
    }
    Ok(())
}

impl<T: Scalar> FlexibleBody<T> {
    /// Refuse a mount orientation off the rotations or a spin the body was not built for; set
    /// the orientation in use.
    pub(super) fn check_inputs(&mut self) -> Result<(), BodyError> {
        let defect = k3::rotation_defect(&self.inputs.mount.rot.map(T::value));
        rotation_refusal(&self.body.mount, defect)?;
        // a derivative goes through the projection even at an exact rotation: a change of R
        // off the rotations moves the body only by its rotational part
        self.derived.rot = if defect > 1e-14 || T::CARRIES_DERIVATIVE {
            k3::nearest_rotation(&self.inputs.mount.rot)
        } else {
            self.inputs.mount.rot
        };
        let spinning = self.inputs.mount.w.iter().chain(&self.inputs.mount.z).any(|x| x.value() != 0.0);
        if self.body.rotation.is_none() && spinning {
            return Err(BodyError::SpinWithoutRotation { mount: self.body.mount.clone() });
        }
        Ok(())
    }

    /// The coupling's coefficients for the inputs, and the rows of its matrices C_d, C_k from
    /// `first` on.
    pub(super) fn prepare_coupling_rows(&mut self, first: usize) {
        self.prepare_coupling_coefficients();
        if self.derived.coupling.rows_from.is_none_or(|r| r > first) {
            fill_coupling_rows(&self.coupling_terms, &self.body, first, &mut self.derived.coupling);
        }
    }

    /// The coupling's coefficients for the inputs (the Co-Simulation step needs its matrices
    /// only where it renews its transition).
    pub(super) fn prepare_coupling_coefficients(&mut self) {
        if !self.derived.coupling.valid {
            coupling_coefficients(
                &self.coupling_terms,
                &self.derived.rot,
                &self.inputs.mount,
                &self.inputs.loads,
                self.inputs.params.g,
                &mut self.derived.coupling,
            );
        }
    }

    /// p = -C_t^T a_B + sum_k Phi_k^T [A^T f_k; A^T t_k]
    pub(super) fn modal_load(&mut self) {
        let a = &self.derived.rot;
        let a_b = k3::mul_t(a, k3::sub(self.inputs.mount.a, self.inputs.params.g.map(c)));
        let n = self.coords.q.len();
        let ct = &self.body.c_t;
        for j in 0..n {
            self.derived.load[j] = -(a_b[0] * ct[j] + a_b[1] * ct[n + j] + a_b[2] * ct[2 * n + j]);
        }
        if let Some(rot) = &self.body.rotation {
            let w = k3::mul_t(a, self.inputs.mount.w);
            let z = k3::mul_t(a, self.inputs.mount.z);
            for i in 0..3 {
                if !z[i].is_zero() {
                    let c_a = &self.body.c_r[i * n..(i + 1) * n];
                    for (load, c_a) in self.derived.load.iter_mut().zip(c_a) {
                        *load -= z[i] * *c_a;
                    }
                }
                for k in 0..3 {
                    let ww = w[i] * w[k];
                    if !ww.is_zero() {
                        let o = &rot.o_vec[(3 * i + k) * n..(3 * i + k + 1) * n];
                        for (load, o) in self.derived.load.iter_mut().zip(o) {
                            *load -= ww * *o;
                        }
                    }
                }
            }
        }
        for (flange, load) in self.body.flanges.iter().zip(&self.inputs.loads) {
            let f_b = k3::mul_t(a, load.f);
            let t_b = k3::mul_t(a, load.t);
            let wrench = [f_b[0], f_b[1], f_b[2], t_b[0], t_b[1], t_b[2]];
            for (row, w) in wrench.iter().enumerate() {
                if !w.is_zero() {
                    let shape = &flange.shapes[row * n..(row + 1) * n];
                    for (load, s) in self.derived.load.iter_mut().zip(shape) {
                        *load += *w * *s;
                    }
                }
            }
        }
    }

    /// q'' of a body on a prescribed mount: the modal diagonal, then the coupling terms.
    pub(super) fn mounted_accelerations(&mut self) -> Result<(), BodyError> {
        self.check_inputs()?;
        self.modal_load();
        let n = self.coords.q.len();
        // the algebraic modes' solve (Model Exchange) reads the coupling's rows; the accelerated
        // modes' coupling force comes from its terms
        if self.split.quasi_static && self.split.n_dynamic < n {
            self.prepare_coupling_rows(self.split.n_dynamic);
        } else {
            self.prepare_coupling_coefficients();
        }
        if self.split.quasi_static {
            // the coupling's rows are lent to the solve (moving the vectors allocates nothing)
            let coupling = std::mem::take(&mut self.derived.coupling);
            let nd = self.split.n_dynamic;
            let rows = coupling.active.then(|| (&coupling.c_k[nd * n..], &coupling.c_d[nd * n..]));
            let solved = self.solve_quasi_static(rows, Some(&coupling.coef));
            self.derived.coupling = coupling;
            solved?;
        }
        // the accelerated modes: all, or (Model Exchange) the dynamic ones; the rest are at rest
        let na = if self.split.quasi_static { self.split.n_dynamic } else { n };
        let (alpha, beta) = (self.inputs.params.alpha, self.inputs.params.beta);
        for j in 0..na {
            let w2 = self.body.omega[j] * self.body.omega[j];
            self.derived.eval.qdd[j] = self.derived.load[j]
                - self.coords.qd[j] * (alpha + beta * w2 + self.body.modal_damping[j])
                - self.coords.q[j] * w2;
        }
        if self.derived.coupling.active {
            let force = &mut self.derived.coupling.force[..na];
            self.coupling_terms.force(&self.body, &self.derived.coupling.coef, &self.coords.q, &self.coords.qd, force);
            for (qdd, f) in self.derived.eval.qdd.iter_mut().zip(force.iter()) {
                *qdd -= *f;
            }
        }
        self.derived.eval.qdd[na..].fill(T::zero());
        Ok(())
    }
}

/// The coupling's coefficients for the given inputs (body-frame w, z, a_B and flange wrenches;
/// see `coupling_terms`) and whether any term is active; its matrices are left to
/// [`fill_coupling_rows`]. `rot` is the mount orientation in use (the input projected onto
/// the rotations), as in the load.
pub(super) fn coupling_coefficients<T: Scalar>(
    terms: &CouplingTerms,
    rot: &Mat3<T>,
    mount: &MountMotion<T>,
    loads: &[FlangeLoad<T>],
    g: Vec3,
    c: &mut Coupling<T>,
) {
    let a = rot;
    c.w = k3::mul_t(a, mount.w);
    c.z = k3::mul_t(a, mount.z);
    c.a = k3::mul_t(a, k3::sub(mount.a, g.map(crate::scalar::c)));
    let wrenches = loads.iter().map(|l| {
        let (f, t) = (k3::mul_t(a, l.f), k3::mul_t(a, l.t));
        [f[0], f[1], f[2], t[0], t[1], t[2]]
    });
    coefficients(c.w, c.z, c.a, wrenches, &mut c.coef);
    c.active = terms.active(&c.coef);
    c.valid = true;
    c.rows_from = None;
}

/// Rows `first..` of C_d = 2 sum w_a G_a and C_k = sum z_a (G_a + E_a) + sum w_a w_b (O_ab +
/// K_ab) + K_G for the coefficients [`coupling_coefficients`] set.
pub(super) fn fill_coupling_rows<T: Scalar>(
    terms: &CouplingTerms,
    body: &ReducedBody,
    first: usize,
    c: &mut Coupling<T>,
) {
    let n = body.n_modes();
    terms.fill_rows(body, &c.coef, first, &mut c.c_d[first * n..], &mut c.c_k[first * n..]);
    c.rows_from = Some(first);
}
