//! One run of the builder as the command line asks for it: the input read, every destination
//! checked before any work, the FMU built (or the methods swept), the exports written and the
//! summary printed. The binary only parses its arguments into a `Job` and prints the error.

mod exports;

use crate::error::{BuildError, InputError, Result};
use crate::input::file_read::{self, FileKind};
use crate::input::size::Memory;
use crate::input::spec::{BackendSpec, Spec};
use crate::output::binaries::{self, PlatformBinary};
use crate::output::destinations::{self, Destination};
use crate::pipeline::{self, Built, sweep::SweepRow};
use crate::profile::{self, Profile};
use crate::progress::Progress;
pub use exports::Exports;
use std::path::{Path, PathBuf};
use tracing_subscriber::layer::SubscriberExt;

/// What one run is asked to do.
#[derive(Debug, Clone, Default)]
pub struct Job {
    /// The input file; "-" reads standard input (relative paths in it then resolve from the
    /// working directory).
    pub input: PathBuf,
    /// The FMU; None: `<name>.fmu` beside the input.
    pub output: Option<PathBuf>,
    /// Overwrite outputs that exist (never the input or the files it names).
    pub force: bool,
    /// `PLATFORM=FILE` runtimes built on other platforms.
    pub platform_binaries: Vec<String>,
    /// Reduce by every method at growing orders instead of building, and print the table.
    pub sweep: bool,
    pub sweep_svg: Option<PathBuf>,
    pub exports: Exports,
    /// The command line's choice of back-end, overriding the input's fields it sets.
    pub backend: BackendSpec,
    /// Print nothing but errors.
    pub quiet: bool,
    /// Also print where the build spent its time and memory.
    pub timings: bool,
}

/// The input's text and the path that names it ("<stdin>" for standard input).
struct Input {
    path: PathBuf,
    text: String,
}

/// Run `job`: every failure comes back as one error, for the caller to print.
pub fn run(job: &Job) -> Result<()> {
    crate::output::temp_files::install_handlers();
    // the PETSc back-end's default place: a killed build's job folder there goes at the next run
    petsc_backend::job_folder::sweep_stale(&std::env::temp_dir());
    destinations::precheck(&named_destinations(job, job.output.as_deref()))?;
    let input = read_input(&job.input)?;
    if crate::input::assembly::is_assembly(&input.text) {
        return build_assembly(job, &input);
    }
    if job.sweep {
        let _reserved = check_destinations(job, &input, None)?;
        return sweep(job, &input);
    }
    let output = output_path(job, &input)?;
    let _reserved = check_destinations(job, &input, Some(&output))?;
    let binaries = platform_binaries(&job.platform_binaries)?;
    build(job, &input, &output, &binaries)
}

fn read_input(path: &Path) -> Result<Input> {
    if path == Path::new("-") {
        let mut text = String::new();
        std::io::Read::read_to_string(&mut std::io::stdin(), &mut text)
            .map_err(|e| BuildError::file(Path::new("<stdin>"), format!("cannot read the input: {e}")).caused_by(e))?;
        return Ok(Input { path: PathBuf::from("<stdin>"), text });
    }
    let text = file_read::read_text(path, FileKind::Input, Memory::of_this_machine().bytes)
        .map_err(|source| InputError::Unreadable { path: path.to_path_buf(), source })?;
    Ok(Input { path: path.to_path_buf(), text })
}

/// The FMU to write: `-o`, or `<name>.fmu` beside the input (in the working directory for
/// standard input); `check_destinations` decides whether it can be written.
fn output_path(job: &Job, input: &Input) -> Result<PathBuf> {
    if let Some(o) = &job.output {
        return Ok(o.clone());
    }
    let spec = Spec::from_str(&input.path, &input.text)?;
    let folder = input.path.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    Ok(folder.join(format!("{}.fmu", spec.name)))
}

/// The FMU (when known) and every export the command line names.
fn named_destinations(job: &Job, output: Option<&Path>) -> Vec<Destination> {
    let e = &job.exports;
    let mut list: Vec<Destination> = output.map(|o| Destination::file("-o", o)).into_iter().collect();
    let files =
        [("--report", &e.report), ("--export-inp", &e.inp), ("--export-vtk", &e.vtk), ("--sweep-svg", &job.sweep_svg)];
    list.extend(files.iter().filter_map(|(option, path)| path.as_ref().map(|p| Destination::file(option, p))));
    if let Some(p) = &e.matrices {
        list.push(Destination::folder("--export-matrices", p, destinations::MOUNTED_MATRIX_FILES));
    }
    if let Some(p) = &e.free_free {
        list.push(Destination::folder("--export-free-free", p, destinations::FREE_FREE_FILES));
    }
    list
}

/// The FMU and every export, refused before any work when one cannot be written or would
/// overwrite the input, another output or (without --force) an existing file, then reserved
/// for this build until the reservation is dropped.
fn check_destinations(job: &Job, input: &Input, output: Option<&Path>) -> Result<destinations::Reservation> {
    let list = named_destinations(job, output);
    let mut inputs = Vec::new();
    if input.path != Path::new("<stdin>") {
        inputs.push(input.path.clone());
    }
    // the files the input names; an input that does not parse fails the build later, with its reason
    if let Ok(spec) = Spec::from_str(&input.path, &input.text) {
        inputs.extend(spec.input_files(&input.path));
        if spec.geometry.matrices.is_some() {
            no_element_exports(job)?;
        }
    }
    destinations::reserve(&list, &inputs, job.force, job.quiet)
}

/// A part given by its matrices has no elements to export.
fn no_element_exports(job: &Job) -> Result<()> {
    for (option, path) in [("--export-inp", &job.exports.inp), ("--export-free-free", &job.exports.free_free)] {
        if let Some(p) = path {
            return Err(BuildError::destination(
                format!("{option} {}", p.display()),
                "the part is given by its matrices (geometry.matrices), so it has no elements to export; export \
                 from the mesh the matrices came from",
            ));
        }
    }
    Ok(())
}

/// The `--platform-binary` files, read and checked before the build starts: a wrong file is
/// refused in a second, not after the reduction.
fn platform_binaries(args: &[String]) -> Result<Vec<PlatformBinary>> {
    let list = args.iter().map(|a| PlatformBinary::from_arg(a)).collect::<Result<Vec<_>>>()?;
    binaries::check_distinct(&list)?;
    Ok(list)
}

/// Reduce by every method at growing orders and print the table's rows as they finish (a
/// sweep takes minutes), then write the plot.
fn sweep(job: &Job, input: &Input) -> Result<()> {
    use std::io::Write;
    let spec = Spec::from_str(&input.path, &input.text)?;
    let band = spec.scene.as_ref().and_then(|s| s.band);
    let mut header = Some(pipeline::sweep::table_header(band));
    let mut print_row = |row: &SweepRow| {
        let mut out = std::io::stdout();
        if let Some(h) = header.take() {
            let _ = out.write_all(h.as_bytes());
        }
        let _ = out.write_all(pipeline::sweep::table_row(row).as_bytes());
        let _ = out.flush();
    };
    let rows = observed(job, &Profile::new(false), || pipeline::sweep::sweep(&spec, &input.path, &mut print_row))?;
    if let Some(path) = &job.sweep_svg {
        crate::output::place::write_bytes(path, pipeline::sweep::plot(&rows).as_bytes())?;
    }
    Ok(())
}

/// An assembly: its bodies reduced and one FMU written; the exports and the sweep are a single
/// body's, refused here before any work.
fn build_assembly(job: &Job, input: &Input) -> Result<()> {
    use crate::input::assembly::AssemblySpec;
    let e = &job.exports;
    let refused = [
        ("--sweep", job.sweep),
        ("--report", e.report.is_some()),
        ("--export-inp", e.inp.is_some()),
        ("--export-vtk", e.vtk.is_some()),
        ("--export-matrices", e.matrices.is_some()),
        ("--export-free-free", e.free_free.is_some()),
        ("--platform-binary", !job.platform_binaries.is_empty()),
    ];
    if let Some((option, _)) = refused.iter().find(|(_, asked)| *asked) {
        return Err(BuildError::command_line(
            *option,
            format!("{} is an assembly: build each body's input on its own for this", input.path.display()),
        ));
    }
    let profile = Profile::new(job.timings);
    let spec = observed(job, &profile, || {
        phases::phase("read and check the input", || AssemblySpec::from_str(&input.path, &input.text))
    })?;
    let output = job.output.clone().unwrap_or_else(|| {
        let folder = input.path.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
        folder.join(format!("{}.fmu", spec.name))
    });
    let mut inputs = spec.input_files();
    if input.path != Path::new("<stdin>") {
        inputs.push(input.path.clone());
    }
    let _reserved = destinations::reserve(&[Destination::file("-o", &output)], &inputs, job.force, job.quiet)?;
    let built = observed(job, &profile, || pipeline::assembly::build_assembly(spec, &output, &[]))?;
    if !job.quiet {
        print!("{}", crate::output::summary::assembly_text(&built.description, built.experiment));
        if let Some(mib) = profile::process_peak_mib() {
            println!("peak memory {mib:.0} MiB");
        }
        println!("wrote {}", output.display());
    }
    if job.timings {
        print!("{}", profile::table(&profile.take()));
    }
    Ok(())
}

/// Build the FMU, write what else was asked for, print the summary.
fn build(job: &Job, input: &Input, output: &Path, binaries: &[PlatformBinary]) -> Result<()> {
    let profile = Profile::new(job.timings);
    let built = observed(job, &profile, || {
        pipeline::build_from_text(&input.text, &input.path, output, binaries, &job.backend)
    })?;
    exports::write(&job.exports, &built, output)?;
    if !job.quiet {
        print_summary(&built, output, binaries);
    }
    if job.timings {
        print!("{}", profile::table(&profile.take()));
    }
    Ok(())
}

/// Run `work` with its phases recorded into `profile` and, unless quiet, shown as they go (the
/// subscriber is this thread's for the run only: a library caller's own is left alone).
fn observed<T>(job: &Job, profile: &Profile, work: impl FnOnce() -> T) -> T {
    let progress = (!job.quiet).then(Progress::on_stderr);
    let subscriber = tracing_subscriber::registry().with(profile.layer()).with(progress.clone());
    let result = tracing::subscriber::with_default(subscriber, work);
    if let Some(progress) = progress {
        progress.finish();
    }
    result
}

fn print_summary(built: &Built, output: &Path, binaries: &[PlatformBinary]) {
    // the part's own were said as it was read
    for w in &built.report.warnings[built.report.said_early.min(built.report.warnings.len())..] {
        eprintln!("warning: {w}");
    }
    print!("{}", crate::output::summary::text(&built.report));
    if let Some(mib) = profile::process_peak_mib() {
        println!("peak memory {mib:.0} MiB");
    }
    println!("wrote {}", output.display());
    // after the summary, last, so that it is not scrolled away
    if let Some(w) = crate::output::package::native_runtime_warning(binaries) {
        eprintln!("warning: {w}");
    }
}
