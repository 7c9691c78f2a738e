//! Assemblies: several bodies, flexible and rigid, joined by joints and solved together inside
//! one FMU. `inertia` holds a body's equations of motion.

mod condensed;
pub mod error;
pub mod joint;
mod mat_vec;

pub use error::AssemblyError;
pub mod description;
pub mod inertia;
pub mod model;
pub mod solver;
pub mod system;
