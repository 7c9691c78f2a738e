//! What an fmi2Component points to.

use std::ffi::CString;

use super::logger::Logger;
use super::state::ModelState;
use super::types::{fmi2CallbackFunctions, fmi2Status};
use super::{Interface, Model};

pub struct Instance<M> {
    pub model: M,
    pub interface: Interface,
    pub state: ModelState,
    pub logger: Logger,
    /// Own copy: the host may free its struct after fmi2Instantiate returns.
    /// Kept for stepFinished, which an asynchronous fmi2DoStep would need.
    pub callbacks: fmi2CallbackFunctions,
    pub time: f64,
    pub start_time: f64,
    /// Stored for completeness; nothing enforces it yet.
    pub stop_time: Option<f64>,
    pub tolerance: Option<f64>,
    /// Answer to fmi2GetStatus(fmi2DoStepStatus).
    pub last_do_step_status: fmi2Status,
    /// fmi2GetString hands out pointers that must outlive the call.
    pub string_buffer: Vec<CString>,
}

impl<M: Model> Instance<M> {
    pub fn new(model: M, interface: Interface, logger: Logger, callbacks: fmi2CallbackFunctions) -> Self {
        Instance {
            model,
            interface,
            state: ModelState::Instantiated,
            logger,
            callbacks,
            time: 0.0,
            start_time: 0.0,
            stop_time: None,
            tolerance: None,
            last_do_step_status: fmi2Status::fmi2OK,
            string_buffer: Vec::new(),
        }
    }

    /// Back to the values fmi2Instantiate leaves; logging settings are the host's and stay.
    pub fn reset_experiment(&mut self) {
        self.state = ModelState::Instantiated;
        self.time = 0.0;
        self.start_time = 0.0;
        self.stop_time = None;
        self.tolerance = None;
        self.last_do_step_status = fmi2Status::fmi2OK;
        self.string_buffer.clear();
    }

    pub fn snapshot(&self) -> Snapshot<M> {
        Snapshot {
            magic: SNAPSHOT_MAGIC,
            model: self.model.clone(),
            interface: self.interface,
            state: self.state,
            time: self.time,
            start_time: self.start_time,
            stop_time: self.stop_time,
            last_do_step_status: self.last_do_step_status,
        }
    }

    pub fn restore(&mut self, s: &Snapshot<M>) {
        // clone_from lets models reuse their buffers on repeated rollbacks.
        self.model.clone_from(&s.model);
        self.state = s.state;
        self.time = s.time;
        self.start_time = s.start_time;
        self.stop_time = s.stop_time;
        self.last_do_step_status = s.last_do_step_status;
    }
}

/// The first field of every [`Snapshot`]: a host that hands back a pointer that is no FMU state
/// of this runtime (another tool's state, an instance, freed memory that was reused) is refused
/// in the common cases instead of being read as one.
pub const SNAPSHOT_MAGIC: u64 = u64::from_le_bytes(*b"FLEXSNAP");

/// What an fmi2FMUstate points to: everything that evolves during a simulation,
/// but not the host's callbacks or logging settings.
#[repr(C)]
pub struct Snapshot<M> {
    pub magic: u64,
    pub model: M,
    /// The interface of the instance it was taken from: states do not cross interfaces.
    pub interface: Interface,
    pub state: ModelState,
    pub time: f64,
    pub start_time: f64,
    pub stop_time: Option<f64>,
    pub last_do_step_status: fmi2Status,
}

impl<M> Drop for Snapshot<M> {
    fn drop(&mut self) {
        // a host that frees a state twice or sets a freed one meets a cleared magic (while the
        // allocator has not reused the memory) instead of a stale model; volatile, since the
        // compiler would drop a plain store to memory about to be freed
        // SAFETY: `self.magic` is a valid, aligned u64 for the duration of drop.
        unsafe { std::ptr::write_volatile(&mut self.magic, 0) };
    }
}
