//! The FMU's variables and what each one means for the body: the one table from which the builder
//! writes modelDescription.xml and through which the runtime answers fmi2Get/Set. Each variable
//! belongs to a family described once in `families.rs` (name, attributes, value, range,
//! dependencies); the table lays the families out for a body.

pub mod assembly;
mod dependencies;
pub mod families;
pub mod family;
mod layout;
mod nominals;

pub use families::FAMILIES;
pub use family::{At, Family, Quantity, Role, StateOf, Value};
pub use nominals::{NOMINAL_FRACTION, modal_nominals};

use family::Structure;
use fmi2::{Causality, Initial, VarType, Variability};

#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Start {
    Real(f64),
    Boolean(bool),
}

#[derive(Debug, Clone, PartialEq)]
pub struct Variable {
    pub vr: u32,
    pub name: String,
    pub description: String,
    pub var_type: VarType,
    pub causality: Causality,
    pub variability: Variability,
    /// Written to the XML only where it differs from the FMI default for the causality.
    pub initial: Option<Initial>,
    pub start: Option<Start>,
    pub unit: Option<&'static str>,
    pub quantity: Quantity,
    /// For a state derivative: the value reference of its state.
    pub derivative_of: Option<u32>,
    /// For a continuous state: its expected magnitude, which hosts scale their absolute
    /// tolerance by (FMI 2.0 `nominal`, fmi2GetNominalsOfContinuousStates).
    pub nominal: Option<f64>,
}

/// Units used by the variables, with their SI base-unit exponents (kg, m, s, rad) for the XML.
pub const UNITS: &[(&str, [i32; 4])] = &[
    ("m", [0, 1, 0, 0]),
    ("m/s", [0, 1, -1, 0]),
    ("m/s2", [0, 1, -2, 0]),
    ("rad", [0, 0, 0, 1]),
    ("rad/s", [0, 0, -1, 1]),
    ("rad/s2", [0, 0, -2, 1]),
    ("N", [1, 1, -2, 0]),
    ("N.m", [1, 2, -2, 0]),
    ("1/s", [0, 0, -1, 0]),
    ("1/s2", [0, 0, -2, 0]),
    ("s", [0, 0, 1, 0]),
    ("J", [1, 2, -2, 0]),
    ("N.s", [1, 1, -1, 0]),
    ("J.s", [1, 2, -1, 0]),
    ("Pa", [1, -1, -2, 0]),
];

/// Names of the stress outputs of a recovery point, in component order (the stress families'
/// `Shape::Component`).
pub const STRESS_COMPONENTS: [&str; 7] = ["sxx", "syy", "szz", "sxy", "syz", "szx", "mises"];

/// The variable table of a body, value references 1.. in table order.
#[derive(Debug, Clone)]
pub struct VariableTable {
    pub variables: Vec<Variable>,
    /// Modes 1..=n_dynamic are states; the rest are quasi-static (Model Exchange solves them from
    /// the inputs and the states at every evaluation).
    pub n_dynamic: usize,
    /// Modes n_dynamic+1..=n_dynamic+n_relaxing are relaxing: their q is a state whose rate
    /// q' is solved from their damping without inertia.
    pub n_relaxing: usize,
    structure: Structure,
}

impl VariableTable {
    pub fn get(&self, vr: u32) -> Option<&Variable> {
        (vr as usize).checked_sub(1).and_then(|i| self.variables.get(i))
    }

    /// The variable of this name (a linear search: for setting up, not for every get/set).
    pub fn variable(&self, name: &str) -> Option<&Variable> {
        self.variables.iter().find(|v| v.name == name)
    }

    /// The value reference of the variable of this name.
    pub fn value_reference(&self, name: &str) -> Option<u32> {
        self.variable(name).map(|v| v.vr)
    }

    /// State value references in state order (`state_variables`).
    pub fn states(&self) -> Vec<u32> {
        self.state_variables().map(|v| v.vr).collect()
    }

    /// The state variables in the order of the model's state vector (q, qd of the dynamic
    /// modes, q of the relaxing ones, then a free body's frame), without allocating.
    pub fn state_variables(&self) -> impl Iterator<Item = &Variable> {
        let (nd, ns) = (self.n_dynamic, self.n_dynamic + self.n_relaxing);
        let modal = move |role: Role, modes: std::ops::Range<usize>| {
            self.variables.iter().filter(move |v| v.quantity.role() == Some(role) && modes.contains(&v.quantity.at.i))
        };
        let frame = self.variables.iter().filter(|v| v.quantity.family.state == StateOf::Always);
        modal(Role::ModalCoordinate, 0..nd)
            .chain(modal(Role::ModalVelocity, 0..nd))
            .chain(modal(Role::ModalCoordinate, nd..ns))
            .chain(frame)
    }

    /// Whether the quantity is a continuous state: q, q' of a dynamic mode, q of a relaxing
    /// one or a frame state.
    pub fn is_state(&self, q: Quantity) -> bool {
        match q.family.state {
            StateOf::Never => false,
            StateOf::Always => true,
            StateOf::DynamicModes => q.at.i < self.n_dynamic,
            StateOf::IntegratedModes => q.at.i < self.n_dynamic + self.n_relaxing,
        }
    }

    /// Derivative value references in state order: each state's derivative (qd = der(q),
    /// der(qd), ..., d/dt of a free body's position being the state frame.v).
    pub fn derivatives(&self) -> Vec<u32> {
        let derivative: std::collections::HashMap<(Role, At), u32> = self
            .variables
            .iter()
            .filter_map(|v| v.quantity.family.derivative_of.map(|state| ((state, v.quantity.at), v.vr)))
            .collect();
        self.state_variables()
            .filter_map(|s| s.quantity.role().and_then(|role| derivative.get(&(role, s.quantity.at)).copied()))
            .collect()
    }

    fn select(&self, f: impl Fn(&Quantity) -> bool) -> Vec<u32> {
        self.variables.iter().filter(|v| f(&v.quantity)).map(|v| v.vr).collect()
    }
}

#[cfg(test)]
mod tests;
