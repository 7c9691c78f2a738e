//! Real failures keep the error they came from: a caller (a GUI, a script driving the library)
//! can tell a missing file from a malformed one by the system's or the parser's own error type,
//! found by walking `source()`, while the message users read stays the sentence it always was.

use fmu_builder::error::BuildError;
use fmu_builder::job::{self, Job};
use std::error::Error;
use std::path::{Path, PathBuf};

/// A fresh folder of this test's own under the system's temporary folder.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("fmu-builder-error-sources-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The first error of type `T` in the chain below `e` (`e` itself excluded).
fn cause_of<T: Error + 'static>(e: &BuildError) -> Option<&T> {
    let mut next = e.source();
    while let Some(s) = next {
        if let Some(found) = s.downcast_ref::<T>() {
            return Some(found);
        }
        next = s.source();
    }
    None
}

fn build(dir: &Path, input: PathBuf) -> BuildError {
    let job = Job { input, output: Some(dir.join("out.fmu")), quiet: true, ..Job::default() };
    job::run(&job).expect_err("the build must fail")
}

#[test]
fn a_missing_input_keeps_the_systems_error() {
    let dir = scratch("missing");
    let input = dir.join("absent.json");
    let e = build(&dir, input.clone());
    assert_eq!(
        e.to_string(),
        format!(
            "{}: cannot read the input: it cannot be read: No such file or directory (os error 2)",
            input.display()
        )
    );
    let io = cause_of::<std::io::Error>(&e).expect("the io::Error is in the chain");
    assert_eq!(io.kind(), std::io::ErrorKind::NotFound);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn malformed_json_keeps_the_parsers_error() {
    let dir = scratch("json");
    let input = dir.join("part.json");
    std::fs::write(&input, "{\"geometry\": ").unwrap();
    let e = build(&dir, input.clone());
    assert_eq!(
        e.to_string(),
        format!("{}: line 1 column 13: not valid JSON: EOF while parsing a value at line 1 column 13", input.display())
    );
    let json = cause_of::<serde_json::Error>(&e).expect("the serde_json::Error is in the chain");
    assert!(json.is_eof());
    assert_eq!((json.line(), json.column()), (1, 13));
    let _ = std::fs::remove_dir_all(&dir);
}

/// The builder reads no archive (it only writes the FMU); a write that the system refuses is
/// the output's failure with a typed source.
#[test]
fn a_refused_write_keeps_the_systems_error() {
    let dir = scratch("write");
    let missing = dir.join("no-such-folder");
    let e = fmu_builder::output::place::write_bytes(&missing.join("report.json"), b"{}").expect_err("no folder");
    assert_eq!(
        e.to_string(),
        format!(
            "{}: cannot create a temporary file in {}: No such file or directory (os error 2)",
            missing.join("report.json").display(),
            missing.display()
        )
    );
    let io = cause_of::<std::io::Error>(&e).expect("the io::Error is in the chain");
    assert_eq!(io.kind(), std::io::ErrorKind::NotFound);
    let _ = std::fs::remove_dir_all(&dir);
}
