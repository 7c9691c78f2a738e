//! The reduced flexible body's equations, free of anything FMI: inputs (mount motion, flange
//! loads, gravity), modal state q, q', and what the flanges see.
//!
//! Equations (body frame B, modal mass I, stiffness diag(w^2), Rayleigh damping; docs/ARCHITECTURE.md):
//!   q'' + (D + 2 sum_a W_a G_a) q' + (K + sum_a Z_a G_a + sum_ab W_a W_b O_ab + K_G) q
//!       = -C_t^T a_B - sum_a Z_a c_a - sum_ab W_a W_b o_ab + sum_k Phi_k^T [A^T f_k; A^T t_k],
//! with W = A^T w, Z = A^T z, a_B = A^T (a - g), and K_G the geometric stiffness of the present
//! loads (linear in them). The coupling terms (everything off the modal diagonal) are gathered in
//! two r x r matrices whenever the inputs change.

use crate::kinematics::{self as k3, Mat3, Vec3};
use crate::coupled_propagator::{CoupledPropagator, Prepared};
use crate::propagator::ModalPropagator;
use crate::reduced::ReducedBody;
use crate::scalar::{Dual, Scalar, c};
use std::sync::Arc;

/// Prescribed motion of the mount flange, resolved in the world frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MountMotion<T = f64> {
    pub r: Vec3<T>,
    /// Rotation B -> world (columns: body axes in world).
    pub rot: Mat3<T>,
    pub v: Vec3<T>,
    pub w: Vec3<T>,
    pub a: Vec3<T>,
    pub z: Vec3<T>,
}

impl<T: Copy> MountMotion<T> {
    pub fn map<U>(&self, f: impl Fn(T) -> U) -> MountMotion<U> {
        MountMotion { r: self.r.map(&f), rot: self.rot.map(&f), v: self.v.map(&f), w: self.w.map(&f), a: self.a.map(&f), z: self.z.map(&f) }
    }
}

impl<T: Scalar> Default for MountMotion<T> {
    fn default() -> Self {
        let o = [T::zero(); 3];
        Self { r: o, rot: k3::IDENTITY.map(c), v: o, w: o, a: o, z: o }
    }
}

/// Force and torque the host applies at a force flange, world frame; torque about the flange.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct FlangeLoad<T = f64> {
    pub f: Vec3<T>,
    pub t: Vec3<T>,
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Parameters {
    pub g: Vec3,
    pub alpha: f64,
    pub beta: f64,
}

/// Motion of a force flange, world frame except `u`, `phi` (deformation in B).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct FlangeMotion<T = f64> {
    pub r: Vec3<T>,
    pub rot: Mat3<T>,
    pub v: Vec3<T>,
    pub w: Vec3<T>,
    pub a: Vec3<T>,
    pub z: Vec3<T>,
    pub u: Vec3<T>,
    pub phi: Vec3<T>,
}

/// Everything that follows from state and inputs at one instant.
#[derive(Debug, Clone, Default)]
struct Evaluation<T> {
    valid: bool,
    qdd: Vec<T>,
    flanges: Vec<FlangeMotion<T>>,
    /// The mount reaction is evaluated on demand: hosts that read only flange outputs skip its
    /// n^2 terms.
    reaction_valid: bool,
    mount_force: Vec3<T>,
    mount_torque: Vec3<T>,
}

/// Rigid-body state of a free-floating body: centre-of-mass position and velocity (world), unit
/// quaternion (w, x, y, z) of the body frame, angular velocity in the body frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrameState<T = f64> {
    pub r: Vec3<T>,
    pub quat: [T; 4],
    pub v: Vec3<T>,
    pub w_body: Vec3<T>,
}

impl<T: Copy> FrameState<T> {
    pub fn map<U>(&self, f: impl Fn(T) -> U) -> FrameState<U> {
        FrameState { r: self.r.map(&f), quat: self.quat.map(&f), v: self.v.map(&f), w_body: self.w_body.map(&f) }
    }
}

impl<T: Scalar> Default for FrameState<T> {
    fn default() -> Self {
        let o = [T::zero(); 3];
        Self { r: o, quat: [c(1.0), T::zero(), T::zero(), T::zero()], v: o, w_body: o }
    }
}

/// Initial pose and velocity of a free-floating body (world frame), the FMU's parameters.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct InitialFrame {
    pub r: Vec3,
    /// Rotation vector of the initial orientation.
    pub phi: Vec3,
    pub v: Vec3,
    pub w: Vec3,
}

/// Energy and momenta of a free-floating body (world frame; angular momentum about the origin).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Invariants<T = f64> {
    pub energy: T,
    pub momentum: Vec3<T>,
    pub angular_momentum: Vec3<T>,
}

/// Workspace of a mounted body's step with coupling terms: the inputs and coupling at the
/// step's end and their midpoint.
#[derive(Debug, Clone, Default)]
struct CoupledWork {
    /// The substep's start state and the predictor-corrector's loads.
    q0: Vec<f64>,
    qd0: Vec<f64>,
    f0: Vec<f64>,
    f1: Vec<f64>,
    /// The coupling at the step's midpoint (ramped inputs) and a zero load rate (held inputs).
    c_d_mid: Vec<f64>,
    c_k_mid: Vec<f64>,
    zeros: Vec<f64>,
    loads_end: Vec<FlangeLoad>,
    coupling_end: Coupling<f64>,
}

/// Workspace of a free-floating body's step: the substep's start state and its two coupling
/// loads (empty for a mounted body).
#[derive(Debug, Clone, Default)]
struct FreeWork {
    q0: Vec<f64>,
    qd0: Vec<f64>,
    load0: Vec<f64>,
    load1: Vec<f64>,
}

/// Everything of a [`FlexibleBody`] that evolves or can be set: what a saved state holds. The
/// rest is the immutable reduced body and caches that are functions of these (recomputed on
/// demand, so a body rebuilt from its state continues bit-identically).
#[derive(Debug, Clone, PartialEq)]
pub struct BodyState {
    pub mount: MountMotion,
    pub loads: Vec<FlangeLoad>,
    pub params: Parameters,
    pub q: Vec<f64>,
    pub qd: Vec<f64>,
    /// Some exactly for free-floating bodies.
    pub frame: Option<FrameState>,
    pub initial_frame: InitialFrame,
    /// Input derivatives set for the next step and not yet used.
    pub rates: InputRates,
    /// The coupling the exact coupled transition was last made for: later steps depend on it,
    /// so a body restored from this state continues bit-identically.
    pub coupling_reference: Option<CouplingReference>,
}

/// Step size, Rayleigh coefficients and coupling matrices of a coupled transition.
#[derive(Debug, Clone, PartialEq)]
pub struct CouplingReference {
    pub h: f64,
    pub alpha: f64,
    pub beta: f64,
    pub c_d: Vec<f64>,
    pub c_k: Vec<f64>,
}

/// Terms that couple the modes, for the present inputs: q'' = ... - C_d q' - C_k q.
#[derive(Debug, Clone, Default)]
struct Coupling<T> {
    valid: bool,
    active: bool,
    c_d: Vec<T>,
    c_k: Vec<T>,
    /// Body-frame angular velocity, angular acceleration and a_B of the present inputs.
    w: Vec3<T>,
    z: Vec3<T>,
    a: Vec3<T>,
}

/// The body's equations over the scalar `T`: `f64` for the model, [`Dual`] for the exact
/// directional derivatives of everything it evaluates (see [`FlexibleBody::to_dual`]). Stepping
/// is `f64` only.
#[derive(Debug, Clone)]
pub struct FlexibleBody<T = f64> {
    body: Arc<ReducedBody>,
    mount: MountMotion<T>,
    loads: Vec<FlangeLoad<T>>,
    params: Parameters,
    q: Vec<T>,
    qd: Vec<T>,
    /// Modal load p, workspace.
    load: Vec<T>,
    eval: Evaluation<T>,
    coupling: Coupling<T>,
    /// The mount orientation in use: the input made exactly orthonormal.
    rot: Mat3<T>,
    /// Free-floating bodies only: the rigid-body state, its initial value and its rates.
    frame: Option<FrameState<T>>,
    pub initial_frame: InitialFrame,
    frame_rate: FrameState<T>,
    /// 3 x n workspace: C_r(q) = C_r + [G_a q]^T
    cr_q: Vec<T>,
    free_work: FreeWork,
    coupled_work: CoupledWork,
    propagator: ModalPropagator,
    /// Exact transition of the coupled modes (mounted bodies with rotation or stiffening terms).
    coupled: CoupledPropagator,
    /// A warning of the last step for the host's log.
    warning: Option<&'static str>,
    /// First derivatives of the inputs for the next step (fmi2SetRealInputDerivatives), and
    /// the modal load's rate they give.
    rates: InputRates,
    load_rate: Vec<f64>,
}

/// Time derivatives of the inputs over the next step (first-order hold); zero means held.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct InputRates {
    pub mount: MountMotion,
    pub loads: Vec<FlangeLoad>,
    pub any: bool,
}

/// Why a body spinning above its critical speed misbehaves, for the host's log.
pub const UNSTABLE_STIFFNESS: &str = "the effective stiffness of the body (elastic plus centrifugal and geometric terms at the present spin and loads) is not positive definite: the spin is above a critical speed of this body, whose deformation can grow without bound (declare geometric_stiffening in the scene if the real part is stiffened by its rotation)";

/// Largest |A^T A - I| accepted for the mount orientation. Hosts interpolate rotation-matrix
/// inputs entry by entry (FMPy between samples, masters with first-order hold), which leaves them
/// slightly off orthonormal; within this tolerance the nearest rotation is used.
const ROTATION_TOLERANCE: f64 = 1e-2;

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
                reaction_valid: false,
                mount_force: [0.0; 3],
                mount_torque: [0.0; 3],
            },
            coupling: Coupling { c_d: vec![0.0; n * n], c_k: vec![0.0; n * n], ..Coupling::default() },
            rot: k3::IDENTITY,
            frame: body.free_floating.then(FrameState::default),
            initial_frame: InitialFrame::default(),
            frame_rate: FrameState::default(),
            cr_q: vec![0.0; 3 * n],
            coupled_work: if body.free_floating {
                CoupledWork::default()
            } else {
                CoupledWork {
                    q0: vec![0.0; n],
                    qd0: vec![0.0; n],
                    f0: vec![0.0; n],
                    f1: vec![0.0; n],
                    c_d_mid: vec![0.0; n * n],
                    c_k_mid: vec![0.0; n * n],
                    zeros: vec![0.0; n],
                    loads_end: vec![FlangeLoad::default(); nf],
                    coupling_end: Coupling { c_d: vec![0.0; n * n], c_k: vec![0.0; n * n], ..Coupling::default() },
                }
            },
            free_work: if body.free_floating {
                FreeWork { q0: vec![0.0; n], qd0: vec![0.0; n], load0: vec![0.0; n], load1: vec![0.0; n] }
            } else {
                FreeWork::default()
            },
            propagator: ModalPropagator::with_modes(n),
            coupled: if body.free_floating || (body.rotation.is_none() && body.stiffening.is_none()) {
                CoupledPropagator::default()
            } else {
                CoupledPropagator::with_modes(n)
            },
            warning: None,
            rates: InputRates { mount: MountMotion { rot: [0.0; 9], ..MountMotion::default() }, loads: vec![FlangeLoad::default(); nf], any: false },
            load_rate: vec![0.0; n],
            body,
        }
    }

    /// This body in dual numbers at the present state and inputs, every derivative part zero.
    /// Seed a direction in the `.d` parts (through `mount_mut`, `load_mut`, `q_mut`, ...) and
    /// evaluate: every result's `.d` is then its exact directional derivative.
    pub fn to_dual(&self) -> FlexibleBody<Dual> {
        let n = self.n_modes();
        let zeros = |len: usize| vec![Dual::default(); len];
        FlexibleBody {
            body: Arc::clone(&self.body),
            mount: self.mount.map(Dual::from),
            loads: self.loads.iter().map(|l| FlangeLoad { f: l.f.map(Dual::from), t: l.t.map(Dual::from) }).collect(),
            params: self.params,
            q: self.q.iter().map(|&x| Dual::from(x)).collect(),
            qd: self.qd.iter().map(|&x| Dual::from(x)).collect(),
            load: zeros(n),
            eval: Evaluation {
                valid: false,
                qdd: zeros(n),
                flanges: vec![FlangeMotion::default(); self.eval.flanges.len()],
                reaction_valid: false,
                mount_force: [Dual::default(); 3],
                mount_torque: [Dual::default(); 3],
            },
            coupling: Coupling { c_d: zeros(n * n), c_k: zeros(n * n), ..Coupling::default() },
            rot: k3::IDENTITY.map(Dual::from),
            frame: self.frame.map(|f| f.map(Dual::from)),
            initial_frame: self.initial_frame,
            frame_rate: FrameState::default(),
            cr_q: zeros(3 * n),
            // stepping is f64 only
            free_work: FreeWork::default(),
            coupled_work: CoupledWork::default(),
            propagator: ModalPropagator::with_modes(0),
            coupled: CoupledPropagator::default(),
            warning: None,
            rates: self.rates.clone(),
            load_rate: Vec::new(),
        }
    }

    pub fn state(&self) -> BodyState {
        BodyState {
            mount: self.mount,
            loads: self.loads.clone(),
            params: self.params,
            q: self.q.clone(),
            qd: self.qd.clone(),
            frame: self.frame,
            initial_frame: self.initial_frame,
            rates: self.rates.clone(),
            coupling_reference: self.coupled.key().map(|(h, alpha, beta)| {
                let (c_d, c_k) = self.coupled.reference();
                CouplingReference { h, alpha, beta, c_d: c_d.to_vec(), c_k: c_k.to_vec() }
            }),
        }
    }

    /// A new body of the same reduced body in `state`, its caches empty; Err if the state's
    /// sizes do not fit this body.
    pub fn with_state(&self, state: BodyState) -> Result<Self, String> {
        let (n, nf) = (self.n_modes(), self.loads.len());
        if state.q.len() != n || state.qd.len() != n {
            return Err(format!(
                "the state has {} and {} modal coordinates and velocities, the body {n} modes",
                state.q.len(),
                state.qd.len()
            ));
        }
        if state.loads.len() != nf || state.rates.loads.len() != nf {
            return Err(format!("the state has loads on {} flanges, the body {nf} force flanges", state.loads.len()));
        }
        if state.frame.is_some() != self.frame.is_some() {
            let kind = |free: bool| if free { "free-floating" } else { "mounted" };
            return Err(format!(
                "the state is of a {} body, this body is {}",
                kind(state.frame.is_some()),
                kind(self.frame.is_some())
            ));
        }
        let mut b = FlexibleBody::new(Arc::clone(&self.body));
        b.mount = state.mount;
        b.loads = state.loads;
        b.params = state.params;
        b.q = state.q;
        b.qd = state.qd;
        b.frame = state.frame;
        b.initial_frame = state.initial_frame;
        b.rates = state.rates;
        if let Some(r) = state.coupling_reference {
            let nn = n * n;
            let valid = r.c_d.len() == nn && r.c_k.len() == nn && r.h > 0.0 && r.h.is_finite();
            if !valid || !b.coupled.has_storage() {
                return Err(format!("the state's coupling reference does not fit this body ({} x {} values for {n} modes)", r.c_d.len(), r.c_k.len()));
            }
            if !(r.c_d.iter().chain(&r.c_k).chain([&r.alpha, &r.beta]).all(|v| v.is_finite())) {
                return Err("the state's coupling reference has non-finite values".into());
            }
            let body = Arc::clone(&b.body);
            b.coupled.prepare(&body.omega, r.alpha, r.beta, &body.modal_damping, &r.c_d, &r.c_k, r.h);
        }
        Ok(b)
    }
    /// Put a free-floating body at its initial pose and velocity.
    pub fn start_frame(&mut self) {
        if let Some(f) = self.frame.as_mut() {
            let i = self.initial_frame;
            let rot = k3::rotation_of(i.phi);
            *f = FrameState { r: i.r, quat: k3::quaternion_of(&rot), v: i.v, w_body: k3::mul_t(&rot, i.w) };
            self.eval.valid = false;
        }
    }

    /// Rates of the mount inputs over the next step (its rotation matrix's rate entry by entry).
    pub fn mount_rate_mut(&mut self) -> &mut MountMotion {
        self.rates.any = true;
        &mut self.rates.mount
    }
    /// Rates of a flange's force and torque over the next step.
    pub fn load_rate_mut(&mut self, flange: usize) -> &mut FlangeLoad {
        self.rates.any = true;
        &mut self.rates.loads[flange]
    }
    pub fn input_rates(&self) -> &InputRates {
        &self.rates
    }
}

impl<T: Scalar> FlexibleBody<T> {
    pub fn reduced(&self) -> &ReducedBody {
        &self.body
    }
    pub fn n_modes(&self) -> usize {
        self.q.len()
    }
    pub fn q(&self) -> &[T] {
        &self.q
    }
    pub fn qd(&self) -> &[T] {
        &self.qd
    }
    pub fn mount(&self) -> &MountMotion<T> {
        &self.mount
    }
    pub fn loads(&self) -> &[FlangeLoad<T>] {
        &self.loads
    }
    pub fn parameters(&self) -> &Parameters {
        &self.params
    }

    pub fn frame(&self) -> Option<&FrameState<T>> {
        self.frame.as_ref()
    }
    pub fn frame_mut(&mut self) -> Option<&mut FrameState<T>> {
        self.eval.valid = false;
        self.frame.as_mut()
    }
    /// Rates of the frame state (d/dt r, quaternion, v, body angular velocity).
    pub fn frame_rate(&mut self) -> Result<FrameState<T>, String> {
        self.evaluate()?;
        Ok(self.frame_rate)
    }

    pub fn mount_mut(&mut self) -> &mut MountMotion<T> {
        self.eval.valid = false;
        self.coupling.valid = false;
        &mut self.mount
    }
    pub fn load_mut(&mut self, flange: usize) -> &mut FlangeLoad<T> {
        self.eval.valid = false;
        self.coupling.valid = false;
        &mut self.loads[flange]
    }
    pub fn parameters_mut(&mut self) -> &mut Parameters {
        self.eval.valid = false;
        self.coupling.valid = false;
        &mut self.params
    }
    pub fn set_state(&mut self, q: &[T], qd: &[T]) {
        self.q.copy_from_slice(q);
        self.qd.copy_from_slice(qd);
        self.eval.valid = false;
    }
    pub fn q_mut(&mut self) -> &mut [T] {
        self.eval.valid = false;
        &mut self.q
    }
    pub fn qd_mut(&mut self) -> &mut [T] {
        self.eval.valid = false;
        &mut self.qd
    }

    fn check_inputs(&mut self) -> Result<(), String> {
        let defect = k3::rotation_defect(&self.mount.rot.map(T::value));
        if !(defect <= ROTATION_TOLERANCE) {
            return Err(format!(
                "{}.R is not a proper rotation matrix (|R^T R - I| = {defect:.3e}, det must be +1)",
                self.body.mount
            ));
        }
        // a derivative goes through the projection even at an exact rotation: a change of R
        // off the rotations moves the body only by its rotational part
        self.rot = if defect > 1e-14 || T::CARRIES_DERIVATIVE { k3::nearest_rotation(&self.mount.rot) } else { self.mount.rot };
        let spinning = self.mount.w.iter().chain(&self.mount.z).any(|x| x.value() != 0.0);
        if self.body.rotation.is_none() && spinning {
            return Err(format!(
                "{m}.w and {m}.z must be zero: this FMU was built for a scene without rotation \
                 (declare \"rotation\" in the input's scene.loads to model a rotating mount)",
                m = self.body.mount
            ));
        }
        Ok(())
    }

    fn gravity(&self) -> Vec3<T> {
        self.params.g.map(c)
    }

    /// Gather C_d = 2 sum W_a G_a and C_k = sum Z_a G_a + sum W_a W_b O_ab + K_G for the inputs.
    fn prepare_coupling(&mut self) {
        if self.coupling.valid {
            return;
        }
        fill_coupling(&self.body, &self.rot, &self.mount, &self.loads, self.params.g, &mut self.coupling);
    }

    /// (C_d q' + C_k q)_i: the coupling terms' force on mode i.
    fn coupling_force(&self, i: usize) -> T {
        coupling_force_of(&self.coupling, i, &self.q, &self.qd)
    }

    /// p = -C_t^T a_B + sum_k Phi_k^T [A^T f_k; A^T t_k]
    fn modal_load(&mut self) {
        let a = &self.rot;
        let a_b = k3::mul_t(a, k3::sub(self.mount.a, self.params.g.map(c)));
        let n = self.q.len();
        let ct = &self.body.c_t;
        for j in 0..n {
            self.load[j] = -(a_b[0] * ct[j] + a_b[1] * ct[n + j] + a_b[2] * ct[2 * n + j]);
        }
        if let Some(rot) = &self.body.rotation {
            let w = k3::mul_t(a, self.mount.w);
            let z = k3::mul_t(a, self.mount.z);
            for i in 0..3 {
                if !z[i].is_zero() {
                    let c_a = &self.body.c_r[i * n..(i + 1) * n];
                    for j in 0..n {
                        self.load[j] -= z[i] * c_a[j];
                    }
                }
                for k in 0..3 {
                    let ww = w[i] * w[k];
                    if !ww.is_zero() {
                        let o = &rot.o_vec[(3 * i + k) * n..(3 * i + k + 1) * n];
                        for j in 0..n {
                            self.load[j] -= ww * o[j];
                        }
                    }
                }
            }
        }
        for (flange, load) in self.body.flanges.iter().zip(&self.loads) {
            let f_b = k3::mul_t(a, load.f);
            let t_b = k3::mul_t(a, load.t);
            let wrench = [f_b[0], f_b[1], f_b[2], t_b[0], t_b[1], t_b[2]];
            for (row, w) in wrench.iter().enumerate() {
                if !w.is_zero() {
                    let shape = &flange.shapes[row * n..(row + 1) * n];
                    for j in 0..n {
                        self.load[j] += *w * shape[j];
                    }
                }
            }
        }
    }

    fn evaluate(&mut self) -> Result<(), String> {
        if self.eval.valid {
            return Ok(());
        }
        let n = self.q.len();
        if self.frame.is_some() {
            self.free_accelerations()?;
        } else {
            self.check_inputs()?;
            self.modal_load();
            self.prepare_coupling();
            let (alpha, beta) = (self.params.alpha, self.params.beta);
            for j in 0..n {
                let w2 = self.body.omega[j] * self.body.omega[j];
                self.eval.qdd[j] = self.load[j] - self.qd[j] * (alpha + beta * w2 + self.body.modal_damping[j]) - self.q[j] * w2;
            }
        }
        if self.coupling.active && self.frame.is_none() {
            for i in 0..n {
                let f = self.coupling_force(i);
                self.eval.qdd[i] -= f;
            }
        }
        let m = &self.mount;
        let a = &self.rot;
        for (i, flange) in self.body.flanges.iter().enumerate() {
            let row = |r: usize, x: &[T]| shape_dot(&flange.shapes[r * n..(r + 1) * n], x);
            let u = [row(0, &self.q), row(1, &self.q), row(2, &self.q)];
            let phi = [row(3, &self.q), row(4, &self.q), row(5, &self.q)];
            let ud = [row(0, &self.qd), row(1, &self.qd), row(2, &self.qd)];
            let phid = [row(3, &self.qd), row(4, &self.qd), row(5, &self.qd)];
            let udd = [row(0, &self.eval.qdd), row(1, &self.eval.qdd), row(2, &self.eval.qdd)];
            let phidd = [row(3, &self.eval.qdd), row(4, &self.eval.qdd), row(5, &self.eval.qdd)];
            let rho = k3::mul(a, k3::add(flange.position.map(c), u));
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
                    k3::add(k3::cross(m.w, k3::cross(m.w, rho)), k3::scale(c(2.0), k3::cross(m.w, ud_w))),
                    k3::mul(a, udd),
                ),
            );
            out.z = k3::add(k3::add(m.z, k3::cross(m.w, phid_w)), k3::mul(a, phidd));
        }
        self.eval.reaction_valid = false;
        self.eval.valid = true;
        Ok(())
    }

    /// The mount reaction at the last evaluation (evaluate first).
    fn evaluate_reaction(&mut self) {
        if self.eval.reaction_valid {
            return;
        }
        let n = self.q.len();
        let a = &self.rot;
        let mut torque_b = [T::zero(); 3];
        let mut force = [T::zero(); 3];
        for (i, flange) in self.body.flanges.iter().enumerate() {
            let u: Vec3<T> = [0, 1, 2].map(|r| shape_dot(&flange.shapes[r * n..(r + 1) * n], &self.q));
            // loads the host applies, moved to the mount point, in B
            let load = &self.loads[i];
            let f_b = k3::mul_t(a, load.f);
            force = k3::add(force, load.f);
            torque_b = k3::add(torque_b, k3::add(k3::cross(k3::add(flange.position.map(c), u), f_b), k3::mul_t(a, load.t)));
        }
        // Momentum balance of the whole body about the mount point, in B: the mount supplies what
        // the inertia needs beyond gravity and the flange loads (terms of second order in q, q'
        // dropped, except where they come for free).
        let (w, z, a_b) = (self.coupling.w, self.coupling.z, self.coupling.a);
        let b = &*self.body;
        let row3 = |mat: &[f64], x: &[T]| -> Vec3<T> { [0, 1, 2].map(|r| shape_dot(&mat[r * n..(r + 1) * n], x)) };
        let qdd = &self.eval.qdd;
        let ct_qdd = row3(&b.c_t, qdd);
        let ct_qd = row3(&b.c_t, &self.qd);
        let first_moment = k3::add(b.first_moment.map(c), row3(&b.c_t, &self.q));
        let mut inertial_force_b = k3::add(k3::scale(c(b.mass), a_b), ct_qdd);
        inertial_force_b = k3::add(inertial_force_b, k3::cross(z, first_moment));
        inertial_force_b = k3::add(inertial_force_b, k3::cross(w, k3::cross(w, first_moment)));
        inertial_force_b = k3::add(inertial_force_b, k3::scale(c(2.0), k3::cross(w, ct_qd)));
        self.eval.mount_force = k3::sub(k3::mul(a, inertial_force_b), force);

        // J(q) = J0 + J1(q), J1_ab = -(o_ab + o_ba) . q;  C_r(q) v = C_r v + [(G_a q) . v]_a
        let mut j: Mat3<T> = b.inertia.map(c);
        let mut j_rate = [T::zero(); 9];
        let mut cr_qdd = row3(&b.c_r, qdd);
        let mut cr_qd = row3(&b.c_r, &self.qd);
        if let Some(rot) = &b.rotation {
            for p_ in 0..3 {
                for q_ in 0..3 {
                    let (o_pq, o_qp) = (&rot.o_vec[(3 * p_ + q_) * n..][..n], &rot.o_vec[(3 * q_ + p_) * n..][..n]);
                    let mut s = T::zero();
                    let mut sd = T::zero();
                    for k in 0..n {
                        s += self.q[k] * (o_pq[k] + o_qp[k]);
                        sd += self.qd[k] * (o_pq[k] + o_qp[k]);
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
                    let gq = shape_dot(&g[r * n..(r + 1) * n], &self.q);
                    s_dd += gq * qdd[r];
                    s_d += gq * self.qd[r];
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
        self.eval.mount_torque = k3::mul(a, k3::sub(inertial_torque_b, torque_b));
        self.eval.reaction_valid = true;
    }

    /// Accelerations of a free-floating body: the frame's translational motion is the centre of
    /// mass's (mean axes: C_t = 0), its rotation and the modes couple through J(q) and C_r(q):
    ///   [J(q)  C_r(q)] [W']   [tau - W x h - J'(q) W                                   ]
    ///   [C_r^T   I   ] [q''] = [p - D q' - K q - 2 sum W_a G_a q' - sum W_a W_b (O_ab q + o_ab)]
    /// with h = J W + C_r q' (floating-frame invariants, exact in q to second order).
    fn free_accelerations(&mut self) -> Result<(), String> {
        let frame = self.frame.ok_or("not a free-floating body")?;
        let n = self.q.len();
        let nn = n * n;
        let b = self.body.clone();
        let rot_terms = b.rotation.as_ref().ok_or("a free-floating body needs its rotation invariants")?;
        let [q0, q1, q2, q3] = frame.quat;
        let norm = (q0 * q0 + q1 * q1 + q2 * q2 + q3 * q3).sqrt();
        if !(norm.value() > 0.5 && norm.value() < 2.0) {
            return Err(format!("the orientation quaternion has drifted to norm {}", norm.value()));
        }
        let quat = frame.quat.map(|x| x / norm);
        let a = k3::rotation_of_quaternion(quat);
        let w = frame.w_body;
        let total_force: Vec3<T> = self.loads.iter().fold([T::zero(); 3], |acc, l| k3::add(acc, l.f));
        let accel = k3::add(k3::scale(c(1.0 / b.mass), total_force), self.gravity());
        self.mount = MountMotion { r: frame.r, rot: a, v: frame.v, w: k3::mul(&a, w), a: accel, z: [T::zero(); 3] };
        self.rot = a;
        // modal load of the flange loads and the centrifugal o_ab terms (C_t = 0, c_a = 0 here)
        self.modal_load();
        let (alpha, beta) = (self.params.alpha, self.params.beta);
        let rhs_q = &mut self.eval.qdd;
        for j in 0..n {
            let w2 = b.omega[j] * b.omega[j];
            rhs_q[j] = self.load[j] - self.qd[j] * (alpha + beta * w2 + b.modal_damping[j]) - self.q[j] * w2;
        }
        for i in 0..3 {
            let g = &rot_terms.g[i * nn..(i + 1) * nn];
            if !w[i].is_zero() {
                for r in 0..n {
                    let s = shape_dot(&g[r * n..(r + 1) * n], &self.qd);
                    rhs_q[r] -= w[i] * 2.0 * s;
                }
            }
            for k in 0..3 {
                let ww = w[i] * w[k];
                if !ww.is_zero() {
                    let o = &rot_terms.o_mat[(3 * i + k) * nn..(3 * i + k + 1) * nn];
                    for r in 0..n {
                        let s = shape_dot(&o[r * n..(r + 1) * n], &self.q);
                        rhs_q[r] -= ww * s;
                    }
                }
            }
        }
        // C_r(q), J(q), J'(q)
        for i in 0..3 {
            let g = &rot_terms.g[i * nn..(i + 1) * nn];
            for col in 0..n {
                // (G_a q)_c
                let s = shape_dot(&g[col * n..(col + 1) * n], &self.q);
                self.cr_q[i * n + col] = s + c(b.c_r[i * n + col]);
            }
        }
        let mut j: Mat3<T> = b.inertia.map(c);
        let mut j_rate = [T::zero(); 9];
        for p in 0..3 {
            for q_ in 0..3 {
                let (o_pq, o_qp) = (&rot_terms.o_vec[(3 * p + q_) * n..][..n], &rot_terms.o_vec[(3 * q_ + p) * n..][..n]);
                let o_mat = &rot_terms.o_mat[(3 * p + q_) * nn..(3 * p + q_ + 1) * nn];
                let (mut lin, mut lin_rate, mut quad, mut quad_rate) = (T::zero(), T::zero(), T::zero(), T::zero());
                for r in 0..n {
                    lin += self.q[r] * (o_pq[r] + o_qp[r]);
                    lin_rate += self.qd[r] * (o_pq[r] + o_qp[r]);
                    let oq = shape_dot(&o_mat[r * n..(r + 1) * n], &self.q);
                    let oqd = shape_dot(&o_mat[r * n..(r + 1) * n], &self.qd);
                    quad += self.q[r] * oq;
                    quad_rate += self.qd[r] * oq + self.q[r] * oqd;
                }
                j[3 * p + q_] -= lin + quad;
                j_rate[3 * p + q_] = -(lin_rate + quad_rate);
            }
        }
        let cr_qd: Vec3<T> = [0, 1, 2].map(|i| dot(&self.cr_q[i * n..(i + 1) * n], &self.qd));
        let h = k3::add(k3::mul(&j, w), cr_qd);
        // torque of the flange loads about the centre of mass, body frame
        let mut torque = [T::zero(); 3];
        for (flange, load) in b.flanges.iter().zip(&self.loads) {
            let u: Vec3<T> = [0, 1, 2].map(|r| shape_dot(&flange.shapes[r * n..(r + 1) * n], &self.q));
            let f_b = k3::mul_t(&a, load.f);
            torque = k3::add(torque, k3::add(k3::cross(k3::add(flange.position.map(c), u), f_b), k3::mul_t(&a, load.t)));
        }
        let rhs_w = k3::sub(k3::sub(torque, k3::cross(w, h)), k3::mul(&j_rate, w));
        // Schur complement: (J - C_r C_r^T) W' = rhs_w - C_r rhs_q
        let mut s = j;
        let mut rhs = rhs_w;
        for p in 0..3 {
            let cp = &self.cr_q[p * n..(p + 1) * n];
            rhs[p] -= dot(cp, &self.eval.qdd);
            for q_ in 0..3 {
                let cq = &self.cr_q[q_ * n..(q_ + 1) * n];
                s[3 * p + q_] -= dot(cp, cq);
            }
        }
        let mut w_dot = rhs;
        solve_dense(&mut s, &mut w_dot, 3).map_err(|_| "the body's inertia matrix became singular".to_string())?;
        for r in 0..n {
            let f = self.cr_q[r] * w_dot[0] + self.cr_q[n + r] * w_dot[1] + self.cr_q[2 * n + r] * w_dot[2];
            self.eval.qdd[r] -= f;
        }
        self.mount.z = k3::mul(&a, w_dot);
        // d/dt quat = 1/2 quat (x) (0, W) of the state's own quaternion: keeps its norm, so the
        // frame turns at exactly W whatever the norm has drifted to
        let [q0, q1, q2, q3] = frame.quat;
        let half = [w[0] * 0.5, w[1] * 0.5, w[2] * 0.5];
        let quat_rate = [
            -(q1 * half[0]) - q2 * half[1] - q3 * half[2],
            q0 * half[0] + q2 * half[2] - q3 * half[1],
            q0 * half[1] + q3 * half[0] - q1 * half[2],
            q0 * half[2] + q1 * half[1] - q2 * half[0],
        ];
        self.frame_rate = FrameState { r: frame.v, quat: quat_rate, v: accel, w_body: w_dot };
        Ok(())
    }

    /// Energy and momenta of a free-floating body (gravity's potential included).
    pub fn invariants(&mut self) -> Result<Invariants<T>, String> {
        self.evaluate()?;
        let frame = self.frame.ok_or("energy and momenta are outputs of free-floating bodies")?;
        let n = self.q.len();
        let b = &self.body;
        let rot_terms = b.rotation.as_ref().ok_or("missing rotation invariants")?;
        let nn = n * n;
        let mut j: Mat3<T> = b.inertia.map(c);
        for p in 0..3 {
            for q_ in 0..3 {
                let (o_pq, o_qp) = (&rot_terms.o_vec[(3 * p + q_) * n..][..n], &rot_terms.o_vec[(3 * q_ + p) * n..][..n]);
                let o_mat = &rot_terms.o_mat[(3 * p + q_) * nn..(3 * p + q_ + 1) * nn];
                let mut v = T::zero();
                for r in 0..n {
                    v += self.q[r] * (o_pq[r] + o_qp[r]);
                    v += self.q[r] * shape_dot(&o_mat[r * n..(r + 1) * n], &self.q);
                }
                j[3 * p + q_] -= v;
            }
        }
        let w = frame.w_body;
        let cr_qd: Vec3<T> = [0, 1, 2].map(|i| dot(&self.cr_q[i * n..(i + 1) * n], &self.qd));
        let jw = k3::mul(&j, w);
        let h = k3::add(jw, cr_qd);
        let v2 = k3::dot(frame.v, frame.v);
        let mut energy = v2 * (0.5 * b.mass) + k3::dot(w, jw) * 0.5 + k3::dot(w, cr_qd);
        for r in 0..n {
            energy += self.qd[r] * 0.5 * self.qd[r] + self.q[r] * (0.5 * b.omega[r] * b.omega[r]) * self.q[r];
        }
        energy -= k3::dot(self.gravity(), frame.r) * b.mass;
        let momentum = k3::scale(c(b.mass), frame.v);
        let angular_momentum = k3::add(k3::cross(frame.r, momentum), k3::mul(&self.mount.rot, h));
        Ok(Invariants { energy, momentum, angular_momentum })
    }

    /// d/dt (q, q') into `dq`, `dqd`.
    pub fn derivatives(&mut self, dq: &mut [T], dqd: &mut [T]) -> Result<(), String> {
        self.evaluate()?;
        dq.copy_from_slice(&self.qd);
        dqd.copy_from_slice(&self.eval.qdd);
        Ok(())
    }

    pub fn qdd(&mut self) -> Result<&[T], String> {
        self.evaluate()?;
        Ok(&self.eval.qdd)
    }

    pub fn flange_motion(&mut self, flange: usize) -> Result<&FlangeMotion<T>, String> {
        self.evaluate()?;
        Ok(&self.eval.flanges[flange])
    }

    /// Force and torque (about the mount point) the mount applies to the body, world frame.
    pub fn mount_reaction(&mut self) -> Result<(Vec3<T>, Vec3<T>), String> {
        self.evaluate()?;
        self.evaluate_reaction();
        Ok((self.eval.mount_force, self.eval.mount_torque))
    }

    /// Put the body at rest in the static equilibrium of the present inputs: q' = 0 and
    /// (K + C_k) q = p, which for a spinning body includes centrifugal softening and stiffening.
    pub fn settle_static(&mut self) -> Result<(), String> {
        if self.frame.is_some() {
            return Err("a free-floating body has no static equilibrium to start in".into());
        }
        self.check_inputs()?;
        self.modal_load();
        self.prepare_coupling();
        let n = self.q.len();
        if self.coupling.active {
            let mut a = self.coupling.c_k.clone();
            for j in 0..n {
                a[j * n + j] += c(self.body.omega[j] * self.body.omega[j]);
            }
            let mut x = self.load.clone();
            solve_dense(&mut a, &mut x, n).map_err(|_| {
                "no static equilibrium: the body is unstable under the present loads (centrifugal softening beyond the elastic stiffness; enable geometric stiffening?)".to_string()
            })?;
            self.q.copy_from_slice(&x);
        } else {
            for j in 0..n {
                self.q[j] = self.load[j] / (self.body.omega[j] * self.body.omega[j]);
            }
        }
        self.qd.fill(T::zero());
        self.eval.valid = false;
        Ok(())
    }
}

/// C_d = 2 sum W_a G_a and C_k = sum Z_a G_a + sum W_a W_b O_ab + K_G for the given inputs.
/// `rot` is the mount orientation in use (the input projected onto the rotations), as in the load.
fn fill_coupling<T: Scalar>(
    body: &ReducedBody,
    rot: &Mat3<T>,
    mount: &MountMotion<T>,
    loads: &[FlangeLoad<T>],
    g: Vec3,
    c: &mut Coupling<T>,
) {
    let n = body.n_modes();
    let nn = n * n;
    let a = rot;
    c.w = k3::mul_t(a, mount.w);
    c.z = k3::mul_t(a, mount.z);
    c.a = k3::mul_t(a, k3::sub(mount.a, g.map(crate::scalar::c)));
    c.c_d.fill(T::zero());
    c.c_k.fill(T::zero());
    let mut active = false;
    let mut add = |target: &mut Vec<T>, scale: T, block: &[f64]| {
        if !scale.is_zero() {
            active = true;
            for (t, b) in target.iter_mut().zip(block) {
                *t += scale * *b;
            }
        }
    };
    if let Some(rot) = &body.rotation {
        for i in 0..3 {
            add(&mut c.c_d, c.w[i] * 2.0, &rot.g[i * nn..(i + 1) * nn]);
            add(&mut c.c_k, c.z[i], &rot.g[i * nn..(i + 1) * nn]);
            for j in 0..3 {
                add(&mut c.c_k, c.w[i] * c.w[j], &rot.o_mat[(3 * i + j) * nn..(3 * i + j + 1) * nn]);
            }
        }
    }
    if let Some(st) = &body.stiffening {
        if let Some(k) = &st.centrifugal {
            for i in 0..3 {
                for j in 0..3 {
                    add(&mut c.c_k, c.w[i] * c.w[j], &k[(3 * i + j) * nn..(3 * i + j + 1) * nn]);
                }
            }
        }
        if let Some(k) = &st.euler {
            for i in 0..3 {
                add(&mut c.c_k, c.z[i], &k[i * nn..(i + 1) * nn]);
            }
        }
        if let Some(k) = &st.translation {
            for i in 0..3 {
                add(&mut c.c_k, c.a[i], &k[i * nn..(i + 1) * nn]);
            }
        }
        for (f, k) in st.flanges.iter().enumerate() {
            if k.is_empty() {
                continue;
            }
            let load = &loads[f];
            let wrench = [k3::mul_t(a, load.f), k3::mul_t(a, load.t)];
            for i in 0..6 {
                add(&mut c.c_k, wrench[i / 3][i % 3], &k[i * nn..(i + 1) * nn]);
            }
        }
    }
    c.active = active;
    c.valid = true;
}

/// (C_d q' + C_k q)_i for the coupling `c` (the present one or the step end's).
fn coupling_force_of<T: Scalar>(c: &Coupling<T>, i: usize, q: &[T], qd: &[T]) -> T {
    let n = q.len();
    let (rd, rk) = (&c.c_d[i * n..(i + 1) * n], &c.c_k[i * n..(i + 1) * n]);
    let mut s = T::zero();
    for j in 0..n {
        s += rd[j] * qd[j] + rk[j] * q[j];
    }
    s
}

/// Largest h |dC| for which the coupling's difference dC from the exact transition's is
/// treated as a load (see `step`): the predictor-corrector then gains at most
/// (h |dC|)^4 / 8 = 1e-7 of energy in a step (and far less on average, as the drift grows from
/// zero after each renewal), and a renewal, one exponential, is needed only every few dozen
/// steps of a spin-up.
const REFERENCE_DRIFT: f64 = 3e-2;

/// |dC| = |C_d - R_d| + |(C_k - R_k) Omega^-1| (largest row sums): the norm of the difference in
/// the transition's own state [Omega q; q'], a rate in 1/s. A stiffness change of a mode at
/// omega shifts its frequency by dC_k / (2 omega), hence the division.
fn coupling_drift(c: &Coupling<f64>, reference: (&[f64], &[f64]), omega: &[f64]) -> f64 {
    let n = omega.len();
    let mut worst = 0.0f64;
    for i in 0..n {
        let r = i * n..(i + 1) * n;
        let (cd, ck, rd, rk) = (&c.c_d[r.clone()], &c.c_k[r.clone()], &reference.0[r.clone()], &reference.1[r]);
        let mut sum = 0.0;
        for j in 0..n {
            sum += (cd[j] - rd[j]).abs() + (ck[j] - rk[j]).abs() / omega[j];
        }
        worst = worst.max(sum);
    }
    worst
}

/// ((C_d - R_d) q' + (C_k - R_k) q)_i: the coupling's force beyond the reference transition's.
fn residual_coupling_force(c: &Coupling<f64>, reference: (&[f64], &[f64]), i: usize, q: &[f64], qd: &[f64]) -> f64 {
    let n = q.len();
    let r = i * n..(i + 1) * n;
    let (cd, ck, rd, rk) = (&c.c_d[r.clone()], &c.c_k[r.clone()], &reference.0[r.clone()], &reference.1[r]);
    let mut s = 0.0;
    for j in 0..n {
        s += (cd[j] - rd[j]) * qd[j] + (ck[j] - rk[j]) * q[j];
    }
    s
}

/// sum_j s_j x_j of a constant row and a state vector.
#[inline]
fn shape_dot<T: Scalar>(s: &[f64], x: &[T]) -> T {
    let mut sum = T::zero();
    for (s, x) in s.iter().zip(x) {
        sum += *x * *s;
    }
    sum
}

#[inline]
fn dot<T: Scalar>(a: &[T], b: &[T]) -> T {
    let mut sum = T::zero();
    for (a, b) in a.iter().zip(b) {
        sum += *a * *b;
    }
    sum
}

impl FlexibleBody {
    /// Advance by h with the inputs held (or ramped at their rates) over the step: exact
    /// propagation of the modal diagonal when nothing couples the modes, else of the whole
    /// coupled system (gyroscopic, centrifugal, stiffening terms) by its matrix exponential,
    /// which keeps an undamped spinning body's energy at any step (see `coupled_propagator`).
    pub fn step(&mut self, h: f64) -> Result<(), String> {
        if !(h > 0.0 && h.is_finite()) {
            return Err(format!("step size {h} must be positive and finite"));
        }
        if self.frame.is_some() {
            // free bodies hold their flange loads over the step; the inputs still end the step
            // at their interpolated values
            self.step_free(h)?;
            if self.rates.any {
                self.extrapolate_inputs(h);
            }
            return Ok(());
        }
        self.check_inputs()?;
        self.modal_load();
        let ramp = self.rates.any;
        if ramp {
            self.modal_load_rate();
        }
        self.prepare_coupling();
        // inputs that move over the step move the coupling too: its matrices at the step's end
        let mut work = std::mem::take(&mut self.coupled_work);
        if ramp {
            let mut end = self.mount;
            let r = &self.rates.mount;
            for i in 0..3 {
                end.w[i] += h * r.w[i];
                end.z[i] += h * r.z[i];
                end.a[i] += h * r.a[i];
            }
            for i in 0..9 {
                end.rot[i] += h * r.rot[i];
            }
            for ((e, l), rate) in work.loads_end.iter_mut().zip(&self.loads).zip(&self.rates.loads) {
                *e = FlangeLoad { f: k3::add(l.f, k3::scale(h, rate.f)), t: k3::add(l.t, k3::scale(h, rate.t)) };
            }
            let end_rot = k3::nearest_rotation(&end.rot);
            fill_coupling(&self.body, &end_rot, &end, &work.loads_end, self.params.g, &mut work.coupling_end);
        }
        // a coupling that starts at zero (spin-up from rest) still couples within the step
        if !self.coupling.active && !(ramp && work.coupling_end.active) {
            self.coupled_work = work;
            self.propagator.prepare(&self.body.omega, self.params.alpha, self.params.beta, &self.body.modal_damping, h);
            if ramp {
                self.propagator.advance_ramp(&self.body.omega, &self.load, &self.load_rate, &mut self.q, &mut self.qd);
                self.extrapolate_inputs(h);
            } else {
                self.propagator.advance(&self.body.omega, &self.load, &mut self.q, &mut self.qd);
            }
            self.eval.valid = false;
            return Ok(());
        }
        // The transition is exact for the coupling it was made for (the reference). A coupling
        // that drifted from it (spin-up, a tumbling mount, or only the round-off of a rotating
        // base.R) enters as the small difference dC = C - C_ref, by a predictor-corrector load on
        // top of the exact coupled transition; the reference is renewed (one matrix exponential,
        // at the step's midpoint coupling) when h |dC| exceeds REFERENCE_DRIFT. A steady spin
        // runs on one exponential.
        let prepared = self.coupled.is_prepared(h, self.params.alpha, self.params.beta);
        // a steady spin meets its own transition again: compared first, cheaper than the drift
        let held_exactly = !ramp && prepared && self.coupled.reference() == (&self.coupling.c_d[..], &self.coupling.c_k[..]);
        let drift_ok = |c: &Coupling<f64>| h * coupling_drift(c, self.coupled.reference(), &self.body.omega) <= REFERENCE_DRIFT;
        let current = held_exactly || prepared && drift_ok(&self.coupling) && (!ramp || drift_ok(&work.coupling_end));
        if !current {
            let (c_d, c_k): (&[f64], &[f64]) = if ramp {
                for (m, (a, b)) in work.c_d_mid.iter_mut().zip(self.coupling.c_d.iter().zip(&work.coupling_end.c_d)) {
                    *m = 0.5 * (a + b);
                }
                for (m, (a, b)) in work.c_k_mid.iter_mut().zip(self.coupling.c_k.iter().zip(&work.coupling_end.c_k)) {
                    *m = 0.5 * (a + b);
                }
                (&work.c_d_mid, &work.c_k_mid)
            } else {
                (&self.coupling.c_d, &self.coupling.c_k)
            };
            let was_definite = self.coupled.definite();
            let prepared = self.coupled.prepare(&self.body.omega, self.params.alpha, self.params.beta, &self.body.modal_damping, c_d, c_k, h);
            if prepared == Prepared::Computed && was_definite && !self.coupled.definite() {
                self.warning = Some(UNSTABLE_STIFFNESS);
            }
        }
        let end = if ramp { &work.coupling_end } else { &self.coupling };
        // a transition made for this step (held or midpoint coupling) needs no correction
        let exact = held_exactly || !current;
        let rate: &[f64] = if ramp { &self.load_rate } else { &work.zeros };
        if exact {
            self.coupled.advance(&self.body.omega, &self.load, rate, &mut self.q, &mut self.qd);
        } else {
            // Heun: the residual coupling force held at its start value, then ramped to its
            // value at the predicted end
            let n = self.q.len();
            work.q0.copy_from_slice(&self.q);
            work.qd0.copy_from_slice(&self.qd);
            for i in 0..n {
                work.f0[i] = self.load[i] - residual_coupling_force(&self.coupling, self.coupled.reference(), i, &work.q0, &work.qd0);
            }
            self.coupled.advance(&self.body.omega, &work.f0, rate, &mut self.q, &mut self.qd);
            for i in 0..n {
                let f_end = self.load[i] + h * rate[i] - residual_coupling_force(end, self.coupled.reference(), i, &self.q, &self.qd);
                work.f1[i] = (f_end - work.f0[i]) / h;
            }
            self.q.copy_from_slice(&work.q0);
            self.qd.copy_from_slice(&work.qd0);
            self.coupled.advance(&self.body.omega, &work.f0, &work.f1, &mut self.q, &mut self.qd);
        }
        self.coupled_work = work;
        if ramp {
            self.extrapolate_inputs(h);
        }
        self.eval.valid = false;
        if !(self.q.iter().chain(&self.qd).all(|v| v.is_finite())) {
            return Err(if self.coupled.definite() {
                "the modal state became non-finite in this step".into()
            } else {
                format!("the deformation grew without bound: {UNSTABLE_STIFFNESS}")
            });
        }
        Ok(())
    }

    /// A warning about the last step, once: the FMI layer logs it.
    pub fn take_warning(&mut self) -> Option<&'static str> {
        self.warning.take()
    }

    /// dp/dt of the modal load for the input rates: every body-frame input x_B = A^T x changes
    /// as A^T x' + A'^T x, with A' = A skew(A^T R') the rotational part of the orientation's rate
    /// (the derivative of the projection onto the rotations); the centrifugal part as
    /// d(w_i w_k)/dt.
    fn modal_load_rate(&mut self) {
        let a = &self.rot;
        let r = &self.rates;
        let n = self.q.len();
        let m = {
            let at_rdot: Mat3 = std::array::from_fn(|ij| {
                let (i, j) = (ij / 3, ij % 3);
                a[i] * r.mount.rot[j] + a[3 + i] * r.mount.rot[3 + j] + a[6 + i] * r.mount.rot[6 + j]
            });
            let skew: Mat3 = std::array::from_fn(|ij| {
                let (i, j) = (ij / 3, ij % 3);
                0.5 * (at_rdot[3 * i + j] - at_rdot[3 * j + i])
            });
            k3::mat_mul(a, &skew)
        };
        let body_rate = |x: Vec3, rate: Vec3| k3::add(k3::mul_t(a, rate), k3::mul_t(&m, x));
        let a_b = body_rate(k3::sub(self.mount.a, self.params.g), r.mount.a);
        for j in 0..n {
            self.load_rate[j] = -(self.body.c_t[j] * a_b[0] + self.body.c_t[n + j] * a_b[1] + self.body.c_t[2 * n + j] * a_b[2]);
        }
        if let Some(rot) = &self.body.rotation {
            let w = k3::mul_t(a, self.mount.w);
            let dw = body_rate(self.mount.w, r.mount.w);
            let dz = body_rate(self.mount.z, r.mount.z);
            for i in 0..3 {
                if dz[i] != 0.0 {
                    let c_a = &self.body.c_r[i * n..(i + 1) * n];
                    for j in 0..n {
                        self.load_rate[j] -= dz[i] * c_a[j];
                    }
                }
                for k in 0..3 {
                    let dww = dw[i] * w[k] + w[i] * dw[k];
                    if dww != 0.0 {
                        let o = &rot.o_vec[(3 * i + k) * n..(3 * i + k + 1) * n];
                        for j in 0..n {
                            self.load_rate[j] -= dww * o[j];
                        }
                    }
                }
            }
        }
        for ((flange, rate), load) in self.body.flanges.iter().zip(&r.loads).zip(&self.loads) {
            let f_b = body_rate(load.f, rate.f);
            let t_b = body_rate(load.t, rate.t);
            let wrench = [f_b[0], f_b[1], f_b[2], t_b[0], t_b[1], t_b[2]];
            for (row, w) in wrench.iter().enumerate() {
                if *w != 0.0 {
                    let shape = &flange.shapes[row * n..(row + 1) * n];
                    for j in 0..n {
                        self.load_rate[j] += shape[j] * w;
                    }
                }
            }
        }
    }

    /// After a step with input rates the inputs hold their interpolated end values (what the
    /// host's interpolation says they are at t + h); the rates are used up.
    fn extrapolate_inputs(&mut self, h: f64) {
        let r = &mut self.rates;
        let m = &mut self.mount;
        for i in 0..3 {
            m.r[i] += h * r.mount.r[i];
            m.v[i] += h * r.mount.v[i];
            m.w[i] += h * r.mount.w[i];
            m.a[i] += h * r.mount.a[i];
            m.z[i] += h * r.mount.z[i];
        }
        for i in 0..9 {
            m.rot[i] += h * r.mount.rot[i];
        }
        for (load, rate) in self.loads.iter_mut().zip(&r.loads) {
            for i in 0..3 {
                load.f[i] += h * rate.f[i];
                load.t[i] += h * rate.t[i];
            }
        }
        r.mount = MountMotion { rot: [0.0; 9], ..MountMotion::default() };
        for rate in r.loads.iter_mut() {
            *rate = FlangeLoad::default();
        }
        r.any = false;
        self.coupling.valid = false;
        self.eval.valid = false;
    }
}

impl FlexibleBody {
    /// A free-floating body over one step, by substeps short against its rotation
    /// (|W| h_sub <= 0.005) of a second-order (Heun) splitting: the modes propagate exactly under
    /// the coupling load (trapezoidal in time), the rigid motion by the averaged rates, the
    /// attitude by the exact rotation of the mean angular velocity.
    fn step_free(&mut self, h: f64) -> Result<(), String> {
        let spin = self.frame.map_or(0.0, |f| k3::dot(f.w_body, f.w_body).sqrt());
        let substeps = ((h * spin / 0.005).ceil() as usize).clamp(1, 1_000_000);
        let hs = h / substeps as f64;
        self.propagator.prepare(&self.body.omega, self.params.alpha, self.params.beta, &self.body.modal_damping, hs);
        // the preallocated workspace, taken out for the substeps (leaves an empty Vec: no allocation)
        let mut work = std::mem::take(&mut self.free_work);
        let result = self.free_substeps(&mut work, substeps, hs);
        self.free_work = work;
        self.eval.valid = false;
        result
    }

    fn free_substeps(&mut self, w: &mut FreeWork, substeps: usize, hs: f64) -> Result<(), String> {
        let n = self.q.len();
        for _ in 0..substeps {
            let start = self.frame.ok_or("not a free-floating body")?;
            w.q0.copy_from_slice(&self.q);
            w.qd0.copy_from_slice(&self.qd);
            // rates at the start, then at the predicted end
            self.eval.valid = false;
            self.evaluate()?;
            let rate0 = self.frame_rate;
            self.coupling_load(&mut w.load0);
            self.advance_free(&start, &rate0, &rate0, &w.load0, hs)?;
            self.eval.valid = false;
            self.evaluate()?;
            let rate1 = self.frame_rate;
            self.coupling_load(&mut w.load1);
            for j in 0..n {
                w.load1[j] = 0.5 * (w.load0[j] + w.load1[j]);
            }
            self.q.copy_from_slice(&w.q0);
            self.qd.copy_from_slice(&w.qd0);
            self.advance_free(&start, &rate0, &rate1, &w.load1, hs)?;
        }
        Ok(())
    }

    /// The part of q'' beyond the modal diagonal at the last evaluation.
    fn coupling_load(&self, out: &mut [f64]) {
        let (alpha, beta) = (self.params.alpha, self.params.beta);
        for j in 0..self.q.len() {
            let w2 = self.body.omega[j] * self.body.omega[j];
            out[j] = self.eval.qdd[j] + (alpha + beta * w2 + self.body.modal_damping[j]) * self.qd[j] + w2 * self.q[j];
        }
    }

    /// From the substep's start frame: rigid motion by the mean of two rate sets, modes exactly
    /// under `load` (q, q' must hold the start values).
    fn advance_free(&mut self, start: &FrameState, a: &FrameState, b: &FrameState, load: &[f64], hs: f64) -> Result<(), String> {
        self.propagator.advance(&self.body.omega, load, &mut self.q, &mut self.qd);
        let w_dot = k3::scale(0.5, k3::add(a.w_body, b.w_body));
        let accel = k3::scale(0.5, k3::add(a.v, b.v));
        let f = self.frame.as_mut().ok_or("not a free-floating body")?;
        let w_mid = k3::add(start.w_body, k3::scale(0.5 * hs, w_dot));
        f.w_body = k3::add(start.w_body, k3::scale(hs, w_dot));
        f.v = k3::add(start.v, k3::scale(hs, accel));
        f.r = k3::add(start.r, k3::scale(0.5 * hs, k3::add(start.v, f.v)));
        f.quat = k3::quaternion_multiply(start.quat, k3::quaternion_of(&k3::rotation_of(k3::scale(hs, w_mid))));
        Ok(())
    }
}

/// Solve A x = b in place (A row-major n x n, destroyed) by Gaussian elimination with partial
/// pivoting; Err on a singular matrix. Used at initialisation only.
fn solve_dense<T: Scalar>(a: &mut [T], b: &mut [T], n: usize) -> Result<(), ()> {
    let scale = a.iter().fold(0.0f64, |m, v| m.max(v.value().abs()));
    for col in 0..n {
        let piv = (col..n).max_by(|&i, &j| a[i * n + col].value().abs().total_cmp(&a[j * n + col].value().abs())).ok_or(())?;
        if !(a[piv * n + col].value().abs() > 1e-14 * scale) {
            return Err(());
        }
        if piv != col {
            for k in 0..n {
                a.swap(piv * n + k, col * n + k);
            }
            b.swap(piv, col);
        }
        let d = a[col * n + col];
        for i in col + 1..n {
            let f = a[i * n + col] / d;
            if !f.is_zero() {
                for k in col..n {
                    let v = f * a[col * n + k];
                    a[i * n + k] -= v;
                }
                let v = f * b[col];
                b[i] -= v;
            }
        }
    }
    for col in (0..n).rev() {
        let mut s = T::zero();
        for k in col + 1..n {
            s += a[col * n + k] * b[k];
        }
        b[col] = (b[col] - s) / a[col * n + col];
    }
    Ok(())
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
        b.mount_mut().rot = [1.1, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0];
        let e = b.step(0.1).unwrap_err();
        assert!(e.contains("base.R"), "{e}");
    }
}
