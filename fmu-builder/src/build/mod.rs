//! The driver: runs the stages for one spec, input to FMU. `mounted` builds bodies held at a
//! mount flange, `free_floating` bodies without one; both return a `Built`, which
//! `output::package` writes as the FMU. `sweep` compares methods and orders side by side.

mod built;
pub mod free_floating;
pub mod mounted;
pub mod sweep;

pub use built::Built;

use crate::error::{BuildError, Result};
use crate::input::spec::Spec;
use crate::linalg::eigen;
use crate::model::{flange, part};
use crate::output::package;
use crate::reduce::basis::ModeCount;
use std::path::Path;

/// Read `input`, reduce, write the FMU to `output`.
pub fn build(input: &Path, output: &Path) -> Result<Built> {
    let spec = Spec::from_file(input)?;
    let built = reduce_spec(spec, input)?;
    package::write_fmu(&built.spec, &built.reduced, &built.report, output)?;
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

/// Read, mesh, couple, assemble and reduce: everything but writing the FMU.
pub fn reduce_spec(spec: Spec, file: &Path) -> Result<Built> {
    let mut part = part::part_of(&spec, file)?;
    let flanges = flange::select_flanges(&spec, file, &part)?;
    let free = part.free_free()?;
    let modes = match (spec.reduction.modes, spec.reduction.max_frequency) {
        (Some(n), _) => ModeCount::Count(check_mode_count(n, part.mesh.n_nodes(), file)?),
        (None, Some(f)) => ModeCount::Below(f),
        (None, None) => ModeCount::Count(0),
    };
    let Some(mount) = spec.mount_index() else {
        return free_floating::reduce(spec, part, free, flanges, modes);
    };
    mounted::reduce(spec, part, free, flanges, modes, mount)
}
