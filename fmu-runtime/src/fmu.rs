//! The body as an FMI model: maps value references onto the mechanics layer and the FMI calls
//! (initialise, step, derivatives) onto its equations. Knows the `fmi2::Model` trait, not C.

use crate::body::{
    BodyState, CouplingReference, FlangeLoad, FlexibleBody, FrameState, InitialFrame, InputRates, MountMotion,
    Parameters, REAL_LIMIT, StepError, SteppedState,
};
use crate::format::RESOURCE_FILE;
use crate::interface::{FlangeOutput, Quantity, VariableTable};
use crate::kinematics as k3;
use crate::reduced::ReducedBody;
use crate::scalar::{Scalar, c};
use fmi2::bytes::{Reader, Writer};
use fmi2::{Causality, Interface, Model, ModelError, VarInfo, VarType};
use std::sync::Arc;

/// Capabilities the model implements; the builder writes them into modelDescription.xml.
pub const PROVIDES_DIRECTIONAL_DERIVATIVE: bool = true;
pub const MAX_OUTPUT_DERIVATIVE_ORDER: i32 = 1;
pub const CAN_INTERPOLATE_INPUTS: bool = true;

#[derive(Debug, Clone)]
pub struct BodyFmu {
    table: Arc<VariableTable>,
    body: FlexibleBody,
    static_start: bool,
    steps: crate::explicit_host::StepWatch,
    /// fmi2SetTime's last value (Model Exchange), for the host's step sizes.
    time: f64,
}

impl BodyFmu {
    /// The model of a reduced body for Co-Simulation (every mode integrated by the exact step).
    pub fn from_reduced(reduced: ReducedBody) -> Self {
        let table = Arc::new(VariableTable::new(&reduced));
        let mut fmu = Self {
            table,
            body: FlexibleBody::new(Arc::new(reduced)),
            static_start: false,
            steps: Default::default(),
            time: 0.0,
        };
        fmu.steps = crate::explicit_host::StepWatch::new(fmu.n_states());
        fmu
    }

    /// The model for `interface`: Model Exchange hands the modes above the cutoff to no
    /// integrator (they are solved at every evaluation); Co-Simulation's exact transition
    /// integrates every mode at any step.
    pub fn for_interface(reduced: ReducedBody, interface: Interface) -> Self {
        let mut fmu = Self::from_reduced(reduced);
        fmu.body.set_quasi_static(interface == Interface::ModelExchange);
        fmu.steps = crate::explicit_host::StepWatch::new(fmu.n_states());
        fmu
    }

    pub fn body(&self) -> &FlexibleBody {
        &self.body
    }

    /// Model Exchange's modal states: q, q' of the dynamic modes and q of the relaxing ones.
    fn n_modal_states(&self) -> usize {
        2 * self.body.n_dynamic() + self.body.n_relaxing()
    }

    /// d/dt of Model Exchange's states: q, q' of the dynamic modes, q of the relaxing ones, a
    /// free body's frame.
    fn state_derivatives(&mut self, dx: &mut [f64]) -> Result<(), String> {
        let (n, nr) = (self.body.n_dynamic(), self.body.n_relaxing());
        let (modal, frame_part) = dx.split_at_mut(2 * n + nr);
        let (dq, rest) = modal.split_at_mut(n);
        let (dqd, dr) = rest.split_at_mut(n);
        self.body.derivatives(dq, dqd)?;
        // a relaxing mode's rate is its q', solved with the evaluation
        dr.copy_from_slice(&self.body.qd()[n..n + nr]);
        if self.body.frame().is_some() {
            let rate = self.body.frame_rate()?;
            write_frame(frame_part, &rate);
        }
        Ok(())
    }

    fn name(&self, vr: u32) -> String {
        self.table.get(vr).map_or_else(|| format!("value reference {vr}"), |v| v.name.clone())
    }

    fn quantity(&self, vr: u32) -> Result<Quantity, String> {
        self.table.get(vr).map(|v| v.quantity).ok_or_else(|| format!("unknown value reference {vr}"))
    }
}

/// Largest reduced-model file read: the largest models we build (hundreds of modes with
/// rotation and stiffening terms, 3 x 3 x r x r each) stay far below it.
const MAX_RESOURCE_BYTES: u64 = 1 << 30;

/// The reduced-model file's bytes: a regular file (a FIFO would block fmi2Instantiate, a link
/// to a device would read without end) of at most [`MAX_RESOURCE_BYTES`].
fn read_resource(path: &std::path::Path) -> Result<Vec<u8>, String> {
    use std::io::Read;
    let meta = std::fs::metadata(path).map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    if !meta.is_file() {
        return Err(format!("{} is not a regular file", path.display()));
    }
    if meta.len() > MAX_RESOURCE_BYTES {
        return Err(format!(
            "{} has {} bytes, more than any reduced model ({MAX_RESOURCE_BYTES} at most)",
            path.display(),
            meta.len()
        ));
    }
    let file = std::fs::File::open(path).map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    // the file may grow between the check and the read: never read past the limit
    let mut bytes = Vec::with_capacity(meta.len() as usize);
    file.take(MAX_RESOURCE_BYTES + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    if bytes.len() as u64 > MAX_RESOURCE_BYTES {
        return Err(format!("{} grew beyond {MAX_RESOURCE_BYTES} bytes while it was read", path.display()));
    }
    Ok(bytes)
}

fn frame<T: Scalar>(b: &FlexibleBody<T>) -> Result<FrameState<T>, String> {
    b.frame().copied().ok_or_else(|| "not a free-floating body".to_string())
}

/// Number of rigid-body states of a free-floating body: position 3, quaternion 4, velocity 3,
/// angular velocity 3.
const FRAME_STATES: usize = 13;

impl Model for BodyFmu {
    fn instantiate(resources: Option<&std::path::Path>, interface: Interface) -> Result<Self, String> {
        let dir =
            resources.ok_or("no resource location given: the reduced body lives in the FMU's resources folder")?;
        let path = dir.join(RESOURCE_FILE);
        let bytes = read_resource(&path)?;
        let reduced = ReducedBody::from_sealed_bytes(&bytes).map_err(|e| format!("{}: {e}", path.display()))?;
        Ok(Self::for_interface(reduced, interface))
    }

    fn guid(&self) -> &str {
        &self.body.reduced().guid
    }

    fn var_info(&self, vr: u32) -> Option<VarInfo> {
        self.table.get(vr).map(|v| VarInfo {
            var_type: v.var_type,
            causality: v.causality,
            variability: v.variability,
            initial: v.initial,
        })
    }

    fn var_name(&self, vr: u32) -> Option<&str> {
        self.table.get(vr).map(|v| v.name.as_str())
    }

    fn get_real(&mut self, vr: u32) -> Result<f64, String> {
        let quantity = self.quantity(vr)?;
        if quantity == Quantity::StaticStart {
            return Err(format!("value reference {vr} (static_start) is a Boolean"));
        }
        value_of(&mut self.body, quantity)
    }

    fn provides_directional_derivative(&self) -> bool {
        PROVIDES_DIRECTIONAL_DERIVATIVE
    }

    /// dv_unknown = (d unknowns / d knowns) dv_known at the present state and inputs, exact:
    /// the body's equations in dual numbers along the direction dv_known.
    fn directional_derivative(
        &mut self,
        unknowns: &[u32],
        knowns: &[u32],
        dv_known: &[f64],
        dv_unknown: &mut [f64],
    ) -> Result<(), String> {
        let mut d = self.body.to_dual();
        for (&vr, &dv) in knowns.iter().zip(dv_known) {
            let quantity = self.quantity(vr)?;
            let x = input_or_state(&mut d, quantity)
                .ok_or_else(|| format!("{} is neither an input nor a continuous state", self.name(vr)))?;
            x.d += dv;
        }
        for (&vr, out) in unknowns.iter().zip(dv_unknown.iter_mut()) {
            *out = value_of(&mut d, self.quantity(vr)?)?.d;
        }
        Ok(())
    }

    /// d/dt of a Real output at the present instant, along the body's own motion: the modes
    /// and a free body's frame move at their rates; the mount moves as its inputs say it does
    /// (r' = v, R' = w~ R, v' = a, w' = z), and a, z and the flange loads change at the rates
    /// fmi2SetRealInputDerivatives set for the next step (zero when none are set: held).
    fn get_real_output_derivative(&mut self, vr: u32, _order: i32) -> Result<f64, String> {
        let quantity = self.quantity(vr)?;
        let mut d = self.body.to_dual();
        let rates = self.body.input_rates().clone();
        let qdd = self.body.qdd()?.to_vec();
        for (j, &qdd) in qdd.iter().enumerate() {
            d.q_mut()[j].d = self.body.qd()[j];
            d.qd_mut()[j].d = qdd;
        }
        if self.body.frame().is_some() {
            let rate = self.body.frame_rate()?;
            let f = d.frame_mut().ok_or("not a free-floating body")?;
            for i in 0..3 {
                f.r[i].d = rate.r[i];
                f.v[i].d = rate.v[i];
                f.w_body[i].d = rate.w_body[i];
            }
            for i in 0..4 {
                f.quat[i].d = rate.quat[i];
            }
        } else {
            let m = *self.body.mount();
            let dm = d.mount_mut();
            // R' = w~ R, row by row: (w x R e_j) per column j
            for j in 0..3 {
                let col = k3::cross(m.w, [m.rot[j], m.rot[3 + j], m.rot[6 + j]]);
                for (i, &rate) in col.iter().enumerate() {
                    dm.rot[3 * i + j].d = rate;
                }
            }
            for i in 0..3 {
                dm.r[i].d = m.v[i];
                dm.v[i].d = m.a[i];
                dm.w[i].d = m.z[i];
                dm.a[i].d = rates.mount.a[i];
                dm.z[i].d = rates.mount.z[i];
            }
        }
        for (k, rate) in rates.loads.iter().enumerate() {
            let l = d.load_mut(k);
            for i in 0..3 {
                l.f[i].d = rate.f[i];
                l.t[i].d = rate.t[i];
            }
        }
        Ok(value_of(&mut d, quantity)?.d)
    }

    /// q, q' of the dynamic modes and a free body's frame (the quasi-static modes are not states).
    fn is_continuous_state(&self, vr: u32) -> bool {
        self.table.get(vr).is_some_and(|v| self.table.is_state(v.quantity))
    }

    /// der(q) = qd, der(r) = v, ... of the states.
    fn is_state_derivative(&self, vr: u32) -> bool {
        self.table.get(vr).is_some_and(|v| v.derivative_of.is_some())
    }

    fn max_output_derivative_order(&self) -> i32 {
        MAX_OUTPUT_DERIVATIVE_ORDER
    }

    fn can_interpolate_inputs(&self) -> bool {
        CAN_INTERPOLATE_INPUTS
    }

    fn set_real_input_derivative(&mut self, vr: u32, value: f64) -> Result<(), String> {
        use Quantity as Q;
        let quantity = self.quantity(vr)?;
        let b = &mut self.body;
        match quantity {
            Q::MountPosition(i) => b.mount_rate_mut().r[i] = value,
            Q::MountRotation(i, j) => b.mount_rate_mut().rot[3 * i + j] = value,
            Q::MountVelocity(i) => b.mount_rate_mut().v[i] = value,
            Q::MountAngularVelocity(i) => b.mount_rate_mut().w[i] = value,
            Q::MountAcceleration(i) => b.mount_rate_mut().a[i] = value,
            Q::MountAngularAcceleration(i) => b.mount_rate_mut().z[i] = value,
            Q::FlangeForce(k, i) => b.load_rate_mut(k).f[i] = value,
            Q::FlangeTorque(k, i) => b.load_rate_mut(k).t[i] = value,
            _ => return Err(format!("value reference {vr} is not an input")),
        }
        Ok(())
    }

    fn admissible_real(&self, vr: u32, value: f64) -> Result<(), String> {
        admissible(self.quantity(vr)?, value)
    }

    /// A rotation matrix is one only as a whole: a call that sets all nine entries of the
    /// mount's orientation hands over a complete matrix, refused here unless it is a rotation
    /// within the tolerance the step and the evaluations use. Set entry by entry, the matrix
    /// passes through non-rotations on its way (from one rotation to the next), so a partial
    /// call is accepted and the whole matrix is checked where it is used: the next evaluation
    /// answers fmi2Discard, the next step refuses its inputs (fmi2Error), each naming base.R, and
    /// the instance stays usable.
    fn admissible_reals(&self, vrs: &[u32], values: &[f64]) -> Result<(), String> {
        let mut rot = self.body.host_rotation();
        let mut set = [false; 9];
        for (&vr, &value) in vrs.iter().zip(values) {
            if let Ok(Quantity::MountRotation(i, j)) = self.quantity(vr) {
                rot[3 * i + j] = value;
                set[3 * i + j] = true;
            }
        }
        if set.iter().all(|s| *s) { self.body.check_rotation(&rot) } else { Ok(()) }
    }

    /// Input derivatives and directional seeds: the range of the values themselves (a rate of
    /// 1e200 turns any step into an overflow).
    fn admissible_direction(&self, _vr: u32, value: f64) -> Result<(), String> {
        if value.abs() > REAL_LIMIT {
            return Err(format!("|{value:e}| is beyond {REAL_LIMIT:e}, the range of any physical rate in SI units"));
        }
        Ok(())
    }

    /// An evaluation changes nothing but caches, so states or inputs it cannot evaluate (a free
    /// body's quaternion of norm 0 or overflowing, a mount orientation off the rotations) are
    /// the host's to change: fmi2Discard in both interfaces, the instance usable.
    fn evaluation_failure(&self, reason: String) -> ModelError {
        ModelError::Discard(reason)
    }

    fn set_real(&mut self, vr: u32, value: f64) -> Result<(), String> {
        use Quantity as Q;
        let name = || self.table.get(vr).map(|v| v.name.clone()).unwrap_or_default();
        // the FMI layer has checked `admissible` (finite, in range) before
        let q = self.quantity(vr)?;
        let b = &mut self.body;
        match q {
            Q::MountPosition(i) => b.mount_mut().r[i] = value,
            Q::MountRotation(i, j) => b.set_mount_rotation(3 * i + j, value),
            Q::MountVelocity(i) => b.mount_mut().v[i] = value,
            Q::MountAngularVelocity(i) => b.set_mount_spin(i, value),
            Q::MountAcceleration(i) => b.mount_mut().a[i] = value,
            Q::MountAngularAcceleration(i) => b.mount_mut().z[i] = value,
            Q::FlangeForce(k, i) => b.load_mut(k).f[i] = value,
            Q::FlangeTorque(k, i) => b.load_mut(k).t[i] = value,
            Q::Gravity(i) => b.parameters_mut().g[i] = value,
            Q::RayleighAlpha => b.parameters_mut().alpha = value,
            Q::RayleighBeta => b.parameters_mut().beta = value,
            Q::ModalCoordinate(j) => b.q_mut()[j] = value,
            Q::ModalVelocity(j) => b.qd_mut()[j] = value,
            Q::InitialPosition(i) => b.initial_frame.r[i] = value,
            Q::InitialRotation(i) => b.initial_frame.phi[i] = value,
            Q::InitialVelocity(i) => b.initial_frame.v[i] = value,
            Q::InitialAngularVelocity(i) => b.initial_frame.w[i] = value,
            _ => return Err(format!("{} cannot be set", name())),
        }
        Ok(())
    }

    fn get_integer(&mut self, vr: u32) -> Result<i32, String> {
        Err(format!("value reference {vr} is not an Integer: this FMU has no Integer variables"))
    }
    fn set_integer(&mut self, vr: u32, _value: i32) -> Result<(), String> {
        Err(format!("value reference {vr} is not an Integer: this FMU has no Integer variables"))
    }

    fn get_boolean(&mut self, vr: u32) -> Result<bool, String> {
        match self.quantity(vr)? {
            Quantity::StaticStart => Ok(self.static_start),
            _ => Err(format!("value reference {vr} is not a Boolean")),
        }
    }
    fn set_boolean(&mut self, vr: u32, value: bool) -> Result<(), String> {
        match self.quantity(vr)? {
            Quantity::StaticStart => {
                self.static_start = value;
                Ok(())
            }
            _ => Err(format!("value reference {vr} is not a Boolean")),
        }
    }

    fn get_string(&mut self, vr: u32) -> Result<String, String> {
        Err(format!("value reference {vr} is not a String: this FMU has no String variables"))
    }
    fn set_string(&mut self, vr: u32, _value: &str) -> Result<(), String> {
        Err(format!("value reference {vr} is not a String: this FMU has no String variables"))
    }

    fn n_states(&self) -> usize {
        self.n_modal_states() + if self.body.frame().is_some() { FRAME_STATES } else { 0 }
    }
    fn n_event_indicators(&self) -> usize {
        0
    }
    fn set_time(&mut self, t: f64) {
        // autonomous: time enters only through the inputs (and the host's steps, `steps`)
        self.time = t;
    }

    // state order: q, q' of the dynamic modes, q of the relaxing modes, a free body's frame
    fn get_continuous_states(&self, x: &mut [f64]) {
        let (n, nr) = (self.body.n_dynamic(), self.body.n_relaxing());
        x[..n].copy_from_slice(&self.body.q()[..n]);
        x[n..2 * n].copy_from_slice(&self.body.qd()[..n]);
        x[2 * n..2 * n + nr].copy_from_slice(&self.body.q()[n..n + nr]);
        if let Some(f) = self.body.frame() {
            write_frame(&mut x[2 * n + nr..], f);
        }
    }

    fn set_continuous_states(&mut self, x: &[f64]) {
        let (n, nr) = (self.body.n_dynamic(), self.body.n_relaxing());
        self.body.set_state(&x[..n], &x[n..2 * n]);
        self.body.set_relaxing(&x[2 * n..2 * n + nr]);
        if let Some(f) = self.body.frame_mut() {
            let y = &x[2 * n + nr..];
            *f = FrameState {
                r: [y[0], y[1], y[2]],
                quat: [y[3], y[4], y[5], y[6]],
                v: [y[7], y[8], y[9]],
                w_body: [y[10], y[11], y[12]],
            };
        }
    }

    fn get_derivatives(&mut self, dx: &mut [f64]) -> Result<(), String> {
        self.state_derivatives(dx)?;
        // the states it was evaluated at, into the watch's own buffer (no allocation)
        let mut x = self.steps.take_state_buffer();
        if x.len() == dx.len() {
            self.get_continuous_states(&mut x);
        }
        self.steps.evaluated(self.time, x, dx);
        Ok(())
    }

    fn tolerance_advice(&self, tolerance: f64) -> Option<String> {
        let p = self.body.parameters();
        let undamped = self.body.reduced().n_undamped_dynamic(p.alpha, p.beta);
        crate::explicit_host::tolerance_advice(self.body.quasi_static(), undamped, tolerance)
    }

    fn completed_integrator_step(&mut self, time: f64) -> Option<String> {
        let p = self.body.parameters();
        let (alpha, beta) = (p.alpha, p.beta);
        let mut x = self.steps.take_state_buffer_now();
        if x.len() == self.n_states() {
            self.get_continuous_states(&mut x);
        }
        self.steps.completed(time, x, self.body.reduced(), alpha, beta)
    }
    fn get_nominals(&self, nominals: &mut [f64]) {
        // the same numbers as modelDescription.xml's `nominal` (one table); a frame state
        // (metres, m/s, quaternion) is of order one
        for (out, v) in nominals.iter_mut().zip(self.table.state_variables()) {
            *out = v.nominal.unwrap_or(1.0);
        }
    }

    fn get_event_indicators(&mut self, _z: &mut [f64]) -> Result<(), String> {
        Ok(())
    }

    fn enter_initialization(&mut self, _start_time: f64) -> Result<(), String> {
        self.body.start_frame();
        Ok(())
    }

    fn exit_initialization(&mut self) -> Result<(), String> {
        self.body.start_frame();
        self.body.start_stepping();
        if self.static_start {
            self.body.settle_static()?;
        }
        self.body.settle_quasi_static()?;
        // surface bad inputs (a non-rotation base.R) at initialisation, not at the first step
        self.body.qdd().map(|_| ())
    }

    fn do_step(&mut self, t: f64, h: f64) -> Result<(), String> {
        self.try_step(t, h).map_err(|e| match e {
            ModelError::Failed(r) | ModelError::Discard(r) | ModelError::Refused(r) => r,
        })
    }

    /// A step not taken leaves the body as before it (`FlexibleBody::step`): refused inputs
    /// are the host's to correct, anything else a step to retry shorter.
    fn try_step(&mut self, _t: f64, h: f64) -> Result<(), ModelError> {
        self.body.step(h).map_err(|e| match e {
            StepError::Inputs(r) => ModelError::Refused(r),
            StepError::NotTaken(r) => ModelError::Discard(r),
        })
    }

    fn take_warning(&mut self) -> Option<&'static str> {
        self.body.take_warning()
    }

    fn reset(&mut self) -> Result<(), String> {
        let reduced = self.body.reduced().clone();
        let quasi_static = self.body.quasi_static();
        *self = Self::from_reduced(reduced);
        self.body.set_quasi_static(quasi_static);
        Ok(())
    }

    fn save_state(&self, out: &mut Vec<u8>) {
        let s = self.body.state();
        let mut w = Writer::new(out);
        w.u32(BODY_STATE_VERSION);
        w.u32(s.q.len() as u32);
        w.u32(s.loads.len() as u32);
        w.bool(s.frame.is_some());
        w.bool(self.static_start);
        let m = &s.mount;
        for v in [&m.r[..], &m.rot, &m.v, &m.w, &m.a, &m.z] {
            w.f64s(v);
        }
        write_loads(&mut w, &s.loads);
        write_parameters(&mut w, &s.params);
        w.f64s(&s.q);
        w.f64s(&s.qd);
        let i = &s.initial_frame;
        for v in [&i.r, &i.phi, &i.v, &i.w] {
            w.f64s(v);
        }
        if let Some(f) = &s.frame {
            write_frame_state(&mut w, f);
        }
        let rm = &s.rates.mount;
        w.bool(s.rates.any);
        for v in [&rm.r[..], &rm.rot, &rm.v, &rm.w, &rm.a, &rm.z] {
            w.f64s(v);
        }
        write_loads(&mut w, &s.rates.loads);
        w.bool(s.coupling_reference.is_some());
        if let Some(c) = &s.coupling_reference {
            w.f64(c.h);
            w.f64(c.alpha);
            w.f64(c.beta);
            w.f64s(&c.c_d);
            w.f64s(&c.c_k);
        }
        w.bool(s.stepped_inputs.is_some());
        if let Some(st) = &s.stepped_inputs {
            w.f64s(&st.a);
            w.f64s(&st.z);
            write_loads(&mut w, &st.loads);
            write_parameters(&mut w, &st.params);
        }
    }

    fn load_state(&mut self, bytes: &[u8]) -> Result<(), String> {
        let mut r = Reader::new(bytes);
        let version = r.u32("body state version")?;
        if version > BODY_STATE_VERSION {
            return Err(format!(
                "body state version {version} was written by a newer runtime (this one reads up to {BODY_STATE_VERSION})"
            ));
        }
        if version == 0 {
            return Err("body state version 0 is invalid".into());
        }
        let n = r.u32("number of modes")? as usize;
        let nf = r.u32("number of force flanges")? as usize;
        let free = r.bool("free-floating flag")?;
        let static_start = r.bool("static_start")?;
        // sizes first: the bytes must describe this body before anything is read by them
        let (n_body, nf_body, free_body) = (self.body.n_modes(), self.body.loads().len(), self.body.frame().is_some());
        if (n, nf, free) != (n_body, nf_body, free_body) {
            return Err(format!(
                "the state is of a body with {n} modes, {nf} force flanges{}; this one has {n_body}, {nf_body}{}",
                if free { ", free-floating" } else { "" },
                if free_body { ", free-floating" } else { "" },
            ));
        }
        let mount = MountMotion {
            r: r.f64_array("mount r")?,
            rot: r.f64_array("mount R")?,
            v: r.f64_array("mount v")?,
            w: r.f64_array("mount w")?,
            a: r.f64_array("mount a")?,
            z: r.f64_array("mount z")?,
        };
        let mut loads = Vec::with_capacity(nf);
        for _ in 0..nf {
            loads.push(FlangeLoad { f: r.f64_array("flange force")?, t: r.f64_array("flange torque")? });
        }
        let params = Parameters { g: r.f64_array("g")?, alpha: r.f64("damping.alpha")?, beta: r.f64("damping.beta")? };
        let mut q = vec![0.0; n];
        r.f64s_into(&mut q, "q")?;
        let mut qd = vec![0.0; n];
        r.f64s_into(&mut qd, "qd")?;
        let initial_frame = InitialFrame {
            r: r.f64_array("initial.r")?,
            phi: r.f64_array("initial.phi")?,
            v: r.f64_array("initial.v")?,
            w: r.f64_array("initial.w")?,
        };
        let frame = if free { Some(read_frame_state(&mut r)?) } else { None };
        let any = r.bool("input rates flag")?;
        let rate_mount = MountMotion {
            r: r.f64_array("mount r rate")?,
            rot: r.f64_array("mount R rate")?,
            v: r.f64_array("mount v rate")?,
            w: r.f64_array("mount w rate")?,
            a: r.f64_array("mount a rate")?,
            z: r.f64_array("mount z rate")?,
        };
        let mut rate_loads = Vec::with_capacity(nf);
        for _ in 0..nf {
            rate_loads.push(FlangeLoad { f: r.f64_array("flange force rate")?, t: r.f64_array("flange torque rate")? });
        }
        let coupling_reference = if version >= 2 && r.bool("coupling reference flag")? {
            let (h, alpha, beta) =
                (r.f64("coupling reference h")?, r.f64("coupling reference alpha")?, r.f64("coupling reference beta")?);
            let mut c_d = vec![0.0; n * n];
            r.f64s_into(&mut c_d, "coupling reference C_d")?;
            let mut c_k = vec![0.0; n * n];
            r.f64s_into(&mut c_k, "coupling reference C_k")?;
            Some(CouplingReference { h, alpha, beta, c_d, c_k })
        } else {
            None
        };
        let stepped_inputs = if version >= 3 && r.bool("stepped inputs flag")? {
            let (a, z) = (r.f64_array("stepped mount a")?, r.f64_array("stepped mount z")?);
            let mut loads = Vec::with_capacity(nf);
            for _ in 0..nf {
                loads.push(FlangeLoad { f: r.f64_array("stepped force")?, t: r.f64_array("stepped torque")? });
            }
            let params = Parameters {
                g: r.f64_array("stepped g")?,
                alpha: r.f64("stepped damping.alpha")?,
                beta: r.f64("stepped damping.beta")?,
            };
            Some(SteppedState { a, z, loads, params })
        } else {
            None
        };
        r.finish("body state")?;
        let rates = InputRates { mount: rate_mount, loads: rate_loads, any };
        let state =
            BodyState { mount, loads, params, q, qd, frame, initial_frame, rates, coupling_reference, stepped_inputs };
        self.body = self.body.with_state(state)?;
        self.static_start = static_start;
        // what the host can set, restored from bytes, obeys the rule fmi2SetReal applies
        for v in self.table.variables.iter().filter(|v| matches!(v.causality, Causality::Input | Causality::Parameter))
        {
            if v.var_type == VarType::Real {
                let value = value_of(&mut self.body, v.quantity)?;
                admissible(v.quantity, value).map_err(|e| format!("{} = {value}: {e}", v.name))?;
            }
        }
        Ok(())
    }
}

/// Whether `value` is in the physical range of `quantity` (the host's values are finite: the
/// FMI layer has checked).
fn admissible(quantity: Quantity, value: f64) -> Result<(), String> {
    use Quantity as Q;
    if !value.is_finite() {
        return Err(format!("{value} is not a finite number"));
    }
    if value.abs() > REAL_LIMIT {
        return Err(format!("|{value:e}| is beyond {REAL_LIMIT:e}, the range of any physical quantity in SI units"));
    }
    match quantity {
        Q::RayleighAlpha | Q::RayleighBeta if value < 0.0 => {
            Err(format!("{value} is negative: damping must not feed energy into the body"))
        }
        // an entry of a rotation matrix: |R_ij| <= 1 (rounding leaves far less than 1e-6)
        Q::MountRotation(..) if value.abs() > 1.0 + 1e-6 => {
            Err(format!("{value} is no entry of a rotation matrix (each lies in [-1, 1])"))
        }
        _ => Ok(()),
    }
}

/// A Real variable's value, in f64 for fmi2GetReal or in dual numbers for its derivatives: the
/// one place that says which variable is which result of the body.
fn value_of<T: Scalar>(b: &mut FlexibleBody<T>, quantity: Quantity) -> Result<T, String> {
    use Quantity as Q;
    Ok(match quantity {
        Q::MountPosition(i) => b.mount().r[i],
        Q::MountRotation(i, j) => b.mount().rot[3 * i + j],
        Q::MountVelocity(i) => b.mount().v[i],
        Q::MountAngularVelocity(i) => b.mount().w[i],
        Q::MountAcceleration(i) => b.mount().a[i],
        Q::MountAngularAcceleration(i) => b.mount().z[i],
        Q::MountForce(i) => b.mount_reaction()?.0[i],
        Q::MountTorque(i) => b.mount_reaction()?.1[i],
        Q::FlangeForce(k, i) => b.loads()[k].f[i],
        Q::FlangeTorque(k, i) => b.loads()[k].t[i],
        Q::Flange(k, o) => {
            let m = b.flange_motion(k)?;
            match o {
                FlangeOutput::Position(i) => m.r[i],
                FlangeOutput::Rotation(i, j) => m.rot[3 * i + j],
                FlangeOutput::Velocity(i) => m.v[i],
                FlangeOutput::AngularVelocity(i) => m.w[i],
                FlangeOutput::Acceleration(i) => m.a[i],
                FlangeOutput::AngularAcceleration(i) => m.z[i],
                FlangeOutput::Displacement(i) => m.u[i],
                FlangeOutput::RotationVector(i) => m.phi[i],
            }
        }
        Q::Stress(k, i) => b.stress(k, i)?,
        Q::Gravity(i) => c(b.parameters().g[i]),
        Q::RayleighAlpha => c(b.parameters().alpha),
        Q::RayleighBeta => c(b.parameters().beta),
        Q::ModalCoordinate(j) => b.q()[j],
        Q::ModalVelocity(j) => b.qd()[j],
        Q::ModalAcceleration(j) => b.qdd()?[j],
        Q::StaticStart => return Err("static_start is a Boolean".into()),
        Q::InitialPosition(i) => c(b.initial_frame.r[i]),
        Q::InitialRotation(i) => c(b.initial_frame.phi[i]),
        Q::InitialVelocity(i) => c(b.initial_frame.v[i]),
        Q::InitialAngularVelocity(i) => c(b.initial_frame.w[i]),
        Q::FramePosition(i) => frame(b)?.r[i],
        Q::FrameQuaternion(i) => frame(b)?.quat[i],
        Q::FrameVelocity(i) => frame(b)?.v[i],
        Q::FrameAngularVelocity(i) => frame(b)?.w_body[i],
        Q::FrameQuaternionRate(i) => b.frame_rate()?.quat[i],
        Q::FrameAcceleration(i) => b.frame_rate()?.v[i],
        Q::FrameAngularAcceleration(i) => b.frame_rate()?.w_body[i],
        Q::BodyRotation(i, j) => {
            b.frame_rate()?;
            b.mount().rot[3 * i + j]
        }
        Q::BodyAngularVelocity(i) => {
            b.frame_rate()?;
            b.mount().w[i]
        }
        Q::BodyAngularAcceleration(i) => {
            b.frame_rate()?;
            b.mount().z[i]
        }
        Q::BodyEnergy => b.invariants()?.energy,
        Q::BodyMomentum(i) => b.invariants()?.momentum[i],
        Q::BodyAngularMomentum(i) => b.invariants()?.angular_momentum[i],
    })
}

/// The input or continuous state a variable is, to seed a derivative's direction (None for
/// anything else).
fn input_or_state<T: Scalar>(b: &mut FlexibleBody<T>, quantity: Quantity) -> Option<&mut T> {
    use Quantity as Q;
    Some(match quantity {
        Q::MountPosition(i) => &mut b.mount_mut().r[i],
        Q::MountRotation(i, j) => &mut b.mount_mut().rot[3 * i + j],
        Q::MountVelocity(i) => &mut b.mount_mut().v[i],
        Q::MountAngularVelocity(i) => &mut b.mount_mut().w[i],
        Q::MountAcceleration(i) => &mut b.mount_mut().a[i],
        Q::MountAngularAcceleration(i) => &mut b.mount_mut().z[i],
        Q::FlangeForce(k, i) => &mut b.load_mut(k).f[i],
        Q::FlangeTorque(k, i) => &mut b.load_mut(k).t[i],
        Q::ModalCoordinate(j) => &mut b.q_mut()[j],
        Q::ModalVelocity(j) => &mut b.qd_mut()[j],
        Q::FramePosition(i) => &mut b.frame_mut()?.r[i],
        Q::FrameQuaternion(i) => &mut b.frame_mut()?.quat[i],
        Q::FrameVelocity(i) => &mut b.frame_mut()?.v[i],
        Q::FrameAngularVelocity(i) => &mut b.frame_mut()?.w_body[i],
        _ => return None,
    })
}

/// Version of the body's part of a serialized FMU state (the layer has its own).
/// Layout, little-endian: version (u32), modes n (u32), force flanges m (u32), free-floating
/// (u8 0/1), static_start (u8 0/1), then f64s: mount r[3] R[9] (row-major) v[3] w[3] a[3] z[3];
/// per force flange f[3] t[3]; g[3], alpha, beta; q[n]; qd[n]; initial r[3] phi[3] v[3] w[3];
/// free-floating only: frame r[3] quaternion[4] v[3] W[3]; then the input derivatives set for
/// the next step: flag (u8 0/1), mount rates r[3] R[9] v[3] w[3] a[3] z[3], per force flange
/// f[3] t[3]; since version 2 the coupled transition's reference: flag (u8), then h, alpha,
/// beta, C_d[n*n], C_k[n*n]; since version 3 the loads the last step ended with: flag (u8),
/// then mount a[3] z[3], per force flange f[3] t[3], g[3], alpha, beta.
/// Sizes are checked against the body before any array is read.
pub const BODY_STATE_VERSION: u32 = 3;

/// Force and torque of every force flange, in flange order.
fn write_loads(w: &mut Writer, loads: &[FlangeLoad]) {
    for l in loads {
        w.f64s(&l.f);
        w.f64s(&l.t);
    }
}

fn write_parameters(w: &mut Writer, p: &Parameters) {
    w.f64s(&p.g);
    w.f64(p.alpha);
    w.f64(p.beta);
}

fn write_frame_state(w: &mut Writer, f: &FrameState) {
    w.f64s(&f.r);
    w.f64s(&f.quat);
    w.f64s(&f.v);
    w.f64s(&f.w_body);
}

fn read_frame_state(r: &mut Reader) -> Result<FrameState, String> {
    Ok(FrameState {
        r: r.f64_array("frame r")?,
        quat: r.f64_array("frame quaternion")?,
        v: r.f64_array("frame v")?,
        w_body: r.f64_array("frame W")?,
    })
}

fn write_frame(x: &mut [f64], f: &FrameState) {
    x[..3].copy_from_slice(&f.r);
    x[3..7].copy_from_slice(&f.quat);
    x[7..10].copy_from_slice(&f.v);
    x[10..13].copy_from_slice(&f.w_body);
}
