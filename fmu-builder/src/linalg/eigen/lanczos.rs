//! The search for the lowest modes, or every mode below a frequency, in one growing block
//! Lanczos space.

use super::block_lanczos::{BlockLanczos, block_size, start_block};
use super::checks::{checked, worst_of};
use super::dense::dense_search;
use super::{Deflation, Eigenpairs, MAX_MODES, RESIDUAL_TOL, Want, distributed_health};
use crate::error::{BuildError, Result};
use crate::linalg::sparse::{Sparse, SpdSolve};
use faer::Mat;

pub(super) fn lanczos_search(
    k: &dyn SpdSolve,
    m: &Sparse,
    want: Want,
    tol: f64,
    shift: f64,
    deflate: Option<&Deflation>,
) -> Result<Eigenpairs> {
    if k.n() <= crate::linalg::dense_eigen::DENSE_MAX_DOFS
        && let Some(pairs) = dense_search(k, m, want, shift, deflate)?
    {
        return Ok(pairs);
    }
    crate::profile::phase("eigen-solve (block shift-invert Lanczos)", || {
        let n = k.n();
        let n_free = n - deflate.map_or(0, |d| d.vectors.ncols());
        // modes below a frequency: ten first, doubled while all found lie below it, in the same
        // growing space (nothing computed is thrown away)
        let mut count = match want {
            Want::Lowest(c) => c,
            Want::Below { min_count, .. } => min_count.max(10),
        }
        .min(n_free);
        if count == 0 {
            return Ok(Eigenpairs { values: Vec::new(), vectors: Mat::zeros(n, 0) });
        }
        let start = start_block(n, block_size(count).min(n_free));
        let p = start.ncols();
        // beyond ten vectors per mode Lanczos with a factored shift-invert operator has failed
        // for a reason more vectors will not cure, and the dense n x dim blocks would grow
        // towards n x n
        let max_dim = |count: usize| (10 * count + 200).max(count + 2 * p).min(n_free);
        let reserve = match want {
            Want::Lowest(c) => max_dim(c),
            Want::Below { .. } => max_dim(count),
        };
        let mut lanczos = BlockLanczos::new(m, &start, deflate, true, reserve)?;
        let mut estimate_tol = tol;
        // the projection's eigen-decomposition costs dim^3 (2 s at 1500 vectors): checked first
        // where convergence begins (600 modes converged with 1352 vectors in blocks of 8, 20
        // modes with 80 in blocks of 5), then whenever the space has grown by 15 %
        let first_check = 2 * count + 2 * p;
        let mut next_check = first_check;
        loop {
            let max_dim = max_dim(count);
            let exhausted = !lanczos.extend(k)?;
            // a block the distributed back-end failed to solve ends the search at once
            distributed_health(k)?;
            let dim = lanczos.dim();
            if (dim < (count + p).min(n_free) || dim < next_check) && !exhausted && dim < max_dim {
                continue;
            }
            next_check = dim + dim.div_ceil(7);
            let began = std::time::Instant::now();
            let (values, y, estimated) = lanczos.ritz(count, estimate_tol, exhausted)?;
            lanczos.clock.ritz += began.elapsed();
            let at_limit = exhausted || dim >= max_dim;
            if !estimated && !at_limit {
                continue;
            }
            let vectors = lanczos.vectors(&y);
            // every returned pair is checked, not assumed: its residual in K and M themselves,
            // and its eigenvalue the Rayleigh quotient of the same solve
            let began = std::time::Instant::now();
            let (pairs, residuals) = checked(k, m, Eigenpairs { values, vectors }, shift, lanczos.refine > 0);
            lanczos.clock.checks += began.elapsed();
            let (worst, at) = residuals.iter().enumerate().fold((0.0f64, 0), worst_of);
            let converged = estimated && worst <= RESIDUAL_TOL && pairs.values.len() == count;
            if !converged && lanczos.refine == 0 {
                // plain solves were judged exact enough from the first block's correction, which
                // the low modes dominate; the higher ones needed more (a slender part's mode 23
                // kept a residual of 1.2e-7): again from the start, every solve refined
                let clock = lanczos.clock;
                lanczos = BlockLanczos::new(m, &start, deflate, false, reserve)?;
                lanczos.clock = clock;
                estimate_tol = tol;
                next_check = first_check;
                continue;
            }
            if !converged && !at_limit {
                // the estimate claimed more than the measured residual: ask more of it
                estimate_tol *= 1e-2;
                continue;
            }
            let solves = lanczos.blocks();
            crate::profile::note(|| {
                format!(
                    "{count} modes: {solves} block solves of {p} ({dim} Lanczos vectors); {}",
                    lanczos.clock.describe()
                )
            });
            if !converged {
                return Err(BuildError::Numerical(format!(
                    "eigensolver: {count} modes did not converge with {dim} Lanczos vectors (of {n_free} DoFs): mode {} has the residual {worst:.1e} (accepted {RESIDUAL_TOL:.0e}); request fewer modes (reduction.modes, max_frequency) or check the mesh for extreme element proportions",
                    at + 1
                )));
            }
            let Want::Below { omega_max, min_count } = want else { return Ok(pairs) };
            let n_below = pairs.values.iter().filter(|&&l| l.sqrt() < omega_max).count();
            if n_below < pairs.values.len() || pairs.values.len() >= n_free {
                let keep = n_below.max(min_count).min(pairs.values.len());
                let vectors = pairs.vectors.subcols(0, keep).to_owned();
                return Ok(Eigenpairs { values: pairs.values[..keep].to_vec(), vectors });
            }
            if count > MAX_MODES {
                return Err(BuildError::Numerical(format!(
                    "more than {MAX_MODES} modes lie below {:.6e} Hz: lower reduction.max_frequency",
                    omega_max / (2.0 * std::f64::consts::PI)
                )));
            }
            count = (count * 2).min(MAX_MODES + 1).min(n_free);
            estimate_tol = tol;
        }
    })
}
