//! The distributed back-end: the heavy linear algebra of a reduction (the factorisation of the
//! stiffness, every solve with it, the shift-invert eigen-solves, the mass products of the
//! floating-frame invariants) run by PETSc, MUMPS and SLEPc across MPI ranks, for parts whose
//! factor no single machine holds. The builder keeps the FE model and does everything else; a
//! small driver (`driver.py`, petsc4py and slepc4py) started under the MPI launcher holds the
//! distributed matrices and the factor, and answers requests over one TCP connection.

mod petsc_binary;
pub mod session;

pub use session::Session;
use std::path::{Path, PathBuf};

/// Where the reduction's linear algebra runs.
#[derive(Clone, Debug, Default, PartialEq)]
pub enum Backend {
    /// In the builder's process (faer's sparse Cholesky, the block Lanczos eigen-solver).
    #[default]
    InProcess,
    /// On PETSc/SLEPc across MPI ranks.
    Petsc(PetscBackend),
}

/// How to launch the driver and reach it.
#[derive(Clone, Debug, PartialEq)]
pub struct PetscBackend {
    /// MPI ranks.
    pub ranks: usize,
    /// The launcher and its own options (`mpirun --hostfile hosts`, `srun`), words split at
    /// white space; `-n <ranks>`, then the Python and the driver follow.
    pub launcher: Vec<String>,
    /// The Python with petsc4py, slepc4py and mpi4py on every rank.
    pub python: String,
    /// The address rank 0 reaches the builder at (this machine's own for a local run).
    pub host: String,
    /// Where the job folder (driver, matrices) is made: a folder every rank sees on a cluster.
    pub job_folder: Option<PathBuf>,
    /// PETSc's MatPartitioning type for the rows' distribution.
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
            partitioner: "ptscotch".into(),
            keep_job_folder: false,
            connect_timeout_seconds: 300.0,
        }
    }
}

impl PetscBackend {
    /// The address the builder listens at: the loopback for a local run, every interface for
    /// ranks on other machines.
    fn listen_address(&self) -> &str {
        if self.host == "127.0.0.1" || self.host == "localhost" { "127.0.0.1" } else { "0.0.0.0" }
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

/// An eigen-solve for SLEPc: `count` lowest pairs, or (with `below`) every pair with lambda
/// below it and at least `count`.
#[derive(Clone, Copy, Debug)]
pub struct EigenRequest {
    pub count: usize,
    pub below: Option<f64>,
    pub tol: f64,
}
