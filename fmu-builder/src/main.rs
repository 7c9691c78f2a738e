//! fmu-builder: read an input file, build the FMU, print a summary. All work is in the library.

use clap::Parser;
use std::path::{Path, PathBuf};
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
    /// Overwrite outputs that exist (the FMU and the exports); never the input or the files it
    /// names, which no output may be
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
    fmu_builder::profile::per_phase_memory(args.timings);
    let input = match Input::read(args.input.as_deref().unwrap_or(Path::new("-"))) {
        Ok(input) => input,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::FAILURE;
        }
    };
    let output = if args.sweep { None } else { Some(output_path(&args, &input)) };
    let output = match output.transpose() {
        Ok(output) => output,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::FAILURE;
        }
    };
    if let Err(e) = check_destinations(&args, &input, output.as_deref()) {
        eprintln!("error: {e}");
        return ExitCode::FAILURE;
    }
    let Some(output) = output else {
        return sweep(&args, &input);
    };
    let binaries = match platform_binaries(&args.platform_binary) {
        Ok(binaries) => binaries,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::FAILURE;
        }
    };
    build(&args, &input, &output, &binaries)
}

/// The input's text and the path that names it ("<stdin>" for standard input: relative paths
/// in it then resolve from the working directory).
struct Input {
    path: PathBuf,
    text: String,
}

impl Input {
    fn read(path: &Path) -> Result<Self, String> {
        if path == Path::new("-") {
            let mut text = String::new();
            std::io::Read::read_to_string(&mut std::io::stdin(), &mut text)
                .map_err(|e| format!("<stdin>: cannot read the input: {e}"))?;
            return Ok(Self { path: PathBuf::from("<stdin>"), text });
        }
        use fmu_builder::input::{file_read, size::Memory};
        let text = file_read::read_text(path, file_read::FileKind::Input, Memory::of_this_machine().bytes)
            .map_err(|e| format!("{}: cannot read the input: it {e}", path.display()))?;
        Ok(Self { path: path.to_path_buf(), text })
    }
}

/// The FMU to write: `-o`, or `<name>.fmu` beside the input (in the working directory for
/// standard input); `check_destinations` decides whether it can be written.
fn output_path(args: &Args, input: &Input) -> Result<PathBuf, String> {
    let output = match &args.output {
        Some(o) => o.clone(),
        None => {
            let spec = fmu_builder::input::spec::Spec::from_str(&input.path, &input.text).map_err(|e| e.to_string())?;
            let folder = input.path.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
            folder.join(format!("{}.fmu", spec.name))
        }
    };
    Ok(output)
}

/// The FMU and every export, refused before any work when one cannot be written or would
/// overwrite the input, another output or (without --force) an existing file.
fn check_destinations(args: &Args, input: &Input, output: Option<&Path>) -> Result<(), String> {
    use fmu_builder::output::destinations::{self, Destination};
    let mut list = Vec::new();
    if let Some(o) = output {
        list.push(Destination::file("-o", o));
    }
    let files = [
        ("--report", &args.report),
        ("--export-inp", &args.export_inp),
        ("--export-vtk", &args.export_vtk),
        ("--sweep-svg", &args.sweep_svg),
    ];
    for (option, path) in files {
        if let Some(p) = path {
            list.push(Destination::file(option, p));
        }
    }
    if let Some(p) = &args.export_matrices {
        list.push(Destination::folder("--export-matrices", p, destinations::MOUNTED_MATRIX_FILES));
    }
    if let Some(p) = &args.export_free_free {
        list.push(Destination::folder("--export-free-free", p, destinations::FREE_FREE_FILES));
    }
    let mut inputs = Vec::new();
    if input.path != Path::new("<stdin>") {
        inputs.push(input.path.clone());
    }
    // the files the input names; an input that does not parse fails the build later, with its reason
    if let Ok(spec) = fmu_builder::input::spec::Spec::from_str(&input.path, &input.text) {
        inputs.extend(spec.input_files(&input.path));
        let by_matrices = spec.geometry.matrices.is_some();
        for (option, path) in [("--export-inp", &args.export_inp), ("--export-free-free", &args.export_free_free)] {
            if by_matrices && let Some(p) = path {
                return Err(format!(
                    "{option} {}: the part is given by its matrices (geometry.matrices), so it has no elements to \
                     export; export from the mesh the matrices came from",
                    p.display()
                ));
            }
        }
    }
    destinations::check(&list, &inputs, args.force)
}

/// The `--platform-binary` files, read and checked before the build starts: a wrong file is
/// refused in a second, not after the reduction.
fn platform_binaries(args: &[String]) -> Result<Vec<fmu_builder::output::binaries::PlatformBinary>, String> {
    use fmu_builder::output::binaries;
    let list = args.iter().map(|a| binaries::PlatformBinary::from_arg(a)).collect::<Result<Vec<_>, _>>();
    let list = list.map_err(|e| e.to_string())?;
    binaries::check_distinct(&list).map_err(|e| e.to_string())?;
    Ok(list)
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

/// Reduce by every method at growing orders and print the table (and plot).
fn sweep(args: &Args, input: &Input) -> ExitCode {
    let spec = match fmu_builder::input::spec::Spec::from_str(&input.path, &input.text) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::FAILURE;
        }
    };
    // the table's rows as they finish: a sweep takes minutes
    let band = spec.scene.as_ref().and_then(|s| s.band);
    let mut header = Some(fmu_builder::pipeline::sweep::table_header(band));
    let mut print_row = |row: &fmu_builder::pipeline::sweep::SweepRow| {
        use std::io::Write;
        let mut out = std::io::stdout();
        if let Some(h) = header.take() {
            let _ = out.write_all(h.as_bytes());
        }
        let _ = out.write_all(fmu_builder::pipeline::sweep::table_row(row).as_bytes());
        let _ = out.flush();
    };
    fmu_builder::progress::enable(!args.quiet);
    let result = fmu_builder::pipeline::sweep::sweep(&spec, &input.path, &mut print_row);
    fmu_builder::progress::finish();
    match result {
        Ok(rows) => {
            if let Some(path) = &args.sweep_svg
                && let Err(e) = std::fs::write(path, fmu_builder::pipeline::sweep::plot(&rows))
            {
                eprintln!("error: --sweep-svg {}: {e}", path.display());
                return ExitCode::FAILURE;
            }
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

/// Build the FMU, write what else was asked for, print the summary.
fn build(
    args: &Args,
    input: &Input,
    output: &Path,
    binaries: &[fmu_builder::output::binaries::PlatformBinary],
) -> ExitCode {
    fmu_builder::progress::enable(!args.quiet);
    let kind = args.backend.as_deref().map(|b| match b {
        "petsc" => fmu_builder::input::spec::BackendKind::Petsc,
        _ => fmu_builder::input::spec::BackendKind::InProcess,
    });
    let backend = fmu_builder::input::spec::BackendSpec {
        kind,
        ranks: args.ranks.map(|r| r as usize),
        launcher: args.launcher.clone(),
        python: args.python.clone(),
        connect_timeout: args.connect_timeout,
        ..Default::default()
    };
    let result = fmu_builder::pipeline::build_from_text(&input.text, &input.path, output, binaries, &backend);
    fmu_builder::progress::finish();
    match result {
        Ok(built) => {
            if let Err(e) = write_exports(args, &built) {
                eprintln!("error: {e}; the FMU {} was written", output.display());
                return ExitCode::FAILURE;
            }
            if !args.quiet {
                for w in &built.report.warnings {
                    eprintln!("warning: {w}");
                }
                print!("{}", fmu_builder::output::summary::text(&built.report));
                if let Some(mib) = fmu_builder::profile::process_peak_mib() {
                    println!("peak memory {mib:.0} MiB");
                }
                println!("wrote {}", output.display());
                // after the summary, last, so that it is not scrolled away
                if let Some(w) = fmu_builder::output::package::native_runtime_warning(binaries) {
                    eprintln!("warning: {w}");
                }
            }
            if args.timings {
                print!("{}", fmu_builder::profile::table(&built.profile));
            }
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

/// The exports asked for besides the FMU; an error names the option.
fn write_exports(args: &Args, b: &fmu_builder::pipeline::Built) -> Result<(), String> {
    let named = |option: &str, e: &dyn std::fmt::Display| format!("{option}: {e}");
    if let Some(path) = &args.report {
        let json = serde_json::to_string_pretty(&b.report).unwrap_or_default();
        std::fs::write(path, json).map_err(|e| named("--report", &format!("{}: {e}", path.display())))?;
    }
    if let Some(path) = &args.export_inp {
        fmu_builder::model::export::write_abaqus_deck(path, &b.part, &b.flanges)
            .map_err(|e| named("--export-inp", &e))?;
    }
    if let Some(path) = &args.export_vtk {
        let shapes = fmu_builder::ffrf::inertia::expand(&b.model, &b.part.mesh.nodes, &b.flanges, b.basis.phi.as_ref());
        let names: Vec<String> = b
            .basis
            .omega
            .iter()
            .enumerate()
            .map(|(j, w)| format!("shape_{:02}_{:.4}Hz", j + 1, w / (2.0 * std::f64::consts::PI)))
            .collect();
        fmu_builder::model::vtk::write_vtk(path, &b.spec.name, &b.part, &b.flanges, shapes.as_ref(), &names)
            .map_err(|e| named("--export-vtk", &e))?;
    }
    if let Some(dir) = &args.export_free_free {
        fmu_builder::model::export::write_free_free_matrices(dir, &b.part)
            .map_err(|e| named("--export-free-free", &e))?;
    }
    if let Some(dir) = &args.export_matrices {
        fmu_builder::model::export::write_matrix_market(dir, &b.model).map_err(|e| named("--export-matrices", &e))?;
    }
    Ok(())
}
