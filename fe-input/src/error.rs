//! The input's failures: every message names the file and the field (or line) and what was
//! expected, because the user fixes it in their input, not in our code.

use std::path::{Path, PathBuf};

/// A failure of the input stage.
#[derive(Debug, thiserror::Error)]
pub enum InputError {
    /// Something in the input file: `field` is a path like `flanges[1].nodes`, or empty when the
    /// whole file is meant.
    #[error("{}: {}{message}", .file.display(), field_prefix(.field))]
    Field {
        file: PathBuf,
        field: String,
        message: String,
        #[source]
        cause: Option<Cause>,
    },
    /// The input file itself cannot be read.
    #[error("{}: cannot read the input: it {source}", .path.display())]
    Unreadable {
        path: PathBuf,
        #[source]
        source: Refusal,
    },
    /// What the builder carries inside itself (the input's schema) failed: a defect of the
    /// build, not of the input.
    #[error("{message}")]
    Internal {
        message: String,
        #[source]
        cause: Option<Cause>,
    },
}

impl InputError {
    pub fn field(file: &Path, field: impl Into<String>, message: impl Into<String>) -> Self {
        InputError::Field { file: file.to_owned(), field: field.into(), message: message.into(), cause: None }
    }
    /// `self` keeping `cause`, the error its message was made from, as its source; the message
    /// is unchanged. A refusal of the file keeps its own.
    pub fn caused_by(mut self, cause: impl std::error::Error + Send + Sync + 'static) -> Self {
        match &mut self {
            InputError::Field { cause: kept, .. } | InputError::Internal { cause: kept, .. } => {
                *kept = Some(Cause::new(cause))
            }
            InputError::Unreadable { .. } => {}
        }
        self
    }
}

/// `field: ` before a message, or nothing for the whole file.
pub fn field_prefix(field: &str) -> String {
    if field.is_empty() { String::new() } else { format!("{field}: ") }
}

pub use petsc_backend::error::Cause;

/// Why a file is refused: a sentence without the path (callers name the path and the field or
/// option the way their messages do).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Refusal {
    pub reason: String,
    /// The system's or a library's error the refusal was made of, if any.
    pub cause: Option<Cause>,
}

impl Refusal {
    /// A refusal whose sentence tells `cause` in words, keeping `cause` itself as its source.
    pub fn caused_by(reason: impl Into<String>, cause: impl std::error::Error + Send + Sync + 'static) -> Self {
        Refusal { reason: reason.into(), cause: Some(Cause::new(cause)) }
    }
}

impl std::error::Error for Refusal {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        self.cause.as_deref().map(|c| c as &(dyn std::error::Error + 'static))
    }
}

impl From<String> for Refusal {
    fn from(reason: String) -> Self {
        Refusal { reason, cause: None }
    }
}

impl From<&str> for Refusal {
    fn from(reason: &str) -> Self {
        Refusal::from(reason.to_string())
    }
}

impl std::fmt::Display for Refusal {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.reason)
    }
}

pub type Result<T> = std::result::Result<T, InputError>;
