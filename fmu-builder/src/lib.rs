//! fmu-builder: from a finite-element description of an elastic part to an FMI 2.0 FMU of the
//! reduced flexible body.
//!
//! The modules are the stages of the data flow, in order; a stage uses only the stages before it
//! (and `linalg`/`error`/`profile`/`out_of_memory`, which every stage may use):
//!
//! 1. [`input`]: what the user wrote: the JSON spec, the built-in box mesher, the importers of
//!    Abaqus/CalculiX decks, Gmsh meshes and Matrix Market matrices, the element catalogue.
//! 2. [`model`]: the FE model: element matrices, assembly, the part, flange selection and the
//!    rigid coupling of flanges to six-DoF masters, and the writers of the full model.
//! 3. [`reduce`]: the reduction: basis methods (Craig-Bampton, modal, Krylov), frequency
//!    responses, order selection and the accuracy comparison against the full model.
//! 4. [`ffrf`]: the floating-frame terms of the reduced body: inertia invariants, inertial load
//!    cases and geometric stiffening.
//! 5. [`output`]: what the user gets: report, summary, HTML documentation and plots, the FMU
//!    archive with its modelDescription.xml.
//!
//! [`pipeline`] runs the stages for one spec as a sequence of phases (mounted or free-floating
//! bodies as two strategies of one pipeline; order sweeps); [`job`] is one run as the command
//! line asks for it (destinations checked first, exports, summary).

pub mod error;
pub mod profile;
pub mod progress;

/// The stages below the builder's own, crates of their own so that Cargo keeps them below:
/// they cannot name the stages that use them.
pub use fe_input as input;
pub use fe_input::out_of_memory;
pub use fe_linalg as linalg;

pub mod ffrf;
pub mod model;
pub mod output;
pub mod reduce;

pub mod pipeline;

pub mod job;
