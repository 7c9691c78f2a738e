//! FMI 2.0 runtime of a reduced flexible body. Two layers, as in the Reference-FMUs:
//! the `fmi2` crate knows the C API and the FMI state machine and nothing of mechanics; `body`
//! knows the reduced equations and nothing of C; `fmu` implements `fmi2::Model` for the body,
//! and `interface` maps FMU variables onto it. `format`/`reduced` define the reduced-model file
//! the builder writes into `resources/`.

pub mod body;
pub mod coupled_propagator;
pub mod fmu;
pub mod format;
pub mod interface;
pub mod kinematics;
pub mod propagator;
pub mod reduced;
pub mod scalar;

fmi2::export_fmi2!(crate::fmu::BodyFmu);
