//! Why a variable could not be read, set or differentiated: a value reference the table does not
//! hold or of another kind, a value out of its range, or the body's equations failing. `model`
//! turns these into `fmi2::ModelError`, whose variant says what becomes of the instance.

use crate::body::{BodyError, OutOfRange};
use std::fmt;

/// A failure of a variable's access.
#[derive(Clone, PartialEq)]
pub enum VariableError {
    /// A value reference the variable table does not hold.
    Unknown(u32),
    /// A Real asked of the Boolean `name` (value reference `vr`).
    BooleanAsReal { vr: u32, name: String },
    /// A Real asked of a variable of the Boolean family `pattern`.
    BooleanFamily(&'static str),
    /// A variable no call may set.
    NotSettable(String),
    /// An input derivative for a variable that is no input.
    NotAnInput(u32),
    /// A Boolean asked of a Real.
    NotABoolean(u32),
    /// A directional derivative's known that is neither an input nor a continuous state.
    NotSeedable(String),
    /// This FMU has no Integer variables.
    NoIntegers(u32),
    /// This FMU has no String variables.
    NoStrings(u32),
    /// A value outside its quantity's physical range.
    OutOfRange(OutOfRange),
    /// The body's equations failed where the value is evaluated.
    Body(BodyError),
}

impl fmt::Display for VariableError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            VariableError::Unknown(vr) => write!(f, "unknown value reference {vr}"),
            VariableError::BooleanAsReal { vr, name } => write!(f, "value reference {vr} ({name}) is a Boolean"),
            VariableError::BooleanFamily(pattern) => write!(f, "{pattern} is a Boolean"),
            VariableError::NotSettable(name) => write!(f, "{name} cannot be set"),
            VariableError::NotAnInput(vr) => write!(f, "value reference {vr} is not an input"),
            VariableError::NotABoolean(vr) => write!(f, "value reference {vr} is not a Boolean"),
            VariableError::NotSeedable(name) => write!(f, "{name} is neither an input nor a continuous state"),
            VariableError::NoIntegers(vr) => {
                write!(f, "value reference {vr} is not an Integer: this FMU has no Integer variables")
            }
            VariableError::NoStrings(vr) => {
                write!(f, "value reference {vr} is not a String: this FMU has no String variables")
            }
            VariableError::OutOfRange(e) => fmt::Display::fmt(e, f),
            VariableError::Body(e) => fmt::Display::fmt(e, f),
        }
    }
}

/// The wrapped errors are shown as they are (transparent): their own sources come next.
impl std::error::Error for VariableError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            VariableError::OutOfRange(e) => e.source(),
            VariableError::Body(e) => e.source(),
            _ => None,
        }
    }
}

impl From<BodyError> for VariableError {
    fn from(e: BodyError) -> Self {
        VariableError::Body(e)
    }
}

impl From<OutOfRange> for VariableError {
    fn from(e: OutOfRange) -> Self {
        VariableError::OutOfRange(e)
    }
}

/// The message, as the FMU logs it (see `body::BodyError`: no derived dump in the binary).
impl std::fmt::Debug for VariableError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        std::fmt::Display::fmt(self, f)
    }
}
