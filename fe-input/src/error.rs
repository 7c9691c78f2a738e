//! The input's failures: every message names the file and the field (or line) and what was
//! expected, because the user fixes it in their input, not in our code.

use std::path::{Path, PathBuf};

/// A failure of the input stage.
#[derive(Debug, thiserror::Error)]
pub enum InputError {
    /// Something in the input file: `field` is a path like `flanges[1].nodes`, or empty when the
    /// whole file is meant.
    #[error("{}: {}{message}", .file.display(), field_prefix(.field))]
    Field { file: PathBuf, field: String, message: String },
    /// The input file itself cannot be read.
    #[error("{}: cannot read the input: it {source}", .path.display())]
    Unreadable {
        path: PathBuf,
        #[source]
        source: Refusal,
    },
    /// What the builder carries inside itself (the input's schema) failed: a defect of the
    /// build, not of the input.
    #[error("{0}")]
    Internal(String),
}

impl InputError {
    pub fn field(file: &Path, field: impl Into<String>, message: impl Into<String>) -> Self {
        InputError::Field { file: file.to_owned(), field: field.into(), message: message.into() }
    }
}

/// `field: ` before a message, or nothing for the whole file.
pub fn field_prefix(field: &str) -> String {
    if field.is_empty() { String::new() } else { format!("{field}: ") }
}

/// Why a file is refused: a sentence without the path (callers name the path and the field or
/// option the way their messages do).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Refusal(pub String);

impl std::error::Error for Refusal {}

impl From<&str> for Refusal {
    fn from(reason: &str) -> Self {
        Refusal(reason.to_string())
    }
}

impl std::fmt::Display for Refusal {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

pub type Result<T> = std::result::Result<T, InputError>;
