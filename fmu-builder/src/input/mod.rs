//! Stage 1, input: what the user wrote. The JSON spec (validated against the schema), the
//! catalogue of the supported elements, the built-in mesher of boxes, and the importers of meshes
//! and matrices from other FE tools.

pub mod element;
pub mod file_read;
pub mod import;
pub mod json_keys;
pub mod mesh;
pub mod ranges;
pub mod reduction_checks;
pub mod schema_errors;
pub mod size;
pub mod spec;
pub mod variable_names;
