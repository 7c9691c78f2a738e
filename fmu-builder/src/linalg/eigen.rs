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

use crate::error::{BuildError, Result};
use crate::linalg::held::{HeldSolver, WholeAndHeld};
use crate::linalg::sparse::{Sparse, SpdSolve};
use crate::linalg::symmetric_eigen::symmetric_eigen;
use crate::linalg::symmetric_product::mul_new;
use faer::Mat;
use faer::reborrow::{Reborrow, ReborrowMut};

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
    let shared = crate::profile::phase("eigen-solve (block shift-invert Lanczos)", || {
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
                return Err(BuildError::Numerical("eigensolver: a held DoF's unit-load response has no mass".into()));
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
        let mut adaptive = true;
        let mut estimate_tol = tol;
        let mut clock = Clock::default();
        loop {
            // the space is dropped before the pairs are checked (its memory is what the check's
            // products need), so a check that fails starts a new space: refined solves if the
            // plain ones were used, else a tighter estimate
            let mut lanczos = BlockLanczos::new(m, &start, None, adaptive, max_dim)?;
            let mut next_check = first_check;
            let (both, count_whole, estimated, at_limit, refine, solves, dim) = loop {
                let exhausted = !lanczos.extend(k)?;
                // a block the distributed back-end failed to solve ends the search at once
                distributed_health(k)?;
                let dim = lanczos.dim();
                if dim < next_check && !exhausted && dim < max_dim {
                    continue;
                }
                next_check = dim + dim.div_ceil(7);
                let began = std::time::Instant::now();
                let (values, y, whole_estimated) = lanczos.ritz(count, estimate_tol, exhausted)?;
                let (held_values, held_y, held_estimated) =
                    lanczos.ritz_held(first, &m_g, held, count_held, estimate_tol, exhausted)?;
                lanczos.clock.ritz += began.elapsed();
                let estimated = whole_estimated && held_estimated;
                if !estimated && !exhausted && dim >= shared_limit {
                    crate::profile::note(|| format!("no shared convergence with {dim} vectors: separate searches"));
                    return Ok(None);
                }
                let at_limit = exhausted || dim >= max_dim;
                if !estimated && !at_limit {
                    continue;
                }
                // both sets' vectors side by side, checked together below (the held pairs' vanish at
                // the held rows, to round-off)
                let mut coordinates = Mat::<f64>::zeros(dim, y.ncols() + held_y.ncols());
                coordinates.as_mut().subcols_mut(0, y.ncols()).copy_from(&y);
                coordinates.as_mut().subcols_mut(y.ncols(), held_y.ncols()).copy_from(&held_y);
                let both = Eigenpairs {
                    vectors: lanczos.vectors(&coordinates),
                    values: values.iter().chain(&held_values).copied().collect(),
                };
                break (both, values.len(), estimated, at_limit, lanczos.refine, lanczos.blocks(), dim);
            };
            clock.add(&lanczos.clock);
            drop(lanczos);
            // one refined solve checks both: the held columns through the held solver
            let (both, worst) = clock.time(
                |c| &mut c.checks,
                || checked(&WholeAndHeld { held, whole: count_whole }, m, both, 0.0, refine > 0),
            );
            let (worst_whole, at_whole) = worst[..count_whole].iter().enumerate().fold((0.0f64, 0), worst_of);
            let (worst_held, at_held) = worst[count_whole..].iter().enumerate().fold((0.0f64, 0), worst_of);
            let whole = Eigenpairs {
                vectors: both.vectors.subcols(0, count_whole).to_owned(),
                values: both.values[..count_whole].to_vec(),
            };
            let held_pairs = Eigenpairs {
                vectors: both.vectors.subcols(count_whole, both.vectors.ncols() - count_whole).to_owned(),
                values: both.values[count_whole..].to_vec(),
            };
            drop(both);
            let converged = estimated
                && worst_whole <= RESIDUAL_TOL
                && worst_held <= RESIDUAL_TOL
                && whole.values.len() == count
                && held_pairs.values.len() == count_held;
            if !converged && (refine == 0 || !at_limit) {
                let worst = worst_whole.max(worst_held);
                let how = if refine > 0 { "a tighter estimate" } else { "every solve refined" };
                crate::profile::note(|| format!("{dim} vectors left a residual of {worst:.1e}: again with {how}"));
                if refine > 0 {
                    estimate_tol *= 1e-2;
                } else {
                    estimate_tol = tol;
                }
                adaptive = false;
                continue;
            }
            crate::profile::note(|| {
                format!(
                    "{count} modes of the whole and {count_held} held, in one space: {solves} block solves of {pt} ({dim} Lanczos vectors); {}",
                    clock.describe()
                )
            });
            if !converged {
                let (worst, at, which) =
                    if worst_held > worst_whole { (worst_held, at_held, "held ") } else { (worst_whole, at_whole, "") };
                return Err(BuildError::Numerical(format!(
                    "eigensolver: {count} modes and {count_held} held modes did not converge with {dim} Lanczos vectors (of {n} DoFs): {which}mode {} has the residual {worst:.1e} (accepted {RESIDUAL_TOL:.0e}); request fewer modes (reduction.modes) or check the mesh for extreme element proportions",
                    at + 1
                )));
            }
            return Ok(Some((whole, free_rows(held_pairs, first))));
        }
    });
    distributed_health(k)?;
    match shared? {
        Some(pairs) => Ok(pairs),
        None => separate(),
    }
}

/// Most modes a shared search (`lowest_and_held`) is used for: its checks decompose the
/// projection twice (dim^3), and its held projection's round-off grows with the spread of the
/// modes it resolves (a 600-mode slender beam stalled there); more modes go separately.
pub const SHARED_MAX_MODES: usize = 100;

/// The pairs' vectors restricted to their first `rows` rows.
fn free_rows(pairs: Eigenpairs, rows: usize) -> Eigenpairs {
    Eigenpairs { vectors: pairs.vectors.subrows(0, rows).to_owned(), values: pairs.values }
}

/// Where an eigen-solve's time went, for the build profile's note.
#[derive(Default, Clone, Copy)]
struct Clock {
    solves: std::time::Duration,
    orthogonalisation: std::time::Duration,
    ritz: std::time::Duration,
    checks: std::time::Duration,
}

impl Clock {
    /// Run `f`, adding its wall time to the entry `at` picks.
    fn time<R>(&mut self, at: fn(&mut Self) -> &mut std::time::Duration, f: impl FnOnce() -> R) -> R {
        let began = std::time::Instant::now();
        let r = f();
        *at(self) += began.elapsed();
        r
    }

    fn add(&mut self, other: &Clock) {
        self.solves += other.solves;
        self.orthogonalisation += other.orthogonalisation;
        self.ritz += other.ritz;
        self.checks += other.checks;
    }

    fn describe(&self) -> String {
        format!(
            "block solves {:.1} s, orthogonalisation {:.1} s, Ritz pairs {:.1} s, checks {:.1} s",
            self.solves.as_secs_f64(),
            self.orthogonalisation.as_secs_f64(),
            self.ritz.as_secs_f64(),
            self.checks.as_secs_f64()
        )
    }
}

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
    k.distributed_session().map_or(Ok(()), |s| s.health())
}

fn lanczos_search(
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

/// Columns per Lanczos block. A solve reads the whole factor from memory whatever the number of
/// right-hand sides, so a block costs less per vector: on a 249k-DoF bracket one right-hand side
/// took 0.21 s, 4 took 0.45 s, 8 0.65 s (one thread; split over two, 5 take 0.30 s and 33
/// 0.6 s, but blocks of 8 and 12 then measured no faster overall than a quarter of the modes). Larger blocks need more vectors for the same modes
/// (20 modes of the 17k-DoF bracket: 45 vectors one by one, 72 in blocks of 4, 104 in blocks of
/// 8), and the vectors' memory and re-orthogonalisation grow with them: a quarter of the modes,
/// at most 8, costs least.
fn block_size(count: usize) -> usize {
    count.div_ceil(4).clamp(1, 8)
}

/// Deterministic start block: `start_vector` and its shuffles, every component non-zero.
fn start_block(n: usize, p: usize) -> Mat<f64> {
    let base = start_vector(n * p);
    Mat::from_fn(n, p, |i, j| base[j * n + i])
}

/// Block Lanczos in the M inner product with full re-orthogonalisation (block classical
/// Gram-Schmidt, twice: "twice is enough"), grown a block at a time until the wanted Ritz pairs
/// converge: no restart throws computed vectors away. The projection T = V^T M K^-1 M V is
/// block tridiagonal; the coupling of the newest block to the rest bounds each pair's residual.
struct BlockLanczos<'a> {
    m: &'a Sparse,
    deflate: Option<&'a Deflation>,
    /// M-orthonormal blocks V_b, n x (blocks p): one matrix, so products with the whole space
    /// are single matrix-matrix products. M V is not kept: one sparse product of the block
    /// (M w) replaces it in every projection, at half the memory of the space.
    v: Mat<f64>,
    /// M V_b of the newest block: the next block's right-hand sides.
    m_last: Mat<f64>,
    /// T by blocks: t[b] holds T[0..(b+1)p, block b].
    t: Vec<Mat<f64>>,
    /// Coupling of the newest block to the one before (W = V_next R).
    coupling: Mat<f64>,
    p: usize,
    exhausted: bool,
    /// Refinement steps per solve: one until a solve shows it changes nothing that matters.
    refine: usize,
    adaptive: bool,
    clock: Clock,
}

impl<'a> BlockLanczos<'a> {
    /// `adaptive`: drop the refinement once a solve shows it changes nothing that matters.
    /// `reserve`: columns the space may reach, allocated at once (pages are touched only as the
    /// space grows; growing by copies cost 0.5 s per doubling at 249k DoFs).
    fn new(
        m: &'a Sparse,
        start: &Mat<f64>,
        deflate: Option<&'a Deflation>,
        adaptive: bool,
        reserve: usize,
    ) -> Result<Self> {
        let p = start.ncols();
        let mut w = start.clone();
        if let Some(d) = deflate {
            d.project(&mut w);
        }
        let mut v = Mat::zeros(start.nrows(), 0);
        v.reserve(start.nrows(), reserve.max(p) + p);
        let mut this = Self {
            m,
            deflate,
            v,
            m_last: Mat::zeros(0, 0),
            t: Vec::new(),
            coupling: Mat::zeros(p, p),
            p,
            exhausted: false,
            refine: 1,
            adaptive,
            clock: Clock::default(),
        };
        let mw = mul_new(m, w.as_ref());
        match this.orthonormalise(w, mw) {
            Some((v, mv, _)) => {
                this.push(&v, mv);
                Ok(this)
            }
            None => Err(BuildError::Numerical("eigensolver: the mass matrix vanishes on the start vectors".into())),
        }
    }

    /// Vectors in the space whose projection `ritz` uses.
    fn dim(&self) -> usize {
        self.t.len() * self.p
    }

    /// Block solves so far.
    fn blocks(&self) -> usize {
        self.t.len()
    }

    /// One more block: W = K^-1 M V_last, orthogonalised against the space. False when the space
    /// is invariant (nothing new reachable).
    fn extend(&mut self, k: &dyn SpdSolve) -> Result<bool> {
        if self.exhausted {
            return Ok(false);
        }
        crate::progress::step(|| format!("{} Lanczos vectors, block solve {}", self.dim(), self.t.len() + 1));
        let b = self.t.len();
        // one refinement step: slender parts have cond(K) ~ 1e12, and a plain solve would cost
        // the lowest Ritz values their sixth digit (corrections of 1e-7 .. 1e-6 on the beams).
        // Where the first correction is below 1e-10 (1e-12 .. 1e-11 on the tet10 bracket), a
        // plain solve perturbs the Ritz values by that much, far below what is accepted
        // (RESIDUAL_TOL), and the refinement's second solve per block is saved.
        let mut w = std::mem::replace(&mut self.m_last, Mat::zeros(0, 0));
        let refine = self.refine;
        let correction = self.clock.time(|c| &mut c.solves, || k.solve_refined_steps(w.as_mut(), refine));
        let began = std::time::Instant::now();
        if self.adaptive && self.refine > 0 && correction < 1e-10 {
            self.refine = 0;
        }
        if let Some(d) = self.deflate {
            d.project(&mut w);
        }
        let p = self.p;
        let dim = (b + 1) * p;
        // classical Gram-Schmidt against the whole space, twice ("twice is enough"): a single
        // pass with a second only where a column lost half its length (DGKS, after the
        // three-term part) cost a 300-mode slender beam its convergence (mode 294 kept a
        // residual of 1.4e-7) and saved no measurable time
        let (c1, _) = self.project_out(&mut w, 0..dim);
        let (c2, m_before) = self.project_out(&mut w, 0..dim);
        let column = c1 + &c2;
        // M w after the second pass is M w before it less M V c2; V c2 is M-orthogonal to w, so
        // leaving it in changes no M inner product with w, and adds to the next block's
        // right-hand sides a part of the space. Where it is round-off of w, it is left, and
        // with it one product with M per block (30 ms of 380 at 249k DoFs)
        let mw = if at_round_off(&w, &m_before, &c2) { m_before } else { mul_new(self.m, w.as_ref()) };
        self.t.push(column);
        let orthonormal = self.orthonormalise(w, mw);
        self.clock.orthogonalisation += began.elapsed();
        match orthonormal {
            Some((v, mv, r)) => {
                self.push(&v, mv);
                self.coupling = r;
                Ok(true)
            }
            None => {
                // invariant subspace: every eigenpair in it is exact
                self.coupling = Mat::zeros(p, p);
                self.exhausted = true;
                Ok(false)
            }
        }
    }

    /// w -= V V^T M w over the columns `range` of the space (one sparse and two dense
    /// matrix-matrix products, the second in place); returns the coefficients V^T M w and M w
    /// as it was before.
    fn project_out(&self, w: &mut Mat<f64>, range: std::ops::Range<usize>) -> (Mat<f64>, Mat<f64>) {
        let v = self.v.subcols(range.start, range.len());
        let mw = mul_new(self.m, w.as_ref());
        let c = v.transpose() * &mw;
        faer::linalg::matmul::matmul(w.as_mut(), faer::Accum::Add, v, c.as_ref(), -1.0, faer::get_global_parallelism());
        (c, mw)
    }

    /// Append a block V_b to the space (within the reserved storage as long as it lasts), with
    /// M V_b for the next block.
    fn push(&mut self, v: &Mat<f64>, mv: Mat<f64>) {
        let (n, cols) = (self.v.nrows(), self.v.ncols());
        self.v.resize_with(n, cols + v.ncols(), |_, _| 0.0);
        self.v.as_mut().subcols_mut(cols, v.ncols()).copy_from(v);
        self.m_last = mv;
    }

    /// M-orthonormal basis of the block `w` (already orthogonal to the space): (V, M V, R) with
    /// W = V R. Modified Gram-Schmidt within the block, the block once more against the space,
    /// again within (twice is enough); M V by a fresh product for the next block. A column
    /// already spanned gets a fresh direction (its column of R zero); None when no fresh
    /// direction is left. (Cholesky QR twice, with M V carried through its triangular solves,
    /// was tried: 300-mode and 200-mode slender parts then kept residuals of 1.4e-7 and 2.3e-7.)
    fn orthonormalise(&self, w: Mat<f64>, mw: Mat<f64>) -> Option<(Mat<f64>, Mat<f64>, Mat<f64>)> {
        let Orthonormal { q, mq, r: r1, kept } = self.gram_schmidt(w, mw)?;
        // W came M-orthogonal to the space (to round-off); Q = W R^-1 stays so, and orthonormal
        // within, to round-off times R's condition: where every column kept half its length or
        // more, that is a few ulps, and the second round (a pass over the space and two
        // products with M, a third of a block's time at 249k DoFs) would change nothing. M Q,
        // updated alongside, is then as exact as a fresh product.
        if kept >= 0.5 {
            return Some((q, mq, r1));
        }
        let mut q = q;
        self.project_out(&mut q, 0..self.v.ncols());
        let mq = mul_new(self.m, q.as_ref());
        let Orthonormal { q, r: r2, .. } = self.gram_schmidt(q, mq)?;
        let mq = mul_new(self.m, q.as_ref());
        Some((q, mq, &r2 * &r1))
    }

    /// Modified Gram-Schmidt in the M inner product among the columns of `w` (`mw` = M w,
    /// updated alongside: one sparse product per block, not per column). Also returns the
    /// smallest fraction of its M-norm a column kept (0 where one was replaced).
    fn gram_schmidt(&self, mut w: Mat<f64>, mut mw: Mat<f64>) -> Option<Orthonormal> {
        let p = w.ncols();
        let mut r = Mat::<f64>::zeros(p, p);
        let mut kept = 1.0f64;
        // column slices, not indexing: the same sums in the same order, without a bounds check
        // per entry (0.3 s a block at 249k DoFs)
        let col_norm = |w: &Mat<f64>, mw: &Mat<f64>, c: usize| {
            w.col(c).iter().zip(mw.col(c).iter()).map(|(x, y)| x * y).sum::<f64>().max(0.0).sqrt()
        };
        for c in 0..p {
            let norm0 = col_norm(&w, &mw, c);
            for j in 0..c {
                let (left, mut right) = w.as_mut().split_at_col_mut(c);
                let (mleft, mut mright) = mw.as_mut().split_at_col_mut(c);
                let (wj, mwj) = (left.rb().col(j), mleft.rb().col(j));
                let a: f64 = mwj.iter().zip(right.rb().col(0).iter()).map(|(x, y)| x * y).sum();
                r[(j, c)] = a;
                for (x, y) in right.rb_mut().col_mut(0).iter_mut().zip(wj.iter()) {
                    *x -= a * y;
                }
                for (x, y) in mright.rb_mut().col_mut(0).iter_mut().zip(mwj.iter()) {
                    *x -= a * y;
                }
            }
            let norm = col_norm(&w, &mw, c);
            if norm > 1e-10 * norm0 && norm > 0.0 {
                kept = kept.min(norm / norm0);
                r[(c, c)] = norm;
                for x in w.as_mut().col_mut(c).iter_mut() {
                    *x /= norm;
                }
                for x in mw.as_mut().col_mut(c).iter_mut() {
                    *x /= norm;
                }
                continue;
            }
            // spanned already: the block continues with a fresh direction, coupled to nothing
            kept = 0.0;
            r.as_mut().col_mut(c).fill(0.0);
            let fresh = self.fresh_direction(&w, c)?;
            let m_fresh = mul_new(self.m, fresh.as_ref());
            w.as_mut().col_mut(c).copy_from(fresh.col(0));
            mw.as_mut().col_mut(c).copy_from(m_fresh.col(0));
        }
        Some(Orthonormal { q: w, mq: mw, r, kept })
    }

    /// A unit direction M-orthogonal to the space and to the first `c` columns of `w` (already
    /// M-orthonormal), or None when none is left.
    fn fresh_direction(&self, w: &Mat<f64>, c: usize) -> Option<Mat<f64>> {
        let n = w.nrows();
        let mw = mul_new(self.m, w.subcols(0, c));
        for attempt in 0..2 {
            // a direction of its own for every column and attempt: a repeated one would be
            // spanned by the one before and leave only round-off
            let seed = ((self.v.ncols() + c) * 3 + attempt) as u64;
            let mut x = Mat::from_fn(n, 1, |i, _| pseudo_random(seed, i));
            if let Some(d) = self.deflate {
                d.project(&mut x);
            }
            let norm0 = m_norm(self.m, &x);
            for _pass in 0..2 {
                self.project_out(&mut x, 0..self.v.ncols());
                let a = mw.transpose() * &x;
                x -= w.subcols(0, c) * &a;
            }
            let norm = m_norm(self.m, &x);
            if norm > 1e-10 * norm0 && norm > 0.0 {
                return Some(x * faer::Scale(1.0 / norm));
            }
        }
        None
    }

    /// The `count` lowest Ritz values of the space with their coordinates Y (the vectors are
    /// V Y, formed by `vectors` only when wanted), and whether Lanczos' own residual estimate
    /// |R U_last| puts every one below `tol` (relative to 1/lambda).
    fn ritz(&self, count: usize, tol: f64, exact: bool) -> Result<(Vec<f64>, Mat<f64>, bool)> {
        let p = self.p;
        let dim = self.dim();
        let evd = symmetric_eigen(&self.projection(), "eigensolver: the block Lanczos projection")?;
        let (s, u) = (&evd.values, &evd.vectors);
        let count = count.min(dim);
        let mut values = Vec::with_capacity(count);
        let mut y = Mat::<f64>::zeros(dim, count);
        let mut converged = true;
        let mut settled = 0;
        // largest theta = 1/lambda first
        for c in 0..count {
            let idx = dim - 1 - c;
            let theta = s[idx];
            if !(theta > 0.0) {
                return Err(BuildError::Numerical(format!("eigensolver: non-positive Ritz value {theta:e}")));
            }
            let estimate = (&self.coupling * u.submatrix(dim - p, idx, p, 1)).norm_l2();
            if !exact && estimate > tol * theta {
                converged = false;
            } else {
                settled += 1;
            }
            values.push(1.0 / theta);
            y.as_mut().col_mut(c).copy_from(u.col(idx));
        }
        crate::progress::step(|| format!("{dim} Lanczos vectors: {settled} of {count} modes converged"));
        Ok((values, y, converged))
    }

    /// The `count` lowest Ritz pairs of the held problem (rows from `first` on held) in the same
    /// space, as `ritz` gives them for the whole: coordinates Y with V Y vanishing at the held
    /// rows. With G = K^-1 E in the space (`m_g` = M G), the held operator is
    /// A_h = A - G S^-1 G^T M, so A_h V = V T' + V_next R E_last^T with T' = T - C S^-1 C^T and
    /// C = V^T M G: the held problem's projection onto the null space of the held rows of V is
    /// Z^T T' Z, and a pair's residual is |T' y - theta y| beside the coupling term, both exact in
    /// the M norm (V and V_next M-orthonormal).
    fn ritz_held(
        &self,
        first: usize,
        m_g: &Mat<f64>,
        held: &HeldSolver<'_>,
        count: usize,
        tol: f64,
        exact: bool,
    ) -> Result<(Vec<f64>, Mat<f64>, bool)> {
        let (p, dim, h) = (self.p, self.dim(), m_g.ncols());
        let v = self.v.subcols(0, dim);
        let t = self.projection();
        let c = v.transpose() * m_g;
        let mut sc = c.transpose().to_owned();
        held.compliance_solve(sc.as_mut());
        let cs = &c * &sc;
        let tp = Mat::<f64>::from_fn(dim, dim, |i, j| t[(i, j)] - 0.5 * (cs[(i, j)] + cs[(j, i)]));
        // coordinates whose vectors vanish at the held rows: the complement of the held rows'
        // span in a full QR of their transpose (G in the space gives those rows full rank)
        let q = v.subrows(first, h).transpose().to_owned().qr().compute_Q();
        let z = q.subcols(h, dim - h);
        let th = z.transpose() * &tp * z;
        let evd = symmetric_eigen(&th, "eigensolver: the held block Lanczos projection")?;
        let free = dim - h;
        let count = count.min(free);
        let mut values = Vec::with_capacity(count);
        let mut y = Mat::<f64>::zeros(dim, count);
        let mut converged = true;
        for c in 0..count {
            let idx = free - 1 - c;
            let theta = evd.values[idx];
            if !(theta > 0.0) {
                return Err(BuildError::Numerical(format!("eigensolver: non-positive held Ritz value {theta:e}")));
            }
            let yc = z * evd.vectors.col(idx).as_mat();
            let inside = (&tp * &yc - &yc * faer::Scale(theta)).norm_l2();
            let outside = (&self.coupling * yc.subrows(dim - p, p)).norm_l2();
            if !exact && inside.hypot(outside) > tol * theta {
                converged = false;
            }
            values.push(1.0 / theta);
            y.as_mut().col_mut(c).copy_from(yc.col(0));
        }
        Ok((values, y, converged))
    }

    /// The block Lanczos projection T = V^T M K^-1 M V, symmetric, from its stored blocks.
    fn projection(&self) -> Mat<f64> {
        let p = self.p;
        let dim = self.dim();
        Mat::<f64>::from_fn(dim, dim, |i, j| {
            let (bi, bj) = (i / p, j / p);
            let upper = if bi <= bj { self.t[bj][(i, j % p)] } else { 0.0 };
            let lower = if bj <= bi { self.t[bi][(j, i % p)] } else { 0.0 };
            // T is symmetric; each entry is known from both sides unless one is outside the band
            match (bi <= bj, bj <= bi) {
                (true, true) => 0.5 * (upper + lower),
                (true, false) => upper,
                _ => lower,
            }
        })
    }

    /// The Ritz vectors V Y of coordinates `y`.
    fn vectors(&self, y: &Mat<f64>) -> Mat<f64> {
        self.v.subcols(0, y.nrows()) * y
    }
}

/// A block made M-orthonormal: W = Q R, M Q alongside, and the smallest fraction of its M-norm
/// a column of W kept.
struct Orthonormal {
    q: Mat<f64>,
    mq: Mat<f64>,
    r: Mat<f64>,
    kept: f64,
}

/// Whether the second projection took at most 1e-12 of what it left from every column: `c` its
/// coefficients, `w` what it left, `mw` M w before it. |V c|_M = |c| (V is M-orthonormal) and
/// |w|_M^2 = w^T M w_before (w is M-orthogonal to V c). The 249k-DoF bracket's blocks measure
/// 3e-14 .. 1.3e-13 after the first; left in M w, so much perturbs the projection T by that
/// relative amount, a hundredth of the plain solves' 1e-10 (`extend`).
fn at_round_off(w: &Mat<f64>, mw: &Mat<f64>, c: &Mat<f64>) -> bool {
    let c2 = (0..c.ncols()).map(|j| c.col(j).iter().map(|x| x * x).sum::<f64>());
    column_dots(w, mw).into_iter().zip(c2).all(|(w2, c2)| c2 <= 1e-24 * w2)
}

/// a_c . b_c for every column c.
pub fn column_dots(a: &Mat<f64>, b: &Mat<f64>) -> Vec<f64> {
    (0..a.ncols()).map(|c| a.col(c).iter().zip(b.col(c).iter()).map(|(x, y)| x * y).sum()).collect()
}

/// Component `i` of the deterministic pseudo-random vector `seed`, in [-0.5, 0.5) (SplitMix64).
fn pseudo_random(seed: u64, i: usize) -> f64 {
    let mut z = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ (i as u64).wrapping_add(0xD1B5_4A32_D192_ED03);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^= z >> 31;
    (z >> 11) as f64 / (1u64 << 53) as f64 - 0.5
}

fn m_norm(m: &Sparse, x: &Mat<f64>) -> f64 {
    let mx = mul_new(m, x.as_ref());
    (0..x.nrows()).map(|i| x[(i, 0)] * mx[(i, 0)]).sum::<f64>().max(0.0).sqrt()
}

/// The pairs with their eigenvalues from a fresh solve (refined as the Lanczos solves were), and
/// every pair's residual in the shift-invert operator's own norm: for each column x, y = A^-1 M x (A the factored
/// K + shift M), mu = 1/theta with theta = x^T M y / x^T M x the operator's Rayleigh quotient,
/// and |x - mu y|_M / |x|_M, what the Lanczos estimate claims, measured (a solve of its own: the
/// check must not share the Lanczos solves' round-off).
///
/// Unlike |K x - lambda M x| / |K x|, the residual does not grow with cond(K) for the lowest
/// modes of slender parts, and it bounds the eigenvalue's error (relative, about its square) and
/// the vector's angle (over the gap). The quotient's error is the residual's square too (high
/// modes in x weigh 1/mu_i in it, not mu_i as in x^T K x / x^T M x), it sums M-weighted terms
/// without cancellation, and costs no product with K; the projection's own values carry the
/// Lanczos solves' round-off (2e-12 on a refined cube with plain solves).
///
/// `refine`: one refinement step for the solve. Where the Lanczos solves went without (their
/// first block's correction was below 1e-10 of the solution: 1e-12 .. 1e-11 on the tet10
/// bracket), a plain solve is as exact here, perturbing the residual by that much against the
/// accepted 1e-7; the refinement's residual and second solve cost 1.4 s of 3.1 at 249k DoFs.
fn checked(k: &dyn SpdSolve, m: &Sparse, pairs: Eigenpairs, shift: f64, refine: bool) -> (Eigenpairs, Vec<f64>) {
    let x = &pairs.vectors;
    let count = x.ncols();
    if count == 0 {
        return (pairs, Vec::new());
    }
    // at most two n x count matrices beside x at a time: M x (then the residual, then the
    // correction, in place) and y, then y (the residual x - mu y) and M y or M r
    let mut mx = mul_new(m, x.as_ref());
    let x2 = column_dots(x, &mx);
    let mut y = mx.clone();
    k.solve_plain(y.as_mut());
    if refine {
        // the correction is solved in place of M x
        k.residual(mx.as_mut(), y.as_ref());
        k.solve_plain(mx.as_mut());
        y += &mx;
    }
    drop(mx);
    // x^T M y = y^T (M x) by a product with y: M x was overwritten to save its memory
    let xmy = column_dots(x, &mul_new(m, y.as_ref()));
    let mut values = Vec::with_capacity(count);
    for c in 0..count {
        let mu = if xmy[c] > 0.0 && x2[c] > 0.0 { x2[c] / xmy[c] } else { pairs.values[c] + shift };
        values.push(mu - shift);
        // y becomes the residual x - mu y
        for (r, x) in y.col_mut(c).iter_mut().zip(x.col(c).iter()) {
            *r = x - mu * *r;
        }
    }
    let r2 = column_dots(&y, &mul_new(m, y.as_ref()));
    let residuals = (0..count)
        .map(|c| if x2[c] > 0.0 && xmy[c] > 0.0 { (r2[c].max(0.0) / x2[c]).sqrt() } else { f64::INFINITY })
        .collect();
    (Eigenpairs { values, vectors: pairs.vectors }, residuals)
}

/// `search` for a small model: every pair at once (`dense_eigen`), the wanted ones kept and
/// checked as Lanczos's are; None where the dense path does not apply (M singular).
fn dense_search(
    k: &dyn SpdSolve,
    m: &Sparse,
    want: Want,
    shift: f64,
    deflate: Option<&Deflation>,
) -> Result<Option<Eigenpairs>> {
    crate::profile::phase("eigen-solve (dense, a small model)", || {
        let n = k.n();
        let leading;
        let m = if m.nrows() > n {
            leading = crate::linalg::sparse::block(m, 0..n, 0..n)?;
            &leading
        } else {
            m
        };
        use crate::linalg::dense_eigen::{complement_basis, mass_definite};
        let basis = complement_basis(n, deflate.map(|d| d.m_vectors.as_ref()))?;
        let all = match shift_invert_ritz(k, m, basis, shift) {
            Ok(all) => all,
            // the Ritz step's mass Gram matrix is not definite: M singular (Lanczos handles it)
            Err(_) if !mass_definite(m, n) => return Ok(None),
            Err(e) => return Err(e),
        };
        let available = all.values.len();
        let keep = match want {
            Want::Lowest(c) => c.min(available),
            Want::Below { omega_max, min_count } => {
                let below = all.values.iter().filter(|&&l| l.sqrt() < omega_max).count();
                below.max(min_count).min(available).min(MAX_MODES)
            }
        };
        let pairs =
            Eigenpairs { values: all.values[..keep].to_vec(), vectors: all.vectors.subcols(0, keep).to_owned() };
        let (pairs, residuals) = checked(k, m, pairs, shift, true);
        let (worst, at) = residuals.iter().enumerate().fold((0.0f64, 0), worst_of);
        crate::profile::note(|| format!("{keep} of {available} modes, {n} DoFs"));
        if worst > RESIDUAL_TOL {
            return Err(BuildError::Numerical(format!(
                "eigensolver: mode {} of the dense solve of this {n}-DoF model has the residual {worst:.1e} \
                 (accepted {RESIDUAL_TOL:.0e}): check the mesh for extreme element proportions",
                at + 1
            )));
        }
        Ok(Some(pairs))
    })
}

/// Rayleigh-Ritz of the shift-invert operator on span(X): S = X^T M K^-1 M X (a refined solve)
/// against H = X^T M X, X Z with S z = theta H z, eigenvalues 1/theta - shift ascending.
///
/// Why: vectors accurate in the residual K x - lambda M x (a dense solver's, 2.5e-11 for a
/// beam's 18th mode) can hold a contamination by a low mode that the shift-invert residual
/// `checked` measures amplified by lambda/lambda_1 (1.2e-6 there, 5e4 times). The products of
/// this step resolve the low modes with the accuracy of the operator itself, as Lanczos does:
/// the same vectors then measure 1e-11.
fn shift_invert_ritz(k: &dyn SpdSolve, m: &Sparse, x: Mat<f64>, shift: f64) -> Result<Eigenpairs> {
    let count = x.ncols();
    if count == 0 {
        return Ok(Eigenpairs { values: Vec::new(), vectors: x });
    }
    let mx = mul_new(m, x.as_ref());
    let mut y = mx.clone();
    k.solve_refined(y.as_mut());
    let s = mx.transpose() * &y;
    let h = mx.transpose() * &x;
    drop(mx);
    drop(y);
    let sym = |a: &Mat<f64>| Mat::<f64>::from_fn(count, count, |i, j| 0.5 * (a[(i, j)] + a[(j, i)]));
    let l = sym(&h).llt(faer::Side::Lower).map_err(|_| {
        BuildError::Numerical("eigensolver: the Ritz vectors are not independent in the mass inner product".into())
    })?;
    let l = l.L().to_owned();
    // C = L^-1 S L^-T
    let mut c = sym(&s);
    faer::linalg::triangular_solve::solve_lower_triangular_in_place(l.as_ref(), c.as_mut(), faer::Par::Seq);
    let mut ct = c.transpose().to_owned();
    faer::linalg::triangular_solve::solve_lower_triangular_in_place(l.as_ref(), ct.as_mut(), faer::Par::Seq);
    let eig = symmetric_eigen(&sym(&ct), "the shift-invert Rayleigh-Ritz step")?;
    // Z = L^-T W, theta descending = lambda ascending
    let mut w = eig.vectors.clone();
    faer::linalg::triangular_solve::solve_upper_triangular_in_place(l.transpose(), w.as_mut(), faer::Par::Seq);
    let order: Vec<usize> = {
        let mut o: Vec<usize> = (0..count).collect();
        o.sort_by(|&a, &b| eig.values[b].total_cmp(&eig.values[a]));
        o
    };
    let z = Mat::<f64>::from_fn(count, count, |i, j| w[(i, order[j])]);
    let values = order.iter().map(|&j| 1.0 / eig.values[j] - shift).collect();
    Ok(Eigenpairs { values, vectors: &x * &z })
}

/// Fold step for the largest residual and its index (NaN counts as largest).
fn worst_of(worst: (f64, usize), (c, &r): (usize, &f64)) -> (f64, usize) {
    if !(r <= worst.0) { (r, c) } else { worst }
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
    use super::*;
    use crate::linalg::sparse::SpdSolver;

    /// A 3D grid: K the 7-point Laplacian plus a small diagonal, M a varying diagonal.
    fn grid(k: usize) -> (Sparse, Sparse) {
        use crate::linalg::test_grids::{diagonal, laplacian};
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
        use crate::linalg::held::HeldSolver;
        use crate::linalg::sparse::block;
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
