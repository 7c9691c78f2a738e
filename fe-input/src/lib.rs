//! Stage 1 of the builder, input: what the user wrote. The JSON spec (validated against the schema), the
//! catalogue of the supported elements, the built-in mesher of boxes, and the importers of meshes
//! and matrices from other FE tools.
//!
//! The stages after it (the model, the reduction, the floating-frame terms, the output) are the
//! builder's; the input cannot name them:
//!
//! ```compile_fail,E0432
//! use fmu_builder::model::part::Part;
//! ```
//!
//! ```
//! use fe_input::element::ElementKind;
//! let _ = std::mem::size_of::<ElementKind>();
//! ```

pub mod assembly;
pub mod element;
pub mod error;
pub mod file_read;
pub mod import;
pub mod json_keys;
pub mod mesh;
pub mod out_of_memory;
pub mod ranges;
pub mod reduction_checks;
pub mod schema_errors;
pub mod size;
pub mod spec;
pub mod variable_names;
