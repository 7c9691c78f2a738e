//! faer's errors in words: its Debug forms (`Numeric(NonPositivePivot { index: 4 })`) mean
//! nothing to a user. What they say about the model, and what usually causes it.

use faer::sparse::linalg::{LltError, LuError};
use faer::sparse::{CreationError, FaerError};

pub fn generic(e: &FaerError) -> String {
    match e {
        FaerError::IndexOverflow => "the matrix's index space overflows (the model is far too large)".into(),
        FaerError::OutOfMemory => "out of memory (the model is too large for this machine: coarsen the mesh)".into(),
        _ => "an allocation or index error (the model is too large)".into(),
    }
}

pub fn creation(e: &CreationError) -> String {
    match e {
        CreationError::Generic(g) => generic(g),
        CreationError::OutOfBounds { row, col } => format!("an entry ({row}, {col}) outside the matrix"),
    }
}

/// A failed sparse Cholesky: with the part's connectivity checked beforehand, a pivot that is
/// not positive is a mechanism inside the mesh (elements joined at a single node or edge,
/// reduced-integration hourglass modes) or a material or geometry so extreme that the stiffness
/// lost its digits.
pub fn llt(e: &LltError) -> String {
    match e {
        LltError::Numeric(_) => "not positive definite: a part of the model can move without deforming it (elements \
             joined only at a node or an edge, hourglass modes of reduced integration in a mesh one element thick), or \
             extreme proportions or material values left the stiffness without the digits to tell"
            .into(),
        LltError::Generic(g) => generic(g),
    }
}

pub fn lu(e: &LuError) -> String {
    match e {
        LuError::SymbolicSingular { .. } => "structurally singular (a DoF no element or coupling touches)".into(),
        LuError::Generic(g) => generic(g),
    }
}
