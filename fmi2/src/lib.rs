//! Generic FMI 2.0 C-ABI layer, the counterpart of the Reference-FMUs' `fmi2Functions.c`.
//!
//! Knows the FMI standard (calling sequence, argument checks, logging, FMU states)
//! and nothing of the model: a model plugs in by implementing [`Model`], and the crate that
//! builds the FMU's binary invokes `fmi2::export_fmi2!(path::To::Model)` at its root, which
//! emits the 44 `fmi2*` symbols.
//!
//! Files: `types` (C types of the headers), `logger` (host logger callback),
//! `state` (state machine tables), `access` (which variables may be set when),
//! `resource` (fmuResourceLocation URI), `instance` (the fmi2Component),
//! `serial` and `bytes` (serialized FMU states), `api` (generic implementations),
//! `export` (the macro), `tests` (the layer's tests against a mock model).

pub mod access;
pub mod api;
pub mod bytes;
mod export;
pub mod instance;
pub mod logger;
pub mod resource;
pub mod serial;
pub mod state;
pub mod types;

#[cfg(test)]
mod tests;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Causality {
    Parameter,
    CalculatedParameter,
    Input,
    Output,
    Local,
    Independent,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Variability {
    Constant,
    Fixed,
    Tunable,
    Discrete,
    Continuous,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Initial {
    Exact,
    Approx,
    Calculated,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VarType {
    Real,
    Integer,
    Boolean,
    String,
}

/// Attributes of a variable as in modelDescription.xml. `initial: None` means the
/// attribute is absent and the standard's default applies (see `access::effective_initial`).
#[derive(Clone, Copy, Debug)]
pub struct VarInfo {
    pub var_type: VarType,
    pub causality: Causality,
    pub variability: Variability,
    pub initial: Option<Initial>,
}

/// A model's own error, kept as the source of a [`ModelError`]: the layer logs its text, a
/// caller may downcast it to the model's type.
pub type Reason = Box<dyn std::error::Error + Send + Sync + 'static>;

/// Why a model method failed: what becomes of the instance follows from the variant, the
/// message (logged by the layer) from the model's error it carries.
#[derive(Debug)]
pub enum ModelError {
    /// The model's state is unknown: the instance enters the FMI Error state.
    Failed(Reason),
    /// The model cannot evaluate (or step from) the present states and inputs and changed
    /// nothing: fmi2Discard, the instance stays usable. Model Exchange: the host may retry with
    /// other states (a smaller integrator step). Co-Simulation: a step answered so was not taken
    /// (fmi2LastSuccessfulTime stays at its start); the slave is in stepFailed, from which the
    /// host restores a saved FMU state and retries with a shorter step, or resets.
    Discard(Reason),
    /// The host's inputs are refused before anything was computed, as fmi2SetReal refuses a
    /// value out of range: fmi2Error, the instance unchanged and in its state.
    Refused(Reason),
}

impl ModelError {
    pub fn failed(reason: impl std::error::Error + Send + Sync + 'static) -> Self {
        ModelError::Failed(Box::new(reason))
    }
    pub fn discard(reason: impl std::error::Error + Send + Sync + 'static) -> Self {
        ModelError::Discard(Box::new(reason))
    }
    pub fn refused(reason: impl std::error::Error + Send + Sync + 'static) -> Self {
        ModelError::Refused(Box::new(reason))
    }
    /// The model's error (downcast it to the model's type to tell its causes apart).
    pub fn reason(&self) -> &(dyn std::error::Error + Send + Sync + 'static) {
        match self {
            ModelError::Failed(r) | ModelError::Discard(r) | ModelError::Refused(r) => r.as_ref(),
        }
    }
}

/// The model's message, as the layer logs it (after the function's name and what it was about).
impl std::fmt::Display for ModelError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        std::fmt::Display::fmt(self.reason(), f)
    }
}

/// Transparent: the variant classifies, the model's error is the message and its source the next.
impl std::error::Error for ModelError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        self.reason().source()
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Interface {
    ModelExchange,
    CoSimulation,
}

/// A capability the model does not implement, as the trait's defaults answer it (the layer
/// checks the capability flags first, so a host never sees it).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Unsupported {
    InputDerivatives,
    DirectionalDerivatives,
    OutputDerivatives,
}

impl std::fmt::Display for Unsupported {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let what = match self {
            Unsupported::InputDerivatives => "input",
            Unsupported::DirectionalDerivatives => "directional",
            Unsupported::OutputDerivatives => "output",
        };
        write!(f, "{what} derivatives are not supported by this model")
    }
}

impl std::error::Error for Unsupported {}

/// The physics side. The layer has already checked the calling sequence, null
/// pointers, array lengths, value references and their types before calling a method,
/// so implementations only deal with valid requests.
///
/// An `Err` is a [`ModelError`], whose variant says what becomes of the instance, the same for
/// every method: `Failed` (and any panic) puts the instance into the FMI Error state (the host
/// may then only read values for diagnostics, restore an FMU state, reset or free it);
/// `Discard` answers fmi2Discard and leaves the instance usable (an evaluation at states or
/// inputs the model cannot evaluate, a step not taken); `Refused` answers fmi2Error with the
/// instance unchanged and in its state (a value refused before anything was set). The layer logs
/// the error's text after the function's name (and the variable it was about).
/// `load_state` is the exception: its `Err` refuses the bytes and changes nothing.
pub trait Model: Sized + Clone {
    /// Load the model from the FMU's resources folder (None: host gave no resource location).
    /// Any Err fails fmi2Instantiate.
    fn instantiate(resources: Option<&std::path::Path>, interface: Interface) -> Result<Self, ModelError>;
    /// GUID the model was built with; the layer compares it with the host's fmuGUID and refuses a mismatch.
    fn guid(&self) -> &str;
    /// Called on every get/set of every value reference: keep it a table lookup.
    fn var_info(&self, vr: u32) -> Option<VarInfo>;
    /// The variable's name, for error messages.
    fn var_name(&self, _vr: u32) -> Option<&str> {
        None
    }
    /// An evaluation: a model whose evaluations change nothing but caches answers
    /// `ModelError::Discard` for states or inputs it cannot evaluate (as for `get_derivatives`,
    /// `directional_derivative` and `get_real_output_derivative`).
    fn get_real(&mut self, vr: u32) -> Result<f64, ModelError>;
    /// Whether the finite `value` may be given to Real variable `vr` (the layer has refused
    /// non-finite values already): `ModelError::Refused` with the reason refuses it before
    /// anything is set, and the instance stays usable. For the model's physical range (a negative
    /// damping, a load whose square overflows); the same rule applies to restored FMU states.
    fn admissible_real(&self, _vr: u32, _value: f64) -> Result<(), ModelError> {
        Ok(())
    }
    /// Whether the values of one fmi2SetReal call, each admissible alone, may be set together:
    /// for variables that are only meaningful as a group (the nine entries of a rotation matrix
    /// handed over in one call). `ModelError::Refused` refuses the whole call before anything is set.
    fn admissible_reals(&self, _vrs: &[u32], _values: &[f64]) -> Result<(), ModelError> {
        Ok(())
    }
    /// Whether the finite `value` may be a rate of change along Real variable `vr`: an input
    /// derivative (fmi2SetRealInputDerivatives) or a directional derivative's seed.
    /// `ModelError::Refused` refuses the call before anything is set, the instance stays usable
    /// (as for `admissible_real`).
    fn admissible_direction(&self, _vr: u32, _value: f64) -> Result<(), ModelError> {
        Ok(())
    }
    fn set_real(&mut self, vr: u32, value: f64) -> Result<(), ModelError>;
    fn get_integer(&mut self, vr: u32) -> Result<i32, ModelError>;
    fn set_integer(&mut self, vr: u32, value: i32) -> Result<(), ModelError>;
    fn get_boolean(&mut self, vr: u32) -> Result<bool, ModelError>;
    fn set_boolean(&mut self, vr: u32, value: bool) -> Result<(), ModelError>;
    fn get_string(&mut self, vr: u32) -> Result<String, ModelError>; // may always Err for models without strings
    fn set_string(&mut self, vr: u32, value: &str) -> Result<(), ModelError>;
    fn n_states(&self) -> usize;
    fn n_event_indicators(&self) -> usize;
    fn set_time(&mut self, t: f64);
    fn get_continuous_states(&self, x: &mut [f64]);
    fn set_continuous_states(&mut self, x: &[f64]);
    fn get_derivatives(&mut self, dx: &mut [f64]) -> Result<(), ModelError>;
    fn get_nominals(&self, nominals: &mut [f64]);
    fn get_event_indicators(&mut self, z: &mut [f64]) -> Result<(), ModelError>;
    fn enter_initialization(&mut self, start_time: f64) -> Result<(), ModelError>;
    fn exit_initialization(&mut self) -> Result<(), ModelError>;
    /// Whether `set_real_input_derivative` is implemented (capability canInterpolateInputs).
    fn can_interpolate_inputs(&self) -> bool {
        false
    }
    /// Co-Simulation: the first time derivative of a Real input over the next step (the layer
    /// has checked that `vr` is a Real input and the order is 1).
    fn set_real_input_derivative(&mut self, _vr: u32, _value: f64) -> Result<(), ModelError> {
        Err(ModelError::failed(Unsupported::InputDerivatives))
    }
    /// Capability providesDirectionalDerivative.
    fn provides_directional_derivative(&self) -> bool {
        false
    }
    /// Whether `vr` is a continuous state / the derivative of one (Model Exchange); the layer uses
    /// these to check which value references a directional derivative may name.
    fn is_continuous_state(&self, _vr: u32) -> bool {
        false
    }
    fn is_state_derivative(&self, _vr: u32) -> bool {
        false
    }
    /// dv_unknown = (d unknowns / d knowns) dv_known at the present state and inputs, exact.
    /// The layer has checked: all are Real; unknowns are outputs or (ME) state derivatives;
    /// knowns are inputs or (ME) continuous states; lengths match; dv_known finite.
    fn directional_derivative(
        &mut self,
        _unknowns: &[u32],
        _knowns: &[u32],
        _dv_known: &[f64],
        _dv_unknown: &mut [f64],
    ) -> Result<(), ModelError> {
        Err(ModelError::failed(Unsupported::DirectionalDerivatives))
    }
    /// Capability maxOutputDerivativeOrder.
    fn max_output_derivative_order(&self) -> i32 {
        0
    }
    /// Co-Simulation: the `order`-th time derivative of Real output `vr` at the current
    /// communication point (layer has checked: Real output, 1 <= order <= max_output_derivative_order()).
    fn get_real_output_derivative(&mut self, _vr: u32, _order: i32) -> Result<f64, ModelError> {
        Err(ModelError::failed(Unsupported::OutputDerivatives))
    }
    /// The relative tolerance the host integrates with (fmi2SetupExperiment): a warning where
    /// the model cannot be accurate at it (the layer logs it, logStatusWarning whatever the debug
    /// logging, and answers fmi2OK: the experiment is set up as asked).
    fn tolerance_advice(&self, _tolerance: f64) -> Option<String> {
        None
    }
    /// Model Exchange left initialisation without the host stating a tolerance (no
    /// fmi2SetupExperiment with one): a warning where the model needs one the host may not
    /// use (the layer logs it as [`Model::tolerance_advice`]'s and answers fmi2OK).
    fn unstated_tolerance_advice(&self) -> Option<String> {
        None
    }
    /// Model Exchange: the host completed an integrator step at `time` (fmi2SetTime's last value).
    /// A warning about how the host integrates (the layer logs it once per call that returns one
    /// and answers fmi2OK, logStatusWarning whatever the debug logging); the step stands either way.
    fn completed_integrator_step(&mut self, _time: f64) -> Option<String> {
        None
    }
    /// Co-Simulation: advance from t to t + h exactly (what fmi2DoStep calls). Its failures told
    /// apart: `ModelError::Discard`: the step was not taken (too costly, or its result not
    /// finite) and the model is as before it; `ModelError::Refused`: the inputs were refused
    /// before anything was done; `ModelError::Failed`: the model's state is unknown.
    fn do_step(&mut self, t: f64, h: f64) -> Result<(), ModelError>;
    /// A warning about the last successful step (the layer logs it, logStatusWarning whatever the
    /// debug logging, and returns fmi2OK: the step was taken).
    fn take_warning(&mut self) -> Option<&'static str> {
        None
    }
    /// Back to the state right after instantiate (parameters at start values).
    fn reset(&mut self) -> Result<(), ModelError>;
    /// fmi2SerializeFMUstate: append a portable encoding (see [`bytes`]) of everything that
    /// evolves or can be set, enough for [`Model::load_state`] to continue bit-identically.
    /// Leave out what instantiate loads from the resources: the layer stores the GUID with it.
    fn save_state(&self, out: &mut Vec<u8>);
    /// fmi2DeSerializeFMUstate: take the state `bytes` (from `save_state` of a model with the
    /// same GUID, already checked) describe. The bytes are checksummed but may still come from
    /// another build or be crafted: check every size and value, never panic (the reader's
    /// errors name the field; [`bytes::DecodeError::Invalid`] carries the model's own refusal).
    /// `self` is a clone of the instance's model, discarded on Err, so a half-loaded state never
    /// reaches an instance; the layer reports the Err as refused bytes (fmi2Error, the instance
    /// stays in its state).
    fn load_state(&mut self, bytes: &[u8]) -> Result<(), bytes::DecodeError>;
}
