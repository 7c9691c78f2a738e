//! The builder's linear algebra, which every stage uses: sparse matrices and their factorisations, the shift-invert
//! Lanczos eigen-solver, and the dense symmetric eigen-solver whose backward error is checked.
//!
//! It sits below every stage and cannot name them: an import of the input or of the builder
//! does not compile.
//!
//! ```compile_fail,E0432
//! use fe_input::spec::Spec;
//! ```
//!
//! ```compile_fail,E0432
//! use fmu_builder::model::part::Part;
//! ```
//!
//! The back-end below it is its to use:
//!
//! ```
//! use fe_linalg::distributed::Backend;
//! assert_eq!(Backend::default(), Backend::InProcess);
//! ```

pub mod dense_eigen;
/// The distributed back-end, behind the same solver.
pub use petsc_backend as distributed;
pub mod dot2;
pub mod eigen;
pub mod error;
pub mod faer_error;
pub mod first_touch;
pub mod held;
pub mod ordering;
pub mod sparse;
pub mod symmetric_eigen;
pub mod symmetric_product;
#[cfg(test)]
pub(crate) mod test_grids;
pub mod tree_solve;
