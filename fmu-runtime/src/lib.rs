//! FMI 2.0 runtime of a reduced flexible body. Two layers, as in the Reference-FMUs:
//! `fmi` knows the C API and the FMI state machine and nothing of mechanics; `body` knows the
//! reduced equations and nothing of C; `interface` maps FMU variables onto the body.
//! `format`/`reduced` define the reduced-model file the builder writes into `resources/`.

pub mod body;
pub mod coupled_propagator;
pub mod format;
pub mod kinematics;
pub mod propagator;
pub mod reduced;
pub mod scalar;
pub mod fmi;
pub mod fmu;
pub mod interface;

export_fmi2!(crate::fmu::BodyFmu);
