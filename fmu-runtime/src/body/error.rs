//! Why the body's equations fail, typed by failure class: a request the kind of body cannot
//! answer, inputs it refuses, a value out of its physical range, an equation without solution
//! at the present state and inputs, a step not taken, a saved state of another body. Each
//! variant's text is the message a host logs (the FMI adapter decides what the failure does to
//! the instance). Building an error allocates only for the names it carries, on the error path.

use super::{REAL_LIMIT, UNSTABLE_STIFFNESS};
use crate::workspace::WorkspaceTooSmall;
use std::fmt;

use super::cosim_step::SUBSTEP_ANGLE;
use super::mounted::ROTATION_TOLERANCE;

/// A failure of the body's equations.
#[derive(Clone, PartialEq)]
pub enum BodyError {
    // --- what the kind of body cannot answer
    /// A free-floating body's quantity asked of a mounted body.
    NotFreeFloating,
    /// Energy and momenta asked of a mounted body.
    InvariantsOfMountedBody,
    /// The static start asked of a free-floating body.
    StaticStartOfFreeBody,
    /// A free-floating body's motion without its rotation invariants (a crafted reduced body).
    RotationInvariantsNeeded,
    /// A free-floating body's energy and momenta without its rotation invariants.
    RotationInvariantsMissing,

    // --- inputs the body cannot be evaluated or stepped with
    /// The mount orientation (input `{mount}.R`) is off the rotations by `defect` (infinite:
    /// its determinant is not positive; NaN: non-finite entries).
    NotARotation {
        mount: String,
        defect: f64,
    },
    /// The mount spins, but the body was built for a scene without rotation.
    SpinWithoutRotation {
        mount: String,
    },
    /// A step size that is not positive and finite.
    StepSize(f64),

    // --- equations without solution at the present state and inputs
    /// The free body's 3 x 3 inertia (Schur complement) is singular.
    SingularInertia,
    /// Model Exchange's quasi-static solve above the dynamic cutoff is singular.
    NoQuasiStaticEquilibrium,
    /// The static start's solve is singular.
    NoStaticEquilibrium,
    /// A free body's orientation quaternion far off the unit sphere.
    Orientation {
        quat: [f64; 4],
        norm: f64,
    },

    // --- steps not taken (the body is as before the step)
    /// A free body's step needs more substeps than one call may take.
    TooManySubsteps {
        h: f64,
        spin: f64,
        needed: f64,
        most: usize,
        longest: f64,
    },
    /// The coupled modes' state became non-finite within a step of `h`.
    StepNotFinite {
        h: f64,
    },
    /// The deformation grew without bound: the spin is above a critical speed.
    Unstable,
    /// `what` would end a step of `h` at `value`, non-finite or beyond [`REAL_LIMIT`];
    /// `unstable`: the effective stiffness is not positive definite (the likely cause).
    StepEndOutOfRange {
        what: String,
        value: f64,
        h: f64,
        unstable: bool,
    },
    /// The step's scratch was made for another body.
    WorkspaceMismatch {
        modes: usize,
        flanges: usize,
    },
    /// A workspace too small for a computation.
    Workspace(WorkspaceTooSmall),

    // --- saved states of another body
    State(StateMismatch),
}

/// A saved body state that does not fit this body (sizes, kind, coupling reference).
#[derive(Clone, PartialEq)]
pub enum StateMismatch {
    Modes { q: usize, qd: usize, n: usize },
    Flanges { found: usize, n: usize },
    Kind { free: bool, body_free: bool },
    SteppedLoads { found: usize, n: usize },
    CouplingReference { c_d: usize, c_k: usize, n: usize },
    CouplingReferenceNotFinite,
}

/// A Real the host sets (or a rate it gives) outside the physical range of its quantity.
#[derive(Clone, Copy, PartialEq)]
pub enum OutOfRange {
    NotFinite(f64),
    /// A value beyond [`REAL_LIMIT`].
    Beyond(f64),
    /// A rate (an input derivative, a directional seed) beyond [`REAL_LIMIT`].
    RateBeyond(f64),
    /// A negative damping coefficient.
    NegativeDamping(f64),
    /// An entry of a rotation matrix beyond [-1, 1].
    RotationEntry(f64),
}

/// Why a Co-Simulation step was not taken; the body is as it was before the step either way.
#[derive(Clone, PartialEq)]
pub enum StepError {
    /// The inputs are none the body can be stepped with (a mount orientation off the rotations,
    /// a spin the body was not built for): the host sets valid ones and steps again.
    Inputs(BodyError),
    /// The step would cost more than one call may take, or its result would not have been
    /// finite and in range: a shorter step (or other inputs) may be taken.
    NotTaken(BodyError),
}

impl StepError {
    /// What failed, whichever the class.
    pub fn error(&self) -> &BodyError {
        match self {
            StepError::Inputs(e) | StepError::NotTaken(e) => e,
        }
    }
    pub fn into_error(self) -> BodyError {
        match self {
            StepError::Inputs(e) | StepError::NotTaken(e) => e,
        }
    }
}

impl fmt::Display for BodyError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            BodyError::NotFreeFloating => f.write_str("not a free-floating body"),
            BodyError::InvariantsOfMountedBody => f.write_str("energy and momenta are outputs of free-floating bodies"),
            BodyError::StaticStartOfFreeBody => {
                f.write_str("a free-floating body has no static equilibrium to start in")
            }
            BodyError::RotationInvariantsNeeded => f.write_str("a free-floating body needs its rotation invariants"),
            BodyError::RotationInvariantsMissing => f.write_str("missing rotation invariants"),
            BodyError::NotARotation { mount, defect } => {
                write!(f, "{mount}.R is not a proper rotation matrix (")?;
                if defect.is_infinite() {
                    f.write_str("its determinant is not positive")?;
                } else {
                    write!(f, "|R^T R - I| = {defect:.3e}")?;
                }
                write!(
                    f,
                    "; a rotation has R^T R = I within {ROTATION_TOLERANCE:e} per entry and det R = +1)"
                )
            }
            BodyError::SpinWithoutRotation { mount: m } => write!(
                f,
                "{m}.w and {m}.z must be zero: this FMU was built for a scene without rotation \
                 (declare \"rotation\" in the input's scene.loads to model a rotating mount)"
            ),
            BodyError::StepSize(h) => write!(f, "step size {h} must be positive and finite"),
            BodyError::SingularInertia => f.write_str("the body's inertia matrix became singular"),
            BodyError::NoQuasiStaticEquilibrium => f.write_str(
                "the quasi-static modes have no equilibrium: the effective stiffness above the dynamic cutoff is \
                 singular at the present spin and loads (raise reduction.dynamic_cutoff so that these modes are \
                 integrated)",
            ),
            BodyError::NoStaticEquilibrium => f.write_str(
                "no static equilibrium: the body is unstable under the present loads (centrifugal softening beyond the elastic stiffness; enable geometric stiffening?)",
            ),
            BodyError::Orientation { quat, norm } => write!(
                f,
                "the orientation quaternion frame.Q = {quat:?} has norm {norm:e}, which is no orientation \
                 (a state of norm between 0.5 and 2 is normalised; retry with states nearer the last \
                 accepted ones)"
            ),
            BodyError::TooManySubsteps { h, spin, needed, most, longest } => write!(
                f,
                "a step of h = {h} s of this free-floating body spinning at |W| = {spin:.3} rad/s needs \
                 {needed:.0} substeps of at most {SUBSTEP_ANGLE} rad, more than the {most} one call takes; \
                 the largest step at this spin is h = {longest:.3e} s (substeps = |W| h / {SUBSTEP_ANGLE} rad)"
            ),
            BodyError::StepNotFinite { h } => write!(
                f,
                "the modal state became non-finite in this step of h = {h} s (a step or load beyond the body's range)"
            ),
            BodyError::Unstable => write!(f, "the deformation grew without bound: {UNSTABLE_STIFFNESS}"),
            BodyError::StepEndOutOfRange { what, value, h, unstable } => {
                write!(f, "{what} would be {value:e} after this step of h = {h:e} s, ")?;
                if value.is_finite() {
                    write!(f, "beyond {REAL_LIMIT:e}")?;
                } else {
                    f.write_str("not finite")?;
                }
                if *unstable {
                    write!(f, ": the deformation grew without bound: {UNSTABLE_STIFFNESS}")?;
                } else {
                    f.write_str(": a step, load or input rate far beyond the body's range")?;
                }
                f.write_str("; the state before the step is kept")
            }
            BodyError::WorkspaceMismatch { modes, flanges } => write!(
                f,
                "the step's workspace was not made for this body of {modes} modes and {flanges} force flanges"
            ),
            BodyError::Workspace(e) => fmt::Display::fmt(e, f),
            BodyError::State(e) => fmt::Display::fmt(e, f),
        }
    }
}

impl std::error::Error for BodyError {
    /// The wrapped errors are shown as they are (transparent): their own sources come next.
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            BodyError::Workspace(e) => e.source(),
            BodyError::State(e) => e.source(),
            _ => None,
        }
    }
}

impl From<WorkspaceTooSmall> for BodyError {
    fn from(e: WorkspaceTooSmall) -> Self {
        BodyError::Workspace(e)
    }
}

impl From<StateMismatch> for BodyError {
    fn from(e: StateMismatch) -> Self {
        BodyError::State(e)
    }
}

impl fmt::Display for StateMismatch {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let kind = |free: bool| if free { "free-floating" } else { "mounted" };
        match self {
            StateMismatch::Modes { q, qd, n } => {
                write!(f, "the state has {q} and {qd} modal coordinates and velocities, the body {n} modes")
            }
            StateMismatch::Flanges { found, n } => {
                write!(f, "the state has loads on {found} flanges, the body {n} force flanges")
            }
            StateMismatch::Kind { free, body_free } => {
                write!(f, "the state is of a {} body, this body is {}", kind(*free), kind(*body_free))
            }
            StateMismatch::SteppedLoads { found, n } => {
                write!(f, "the state has stepped loads on {found} flanges, the body {n}")
            }
            StateMismatch::CouplingReference { c_d, c_k, n } => {
                write!(f, "the state's coupling reference does not fit this body ({c_d} x {c_k} values for {n} modes)")
            }
            StateMismatch::CouplingReferenceNotFinite => {
                f.write_str("the state's coupling reference has non-finite values")
            }
        }
    }
}

impl std::error::Error for StateMismatch {}

impl fmt::Display for OutOfRange {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            OutOfRange::NotFinite(value) => write!(f, "{value} is not a finite number"),
            OutOfRange::Beyond(value) => {
                write!(f, "|{value:e}| is beyond {REAL_LIMIT:e}, the range of any physical quantity in SI units")
            }
            OutOfRange::RateBeyond(value) => {
                write!(f, "|{value:e}| is beyond {REAL_LIMIT:e}, the range of any physical rate in SI units")
            }
            OutOfRange::NegativeDamping(value) => {
                write!(f, "{value} is negative: damping must not feed energy into the body")
            }
            OutOfRange::RotationEntry(value) => {
                write!(f, "{value} is no entry of a rotation matrix (each lies in [-1, 1])")
            }
        }
    }
}

impl std::error::Error for OutOfRange {}

/// Transparent: the class is the variant, the message the body's error.
impl fmt::Display for StepError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt::Display::fmt(self.error(), f)
    }
}

impl std::error::Error for StepError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        self.error().source()
    }
}

// Debug of each error is its message, as the FMU logs it: the FMU binary carries no derived
// dump of its errors (some 16 kB); the variants are for matching.
impl std::fmt::Debug for BodyError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        std::fmt::Display::fmt(self, f)
    }
}

impl std::fmt::Debug for StateMismatch {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        std::fmt::Display::fmt(self, f)
    }
}

impl std::fmt::Debug for OutOfRange {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        std::fmt::Display::fmt(self, f)
    }
}

impl std::fmt::Debug for StepError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        std::fmt::Display::fmt(self, f)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The texts hosts log, kept word for word through the move to typed errors.
    #[test]
    fn messages_are_the_ones_hosts_log() {
        let e = BodyError::NotARotation { mount: "base".into(), defect: f64::INFINITY };
        assert_eq!(
            e.to_string(),
            "base.R is not a proper rotation matrix (its determinant is not positive; a rotation has R^T R = I \
             within 1e-2 per entry and det R = +1)"
        );
        let e = BodyError::NotARotation { mount: "base".into(), defect: 0.1 };
        assert!(e.to_string().contains("(|R^T R - I| = 1.000e-1; a rotation"), "{e}");
        let e = BodyError::StepEndOutOfRange {
            what: "the modal state q[1]".into(),
            value: f64::NAN,
            h: 0.1,
            unstable: false,
        };
        assert_eq!(
            e.to_string(),
            "the modal state q[1] would be NaN after this step of h = 1e-1 s, not finite: a step, load or input \
             rate far beyond the body's range; the state before the step is kept"
        );
        let e = StepError::NotTaken(BodyError::Workspace(WorkspaceTooSmall { needed: 2, available: 1 }));
        assert_eq!(e.to_string(), WorkspaceTooSmall { needed: 2, available: 1 }.to_string());
        assert_eq!(
            StateMismatch::Kind { free: true, body_free: false }.to_string(),
            "the state is of a free-floating body, this body is mounted"
        );
    }
}
