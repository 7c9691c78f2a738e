//! Sparse matrix times dense block, in plain double sums.

use super::Sparse;
use crate::symmetric_product;
use faer::{Mat, MatMut, MatRef, Par};

/// out = A x. Two or more columns are split between two threads: faer's product runs on one
/// (its parallel setting changes nothing here) and reads A once per column, which leaves half
/// the memory bandwidth unused (249k-DoF bracket's mass, 6.4M entries, 5 columns: 36 ms ->
/// 24 ms; 20 columns: 145 ms -> 91 ms).
pub fn mul(out: MatMut<'_, f64>, a: &Sparse, x: MatRef<'_, f64>) {
    let k = x.ncols();
    let product = |out: MatMut<'_, f64>, x: MatRef<'_, f64>| {
        faer::sparse::linalg::matmul::sparse_dense_matmul(out, faer::Accum::Replace, a.as_ref(), x, 1.0, Par::Seq)
    };
    if k >= 2 && rayon::current_num_threads() >= 2 {
        let (o1, o2) = out.split_at_col_mut(k.div_ceil(2));
        let (x1, x2) = x.split_at_col(k.div_ceil(2));
        rayon::join(|| product(o1, x1), || product(o2, x2));
    } else {
        product(out, x);
    }
}

/// A[0..k, 0..k] x for x of k rows and A exactly symmetric, without forming the leading block
/// (a copy of the matrix): the rows of A [x; 0] that belong to it. `compensated` sums in
/// double-double.
pub fn mul_leading(a: &Sparse, x: MatRef<'_, f64>, compensated: bool) -> Mat<f64> {
    if compensated { symmetric_product::mul_compensated(None, 1.0, a, x) } else { symmetric_product::mul_new(a, x) }
}

pub fn mul_new(a: &Sparse, x: MatRef<'_, f64>) -> Mat<f64> {
    let mut out = Mat::zeros(a.nrows(), x.ncols());
    mul(out.as_mut(), a, x);
    out
}
