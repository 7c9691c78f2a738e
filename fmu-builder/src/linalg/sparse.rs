//! Sparse helpers over faer: leading blocks, symmetric products and a factor-once solver.

use crate::error::{BuildError, Result};
use crate::linalg::faer_error;
use faer::linalg::solvers::Solve;
use faer::reborrow::{Reborrow, ReborrowMut};
use faer::sparse::linalg::solvers::Llt;
use faer::sparse::{SparseColMat, Triplet};
use faer::{Mat, MatMut, MatRef, Par, Side};

pub type Sparse = SparseColMat<usize, f64>;

/// The block A[rows, cols] for index ranges.
pub fn block(a: &Sparse, rows: std::ops::Range<usize>, cols: std::ops::Range<usize>) -> Result<Sparse> {
    let mut trip = Vec::new();
    for j in cols.clone() {
        let rows_j = a.row_idx_of_col_raw(j);
        let vals = a.val_of_col(j);
        for (&i, &v) in rows_j.iter().zip(vals) {
            if rows.contains(&i) {
                trip.push(Triplet::new(i - rows.start, j - cols.start, v));
            }
        }
    }
    SparseColMat::try_new_from_triplets(rows.len(), cols.len(), &trip)
        .map_err(|e| BuildError::Numerical(format!("extracting a sparse block: {}", faer_error::creation(&e))))
}

/// out = A x
pub fn mul(out: MatMut<'_, f64>, a: &Sparse, x: MatRef<'_, f64>) {
    faer::sparse::linalg::matmul::sparse_dense_matmul(out, faer::Accum::Replace, a.as_ref(), x, 1.0, Par::Seq);
}

pub fn mul_new(a: &Sparse, x: MatRef<'_, f64>) -> Mat<f64> {
    let mut out = Mat::zeros(a.nrows(), x.ncols());
    mul(out.as_mut(), a, x);
    out
}

/// C + sign * A X, each entry accumulated in double-double (Ogita-Rump-Oishi Dot2: exact products
/// by FMA, error-free sums) and rounded once. Stiffness matrices of slender parts multiply static
/// shapes into reactions that are 1e-6 of the terms summed; plain sums would lose those digits.
pub fn mul_compensated(c: Option<MatRef<'_, f64>>, sign: f64, a: &Sparse, x: MatRef<'_, f64>) -> Mat<f64> {
    let (n, k) = (a.nrows(), x.ncols());
    let col_ptr = a.symbolic().col_ptr();
    let row_idx = a.symbolic().row_idx();
    let val = a.val();
    let mut out = Mat::<f64>::zeros(n, k);
    let mut hi = vec![0.0; n];
    let mut lo = vec![0.0; n];
    let mut xc = vec![0.0; a.ncols()];
    for col in 0..k {
        match c {
            Some(c) => {
                for i in 0..n {
                    hi[i] = c[(i, col)];
                }
            }
            None => hi.fill(0.0),
        }
        lo.fill(0.0);
        for (j, xj) in xc.iter_mut().enumerate() {
            *xj = sign * x[(j, col)];
        }
        for j in 0..a.ncols() {
            let xj = xc[j];
            if xj == 0.0 {
                continue;
            }
            for p in col_ptr[j]..col_ptr[j + 1] {
                let i = row_idx[p];
                let aij = val[p];
                let prod = aij * xj;
                let err = product_error(aij, xj, prod);
                let s = hi[i] + prod;
                let bp = s - hi[i];
                let t = (hi[i] - (s - bp)) + (prod - bp);
                hi[i] = s;
                lo[i] += t + err;
            }
        }
        for i in 0..n {
            out[(i, col)] = hi[i] + lo[i];
        }
    }
    out
}

/// The rounding error of p = a * b (exactly a * b - p), by Dekker's splitting: `f64::mul_add`
/// would do it in one instruction, but without the FMA target feature it becomes a call into
/// libm's software fma, a hundred times slower in these inner loops.
#[inline(always)]
fn product_error(a: f64, b: f64, p: f64) -> f64 {
    const SPLIT: f64 = 134_217_729.0; // 2^27 + 1
    let t = SPLIT * a;
    let a_hi = t - (t - a);
    let a_lo = a - a_hi;
    let t = SPLIT * b;
    let b_hi = t - (t - b);
    let b_lo = b - b_hi;
    ((a_hi * b_hi - p) + a_hi * b_lo + a_lo * b_hi) + a_lo * b_lo
}

/// Sparse LU of a general (here: symmetric indefinite, K - w^2 M above the first eigenvalue)
/// matrix, with the same double-double refinement as the Cholesky solver.
pub struct LuSolver {
    lu: faer::sparse::linalg::solvers::Lu<usize, f64>,
    matrix: Sparse,
}

impl LuSolver {
    pub fn new(a: &Sparse, what: &str) -> Result<Self> {
        let lu = crate::profile::phase(format!("LU factorisation: {what}"), || {
            crate::profile::note(|| format!("n {}, nnz(A) {}", a.nrows(), a.compute_nnz()));
            a.sp_lu()
        })
        .map_err(|e| BuildError::Numerical(format!("{what} is {}", faer_error::lu(&e))))?;
        Ok(Self { lu, matrix: a.clone() })
    }

    pub fn solve_refined(&self, mut rhs: MatMut<'_, f64>) {
        let b = rhs.to_owned();
        self.lu.solve_in_place(rhs.rb_mut());
        for _ in 0..2 {
            let mut r = mul_compensated(Some(b.as_ref()), -1.0, &self.matrix, rhs.rb());
            self.lu.solve_in_place(r.as_mut());
            for j in 0..r.ncols() {
                for i in 0..r.nrows() {
                    rhs[(i, j)] += r[(i, j)];
                }
            }
        }
    }
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
    SparseColMat::try_new_from_triplets(a.nrows(), a.ncols(), &trip)
        .map_err(|e| BuildError::Numerical(format!("adding sparse matrices: {}", faer_error::creation(&e))))
}

/// Sparse Cholesky of a symmetric positive definite matrix (fill-reducing ordering inside faer).
pub struct SpdSolver {
    llt: Llt<usize, f64>,
    matrix: Sparse,
    n: usize,
}

impl SpdSolver {
    pub fn new(a: &Sparse, what: &str) -> Result<Self> {
        let llt = crate::profile::phase(format!("Cholesky factorisation: {what}"), || {
            crate::profile::note(|| format!("n {}, nnz(A) {}", a.nrows(), a.compute_nnz()));
            a.sp_cholesky(Side::Lower)
        })
        .map_err(|e| BuildError::Numerical(format!("{what} is {}", faer_error::llt(&e))))?;
        Ok(Self { llt, matrix: a.clone(), n: a.nrows() })
    }

    pub fn n(&self) -> usize {
        self.n
    }

    /// The factored matrix.
    pub fn matrix(&self) -> &Sparse {
        &self.matrix
    }

    pub fn solve_in_place(&self, rhs: MatMut<'_, f64>) {
        self.llt.solve_in_place(rhs);
    }

    /// Solve with iterative refinement on residuals computed in double-double: static shapes of
    /// slender parts lose digits to the stiffness's condition number (~1e10), and the flange
    /// compliance must be exact to round-off; an extended-precision residual restores them.
    pub fn solve_refined(&self, rhs: MatMut<'_, f64>) {
        self.solve_refined_steps(rhs, 2);
    }

    pub fn solve_refined_steps(&self, mut rhs: MatMut<'_, f64>, steps: usize) {
        let b = rhs.to_owned();
        self.llt.solve_in_place(rhs.rb_mut());
        for _ in 0..steps {
            let mut r = mul_compensated(Some(b.as_ref()), -1.0, &self.matrix, rhs.rb());
            self.llt.solve_in_place(r.as_mut());
            for j in 0..r.ncols() {
                for i in 0..r.nrows() {
                    rhs[(i, j)] += r[(i, j)];
                }
            }
        }
    }
}

/// The row of `a` (in its own order) where a Cholesky factorisation meets a pivot that is not
/// positive, or None when it factors (or fails otherwise). Only for messages after a failed
/// `SpdSolver::new`: faer reports the pivot in its fill-reducing order, which this repeats with
/// the symbolic factorisation in hand to map it back.
pub fn nonpositive_pivot_row(a: &Sparse) -> Option<usize> {
    use faer::dyn_stack::{MemBuffer, MemStack};
    use faer::linalg::cholesky::llt::factor::LltError;
    use faer::sparse::linalg::cholesky::{SymbolicCholeskyRaw, factorize_symbolic_cholesky};
    let symbolic =
        factorize_symbolic_cholesky(a.symbolic(), Side::Lower, Default::default(), Default::default()).ok()?;
    let mut values = Vec::new();
    values.try_reserve_exact(symbolic.len_val()).ok()?;
    values.resize(symbolic.len_val(), 0.0);
    let mut mem =
        MemBuffer::try_new(symbolic.factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default())).ok()?;
    let outcome = symbolic.factorize_numeric_llt::<f64>(
        &mut values,
        a.as_ref(),
        Side::Lower,
        Default::default(),
        Par::Seq,
        MemStack::new(&mut mem),
        Default::default(),
    );
    match outcome {
        Err(LltError::NonPositivePivot { index }) => {
            // faer 0.24 counts the simplicial pivot from 1 (k + 1) and the supernodal one from 0
            let position = match symbolic.raw() {
                SymbolicCholeskyRaw::Simplicial(_) => index.checked_sub(1)?,
                SymbolicCholeskyRaw::Supernodal(_) => index,
            };
            // the fill-reducing order: its forward array names the matrix row eliminated at each
            // position (AMD's perm[k] = i)
            match symbolic.perm() {
                Some(p) => p.arrays().0.get(position).copied(),
                None => Some(position),
            }
        }
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    /// A chain of 50 rows, row 37 indefinite: whatever order the factorisation chooses, every
    /// other pivot stays positive, so the failure maps back to row 37.
    #[test]
    fn the_failing_pivot_is_found_in_the_matrix_order() {
        use faer::sparse::{SparseColMat, Triplet};
        let chain = |bad: Option<usize>| {
            let mut t = Vec::new();
            for i in 0..50 {
                t.push(Triplet::new(i, i, if Some(i) == bad { -1.0 } else { 4.0 }));
                if i + 1 < 50 {
                    t.push(Triplet::new(i, i + 1, 1.0));
                    t.push(Triplet::new(i + 1, i, 1.0));
                }
            }
            SparseColMat::try_new_from_triplets(50, 50, &t).unwrap()
        };
        assert!(super::SpdSolver::new(&chain(Some(37)), "test").is_err());
        assert_eq!(super::nonpositive_pivot_row(&chain(Some(37))), Some(37));
        assert_eq!(super::nonpositive_pivot_row(&chain(None)), None);
        // a 3D grid (supernodal factor, reordered): every principal block without the bad row is
        // diagonally dominant, so the failure is that row whatever the order
        let k = 12;
        let mut t = Vec::new();
        let id = |x: usize, y: usize, z: usize| x + k * (y + k * z);
        for z in 0..k {
            for y in 0..k {
                for x in 0..k {
                    let i = id(x, y, z);
                    t.push(Triplet::new(i, i, if i == 1000 { -100.0 } else { 7.0 }));
                    for (dx, dy, dz) in [(1, 0, 0), (0, 1, 0), (0, 0, 1)] {
                        if x + dx < k && y + dy < k && z + dz < k {
                            let j = id(x + dx, y + dy, z + dz);
                            t.push(Triplet::new(i, j, -1.0));
                            t.push(Triplet::new(j, i, -1.0));
                        }
                    }
                }
            }
        }
        let grid = SparseColMat::try_new_from_triplets(k * k * k, k * k * k, &t).unwrap();
        assert_eq!(super::nonpositive_pivot_row(&grid), Some(1000));
    }

    #[test]
    fn product_error_is_exact() {
        for (a, b) in [(0.1, 0.3), (1e10 / 3.0, 7.0 / 3.0), (-2.5e-8, 1.0 / 7.0), (123456.789, -9.87654321e-5)] {
            let p = a * b;
            assert_eq!(super::product_error(a, b, p), a.mul_add(b, -p));
        }
    }
}
