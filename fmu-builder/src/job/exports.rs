//! The files written besides the FMU, after it: the report, the mesh as a deck or a VTK file
//! with the basis' shapes, and the matrices, each through a temporary file and a checked rename
//! (`output::place`). A failure names the option and says that the FMU was written.

use crate::error::{BuildError, Result};
use crate::model::{export, vtk};
use crate::output::place;
use crate::pipeline::Built;
use std::path::{Path, PathBuf};

/// Files written besides the FMU.
#[derive(Debug, Clone, Default)]
pub struct Exports {
    pub report: Option<PathBuf>,
    pub inp: Option<PathBuf>,
    pub vtk: Option<PathBuf>,
    pub matrices: Option<PathBuf>,
    pub free_free: Option<PathBuf>,
}

pub(super) fn write(exports: &Exports, built: &Built, fmu: &Path) -> Result<()> {
    let failed = |option: &'static str| {
        move |source: BuildError| BuildError::Export { option, fmu: fmu.to_path_buf(), source: Box::new(source) }
    };
    let put = &place::write_bytes;
    if let Some(path) = &exports.report {
        let json = serde_json::to_string_pretty(&built.report)
            .map_err(|e| BuildError::internal(format!("serialising the report: {e}")).caused_by(e))
            .map_err(failed("--report"))?;
        put(path, json.as_bytes()).map_err(failed("--report"))?;
    }
    if let Some(path) = &exports.inp {
        export::write_abaqus_deck(path, &built.part, &built.flanges, put).map_err(failed("--export-inp"))?;
    }
    if let Some(path) = &exports.vtk {
        write_vtk(path, built).map_err(failed("--export-vtk"))?;
    }
    if let Some(dir) = &exports.free_free {
        export::write_free_free_matrices(dir, &built.part, put).map_err(failed("--export-free-free"))?;
    }
    if let Some(dir) = &exports.matrices {
        export::write_matrix_market(dir, &built.model, put).map_err(failed("--export-matrices"))?;
    }
    Ok(())
}

/// The mesh with the basis' shapes as displacement fields, named with their frequencies.
fn write_vtk(path: &Path, b: &Built) -> Result<()> {
    let shapes = crate::ffrf::inertia::expand(&b.model, &b.part.mesh.nodes, &b.flanges, b.basis.phi.as_ref());
    let names: Vec<String> = b
        .basis
        .omega
        .iter()
        .enumerate()
        .map(|(j, w)| format!("shape_{:02}_{:.4}Hz", j + 1, w / (2.0 * std::f64::consts::PI)))
        .collect();
    vtk::write_vtk(path, &b.spec.name, &b.part, &b.flanges, shapes.as_ref(), &names, &place::write_bytes)
}
