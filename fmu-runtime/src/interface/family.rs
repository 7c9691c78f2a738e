//! What a descriptor of a variable family says, and the vocabulary its dependency rules use.

use crate::body::{BodyError, FlexibleBody, OutOfRange};
use crate::scalar::Dual;
use fmi2::{Causality, Initial, Variability};

/// Where in its family a variable sits: the flange or stress point it belongs to (`owner`), its
/// component, matrix row or mode (`i`) and matrix column (`j`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct At {
    pub owner: usize,
    pub i: usize,
    pub j: usize,
}

/// Which bodies have a family, and how often.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Scope {
    /// Once in every body.
    Every,
    /// Once in a body held by a mount.
    Mounted,
    /// Once in a free-floating body.
    Free,
    /// Once per force flange; a flange's families are listed together.
    Flange,
    /// Once per stress recovery point; a point's families are listed together.
    StressPoint,
}

/// The variables of a family within its owner.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Shape {
    Scalar,
    /// Components 1..=n (`[i]` in the name).
    Vector(usize),
    /// A 3 x 3 matrix, row-major (`[i,j]`).
    Matrix,
    /// One per mode (`[k]`).
    Modes,
    /// The one component `i` of a quantity of several (a stress component).
    Component(usize),
}

/// The knowns and states by the part they play in the body's equations: what the dependency
/// rules of the unknowns are written in.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Role {
    MountPosition,
    MountRotation,
    MountVelocity,
    MountSpin,
    MountAcceleration,
    MountAngularAcceleration,
    FlangeForce,
    FlangeTorque,
    Gravity,
    MassDamping,
    StiffnessDamping,
    StaticStart,
    InitialPosition,
    InitialRotation,
    InitialVelocity,
    InitialSpin,
    ModalCoordinate,
    ModalVelocity,
    FramePosition,
    FrameQuaternion,
    FrameVelocity,
    FrameSpin,
}

impl Role {
    pub fn is_flange_load(self) -> bool {
        matches!(self, Role::FlangeForce | Role::FlangeTorque)
    }

    /// Parameters that enter the loads and the modal acceleration directly.
    pub fn is_load_parameter(self) -> bool {
        matches!(self, Role::Gravity | Role::MassDamping | Role::StiffnessDamping)
    }

    pub fn is_initial_frame(self) -> bool {
        matches!(self, Role::InitialPosition | Role::InitialRotation | Role::InitialVelocity | Role::InitialSpin)
    }

    /// What sets the static equilibrium `static_start` starts a mounted body in.
    pub fn sets_static_equilibrium(self) -> bool {
        matches!(
            self,
            Role::MountAcceleration
                | Role::MountRotation
                | Role::MountSpin
                | Role::MountAngularAcceleration
                | Role::FlangeForce
                | Role::FlangeTorque
                | Role::Gravity
                | Role::StaticStart
        )
    }
}

/// Where a variable's start value (and with it, for the modes, its `initial`) comes from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum StartRule {
    None,
    Zero,
    /// The identity matrix: an input orientation starts unrotated.
    Identity,
    False,
    /// The body's Rayleigh coefficients, from the build.
    MassDamping,
    StiffnessDamping,
    /// A dynamic mode's q, q' are states with start values; a quasi-static mode's are
    /// calculated (its equilibrium with the inputs and the dynamic modes, at rest), a relaxing
    /// mode's q a state that starts there.
    DynamicModes,
}

/// The expected magnitude of a modal state, which hosts scale their absolute tolerance by.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Nominal {
    None,
    /// `NOMINAL_FRACTION` of the mode's static response.
    ModalCoordinate,
    /// The coordinate's nominal times the mode's angular frequency.
    ModalVelocity,
}

/// When a variable of the family is a continuous state.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StateOf {
    Never,
    Always,
    DynamicModes,
    /// The dynamic and the relaxing modes.
    IntegratedModes,
}

/// The physical range of a value the host sets, beyond finiteness.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Range {
    Any,
    /// Damping must not feed energy into the body.
    NonNegative,
    /// An entry of a rotation matrix: |R_ij| <= 1 (rounding leaves far less than 1e-6).
    RotationEntry,
}

impl Range {
    pub fn check(self, value: f64) -> Result<(), OutOfRange> {
        match self {
            Range::NonNegative if value < 0.0 => Err(OutOfRange::NegativeDamping(value)),
            Range::RotationEntry if value.abs() > 1.0 + 1e-6 => Err(OutOfRange::RotationEntry(value)),
            _ => Ok(()),
        }
    }
}

/// A Real variable's value, in f64 for fmi2GetReal and in dual numbers for its derivatives: the
/// same expression, instantiated for both by [`read!`].
#[derive(Debug, Clone, Copy)]
pub struct Read {
    pub real: fn(&mut FlexibleBody<f64>, At) -> Result<f64, BodyError>,
    pub dual: fn(&mut FlexibleBody<Dual>, At) -> Result<Dual, BodyError>,
}

/// `read!(|b, at| expression)`: a [`Read`] of `Ok(expression)`, generic over the scalar as the
/// body's equations are; `read!(? |b, at| expression)` for an expression that is itself a
/// `Result`.
macro_rules! read {
    (|$b:tt, $at:tt| $value:expr) => {
        $crate::interface::family::Read { real: |$b, $at| Ok($value), dual: |$b, $at| Ok($value) }
    };
    (? |$b:tt, $at:tt| $value:expr) => {
        $crate::interface::family::Read { real: |$b, $at| $value, dual: |$b, $at| $value }
    };
}
pub(crate) use read;

#[derive(Debug, Clone, Copy)]
pub enum Value {
    Real(Read),
    /// The one Boolean, `static_start`: a switch of the FMU's initialisation, not of the body.
    Switch,
}

/// The structure of a body the dependency rules depend on.
#[derive(Debug, Clone, Copy)]
pub struct Structure {
    /// Modes 0..n_dynamic are dynamic.
    pub n_dynamic: usize,
    /// Modes n_dynamic..n_integrated are relaxing, the rest quasi-static.
    pub n_integrated: usize,
    /// Some modes are not dynamic (relaxing or quasi-static): the modal coordinates follow the
    /// loads directly, not only through the dynamic states.
    pub solved_modes: bool,
    /// The body has rotating-frame terms, through which q'_d loads the quasi-static modes.
    pub rotates: bool,
    pub free: bool,
}

/// Sets a variable of the body from an f64 (its value, or its rate).
pub type Write = fn(&mut FlexibleBody, At, f64);

/// The input or state a directional derivative seeds (None where a free body's frame is asked
/// of a mounted one).
pub type Seed = fn(&mut FlexibleBody<Dual>, At) -> Option<&mut Dual>;

/// Whether `known` is a dependency of a variable at `at`, for a mounted body.
pub type Depends = fn(&Structure, At, &Quantity) -> bool;

impl Structure {
    pub fn relaxing(&self, mode: usize) -> bool {
        mode >= self.n_dynamic && mode < self.n_integrated
    }

    pub fn has_relaxing_modes(&self) -> bool {
        self.n_integrated > self.n_dynamic
    }

    /// q' of a dynamic mode.
    pub fn dynamic_velocity(&self, k: &Quantity) -> bool {
        k.role() == Some(Role::ModalVelocity) && k.at.i < self.n_dynamic
    }

    /// What the modal coordinates follow: the dynamic and relaxing modes' states, and what the
    /// quasi-static modes are solved from (the modal load of the mount's motion and the flange
    /// loads, the coupling of the spin, and through the gyroscopic terms the dynamic modes'
    /// velocities).
    pub fn deformation(&self, k: &Quantity) -> bool {
        use Role::*;
        let Some(role) = k.role() else { return false };
        let spin = matches!(role, MountSpin | MountAngularAcceleration) || self.dynamic_velocity(k);
        role == ModalCoordinate && k.at.i < self.n_integrated
            || self.solved_modes
                && (matches!(role, MountAcceleration | MountRotation) || role.is_flange_load() || self.rotates && spin)
    }

    /// q'' = p(a, R, loads) - d q' - w^2 q.
    pub fn modal_acceleration(&self, k: &Quantity) -> bool {
        matches!(k.role(), Some(Role::MountAcceleration | Role::MountRotation))
            || k.role().is_some_and(Role::is_flange_load)
            || self.deformation(k)
            || self.dynamic_velocity(k)
    }

    /// d_r q'_r = p_r - w_r^2 q_r - (C_k q + C_d q'_d)_r; the rotating-frame terms couple all
    /// modes and bring in the spin, as they do in everything the acceleration enters.
    pub fn relaxing_rate(&self, k: &Quantity) -> bool {
        self.modal_acceleration(k) || matches!(k.role(), Some(Role::MountSpin | Role::MountAngularAcceleration))
    }
}

/// How a variable depends on the knowns during initialisation (InitialUnknowns), where the
/// states are unknowns too.
#[derive(Debug, Clone, Copy)]
pub enum Initially {
    /// Its dependencies, each state replaced by what the state starts from.
    AsItsDependencies,
    /// Those, and gravity and damping, which enter the modal acceleration directly.
    ThroughAcceleration,
    /// A state: what it starts from (and what a dependence on it stands for).
    StartsFrom(fn(&Structure, &Quantity) -> bool),
}

/// One family of FMU variables: everything the builder writes into modelDescription.xml about
/// it and everything the runtime does with it.
#[derive(Debug, Clone, Copy)]
pub struct Family {
    /// The name, with `<mount>`, `<flange>`, `<point>` for its owner's name and `[i]`, `[i,j]`,
    /// `[k]` for component, matrix entry or mode (numbered from 1): as docs/VARIABLES.md lists it.
    pub pattern: &'static str,
    /// With `{axis}` (x, y, z), `{row}`, `{column}`, `{index}` (i from 1), `{mode}`,
    /// `{frequency}` (Hz), `{kind}` (how Model Exchange treats the mode) and `{point}` (the
    /// stress point's node and why it was chosen).
    pub description: &'static str,
    pub scope: Scope,
    pub shape: Shape,
    pub causality: Causality,
    pub variability: Variability,
    /// Written to the XML only where it differs from the FMI default for the causality.
    pub initial: Option<Initial>,
    pub start: StartRule,
    pub unit: Option<&'static str>,
    pub nominal: Nominal,
    /// For a known or a state: the part it plays in the equations.
    pub role: Option<Role>,
    /// For a state derivative: the role of its state, at the same place.
    pub derivative_of: Option<Role>,
    pub state: StateOf,
    pub value: Value,
    /// fmi2SetReal (the layer has checked finiteness and `range` before).
    pub write: Option<Write>,
    pub seed: Option<Seed>,
    /// fmi2SetRealInputDerivatives.
    pub rate: Option<Write>,
    pub range: Range,
    /// The inputs and states the value depends on in a mounted body (ModelStructure); a free
    /// body's unknowns may depend on every state and flange load.
    pub depends: Depends,
    pub initially: Initially,
}

const fn family(pattern: &'static str, description: &'static str, causality: Causality, value: Value) -> Family {
    Family {
        pattern,
        description,
        scope: Scope::Every,
        shape: Shape::Vector(3),
        causality,
        variability: Variability::Continuous,
        initial: None,
        start: StartRule::None,
        unit: None,
        nominal: Nominal::None,
        role: None,
        derivative_of: None,
        state: StateOf::Never,
        value,
        write: None,
        seed: None,
        rate: None,
        range: Range::Any,
        depends: |_, _, _| false,
        initially: Initially::AsItsDependencies,
    }
}

/// A continuous input, starting at zero: a vector unless `shape` says otherwise.
pub const fn input(pattern: &'static str, description: &'static str, role: Role, read: Read) -> Family {
    Family {
        start: StartRule::Zero,
        role: Some(role),
        ..family(pattern, description, Causality::Input, Value::Real(read))
    }
}

/// A continuous output: a vector unless `shape` says otherwise.
pub const fn output(pattern: &'static str, description: &'static str, read: Read) -> Family {
    family(pattern, description, Causality::Output, Value::Real(read))
}

/// A fixed parameter, starting at zero.
pub const fn parameter(pattern: &'static str, description: &'static str, role: Role, value: Value) -> Family {
    Family {
        variability: Variability::Fixed,
        start: StartRule::Zero,
        role: Some(role),
        ..family(pattern, description, Causality::Parameter, value)
    }
}

/// A continuous local: a state, a state derivative or a quasi-static mode's coordinate.
pub const fn local(pattern: &'static str, description: &'static str, read: Read) -> Family {
    family(pattern, description, Causality::Local, Value::Real(read))
}

impl Family {
    pub const fn unit(self, unit: &'static str) -> Self {
        Family { unit: Some(unit), ..self }
    }
    pub const fn scope(self, scope: Scope) -> Self {
        Family { scope, ..self }
    }
    pub const fn shape(self, shape: Shape) -> Self {
        Family { shape, ..self }
    }
    pub const fn start(self, start: StartRule) -> Self {
        Family { start, ..self }
    }
    pub const fn initial(self, initial: Initial) -> Self {
        Family { initial: Some(initial), ..self }
    }
    pub const fn nominal(self, nominal: Nominal) -> Self {
        Family { nominal, ..self }
    }
    pub const fn role(self, role: Role) -> Self {
        Family { role: Some(role), ..self }
    }
    pub const fn derivative_of(self, state: Role) -> Self {
        Family { derivative_of: Some(state), ..self }
    }
    pub const fn state(self, state: StateOf) -> Self {
        Family { state, ..self }
    }
    pub const fn write(self, write: Write) -> Self {
        Family { write: Some(write), ..self }
    }
    pub const fn seed(self, seed: Seed) -> Self {
        Family { seed: Some(seed), ..self }
    }
    pub const fn rate(self, rate: Write) -> Self {
        Family { rate: Some(rate), ..self }
    }
    pub const fn range(self, range: Range) -> Self {
        Family { range, ..self }
    }
    pub const fn depends(self, depends: Depends) -> Self {
        Family { depends, ..self }
    }
    pub const fn initially(self, initially: Initially) -> Self {
        Family { initially, ..self }
    }
}

/// What a variable stands for: a place in a family.
#[derive(Debug, Clone, Copy)]
pub struct Quantity {
    pub family: &'static Family,
    pub at: At,
}

impl Quantity {
    pub fn role(&self) -> Option<Role> {
        self.family.role
    }
}

/// Families are told apart by identity: each lives once, in `FAMILIES`.
impl PartialEq for Quantity {
    fn eq(&self, other: &Self) -> bool {
        std::ptr::eq(self.family, other.family) && self.at == other.at
    }
}
