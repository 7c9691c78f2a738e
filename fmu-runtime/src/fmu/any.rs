//! The model the FMU's binary exports: a body or an assembly, whichever the FMU's resources hold
//! (one binary serves both, so the builder embeds one runtime).

use super::BodyFmu;
use super::assembly::AssemblyFmu;
use crate::assembly::description::ASSEMBLY_FILE;
use fmi2::bytes::DecodeError;
use fmi2::{Interface, Model, ModelError, VarInfo};

#[derive(Debug, Clone)]
pub enum AnyFmu {
    Body(Box<BodyFmu>),
    Assembly(Box<AssemblyFmu>),
}

/// The same call on whichever model this is.
macro_rules! each {
    ($self:ident, $m:ident => $e:expr) => {
        match $self {
            AnyFmu::Body($m) => $e,
            AnyFmu::Assembly($m) => $e,
        }
    };
}

impl Model for AnyFmu {
    fn instantiate(resources: Option<&std::path::Path>, interface: Interface) -> Result<Self, ModelError> {
        if resources.is_some_and(|dir| dir.join(ASSEMBLY_FILE).exists()) {
            return AssemblyFmu::instantiate(resources, interface).map(|a| AnyFmu::Assembly(Box::new(a)));
        }
        BodyFmu::instantiate(resources, interface).map(|b| AnyFmu::Body(Box::new(b)))
    }
    fn guid(&self) -> &str {
        each!(self, m => m.guid())
    }
    fn var_info(&self, vr: u32) -> Option<VarInfo> {
        each!(self, m => m.var_info(vr))
    }
    fn var_name(&self, vr: u32) -> Option<&str> {
        each!(self, m => m.var_name(vr))
    }
    fn get_real(&mut self, vr: u32) -> Result<f64, ModelError> {
        each!(self, m => m.get_real(vr))
    }
    fn admissible_real(&self, vr: u32, value: f64) -> Result<(), ModelError> {
        each!(self, m => m.admissible_real(vr, value))
    }
    fn admissible_reals(&self, vrs: &[u32], values: &[f64]) -> Result<(), ModelError> {
        each!(self, m => m.admissible_reals(vrs, values))
    }
    fn admissible_direction(&self, vr: u32, value: f64) -> Result<(), ModelError> {
        each!(self, m => m.admissible_direction(vr, value))
    }
    fn set_real(&mut self, vr: u32, value: f64) -> Result<(), ModelError> {
        each!(self, m => m.set_real(vr, value))
    }
    fn get_integer(&mut self, vr: u32) -> Result<i32, ModelError> {
        each!(self, m => m.get_integer(vr))
    }
    fn set_integer(&mut self, vr: u32, value: i32) -> Result<(), ModelError> {
        each!(self, m => m.set_integer(vr, value))
    }
    fn get_boolean(&mut self, vr: u32) -> Result<bool, ModelError> {
        each!(self, m => m.get_boolean(vr))
    }
    fn set_boolean(&mut self, vr: u32, value: bool) -> Result<(), ModelError> {
        each!(self, m => m.set_boolean(vr, value))
    }
    fn get_string(&mut self, vr: u32) -> Result<String, ModelError> {
        each!(self, m => m.get_string(vr))
    }
    fn set_string(&mut self, vr: u32, value: &str) -> Result<(), ModelError> {
        each!(self, m => m.set_string(vr, value))
    }
    fn n_states(&self) -> usize {
        each!(self, m => m.n_states())
    }
    fn n_event_indicators(&self) -> usize {
        each!(self, m => m.n_event_indicators())
    }
    fn set_time(&mut self, t: f64) {
        each!(self, m => m.set_time(t))
    }
    fn get_continuous_states(&self, x: &mut [f64]) {
        each!(self, m => m.get_continuous_states(x))
    }
    fn set_continuous_states(&mut self, x: &[f64]) {
        each!(self, m => m.set_continuous_states(x))
    }
    fn get_derivatives(&mut self, dx: &mut [f64]) -> Result<(), ModelError> {
        each!(self, m => m.get_derivatives(dx))
    }
    fn get_nominals(&self, nominals: &mut [f64]) {
        each!(self, m => m.get_nominals(nominals))
    }
    fn get_event_indicators(&mut self, z: &mut [f64]) -> Result<(), ModelError> {
        each!(self, m => m.get_event_indicators(z))
    }
    fn enter_initialization(&mut self, start_time: f64) -> Result<(), ModelError> {
        each!(self, m => m.enter_initialization(start_time))
    }
    fn exit_initialization(&mut self) -> Result<(), ModelError> {
        each!(self, m => m.exit_initialization())
    }
    fn can_interpolate_inputs(&self) -> bool {
        each!(self, m => m.can_interpolate_inputs())
    }
    fn set_real_input_derivative(&mut self, vr: u32, value: f64) -> Result<(), ModelError> {
        each!(self, m => m.set_real_input_derivative(vr, value))
    }
    fn provides_directional_derivative(&self) -> bool {
        each!(self, m => m.provides_directional_derivative())
    }
    fn is_continuous_state(&self, vr: u32) -> bool {
        each!(self, m => m.is_continuous_state(vr))
    }
    fn is_state_derivative(&self, vr: u32) -> bool {
        each!(self, m => m.is_state_derivative(vr))
    }
    fn directional_derivative(
        &mut self,
        unknowns: &[u32],
        knowns: &[u32],
        dv_known: &[f64],
        dv_unknown: &mut [f64],
    ) -> Result<(), ModelError> {
        each!(self, m => m.directional_derivative(unknowns, knowns, dv_known, dv_unknown))
    }
    fn max_output_derivative_order(&self) -> i32 {
        each!(self, m => m.max_output_derivative_order())
    }
    fn get_real_output_derivative(&mut self, vr: u32, order: i32) -> Result<f64, ModelError> {
        each!(self, m => m.get_real_output_derivative(vr, order))
    }
    fn tolerance_advice(&self, tolerance: f64) -> Option<String> {
        each!(self, m => m.tolerance_advice(tolerance))
    }

    fn unstated_tolerance_advice(&self) -> Option<String> {
        each!(self, m => m.unstated_tolerance_advice())
    }
    fn completed_integrator_step(&mut self, time: f64) -> Option<String> {
        each!(self, m => m.completed_integrator_step(time))
    }
    fn do_step(&mut self, t: f64, h: f64) -> Result<(), ModelError> {
        each!(self, m => m.do_step(t, h))
    }
    fn take_warning(&mut self) -> Option<&'static str> {
        each!(self, m => m.take_warning())
    }
    fn reset(&mut self) -> Result<(), ModelError> {
        each!(self, m => m.reset())
    }
    fn save_state(&self, out: &mut Vec<u8>) {
        each!(self, m => m.save_state(out))
    }
    fn load_state(&mut self, bytes: &[u8]) -> Result<(), DecodeError> {
        each!(self, m => m.load_state(bytes))
    }
}
