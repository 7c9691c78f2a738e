//! The pipeline: one spec, input to FMU, as a sequence of phases over typed values. `prepare`
//! meshes or imports the part, selects its flanges and assembles it; `body::reduce` couples,
//! factors, reduces, measures and reports it, with the strategy of how the body is held
//! (`mounted` or `free_floating`); `output::package` writes the FMU. `sweep` compares methods
//! and orders side by side.

mod against;
pub mod assembly;
mod body;
mod built;
mod free_floating;
mod mounted;
mod prepare;
mod stress;
pub mod sweep;

pub use built::Built;

use crate::error::{InputHint, Result};
use crate::input::spec::{BackendSpec, Spec};
use crate::linalg::distributed::Backend;
use crate::output::binaries::PlatformBinary;
use crate::output::package;
use against::Against;
use std::path::Path;

/// Read `input`, reduce, write the FMU to `output`.
pub fn build(input: &Path, output: &Path) -> Result<Built> {
    let spec = phases::phase("read and check the input", || Spec::from_file(input))?;
    build_spec(spec, input, output, &[])
}

/// As `build`, the input's text given (`input` names it in messages, and relative paths in it
/// resolve from its folder: for standard input, name it "<stdin>" and they resolve from the
/// working directory). `binaries`: runtimes built for other platforms, packaged beside the
/// builder's own (a linux64 one replaces it).
/// `backend`: the command line's choice of back-end, overriding the input's fields it sets.
pub fn build_from_text(
    text: &str,
    input: &Path,
    output: &Path,
    binaries: &[PlatformBinary],
    backend: &BackendSpec,
) -> Result<Built> {
    let mut spec = phases::phase("read and check the input", || Spec::from_str(input, text))?;
    spec.reduction.backend = spec.reduction.backend.merged(backend);
    preflight_backend(&mut spec, input)?;
    build_spec(spec, input, output, binaries)
}

/// A missing launcher or a Python without petsc4py is found in a second, not after assembly.
fn preflight_backend(spec: &mut Spec, input: &Path) -> Result<()> {
    let backend = spec.reduction.backend.backend(input.parent().unwrap_or(Path::new("")));
    if let Backend::Petsc(petsc) = &backend {
        // before anything can fail: a killed build's folder holds its token and the stiffness
        let base = petsc.job_folder.clone().unwrap_or_else(std::env::temp_dir);
        for gone in petsc_backend::job_folder::sweep_stale(&base) {
            phases::note(|| format!("removed {}, the job folder of a build that is gone", gone.display()));
        }
    }
    spec.reduction.backend.check_launcher(input)?;
    let Backend::Petsc(petsc) = backend else {
        return Ok(());
    };
    let (python, report) = phases::phase("PETSc back-end: launcher and Python checked", || {
        petsc.preflight(spec.reduction.backend.python.is_some())
    })?;
    phases::note(|| format!("{python}: {report}"));
    phases::step(|| format!("PETSc back-end: the driver runs under {python}"));
    spec.reduction.backend.python = Some(python);
    Ok(())
}

fn build_spec(spec: Spec, input: &Path, output: &Path, binaries: &[PlatformBinary]) -> Result<Built> {
    let built = reduce_spec(spec, input)?;
    phases::phase("checks and packaging", || {
        package::write_fmu(&built.spec, &built.reduced, &built.report, output, binaries)
    })
    .against(input, InputHint { field: "", hint: "" })?;
    Ok(built)
}

/// Read, mesh, couple, assemble and reduce: everything but writing the FMU.
pub fn reduce_spec(spec: Spec, file: &Path) -> Result<Built> {
    let prepared = prepare::prepare(spec, file)?;
    match prepared.spec.mount_index() {
        Some(_) => body::reduce::<mounted::Mounted>(prepared),
        None => body::reduce::<free_floating::FreeFloating>(prepared),
    }
    .against_stage(file)
}
