//! Linear algebra every stage uses: sparse matrices and their factorisations, the shift-invert
//! Lanczos eigen-solver, and the dense symmetric eigen-solver whose backward error is checked.

pub mod dense_eigen;
pub mod distributed;
pub mod dot2;
pub mod eigen;
pub mod faer_error;
pub mod held;
pub mod ordering;
pub mod sparse;
pub mod symmetric_eigen;
pub mod symmetric_product;
#[cfg(test)]
pub(crate) mod test_grids;
pub mod tree_solve;
