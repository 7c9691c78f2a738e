//! Craig-Bampton's two eigenproblems (the mounted body's modes and the held problem's) from one
//! block Krylov space.

use super::block_lanczos::{BlockLanczos, block_size, column_dots, start_block};
use super::checks::{checked, worst_of};
use super::clock::Clock;
use super::{Eigenpairs, RESIDUAL_TOL, SHARED_MAX_MODES, distributed_health, lowest};
use crate::error::{LinalgError, Result};
use crate::held::{HeldSolver, WholeAndHeld};
use crate::sparse::{Sparse, SpdSolve};
use crate::symmetric_product::mul_new;
use faer::Mat;

/// The mounted body's `count` lowest modes and, from the same block Krylov space, the `held`
/// problem's `count_held` lowest (the rows from `held.n()` on fixed, `m_held` its mass): what
/// Craig-Bampton (fixed-interface modes) and the accuracy comparison (the full model's modes)
/// each solved for on their own, 16 and 19 block solves on a 249k-DoF bracket. The held
/// operator differs from the whole one by the rank-h correction through G = K^-1 E, so with G in
/// the start block the space holds the held problem's Krylov space too (`ritz_held`). Both sets
/// are checked as a search of their own checks them: Rayleigh quotients, measured residuals.
pub fn lowest_and_held(
    k: &dyn SpdSolve,
    m: &Sparse,
    count: usize,
    held: &HeldSolver<'_>,
    count_held: usize,
    tol: f64,
) -> Result<(Eigenpairs, Eigenpairs)> {
    let n = k.n();
    let first = held.n();
    let g = held.unit_shapes();
    let h = g.ncols();
    let (count, count_held) = (count.min(n), count_held.min(first));
    let wanted = count.max(count_held);
    let separate =
        || -> Result<(Eigenpairs, Eigenpairs)> { Ok((lowest(k, m, count, tol)?, lowest(held, m, count_held, tol)?)) };
    if count == 0 || count_held == 0 || h == 0 || 4 * (wanted + h) > n || wanted > SHARED_MAX_MODES {
        // nothing to share, a problem too small for it, or too many modes: each on its own
        return separate();
    }
    let shared = phases::phase("eigen-solve (block shift-invert Lanczos)", || {
        SharedSearch::new(k, m, held, count, count_held)?.run(tol)
    });
    distributed_health(k)?;
    match shared? {
        Some(pairs) => Ok(pairs),
        None => separate(),
    }
}

/// The pairs' vectors restricted to their first `rows` rows.
fn free_rows(pairs: Eigenpairs, rows: usize) -> Eigenpairs {
    Eigenpairs { vectors: pairs.vectors.subrows(0, rows).to_owned(), values: pairs.values }
}

/// A search of both problems in one space, and what it keeps between its attempts.
struct SharedSearch<'a, 'h> {
    k: &'a dyn SpdSolve,
    m: &'a Sparse,
    held: &'a HeldSolver<'h>,
    /// M G: the held projection subtracts the unit-load responses' part through it.
    m_g: Mat<f64>,
    start: Mat<f64>,
    /// The first held row: the free rows come before it.
    first: usize,
    count: usize,
    count_held: usize,
    /// Columns per block.
    pt: usize,
    max_dim: usize,
    shared_limit: usize,
    first_check: usize,
}

/// A space grown until its Ritz pairs were estimated converged (or could grow no more).
struct Grown {
    /// The whole problem's Ritz values, then the held problem's, and their coordinates in the
    /// space, side by side.
    values: Vec<f64>,
    coordinates: Mat<f64>,
    count_whole: usize,
    estimated: bool,
    at_limit: bool,
    refine: usize,
    solves: usize,
    dim: usize,
}

impl<'a, 'h> SharedSearch<'a, 'h> {
    fn new(
        k: &'a dyn SpdSolve,
        m: &'a Sparse,
        held: &'a HeldSolver<'h>,
        count: usize,
        count_held: usize,
    ) -> Result<Self> {
        let n = k.n();
        let g = held.unit_shapes();
        let h = g.ncols();
        let wanted = count.max(count_held);
        // half a search's own random columns: the unit-load responses fill the block (26 and 20
        // modes of the 249k-DoF bracket: 3 + 6 columns, 14 block solves, 126 vectors, 15.2 s;
        // 7 + 6: 12 solves, 156 vectors, 15.3 s and 30 MB more per 1e5 DoFs)
        let p = (block_size(wanted) / 2).max(2);
        // start: pseudo-random columns and the held DoFs' unit-load responses, each of unit
        // M-norm (the responses of stiff directions are 1e-9 of the rest)
        let mut start = start_block(n, p + h);
        let m_g = mul_new(m, g.as_ref());
        for (j, norm) in column_dots(g, &m_g).into_iter().enumerate() {
            if !(norm > 0.0) {
                return Err(LinalgError::inconsistent("eigensolver: a held DoF's unit-load response has no mass"));
            }
            let norm = norm.sqrt();
            for i in 0..n {
                start[(i, p + j)] = g[(i, j)] / norm;
            }
        }
        let pt = p + h;
        let max_dim = (10 * wanted + 200).max(wanted + 2 * pt).min(n);
        // where separate searches would have converged long since (the bracket: 4.8 vectors per
        // mode), a shared one that has not is stalled by its held projection's round-off (it
        // subtracts G's part, large beside the highest modes' 1/lambda): separate searches then
        let shared_limit = (6 * wanted + 4 * pt).min(max_dim);
        let first_check = 2 * wanted + 2 * pt;
        Ok(Self { k, m, held, m_g, start, first: held.n(), count, count_held, pt, max_dim, shared_limit, first_check })
    }

    /// Both sets of pairs, checked; None where the shared space stalled (separate searches then).
    fn run(&self, tol: f64) -> Result<Option<(Eigenpairs, Eigenpairs)>> {
        let (count, count_held, pt) = (self.count, self.count_held, self.pt);
        let mut adaptive = true;
        let mut estimate_tol = tol;
        let mut clock = Clock::default();
        loop {
            // the space is dropped before the pairs are checked (its memory is what the check's
            // products need), so a check that fails starts a new space: refined solves if the
            // plain ones were used, else a tighter estimate
            let mut lanczos = BlockLanczos::new(self.m, &self.start, None, adaptive, self.max_dim)?;
            let Some(Grown { values, coordinates, count_whole, estimated, at_limit, refine, solves, dim }) =
                self.grow(&mut lanczos, estimate_tol)?
            else {
                return Ok(None);
            };
            clock.add(&lanczos.clock);
            // the vectors take the space's place (its memory is what the check's products need)
            let vectors = clock.time(|c| &mut c.ritz, || lanczos.into_vectors(&coordinates));
            let both = Eigenpairs { vectors, values };
            // one refined solve checks both: the held columns through the held solver
            let (both, worst) = clock.time(
                |c| &mut c.checks,
                || checked(&WholeAndHeld { held: self.held, whole: count_whole }, self.m, both, 0.0, refine > 0),
            );
            let (worst_whole, at_whole) = worst[..count_whole].iter().enumerate().fold((0.0f64, 0), worst_of);
            let (worst_held, at_held) = worst[count_whole..].iter().enumerate().fold((0.0f64, 0), worst_of);
            let (whole, held_pairs) = whole_and_held(both, count_whole);
            let converged = estimated
                && worst_whole <= RESIDUAL_TOL
                && worst_held <= RESIDUAL_TOL
                && whole.values.len() == count
                && held_pairs.values.len() == count_held;
            if !converged && (refine == 0 || !at_limit) {
                let worst = worst_whole.max(worst_held);
                let how = if refine > 0 { "a tighter estimate" } else { "every solve refined" };
                phases::note(|| format!("{dim} vectors left a residual of {worst:.1e}: again with {how}"));
                if refine > 0 {
                    estimate_tol *= 1e-2;
                } else {
                    estimate_tol = tol;
                }
                adaptive = false;
                continue;
            }
            phases::note(|| {
                format!(
                    "{count} modes of the whole and {count_held} held, in one space: {solves} block solves of {pt} ({dim} Lanczos vectors); {}",
                    clock.describe()
                )
            });
            if !converged {
                let (worst, at, which) =
                    if worst_held > worst_whole { (worst_held, at_held, "held ") } else { (worst_whole, at_whole, "") };
                let n = self.k.n();
                return Err(LinalgError::not_converged(format!(
                    "eigensolver: {count} modes and {count_held} held modes did not converge with {dim} Lanczos vectors (of {n} DoFs): {which}mode {} has the residual {worst:.1e} (accepted {RESIDUAL_TOL:.0e}); request fewer modes (reduction.modes) or check the mesh for extreme element proportions",
                    at + 1
                )));
            }
            return Ok(Some((whole, free_rows(held_pairs, self.first))));
        }
    }

    /// Block solves until both sets' Ritz pairs are estimated converged or the space can grow no
    /// more; None where it stalled short of that.
    fn grow(&self, lanczos: &mut BlockLanczos<'_>, estimate_tol: f64) -> Result<Option<Grown>> {
        let mut next_check = self.first_check;
        loop {
            let exhausted = !lanczos.extend(self.k)?;
            // a block the distributed back-end failed to solve ends the search at once
            distributed_health(self.k)?;
            let dim = lanczos.dim();
            if dim < next_check && !exhausted && dim < self.max_dim {
                continue;
            }
            next_check = dim + dim.div_ceil(7);
            let began = std::time::Instant::now();
            let (values, y, whole_estimated) = lanczos.ritz(self.count, estimate_tol, exhausted)?;
            let (held_values, held_y, held_estimated) =
                lanczos.ritz_held(self.first, &self.m_g, self.held, self.count_held, estimate_tol, exhausted)?;
            lanczos.clock.ritz += began.elapsed();
            let estimated = whole_estimated && held_estimated;
            if !estimated && !exhausted && dim >= self.shared_limit {
                phases::note(|| format!("no shared convergence with {dim} vectors: separate searches"));
                return Ok(None);
            }
            let at_limit = exhausted || dim >= self.max_dim;
            if !estimated && !at_limit {
                continue;
            }
            // both sets' vectors side by side, checked together (the held pairs' vanish at the
            // held rows, to round-off)
            let mut coordinates = Mat::<f64>::zeros(dim, y.ncols() + held_y.ncols());
            coordinates.as_mut().subcols_mut(0, y.ncols()).copy_from(&y);
            coordinates.as_mut().subcols_mut(y.ncols(), held_y.ncols()).copy_from(&held_y);
            return Ok(Some(Grown {
                values: values.iter().chain(&held_values).copied().collect(),
                coordinates,
                count_whole: values.len(),
                estimated,
                at_limit,
                refine: lanczos.refine,
                solves: lanczos.blocks(),
                dim,
            }));
        }
    }
}

/// The checked pairs taken apart: the whole problem's first `count_whole`, the held problem's after.
fn whole_and_held(both: Eigenpairs, count_whole: usize) -> (Eigenpairs, Eigenpairs) {
    let whole = Eigenpairs {
        vectors: both.vectors.subcols(0, count_whole).to_owned(),
        values: both.values[..count_whole].to_vec(),
    };
    let held_pairs = Eigenpairs {
        vectors: both.vectors.subcols(count_whole, both.vectors.ncols() - count_whole).to_owned(),
        values: both.values[count_whole..].to_vec(),
    };
    (whole, held_pairs)
}
