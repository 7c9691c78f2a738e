//! PETSc's binary matrix format, as `MatLoad` reads it: big-endian 32-bit integers (class id,
//! rows, columns, entries, each row's length, the column indices) then the values as doubles.

use crate::error::{BackendError, Result};
use std::io::Write;
use std::path::Path;

/// `MAT_FILE_CLASSID` of petscmat.h.
const MAT_FILE_CLASSID: i32 = 1_211_216;

type Sparse = faer::sparse::SparseColMat<usize, f64>;

/// Write the symmetric `a` (both triangles stored) as a PETSc AIJ matrix. Its compressed columns
/// are written as compressed rows: the transpose, which is `a` itself. Debian's PETSc indexes
/// with 32-bit integers, so larger matrices are refused with the count.
pub fn write_symmetric(path: &Path, a: &Sparse) -> Result<()> {
    let (n, nnz) = (a.ncols(), a.compute_nnz());
    let fits = |v: usize| i32::try_from(v).ok();
    let (Some(n32), Some(nnz32)) = (fits(n), fits(nnz)) else {
        return Err(BackendError::matrix(format!(
            "a matrix of {n} rows and {nnz} entries is beyond PETSc's 32-bit indices: use a PETSc built with \
             --with-64-bit-indices"
        )));
    };
    let io = |e: std::io::Error| BackendError::matrix(format!("writing {}: {e}", path.display())).caused_by(e);
    let mut out = std::io::BufWriter::with_capacity(1 << 20, super::job_folder::private_file(path)?);
    for v in [MAT_FILE_CLASSID, n32, fits(a.nrows()).unwrap_or(i32::MAX), nnz32] {
        out.write_all(&v.to_be_bytes()).map_err(io)?;
    }
    for j in 0..n {
        out.write_all(&(a.row_idx_of_col_raw(j).len() as i32).to_be_bytes()).map_err(io)?;
    }
    // PETSc wants each row's columns ascending; a column of ours may hold its rows in any order
    let sorted = |j: usize| -> Vec<(usize, f64)> {
        let mut entries: Vec<(usize, f64)> =
            a.row_idx_of_col_raw(j).iter().copied().zip(a.val_of_col(j).iter().copied()).collect();
        entries.sort_unstable_by_key(|e| e.0);
        entries
    };
    for j in 0..n {
        for (i, _) in sorted(j) {
            out.write_all(&(i as i32).to_be_bytes()).map_err(io)?;
        }
    }
    for j in 0..n {
        for (_, v) in sorted(j) {
            out.write_all(&v.to_be_bytes()).map_err(io)?;
        }
    }
    out.flush().map_err(io)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The bytes of a 2 x 2 matrix, laid out by hand from PETSc's MatLoad documentation (the
    /// driver's tests load the files with PETSc itself).
    #[test]
    fn layout_of_a_small_matrix() {
        let a = Sparse::try_new_from_triplets(
            2,
            2,
            &[
                faer::sparse::Triplet::new(0, 0, 2.0),
                faer::sparse::Triplet::new(1, 0, -1.0),
                faer::sparse::Triplet::new(0, 1, -1.0),
                faer::sparse::Triplet::new(1, 1, 3.0),
            ],
        )
        .unwrap();
        let dir = std::env::temp_dir().join(format!("petsc-binary-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("a.bin");
        write_symmetric(&path, &a).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        std::fs::remove_dir_all(&dir).ok();
        let ints: Vec<i32> = bytes[..4 * 10].chunks(4).map(|c| i32::from_be_bytes([c[0], c[1], c[2], c[3]])).collect();
        assert_eq!(ints, vec![MAT_FILE_CLASSID, 2, 2, 4, 2, 2, 0, 1, 0, 1]);
        let values: Vec<f64> = bytes[40..].chunks(8).map(|c| f64::from_be_bytes(c.try_into().unwrap())).collect();
        assert_eq!(values, vec![2.0, -1.0, -1.0, 3.0]);
    }
}
