//! Errors of the builder: every message names where the problem is (file and field) and what
//! was expected, because the user fixes it in their input, not in our code.

use std::fmt;
use std::path::PathBuf;

pub use fe_input::error::{Cause as SharedCause, InputError, Refusal};
pub use fe_linalg::error::LinalgError;
pub use petsc_backend::BackendError;

/// The error a failure's words were made from (the system's, a library's), kept as its source so
/// that a caller can tell it by type; the message users read already says it.
pub type Cause = Box<dyn std::error::Error + Send + Sync + 'static>;

#[derive(Debug, thiserror::Error)]
pub enum BuildError {
    /// Something in the input file, named by its field (the input stage's error).
    #[error(transparent)]
    Input(#[from] InputError),
    /// The linear algebra failed: a factor, an eigen-solve, the distributed back-end.
    #[error(transparent)]
    Linalg(#[from] LinalgError),
    /// A numerical step of the model or the reduction failed (a dynamic stiffness that cannot
    /// be factored at a frequency, a sparse pattern that cannot be built).
    #[error("{message}")]
    Numerical {
        message: String,
        #[source]
        cause: Option<Cause>,
    },
    /// The part can move without deforming, or a flange's coupling has no unique solution: a
    /// mechanism, a mount that does not hold the part, a part without mass in some direction.
    #[error("{message}")]
    Singular {
        message: String,
        #[source]
        cause: Option<Cause>,
    },
    /// The reduced model fails the checks every build must pass against the full model.
    #[error("{message}")]
    Inaccurate {
        message: String,
        #[source]
        cause: Option<Cause>,
    },
    /// A result (the report, the reduced body's arrays, the FMU's first steps) is NaN or
    /// infinite.
    #[error("{message}")]
    NotFinite {
        message: String,
        #[source]
        cause: Option<Cause>,
    },
    /// A check of the builder's own work failed (sizes that must agree, what it serialises): a
    /// defect to report, not an input to change.
    #[error("{message}")]
    Internal {
        message: String,
        #[source]
        cause: Option<Cause>,
    },
    /// A numerical failure put against the part of the input that drives the stage it happened
    /// in, with what to change there: the user fixes their input, not our code.
    #[error("{}: {}{source}{}", .file.display(), field_prefix(.place.field), hint_suffix(.place.hint))]
    InInput {
        file: PathBuf,
        place: InputHint,
        #[source]
        source: Box<BuildError>,
    },
    /// The system refused a read or a write.
    #[error("{}: {source}", .path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// A file that cannot be read, written or used as what it is given for, and why (not a
    /// regular file, too large, a binary of the wrong platform, an export the part cannot give).
    #[error("{}: {message}", .path.display())]
    File {
        path: PathBuf,
        message: String,
        #[source]
        cause: Option<Cause>,
    },
    /// A runtime binary of another platform refused as the FMU's binary, and why.
    #[error("{}: refused as the FMU's {platform} binary (--platform-binary {platform}=...): it {reason}", .path.display())]
    Binary {
        path: PathBuf,
        platform: String,
        #[source]
        reason: Refusal,
    },
    /// A command-line option's value refused before the build.
    #[error("{option}: {message}")]
    CommandLine {
        option: String,
        message: String,
        #[source]
        cause: Option<Cause>,
    },
    /// An output refused before any work: it cannot be written, or would overwrite the input,
    /// another output or (without --force) an existing file. `shown` is the option and its path.
    #[error("{shown}: {reason}")]
    Destination {
        shown: String,
        reason: String,
        #[source]
        cause: Option<Cause>,
    },
    /// An export asked for besides the FMU failed after the FMU was written.
    #[error("{option}: {source}; the FMU {} was written", .fmu.display())]
    Export {
        option: &'static str,
        fmu: PathBuf,
        #[source]
        source: Box<BuildError>,
    },
}

/// Where in the input a numerical failure is put, and what to change there.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct InputHint {
    /// The field, as in `Input`'s; empty for the whole file.
    pub field: &'static str,
    /// What to change, appended after the failure; empty for nothing to add.
    pub hint: &'static str,
}

use fe_input::error::field_prefix;

fn hint_suffix(hint: &str) -> String {
    if hint.is_empty() { String::new() } else { format!("; {hint}") }
}

impl BuildError {
    pub fn input(file: &std::path::Path, field: impl Into<String>, message: impl Into<String>) -> Self {
        BuildError::Input(InputError::field(file, field, message))
    }
    /// A numerical failure as one of the input's `place`; any other error is already the
    /// input's, the back-end's (it could not be started or reached) or a file's, and stays as
    /// it is.
    pub fn in_input(self, file: &std::path::Path, place: InputHint) -> Self {
        match self {
            BuildError::Numerical { .. }
            | BuildError::Singular { .. }
            | BuildError::Inaccurate { .. }
            | BuildError::NotFinite { .. }
            | BuildError::Internal { .. } => {
                BuildError::InInput { file: file.to_owned(), place, source: Box::new(self) }
            }
            BuildError::Linalg(LinalgError::Backend(BackendError::Unavailable { .. })) => self,
            BuildError::Linalg(_) => BuildError::InInput { file: file.to_owned(), place, source: Box::new(self) },
            other => other,
        }
    }
    /// A factor that could not be made because its matrix is singular or not positive definite:
    /// in a model, a mechanism or a mount that does not hold the part.
    pub fn is_singular(&self) -> bool {
        matches!(
            self,
            BuildError::Singular { .. }
                | BuildError::Linalg(
                    LinalgError::Singular { .. } | LinalgError::Backend(BackendError::NotFactored { .. })
                )
        )
    }
    pub fn io(path: &std::path::Path, source: std::io::Error) -> Self {
        BuildError::Io { path: path.to_owned(), source }
    }
    pub fn file(path: &std::path::Path, message: impl fmt::Display) -> Self {
        BuildError::File { path: path.to_owned(), message: message.to_string(), cause: None }
    }
    pub fn numerical(message: impl Into<String>) -> Self {
        BuildError::Numerical { message: message.into(), cause: None }
    }
    pub fn singular(message: impl Into<String>) -> Self {
        BuildError::Singular { message: message.into(), cause: None }
    }
    pub fn inaccurate(message: impl Into<String>) -> Self {
        BuildError::Inaccurate { message: message.into(), cause: None }
    }
    pub fn not_finite(message: impl Into<String>) -> Self {
        BuildError::NotFinite { message: message.into(), cause: None }
    }
    pub fn internal(message: impl Into<String>) -> Self {
        BuildError::Internal { message: message.into(), cause: None }
    }
    pub fn destination(shown: impl Into<String>, reason: impl Into<String>) -> Self {
        BuildError::Destination { shown: shown.into(), reason: reason.into(), cause: None }
    }
    pub fn command_line(option: impl Into<String>, message: impl Into<String>) -> Self {
        BuildError::CommandLine { option: option.into(), message: message.into(), cause: None }
    }
    /// `self` keeping `cause`, the error its message was made from, as its source; the message
    /// is unchanged. A variant that has its own typed source keeps that one.
    pub fn caused_by(mut self, cause: impl std::error::Error + Send + Sync + 'static) -> Self {
        if let BuildError::Input(e) = self {
            return BuildError::Input(e.caused_by(cause));
        }
        match &mut self {
            BuildError::Numerical { cause: kept, .. }
            | BuildError::Singular { cause: kept, .. }
            | BuildError::Inaccurate { cause: kept, .. }
            | BuildError::NotFinite { cause: kept, .. }
            | BuildError::Internal { cause: kept, .. }
            | BuildError::File { cause: kept, .. }
            | BuildError::CommandLine { cause: kept, .. }
            | BuildError::Destination { cause: kept, .. } => *kept = Some(Box::new(cause)),
            _ => {}
        }
        self
    }
}

/// The back-end's failures reach the build as the linear algebra's, whose solves run there.
impl From<BackendError> for BuildError {
    fn from(e: BackendError) -> Self {
        BuildError::Linalg(LinalgError::Backend(e))
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
        let denied = std::io::Error::from(std::io::ErrorKind::PermissionDenied);
        let io = BuildError::io(Path::new("out/B.fmu"), denied);
        assert_eq!(io.to_string(), "out/B.fmu: permission denied");
        // the system's error stays reachable, not only its words
        let source = std::error::Error::source(&io).and_then(|s| s.downcast_ref::<std::io::Error>());
        assert_eq!(source.map(|e| e.kind()), Some(std::io::ErrorKind::PermissionDenied));
    }

    #[test]
    fn a_numerical_failure_put_against_the_input_keeps_it_as_its_source() {
        use super::InputHint;
        use std::error::Error;
        let place = InputHint { field: "geometry", hint: "check the mesh" };
        let e = BuildError::numerical("the stiffness is singular").in_input(Path::new("part.json"), place);
        assert_eq!(e.to_string(), "part.json: geometry: the stiffness is singular; check the mesh");
        assert_eq!(e.source().map(|s| s.to_string()).as_deref(), Some("the stiffness is singular"));
        let whole = BuildError::numerical("no FMU").in_input(Path::new("p.json"), InputHint { field: "", hint: "" });
        assert_eq!(whole.to_string(), "p.json: no FMU");
        // an input error is already the input's: unchanged
        let input = BuildError::input(Path::new("p.json"), "flanges", "none");
        assert_eq!(input.in_input(Path::new("q.json"), place).to_string(), "p.json: flanges: none");
    }

    /// The error a message was made from stays reachable by type, below the same words, in its
    /// class and when the failure is put against the input.
    #[test]
    fn a_kept_cause_changes_neither_the_words_nor_the_class() {
        use super::InputHint;
        use std::error::Error;
        let full = || std::io::Error::from(std::io::ErrorKind::StorageFull);
        let e = BuildError::singular("the mass is singular").caused_by(full());
        assert_eq!(e.to_string(), "the mass is singular");
        assert!(e.is_singular());
        let placed = e.in_input(Path::new("p.json"), InputHint { field: "material", hint: "" });
        assert_eq!(placed.to_string(), "p.json: material: the mass is singular");
        let below = placed.source().and_then(Error::source).and_then(|s| s.downcast_ref::<std::io::Error>());
        assert_eq!(below.map(std::io::Error::kind), Some(std::io::ErrorKind::StorageFull));
        // an input's field error keeps it too, through the input stage's own error
        let input = BuildError::input(Path::new("p.json"), "geometry", "bad").caused_by(full());
        assert_eq!(input.to_string(), "p.json: geometry: bad");
        assert!(input.source().is_some_and(|s| s.is::<std::io::Error>()));
    }

    /// A failure that means the part can move without deforming is told from the others by
    /// its class, not its words: it is put against the mesh and the mount, not the reduction.
    #[test]
    fn singular_failures_are_known_by_their_class() {
        use super::{BackendError, LinalgError};
        let singular: Vec<BuildError> = vec![
            BuildError::singular("x"),
            LinalgError::singular("x").into(),
            BackendError::NotFactored { what: "K".into(), reason: "x".into() }.into(),
        ];
        let other: Vec<BuildError> = vec![
            BuildError::numerical("the stiffness is singular"),
            LinalgError::not_converged("x").into(),
            BackendError::unavailable("x").into(),
        ];
        assert_eq!((singular.len(), other.len()), (3, 3));
        assert!(singular.iter().all(BuildError::is_singular));
        assert!(!other.iter().any(BuildError::is_singular));
        // the back-end that cannot be reached is not the input's to change
        let unreachable = BuildError::from(BackendError::unavailable("mpirun not found"));
        let place = super::InputHint { field: "geometry", hint: "h" };
        assert_eq!(
            unreachable.in_input(Path::new("p.json"), place).to_string(),
            "the PETSc back-end: mpirun not found"
        );
    }

    /// The words users read for each failure class: the variants are typed, the messages are
    /// the ones the command line has always printed.
    #[test]
    fn every_failure_class_keeps_its_message() {
        use super::{BackendError, InputError, LinalgError, Refusal};
        use std::path::PathBuf;
        let cases: Vec<(BuildError, &str)> = vec![
            (BuildError::file(Path::new("a.vtk"), "needs a part with elements"), "a.vtk: needs a part with elements"),
            (
                BuildError::Input(InputError::Unreadable {
                    path: PathBuf::from("b.json"),
                    source: Refusal::from("is a folder"),
                }),
                "b.json: cannot read the input: it is a folder",
            ),
            (
                BuildError::command_line("--platform-binary x", "expected PLATFORM=FILE"),
                "--platform-binary x: expected PLATFORM=FILE",
            ),
            (BuildError::destination("-o B.fmu", "B.fmu exists; pass --force"), "-o B.fmu: B.fmu exists; pass --force"),
            (
                BuildError::Export {
                    option: "--report",
                    fmu: PathBuf::from("B.fmu"),
                    source: Box::new(BuildError::io(Path::new("r.json"), std::io::Error::other("disk full"))),
                },
                "--report: r.json: disk full; the FMU B.fmu was written",
            ),
            (
                BuildError::Binary {
                    path: PathBuf::from("f.dll"),
                    platform: "win64".into(),
                    reason: "is empty".into(),
                },
                "f.dll: refused as the FMU's win64 binary (--platform-binary win64=...): it is empty",
            ),
            (BackendError::unavailable("mpirun not found").into(), "the PETSc back-end: mpirun not found"),
            (
                BackendError::NotFactored { what: "the stiffness".into(), reason: "singular".into() }.into(),
                "the stiffness could not be factored by MUMPS: singular",
            ),
            (
                LinalgError::singular("the stiffness is not positive definite").into(),
                "the stiffness is not positive definite",
            ),
            (
                BuildError::singular("the reduced stiffness is not positive definite"),
                "the reduced stiffness is not positive definite",
            ),
            (BuildError::not_finite("the report's x is not a finite number"), "the report's x is not a finite number"),
        ];
        assert_eq!(cases.len(), 11);
        for (error, words) in cases {
            assert_eq!(error.to_string(), words);
        }
    }
}
