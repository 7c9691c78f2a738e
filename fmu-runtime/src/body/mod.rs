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
//! `FlexibleBody` is a façade over four parts, each in a file of its own: `coordinates` (q, q'
//! and a free body's frame: what the equations integrate), `inputs` (what the host sets: mount
//! motion, flange loads, parameters, input rates, its view of a mount a step moved),
//! `derived` (everything computed from those two, behind one cache that only the body's
//! `coords_mut` and `inputs_mut` make stale, through `Derived::invalidate`) and `stepper`
//! (Co-Simulation's machinery: the exact transitions, their reference, the stepped inputs, the
//! step's scratch). A saved state (`BodyState`) holds the coordinates and inputs as they are.
//!
//! The equations, one job per file: this one holds the types, construction, saved state,
//! accessors and the evaluation shared by every body (dispatch and flange kinematics);
//! `mounted` the equations of a body on a prescribed mount (input check, modal load, coupling
//! terms); `reaction` the mount reaction; `stress` the stresses at the recovery points;
//! `free_floating` the free body's accelerations and invariants; `cosim_step` Co-Simulation
//! stepping (input rates, exact and predictor-corrector steps, the free body's substeps);
//! `step_workspace` the step's scratch, lent down its functions; `input_jump` Co-Simulation's
//! quasi-static modes across load changes; `quasi_static` Model Exchange's solve of the modes
//! above the cutoff (and `ModeSplit`, which modes are dynamic); `statics` the static start;
//! `coupling_terms` the coupling as coefficients times matrices, and `coupling_bound` their
//! norms; `dense` the dense kernels (dot products and the small in-place solver); `error` why
//! the equations fail, by failure class.

mod coordinates;
mod cosim_step;
mod coupling_bound;
mod coupling_terms;
pub use coordinates::Coordinates;
pub use cosim_step::SUBSTEP_ANGLE;
pub(crate) mod dense;
mod derived;
mod error;
pub use error::{BodyError, OutOfRange, StateMismatch, StepError};
mod free_floating;
mod input_jump;
mod inputs;
pub(crate) use inputs::HostMount;
pub use inputs::{BodyInputs, InputRates};
mod mounted;
mod quasi_static;
mod reaction;
mod statics;
mod step_workspace;
mod stepper;
mod stress;

use crate::kinematics::{self as k3, Mat3, Vec3};
use crate::reduced::ReducedBody;
use crate::scalar::{Dual, Scalar, c};
use coupling_terms::CouplingTerms;
pub(crate) use coupling_terms::term_count;
use derived::{Change, Coupling, Derived};
use quasi_static::ModeSplit;
use std::sync::Arc;
use stepper::Stepper;

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

/// Everything of a [`FlexibleBody`] that evolves or can be set: what a saved state holds, its
/// coordinates and inputs as the body holds them. The rest is the immutable reduced body, caches
/// that are functions of these (recomputed on demand, so a body rebuilt from its state continues
/// bit-identically) and the step's machinery, of which the two parts later steps depend on come
/// along.
#[derive(Debug, Clone, PartialEq)]
pub struct BodyState {
    pub coordinates: Coordinates,
    /// The host's inputs (the mount as the host set it, not the pose a step turned it to).
    pub inputs: BodyInputs,
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

/// The body's equations over the scalar `T`: `f64` for the model, [`Dual`] for the exact
/// directional derivatives of everything it evaluates (see [`FlexibleBody::to_dual`]). Stepping
/// is `f64` only.
///
/// A façade over four parts, each with one job: the [`Coordinates`] it integrates, the
/// [`BodyInputs`] the host sets, the `Derived` values computed from those two (behind one
/// cache, made stale through `Derived::invalidate` by the setters `coords_mut` and
/// `inputs_mut`), and the `Stepper` that advances it in Co-Simulation; beside them the
/// immutable model (the reduced body and its coupling terms) and how its modes are split
/// (`ModeSplit`).
#[derive(Debug, Clone)]
pub struct FlexibleBody<T = f64> {
    body: Arc<ReducedBody>,
    /// The matrices the coupling's coefficients multiply, with their norms (`coupling_terms`):
    /// made once per reduced body and shared by its copies; used by evaluation and step alike.
    coupling_terms: Arc<CouplingTerms>,
    /// Which modes are dynamic, and whether the others are solved (Model Exchange).
    split: ModeSplit,
    /// What the equations integrate; written through `coords_mut` (or by an evaluation's own
    /// solve of the quasi-static modes).
    coords: Coordinates<T>,
    /// What the host sets; written through `inputs_mut` (or, for a free body's mount, by the
    /// evaluation).
    inputs: BodyInputs<T>,
    /// Computed from `coords` and `inputs` on demand, never saved.
    derived: Derived<T>,
    /// Co-Simulation's machinery (empty in the dual copy).
    stepper: Stepper,
}

/// Largest magnitude of a Real the host sets (and of a rate it gives, and of a state a step may
/// end in): beyond any load, speed, acceleration or damping in SI units by scores of orders of
/// magnitude, and small enough that products of three such values (a centrifugal load w^2 r)
/// stay finite. A value past it is a unit or host error that would otherwise surface as NaN
/// outputs many calls later.
pub const REAL_LIMIT: f64 = 1e100;

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
        let split = ModeSplit::of(&body);
        Self {
            coords: Coordinates {
                q: vec![0.0; n],
                qd: vec![0.0; n],
                frame: body.free_floating.then(FrameState::default),
            },
            inputs: BodyInputs {
                mount: MountMotion::default(),
                loads: vec![FlangeLoad::default(); nf],
                params: Parameters { g: [0.0; 3], alpha: body.alpha, beta: body.beta },
                initial_frame: InitialFrame::default(),
                rates: InputRates::held(nf),
                host: HostMount::default(),
            },
            derived: Derived::for_body(&body, split.n_dynamic),
            stepper: Stepper::for_body(&body),
            split,
            coupling_terms,
            body,
        }
    }

    /// This body in dual numbers at the present state and inputs, every derivative part zero.
    /// Seed a direction in the `.d` parts (through `mount_mut`, `load_mut`, `q_mut`, ...) and
    /// evaluate: every result's `.d` is then its exact directional derivative.
    pub fn to_dual(&self) -> FlexibleBody<Dual> {
        FlexibleBody {
            body: Arc::clone(&self.body),
            coupling_terms: Arc::clone(&self.coupling_terms),
            split: ModeSplit { settling: false, ..self.split },
            coords: self.coords.map(Dual::from),
            inputs: self.inputs.to_dual(),
            derived: Derived::for_body(&self.body, self.split.n_dynamic),
            // stepping is f64 only
            stepper: Stepper::none(),
        }
    }

    pub fn state(&self) -> BodyState {
        BodyState {
            coordinates: self.coords.clone(),
            // the host's mount: a restored body starts its next step where this one would
            inputs: self.inputs.as_saved(),
            coupling_reference: self.stepper.coupling_reference(),
            stepped_inputs: self.stepped_inputs(),
        }
    }

    /// A new body of the same reduced body in `state`, its caches empty; Err if the state's
    /// sizes do not fit this body.
    pub fn with_state(&self, state: BodyState) -> Result<Self, BodyError> {
        let (n, nf) = (self.n_modes(), self.inputs.loads.len());
        let BodyState { coordinates, inputs, coupling_reference, stepped_inputs } = state;
        if coordinates.q.len() != n || coordinates.qd.len() != n {
            return Err(StateMismatch::Modes { q: coordinates.q.len(), qd: coordinates.qd.len(), n }.into());
        }
        if inputs.loads.len() != nf || inputs.rates.loads.len() != nf {
            return Err(StateMismatch::Flanges { found: inputs.loads.len(), n: nf }.into());
        }
        let (free, body_free) = (coordinates.frame.is_some(), self.coords.frame.is_some());
        if free != body_free {
            return Err(StateMismatch::Kind { free, body_free }.into());
        }
        let mut b = FlexibleBody::with_coupling_terms(Arc::clone(&self.body), Arc::clone(&self.coupling_terms));
        b.split.quasi_static = self.split.quasi_static;
        b.coords = coordinates;
        // a saved state holds the host's mount, no view of one a step moved
        b.inputs = BodyInputs { host: HostMount::default(), ..inputs };
        if let Some(st) = &stepped_inputs {
            b.set_stepped_inputs(st)?;
        }
        if let Some(r) = coupling_reference {
            let nn = n * n;
            let valid = r.c_d.len() == nn && r.c_k.len() == nn && r.h > 0.0 && r.h.is_finite();
            if !valid || !b.stepper.coupled.has_storage() {
                return Err(StateMismatch::CouplingReference { c_d: r.c_d.len(), c_k: r.c_k.len(), n }.into());
            }
            if !(r.c_d.iter().chain(&r.c_k).chain([&r.alpha, &r.beta]).all(|v| v.is_finite())) {
                return Err(StateMismatch::CouplingReferenceNotFinite.into());
            }
            let body = Arc::clone(&b.body);
            let s = &mut b.stepper;
            let ws = &mut s.work.coupled.propagator;
            s.coupled.prepare(&body.omega, r.alpha, r.beta, &body.modal_damping, &r.c_d, &r.c_k, r.h, ws)?;
            // coefficients of another length or not finite: unknown, and the next step renews
            if let Some(coef) = r.coef.filter(|c| c.len() == s.reference_coef.len() && c.iter().all(|v| v.is_finite()))
            {
                s.reference_coef.copy_from_slice(&coef);
                s.reference_coef_known = true;
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
        self.coords.q.len()
    }
    pub fn q(&self) -> &[T] {
        &self.coords.q
    }
    pub fn qd(&self) -> &[T] {
        &self.coords.qd
    }
    pub fn mount(&self) -> &MountMotion<T> {
        &self.inputs.mount
    }
    pub fn loads(&self) -> &[FlangeLoad<T>] {
        &self.inputs.loads
    }
    pub fn parameters(&self) -> &Parameters {
        &self.inputs.params
    }

    pub fn frame(&self) -> Option<&FrameState<T>> {
        self.coords.frame.as_ref()
    }
    pub fn frame_mut(&mut self) -> Option<&mut FrameState<T>> {
        self.coords_mut().frame.as_mut()
    }

    /// The coordinates for writing: the derived values are stale from here on. Writes made by
    /// an evaluation itself (the quasi-static modes it solves) go to `coords` directly.
    pub(super) fn coords_mut(&mut self) -> &mut Coordinates<T> {
        self.derived.invalidate(Change::Coordinates);
        &mut self.coords
    }
    /// The inputs for writing: the derived values, the coupling included, are stale from here
    /// on. Writes made by an evaluation itself (a free body's mount, its frame's motion) go to
    /// `inputs` directly.
    pub(super) fn inputs_mut(&mut self) -> &mut BodyInputs<T> {
        self.derived.invalidate(Change::Inputs);
        &mut self.inputs
    }

    pub fn mount_mut(&mut self) -> &mut MountMotion<T> {
        &mut self.inputs_mut().mount
    }
    /// Entry k (row-major) of the mount's orientation, as the host sets it: the mount returns to
    /// the host's view of its orientation, this entry changed.
    pub fn set_mount_rotation(&mut self, k: usize, value: T) {
        let inputs = self.inputs_mut();
        if let Some(host) = inputs.host.rot.take() {
            inputs.mount.rot = host.map(c);
        }
        inputs.host.rot_driven = true;
        inputs.mount.rot[k] = value;
    }
    /// Component i of the mount's angular velocity, as the host sets it.
    pub fn set_mount_spin(&mut self, i: usize, value: T) {
        let inputs = self.inputs_mut();
        if let Some(host) = inputs.host.w.take() {
            inputs.mount.w = host.map(c);
        }
        inputs.host.w_driven = true;
        inputs.mount.w[i] = value;
    }
    /// Initialisation is over: what the host set so far are start values, not a drive.
    pub fn start_stepping(&mut self) {
        self.inputs.host.rot_driven = false;
        self.inputs.host.w_driven = false;
    }
    pub fn load_mut(&mut self, flange: usize) -> &mut FlangeLoad<T> {
        &mut self.inputs_mut().loads[flange]
    }
    pub fn parameters_mut(&mut self) -> &mut Parameters {
        &mut self.inputs_mut().params
    }
    /// A free-floating body's initial pose and velocity (the FMU's parameters): read only when
    /// its frame is started (`start_frame`), so setting it leaves the derived values as they are.
    pub fn initial_frame(&self) -> &InitialFrame {
        &self.inputs.initial_frame
    }
    pub fn initial_frame_mut(&mut self) -> &mut InitialFrame {
        &mut self.inputs.initial_frame
    }
    /// Set the leading modes' q, q' (all of them, or Model Exchange's dynamic ones).
    pub fn set_state(&mut self, q: &[T], qd: &[T]) {
        let coords = self.coords_mut();
        coords.q[..q.len()].copy_from_slice(q);
        coords.qd[..qd.len()].copy_from_slice(qd);
    }
    pub fn q_mut(&mut self) -> &mut [T] {
        &mut self.coords_mut().q
    }
    pub fn qd_mut(&mut self) -> &mut [T] {
        &mut self.coords_mut().qd
    }

    fn gravity(&self) -> Vec3<T> {
        self.inputs.params.g.map(c)
    }

    /// Everything that follows from the state and inputs (q'', flange motion), once per change.
    fn evaluate(&mut self) -> Result<(), BodyError> {
        if self.derived.eval.valid {
            return Ok(());
        }
        if self.coords.frame.is_some() {
            self.free_accelerations()?;
        } else {
            self.mounted_accelerations()?;
        }
        self.flange_kinematics();
        self.derived.evaluated();
        Ok(())
    }

    /// Position, orientation and their rates of every force flange, from q, q', q'' and the
    /// mount (or the free body's frame) of the evaluation.
    fn flange_kinematics(&mut self) {
        let n = self.coords.q.len();
        let m = &self.inputs.mount;
        let a = &self.derived.rot;
        for (i, flange) in self.body.flanges.iter().enumerate() {
            // the flange's six shape rows (translation, rotation) times q, q' and q''
            let rows = |x: &[T]| {
                let mut out = [T::zero(); 6];
                T::add_scaled_mat_vec(&flange.shapes[..6 * n], x, T::from(1.0), &mut out);
                out
            };
            let (x, xd, xdd) = (rows(&self.coords.q), rows(&self.coords.qd), rows(&self.derived.eval.qdd));
            let (u, phi) = ([x[0], x[1], x[2]], [x[3], x[4], x[5]]);
            let (ud, phid) = ([xd[0], xd[1], xd[2]], [xd[3], xd[4], xd[5]]);
            let (udd, phidd) = ([xdd[0], xdd[1], xdd[2]], [xdd[3], xdd[4], xdd[5]]);
            let rho = k3::mul(a, k3::add(flange.position.map(c), u));
            let ud_w = k3::mul(a, ud);
            let phid_w = k3::mul(a, phid);
            let out = &mut self.derived.eval.flanges[i];
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
        dq.copy_from_slice(&self.coords.qd[..dq.len()]);
        dqd.copy_from_slice(&self.derived.eval.qdd[..dqd.len()]);
        Ok(())
    }

    pub fn qdd(&mut self) -> Result<&[T], BodyError> {
        self.evaluate()?;
        Ok(&self.derived.eval.qdd)
    }

    pub fn flange_motion(&mut self, flange: usize) -> Result<&FlangeMotion<T>, BodyError> {
        self.evaluate()?;
        Ok(&self.derived.eval.flanges[flange])
    }
}
