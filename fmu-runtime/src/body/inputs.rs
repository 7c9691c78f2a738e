//! What the host sets: the mount's motion, the flange loads, the parameters, the initial frame,
//! the input rates of the next step and the host's view of a mount a step moved; and the loads
//! the last step ended with.

use super::{FlangeLoad, InitialFrame, MountMotion, Parameters};
use crate::kinematics::{Mat3, Vec3};
use crate::scalar::Dual;

/// Everything the host sets on a body (see [`FlexibleBody`](super::FlexibleBody)'s setters,
/// which mark the derived values stale whenever they hand this out for writing). One struct so
/// that a saved state ([`BodyState`](super::BodyState)) takes and gives it as it is and a step's
/// undo copies it in one call. A free-floating body has no mount input: its `mount` is its
/// frame's motion, written by each evaluation.
#[derive(Debug, Clone, PartialEq)]
pub struct BodyInputs<T = f64> {
    pub mount: MountMotion<T>,
    pub loads: Vec<FlangeLoad<T>>,
    pub params: Parameters,
    /// A free-floating body's initial pose and velocity: read only when its frame is started.
    pub initial_frame: InitialFrame,
    /// Input derivatives set for the next step and not yet used.
    pub rates: InputRates,
    /// Co-Simulation: the host's view of the mount's orientation and spin where the last step
    /// moved them by their kinematics (see `cosim_step`), and which of them the host drives. No
    /// part of a saved state, which holds the host's view as its `mount`.
    pub(crate) host: HostMount,
}

impl<T: Copy> BodyInputs<T> {
    /// `other`'s values into this one's storage (no allocation; the sizes must agree).
    pub(super) fn copy_from(&mut self, other: &Self) {
        self.mount = other.mount;
        self.loads.copy_from_slice(&other.loads);
        self.params = other.params;
        self.initial_frame = other.initial_frame;
        self.rates.mount = other.rates.mount;
        self.rates.loads.copy_from_slice(&other.rates.loads);
        self.rates.any = other.rates.any;
        self.host = other.host;
    }
}

impl BodyInputs {
    /// The inputs as a saved state holds them: the host's mount (a restored body starts its next
    /// step where this one would), no view of a mount moved by a step.
    pub(super) fn as_saved(&self) -> Self {
        BodyInputs {
            mount: MountMotion {
                rot: self.host.rot.unwrap_or(self.mount.rot),
                w: self.host.w.unwrap_or(self.mount.w),
                ..self.mount
            },
            loads: self.loads.clone(),
            params: self.params,
            initial_frame: self.initial_frame,
            rates: self.rates.clone(),
            host: HostMount::default(),
        }
    }

    /// These inputs in dual numbers, every derivative part zero; the host's view stays behind
    /// (stepping is `f64` only).
    pub(super) fn to_dual(&self) -> BodyInputs<Dual> {
        BodyInputs {
            mount: self.mount.map(Dual::from),
            loads: self.loads.iter().map(|l| FlangeLoad { f: l.f.map(Dual::from), t: l.t.map(Dual::from) }).collect(),
            params: self.params,
            initial_frame: self.initial_frame,
            rates: self.rates.clone(),
            host: HostMount::default(),
        }
    }
}

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

impl InputRates {
    /// Every rate zero, for `flanges` force flanges.
    pub(super) fn held(flanges: usize) -> Self {
        InputRates {
            mount: MountMotion { rot: [0.0; 9], ..MountMotion::default() },
            loads: vec![FlangeLoad::default(); flanges],
            any: false,
        }
    }
}

/// The loads a Co-Simulation step ended with (host-given rates applied): a snapshot of part of
/// the [`BodyInputs`], which the [`Stepper`](super::stepper::Stepper) keeps and `input_jump`
/// compares the next step's inputs with (the shift's scratch is the step's `JumpWork`).
#[derive(Debug, Clone, Default)]
pub(super) struct SteppedInputs {
    pub(super) valid: bool,
    /// The mount's acceleration a and angular acceleration z.
    pub(super) a: Vec3,
    pub(super) z: Vec3,
    pub(super) loads: Vec<FlangeLoad>,
    pub(super) params: Option<Parameters>,
}

impl SteppedInputs {
    pub(super) fn new(flanges: usize) -> Self {
        Self { valid: false, a: [0.0; 3], z: [0.0; 3], loads: vec![FlangeLoad::default(); flanges], params: None }
    }

    /// `other`'s values into this one's storage (no allocation; the sizes must agree).
    pub(super) fn copy_from(&mut self, other: &Self) {
        self.valid = other.valid;
        self.a = other.a;
        self.z = other.z;
        self.loads.copy_from_slice(&other.loads);
        self.params = other.params;
    }
}
