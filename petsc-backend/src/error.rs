//! The back-end's failures, by who has to act: the back-end could not be started or reached
//! (the launcher, the Python packages, the network: nothing in the model to change), or the
//! numbers failed on the ranks (a factor MUMPS could not make, a request the driver refused).

/// A failure of the distributed back-end.
#[derive(Debug, Clone, thiserror::Error)]
pub enum BackendError {
    /// The back-end could not be started or reached, or it ended: the launcher, the Python
    /// packages, the network, a rank stopped.
    #[error("the PETSc back-end: {message}")]
    Unavailable {
        message: String,
        #[source]
        cause: Option<Cause>,
    },
    /// MUMPS could not factor the matrix (`what` names it): the model's numbers, not the
    /// back-end, are to be looked at.
    #[error("{what} could not be factored by MUMPS: {reason}")]
    NotFactored { what: String, reason: String },
    /// The driver answered a request with a failure, or an answer of the wrong size.
    #[error("{message}")]
    Request {
        message: String,
        #[source]
        cause: Option<Cause>,
    },
    /// A matrix the back-end cannot take (PETSc's 32-bit indices), or its job file unwritable.
    #[error("{message}")]
    Matrix {
        message: String,
        #[source]
        cause: Option<Cause>,
    },
}

impl BackendError {
    pub fn unavailable(message: impl Into<String>) -> Self {
        BackendError::Unavailable { message: message.into(), cause: None }
    }
    pub fn request(message: impl Into<String>) -> Self {
        BackendError::Request { message: message.into(), cause: None }
    }
    pub fn matrix(message: impl Into<String>) -> Self {
        BackendError::Matrix { message: message.into(), cause: None }
    }
    /// `self` keeping `cause`, the error its message was made from, as its source; the message
    /// is unchanged. MUMPS's refusal comes from the driver as words, with no error to keep.
    pub fn caused_by(mut self, cause: impl std::error::Error + Send + Sync + 'static) -> Self {
        match &mut self {
            BackendError::Unavailable { cause: kept, .. }
            | BackendError::Request { cause: kept, .. }
            | BackendError::Matrix { cause: kept, .. } => *kept = Some(Cause::new(cause)),
            BackendError::NotFactored { .. } => {}
        }
        self
    }
}

/// Why a launcher command is refused, a sentence without the command.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub struct LauncherRefusal(pub &'static str);

/// The error a failure came from (the system's, a library's), kept so that callers can reach it
/// by type through `source()`; its words are already in the failure's message, which users read
/// unchanged. Shared, so that the errors holding it stay `Clone`; it derefs to the error itself
/// (and is no error of its own), so `source()` gives that error, not a wrapper of it. Defined in
/// this, the lowest crate, so that the crates above keep their causes the same way.
#[derive(Clone)]
pub struct Cause(std::sync::Arc<dyn std::error::Error + Send + Sync + 'static>);

impl Cause {
    pub fn new(cause: impl std::error::Error + Send + Sync + 'static) -> Self {
        Cause(std::sync::Arc::new(cause))
    }
}

impl std::ops::Deref for Cause {
    type Target = dyn std::error::Error + Send + Sync + 'static;
    fn deref(&self) -> &Self::Target {
        &*self.0
    }
}

impl std::fmt::Display for Cause {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        std::fmt::Display::fmt(&*self.0, f)
    }
}

impl std::fmt::Debug for Cause {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        std::fmt::Debug::fmt(&*self.0, f)
    }
}

/// Errors compare by what they say, and a cause is already said in its error's message.
impl PartialEq for Cause {
    fn eq(&self, _: &Self) -> bool {
        true
    }
}

impl Eq for Cause {}

pub type Result<T> = std::result::Result<T, BackendError>;
