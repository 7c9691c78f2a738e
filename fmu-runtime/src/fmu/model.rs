//! `fmi2::Model` for the body: each FMI call onto the part of `BodyFmu` that answers it, and
//! each failure classified for the FMI layer (`ModelError`): an evaluation that cannot be made
//! at the host's states or inputs is theirs to change (Discard), a value out of range is refused
//! before anything is set (Refused), a step not taken is Discard or, for refused inputs, Refused;
//! anything else leaves the model's state unknown (Failed).

use super::error::VariableError;
use super::resource::load_resource;
use super::values::admissible;
use super::{
    BodyFmu, CAN_INTERPOLATE_INPUTS, FRAME_STATES, MAX_OUTPUT_DERIVATIVE_ORDER, PROVIDES_DIRECTIONAL_DERIVATIVE,
};
use crate::body::{OutOfRange, REAL_LIMIT, StepError};
use crate::format::RESOURCE_FILE;
use crate::reduced::ReducedBody;
use fmi2::bytes::DecodeError;
use fmi2::{Interface, Model, ModelError, VarInfo};

/// An evaluation changes nothing but caches, so states or inputs it cannot evaluate (a free
/// body's quaternion of norm 0 or overflowing, a mount orientation off the rotations) are the
/// host's to change: fmi2Discard in both interfaces, the instance usable.
fn evaluation(e: impl Into<VariableError>) -> ModelError {
    ModelError::discard(e.into())
}

impl Model for BodyFmu {
    fn instantiate(resources: Option<&std::path::Path>, interface: Interface) -> Result<Self, ModelError> {
        let reduced = load_resource(resources, RESOURCE_FILE, ReducedBody::from_sealed_bytes)?;
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

    fn get_real(&mut self, vr: u32) -> Result<f64, ModelError> {
        self.real(vr).map_err(evaluation)
    }

    fn provides_directional_derivative(&self) -> bool {
        PROVIDES_DIRECTIONAL_DERIVATIVE
    }

    fn directional_derivative(
        &mut self,
        unknowns: &[u32],
        knowns: &[u32],
        dv_known: &[f64],
        dv_unknown: &mut [f64],
    ) -> Result<(), ModelError> {
        self.directional(unknowns, knowns, dv_known, dv_unknown).map_err(evaluation)
    }

    fn get_real_output_derivative(&mut self, vr: u32, _order: i32) -> Result<f64, ModelError> {
        self.output_derivative(vr).map_err(evaluation)
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

    fn set_real_input_derivative(&mut self, vr: u32, value: f64) -> Result<(), ModelError> {
        self.set_input_rate(vr, value).map_err(ModelError::failed)
    }

    fn admissible_real(&self, vr: u32, value: f64) -> Result<(), ModelError> {
        let quantity = self.quantity(vr).map_err(ModelError::refused)?;
        admissible(quantity, value).map_err(ModelError::refused)
    }

    fn admissible_reals(&self, vrs: &[u32], values: &[f64]) -> Result<(), ModelError> {
        self.admissible_rotation(vrs, values).map_err(ModelError::refused)
    }

    /// Input derivatives and directional seeds: the range of the values themselves (a rate of
    /// 1e200 turns any step into an overflow).
    fn admissible_direction(&self, _vr: u32, value: f64) -> Result<(), ModelError> {
        if value.abs() > REAL_LIMIT {
            return Err(ModelError::refused(OutOfRange::RateBeyond(value)));
        }
        Ok(())
    }

    fn set_real(&mut self, vr: u32, value: f64) -> Result<(), ModelError> {
        self.set_value(vr, value).map_err(ModelError::failed)?;
        // after initialisation the frame evolves on its own and `initial.*` no longer moves it
        if self.initializing && self.quantity(vr).is_ok_and(|q| q.role().is_some_and(|r| r.is_initial_frame())) {
            self.body.start_frame();
        }
        Ok(())
    }

    fn get_integer(&mut self, vr: u32) -> Result<i32, ModelError> {
        Err(ModelError::failed(VariableError::NoIntegers(vr)))
    }
    fn set_integer(&mut self, vr: u32, _value: i32) -> Result<(), ModelError> {
        Err(ModelError::failed(VariableError::NoIntegers(vr)))
    }

    fn get_boolean(&mut self, vr: u32) -> Result<bool, ModelError> {
        self.switch(vr).map_err(ModelError::failed)
    }
    fn set_boolean(&mut self, vr: u32, value: bool) -> Result<(), ModelError> {
        self.set_switch(vr, value).map_err(ModelError::failed)
    }

    fn get_string(&mut self, vr: u32) -> Result<String, ModelError> {
        Err(ModelError::failed(VariableError::NoStrings(vr)))
    }
    fn set_string(&mut self, vr: u32, _value: &str) -> Result<(), ModelError> {
        Err(ModelError::failed(VariableError::NoStrings(vr)))
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
        self.continuous_states(x)
    }

    fn set_continuous_states(&mut self, x: &[f64]) {
        self.set_states(x)
    }

    fn get_derivatives(&mut self, dx: &mut [f64]) -> Result<(), ModelError> {
        self.state_derivatives(dx).map_err(evaluation)?;
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

    fn unstated_tolerance_advice(&self) -> Option<String> {
        let p = self.body.parameters();
        let undamped = self.body.reduced().n_undamped_dynamic(p.alpha, p.beta);
        crate::explicit_host::unstated_tolerance_advice(self.body.quasi_static(), undamped)
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

    fn get_event_indicators(&mut self, _z: &mut [f64]) -> Result<(), ModelError> {
        Ok(())
    }

    fn enter_initialization(&mut self, _start_time: f64) -> Result<(), ModelError> {
        self.body.start_frame();
        self.initializing = true;
        Ok(())
    }

    fn exit_initialization(&mut self) -> Result<(), ModelError> {
        self.initializing = false;
        self.body.start_frame();
        self.body.start_stepping();
        if self.static_start {
            self.body.settle_static().map_err(ModelError::failed)?;
        }
        self.body.settle_quasi_static().map_err(ModelError::failed)?;
        // surface bad inputs (a non-rotation base.R) at initialisation, not at the first step
        self.body.qdd().map(|_| ()).map_err(ModelError::failed)
    }

    /// A step not taken leaves the body as before it (`FlexibleBody::step`): refused inputs
    /// are the host's to correct, anything else a step to retry shorter.
    fn do_step(&mut self, _t: f64, h: f64) -> Result<(), ModelError> {
        self.body.step(h).map_err(|e| match e {
            StepError::Inputs(e) => ModelError::refused(e),
            StepError::NotTaken(e) => ModelError::discard(e),
        })
    }

    fn take_warning(&mut self) -> Option<&'static str> {
        self.body.take_warning()
    }

    fn reset(&mut self) -> Result<(), ModelError> {
        let reduced = self.body.reduced().clone();
        let quasi_static = self.body.quasi_static();
        *self = Self::from_reduced(reduced);
        self.body.set_quasi_static(quasi_static);
        Ok(())
    }

    fn save_state(&self, out: &mut Vec<u8>) {
        self.write_state(out)
    }

    fn load_state(&mut self, bytes: &[u8]) -> Result<(), DecodeError> {
        self.read_state(bytes)
    }
}
