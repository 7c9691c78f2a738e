//! The reduced flexible body's equations, free of anything FMI: inputs (mount motion, flange
//! loads, gravity), modal state q, q', and what the flanges see.
//!
//! Equations (body frame B, modal mass I, stiffness diag(w^2), Rayleigh damping; docs/ARCHITECTURE.md):
//!   q'' + (D + 2 sum_a W_a G_a) q' + (K + sum_a Z_a G_a + sum_ab W_a W_b O_ab + K_G) q
//!       = -C_t^T a_B - sum_a Z_a c_a - sum_ab W_a W_b o_ab + sum_k Phi_k^T [A^T f_k; A^T t_k],
//! with W = A^T w, Z = A^T z, a_B = A^T (a - g), and K_G the geometric stiffness of the present
//! loads (linear in them). The coupling terms (everything off the modal diagonal) are gathered in
//! two r x r matrices whenever the inputs change.
//!
//! Files, one job each: this one holds the types, construction, saved state, accessors and the
//! evaluation shared by every body (dispatch and flange kinematics); `mounted` the equations of
//! a body on a prescribed mount (input check, modal load, coupling terms); `reaction` the mount
//! reaction; `free_floating` the free body's accelerations and invariants; `cosim_step`
//! Co-Simulation stepping (input rates, exact and predictor-corrector steps, the free body's
//! substeps); `step_workspace` the step's scratch, lent down its functions; `input_jump`
//! Co-Simulation's quasi-static modes across load changes; `quasi_static` Model Exchange's solve
//! of the modes above the cutoff; `statics` the static start; `dense` the dense kernels (dot
//! products and the small in-place solver); `error` why the equations fail, by failure class.

mod cosim_step;
mod coupling_bound;
mod coupling_terms;
pub use cosim_step::SUBSTEP_ANGLE;
pub(crate) mod dense;
mod error;
pub use error::{BodyError, OutOfRange, StateMismatch, StepError};
mod free_floating;
mod input_jump;
mod mounted;
mod quasi_static;
mod reaction;
mod statics;
mod step_workspace;
mod stress;

use crate::coupled_propagator::CoupledPropagator;
use crate::kinematics::{self as k3, Mat3, Vec3};
use crate::propagator::ModalPropagator;
use crate::reduced::ReducedBody;
use crate::scalar::{Dual, Scalar, c};
use coupling_terms::CouplingTerms;
pub(crate) use coupling_terms::term_count;
use input_jump::SteppedInputs;
use quasi_static::QuasiStaticWork;
use std::sync::Arc;
use step_workspace::StepWorkspace;

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
        MountMotion {
            r: self.r.map(&f),
            rot: self.rot.map(&f),
            v: self.v.map(&f),
            w: self.w.map(&f),
            a: self.a.map(&f),
            z: self.z.map(&f),
        }
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
    /// Counts the evaluations: results computed on demand remember the one they belong to.
    generation: u64,
    /// Stresses at the recovery points (xx .. zx, von Mises), each with the generation it was
    /// computed at (0: never): a host reads a point's seven outputs one by one.
    stresses: Vec<([T; 7], u64)>,
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
    /// The loads the last Co-Simulation step ended with: the next step moves the algebraic
    /// modes by the change of their equilibrium from these (None before the first).
    pub stepped_inputs: Option<SteppedState>,
}

/// The loads a step ended with: the mount's accelerations, flange loads and parameters.
#[derive(Debug, Clone, PartialEq)]
pub struct SteppedState {
    pub a: Vec3,
    pub z: Vec3,
    pub loads: Vec<FlangeLoad>,
    pub params: Parameters,
}

/// Step size, Rayleigh coefficients and coupling matrices of a coupled transition.
#[derive(Debug, Clone, PartialEq)]
pub struct CouplingReference {
    pub h: f64,
    pub alpha: f64,
    pub beta: f64,
    pub c_d: Vec<f64>,
    pub c_k: Vec<f64>,
    /// The coefficients the reference coupling combines its matrices with (the drift test's
    /// reference); None in states written before they were kept: the next step renews it.
    pub coef: Option<Vec<f64>>,
}

/// Terms that couple the modes, for the present inputs: q'' = ... - C_d q' - C_k q.
#[derive(Debug, Clone, Default)]
struct Coupling<T> {
    /// The coefficients (and `active`) are those of the present inputs.
    valid: bool,
    active: bool,
    /// The rows of C_d, C_k from this one on are those of the coefficients (None: no row). They
    /// are filled only where needed: the rows of Model Exchange's algebraic modes, all of them for
    /// the static start.
    rows_from: Option<usize>,
    c_d: Vec<T>,
    c_k: Vec<T>,
    /// (C_d q' + C_k q) of an evaluation (n).
    force: Vec<T>,
    /// Body-frame angular velocity, angular acceleration and a_B of the present inputs.
    w: Vec3<T>,
    z: Vec3<T>,
    a: Vec3<T>,
    /// The coefficients c_d and c_k combine the body's matrices with (see `coupling_terms`).
    coef: Vec<T>,
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
    propagator: ModalPropagator,
    /// Exact transition of the coupled modes (mounted bodies with rotation or stiffening terms).
    coupled: CoupledPropagator,
    /// The coefficients of the coupling `coupled` was made for, where known (every renewal sets
    /// them), and the matrices they multiply with their norms (`coupling_terms`), made once per
    /// reduced body and shared by its copies.
    reference_coef: Vec<f64>,
    reference_coef_known: bool,
    coupling_terms: Arc<CouplingTerms>,
    /// A warning of the last step for the host's log.
    warning: Option<&'static str>,
    /// First derivatives of the inputs for the next step (fmi2SetRealInputDerivatives), and
    /// the modal load's rate they give.
    rates: InputRates,
    load_rate: Vec<f64>,
    /// Modes 0..n_dynamic are below the dynamic cutoff; with `quasi_static` (Model Exchange) the
    /// others are solved algebraically at every evaluation instead of integrated.
    n_dynamic: usize,
    /// Quasi-static modes nd..nd + n_relaxing settle through their damping (first-order states
    /// in Model Exchange); the rest are algebraic.
    n_relaxing: usize,
    quasi_static: bool,
    /// Set while the quasi-static modes are put in equilibrium (relaxing ones included).
    settling: bool,
    qs_work: QuasiStaticWork<T>,
    /// Co-Simulation: the inputs of the last step, to move the algebraic modes when they change.
    stepped: SteppedInputs,
    /// Co-Simulation: the host's view of the mount's orientation and spin where the last step
    /// moved them by their kinematics (see `cosim_step`), and which of them the host drives.
    host_mount: HostMount,
    /// Co-Simulation: the step's scratch (its start, to undo it; the coupled propagator's
    /// workspace; ...), allocated here once and lent to the step's functions. Not state.
    step_work: StepWorkspace,
}

/// Largest magnitude of a Real the host sets (and of a rate it gives, and of a state a step may
/// end in): beyond any load, speed, acceleration or damping in SI units by scores of orders of
/// magnitude, and small enough that products of three such values (a centrifugal load w^2 r)
/// stay finite. A value past it is a unit or host error that would otherwise surface as NaN
/// outputs many calls later.
pub const REAL_LIMIT: f64 = 1e100;

/// A Co-Simulation host that sets the mount's orientation (or spin) between steps drives it:
/// after a step the FMU reports the state the step produced in the pose the step turned the
/// mount to, which the host's next value replaces (what co-simulation masters read before they
/// set the next inputs). A host that holds them (set once, before initialisation ends) keeps its
/// own values, as Model Exchange does. `rot`, `w`: the host's values while `mount` holds the
/// step's end pose, until the host sets an entry (the others stay the host's) or the next step
/// starts from them.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(crate) struct HostMount {
    pub rot: Option<Mat3>,
    pub w: Option<Vec3>,
    pub rot_driven: bool,
    pub w_driven: bool,
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

impl FlexibleBody {
    pub fn new(body: Arc<ReducedBody>) -> Self {
        let terms = Arc::new(CouplingTerms::of(&body));
        Self::with_coupling_terms(body, terms)
    }

    /// A body at rest whose coupling terms are known (a copy of a body of the same reduced
    /// body shares them instead of computing them again).
    fn with_coupling_terms(body: Arc<ReducedBody>, coupling_terms: Arc<CouplingTerms>) -> Self {
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
                generation: 0,
                stresses: vec![([0.0; 7], 0); body.stress_points.len()],
            },
            coupling: Coupling {
                c_d: vec![0.0; n * n],
                c_k: vec![0.0; n * n],
                force: vec![0.0; n],
                coef: vec![0.0; term_count(nf)],
                ..Coupling::default()
            },
            rot: k3::IDENTITY,
            frame: body.free_floating.then(FrameState::default),
            initial_frame: InitialFrame::default(),
            frame_rate: FrameState::default(),
            cr_q: vec![0.0; 3 * n],
            propagator: ModalPropagator::with_modes(n),
            coupled: if body.modes_couple() { CoupledPropagator::with_modes(n) } else { CoupledPropagator::default() },
            reference_coef: vec![0.0; term_count(nf)],
            reference_coef_known: false,
            coupling_terms,
            warning: None,
            rates: InputRates {
                mount: MountMotion { rot: [0.0; 9], ..MountMotion::default() },
                loads: vec![FlangeLoad::default(); nf],
                any: false,
            },
            load_rate: vec![0.0; n],
            n_dynamic: body.n_dynamic(),
            n_relaxing: body.n_relaxing(),
            quasi_static: false,
            settling: false,
            qs_work: QuasiStaticWork::new(n, body.n_dynamic(), body.free_floating, term_count(nf)),
            stepped: SteppedInputs::new(nf),
            host_mount: HostMount::default(),
            step_work: StepWorkspace::for_body(&body),
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
                generation: 0,
                stresses: vec![([Dual::default(); 7], 0); self.eval.stresses.len()],
            },
            coupling: Coupling {
                c_d: zeros(n * n),
                c_k: zeros(n * n),
                force: zeros(n),
                coef: zeros(term_count(self.loads.len())),
                ..Coupling::default()
            },
            rot: k3::IDENTITY.map(Dual::from),
            frame: self.frame.map(|f| f.map(Dual::from)),
            initial_frame: self.initial_frame,
            frame_rate: FrameState::default(),
            cr_q: zeros(3 * n),
            propagator: ModalPropagator::with_modes(0),
            coupled: CoupledPropagator::default(),
            reference_coef: Vec::new(),
            reference_coef_known: false,
            coupling_terms: Arc::clone(&self.coupling_terms),
            warning: None,
            rates: self.rates.clone(),
            load_rate: Vec::new(),
            n_dynamic: self.n_dynamic,
            n_relaxing: self.n_relaxing,
            quasi_static: self.quasi_static,
            settling: false,
            qs_work: QuasiStaticWork::new(n, self.n_dynamic, self.frame.is_some(), term_count(self.loads.len())),
            // stepping is f64 only
            stepped: SteppedInputs::default(),
            host_mount: HostMount::default(),
            step_work: StepWorkspace::default(),
        }
    }

    pub fn state(&self) -> BodyState {
        BodyState {
            // the host's mount: a restored body starts its next step where this one would
            mount: MountMotion {
                rot: self.host_mount.rot.unwrap_or(self.mount.rot),
                w: self.host_mount.w.unwrap_or(self.mount.w),
                ..self.mount
            },
            loads: self.loads.clone(),
            params: self.params,
            q: self.q.clone(),
            qd: self.qd.clone(),
            frame: self.frame,
            initial_frame: self.initial_frame,
            rates: self.rates.clone(),
            coupling_reference: self.coupled.key().map(|(h, alpha, beta)| {
                let (c_d, c_k) = self.coupled.reference();
                let coef = self.reference_coef_known.then(|| self.reference_coef.clone());
                CouplingReference { h, alpha, beta, c_d: c_d.to_vec(), c_k: c_k.to_vec(), coef }
            }),
            stepped_inputs: self.stepped_inputs(),
        }
    }

    /// A new body of the same reduced body in `state`, its caches empty; Err if the state's
    /// sizes do not fit this body.
    pub fn with_state(&self, state: BodyState) -> Result<Self, BodyError> {
        let (n, nf) = (self.n_modes(), self.loads.len());
        if state.q.len() != n || state.qd.len() != n {
            return Err(StateMismatch::Modes { q: state.q.len(), qd: state.qd.len(), n }.into());
        }
        if state.loads.len() != nf || state.rates.loads.len() != nf {
            return Err(StateMismatch::Flanges { found: state.loads.len(), n: nf }.into());
        }
        if state.frame.is_some() != self.frame.is_some() {
            return Err(StateMismatch::Kind { free: state.frame.is_some(), body_free: self.frame.is_some() }.into());
        }
        let mut b = FlexibleBody::with_coupling_terms(Arc::clone(&self.body), Arc::clone(&self.coupling_terms));
        b.quasi_static = self.quasi_static;
        b.mount = state.mount;
        b.loads = state.loads;
        b.params = state.params;
        b.q = state.q;
        b.qd = state.qd;
        b.frame = state.frame;
        b.initial_frame = state.initial_frame;
        b.rates = state.rates;
        if let Some(st) = &state.stepped_inputs {
            b.set_stepped_inputs(st)?;
        }
        if let Some(r) = state.coupling_reference {
            let nn = n * n;
            let valid = r.c_d.len() == nn && r.c_k.len() == nn && r.h > 0.0 && r.h.is_finite();
            if !valid || !b.coupled.has_storage() {
                return Err(StateMismatch::CouplingReference { c_d: r.c_d.len(), c_k: r.c_k.len(), n }.into());
            }
            if !(r.c_d.iter().chain(&r.c_k).chain([&r.alpha, &r.beta]).all(|v| v.is_finite())) {
                return Err(StateMismatch::CouplingReferenceNotFinite.into());
            }
            let body = Arc::clone(&b.body);
            let ws = &mut b.step_work.coupled.propagator;
            b.coupled.prepare(&body.omega, r.alpha, r.beta, &body.modal_damping, &r.c_d, &r.c_k, r.h, ws)?;
            // coefficients of another length or not finite: unknown, and the next step renews
            if let Some(coef) = r.coef.filter(|c| c.len() == b.reference_coef.len() && c.iter().all(|v| v.is_finite()))
            {
                b.reference_coef.copy_from_slice(&coef);
                b.reference_coef_known = true;
            }
        }
        Ok(b)
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

    pub fn mount_mut(&mut self) -> &mut MountMotion<T> {
        self.eval.valid = false;
        self.coupling.valid = false;
        &mut self.mount
    }
    /// Entry k (row-major) of the mount's orientation, as the host sets it: the mount returns to
    /// the host's view of its orientation, this entry changed.
    pub fn set_mount_rotation(&mut self, k: usize, value: T) {
        if let Some(host) = self.host_mount.rot.take() {
            self.mount.rot = host.map(c);
        }
        self.host_mount.rot_driven = true;
        self.mount_mut().rot[k] = value;
    }
    /// Component i of the mount's angular velocity, as the host sets it.
    pub fn set_mount_spin(&mut self, i: usize, value: T) {
        if let Some(host) = self.host_mount.w.take() {
            self.mount.w = host.map(c);
        }
        self.host_mount.w_driven = true;
        self.mount_mut().w[i] = value;
    }
    /// Initialisation is over: what the host set so far are start values, not a drive.
    pub fn start_stepping(&mut self) {
        self.host_mount.rot_driven = false;
        self.host_mount.w_driven = false;
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
    /// Set the leading modes' q, q' (all of them, or Model Exchange's dynamic ones).
    pub fn set_state(&mut self, q: &[T], qd: &[T]) {
        self.q[..q.len()].copy_from_slice(q);
        self.qd[..qd.len()].copy_from_slice(qd);
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

    fn gravity(&self) -> Vec3<T> {
        self.params.g.map(c)
    }

    /// Everything that follows from the state and inputs (q'', flange motion), once per change.
    fn evaluate(&mut self) -> Result<(), BodyError> {
        if self.eval.valid {
            return Ok(());
        }
        if self.frame.is_some() {
            self.free_accelerations()?;
        } else {
            self.mounted_accelerations()?;
        }
        self.flange_kinematics();
        self.eval.reaction_valid = false;
        self.eval.generation += 1;
        self.eval.valid = true;
        Ok(())
    }

    /// Position, orientation and their rates of every force flange, from q, q', q'' and the
    /// mount (or the free body's frame) of the evaluation.
    fn flange_kinematics(&mut self) {
        let n = self.q.len();
        let m = &self.mount;
        let a = &self.rot;
        for (i, flange) in self.body.flanges.iter().enumerate() {
            // the flange's six shape rows (translation, rotation) times q, q' and q''
            let rows = |x: &[T]| {
                let mut out = [T::zero(); 6];
                T::add_scaled_mat_vec(&flange.shapes[..6 * n], x, T::from(1.0), &mut out);
                out
            };
            let (x, xd, xdd) = (rows(&self.q), rows(&self.qd), rows(&self.eval.qdd));
            let (u, phi) = ([x[0], x[1], x[2]], [x[3], x[4], x[5]]);
            let (ud, phid) = ([xd[0], xd[1], xd[2]], [xd[3], xd[4], xd[5]]);
            let (udd, phidd) = ([xdd[0], xdd[1], xdd[2]], [xdd[3], xdd[4], xdd[5]]);
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
    }

    /// d/dt (q, q') of the leading modes (as many as `dq` holds) into `dq`, `dqd`.
    pub fn derivatives(&mut self, dq: &mut [T], dqd: &mut [T]) -> Result<(), BodyError> {
        self.evaluate()?;
        dq.copy_from_slice(&self.qd[..dq.len()]);
        dqd.copy_from_slice(&self.eval.qdd[..dqd.len()]);
        Ok(())
    }

    pub fn qdd(&mut self) -> Result<&[T], BodyError> {
        self.evaluate()?;
        Ok(&self.eval.qdd)
    }

    pub fn flange_motion(&mut self, flange: usize) -> Result<&FlangeMotion<T>, BodyError> {
        self.evaluate()?;
        Ok(&self.eval.flanges[flange])
    }
}
