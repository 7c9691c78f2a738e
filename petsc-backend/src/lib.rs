//! The builder's distributed back-end: the heavy linear algebra of a reduction (the factorisation of the
//! stiffness, every solve with it, the shift-invert eigen-solves, the mass products of the
//! floating-frame invariants) run by PETSc and MUMPS across MPI ranks, for parts whose
//! factor no single machine holds. The builder keeps the FE model and does everything else (its
//! block Lanczos eigen-solver drives the distributed block solves); a
//! small driver (`driver.py`, petsc4py) started under the MPI launcher holds the
//! distributed matrices and the factor, and answers requests over one TCP connection.
//!
//! The back-end is the lowest of the builder's crates: it cannot name the linear algebra, the
//! input or the builder, which use it (the crate graph is the layering):
//!
//! ```compile_fail,E0432
//! use fe_linalg::sparse::SpdSolver;
//! ```
//!
//! ```compile_fail,E0432
//! use fmu_builder::pipeline::build;
//! ```

mod accept;
pub mod error;
pub mod heartbeat;
pub mod job_folder;
mod messages;
mod petsc_binary;
pub mod process_group;
pub mod session;

pub use error::{BackendError, Cause, LauncherRefusal};
pub use session::Session;
use std::path::{Path, PathBuf};

/// Where the reduction's linear algebra runs.
#[derive(Clone, Debug, Default, PartialEq)]
pub enum Backend {
    /// In the builder's process (faer's sparse Cholesky, the block Lanczos eigen-solver).
    #[default]
    InProcess,
    /// On PETSc and MUMPS across MPI ranks.
    Petsc(PetscBackend),
}

/// How to launch the driver and reach it.
#[derive(Clone, Debug, PartialEq)]
pub struct PetscBackend {
    /// MPI ranks.
    pub ranks: usize,
    /// The launcher and its own options (`mpirun --hostfile hosts`, `srun`), in words
    /// (`launcher_words`); `-n <ranks>`, then the Python and the driver follow.
    pub launcher: Vec<String>,
    /// The Python with petsc4py and mpi4py on every rank.
    pub python: String,
    /// The address rank 0 reaches the builder at (this machine's own for a local run).
    pub host: String,
    /// Where the job folder (driver, matrices) is made: a folder every rank sees on a cluster.
    pub job_folder: Option<PathBuf>,
    /// PETSc's MatPartitioning type for the rows' distribution, or `current`: PETSc's contiguous
    /// rows, repartitioned by nothing (MUMPS orders and maps the factor itself; a graph partition
    /// cost 1.2 s at 1e5 DoF and bought nothing).
    pub partitioner: String,
    pub keep_job_folder: bool,
    pub connect_timeout_seconds: f64,
}

impl Default for PetscBackend {
    fn default() -> Self {
        Self {
            ranks: 2,
            launcher: vec!["mpirun".into()],
            python: "python3".into(),
            host: "127.0.0.1".into(),
            job_folder: None,
            partitioner: "current".into(),
            keep_job_folder: keep_job_requested(),
            connect_timeout_seconds: 300.0,
        }
    }
}

/// `FMU_BUILDER_KEEP_PETSC_JOB`: keep the job's files (matrices, driver, its output) for a look
/// at a failure. A debugging switch of this back-end, read where the back-end is configured, not
/// by the input's parser.
fn keep_job_requested() -> bool {
    std::env::var_os("FMU_BUILDER_KEEP_PETSC_JOB").is_some()
}

/// The launcher's words as a POSIX shell splits them: quotes keep a word with spaces whole
/// (`mpirun --hostfile "my hosts"`), which splitting at white space would cut in two.
pub fn launcher_words(text: &str) -> Result<Vec<String>, LauncherRefusal> {
    match shlex::split(text) {
        None => Err(LauncherRefusal(
            "has an unbalanced quote or ends in a backslash: quote its words as a POSIX shell would",
        )),
        Some(words) if words.is_empty() => Err(LauncherRefusal("names no program")),
        Some(words) => Ok(words),
    }
}

impl PetscBackend {
    /// The address the builder listens at: the loopback for a local run, else the address the
    /// input names (which must be this machine's: the ranks reach the builder there), never
    /// every interface.
    fn listen_address(&self) -> &str {
        if self.host == "127.0.0.1" || self.host == "localhost" { "127.0.0.1" } else { &self.host }
    }

    /// Checks, before any FE work, that the launcher can be started and finds the Python whose
    /// imports the driver needs (petsc4py, mpi4py): `python` alone when the user named
    /// one, else Debian's /usr/bin/python3 first, then `python3` in PATH (another Python first in
    /// PATH, a virtual environment's, has none of Debian's packages). Returns that Python and
    /// what it reported (PETSc's version).
    pub fn preflight(&self, python_named: bool) -> error::Result<(String, String)> {
        let launcher = self.launcher.first().map_or("mpirun", String::as_str);
        if find_program(launcher).is_none() {
            return Err(BackendError::unavailable(format!(
                "the launcher `{launcher}` is not found{}; install OpenMPI (mpirun) or name the launcher \
                 (reduction.backend.launcher, --launcher)",
                if launcher.contains('/') { "" } else { " in PATH" }
            )));
        }
        let candidates: Vec<String> = if python_named {
            vec![self.python.clone()]
        } else {
            let mut c = vec!["/usr/bin/python3".to_string(), "python3".to_string()];
            c.dedup();
            c
        };
        let mut tried = Vec::new();
        for python in &candidates {
            match probe_python(python) {
                Ok(report) => return Ok((python.clone(), report)),
                Err(why) => tried.push(format!("{python}: {why}")),
            }
        }
        Err(BackendError::unavailable(format!(
            "no Python that imports petsc4py and mpi4py ({}); install Debian's python3-petsc4py-real \
             and python3-mpi4py, or name the Python that has them (--python, \
             reduction.backend.python)",
            tried.join("; ")
        )))
    }

    /// The program and arguments that start the driver on every rank.
    fn command(&self, driver: &Path, job: &Path) -> (String, Vec<String>) {
        let mut words = self.launcher.clone();
        let program = if words.is_empty() { "mpirun".to_string() } else { words.remove(0) };
        words.extend(["-n".to_string(), self.ranks.to_string(), self.python.clone()]);
        words.push(driver.display().to_string());
        words.push(job.display().to_string());
        (program, words)
    }
}

/// `name` as the system would run it: a path that exists and is executable, or found in PATH.
fn find_program(name: &str) -> Option<PathBuf> {
    use std::os::unix::fs::PermissionsExt;
    let executable = |p: &Path| std::fs::metadata(p).is_ok_and(|m| m.is_file() && m.permissions().mode() & 0o111 != 0);
    if name.contains('/') {
        let p = PathBuf::from(name);
        return executable(&p).then_some(p);
    }
    let path = std::env::var_os("PATH")?;
    std::env::split_paths(&path).map(|d| d.join(name)).find(|p| executable(p))
}

/// Runs the driver's import check (`--probe`) under `python`: Ok with what it printed, or the
/// last line of its error.
/// Why a Python cannot run the driver: its own last words, or why it did not start.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
struct Unfit(String);

fn probe_python(python: &str) -> Result<String, Unfit> {
    use std::io::Write;
    use std::process::{Command, Stdio};
    let mut command = Command::new(python);
    command.args(["-", "--probe"]).stdin(Stdio::piped()).stdout(Stdio::piped()).stderr(Stdio::piped());
    // SAFETY: geteuid only reads the process's user id
    if unsafe { libc::geteuid() } == 0 {
        command.env("OMPI_ALLOW_RUN_AS_ROOT", "1").env("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1");
    }
    let mut child = command.spawn().map_err(|e| Unfit(format!("cannot be started: {e}")))?;
    if let Some(mut stdin) = child.stdin.take() {
        stdin.write_all(session::DRIVER.as_bytes()).map_err(|e| Unfit(format!("cannot be given the driver: {e}")))?;
    }
    let output = child.wait_with_output().map_err(|e| Unfit(e.to_string()))?;
    if output.status.success() {
        return Ok(String::from_utf8_lossy(&output.stdout).trim().to_string());
    }
    let stderr = String::from_utf8_lossy(&output.stderr);
    Err(Unfit(
        stderr.lines().rev().find(|l| !l.trim().is_empty()).unwrap_or("failed without a message").trim().to_string(),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn launcher_words_split_as_a_shell_splits_them() {
        let words = launcher_words("mpirun --hostfile \"my hosts\" --mca btl self,tcp").unwrap();
        assert_eq!(words, ["mpirun", "--hostfile", "my hosts", "--mca", "btl", "self,tcp"]);
        assert_eq!(launcher_words("srun").unwrap(), ["srun"]);
        let unbalanced = launcher_words("mpirun --hostfile \"my hosts").unwrap_err();
        assert!(unbalanced.0.contains("unbalanced quote"), "{unbalanced}");
        assert!(launcher_words("  ").unwrap_err().0.contains("names no program"));
    }
}
