//! Errors of the builder: every message names where the problem is (file and field) and what
//! was expected, because the user fixes it in their input, not in our code.

use std::fmt;
use std::path::PathBuf;

#[derive(Debug, thiserror::Error)]
pub enum BuildError {
    /// Something in the input file: `field` is a path like `flanges[1].nodes`, or empty when the
    /// whole file is meant.
    #[error("{}: {}{message}", .file.display(), field_prefix(.field))]
    Input { file: PathBuf, field: String, message: String },
    /// A numerical step failed (a singular stiffness, an eigensolver that did not converge).
    #[error("{0}")]
    Numerical(String),
    #[error("{}: {message}", .path.display())]
    Io { path: PathBuf, message: String },
    /// The distributed back-end could not be started or reached (launcher, Python packages,
    /// network): nothing in the input's model to change.
    #[error("the PETSc back-end: {0}")]
    Backend(String),
}

fn field_prefix(field: &str) -> String {
    if field.is_empty() { String::new() } else { format!("{field}: ") }
}

impl BuildError {
    pub fn input(file: &std::path::Path, field: impl Into<String>, message: impl Into<String>) -> Self {
        BuildError::Input { file: file.to_owned(), field: field.into(), message: message.into() }
    }
    pub fn io(path: &std::path::Path, e: impl fmt::Display) -> Self {
        BuildError::Io { path: path.to_owned(), message: e.to_string() }
    }
}

pub type Result<T> = std::result::Result<T, BuildError>;

#[cfg(test)]
mod tests {
    use super::BuildError;
    use std::path::Path;

    #[test]
    fn messages_name_the_file_and_the_field() {
        let with_field = BuildError::input(Path::new("beam.json"), "flanges[1].nodes", "selects no node");
        assert_eq!(with_field.to_string(), "beam.json: flanges[1].nodes: selects no node");
        let whole_file = BuildError::input(Path::new("beam.json"), "", "is not JSON");
        assert_eq!(whole_file.to_string(), "beam.json: is not JSON");
        assert_eq!(BuildError::io(Path::new("out/B.fmu"), "denied").to_string(), "out/B.fmu: denied");
    }
}
