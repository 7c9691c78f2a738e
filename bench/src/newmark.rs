//! The full FE model (the builder's assembled, flange-constrained K and M with the mount held)
//! stepped by Newmark's average-acceleration scheme (gamma = 1/2, beta = 1/4), Rayleigh damping
//! C = alpha M + beta K as in the FMU.
//!
//! Written in the increment du = u_{n+1} - u_n (no acceleration vector needed):
//!   (K + 2/h C + 4/h^2 M) du = F_n + F_{n+1} - 2 K u_n + 4/h M v_n,   v_{n+1} = 2 du / h - v_n
//! (the damping terms of the right-hand side cancel exactly). The effective stiffness is factored
//! once by faer's sparse Cholesky (AMD ordering); a step is two sparse matrix-vector products and
//! one forward/backward solve, in preallocated vectors and a preallocated solve workspace.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::sparse::linalg::cholesky::{LltRef, SymbolicCholesky, SymmetricOrdering, factorize_symbolic_cholesky};
use faer::sparse::{SparseColMat, Triplet};
use faer::{Conj, MatMut, Par, Side};

pub type Sparse = SparseColMat<usize, f64>;

/// A sparse matrix in compressed columns, owned as plain vectors for the hot loop.
struct Csc {
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    val: Vec<f64>,
}

impl Csc {
    fn of(a: &Sparse) -> Self {
        let mut col_ptr = vec![0];
        let mut row_idx = Vec::new();
        let mut val = Vec::new();
        for j in 0..a.ncols() {
            row_idx.extend_from_slice(a.row_idx_of_col_raw(j));
            val.extend_from_slice(a.val_of_col(j));
            col_ptr.push(row_idx.len());
        }
        Self { col_ptr, row_idx, val }
    }

    /// y += s A x (A stored in full, both triangles).
    #[inline]
    fn mul_add(&self, s: f64, x: &[f64], y: &mut [f64]) {
        for (j, &xj) in x.iter().enumerate() {
            let sx = s * xj;
            if sx == 0.0 {
                continue;
            }
            let range = self.col_ptr[j]..self.col_ptr[j + 1];
            for (&i, &a) in self.row_idx[range.clone()].iter().zip(&self.val[range]) {
                y[i] += a * sx;
            }
        }
    }
}

/// Both triangles stored (the products assume it).
pub fn stores_both_triangles(a: &Sparse) -> bool {
    let (mut upper, mut lower) = (0usize, 0usize);
    for j in 0..a.ncols() {
        for &i in a.row_idx_of_col_raw(j) {
            if i < j {
                upper += 1;
            } else if i > j {
                lower += 1;
            }
        }
    }
    upper == lower && upper > 0
}

pub struct Newmark {
    k: Csc,
    m: Csc,
    symbolic: SymbolicCholesky<usize>,
    l_values: Vec<f64>,
    solve_mem: MemBuffer,
    h: f64,
    pub u: Vec<f64>,
    pub v: Vec<f64>,
    rhs: Vec<f64>,
    /// Nonzero loads (DoF, F_n + F_{n+1}).
    load: Vec<(usize, f64)>,
}

impl Newmark {
    pub fn new(k: &Sparse, m: &Sparse, alpha: f64, beta: f64, h: f64) -> Result<Self, String> {
        let n = k.nrows();
        if !(stores_both_triangles(k) && stores_both_triangles(m)) {
            return Err("K and M must store both triangles".into());
        }
        let (sk, sm) = (1.0 + 2.0 * beta / h, 2.0 * alpha / h + 4.0 / (h * h));
        let mut trip = Vec::with_capacity(k.compute_nnz() + m.compute_nnz());
        for (a, s) in [(k, sk), (m, sm)] {
            for j in 0..n {
                for (&i, &v) in a.row_idx_of_col_raw(j).iter().zip(a.val_of_col(j)) {
                    trip.push(Triplet::new(i, j, s * v));
                }
            }
        }
        let k_eff = Sparse::try_new_from_triplets(n, n, &trip).map_err(|e| format!("{e:?}"))?;
        let symbolic =
            factorize_symbolic_cholesky(k_eff.symbolic(), Side::Lower, SymmetricOrdering::Amd, Default::default())
                .map_err(|e| format!("symbolic Cholesky: {e:?}"))?;
        let mut l_values = vec![0.0; symbolic.len_val()];
        let mut mem = MemBuffer::new(symbolic.factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default()));
        symbolic
            .factorize_numeric_llt(
                &mut l_values,
                k_eff.as_ref(),
                Side::Lower,
                LltRegularization::default(),
                Par::Seq,
                MemStack::new(&mut mem),
                Default::default(),
            )
            .map_err(|e| format!("the effective stiffness is not positive definite: {e:?}"))?;
        let solve_mem = MemBuffer::new(symbolic.solve_in_place_scratch::<f64>(1, Par::Seq));
        Ok(Self {
            k: Csc::of(k),
            m: Csc::of(m),
            symbolic,
            l_values,
            solve_mem,
            h,
            u: vec![0.0; n],
            v: vec![0.0; n],
            rhs: vec![0.0; n],
            load: Vec::new(),
        })
    }

    pub fn factor_nnz(&self) -> usize {
        self.l_values.len()
    }

    pub fn matrix_nnz(&self) -> usize {
        self.k.val.len()
    }

    /// A constant load from t = 0 on (F_n = F_{n+1} = F on every step, the value just after the
    /// step at t = 0, so the trapezoidal rule sees a smooth problem on (0, T]).
    pub fn set_constant_load(&mut self, loads: &[(usize, f64)]) {
        self.load.clear();
        self.load.extend(loads.iter().map(|&(i, f)| (i, 2.0 * f)));
    }

    pub fn reset(&mut self) {
        self.u.fill(0.0);
        self.v.fill(0.0);
    }

    /// One step; no allocation.
    pub fn step(&mut self) {
        let h = self.h;
        self.rhs.fill(0.0);
        self.k.mul_add(-2.0, &self.u, &mut self.rhs);
        self.m.mul_add(4.0 / h, &self.v, &mut self.rhs);
        for &(i, f) in &self.load {
            self.rhs[i] += f;
        }
        let n = self.rhs.len();
        let llt = LltRef::<'_, usize, f64>::new(&self.symbolic, &self.l_values);
        llt.solve_in_place_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(&mut self.rhs, n, 1),
            Par::Seq,
            MemStack::new(&mut self.solve_mem),
        );
        for ((u, v), &du) in self.u.iter_mut().zip(self.v.iter_mut()).zip(&self.rhs) {
            *u += du;
            *v = 2.0 / h * du - *v;
        }
    }
}
