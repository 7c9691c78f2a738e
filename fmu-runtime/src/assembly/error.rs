//! Why an assembly cannot be loaded, started or stepped.

use std::fmt;

#[derive(Debug, Clone, PartialEq)]
pub enum AssemblyError {
    /// A body that cannot be part of an assembly, and why.
    Body { body: String, reason: String },
    /// A joint that cannot be formed, and why.
    Joint { joint: String, reason: String },
    /// The joints' equations are not independent at the start: the joints named share the
    /// dependent equations.
    Redundant { joints: Vec<String> },
    /// The start pose does not satisfy the joints within the assembly's tolerance.
    Misassembled { joint: String, gap: f64 },
    /// Newton did not converge in a step, even with a fresh iteration matrix.
    NotConverged { time: f64, residual: f64 },
    /// The iteration matrix is singular (the joints lock each other or a body has no mass).
    Singular { time: f64 },
    /// The step's result is not finite.
    NotFinite { time: f64 },
    /// Something of the assembly's file is inconsistent.
    Format(String),
}

impl fmt::Display for AssemblyError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            AssemblyError::Body { body, reason } => write!(f, "body '{body}': {reason}"),
            AssemblyError::Joint { joint, reason } => write!(f, "joint '{joint}': {reason}"),
            AssemblyError::Redundant { joints } => write!(
                f,
                "the joints {} constrain the same motion twice (their equations are dependent at the start pose): \
                 replace one revolute joint of the loop by a universal or spherical joint",
                joints.iter().map(|j| format!("'{j}'")).collect::<Vec<_>>().join(", ")
            ),
            AssemblyError::Misassembled { joint, gap } => write!(
                f,
                "joint '{joint}': its two flanges are {gap:.3e} apart (or turned) at the start; place the bodies so \
                 that every joint's flanges coincide"
            ),
            AssemblyError::NotConverged { time, residual } => write!(
                f,
                "the joints' equations did not converge in the step at t = {time} s (residual {residual:.3e}); \
                 try a smaller step or solver.max_iterations"
            ),
            AssemblyError::Singular { time } => write!(
                f,
                "the assembly's equations are singular at t = {time} s (a mechanism at a dead point, or joints \
                 that lock each other)"
            ),
            AssemblyError::NotFinite { time } => write!(f, "the step from t = {time} s gave a non-finite state"),
            AssemblyError::Format(m) => write!(f, "assembly file: {m}"),
        }
    }
}

impl std::error::Error for AssemblyError {}
