//! The linear algebra's failures, a variant per class, so that the stages above can say what to
//! change (a singular stiffness is the model's, an eigen-solve that does not converge asks for
//! fewer modes) without reading the words. Each message names the matrix and, where one helps,
//! what to do.

use petsc_backend::{BackendError, Cause};

/// A failure of the linear algebra.
#[derive(Debug, Clone, thiserror::Error)]
pub enum LinalgError {
    /// A matrix to be factored is singular or, for a Cholesky factor, not positive definite: in
    /// a model, a mechanism or a part no flange holds.
    #[error("{message}")]
    Singular {
        message: String,
        #[source]
        cause: Option<Cause>,
    },
    /// An iterative or dense eigen-solve that did not reach its accuracy.
    #[error("{message}")]
    NotConverged {
        message: String,
        #[source]
        cause: Option<Cause>,
    },
    /// More than the machine can hold, or more modes than the solver searches.
    #[error("{message}")]
    TooLarge {
        message: String,
        #[source]
        cause: Option<Cause>,
    },
    /// Operands that do not fit together or hold no usable numbers (sizes, non-finite entries,
    /// a vanishing mass): a defect of the caller's data.
    #[error("{message}")]
    Inconsistent {
        message: String,
        #[source]
        cause: Option<Cause>,
    },
    /// The distributed back-end's own failure.
    #[error(transparent)]
    Backend(#[from] BackendError),
}

impl LinalgError {
    pub fn singular(message: impl Into<String>) -> Self {
        LinalgError::Singular { message: message.into(), cause: None }
    }
    pub fn not_converged(message: impl Into<String>) -> Self {
        LinalgError::NotConverged { message: message.into(), cause: None }
    }
    pub fn too_large(message: impl Into<String>) -> Self {
        LinalgError::TooLarge { message: message.into(), cause: None }
    }
    pub fn inconsistent(message: impl Into<String>) -> Self {
        LinalgError::Inconsistent { message: message.into(), cause: None }
    }
    /// `self` keeping `cause` (faer's error, say), the error its message was made from, as its
    /// source; the message is unchanged. The back-end's failures keep their own.
    pub fn caused_by(mut self, cause: impl std::error::Error + Send + Sync + 'static) -> Self {
        match &mut self {
            LinalgError::Singular { cause: kept, .. }
            | LinalgError::NotConverged { cause: kept, .. }
            | LinalgError::TooLarge { cause: kept, .. }
            | LinalgError::Inconsistent { cause: kept, .. } => *kept = Some(Cause::new(cause)),
            LinalgError::Backend(_) => {}
        }
        self
    }
}

pub type Result<T> = std::result::Result<T, LinalgError>;
