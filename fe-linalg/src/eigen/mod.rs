//! Lowest eigenpairs of K x = lambda M x (K positive definite, M positive semidefinite) by block
//! shift-invert Lanczos in the M inner product: the operator K^-1 M is self-adjoint in it, its
//! largest eigenvalues 1/lambda are the modes we want, and one sparse Cholesky of K serves every
//! iteration, a block of right-hand sides per read of the factor. Full re-orthogonalisation
//! (twice) keeps the basis M-orthonormal to round-off; the space grows a block at a time until
//! the projection (solved by the checked dense eigensolver, `symmetric_eigen`) estimates every
//! wanted pair converged. Every pair is then measured with a fresh solve (`checked`): its
//! eigenvalue the Rayleigh quotient of the shift-invert operator, its residual not taken from the
//! Lanczos estimate; a request the space cannot meet within ten vectors per mode is an error
//! with the residual found.

mod block_lanczos;
mod checks;
mod clock;
mod craig_bampton_space;
mod dense;
mod lanczos;
mod shift_invert_ritz;

pub use block_lanczos::column_dots;
pub use craig_bampton_space::lowest_and_held;

use crate::error::Result;
use crate::sparse::{Sparse, SpdSolve};
use faer::Mat;
use lanczos::lanczos_search;

pub struct Eigenpairs {
    /// Ascending eigenvalues lambda = omega^2.
    pub values: Vec<f64>,
    /// M-orthonormal eigenvectors, one per column.
    pub vectors: Mat<f64>,
}

/// Largest accepted residual |x - mu A^-1 M x|_M / |x|_M of a returned mode (see
/// `checked`). The Ritz estimate asks for 1e-10; converged modes measure 1e-10 and below,
/// the unconverged modes of the failure this check was written for 1e-5 .. 1e-3. At 1e-7 the
/// eigenvalue is exact to about 1e-14.
pub const RESIDUAL_TOL: f64 = 1e-7;

/// Most modes a build computes (requested or below a frequency).
pub const MAX_MODES: usize = 1000;

/// Known eigenvectors to keep out of the search (a free body's rigid-body modes), M-orthonormal,
/// with M applied to them.
pub struct Deflation {
    pub vectors: Mat<f64>,
    pub m_vectors: Mat<f64>,
}

impl Deflation {
    /// w -= Y (M Y)^T w
    fn project(&self, w: &mut Mat<f64>) {
        let c = self.m_vectors.transpose() * &*w;
        *w -= &self.vectors * &c;
    }
}

/// The `count` lowest eigenpairs; relative residual tolerance `tol` on 1/lambda.
pub fn lowest(k: &dyn SpdSolve, m: &Sparse, count: usize, tol: f64) -> Result<Eigenpairs> {
    search(k, m, Want::Lowest(count), tol, 0.0, None)
}

/// As `lowest`, with `k` factoring K + shift M (shift > 0 makes a free body's K definite) and the
/// `deflate` vectors kept out: eigenvalues of K come back, the deflated ones excluded.
pub fn lowest_shifted(
    k: &dyn SpdSolve,
    m: &Sparse,
    count: usize,
    tol: f64,
    shift: f64,
    deflate: Option<&Deflation>,
) -> Result<Eigenpairs> {
    search(k, m, Want::Lowest(count), tol, shift, deflate)
}

/// Most modes a shared search (`lowest_and_held`) is used for: its checks decompose the
/// projection twice (dim^3), and its held projection's round-off grows with the spread of the
/// modes it resolves (a 600-mode slender beam stalled there); more modes go separately.
pub const SHARED_MAX_MODES: usize = 100;
/// What a search is for: a number of modes, or every mode below a frequency.
#[derive(Clone, Copy)]
enum Want {
    Lowest(usize),
    Below { omega_max: f64, min_count: usize },
}

fn search(
    k: &dyn SpdSolve,
    m: &Sparse,
    want: Want,
    tol: f64,
    shift: f64,
    deflate: Option<&Deflation>,
) -> Result<Eigenpairs> {
    let found = lanczos_search(k, m, want, tol, shift, deflate);
    // a distributed solve that failed filled its columns with NaN: its reason, not what the
    // search made of the NaN
    distributed_health(k)?;
    found
}

/// The failure of a solve on the distributed back-end behind `k`, if one failed.
fn distributed_health(k: &dyn SpdSolve) -> Result<()> {
    k.distributed_session().map_or(Ok(()), |s| Ok(s.health()?))
}

/// All eigenpairs with omega below `omega_max`, at least `min_count` of them.
pub fn below(k: &dyn SpdSolve, m: &Sparse, omega_max: f64, min_count: usize, tol: f64) -> Result<Eigenpairs> {
    below_shifted(k, m, omega_max, min_count, tol, 0.0, None)
}

pub fn below_shifted(
    k: &dyn SpdSolve,
    m: &Sparse,
    omega_max: f64,
    min_count: usize,
    tol: f64,
    shift: f64,
    deflate: Option<&Deflation>,
) -> Result<Eigenpairs> {
    search(k, m, Want::Below { omega_max, min_count }, tol, shift, deflate)
}

#[cfg(test)]
mod tests {
    use super::checks::checked;
    use super::*;
    use crate::sparse::SpdSolver;

    /// A 3D grid: K the 7-point Laplacian plus a small diagonal, M a varying diagonal.
    fn grid(k: usize) -> (Sparse, Sparse) {
        use crate::test_grids::{diagonal, laplacian};
        (laplacian(k, |_| 6.01), diagonal(k, |i| 1.0 + 0.5 * ((i * 7) % 5) as f64))
    }

    /// Every mode below a frequency, found in one growing space, equals the same number of
    /// lowest modes found on their own (a consistency check of the two searches; the
    /// eigenvalues themselves are checked against CalculiX and beam theory in the Python tests).
    #[test]
    fn modes_below_a_frequency_equal_the_lowest_modes() {
        let (k, m) = grid(12);
        let name = |d: usize| format!("row {d}");
        let solver = SpdSolver::new(std::borrow::Cow::Owned(k), "grid", &name).unwrap();
        let own = lowest(&solver, &m, 30, 1e-10).unwrap();
        assert_eq!(own.values.len(), 30);
        // between modes 24 and 25 (the grid's eigenvalues come in degenerate groups)
        let cut = 0.5 * (own.values[23].sqrt() + own.values[24].sqrt());
        let below = below(&solver, &m, cut, 1, 1e-10).unwrap();
        let expected = own.values.iter().filter(|l| l.sqrt() < cut).count();
        assert_eq!(below.values.len(), expected);
        assert_eq!(below.vectors.ncols(), expected);
        for (a, b) in own.values.iter().zip(&below.values) {
            // both converged to residual 1e-7 and below, so eigenvalues agree to its square
            assert!((a - b).abs() <= 1e-10 * a, "{a} vs {b}");
        }
    }

    /// The whole problem's and the held problem's modes from one space equal each found by a
    /// search of its own (the held one with the free block's own mass), and the held modes
    /// vanish at the held rows: a consistency check of the shared space against the two
    /// searches it replaces (the physics is checked against CalculiX in the Python tests).
    #[test]
    fn whole_and_held_modes_from_one_space_equal_separate_searches() {
        use crate::held::HeldSolver;
        use crate::sparse::block;
        let (k, m) = grid(14);
        let n = k.nrows();
        // the last 6 rows held, as Craig-Bampton holds a force flange's master DoFs
        let first = n - 6;
        let name = |d: usize| format!("row {d}");
        let solver = SpdSolver::new(std::borrow::Cow::Owned(k), "grid", &name).unwrap();
        let held = HeldSolver::new(&solver, first).unwrap();
        let (whole, held_modes) = lowest_and_held(&solver, &m, 26, &held, 20, 1e-8).unwrap();
        let own_whole = lowest(&solver, &m, 26, 1e-8).unwrap();
        let m_ii = block(&m, 0..first, 0..first).unwrap();
        let own_held = lowest(&held, &m_ii, 20, 1e-8).unwrap();
        assert_eq!((whole.values.len(), whole.vectors.nrows()), (26, n));
        assert_eq!((held_modes.values.len(), held_modes.vectors.nrows(), held_modes.vectors.ncols()), (20, first, 20));
        assert_eq!(own_whole.values.len(), 26);
        assert_eq!(own_held.values.len(), 20);
        for (a, b) in whole.values.iter().zip(&own_whole.values).chain(held_modes.values.iter().zip(&own_held.values)) {
            // every pair's residual is at most 1e-7 (checked by both searches), so the Rayleigh
            // quotients agree to about its square; a held mode taken from the whole problem
            // (or the reverse) differs by 1e-3 and more on this grid
            assert!((a - b).abs() <= 1e-10 * a, "{a} vs {b}");
        }
        // held modes really are held: the padded vectors' check found residuals at most 1e-7,
        // and as vectors of the free rows they solve K_ii x = lambda M_ii x
        let (_, residuals) = checked(&held, &m_ii, held_modes, 0.0, true);
        assert_eq!(residuals.len(), 20);
        let worst = residuals.iter().fold(0.0f64, |a, &b| a.max(b));
        assert!(worst <= RESIDUAL_TOL, "held residual {worst:e}");
    }
}
