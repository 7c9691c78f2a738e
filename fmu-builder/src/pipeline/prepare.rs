//! The phases every body goes through before it is coupled: the part meshed or imported, its
//! flanges and recovery points selected, its connectivity checked, its free-free matrices
//! assembled, and the reduction's settings checked against it.

use super::against::{Against, GEOMETRY};
use crate::error::Result;
use crate::input::reduction_checks::{
    check_basis_not_empty, check_distributable, check_free_body_modes, check_krylov_size, check_mode_count,
};
use crate::input::spec::Spec;
use crate::model::assembly::Uncoupled;
use crate::model::connectivity;
use crate::model::flange::{self, Flange};
use crate::model::part::{self, Part};
use crate::model::stress::{Recovery, requested_points};
use crate::output::plausibility;
use crate::reduce::basis::ModeCount;
use std::path::{Path, PathBuf};

/// The part before its flanges are tied: what both kinds of body start from.
pub(super) struct Prepared {
    pub spec: Spec,
    /// The input file: messages name it, relative paths in it resolve from its folder.
    pub file: PathBuf,
    pub part: Part,
    pub flanges: Vec<Flange>,
    pub free: Uncoupled,
    pub modes: ModeCount,
    pub recovery: Option<Recovery>,
}

pub(super) fn prepare(spec: Spec, file: &Path) -> Result<Prepared> {
    let mut part = phases::phase("mesh or import", || part::part_of(&spec, file))?;
    let flanges = phases::phase("flange selection", || flange::select_flanges(&spec, file, &part))?;
    // recovery points are checked before anything costly: a misspelt node set fails at once
    let recovery = match spec.outputs.as_ref().and_then(|o| o.stress.as_ref()) {
        Some(request) => Some(requested_points(file, request, &part)?),
        None => None,
    };
    // a part given with its supports (free_free false) is held by them, not only by flanges
    if spec.geometry.matrices.as_ref().is_none_or(|m| m.free_free) {
        phases::phase("connectivity", || connectivity::check_connected(file, &part, &flanges))?;
    }
    let free = phases::phase("assembly (free-free K, M)", || {
        phases::note(|| format!("{} nodes, {} DoFs", part.mesh.n_nodes(), 3 * part.mesh.n_nodes()));
        part.free_free()
    })
    .against(file, GEOMETRY)?;
    // a unit slip said now, before a reduction of the wrong part
    for w in plausibility::early_warnings(&part, part_mass(&part, &free), spec.reduction.max_frequency) {
        phases::warning(|| w);
    }
    let modes = mode_count(&spec, &part, file)?;
    Ok(Prepared { spec, file: file.to_path_buf(), part, flanges, free, modes, recovery })
}

/// The part's mass [kg] from its assembled nodal mass, as the report's mass properties sum it;
/// None for a part given by its matrices (their mass is the user's, not the mesh's).
fn part_mass(part: &Part, free: &Uncoupled) -> Option<f64> {
    (!part.from_matrices).then(|| free.nodal_mass.val().iter().sum())
}

/// The modes the input asks for, and the reduction's settings checked against the part.
fn mode_count(spec: &Spec, part: &Part, file: &Path) -> Result<ModeCount> {
    let modes = match (spec.reduction.modes, spec.reduction.max_frequency) {
        (Some(n), _) => ModeCount::Count(check_mode_count(n, part.mesh.n_nodes(), file)?),
        (None, Some(f)) => ModeCount::Below(f),
        (None, None) => ModeCount::Count(0),
    };
    check_basis_not_empty(spec, file)?;
    check_free_body_modes(spec, file)?;
    check_krylov_size(spec, file)?;
    check_distributable(spec, file)?;
    Ok(modes)
}
