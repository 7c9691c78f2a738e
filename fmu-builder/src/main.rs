//! fmu-builder: read an input file, build the FMU, print a summary. All work is in the library.

use clap::Parser;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    version,
    about = "Turn a finite-element model of an elastic part into an FMI 2.0 FMU (Model Exchange + Co-Simulation)"
)]
struct Args {
    /// Input file (JSON, see schemas/fmu-builder-input.schema.json)
    input: PathBuf,
    /// Output FMU
    #[arg(short, long, required_unless_present = "sweep", conflicts_with = "sweep")]
    output: Option<PathBuf>,
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
    /// Also write the mounted body's K and M (Matrix Market) and the flange load DoFs into this folder
    #[arg(long)]
    export_matrices: Option<PathBuf>,
    /// Also write the part's free-free K and M (Matrix Market), its DoF map and node table into
    /// this folder: the input of `geometry.matrices`
    #[arg(long)]
    export_free_free: Option<PathBuf>,
    /// Print nothing but errors
    #[arg(short, long)]
    quiet: bool,
    /// Also print where the build spent its time and memory: every phase (import, assembly,
    /// coupling, factorisations, eigen-solves, shapes, invariants, accuracy comparison, packaging)
    /// with wall time, peak resident memory and its counts
    #[arg(long)]
    timings: bool,
}

fn main() -> ExitCode {
    let args = Args::parse();
    return_freed_memory();
    fmu_builder::profile::per_phase_memory(args.timings);
    // clap lets exactly one of --output and --sweep through
    match args.output.clone() {
        Some(output) => build(&args, &output),
        None => sweep(&args),
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

/// Reduce by every method at growing orders and print the table (and plot).
fn sweep(args: &Args) -> ExitCode {
    let spec = match fmu_builder::input::spec::Spec::from_file(&args.input) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::FAILURE;
        }
    };
    match fmu_builder::build::sweep::sweep(&spec, &args.input) {
        Ok(rows) => {
            print!("{}", fmu_builder::build::sweep::table(&rows, spec.scene.as_ref().and_then(|s| s.band)));
            if let Some(path) = &args.sweep_svg
                && let Err(e) = std::fs::write(path, fmu_builder::build::sweep::plot(&rows))
            {
                eprintln!("error: {}: {e}", path.display());
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
fn build(args: &Args, output: &Path) -> ExitCode {
    match fmu_builder::build::build(&args.input, output) {
        Ok(built) => {
            if let Some(path) = &args.report {
                let json = serde_json::to_string_pretty(&built.report).unwrap_or_default();
                if let Err(e) = std::fs::write(path, json) {
                    eprintln!("error: {}: {e}", path.display());
                    return ExitCode::FAILURE;
                }
            }
            if let Some(path) = &args.export_inp {
                let b = &built;
                if let Err(e) = fmu_builder::model::export::write_abaqus_deck(path, &b.part, &b.flanges) {
                    eprintln!("error: {e}");
                    return ExitCode::FAILURE;
                }
            }
            if let Some(dir) = &args.export_free_free
                && let Err(e) = fmu_builder::model::export::write_free_free_matrices(dir, &built.part)
            {
                eprintln!("error: {e}");
                return ExitCode::FAILURE;
            }
            if let Some(dir) = &args.export_matrices
                && let Err(e) = fmu_builder::model::export::write_matrix_market(dir, &built.model)
            {
                eprintln!("error: {e}");
                return ExitCode::FAILURE;
            }
            if !args.quiet {
                print!("{}", fmu_builder::output::summary::text(&built.report));
                if let Some(mib) = fmu_builder::profile::process_peak_mib() {
                    println!("peak memory {mib:.0} MiB");
                }
                println!("wrote {}", output.display());
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
