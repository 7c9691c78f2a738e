//! The back-end's failures, by who has to act: the back-end could not be started or reached
//! (the launcher, the Python packages, the network: nothing in the model to change), or the
//! numbers failed on the ranks (a factor MUMPS could not make, a request the driver refused).

/// A failure of the distributed back-end.
#[derive(Debug, Clone, thiserror::Error)]
pub enum BackendError {
    /// The back-end could not be started or reached, or it ended: the launcher, the Python
    /// packages, the network, a rank stopped.
    #[error("the PETSc back-end: {0}")]
    Unavailable(String),
    /// MUMPS could not factor the matrix (`what` names it): the model's numbers, not the
    /// back-end, are to be looked at.
    #[error("{what} could not be factored by MUMPS: {reason}")]
    NotFactored { what: String, reason: String },
    /// The driver answered a request with a failure, or an answer of the wrong size.
    #[error("{0}")]
    Request(String),
    /// A matrix the back-end cannot take (PETSc's 32-bit indices), or its job file unwritable.
    #[error("{0}")]
    Matrix(String),
}

/// Why a launcher command is refused, a sentence without the command.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub struct LauncherRefusal(pub &'static str);

pub type Result<T> = std::result::Result<T, BackendError>;
