//! The reduction's settings checked against the part before anything costly: what the
//! eigensolver, the dense reduced problems and the distributed back-end can deliver.

use crate::error::{InputError, Result};
use crate::spec::{BackendKind, BackendSpec, Method, Role, Spec};
use fe_linalg::eigen;
use std::path::Path;

/// The requested number of modes, or why it cannot be delivered accurately: the eigensolver
/// needs a Krylov space of twice the modes within the mesh's DoFs, and modes beyond a quarter
/// of them resolve the mesh rather than the part; beyond `eigen::MAX_MODES` the build's dense
/// reduced eigenproblems (cubic in the order) take minutes for a model no system simulation
/// steps fast.
pub fn check_mode_count(requested: usize, nodes: usize, file: &Path) -> Result<usize> {
    let dofs = 3 * nodes;
    if requested > eigen::MAX_MODES {
        return Err(InputError::field(
            file,
            "reduction.modes",
            format!(
                "{requested} modes requested, at most {} are supported: a reduced body for system simulation needs the modes of its scene's band (use reduction.max_frequency, or scene.band with scene.tolerance)",
                eigen::MAX_MODES
            ),
        ));
    }
    if requested > dofs / 4 {
        return Err(InputError::field(
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
pub fn check_krylov_size(spec: &Spec, file: &Path) -> Result<()> {
    let r = &spec.reduction;
    if r.method != Method::Krylov {
        return Ok(());
    }
    let points =
        1 + r.expansion_points.as_ref().map_or(0, Vec::len) + r.real_expansion_points.as_ref().map_or(0, Vec::len);
    if points > MAX_EXPANSION_POINTS {
        return Err(InputError::field(
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
        return Err(InputError::field(
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
pub fn check_distributable(spec: &Spec, file: &Path) -> Result<()> {
    let backend = &spec.reduction.backend;
    if backend.kind != Some(BackendKind::Petsc) {
        if backend != &(BackendSpec { kind: backend.kind, ..Default::default() }) {
            return Err(InputError::field(
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
        return Err(InputError::field(
            file,
            "reduction.expansion_points",
            "the petsc back-end expands about s = 0 only (each other expansion point needs an indefinite factorisation \
             of its own, which it does not run): remove the expansion points and use reduction.moments, or build in process",
        ));
    }
    if spec.scene.as_ref().is_some_and(|s| s.tolerance.is_some()) {
        return Err(InputError::field(
            file,
            "scene.tolerance",
            "the order selection by tolerance compares complex full-model responses across the band, which the petsc \
             back-end does not run: give reduction.modes or reduction.max_frequency instead, or build in process",
        ));
    }
    Ok(())
}

/// A basis needs at least one shape: a mode, a force flange's static shapes or a scene load's.
pub fn check_basis_not_empty(spec: &Spec, file: &Path) -> Result<()> {
    let force_flanges = spec.flanges.iter().filter(|f| f.role == Role::Force).count();
    let loads = spec.scene.as_ref().map_or(0, |s| s.loads.len());
    let r = &spec.reduction;
    let modes = r.modes.is_some_and(|n| n > 0) || (r.modes.is_none() && r.max_frequency.is_some());
    if modes || force_flanges > 0 || loads > 0 {
        return Ok(());
    }
    let field = if spec.reduction.method == Method::Krylov { "flanges" } else { "reduction.modes" };
    Err(InputError::field(
        file,
        field,
        "the reduced body would have no shape at all: no normal modes are requested (reduction.modes is 0 or missing), the body has no force flange whose static shapes would join the basis, and the scene declares no loads; request modes (reduction.modes >= 1 or reduction.max_frequency), add a force flange, or declare scene.loads",
    ))
}

/// A free-floating body (no "motion" flange) needs at least one elastic mode: its attachment
/// shapes alone are quasi-static, and with nothing holding the body the lowest elastic mode they
/// stand in for is missing, so the reduced model has no frequency range in which it is valid.
/// A mounted body may be static-only (its flange compliance exact); the summary says so.
pub fn check_free_body_modes(spec: &Spec, file: &Path) -> Result<()> {
    let mounted = spec.flanges.iter().any(|f| f.role == Role::Motion);
    if mounted || spec.reduction.modes != Some(0) {
        return Ok(());
    }
    Err(InputError::field(
        file,
        "reduction.modes",
        "0 modes for a free-floating body (no \"motion\" flange): its static attachment shapes alone leave out the \
         lowest elastic mode, so the model would be valid in no frequency range; request modes (reduction.modes >= 1 \
         or reduction.max_frequency), or mount the body with a \"motion\" flange for a static-only model",
    ))
}
