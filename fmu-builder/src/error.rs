//! Errors of the builder: every message names where the problem is (file and field) and what
//! was expected, because the user fixes it in their input, not in our code.

use std::fmt;
use std::path::PathBuf;

#[derive(Debug)]
pub enum BuildError {
    /// Something in the input file: `field` is a path like `flanges[1].nodes`.
    Input { file: PathBuf, field: String, message: String },
    /// A numerical step failed (a singular stiffness, an eigensolver that did not converge).
    Numerical(String),
    Io { path: PathBuf, message: String },
}

impl BuildError {
    pub fn input(file: &std::path::Path, field: impl Into<String>, message: impl Into<String>) -> Self {
        BuildError::Input { file: file.to_owned(), field: field.into(), message: message.into() }
    }
    pub fn io(path: &std::path::Path, e: impl fmt::Display) -> Self {
        BuildError::Io { path: path.to_owned(), message: e.to_string() }
    }
}

impl fmt::Display for BuildError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            BuildError::Input { file, field, message } if field.is_empty() => {
                write!(f, "{}: {message}", file.display())
            }
            BuildError::Input { file, field, message } => write!(f, "{}: {field}: {message}", file.display()),
            BuildError::Numerical(m) => write!(f, "{m}"),
            BuildError::Io { path, message } => write!(f, "{}: {message}", path.display()),
        }
    }
}

impl std::error::Error for BuildError {}

pub type Result<T> = std::result::Result<T, BuildError>;
