//! Lowest eigenpairs of K x = lambda M x (K positive definite, M positive semidefinite) by
//! shift-invert Lanczos in the M inner product: the operator K^-1 M is self-adjoint in it, its
//! largest eigenvalues 1/lambda are the modes we want, and one sparse Cholesky of K serves every
//! iteration. Full re-orthogonalisation (twice) keeps the basis M-orthonormal to round-off; the
//! tridiagonal projection is solved by the checked dense eigensolver (`symmetric_eigen`), and
//! every returned pair's residual is measured with a fresh solve (`worst_residual`), not taken
//! from the Lanczos estimate. When the space is too small for the accuracy it is enlarged and the
//! run repeated from the best Ritz combination; a request the full space cannot meet is an error
//! with the residual found.

use crate::error::{BuildError, Result};
use crate::linalg::sparse::{Sparse, SpdSolver, mul_new};
use crate::linalg::symmetric_eigen::symmetric_eigen;
use faer::Mat;

pub struct Eigenpairs {
    /// Ascending eigenvalues lambda = omega^2.
    pub values: Vec<f64>,
    /// M-orthonormal eigenvectors, one per column.
    pub vectors: Mat<f64>,
}

/// Largest accepted residual |x - mu A^-1 M x|_M / |x|_M of a returned mode (see
/// `worst_residual`). The Ritz estimate asks for 1e-10; converged modes measure 1e-10 and below,
/// the unconverged modes of the failure this check was written for 1e-5 .. 1e-3. At 1e-7 the
/// eigenvalue is exact to about 1e-14.
pub const RESIDUAL_TOL: f64 = 1e-7;

/// Most modes a build computes (requested or below a frequency).
pub const MAX_MODES: usize = 1000;

/// Deterministic start vector with all components non-zero (no symmetry can hide a mode from it).
fn start_vector(n: usize) -> Vec<f64> {
    let mut s: u64 = 0x9E37_79B9_7F4A_7C15;
    (0..n)
        .map(|_| {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            0.5 + (s >> 11) as f64 / (1u64 << 53) as f64
        })
        .collect()
}

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
pub fn lowest(k: &SpdSolver, m: &Sparse, count: usize, tol: f64) -> Result<Eigenpairs> {
    lowest_shifted(k, m, count, tol, 0.0, None)
}

/// As `lowest`, with `k` factoring K + shift M (shift > 0 makes a free body's K definite) and the
/// `deflate` vectors kept out: eigenvalues of K come back, the deflated ones excluded.
pub fn lowest_shifted(
    k: &SpdSolver,
    m: &Sparse,
    count: usize,
    tol: f64,
    shift: f64,
    deflate: Option<&Deflation>,
) -> Result<Eigenpairs> {
    crate::profile::phase("eigen-solve (shift-invert Lanczos)", || {
        let n = k.n();
        let count = count.min(n);
        if count == 0 {
            return Ok(Eigenpairs { values: Vec::new(), vectors: Mat::zeros(n, 0) });
        }
        let n_free = n - deflate.map_or(0, |d| d.vectors.ncols());
        let count = count.min(n_free);
        let mut dim = (2 * count + 20).max(count + 30).min(n_free);
        // restarts grow the space by half; beyond ten vectors per mode (four restarts) Lanczos with
        // a factored shift-invert operator has failed for a reason more vectors will not cure, and
        // the dense n x dim blocks would grow towards n x n
        let max_dim = (10 * count + 200).min(n_free);
        let mut start = start_vector(n);
        loop {
            let (mut pairs, estimated, next_start) = lanczos(k, m, count, dim, &start, tol, deflate)?;
            crate::profile::note(|| format!("{count} modes: {dim} Lanczos vectors (as many solves)"));
            for v in pairs.values.iter_mut() {
                *v -= shift;
            }
            // every returned pair is checked, not assumed: its residual in K and M themselves
            let (worst, at) = worst_residual(k, m, &pairs, shift);
            let converged = estimated && worst <= RESIDUAL_TOL && pairs.values.len() == count;
            if converged || dim >= max_dim {
                if !converged {
                    return Err(BuildError::Numerical(format!(
                        "eigensolver: {count} modes did not converge with {dim} Lanczos vectors (of {n_free} DoFs): mode {} has the residual {worst:.1e} (accepted {RESIDUAL_TOL:.0e}); request fewer modes (reduction.modes, max_frequency) or check the mesh for extreme element proportions",
                        at + 1
                    )));
                }
                return Ok(pairs);
            }
            start = next_start;
            dim = (dim + dim / 2).min(max_dim);
        }
    })
}

/// One Lanczos run of `dim` steps. Returns the `count` lowest Ritz pairs, whether they converged,
/// and a restart vector (sum of the wanted Ritz vectors).
fn lanczos(
    k: &SpdSolver,
    m: &Sparse,
    count: usize,
    dim: usize,
    start: &[f64],
    tol: f64,
    deflate: Option<&Deflation>,
) -> Result<(Eigenpairs, bool, Vec<f64>)> {
    let n = k.n();
    let mut v = Mat::<f64>::zeros(n, dim);
    let mut mv = Mat::<f64>::zeros(n, dim);
    let mut alpha = vec![0.0; dim];
    let mut beta = vec![0.0; dim];
    let mut w = Mat::<f64>::zeros(n, 1);
    // v0 = start / |start|_M
    w.col_mut(0).as_mut().copy_from(faer::ColRef::from_slice(start));
    if let Some(d) = deflate {
        d.project(&mut w);
    }
    let mw = mul_new(m, w.as_ref());
    let norm = (0..n).map(|i| w[(i, 0)] * mw[(i, 0)]).sum::<f64>().sqrt();
    if !(norm > 0.0) {
        return Err(BuildError::Numerical("eigensolver: the mass matrix vanishes on the start vector".into()));
    }
    for i in 0..n {
        v[(i, 0)] = w[(i, 0)] / norm;
        mv[(i, 0)] = mw[(i, 0)] / norm;
    }
    let mut steps = dim;
    for j in 0..dim {
        // w = K^-1 M v_j
        for i in 0..n {
            w[(i, 0)] = mv[(i, j)];
        }
        // one refinement step: slender parts have cond(K) ~ 1e12, and a plain solve would cost
        // the lowest Ritz values their sixth digit
        k.solve_refined_steps(w.as_mut(), 1);
        if let Some(d) = deflate {
            d.project(&mut w);
        }
        // full re-orthogonalisation in the M inner product, block classical Gram-Schmidt done
        // twice (Kahan-Parlett "twice is enough"); the j-th coefficient is the Lanczos alpha
        alpha[j] = 0.0;
        for _pass in 0..2 {
            let c = mv.subcols(0, j + 1).transpose() * &w;
            alpha[j] += c[(j, 0)];
            w -= v.subcols(0, j + 1) * &c;
        }
        let mw = mul_new(m, w.as_ref());
        let b = (0..n).map(|r| w[(r, 0)] * mw[(r, 0)]).sum::<f64>().max(0.0).sqrt();
        beta[j] = b;
        if j + 1 == dim {
            break;
        }
        if b <= 1e-13 * alpha[j].abs() {
            // invariant subspace: every eigenpair in it is exact
            steps = j + 1;
            break;
        }
        for r in 0..n {
            v[(r, j + 1)] = w[(r, 0)] / b;
            mv[(r, j + 1)] = mw[(r, 0)] / b;
        }
    }
    // Ritz values of the tridiagonal T (projection of K^-1 M)
    let mut t = Mat::<f64>::zeros(steps, steps);
    for j in 0..steps {
        t[(j, j)] = alpha[j];
        if j + 1 < steps {
            t[(j, j + 1)] = beta[j];
            t[(j + 1, j)] = beta[j];
        }
    }
    let evd = symmetric_eigen(&t, "eigensolver: the Lanczos tridiagonal matrix")?;
    let s = &evd.values;
    let u = &evd.vectors;
    // largest theta first
    let count = count.min(steps);
    let mut values = Vec::with_capacity(count);
    let mut ritz = Mat::<f64>::zeros(steps, count);
    let mut converged = true;
    let last_beta = beta[steps - 1];
    for c in 0..count {
        let idx = steps - 1 - c;
        let theta = s[idx];
        if !(theta > 0.0) {
            return Err(BuildError::Numerical(format!("eigensolver: non-positive Ritz value {theta:e}")));
        }
        let estimate = (last_beta * u[(steps - 1, idx)]).abs();
        if steps == dim && estimate > tol * theta {
            converged = false;
        }
        values.push(1.0 / theta);
        ritz.as_mut().col_mut(c).copy_from(u.col(idx));
    }
    let vectors = v.subcols(0, steps) * &ritz;
    let mut restart = vec![0.0; n];
    for c in 0..count {
        for r in 0..n {
            restart[r] += vectors[(r, c)];
        }
    }
    Ok((Eigenpairs { values, vectors }, converged, restart))
}

/// The largest residual of the pairs in the shift-invert operator's own norm,
/// |x - mu A^-1 M x|_M / |x|_M (mu = lambda + shift, A the factored K + shift M): what the
/// Lanczos estimate claims, measured with a fresh solve. Unlike |K x - lambda M x| / |K x|, it
/// does not grow with cond(K) for the lowest modes of slender parts, and it bounds the
/// eigenvalue error (relative, about its square) and the vector's angle (over the gap).
pub fn worst_residual(k: &SpdSolver, m: &Sparse, pairs: &Eigenpairs, shift: f64) -> (f64, usize) {
    if pairs.values.is_empty() {
        return (0.0, 0);
    }
    let mx = mul_new(m, pairs.vectors.as_ref());
    let mut y = mx.clone();
    k.solve_refined_steps(y.as_mut(), 1);
    let mut worst = (0.0f64, 0);
    for (c, lambda) in pairs.values.iter().enumerate() {
        let mu = lambda + shift;
        let mut r = Mat::<f64>::zeros(mx.nrows(), 1);
        for i in 0..mx.nrows() {
            r[(i, 0)] = pairs.vectors[(i, c)] - mu * y[(i, c)];
        }
        let mr = mul_new(m, r.as_ref());
        let r2: f64 = (0..mx.nrows()).map(|i| r[(i, 0)] * mr[(i, 0)]).sum();
        let x2: f64 = (0..mx.nrows()).map(|i| pairs.vectors[(i, c)] * mx[(i, c)]).sum();
        let rel = if x2 > 0.0 { (r2.max(0.0) / x2).sqrt() } else { f64::INFINITY };
        if !(rel <= worst.0) {
            worst = (rel, c);
        }
    }
    worst
}

/// All eigenpairs with omega below `omega_max`, at least `min_count` of them.
pub fn below(k: &SpdSolver, m: &Sparse, omega_max: f64, min_count: usize, tol: f64) -> Result<Eigenpairs> {
    below_shifted(k, m, omega_max, min_count, tol, 0.0, None)
}

pub fn below_shifted(
    k: &SpdSolver,
    m: &Sparse,
    omega_max: f64,
    min_count: usize,
    tol: f64,
    shift: f64,
    deflate: Option<&Deflation>,
) -> Result<Eigenpairs> {
    let mut count = min_count.max(10);
    loop {
        let pairs = lowest_shifted(k, m, count, tol, shift, deflate)?;
        let n_below = pairs.values.iter().filter(|&&l| l.sqrt() < omega_max).count();
        let available = k.n() - deflate.map_or(0, |d| d.vectors.ncols());
        if n_below < pairs.values.len() || pairs.values.len() >= available {
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
        count = (count * 2).min(MAX_MODES + 1);
    }
}
