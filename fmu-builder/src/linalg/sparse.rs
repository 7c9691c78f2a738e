//! Sparse helpers over faer: leading blocks, symmetric products and a factor-once solver.

use crate::error::{BuildError, Result};
use crate::linalg::distributed::Backend;
use crate::linalg::distributed::session::Session;
use crate::linalg::dot2::add_product;
use crate::linalg::faer_error;
use crate::linalg::ordering;
use crate::linalg::symmetric_product;
use crate::linalg::tree_solve::TreeSolve;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::solvers::Solve;
use faer::reborrow::{Reborrow, ReborrowMut};
use faer::sparse::linalg::LltError;
use faer::sparse::linalg::cholesky::{
    LltRef, SymbolicCholesky, SymbolicCholeskyRaw, SymmetricOrdering, factorize_symbolic_cholesky,
};
use faer::sparse::{SparseColMat, Triplet};
use faer::{Mat, MatMut, MatRef, Par, Side};
use std::borrow::Cow;

pub type Sparse = SparseColMat<usize, f64>;

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

/// C + sign * A X, each entry accumulated in double-double (Ogita-Rump-Oishi Dot2: exact products
/// by FMA, error-free sums) and rounded once. Stiffness matrices of slender parts multiply static
/// shapes into reactions that are 1e-6 of the terms summed; plain sums would lose those digits.
///
/// The residual of every refined solve is one of these, so it is made fast: columns go in groups
/// of at most `GROUP` (A is read once per group, the group's sums of one row side by side, a
/// fixed width the compiler unrolls into vector instructions), as many groups as it takes to
/// give every thread one (26 columns on two threads: four of 7, 7, 6, 6, not 8, 8, 8, 2), groups
/// on rayon's threads, and the product's rounding error is one FMA instruction where the CPU has
/// it.
pub fn mul_compensated(c: Option<MatRef<'_, f64>>, sign: f64, a: &Sparse, x: MatRef<'_, f64>) -> Mat<f64> {
    use rayon::prelude::*;
    let (n, k) = (a.nrows(), x.ncols());
    let mut out = Mat::<f64>::zeros(n, k);
    if k == 0 {
        return out;
    }
    let threads = rayon::current_num_threads().max(1);
    let count = k.div_ceil(GROUP).next_multiple_of(threads).min(k);
    let groups: Vec<(usize, usize)> = (0..count).map(|g| (g * k / count, (g + 1) * k / count)).collect();
    let columns: Vec<Mat<f64>> = groups
        .par_iter()
        .map(|&(first, end)| {
            let c = c.map(|c| c.subcols(first, end - first));
            compensated_group(c, sign, a, x.subcols(first, end - first))
        })
        .collect();
    for (&(first, _), group) in groups.iter().zip(&columns) {
        out.as_mut().subcols_mut(first, group.ncols()).copy_from(group);
    }
    out
}

/// Most columns summed side by side: enough to amortise reading A, few enough for the running
/// sums of a row to stay in one cache line pair.
const GROUP: usize = 8;

/// A group of at most `GROUP` columns, at the narrowest fixed width that holds it.
fn compensated_group(c: Option<MatRef<'_, f64>>, sign: f64, a: &Sparse, x: MatRef<'_, f64>) -> Mat<f64> {
    match x.ncols() {
        0..=1 => compensated_width::<1>(c, sign, a, x),
        2 => compensated_width::<2>(c, sign, a, x),
        3..=4 => compensated_width::<4>(c, sign, a, x),
        _ => compensated_width::<GROUP>(c, sign, a, x),
    }
}

fn compensated_width<const W: usize>(
    c: Option<MatRef<'_, f64>>,
    sign: f64,
    a: &Sparse,
    x: MatRef<'_, f64>,
) -> Mat<f64> {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("fma") {
        // SAFETY: the CPU has the FMA instructions the function is compiled for
        return unsafe { compensated_fma::<W>(c, sign, a, x) };
    }
    compensated_generic::<false, W>(c, sign, a, x)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "fma")]
unsafe fn compensated_fma<const W: usize>(
    c: Option<MatRef<'_, f64>>,
    sign: f64,
    a: &Sparse,
    x: MatRef<'_, f64>,
) -> Mat<f64> {
    compensated_generic::<true, W>(c, sign, a, x)
}

/// `x` has at most W columns; the rest of the width is zero.
#[inline(always)]
fn compensated_generic<const FMA: bool, const W: usize>(
    c: Option<MatRef<'_, f64>>,
    sign: f64,
    a: &Sparse,
    x: MatRef<'_, f64>,
) -> Mat<f64> {
    let (n, w) = (a.nrows(), x.ncols());
    let col_ptr = a.symbolic().col_ptr();
    let row_idx = a.symbolic().row_idx();
    let val = a.val();
    // running sums row-major: row i's W sums side by side
    let mut hi = vec![[0.0; W]; n];
    let mut lo = vec![[0.0; W]; n];
    if let Some(c) = c {
        for col in 0..w {
            for (i, h) in hi.iter_mut().enumerate() {
                h[col] = c[(i, col)];
            }
        }
    }
    let mut xj = [0.0; W];
    for j in 0..a.ncols() {
        let mut any = false;
        for col in 0..w {
            xj[col] = sign * x[(j, col)];
            any |= xj[col] != 0.0;
        }
        if !any {
            continue;
        }
        for p in col_ptr[j]..col_ptr[j + 1] {
            let i = row_idx[p];
            let aij = val[p];
            let (hi, lo) = (&mut hi[i], &mut lo[i]);
            for col in 0..W {
                add_product::<FMA>(&mut hi[col], &mut lo[col], aij, xj[col]);
            }
        }
    }
    Mat::from_fn(n, w, |i, col| hi[i][col] + lo[i][col])
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

/// Sparse Cholesky of a symmetric positive definite matrix, in METIS's nested-dissection order
/// (AMD where METIS cannot take the matrix), factored on every core faer's global parallelism
/// allows. The symbolic factorisation comes first, so the factor's size is known (and in the
/// build profile) before its memory is taken.
pub struct SpdSolver<'m> {
    engine: Engine,
    /// The factored matrix, for the refinement's residuals: borrowed where the model keeps it
    /// anyway (the mounted body's stiffness: one copy of 0.3 GB at 249k DoFs, not two).
    matrix: Cow<'m, Sparse>,
}

/// Where the factor lives.
enum Engine {
    InProcess {
        symbolic: SymbolicCholesky<usize>,
        values: Vec<f64>,
        /// The factor's elimination tree split between the threads, where it splits.
        tree: Option<TreeSolve>,
    },
    /// MUMPS's, across the MPI ranks of the PETSc back-end.
    Distributed(Session),
}

/// The symbolic Cholesky factorisation of `a` in METIS's nested-dissection order, or in AMD's
/// where METIS refuses the graph. One METIS run at a time: it draws its random numbers from the
/// C library's one generator, and two side by side (two seeds, to keep the better order) gave
/// orders that changed from run to run.
fn symbolic_factor(a: &Sparse, what: &str) -> Result<SymbolicCholesky<usize>> {
    let order = ordering::nested_dissection(a.symbolic());
    let perm = order.as_ref().map(|o| faer::perm::PermRef::new_checked(&o.forward, &o.inverse, a.nrows()));
    let ordering = match perm {
        Some(p) => SymmetricOrdering::Custom(p),
        None => SymmetricOrdering::Amd,
    };
    let by = if order.is_some() { "METIS nested dissection" } else { "AMD (METIS refused the graph)" };
    crate::profile::note(|| format!("{by}, n {}, nnz(A) {}", a.nrows(), a.compute_nnz()));
    factorize_symbolic_cholesky(a.symbolic(), Side::Lower, ordering, Default::default())
        .map_err(|e| BuildError::Numerical(format!("{what}: its factor {}", faer_error::generic(&e))))
}

/// Bytes of one stored factor entry and its share of the row indices (supernodal storage keeps
/// one index per row of a supernode, a small fraction of the values): for the size estimate.
const FACTOR_BYTES_PER_ENTRY: f64 = 8.0;

impl<'m> SpdSolver<'m> {
    /// Factor `a` on the reduction's back-end: in this process (`new`), or distributed by PETSc
    /// (`distributed::Session`), which reports a factorisation that fails with its reason.
    pub fn on(backend: &Backend, a: Cow<'m, Sparse>, what: &str, dof: &dyn Fn(usize) -> String) -> Result<Self> {
        match backend {
            Backend::InProcess => Self::new(a, what, dof),
            Backend::Petsc(petsc) => {
                let session = Session::start(petsc, &a, what)?;
                Ok(Self { engine: Engine::Distributed(session), matrix: a })
            }
        }
    }

    /// The distributed back-end's session, if the factor is there.
    pub fn session(&self) -> Option<&Session> {
        match &self.engine {
            Engine::Distributed(s) => Some(s),
            Engine::InProcess { .. } => None,
        }
    }

    /// A solve of the distributed back-end that failed (its solves cannot return errors
    /// through `SpdSolve`: they fill the result with NaN and keep the reason for this check).
    pub fn health(&self) -> Result<()> {
        self.session().map_or(Ok(()), Session::health)
    }

    /// Factor `a` (both triangles stored); `dof` names a row of `a` for the message when the
    /// factorisation meets a pivot that is not positive (where the mechanism is).
    pub fn new(a: Cow<'m, Sparse>, what: &str, dof: &dyn Fn(usize) -> String) -> Result<Self> {
        let symbolic = crate::profile::phase(format!("ordering: {what}"), || symbolic_factor(&a, what))?;
        let entries = symbolic.len_val();
        let mut values = zeroed(entries).ok_or_else(|| {
            BuildError::Numerical(format!(
                "{what}: its Cholesky factor needs {:.1} GiB, more than this machine can give; coarsen the mesh",
                entries as f64 * FACTOR_BYTES_PER_ENTRY / (1u64 << 30) as f64
            ))
        })?;
        huge_pages(&mut values);
        let par = faer::get_global_parallelism();
        let outcome = crate::profile::phase(format!("Cholesky factorisation: {what}"), || {
            crate::profile::note(|| {
                format!(
                    "n {}, nnz(A) {}, nnz(L) {entries} ({:.0} MiB, known before factoring)",
                    a.nrows(),
                    a.compute_nnz(),
                    entries as f64 * FACTOR_BYTES_PER_ENTRY / (1u64 << 20) as f64,
                )
            });
            // the factor's pages touched first by every thread at once: the first touch of a page
            // is slow on this (virtual) machine, 1.27 GB took 3 s from one thread, and faer's
            // factorisation touches them one supernode at a time (factorisation with the touch
            // 5.7-7.3 s -> 4.0-4.4 s, the 249k-DoF bracket)
            {
                use rayon::prelude::*;
                values.par_chunks_mut(1 << 18).for_each(|c| c.fill(0.0));
            }
            let mut scratch =
                MemBuffer::try_new(symbolic.factorize_numeric_llt_scratch::<f64>(par, Default::default()))
                    .map_err(|_| LltError::Generic(faer::sparse::FaerError::OutOfMemory))?;
            symbolic
                .factorize_numeric_llt::<f64>(
                    &mut values,
                    (*a).as_ref(),
                    Side::Lower,
                    Default::default(),
                    par,
                    MemStack::new(&mut scratch),
                    Default::default(),
                )
                .map(|_| ())
                .map_err(LltError::Numeric)
        });
        match outcome {
            Ok(()) => {
                let tree = TreeSolve::new(&symbolic, rayon::current_num_threads());
                Ok(Self { engine: Engine::InProcess { symbolic, values, tree }, matrix: a })
            }
            Err(e) => {
                let mut message = format!("{what} is {}", faer_error::llt(&e));
                if let LltError::Numeric(faer::linalg::cholesky::llt::factor::LltError::NonPositivePivot { index }) = e
                    && let Some(row) = pivot_row(&symbolic, index)
                {
                    message.push_str(&format!("; the factorisation fails at {}", dof(row)));
                }
                Err(BuildError::Numerical(message))
            }
        }
    }

    /// The factored matrix.
    pub fn matrix(&self) -> &Sparse {
        &self.matrix
    }

    /// Entries of the Cholesky factor (all ranks' for a distributed one).
    pub fn factor_entries(&self) -> usize {
        match &self.engine {
            Engine::InProcess { values, .. } => values.len(),
            Engine::Distributed(s) => s.started.factor_entries as usize,
        }
    }

    /// Solve in place: the elimination tree split between the threads (`tree_solve`) where it
    /// splits, else as `solve_whole_tree`; on the distributed back-end, by its factor.
    pub fn solve_in_place(&self, rhs: MatMut<'_, f64>) {
        match &self.engine {
            Engine::InProcess { symbolic, values, tree: Some(tree) } => tree.solve(symbolic, values, rhs),
            Engine::InProcess { tree: None, .. } => self.solve_whole_tree(rhs),
            Engine::Distributed(s) => s.solve_or_nan(rhs),
        }
    }

    /// The symbolic factorisation and the factor's values, of an in-process factor.
    pub fn factor(&self) -> Option<(&SymbolicCholesky<usize>, &[f64])> {
        match &self.engine {
            Engine::InProcess { symbolic, values, .. } => Some((symbolic, values)),
            Engine::Distributed(_) => None,
        }
    }

    /// Solve in place through faer's solve. Two or more right-hand sides are split between two
    /// threads, each solving its half through the whole factor: a solve streams the factor from
    /// memory with little arithmetic per entry, which faer's parallel dense kernels inside the
    /// supernodes cannot spread over the cores, and one core does not draw the memory's whole
    /// bandwidth (249k-DoF bracket, 1.2 GB factor: 33 right-hand sides 1.2 s -> 0.6 s, 5:
    /// 0.40 s -> 0.30 s).
    pub fn solve_whole_tree(&self, rhs: MatMut<'_, f64>) {
        let nc = rhs.ncols();
        if nc >= 2 && rayon::current_num_threads() >= 2 {
            let (a, b) = rhs.split_at_col_mut(nc.div_ceil(2));
            rayon::join(|| self.solve_with(a, Par::Seq), || self.solve_with(b, Par::Seq));
        } else {
            self.solve_with(rhs, faer::get_global_parallelism());
        }
    }

    fn solve_with(&self, rhs: MatMut<'_, f64>, par: Par) {
        let (symbolic, values) = match &self.engine {
            Engine::InProcess { symbolic, values, .. } => (symbolic, values),
            Engine::Distributed(s) => return s.solve_or_nan(rhs),
        };
        let mut scratch = MemBuffer::new(symbolic.solve_in_place_scratch::<f64>(rhs.ncols(), par));
        LltRef::<'_, usize, f64>::new(symbolic, values).solve_in_place_with_conj(
            faer::Conj::No,
            rhs,
            par,
            MemStack::new(&mut scratch),
        );
    }
}

/// A refinement correction below this (relative, per column) leaves the next one at round-off:
/// the refinement stops there.
const SETTLED: f64 = 1e-8;

/// Solves with a symmetric positive definite matrix, as the eigen-solver and the static shapes
/// need them: the factored matrix itself (`SpdSolver`) or a part of it (`held::HeldSolver`).
pub trait SpdSolve {
    /// Rows of the matrix solved with.
    fn n(&self) -> usize;

    /// One solve through the factor, without refinement.
    fn solve_plain(&self, rhs: MatMut<'_, f64>);

    /// b - A x in place of b, every entry summed in double-double
    /// (`symmetric_product::subtract_compensated`): what iterative refinement corrects with.
    fn residual(&self, b: MatMut<'_, f64>, x: MatRef<'_, f64>);

    /// Solve, then `steps` rounds of iterative refinement on residuals computed in
    /// double-double: static shapes of slender parts lose digits to the stiffness's condition
    /// number (~1e10), and the flange compliance must be exact to round-off; an
    /// extended-precision residual restores them. Returns the last correction's size relative
    /// to the solution (max norms; 0 without refinement): how far a plain solve is off.
    fn solve_refined_steps(&self, mut rhs: MatMut<'_, f64>, steps: usize) -> f64 {
        if steps == 0 {
            self.solve_plain(rhs);
            return 0.0;
        }
        let b = rhs.to_owned();
        self.solve_plain(rhs.rb_mut());
        let mut correction = 0.0;
        for _ in 0..steps {
            let mut r = b.clone();
            self.residual(r.as_mut(), rhs.rb());
            self.solve_plain(r.as_mut());
            correction = r.norm_max() / rhs.norm_max();
            // the worst column's correction relative to that column (stiff directions' static
            // shapes are 1e-9 of the others)
            let mut worst_column = 0.0f64;
            for j in 0..r.ncols() {
                worst_column = worst_column.max(r.col(j).norm_max() / rhs.rb().col(j).norm_max());
                for i in 0..r.nrows() {
                    rhs[(i, j)] += r[(i, j)];
                }
            }
            // refinement contracts the error by about the size of the correction it made: after
            // one below SETTLED the next would change the solution below round-off (the
            // 249k-DoF bracket's flange shapes: 1e-12, one solve and product saved)
            if worst_column < SETTLED {
                break;
            }
        }
        correction
    }

    fn solve_refined(&self, rhs: MatMut<'_, f64>) {
        self.solve_refined_steps(rhs, 2);
    }

    /// The distributed back-end's session behind these solves, if they run there: a solve
    /// that fails there leaves NaN and its reason with the session (`Session::health`).
    fn distributed_session(&self) -> Option<&Session> {
        None
    }
}

impl SpdSolve for SpdSolver<'_> {
    fn n(&self) -> usize {
        self.matrix.nrows()
    }

    fn solve_plain(&self, rhs: MatMut<'_, f64>) {
        self.solve_in_place(rhs);
    }

    fn residual(&self, b: MatMut<'_, f64>, x: MatRef<'_, f64>) {
        symmetric_product::subtract_compensated(b, &self.matrix, x);
    }

    fn distributed_session(&self) -> Option<&Session> {
        self.session()
    }
}

/// `n` zeros from the allocator's zeroed memory: fresh pages from the system, touched only when
/// first written, on all threads together (`SpdSolver::new`), not by one thread's fill here.
fn zeroed(n: usize) -> Option<Vec<f64>> {
    if n == 0 {
        return Some(Vec::new());
    }
    let layout = std::alloc::Layout::array::<f64>(n).ok()?;
    // SAFETY: the layout has a non-zero size; a null pointer is handled, and a non-null one
    // holds n zeroed f64 (all-zero bits are 0.0) allocated by the global allocator with exactly
    // the layout Vec<f64> of capacity n frees it with
    unsafe {
        let ptr = std::alloc::alloc_zeroed(layout).cast::<f64>();
        if ptr.is_null() {
            return None;
        }
        Some(Vec::from_raw_parts(ptr, n, n))
    }
}

/// Ask the kernel to back `buffer` (not yet touched) with 2 MB pages where it can, so that its
/// first touch faults in fewer, larger pages. Transparent huge pages are commonly enabled for
/// those who ask (`madvise`); elsewhere this changes nothing.
fn huge_pages<T>(buffer: &mut [T]) {
    #[cfg(target_os = "linux")]
    {
        const HUGE: usize = 2 << 20;
        let start = buffer.as_mut_ptr() as usize;
        let end = start + std::mem::size_of_val(buffer);
        let first = start.next_multiple_of(HUGE);
        let last = end - end % HUGE;
        if last > first {
            // SAFETY: the range lies within `buffer`'s allocation, and the advice changes only
            // how the kernel backs its pages, not their contents or validity
            unsafe {
                libc::madvise(first as *mut libc::c_void, last - first, libc::MADV_HUGEPAGE);
            }
        }
    }
}

/// The row of the matrix (in its own order) where a factorisation with `symbolic` met the
/// non-positive pivot faer reports as `index` (in the factor's order).
fn pivot_row(symbolic: &SymbolicCholesky<usize>, index: usize) -> Option<usize> {
    // faer 0.24 counts the simplicial pivot from 1 (k + 1) and the supernodal one from 0
    let position = match symbolic.raw() {
        SymbolicCholeskyRaw::Simplicial(_) => index.checked_sub(1)?,
        SymbolicCholeskyRaw::Supernodal(_) => index,
    };
    // the fill-reducing order's forward array names the matrix row eliminated at each position
    match symbolic.perm() {
        Some(p) => p.arrays().0.get(position).copied(),
        None => Some(position),
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
        let failure = |a| match super::SpdSolver::new(std::borrow::Cow::Owned(a), "test", &|d| format!("row {d}.")) {
            Ok(_) => "factored".to_string(),
            Err(e) => e.to_string(),
        };
        assert!(failure(chain(Some(37))).contains("fails at row 37."), "{}", failure(chain(Some(37))));
        assert_eq!(failure(chain(None)), "factored");
        // a 3D grid (supernodal factor, reordered): every principal block without the bad row is
        // diagonally dominant, so the failure is that row whatever the order
        let grid = crate::linalg::test_grids::laplacian(12, |i| if i == 1000 { -100.0 } else { 7.0 });
        assert!(failure(grid.clone()).contains("fails at row 1000."), "{}", failure(grid));
    }

    /// A symmetric matrix with an irregular pattern: entry (i, j) where (i * j + i + j) % 7 < 2.
    fn symmetric(n: usize) -> super::Sparse {
        use faer::sparse::{SparseColMat, Triplet};
        let mut t = Vec::new();
        for i in 0..n {
            for j in 0..=i {
                if i == j || (i * j + i + j) % 7 < 2 {
                    let v = ((i * 13 + j * 31) % 17) as f64 / 7.0 - 1.1 + if i == j { 5.0 } else { 0.0 };
                    t.push(Triplet::new(i, j, v));
                    if i != j {
                        t.push(Triplet::new(j, i, v));
                    }
                }
            }
        }
        SparseColMat::try_new_from_triplets(n, n, &t).unwrap()
    }

    /// `symmetric_product`'s gather form against the general scatter products on every group width (1 to 37 columns,
    /// with and without C, both signs): the plain sums differ only in their order (round-off of
    /// 1e-15 relative), the compensated ones are exact to the last bit in both (double-double
    /// sums rounded once).
    #[test]
    fn gather_products_equal_the_general_ones() {
        use crate::linalg::symmetric_product;
        use faer::Mat;
        let n = 90;
        let a = symmetric(n);
        for k in [1, 2, 3, 5, 8, 9, 16, 17, 26, 37] {
            let x = Mat::<f64>::from_fn(n, k, |i, j| ((i * 3 + j * 11) % 23) as f64 / 3.0 - 3.3);
            let c = Mat::<f64>::from_fn(n, k, |i, j| (i as f64 - j as f64) / 9.0);
            let plain = symmetric_product::mul_new(&a, x.as_ref());
            let general = super::mul_new(&a, x.as_ref());
            assert_eq!((plain.nrows(), plain.ncols()), (general.nrows(), general.ncols()));
            let scale = general.norm_max();
            assert!((&plain - &general).norm_max() <= 1e-14 * scale, "{k} columns");
            for (sign, cc) in [(1.0, None), (-1.0, Some(c.as_ref()))] {
                let fast = symmetric_product::mul_compensated(cc, sign, &a, x.as_ref());
                let general = super::mul_compensated(cc, sign, &a, x.as_ref());
                assert_eq!((fast.nrows(), fast.ncols()), (general.nrows(), general.ncols()));
                for j in 0..k {
                    for i in 0..n {
                        // both exact to double-double before one rounding: equal unless the exact
                        // sum lies within 1e-32 of a rounding boundary (none does here)
                        assert_eq!(fast[(i, j)].to_bits(), general[(i, j)].to_bits(), "({i}, {j}) of {k}");
                    }
                }
            }
        }
    }

    /// On a 3D grid (a supernodal factor in nested-dissection order) the split solve equals
    /// faer's own solve through the same factor to round-off, for one and for many right-hand
    /// sides, and its solution satisfies A x = b (consistency with faer's solve and with the
    /// matrix itself; the physics of the solves is checked against CalculiX in the Python tests).
    #[test]
    fn split_solves_equal_the_whole_tree_solve() {
        use super::SpdSolver;
        use crate::linalg::tree_solve::TreeSolve;
        use faer::Mat;
        let a = crate::linalg::test_grids::laplacian(16, |i| 6.0 + 1e-3 * (i % 7) as f64);
        let n = a.nrows();
        let name = |d: usize| format!("row {d}");
        let solver = SpdSolver::new(std::borrow::Cow::Borrowed(&a), "grid", &name).unwrap();
        let (symbolic, values) = solver.factor().unwrap();
        let tree = TreeSolve::new(symbolic, 2).expect("a grid's tree splits between two threads");
        let parts = tree.subtrees_per_thread();
        assert_eq!(parts.len(), 2);
        assert!(parts.iter().all(|&p| p > 0), "both threads get subtrees");
        for k in [1, 9, 46] {
            let b = Mat::<f64>::from_fn(n, k, |i, j| ((i * 7 + 3 * j) % 11) as f64 - 5.0);
            let mut split = b.clone();
            tree.solve(symbolic, values, split.as_mut());
            let mut whole = b.clone();
            solver.solve_whole_tree(whole.as_mut());
            assert_eq!((split.nrows(), split.ncols()), (whole.nrows(), whole.ncols()));
            let scale = whole.norm_max();
            // the same arithmetic in another order: round-off (measured 1e-16 of the solution)
            assert!((&split - &whole).norm_max() <= 1e-13 * scale, "{k} right-hand sides");
            let residual = &b - crate::linalg::symmetric_product::mul_new(&a, split.as_ref());
            assert!(residual.norm_max() <= 1e-12 * b.norm_max(), "A x = b for {k} right-hand sides");
        }
    }

    /// The compensated product in groups, on threads and with FMA equals the plain Dekker route
    /// bit for bit (both form the exact product errors), and recovers a sum that cancels to 1
    /// out of terms of 1e16, which plain double sums lose entirely.
    #[test]
    fn compensated_product_is_exact_in_every_route() {
        use faer::Mat;
        use faer::sparse::{SparseColMat, Triplet};
        let n = 40;
        let mut t = Vec::new();
        for i in 0..n {
            for j in 0..n {
                if (i * 7 + j * 3) % 5 == 0 {
                    t.push(Triplet::new(i, j, ((i * 13 + j * 31) % 17) as f64 / 7.0 - 1.1));
                }
            }
        }
        let a = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &t).unwrap();
        let x = Mat::<f64>::from_fn(n, 19, |i, j| ((i * 3 + j * 11) % 23) as f64 / 3.0 - 3.3);
        let c = Mat::<f64>::from_fn(n, 19, |i, j| (i as f64 - j as f64) / 9.0);
        let fast = super::mul_compensated(Some(c.as_ref()), -1.0, &a, x.as_ref());
        assert_eq!((fast.nrows(), fast.ncols()), (n, 19));
        // every column on its own, width 1 without FMA: the grouping and the vector width change
        // nothing
        for first in 0..19 {
            let w = 1;
            let plain = super::compensated_generic::<false, 1>(
                Some(c.as_ref().subcols(first, w)),
                -1.0,
                &a,
                x.as_ref().subcols(first, w),
            );
            for j in 0..w {
                for i in 0..n {
                    assert_eq!(fast[(i, first + j)].to_bits(), plain[(i, j)].to_bits());
                }
            }
        }
        let row = SparseColMat::<usize, f64>::try_new_from_triplets(
            1,
            3,
            &[Triplet::new(0, 0, 1e16), Triplet::new(0, 1, 1.0), Triplet::new(0, 2, -1e16)],
        )
        .unwrap();
        let ones = Mat::<f64>::from_fn(3, 1, |_, _| 1.0);
        assert_eq!(super::mul_compensated(None, 1.0, &row, ones.as_ref())[(0, 0)], 1.0);
    }
}
