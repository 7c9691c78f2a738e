//! The search for the lowest modes, or every mode below a frequency, in one growing block
//! Lanczos space.

use super::block_lanczos::{BlockLanczos, block_size, start_block};
use super::checks::{checked, worst_of};
use super::dense::dense_search;
use super::{Deflation, Eigenpairs, MAX_MODES, RESIDUAL_TOL, Want, distributed_health};
use crate::error::{LinalgError, Result};
use crate::sparse::{Sparse, SpdSolve};
use faer::Mat;

pub(super) fn lanczos_search(
    k: &dyn SpdSolve,
    m: &Sparse,
    want: Want,
    tol: f64,
    shift: f64,
    deflate: Option<&Deflation>,
) -> Result<Eigenpairs> {
    if k.n() <= crate::dense_eigen::DENSE_MAX_DOFS
        && let Some(pairs) = dense_search(k, m, want, shift, deflate)?
    {
        return Ok(pairs);
    }
    phases::phase("eigen-solve (block shift-invert Lanczos)", || block_lanczos_search(k, m, want, tol, shift, deflate))
}

/// `lanczos_search` past the dense path: one space grown until the wanted pairs converge.
fn block_lanczos_search(
    k: &dyn SpdSolve,
    m: &Sparse,
    want: Want,
    tol: f64,
    shift: f64,
    deflate: Option<&Deflation>,
) -> Result<Eigenpairs> {
    let n = k.n();
    let n_free = n - deflate.map_or(0, |d| d.vectors.ncols());
    // modes below a frequency: ten first, doubled while all found lie below it, in the same
    // growing space (nothing computed is thrown away)
    let mut count = first_count(want, n_free);
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
        let RitzPairs { values, y, estimated, at_limit, dim } =
            grow(k, &mut lanczos, count, (p, n_free, max_dim(count)), &mut next_check, estimate_tol)?;
        let (pairs, worst, at) = checked_ritz_pairs(k, m, &mut lanczos, values, &y, shift);
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
        phases::note(|| {
            format!("{count} modes: {solves} block solves of {p} ({dim} Lanczos vectors); {}", lanczos.clock.describe())
        });
        if !converged {
            return Err(not_converged(count, dim, n_free, worst, at));
        }
        let Want::Below { omega_max, min_count } = want else { return Ok(pairs) };
        if let Some(below) = all_below(pairs, omega_max, min_count, n_free) {
            return Ok(below);
        }
        if count > MAX_MODES {
            return Err(LinalgError::too_large(format!(
                "more than {MAX_MODES} modes lie below {:.6e} Hz: lower reduction.max_frequency",
                omega_max / (2.0 * std::f64::consts::PI)
            )));
        }
        count = (count * 2).min(MAX_MODES + 1).min(n_free);
        estimate_tol = tol;
    }
}

/// The projection's Ritz pairs once they are estimated converged or the space is at its limit.
struct RitzPairs {
    values: Vec<f64>,
    /// Coordinates in the space.
    y: Mat<f64>,
    estimated: bool,
    at_limit: bool,
    dim: usize,
}

/// Block solves until the `count` wanted Ritz pairs are estimated converged or the space reaches
/// `max_dim` (or can grow no more); `p` columns per block, `n_free` DoFs outside the deflation.
fn grow(
    k: &dyn SpdSolve,
    lanczos: &mut BlockLanczos<'_>,
    count: usize,
    (p, n_free, max_dim): (usize, usize, usize),
    next_check: &mut usize,
    estimate_tol: f64,
) -> Result<RitzPairs> {
    loop {
        let exhausted = !lanczos.extend(k)?;
        // a block the distributed back-end failed to solve ends the search at once
        distributed_health(k)?;
        let dim = lanczos.dim();
        if (dim < (count + p).min(n_free) || dim < *next_check) && !exhausted && dim < max_dim {
            continue;
        }
        *next_check = dim + dim.div_ceil(7);
        let began = std::time::Instant::now();
        let (values, y, estimated) = lanczos.ritz(count, estimate_tol, exhausted)?;
        lanczos.clock.ritz += began.elapsed();
        let at_limit = exhausted || dim >= max_dim;
        if estimated || at_limit {
            return Ok(RitzPairs { values, y, estimated, at_limit, dim });
        }
    }
}

/// Modes to search for first: the count wanted, or ten for every mode below a frequency (doubled
/// while all found lie below it).
fn first_count(want: Want, n_free: usize) -> usize {
    match want {
        Want::Lowest(c) => c,
        Want::Below { min_count, .. } => min_count.max(10),
    }
    .min(n_free)
}

/// The Ritz pairs with coordinates `y` in the space, checked, not assumed: their residuals in K
/// and M themselves, their eigenvalues the Rayleigh quotients of the same solve; with the worst
/// residual and its mode.
fn checked_ritz_pairs(
    k: &dyn SpdSolve,
    m: &Sparse,
    lanczos: &mut BlockLanczos<'_>,
    values: Vec<f64>,
    y: &Mat<f64>,
    shift: f64,
) -> (Eigenpairs, f64, usize) {
    let vectors = lanczos.vectors(y);
    let began = std::time::Instant::now();
    let (pairs, residuals) = checked(k, m, Eigenpairs { values, vectors }, shift, lanczos.refine > 0);
    lanczos.clock.checks += began.elapsed();
    let (worst, at) = residuals.iter().enumerate().fold((0.0f64, 0), worst_of);
    (pairs, worst, at)
}

/// The modes below `omega_max` (at least `min_count`) once the converged `pairs` reach past it or
/// span the whole space; None while they all lie below it (the search goes on).
fn all_below(pairs: Eigenpairs, omega_max: f64, min_count: usize, n_free: usize) -> Option<Eigenpairs> {
    let n_below = pairs.values.iter().filter(|&&l| l.sqrt() < omega_max).count();
    if n_below < pairs.values.len() || pairs.values.len() >= n_free {
        let keep = n_below.max(min_count).min(pairs.values.len());
        let vectors = pairs.vectors.subcols(0, keep).to_owned();
        return Some(Eigenpairs { values: pairs.values[..keep].to_vec(), vectors });
    }
    None
}

fn not_converged(count: usize, dim: usize, n_free: usize, worst: f64, at: usize) -> LinalgError {
    LinalgError::not_converged(format!(
        "eigensolver: {count} modes did not converge with {dim} Lanczos vectors (of {n_free} DoFs): mode {} has the residual {worst:.1e} (accepted {RESIDUAL_TOL:.0e}); request fewer modes (reduction.modes, max_frequency) or check the mesh for extreme element proportions",
        at + 1
    ))
}
