//! The body as an FMI model: maps value references onto the mechanics layer and the FMI calls
//! (initialise, step, derivatives) onto its equations. Knows the `fmi2::Model` trait, not C.
//! `model` answers each call, `values` the variables' values through their families,
//! `continuous_states` Model Exchange's state vector, `state_serialization` the saved states,
//! `resource` the reduced-model file, `error` why a variable's access fails.

pub mod any;
pub mod assembly;
mod continuous_states;
mod error;
mod model;
mod resource;
mod state_serialization;
mod values;

pub use error::VariableError;
pub use resource::LoadError;
pub use state_serialization::{BODY_STATE_VERSION, BodyStateError};

use crate::body::FlexibleBody;
use crate::interface::{Quantity, VariableTable};
use crate::reduced::ReducedBody;
use fmi2::{Interface, Model};
use std::sync::Arc;

/// Capabilities the model implements; the builder writes them into modelDescription.xml.
pub const PROVIDES_DIRECTIONAL_DERIVATIVE: bool = true;
pub const MAX_OUTPUT_DERIVATIVE_ORDER: i32 = 1;
pub const CAN_INTERPOLATE_INPUTS: bool = true;

/// Number of rigid-body states of a free-floating body: position 3, quaternion 4, velocity 3,
/// angular velocity 3.
const FRAME_STATES: usize = 13;

#[derive(Debug, Clone)]
pub struct BodyFmu {
    table: Arc<VariableTable>,
    body: FlexibleBody,
    static_start: bool,
    steps: crate::explicit_host::StepWatch,
    /// fmi2SetTime's last value (Model Exchange), for the host's step sizes.
    time: f64,
    /// Between fmi2EnterInitializationMode and fmi2ExitInitializationMode: a free body's
    /// `initial.*` set then moves its frame at once, so that what the host reads in that mode
    /// (values, derivatives, directional derivatives) starts from them as the run will.
    initializing: bool,
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
            initializing: false,
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

    fn name(&self, vr: u32) -> String {
        self.table.get(vr).map_or_else(|| format!("value reference {vr}"), |v| v.name.clone())
    }

    fn quantity(&self, vr: u32) -> Result<Quantity, VariableError> {
        self.table.get(vr).map(|v| v.quantity).ok_or(VariableError::Unknown(vr))
    }
}
