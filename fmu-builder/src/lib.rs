//! fmu-builder: from a finite-element description of an elastic part to an FMI 2.0 FMU of the
//! reduced flexible body. Modules follow the data: spec -> mesh -> fe/assembly -> flange ->
//! reduce -> ffrf -> fmu.

pub mod assembly;
pub mod eigen;
pub mod error;
pub mod export;
pub mod fe;
pub mod fmu;
pub mod flange;
pub mod free_floating;
pub mod frf;
pub mod import;
pub mod inertia;
pub mod mesh;
pub mod order;
pub mod part;
pub mod reduce;
pub mod sparse;
pub mod spec;
pub mod stiffening;
pub mod documentation;
pub mod ffrf;
pub mod pipeline;
pub mod package;
pub mod report;
pub mod summary;
pub mod sweep;
pub mod symmetric_eigen;
