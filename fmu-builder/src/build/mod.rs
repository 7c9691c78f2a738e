//! The driver: runs the stages for one spec, input to FMU. `mounted` builds bodies held at a
//! mount flange, `free_floating` bodies without one; both return a `Built`, which
//! `output::package` writes as the FMU. `sweep` compares methods and orders side by side.

mod built;
pub mod free_floating;
pub mod mounted;
mod stress;
pub mod sweep;

pub use built::Built;

use crate::error::{BuildError, Result};
use crate::input::spec::{BackendKind, BackendSpec, Method, Role, Spec};
use crate::linalg::eigen;
use crate::model::{connectivity, flange, part};
use crate::output::binaries::PlatformBinary;
use crate::output::package;
use crate::profile;
use crate::reduce::basis::ModeCount;
use std::path::Path;

/// Read `input`, reduce, write the FMU to `output`.
pub fn build(input: &Path, output: &Path) -> Result<Built> {
    profile::take();
    let spec = profile::phase("read and check the input", || Spec::from_file(input))?;
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
    profile::take();
    let mut spec = profile::phase("read and check the input", || Spec::from_str(input, text))?;
    spec.reduction.backend = spec.reduction.backend.merged(backend);
    if let crate::linalg::distributed::Backend::Petsc(petsc) =
        spec.reduction.backend.backend(input.parent().unwrap_or(Path::new("")))
    {
        // a missing launcher or a Python without petsc4py is found in a second, not after assembly
        let (python, report) = profile::phase("PETSc back-end: launcher and Python checked", || {
            petsc.preflight(spec.reduction.backend.python.is_some())
        })?;
        profile::note(|| format!("{python}: {report}"));
        crate::progress::step(|| format!("PETSc back-end: the driver runs under {python}"));
        spec.reduction.backend.python = Some(python);
    }
    build_spec(spec, input, output, binaries)
}

fn build_spec(spec: Spec, input: &Path, output: &Path, binaries: &[PlatformBinary]) -> Result<Built> {
    let mut built = reduce_spec(spec, input)?;
    profile::phase("checks and packaging", || {
        package::write_fmu(&built.spec, &built.reduced, &built.report, output, binaries)
    })
    .map_err(|e| match e {
        BuildError::Numerical(m) => BuildError::input(input, "", m),
        other => other,
    })?;
    built.profile = profile::take();
    Ok(built)
}

/// The requested number of modes, or why it cannot be delivered accurately: the eigensolver
/// needs a Krylov space of twice the modes within the mesh's DoFs, and modes beyond a quarter
/// of them resolve the mesh rather than the part; beyond `eigen::MAX_MODES` the build's dense
/// reduced eigenproblems (cubic in the order) take minutes for a model no system simulation
/// steps fast.
fn check_mode_count(requested: usize, nodes: usize, file: &Path) -> Result<usize> {
    let dofs = 3 * nodes;
    if requested > eigen::MAX_MODES {
        return Err(BuildError::input(
            file,
            "reduction.modes",
            format!(
                "{requested} modes requested, at most {} are supported: a reduced body for system simulation needs the modes of its scene's band (use reduction.max_frequency, or scene.band with scene.tolerance)",
                eigen::MAX_MODES
            ),
        ));
    }
    if requested > dofs / 4 {
        return Err(BuildError::input(
            file,
            "reduction.modes",
            format!(
                "{requested} modes requested from a mesh with {dofs} DoFs: at most a quarter of the DoFs ({}) can be computed accurately (the eigensolver needs a space of twice the modes, and higher modes resolve the mesh, not the part); refine the mesh or request fewer modes",
                dofs / 4
            ),
        ));
    }
    Ok(requested)
}

/// Expansion points of a Krylov reduction, at most: each costs a sparse LU factorisation of
/// K + s^2 M, and ten points resolve any band a system simulation needs.
const MAX_EXPANSION_POINTS: usize = 100;

/// A Krylov basis grows by one block (six columns per force flange) per point and moment; it
/// must stay within the dense reduced problems' `eigen::MAX_MODES`, and its factorisations
/// within minutes, before they are made.
fn check_krylov_size(spec: &Spec, file: &Path) -> Result<()> {
    let r = &spec.reduction;
    if r.method != Method::Krylov {
        return Ok(());
    }
    let points =
        1 + r.expansion_points.as_ref().map_or(0, Vec::len) + r.real_expansion_points.as_ref().map_or(0, Vec::len);
    if points > MAX_EXPANSION_POINTS {
        return Err(BuildError::input(
            file,
            "reduction.expansion_points",
            format!(
                "{points} expansion points (with s = 0 and the real ones): at most {MAX_EXPANSION_POINTS}, since each costs a \
                 sparse factorisation; a few points across the band match it (add moments instead)"
            ),
        ));
    }
    let force_flanges = spec.flanges.iter().filter(|f| f.role == Role::Force).count().max(1);
    let moments = r.moments.unwrap_or(2);
    let columns = points.saturating_mul(moments).saturating_mul(6 * force_flanges);
    if columns > eigen::MAX_MODES {
        return Err(BuildError::input(
            file,
            "reduction.moments",
            format!(
                "{points} expansion points x {moments} moments x {} flange load directions = {columns} basis vectors, more than \
                 the {} a reduced body supports: use fewer points or moments",
                6 * force_flanges,
                eigen::MAX_MODES
            ),
        ));
    }
    Ok(())
}

/// What the distributed back-end does not run: the Krylov method's expansion points other than
/// s = 0 (each an indefinite LU factorisation of its own) and the order selection by tolerance
/// (complex factorisations of the full model across the band). Refused before anything costly,
/// with the way out.
fn check_distributable(spec: &Spec, file: &Path) -> Result<()> {
    let backend = &spec.reduction.backend;
    if backend.kind != Some(BackendKind::Petsc) {
        if backend != &(BackendSpec { kind: backend.kind, ..Default::default() }) {
            return Err(BuildError::input(
                file,
                "reduction.backend",
                "ranks, launcher, python, host, job_folder, partitioner and connect_timeout are settings of the petsc back-end: \
                 set kind to \"petsc\" (or --backend petsc), or remove them",
            ));
        }
        return Ok(());
    }
    let r = &spec.reduction;
    let points = r.expansion_points.iter().flatten().chain(r.real_expansion_points.iter().flatten()).any(|&p| p > 0.0);
    if r.method == Method::Krylov && points {
        return Err(BuildError::input(
            file,
            "reduction.expansion_points",
            "the petsc back-end expands about s = 0 only (each other expansion point needs an indefinite factorisation \
             of its own, which it does not run): remove the expansion points and use reduction.moments, or build in process",
        ));
    }
    if spec.scene.as_ref().is_some_and(|s| s.tolerance.is_some()) {
        return Err(BuildError::input(
            file,
            "scene.tolerance",
            "the order selection by tolerance compares complex full-model responses across the band, which the petsc \
             back-end does not run: give reduction.modes or reduction.max_frequency instead, or build in process",
        ));
    }
    Ok(())
}

/// A basis needs at least one shape: a mode, a force flange's static shapes or a scene load's.
fn check_basis_not_empty(spec: &Spec, modes: &ModeCount, file: &Path) -> Result<()> {
    let force_flanges = spec.flanges.iter().filter(|f| f.role == Role::Force).count();
    let loads = spec.scene.as_ref().map_or(0, |s| s.loads.len());
    if !matches!(modes, ModeCount::Count(0)) || force_flanges > 0 || loads > 0 {
        return Ok(());
    }
    let field = if spec.reduction.method == Method::Krylov { "flanges" } else { "reduction.modes" };
    Err(BuildError::input(
        file,
        field,
        "the reduced body would have no shape at all: no normal modes are requested (reduction.modes is 0 or missing), the body has no force flange whose static shapes would join the basis, and the scene declares no loads; request modes (reduction.modes >= 1 or reduction.max_frequency), add a force flange, or declare scene.loads",
    ))
}

/// A numerical failure deep in a stage, put against the input that drives that stage, with what
/// to change: the user fixes their input, not our code.
fn against_input(file: &Path, field: &'static str, hint: &'static str) -> impl FnOnce(BuildError) -> BuildError {
    move |e| match e {
        BuildError::Numerical(m) => BuildError::input(file, field, format!("{m}; {hint}")),
        other => other,
    }
}

/// Read, mesh, couple, assemble and reduce: everything but writing the FMU.
pub fn reduce_spec(spec: Spec, file: &Path) -> Result<Built> {
    let mut part = profile::phase("mesh or import", || part::part_of(&spec, file))?;
    let flanges = profile::phase("flange selection", || flange::select_flanges(&spec, file, &part))?;
    // recovery points are checked before anything costly: a misspelt node set fails at once
    let recovery = match spec.outputs.as_ref().and_then(|o| o.stress.as_ref()) {
        Some(request) => Some(crate::model::stress::requested_points(file, request, &part)?),
        None => None,
    };
    // a part given with its supports (free_free false) is held by them, not only by flanges
    if spec.geometry.matrices.as_ref().is_none_or(|m| m.free_free) {
        profile::phase("connectivity", || connectivity::check_connected(file, &part, &flanges))?;
    }
    let free = profile::phase("assembly (free-free K, M)", || {
        profile::note(|| format!("{} nodes, {} DoFs", part.mesh.n_nodes(), 3 * part.mesh.n_nodes()));
        part.free_free()
    })
    .map_err(against_input(file, "geometry", "check the mesh (element shapes, node order) and the material"))?;
    let modes = match (spec.reduction.modes, spec.reduction.max_frequency) {
        (Some(n), _) => ModeCount::Count(check_mode_count(n, part.mesh.n_nodes(), file)?),
        (None, Some(f)) => ModeCount::Below(f),
        (None, None) => ModeCount::Count(0),
    };
    check_basis_not_empty(&spec, &modes, file)?;
    check_krylov_size(&spec, file)?;
    check_distributable(&spec, file)?;
    let Some(mount) = spec.mount_index() else {
        return free_floating::reduce(spec, file, part, free, flanges, modes, recovery)
            .map_err(|e| against_stage(file, e));
    };
    mounted::reduce(spec, file, part, free, flanges, modes, mount, recovery).map_err(|e| against_stage(file, e))
}

/// A failure of the reduction, against the input most likely behind it: a factorisation that
/// fails is the model's (mesh, flanges), anything else the reduction's settings.
fn against_stage(file: &Path, e: BuildError) -> BuildError {
    let BuildError::Numerical(m) = &e else { return e };
    if m.contains("positive definite") || m.contains("singular") {
        against_input(
            file,
            "geometry",
            "check the mesh for mechanisms and extreme element proportions, and that the mount flange (flanges[].nodes) holds the part",
        )(e)
    } else {
        against_input(
            file,
            "reduction",
            "change the reduction (method, reduction.modes or max_frequency, expansion points, scene.band and tolerance) or check \
             that the flanges hold the part and the material and damping are those of a real solid",
        )(e)
    }
}
