//! Sparse matrices made from others: a block of one, a sum of two.

use super::Sparse;
use crate::error::{LinalgError, Result};
use crate::faer_error;
use faer::sparse::{SparseColMat, Triplet};

/// The block A[rows, cols] for index ranges, column by column in compressed form (no triplets:
/// the mounted body's 19M-entry stiffness took 0.5 GB of them).
pub fn block(a: &Sparse, rows: std::ops::Range<usize>, cols: std::ops::Range<usize>) -> Result<Sparse> {
    let mut col_ptr = Vec::with_capacity(cols.len() + 1);
    let mut row_idx = Vec::new();
    let mut values = Vec::new();
    col_ptr.push(0);
    for j in cols.clone() {
        for (&i, &v) in a.row_idx_of_col_raw(j).iter().zip(a.val_of_col(j)) {
            if rows.contains(&i) {
                row_idx.push(i - rows.start);
                values.push(v);
            }
        }
        col_ptr.push(row_idx.len());
    }
    let symbolic =
        faer::sparse::SymbolicSparseColMat::new_unsorted_checked(rows.len(), cols.len(), col_ptr, None, row_idx);
    Ok(SparseColMat::new(symbolic, values))
}

/// A + c B for matrices of the same size.
pub fn add_scaled(a: &Sparse, c: f64, b: &Sparse) -> Result<Sparse> {
    let mut trip = Vec::new();
    for (m, scale) in [(a, 1.0), (b, c)] {
        for j in 0..m.ncols() {
            for (&i, &v) in m.row_idx_of_col_raw(j).iter().zip(m.val_of_col(j)) {
                trip.push(Triplet::new(i, j, scale * v));
            }
        }
    }
    SparseColMat::try_new_from_triplets(a.nrows(), a.ncols(), &trip).map_err(|e| {
        LinalgError::inconsistent(format!("adding sparse matrices: {}", faer_error::creation(&e))).caused_by(e)
    })
}
