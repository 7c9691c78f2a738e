//! The sparse Cholesky solver: symbolic factorisation first, then the numeric one on every core.

use super::{Sparse, SpdSolve};
use crate::error::{LinalgError, Result};
use crate::faer_error;
use crate::first_touch;
use crate::ordering;
use crate::symmetric_product;
use crate::tree_solve::TreeSolve;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::linalg::LltError;
use faer::sparse::linalg::cholesky::{
    LltRef, SymbolicCholesky, SymbolicCholeskyRaw, SymmetricOrdering, factorize_symbolic_cholesky,
};
use faer::{MatMut, MatRef, Par, Side};
use petsc_backend::Backend;
use petsc_backend::session::Session;
use std::borrow::Cow;

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
    phases::note(|| format!("{by}, n {}, nnz(A) {}", a.nrows(), a.compute_nnz()));
    factorize_symbolic_cholesky(a.symbolic(), Side::Lower, ordering, Default::default())
        .map_err(|e| LinalgError::too_large(format!("{what}: its factor {}", faer_error::generic(&e))).caused_by(e))
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
        self.session().map_or(Ok(()), |s| Ok(s.health()?))
    }

    /// Factor `a` (both triangles stored); `dof` names a row of `a` for the message when the
    /// factorisation meets a pivot that is not positive (where the mechanism is).
    pub fn new(a: Cow<'m, Sparse>, what: &str, dof: &dyn Fn(usize) -> String) -> Result<Self> {
        let symbolic = phases::phase(format!("ordering: {what}"), || symbolic_factor(&a, what))?;
        let entries = symbolic.len_val();
        let mut values = zeroed(entries).ok_or_else(|| {
            LinalgError::too_large(format!(
                "{what}: its Cholesky factor needs {:.1} GiB, more than this machine can give; coarsen the mesh",
                entries as f64 * FACTOR_BYTES_PER_ENTRY / (1u64 << 30) as f64
            ))
        })?;
        huge_pages(&mut values);
        let par = faer::get_global_parallelism();
        let outcome = phases::phase(format!("Cholesky factorisation: {what}"), || {
            phases::note(|| {
                format!(
                    "n {}, nnz(A) {}, nnz(L) {entries} ({:.0} MiB, known before factoring)",
                    a.nrows(),
                    a.compute_nnz(),
                    entries as f64 * FACTOR_BYTES_PER_ENTRY / (1u64 << 20) as f64,
                )
            });
            // the factor's pages touched first by every thread at once (`first_touch`): faer's
            // factorisation touches them one supernode at a time (factorisation with the touch
            // 5.7-7.3 s -> 4.0-4.4 s, the 249k-DoF bracket)
            first_touch::touch_zeroed(&mut values);
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
                Err(LinalgError::singular(message).caused_by(e))
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
