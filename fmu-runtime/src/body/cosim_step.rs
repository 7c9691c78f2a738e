//! Co-Simulation stepping: the input rates of the next step, the mounted body's step (exact
//! transition of the modal diagonal or of the coupled modes, with a predictor-corrector load for
//! the coupling's drift from the transition's) and the free body's substeps.

use super::mounted::coupling_coefficients;
use super::step_workspace::{CoupledWork, FreeWork, StepStart, StepWorkspace};
use super::{
    BodyError, Change, Coupling, FlangeLoad, FlexibleBody, FrameState, InputRates, MountMotion, REAL_LIMIT, StepError,
    UNSTABLE_STIFFNESS,
};
use crate::coupled_propagator::Prepared;
use crate::kinematics::{self as k3, Mat3, Vec3};
use crate::workspace::WorkspaceTooSmall;

/// Largest h |dC| for which the coupling's difference dC from the exact transition's is
/// treated as a load (see `step`), |dC| bounded in the energy norm of the transition's state
/// from the coupling's coefficients (`coupling_bound`): the predictor-corrector then gains at
/// most (h |dC|)^4 / 8 = 1e-7 of energy in a step (and far less on average, as the drift runs
/// between -REFERENCE_DRIFT/2 and +REFERENCE_DRIFT, the reference set ahead of a steady change),
/// and a renewal, one exponential, is needed only every few hundred steps of a spin-up (once in
/// the bench's 1000-step spin-up from 10 to 40 rad/s, at 20 to 100 modes).
const REFERENCE_DRIFT: f64 = 3e-2;

/// Largest rotation of a free body within one of its substeps (rad): the Heun splitting's error
/// per substep is of third order in it.
pub const SUBSTEP_ANGLE: f64 = 0.005;

/// Most substeps one Co-Simulation step of a free body takes, as a budget of work (a step that
/// needs more is not taken: `StepError::NotTaken`, naming the longest step that fits). A substep
/// costs two evaluations of the free body's equations, some 40 n^2 multiply-adds each for n
/// modes plus a fixed part; measured (release build) on the 2-core machine of docs/FUZZING.md's
/// runs: 22 us for the fuzzer's 18-mode free beam, 3.7 to 7 us for 2 to 12 modes, within
/// (n^2 + 60) units of 0.06 us. The budget keeps one call near 0.15 s there (6 510 substeps of
/// the 18-mode beam, 39 000 of 2 modes), below 0.5 s on a machine three times slower (the
/// fuzzing machine that found it took 38 us per substep of the beam).
const SUBSTEP_WORK: f64 = 2.5e6;

/// Work units of one substep of a body of n modes (see [`SUBSTEP_WORK`]).
fn substep_work(n: usize) -> f64 {
    (n * n) as f64 + 60.0
}

/// The mount as the host set it, and which of its groups moved by their kinematic rates
/// (position and velocity do not enter the body's equations: they are left alone).
struct HeldMount {
    mount: MountMotion,
    rot: bool,
    w: bool,
    /// Only the orientation turns, at the mount's own spin: body-frame w and z stay constant.
    steady: bool,
}

impl FlexibleBody {
    /// Rates of the mount inputs over the next step (its rotation matrix's rate entry by entry).
    pub fn mount_rate_mut(&mut self) -> &mut MountMotion {
        self.inputs.rates.any = true;
        &mut self.inputs.rates.mount
    }
    /// Rates of a flange's force and torque over the next step.
    pub fn load_rate_mut(&mut self, flange: usize) -> &mut FlangeLoad {
        self.inputs.rates.any = true;
        &mut self.inputs.rates.loads[flange]
    }
    pub fn input_rates(&self) -> &InputRates {
        &self.inputs.rates
    }

    /// Advance by h with the inputs held (or ramped at their rates) over the step: exact
    /// propagation of the modal diagonal when nothing couples the modes, else of the whole
    /// coupled system (gyroscopic, centrifugal, stiffening terms) by its matrix exponential,
    /// which keeps an undamped spinning body's energy at any step (see `coupled_propagator`).
    /// An input changed since the last step moves the algebraic modes with their equilibrium
    /// first (`input_jump`).
    ///
    /// A step whose cost is beyond one call's budget (a free body spinning fast over a long
    /// step) is refused before any work; one whose end state or extrapolated inputs are not
    /// finite or beyond [`REAL_LIMIT`] (a step or load far beyond the body's range) is undone.
    /// Either way the body is as before the step, with the reason in the error.
    pub fn step(&mut self, h: f64) -> Result<(), StepError> {
        if !(h > 0.0 && h.is_finite()) {
            return Err(StepError::Inputs(BodyError::StepSize(h)));
        }
        if self.coords.frame.is_some() {
            self.free_substeps_within_budget(h)?;
        }
        // the step's scratch, lent down its functions (taking it out leaves an empty one behind:
        // no allocation)
        let mut ws = std::mem::take(&mut self.stepper.work);
        let result = self.step_in(&mut ws, h);
        self.stepper.work = ws;
        // taken, refused or undone, the step wrote coordinates and inputs in place: whatever was
        // derived before it is stale
        self.derived.invalidate(Change::Inputs);
        result
    }

    /// The step in the scratch `ws` lends: kept at its start, undone if it fails.
    fn step_in(&mut self, ws: &mut StepWorkspace, h: f64) -> Result<(), StepError> {
        if !ws.fits(self.coords.q.len(), self.inputs.loads.len()) {
            return Err(StepError::NotTaken(BodyError::WorkspaceMismatch {
                modes: self.coords.q.len(),
                flanges: self.inputs.loads.len(),
            }));
        }
        self.keep_step_start(&mut ws.start);
        let result = self.step_from_start(ws, h).and_then(|()| self.check_step_end(h));
        if result.is_err() {
            self.restore_step_start(&ws.start);
        }
        result
    }

    fn step_from_start(&mut self, ws: &mut StepWorkspace, h: f64) -> Result<(), StepError> {
        let not_taken = StepError::NotTaken;
        if self.coords.frame.is_some() {
            self.follow_input_change(&mut ws.jump).map_err(not_taken)?;
            // free bodies hold their flange loads over the step; the inputs still end the step
            // at their interpolated values
            self.step_free(&mut ws.free, h).map_err(not_taken)?;
            if self.inputs.rates.any {
                self.extrapolate_inputs(h);
            }
            self.record_stepped_inputs();
            return Ok(());
        }
        // what the last step moved and the host did not set since: the host's values
        if let Some(rot) = self.inputs.host.rot.take() {
            self.inputs_mut().mount.rot = rot;
        }
        if let Some(w) = self.inputs.host.w.take() {
            self.inputs_mut().mount.w = w;
        }
        self.check_inputs().map_err(StepError::Inputs)?;
        self.follow_input_change(&mut ws.jump).map_err(not_taken)?;
        self.step_mounted(&mut ws.coupled, h).map_err(not_taken)
    }

    /// Substeps of a free body's step of h at its present spin, and Err if more than one call
    /// may take (before anything is done).
    fn free_substeps_within_budget(&self, h: f64) -> Result<usize, StepError> {
        let spin = self.coords.frame.map_or(0.0, |f| k3::dot(f.w_body, f.w_body).sqrt());
        let needed = (h * spin / SUBSTEP_ANGLE).ceil();
        let most = self.max_free_substeps();
        if needed.is_nan() || needed > most as f64 {
            // the longest step within the budget, rounded down to four digits so that it fits
            let longest = most as f64 * SUBSTEP_ANGLE / spin;
            // saturating: a spin that overflows makes the longest step 0, whose log is -inf
            let unit = 10f64.powi((longest.log10().floor() as i32).saturating_sub(3));
            let longest = (longest / unit).floor() * unit;
            return Err(StepError::NotTaken(BodyError::TooManySubsteps { h, spin, needed, most, longest }));
        }
        Ok((needed as usize).max(1))
    }

    /// The substep budget of one call for this body's size (see [`SUBSTEP_WORK`]).
    pub fn max_free_substeps(&self) -> usize {
        (SUBSTEP_WORK / substep_work(self.coords.q.len())) as usize
    }

    /// Everything the step changes, copied into the step's preallocated [`StepStart`].
    fn keep_step_start(&self, s: &mut StepStart) {
        s.coords.copy_from(&self.coords);
        s.inputs.copy_from(&self.inputs);
        s.stepped.copy_from(&self.stepper.stepped);
    }

    /// The body as [`keep_step_start`](Self::keep_step_start) found it; the caches are made
    /// stale by `step` when it returns.
    fn restore_step_start(&mut self, s: &StepStart) {
        self.coords.copy_from(&s.coords);
        self.inputs.copy_from(&s.inputs);
        self.stepper.stepped.copy_from(&s.stepped);
        self.stepper.warning = None;
    }

    /// Err naming the first input or state the step left non-finite or beyond [`REAL_LIMIT`]
    /// (inputs move by their derivatives over the step): no state to go on from, and outputs
    /// computed from it would overflow.
    fn check_step_end(&self, h: f64) -> Result<(), StepError> {
        let out_of_range = |v: f64| !(v.abs() <= REAL_LIMIT);
        // a spin above a critical speed makes the deformation grow without bound: say so
        let unstable =
            self.coords.frame.is_none() && self.stepper.coupled.has_storage() && !self.stepper.coupled.definite();
        let fail = |what: String, value: f64| {
            Err(StepError::NotTaken(BodyError::StepEndOutOfRange { what, value, h, unstable }))
        };
        // a free body's mount is its frame's motion, no input
        let m = &self.inputs.mount;
        let mount = &self.body.mount;
        let inputs = [("r", &m.r[..]), ("R", &m.rot), ("v", &m.v), ("w", &m.w), ("a", &m.a), ("z", &m.z)];
        for (name, x) in inputs.into_iter().filter(|_| self.coords.frame.is_none()) {
            if let Some(i) = x.iter().position(|v| out_of_range(*v)) {
                let entry = if name == "R" { format!("{},{}", i / 3 + 1, i % 3 + 1) } else { format!("{}", i + 1) };
                return fail(format!("the input {mount}.{name}[{entry}]"), x[i]);
            }
        }
        for (flange, load) in self.body.flanges.iter().zip(&self.inputs.loads) {
            for (name, x) in [("f", &load.f), ("t", &load.t)] {
                if let Some(i) = x.iter().position(|v| out_of_range(*v)) {
                    return fail(format!("the input {}.{name}[{}]", flange.name, i + 1), x[i]);
                }
            }
        }
        // the state after the inputs: an input carried out of range by its rate is the cause
        for (name, x) in [("q", &self.coords.q), ("qd", &self.coords.qd)] {
            if let Some(j) = x.iter().position(|v| out_of_range(*v)) {
                return fail(format!("the modal state {name}[{}]", j + 1), x[j]);
            }
        }
        if let Some(f) = &self.coords.frame {
            for (name, x) in [("r", &f.r[..]), ("Q", &f.quat), ("v", &f.v), ("W", &f.w_body)] {
                if let Some(i) = x.iter().position(|v| out_of_range(*v)) {
                    return fail(format!("the frame state frame.{name}[{}]", i + 1), x[i]);
                }
            }
        }
        Ok(())
    }

    /// A mounted body's step, in the scratch `work` lends.
    fn step_mounted(&mut self, work: &mut CoupledWork, h: f64) -> Result<(), BodyError> {
        // the mount moves within the step as its own inputs say (r' = v, R' = w~ R, v' = a,
        // w' = z) wherever the host gave no rate; the host's next inputs replace that motion
        let held = self.kinematic_mount_rates();
        self.modal_load();
        let ramp = self.inputs.rates.any;
        if ramp {
            self.modal_load_rate();
        }
        self.prepare_coupling_coefficients();
        // a mount turning at a steady spin (R' = w~ R, nothing else moving) keeps the
        // body-frame spin and hence the coupling: only the load turns
        let steady = held.steady && self.steady_coupling();
        // inputs that move over the step move the coupling too: its matrices at the step's end
        let moving = ramp && !steady;
        if moving {
            self.coupling_at_step_end(work, h);
        }
        // a coupling that starts at zero (spin-up from rest) still couples within the step
        let coupled = self.derived.coupling.active || (moving && work.coupling_end.active);
        if coupled {
            self.advance_coupled(work, ramp, moving, h)?;
        } else {
            self.stepper.propagator.prepare(
                &self.body.omega,
                self.inputs.params.alpha,
                self.inputs.params.beta,
                &self.body.modal_damping,
                h,
            );
            if ramp {
                self.stepper.propagator.advance_ramp(
                    &self.body.omega,
                    &self.derived.load,
                    &self.derived.load_rate,
                    &mut self.coords.q,
                    &mut self.coords.qd,
                );
            } else {
                self.stepper.propagator.advance(
                    &self.body.omega,
                    &self.derived.load,
                    &mut self.coords.q,
                    &mut self.coords.qd,
                );
            }
        }
        if ramp {
            self.extrapolate_inputs(h);
            self.record_stepped_inputs();
            self.advance_held_mount(&held, h);
        } else {
            self.record_stepped_inputs();
        }
        if coupled && !(self.coords.q.iter().chain(&self.coords.qd).all(|v| v.is_finite())) {
            return Err(if self.stepper.coupled.definite() {
                BodyError::StepNotFinite { h }
            } else {
                BodyError::Unstable
            });
        }
        Ok(())
    }

    /// The coupling's coefficients at the step's end, where the inputs' rates carry the mount
    /// and the loads.
    fn coupling_at_step_end(&self, work: &mut CoupledWork, h: f64) {
        let mut end = self.inputs.mount;
        let r = &self.inputs.rates.mount;
        for i in 0..3 {
            end.w[i] += h * r.w[i];
            end.z[i] += h * r.z[i];
            end.a[i] += h * r.a[i];
        }
        for i in 0..9 {
            end.rot[i] += h * r.rot[i];
        }
        for ((e, l), rate) in work.loads_end.iter_mut().zip(&self.inputs.loads).zip(&self.inputs.rates.loads) {
            *e = FlangeLoad { f: k3::add(l.f, k3::scale(h, rate.f)), t: k3::add(l.t, k3::scale(h, rate.t)) };
        }
        let end_rot = k3::nearest_rotation(&end.rot);
        coupling_coefficients(
            &self.coupling_terms,
            &end_rot,
            &end,
            &work.loads_end,
            self.inputs.params.g,
            &mut work.coupling_end,
        );
    }

    /// The modes over a step with coupling. The transition is exact for the coupling it was
    /// made for (the reference). A coupling that drifted from it (spin-up, a tumbling mount, or
    /// only the round-off of a rotating base.R) enters as the small difference dC = C - C_ref,
    /// by a predictor-corrector load on top of the exact coupled transition; the reference is
    /// renewed (one matrix exponential, at the step's midpoint coupling, or ahead of a steady
    /// change: `renew_reference`) when h |dC| exceeds REFERENCE_DRIFT. A steady spin runs on one
    /// exponential. The propagator's scratch is
    /// `work.propagator`; Err (before anything moved) if it is too small.
    fn advance_coupled(
        &mut self,
        work: &mut CoupledWork,
        ramp: bool,
        moving: bool,
        h: f64,
    ) -> Result<(), WorkspaceTooSmall> {
        let prepared = self.stepper.coupled.is_prepared(h, self.inputs.params.alpha, self.inputs.params.beta);
        // a steady spin meets its own transition again (the same coefficients make the same
        // matrices)
        let held_exactly = !moving
            && prepared
            && self.stepper.reference_coef_known
            && self.coupling_terms.same_coupling(&self.derived.coupling.coef, &self.stepper.reference_coef);
        let drift_ok = |c: &Coupling<f64>| {
            self.stepper.reference_coef_known
                && h * self.coupling_terms.drift_bound(&c.coef, &self.stepper.reference_coef) <= REFERENCE_DRIFT
        };
        let current =
            held_exactly || prepared && drift_ok(&self.derived.coupling) && (!moving || drift_ok(&work.coupling_end));
        let renewed_for_this_step = !current && self.renew_reference(work, moving, prepared, h)?;
        let rate: &[f64] = if ramp { &self.derived.load_rate } else { &work.zeros };
        let ws = &mut work.propagator;
        // a transition made for this step (held or midpoint coupling) needs no correction
        if held_exactly || renewed_for_this_step {
            return self.stepper.coupled.advance(
                &self.body.omega,
                &self.derived.load,
                rate,
                &mut self.coords.q,
                &mut self.coords.qd,
                ws,
            );
        }
        // Heun: the residual coupling force held at its start value, then ramped to its value at
        // the predicted end. The step is linear in the load, so the corrector adds only the
        // ramp's difference to the predictor's end (G2 (f1 - rate), a 2n x n product) instead of
        // taking the step again (2n x 4n)
        let end = if moving { &work.coupling_end } else { &self.derived.coupling };
        let terms = &self.coupling_terms;
        let reference = &self.stepper.reference_coef;
        terms.drift_force(
            &self.body,
            &self.derived.coupling.coef,
            reference,
            h,
            &self.coords.q,
            &self.coords.qd,
            &mut work.f0,
        );
        for (f0, load) in work.f0.iter_mut().zip(&self.derived.load) {
            *f0 = load - *f0;
        }
        self.stepper.coupled.advance(&self.body.omega, &work.f0, rate, &mut self.coords.q, &mut self.coords.qd, ws)?;
        terms.drift_force(&self.body, &end.coef, reference, h, &self.coords.q, &self.coords.qd, &mut work.f1);
        for (((f1, rate), load), f0) in work.f1.iter_mut().zip(rate).zip(&self.derived.load).zip(&work.f0) {
            let f_end = load + h * rate - *f1;
            *f1 = (f_end - f0) / h - rate;
        }
        self.stepper.coupled.add_ramp(&self.body.omega, &work.f1, &mut self.coords.q, &mut self.coords.qd, ws)
    }

    /// A new reference transition, in the propagator's scratch `work.propagator`: at the step's
    /// coupling (its midpoint where the inputs move), or, where the coupling has been changing
    /// steadily (a spin-up: the drift from the old reference just past the limit, not a jump
    /// of the inputs), half a renewal interval ahead of it, C + (C - C_old) / 2. The drift then
    /// runs from -X to +X instead of from 0 to X: a renewal every twice as many steps, the
    /// drift's correction as accurate. Ok(true) where the transition is this step's own
    /// coupling (exact for it, no correction needed), Ok(false) where it was set ahead.
    fn renew_reference(
        &mut self,
        work: &mut CoupledWork,
        moving: bool,
        prepared: bool,
        h: f64,
    ) -> Result<bool, WorkspaceTooSmall> {
        if moving {
            for (m, (a, b)) in
                work.coef_mid.iter_mut().zip(self.derived.coupling.coef.iter().zip(&work.coupling_end.coef))
            {
                *m = 0.5 * (a + b);
            }
        } else {
            work.coef_mid.copy_from_slice(&self.derived.coupling.coef);
        }
        let steady = prepared
            && self.stepper.reference_coef_known
            && h * self.coupling_terms.drift_bound(&work.coef_mid, &self.stepper.reference_coef)
                <= 2.0 * REFERENCE_DRIFT;
        if steady {
            for (m, o) in work.coef_mid.iter_mut().zip(&self.stepper.reference_coef) {
                *m += 0.5 * (*m - o);
            }
        }
        // the coupling is linear in the coefficients (the products w_i w_j are coefficients of
        // their own): the midpoint's and the extrapolated coefficients make the midpoint's and
        // the extrapolated matrices
        self.coupling_terms.fill(&self.body, &work.coef_mid, &mut work.c_d_mid, &mut work.c_k_mid);
        let (c_d, c_k): (&[f64], &[f64]) = (&work.c_d_mid, &work.c_k_mid);
        let was_definite = self.stepper.coupled.definite();
        let prepared = self.stepper.coupled.prepare(
            &self.body.omega,
            self.inputs.params.alpha,
            self.inputs.params.beta,
            &self.body.modal_damping,
            c_d,
            c_k,
            h,
            &mut work.propagator,
        )?;
        self.stepper.reference_coef.copy_from_slice(&work.coef_mid);
        self.stepper.reference_coef_known = true;
        if prepared == Prepared::Computed && was_definite && !self.stepper.coupled.definite() {
            self.stepper.warning = Some(UNSTABLE_STIFFNESS);
        }
        Ok(!steady)
    }

    /// A warning about the last step, once: the FMI layer logs it.
    pub fn take_warning(&mut self) -> Option<&'static str> {
        self.stepper.warning.take()
    }

    /// dp/dt of the modal load for the input rates: every body-frame input x_B = A^T x changes
    /// as A^T x' + A'^T x, with A' = A skew(A^T R') the rotational part of the orientation's rate
    /// (the derivative of the projection onto the rotations); the centrifugal part as
    /// d(w_i w_k)/dt.
    fn modal_load_rate(&mut self) {
        let a = &self.derived.rot;
        let r = &self.inputs.rates;
        let n = self.coords.q.len();
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
        let a_b = body_rate(k3::sub(self.inputs.mount.a, self.inputs.params.g), r.mount.a);
        for j in 0..n {
            self.derived.load_rate[j] =
                -(self.body.c_t[j] * a_b[0] + self.body.c_t[n + j] * a_b[1] + self.body.c_t[2 * n + j] * a_b[2]);
        }
        if let Some(rot) = &self.body.rotation {
            let w = k3::mul_t(a, self.inputs.mount.w);
            let dw = body_rate(self.inputs.mount.w, r.mount.w);
            let dz = body_rate(self.inputs.mount.z, r.mount.z);
            for i in 0..3 {
                if dz[i] != 0.0 {
                    let c_a = &self.body.c_r[i * n..(i + 1) * n];
                    for (rate, c_a) in self.derived.load_rate.iter_mut().zip(c_a) {
                        *rate -= dz[i] * c_a;
                    }
                }
                for k in 0..3 {
                    let dww = dw[i] * w[k] + w[i] * dw[k];
                    if dww != 0.0 {
                        let o = &rot.o_vec[(3 * i + k) * n..(3 * i + k + 1) * n];
                        for (rate, o) in self.derived.load_rate.iter_mut().zip(o) {
                            *rate -= dww * o;
                        }
                    }
                }
            }
        }
        for ((flange, rate), load) in self.body.flanges.iter().zip(&r.loads).zip(&self.inputs.loads) {
            let f_b = body_rate(load.f, rate.f);
            let t_b = body_rate(load.t, rate.t);
            let wrench = [f_b[0], f_b[1], f_b[2], t_b[0], t_b[1], t_b[2]];
            for (row, w) in wrench.iter().enumerate() {
                if *w != 0.0 {
                    let shape = &flange.shapes[row * n..(row + 1) * n];
                    for (rate, s) in self.derived.load_rate.iter_mut().zip(shape) {
                        *rate += s * w;
                    }
                }
            }
        }
    }

    /// Fills the rates of the mount's orientation and spin the host left at zero with the motion
    /// its inputs describe: R' = w~ R (w in world axes) and w' = z. Without it a spinning mount
    /// would stand still within a step, its gravity and world-fixed loads held in the body frame
    /// at the step's start (first order in h); with it they turn (second order, as with
    /// host-given rates). Position and velocity do not enter the body's equations and are left
    /// alone. Returns the inputs as the host set them: the host's values stay what fmi2GetReal
    /// returns after the step.
    fn kinematic_mount_rates(&mut self) -> HeldMount {
        let m = self.inputs.mount;
        let r = &mut self.inputs.rates.mount;
        let unset = |x: &[f64]| x.iter().all(|v| *v == 0.0);
        let host_rates = self.inputs.rates.any;
        let mut held = HeldMount { mount: m, rot: false, w: false, steady: false };
        if unset(&r.rot) && !unset(&m.w) {
            let w = m.w;
            // w~ R, column by column: w x (column j of R)
            for j in 0..3 {
                let col = k3::cross(w, [m.rot[j], m.rot[3 + j], m.rot[6 + j]]);
                for i in 0..3 {
                    r.rot[3 * i + j] = col[i];
                }
            }
            held.rot = true;
        }
        if unset(&r.w) && !unset(&m.z) {
            r.w = m.z;
            held.w = true;
        }
        held.steady = held.rot && !held.w && !host_rates;
        if held.rot || held.w {
            self.inputs.rates.any = true;
        }
        held
    }

    /// Whether the coupling stays what it is while the orientation turns at a steady spin: the
    /// rotating-frame terms and centrifugal stiffening see only the body-frame spin (constant,
    /// as (R^T w)' = R^T w~^T w = 0), but translational and flange-load stiffening see loads
    /// that turn in the body frame.
    fn steady_coupling(&self) -> bool {
        match &self.body.stiffening {
            None => true,
            Some(st) => {
                let turning_acceleration = st.translation.is_some()
                    && k3::sub(self.inputs.mount.a, self.inputs.params.g).iter().any(|x| *x != 0.0);
                let loaded = st
                    .flanges
                    .iter()
                    .zip(&self.inputs.loads)
                    .any(|(k, l)| !k.is_empty() && l.f.iter().chain(&l.t).any(|x| *x != 0.0));
                !turning_acceleration && !loaded
            }
        }
    }

    /// The mount groups whose rates were filled from the kinematics end the step where those
    /// kinematics took them: the orientation turned by the step's mean spin (a rotation, where
    /// the linear extrapolation R + h w~ R is not), the spin by z h. Co-simulation masters
    /// (libcosim, Ecos, FMPy) read the outputs after fmi2DoStep, before they set the next
    /// inputs: those are then the state the step produced in the pose at t + h, not one step
    /// late. The host's own values are kept for the next step (`host_mount`), so a host that
    /// holds the mount's pose while giving its spin steps as before.
    fn advance_held_mount(&mut self, held: &HeldMount, h: f64) {
        let driven = self.inputs.host;
        if held.rot {
            if driven.rot_driven {
                let mean = k3::scale(0.5 * h, k3::add(held.mount.w, self.inputs.mount.w));
                self.inputs.mount.rot = k3::mat_mul(&k3::rotation_of(mean), &held.mount.rot);
                self.inputs.host.rot = Some(held.mount.rot);
            } else {
                self.inputs.mount.rot = held.mount.rot;
            }
        }
        if held.w {
            if driven.w_driven {
                self.inputs.host.w = Some(held.mount.w);
            } else {
                self.inputs.mount.w = held.mount.w;
            }
        }
        self.inputs.host.rot_driven = false;
        self.inputs.host.w_driven = false;
    }

    /// After a step with input rates the inputs hold their interpolated end values (what the
    /// host's interpolation says they are at t + h); the rates are used up.
    fn extrapolate_inputs(&mut self, h: f64) {
        let r = &mut self.inputs.rates;
        let m = &mut self.inputs.mount;
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
        for (load, rate) in self.inputs.loads.iter_mut().zip(&r.loads) {
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
    }
}

impl FlexibleBody {
    /// A free-floating body over one step, by substeps short against its rotation
    /// (|W| h_sub <= SUBSTEP_ANGLE) of a second-order (Heun) splitting: the modes propagate exactly under
    /// the coupling load (trapezoidal in time), the rigid motion by the averaged rates, the
    /// attitude by the exact rotation of the mean angular velocity.
    fn step_free(&mut self, work: &mut FreeWork, h: f64) -> Result<(), BodyError> {
        let substeps = self.free_substeps_within_budget(h).map_err(StepError::into_error)?;
        let hs = h / substeps as f64;
        self.stepper.propagator.prepare(
            &self.body.omega,
            self.inputs.params.alpha,
            self.inputs.params.beta,
            &self.body.modal_damping,
            hs,
        );
        self.free_substeps(work, substeps, hs)
    }

    fn free_substeps(&mut self, w: &mut FreeWork, substeps: usize, hs: f64) -> Result<(), BodyError> {
        let n = self.coords.q.len();
        for _ in 0..substeps {
            let start = self.coords.frame.ok_or(BodyError::NotFreeFloating)?;
            w.q0.copy_from_slice(&self.coords.q);
            w.qd0.copy_from_slice(&self.coords.qd);
            // rates at the start, then at the predicted end
            self.derived.invalidate(Change::Coordinates);
            self.evaluate()?;
            let rate0 = self.derived.frame_rate;
            self.coupling_load(&mut w.load0);
            self.advance_free(&start, &rate0, &rate0, &w.load0, hs)?;
            self.derived.invalidate(Change::Coordinates);
            self.evaluate()?;
            let rate1 = self.derived.frame_rate;
            self.coupling_load(&mut w.load1);
            for j in 0..n {
                w.load1[j] = 0.5 * (w.load0[j] + w.load1[j]);
            }
            self.coords.q.copy_from_slice(&w.q0);
            self.coords.qd.copy_from_slice(&w.qd0);
            self.advance_free(&start, &rate0, &rate1, &w.load1, hs)?;
        }
        Ok(())
    }

    /// The part of q'' beyond the modal diagonal at the last evaluation.
    fn coupling_load(&self, out: &mut [f64]) {
        let (alpha, beta) = (self.inputs.params.alpha, self.inputs.params.beta);
        for (j, out) in out.iter_mut().enumerate() {
            let w2 = self.body.omega[j] * self.body.omega[j];
            *out = self.derived.eval.qdd[j]
                + (alpha + beta * w2 + self.body.modal_damping[j]) * self.coords.qd[j]
                + w2 * self.coords.q[j];
        }
    }

    /// From the substep's start frame: rigid motion by the mean of two rate sets, modes exactly
    /// under `load` (q, q' must hold the start values).
    fn advance_free(
        &mut self,
        start: &FrameState,
        a: &FrameState,
        b: &FrameState,
        load: &[f64],
        hs: f64,
    ) -> Result<(), BodyError> {
        self.stepper.propagator.advance(&self.body.omega, load, &mut self.coords.q, &mut self.coords.qd);
        let w_dot = k3::scale(0.5, k3::add(a.w_body, b.w_body));
        let accel = k3::scale(0.5, k3::add(a.v, b.v));
        let f = self.coords.frame.as_mut().ok_or(BodyError::NotFreeFloating)?;
        let w_mid = k3::add(start.w_body, k3::scale(0.5 * hs, w_dot));
        f.w_body = k3::add(start.w_body, k3::scale(hs, w_dot));
        f.v = k3::add(start.v, k3::scale(hs, accel));
        f.r = k3::add(start.r, k3::scale(0.5 * hs, k3::add(start.v, f.v)));
        f.quat = k3::quaternion_multiply(start.quat, k3::quaternion_of(&k3::rotation_of(k3::scale(hs, w_mid))));
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::super::FlexibleBody;
    use crate::reduced::{rotating_two_mode_body, two_mode_body};
    use std::sync::Arc;

    /// A load applied from rest: the dynamic mode answers as the undamped oscillator does,
    /// p / omega^2 (1 - cos omega t) (analytic), and the mode above the cutoff takes its static
    /// response at once, q = p / omega^2, q' = 0, instead of ringing at 2000 rad/s as the exact
    /// step alone would make it; with the cutoff above every mode it rings.
    #[test]
    fn a_load_step_moves_the_quasi_static_mode_statically() {
        let run = |cutoff: f64| {
            let mut reduced = two_mode_body();
            reduced.alpha = 0.0;
            reduced.beta = 0.0;
            reduced.dynamic_cutoff = cutoff;
            let mut b = FlexibleBody::new(Arc::new(reduced));
            b.settle_quasi_static().unwrap();
            b.load_mut(0).f = [0.0, 3.0, -2.0];
            // q = q' = 0: q'' is the modal load
            let p = b.qdd().unwrap().to_vec();
            let h = 1e-3;
            let mut history = Vec::new();
            for _ in 0..7 {
                b.step(h).unwrap();
                history.push((b.q().to_vec(), b.qd().to_vec()));
            }
            (p, history)
        };
        let (p, split) = run(100.0);
        assert_eq!((p.len(), split.len()), (2, 7));
        for (k, (q, qd)) in split.iter().enumerate() {
            let t = (k + 1) as f64 * 1e-3;
            let dynamic = p[0] / 100.0 * (1.0 - (10.0 * t).cos());
            // the exact step is exact for a held load: only its round-off is left
            assert!((q[0] - dynamic).abs() < 1e-12 * (p[0] / 100.0).abs(), "step {k}: {} vs {dynamic}", q[0]);
            assert_eq!((q[1], qd[1]), (p[1] / 4.0e6, 0.0), "step {k}");
        }
        // the exact step alone rings the upper mode about its static value: swing 2 p / omega^2
        let (_, ringing) = run(f64::INFINITY);
        let swing = ringing.iter().map(|(q, _)| q[1]).fold(0.0f64, |m, v| m.max((v - p[1] / 4.0e6).abs()));
        assert!(swing > 0.5 * (p[1] / 4.0e6).abs(), "swing {swing}");
    }

    /// A spin-up saved mid-way continues bit-identically from its state (the reference's
    /// coefficients travel with it); a state without them (written before they were kept)
    /// renews the reference at its next step and continues within the drift correction's
    /// accuracy of the original.
    #[test]
    fn a_state_without_the_reference_coefficients_renews_and_continues() {
        let h = 1e-3;
        let spin = |k: usize| 2.0 + 40.0 * h * k as f64;
        let steps = |b: &mut FlexibleBody, from: usize, count: usize| -> Vec<(Vec<f64>, Vec<f64>)> {
            (from..from + count)
                .map(|k| {
                    b.set_mount_spin(2, spin(k));
                    b.load_mut(0).f = [0.0, 0.0, 1.0];
                    b.step(h).unwrap();
                    (b.q().to_vec(), b.qd().to_vec())
                })
                .collect()
        };
        let mut a = FlexibleBody::new(Arc::new(rotating_two_mode_body()));
        steps(&mut a, 0, 60);
        let saved = a.state();
        let coef = saved.coupling_reference.as_ref().and_then(|r| r.coef.clone());
        assert!(coef.is_some(), "a spin-up keeps its reference's coefficients in its state");
        let expected = steps(&mut a, 60, 200);

        let mut same = a.with_state(saved.clone()).unwrap();
        assert_eq!(steps(&mut same, 60, 200), expected);

        let mut older = saved.clone();
        older.coupling_reference.as_mut().unwrap().coef = None;
        let mut b = a.with_state(older).unwrap();
        let found = steps(&mut b, 60, 200);
        assert!(b.state().coupling_reference.and_then(|r| r.coef).is_some(), "renewed with its coefficients");
        assert_eq!((found.len(), expected.len()), (200, 200));
        let scale = expected.iter().flat_map(|(q, _)| q.iter()).fold(0.0f64, |m, v| m.max(v.abs()));
        let worst = found
            .iter()
            .zip(&expected)
            .flat_map(|((q1, _), (q0, _))| q1.iter().zip(q0).map(|(x, y)| (x - y).abs()))
            .fold(0.0f64, f64::max);
        // measured 4.4e-7 of the largest q (the drift correction's error against a renewal's
        // exact transition); ten times that
        assert!(worst <= 5e-6 * scale, "{:.2e} of the largest q", worst / scale);
    }

    #[test]
    fn a_non_rotation_mount_is_refused_with_its_name() {
        let mut b = FlexibleBody::new(Arc::new(two_mode_body()));
        b.mount_mut().rot = [1.1, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0];
        let e = b.step(0.1).unwrap_err();
        assert!(matches!(&e, super::StepError::Inputs(r) if r.to_string().contains("base.R")), "{e}");
    }
}
