//! The linear algebra's failures, a variant per class, so that the stages above can say what to
//! change (a singular stiffness is the model's, an eigen-solve that does not converge asks for
//! fewer modes) without reading the words. Each message names the matrix and, where one helps,
//! what to do.

use petsc_backend::BackendError;

/// A failure of the linear algebra.
#[derive(Debug, Clone, thiserror::Error)]
pub enum LinalgError {
    /// A matrix to be factored is singular or, for a Cholesky factor, not positive definite: in
    /// a model, a mechanism or a part no flange holds.
    #[error("{0}")]
    Singular(String),
    /// An iterative or dense eigen-solve that did not reach its accuracy.
    #[error("{0}")]
    NotConverged(String),
    /// More than the machine can hold, or more modes than the solver searches.
    #[error("{0}")]
    TooLarge(String),
    /// Operands that do not fit together or hold no usable numbers (sizes, non-finite entries,
    /// a vanishing mass): a defect of the caller's data.
    #[error("{0}")]
    Inconsistent(String),
    /// The distributed back-end's own failure.
    #[error(transparent)]
    Backend(#[from] BackendError),
}

pub type Result<T> = std::result::Result<T, LinalgError>;
