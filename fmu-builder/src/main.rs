//! fmu-builder: parse the command line into a `Job`, run it, print its error. All work is in
//! the library (`fmu_builder::job`).

use clap::Parser;
use fmu_builder::input::spec::{BackendKind, BackendSpec};
use fmu_builder::job::{Exports, Job};
use std::path::PathBuf;
use std::process::ExitCode;

/// A failed allocation ends the build with the size estimate and the limit, not an abort.
#[global_allocator]
static ALLOCATOR: fmu_builder::out_of_memory::ReportingAllocator = fmu_builder::out_of_memory::ReportingAllocator;

#[derive(Parser)]
#[command(
    // which linux64 binary the FMUs get: portable (glibc 2.17+) or only for glibc as new as the
    // build machine's (build.rs), with a warning for the latter
    version = version_text(),
    about = "Turn a finite-element model of an elastic part into an FMI 2.0 FMU (Model Exchange + Co-Simulation)"
)]
struct Args {
    /// Input file (JSON, see --print-schema); "-" reads it from standard input (relative paths in
    /// it then resolve from the working directory)
    #[arg(required_unless_present = "print_schema")]
    input: Option<PathBuf>,
    /// Output FMU [default: <name>.fmu beside the input, <name> the input's "name"]
    #[arg(short, long, conflicts_with = "sweep")]
    output: Option<PathBuf>,
    /// Overwrite outputs that exist (the FMU and the exports), and wait for another build that
    /// writes one of them to end instead of stopping; never the input or the files it names,
    /// which no output may be
    #[arg(long)]
    force: bool,
    /// Also package fmu-runtime built on another platform (repeatable): PLATFORM is win32, win64,
    /// linux32, linux64 (replaces the builder's own), darwin32 or darwin64; FILE is what `cargo
    /// build -p fmu-runtime --release` wrote there (fmu_runtime.dll, libfmu_runtime.so,
    /// libfmu_runtime.dylib), from the same source as this builder. Checked before the build:
    /// format, processor, shared library, exported fmi2 functions, runtime source
    #[arg(long, value_name = "PLATFORM=FILE", conflicts_with = "sweep")]
    platform_binary: Vec<String>,
    /// Print the input's JSON schema and exit
    #[arg(long, exclusive = true)]
    print_schema: bool,
    /// Instead of building, reduce the body by every method at growing orders and print error in
    /// band vs cost per step vs build time
    #[arg(long)]
    sweep: bool,
    /// With --sweep: also write the error-vs-cost plot (SVG) here
    #[arg(long, requires = "sweep")]
    sweep_svg: Option<PathBuf>,
    /// Also write the accuracy report (JSON) here
    #[arg(long)]
    report: Option<PathBuf>,
    /// Also write the meshed part with its flange node sets as an Abaqus/CalculiX deck here
    #[arg(long)]
    export_inp: Option<PathBuf>,
    /// Also write the mesh, the flanges' slave nodes and the reduced basis' shapes (displacement
    /// fields named with their frequencies) as a legacy VTK file ParaView opens
    #[arg(long)]
    export_vtk: Option<PathBuf>,
    /// Also write the mounted body's K and M (Matrix Market) and the flange load DoFs into this folder
    #[arg(long)]
    export_matrices: Option<PathBuf>,
    /// Also write the part's free-free K and M (Matrix Market), its DoF map and node table into
    /// this folder: the input of `geometry.matrices`
    #[arg(long)]
    export_free_free: Option<PathBuf>,
    /// Where the reduction's linear algebra runs: in-process (default) or petsc (the factor and
    /// its solves on PETSc and MUMPS across MPI ranks, through a driver started by the MPI
    /// launcher; needs petsc4py and mpi4py on every rank). Overrides the input's reduction.backend.kind
    #[arg(long, value_parser = ["in-process", "petsc"], conflicts_with = "sweep")]
    backend: Option<String>,
    /// petsc back-end: MPI ranks [default 2]
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..), conflicts_with = "sweep")]
    ranks: Option<u32>,
    /// petsc back-end: the MPI launcher with its own options, e.g. "mpirun --hostfile hosts" or
    /// "srun" ["-n <ranks> <python> driver.py job.json" follow; default "mpirun"]
    #[arg(long, conflicts_with = "sweep")]
    launcher: Option<String>,
    /// petsc back-end: the Python with petsc4py and mpi4py on every rank [default: the
    /// first of /usr/bin/python3 and python3 in PATH that imports them]
    #[arg(long, conflicts_with = "sweep")]
    python: Option<String>,
    /// petsc back-end: seconds to wait for the driver to connect [default 300]
    #[arg(long, value_name = "SECONDS", value_parser = connect_timeout, conflicts_with = "sweep")]
    connect_timeout: Option<f64>,
    /// Print nothing but errors
    #[arg(short, long)]
    quiet: bool,
    /// Also print where the build spent its time and memory: every phase (import, assembly,
    /// coupling, factorisations, eigen-solves, shapes, invariants, accuracy comparison, packaging)
    /// with wall time, peak resident memory and its counts
    #[arg(long)]
    timings: bool,
}

/// `--connect-timeout`: seconds in (0, 1e6], as the input's reduction.backend.connect_timeout.
fn connect_timeout(text: &str) -> Result<f64, String> {
    let v: f64 = text.parse().map_err(|_| format!("expected seconds, e.g. 60; found \"{text}\""))?;
    if v > 0.0 && v <= 1e6 { Ok(v) } else { Err(format!("expected seconds in (0, 1e6]; found {text}")) }
}

/// `--version`: the builder's version, its linux64 runtime's kind, and for a natively linked one
/// a warning saying which glibc it needs and how to get the portable one.
fn version_text() -> &'static str {
    static TEXT: std::sync::OnceLock<String> = std::sync::OnceLock::new();
    TEXT.get_or_init(|| {
        use fmu_builder::output::package::{RUNTIME_KIND, native_runtime_warning};
        let mut text = format!("{} (linux64 runtime: {RUNTIME_KIND})", env!("CARGO_PKG_VERSION"));
        if let Some(w) = native_runtime_warning(&[]) {
            text.push_str(&format!("\nwarning: {w}"));
        }
        text
    })
}

fn main() -> ExitCode {
    let args = Args::parse();
    if args.print_schema {
        print!("{}", fmu_builder::input::spec::SCHEMA);
        return ExitCode::SUCCESS;
    }
    return_freed_memory();
    match fmu_builder::job::run(&args.into_job()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

impl Args {
    fn into_job(self) -> Job {
        let kind = self.backend.as_deref().map(|b| match b {
            "petsc" => BackendKind::Petsc,
            _ => BackendKind::InProcess,
        });
        let backend = BackendSpec {
            kind,
            ranks: self.ranks.map(|r| r as usize),
            launcher: self.launcher,
            python: self.python,
            connect_timeout: self.connect_timeout,
            ..Default::default()
        };
        let exports = Exports {
            report: self.report,
            inp: self.export_inp,
            vtk: self.export_vtk,
            matrices: self.export_matrices,
            free_free: self.export_free_free,
        };
        Job {
            input: self.input.unwrap_or_else(|| PathBuf::from("-")),
            output: self.output,
            force: self.force,
            platform_binaries: self.platform_binary,
            sweep: self.sweep,
            sweep_svg: self.sweep_svg,
            exports,
            backend,
            quiet: self.quiet,
            timings: self.timings,
        }
    }
}

/// Blocks of a megabyte and more come from the system and go back to it when freed. glibc
/// otherwise raises its threshold for that to 32 MB after the first large free, and the n x k
/// blocks of the eigen-solves (10-50 MB each, freed within a phase) then stay in the process's
/// resident set: 1043 MiB instead of 957 at the peak of a 106k-DoF build.
fn return_freed_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: mallopt only sets an allocator parameter; called before any thread is started
    unsafe {
        libc::mallopt(libc::M_MMAP_THRESHOLD, 1 << 20);
    }
}
