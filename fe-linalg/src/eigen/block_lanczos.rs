//! The block Lanczos space in the M inner product and its start block.

use super::Deflation;
use super::clock::Clock;
use crate::error::{LinalgError, Result};
use crate::first_touch;
use crate::held::HeldSolver;
use crate::sparse::{Sparse, SpdSolve};
use crate::symmetric_eigen::symmetric_eigen;
use crate::symmetric_product::mul_new;
use faer::Mat;
use faer::reborrow::{Reborrow, ReborrowMut};
use rayon::prelude::*;

/// Deterministic start vector with all components non-zero (no symmetry can hide a mode from it).
pub(super) fn start_vector(n: usize) -> Vec<f64> {
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

/// Columns per Lanczos block. A solve reads the whole factor from memory whatever the number of
/// right-hand sides, so a block costs less per vector: on a 249k-DoF bracket one right-hand side
/// took 0.21 s, 4 took 0.45 s, 8 0.65 s (one thread; split over two, 5 take 0.30 s and 33
/// 0.6 s, but blocks of 8 and 12 then measured no faster overall than a quarter of the modes). Larger blocks need more vectors for the same modes
/// (20 modes of the 17k-DoF bracket: 45 vectors one by one, 72 in blocks of 4, 104 in blocks of
/// 8), and the vectors' memory and re-orthogonalisation grow with them: a quarter of the modes,
/// at most 8, costs least.
pub(super) fn block_size(count: usize) -> usize {
    count.div_ceil(4).clamp(1, 8)
}

/// Deterministic start block: `start_vector` and its shuffles, every component non-zero.
pub(super) fn start_block(n: usize, p: usize) -> Mat<f64> {
    let base = start_vector(n * p);
    Mat::from_fn(n, p, |i, j| base[j * n + i])
}

/// Block Lanczos in the M inner product with full re-orthogonalisation (block classical
/// Gram-Schmidt, twice: "twice is enough"), grown a block at a time until the wanted Ritz pairs
/// converge: no restart throws computed vectors away. The projection T = V^T M K^-1 M V is
/// block tridiagonal; the coupling of the newest block to the rest bounds each pair's residual.
pub(super) struct BlockLanczos<'a> {
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
    pub(super) refine: usize,
    adaptive: bool,
    pub(super) clock: Clock,
}

impl<'a> BlockLanczos<'a> {
    /// `adaptive`: drop the refinement once a solve shows it changes nothing that matters.
    /// `reserve`: columns the space may reach, allocated at once (pages are touched only as the
    /// space grows; growing by copies cost 0.5 s per doubling at 249k DoFs).
    pub(super) fn new(
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
            None => Err(LinalgError::inconsistent("eigensolver: the mass matrix vanishes on the start vectors")),
        }
    }

    /// Vectors in the space whose projection `ritz` uses.
    pub(super) fn dim(&self) -> usize {
        self.t.len() * self.p
    }

    /// Block solves so far.
    pub(super) fn blocks(&self) -> usize {
        self.t.len()
    }

    /// One more block: W = K^-1 M V_last, orthogonalised against the space. False when the space
    /// is invariant (nothing new reachable).
    pub(super) fn extend(&mut self, k: &dyn SpdSolve) -> Result<bool> {
        if self.exhausted {
            return Ok(false);
        }
        phases::step(|| format!("{} Lanczos vectors, block solve {}", self.dim(), self.t.len() + 1));
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
    pub(super) fn project_out(&self, w: &mut Mat<f64>, range: std::ops::Range<usize>) -> (Mat<f64>, Mat<f64>) {
        let v = self.v.subcols(range.start, range.len());
        let mw = mul_new(self.m, w.as_ref());
        let c = v.transpose() * &mw;
        faer::linalg::matmul::matmul(w.as_mut(), faer::Accum::Add, v, c.as_ref(), -1.0, faer::get_global_parallelism());
        (c, mw)
    }

    /// Append a block V_b to the space (within the reserved storage as long as it lasts), with
    /// M V_b for the next block.
    pub(super) fn push(&mut self, v: &Mat<f64>, mv: Mat<f64>) {
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
    pub(super) fn orthonormalise(&self, w: Mat<f64>, mw: Mat<f64>) -> Option<(Mat<f64>, Mat<f64>, Mat<f64>)> {
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
    pub(super) fn gram_schmidt(&self, mut w: Mat<f64>, mut mw: Mat<f64>) -> Option<Orthonormal> {
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
    pub(super) fn fresh_direction(&self, w: &Mat<f64>, c: usize) -> Option<Mat<f64>> {
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
    pub(super) fn ritz(&self, count: usize, tol: f64, exact: bool) -> Result<(Vec<f64>, Mat<f64>, bool)> {
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
                return Err(LinalgError::inconsistent(format!("eigensolver: non-positive Ritz value {theta:e}")));
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
        phases::step(|| format!("{dim} Lanczos vectors: {settled} of {count} modes converged"));
        Ok((values, y, converged))
    }

    /// The `count` lowest Ritz pairs of the held problem (rows from `first` on held) in the same
    /// space, as `ritz` gives them for the whole: coordinates Y with V Y vanishing at the held
    /// rows. With G = K^-1 E in the space (`m_g` = M G), the held operator is
    /// A_h = A - G S^-1 G^T M, so A_h V = V T' + V_next R E_last^T with T' = T - C S^-1 C^T and
    /// C = V^T M G: the held problem's projection onto the null space of the held rows of V is
    /// Z^T T' Z, and a pair's residual is |T' y - theta y| beside the coupling term, both exact in
    /// the M norm (V and V_next M-orthonormal).
    pub(super) fn ritz_held(
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
                return Err(LinalgError::inconsistent(format!("eigensolver: non-positive held Ritz value {theta:e}")));
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
    pub(super) fn projection(&self) -> Mat<f64> {
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
    pub(super) fn vectors(&self, y: &Mat<f64>) -> Mat<f64> {
        self.v.subcols(0, y.nrows()) * y
    }

    /// The Ritz vectors V Y formed in the space's own storage, which they end: a block of rows
    /// of V Y needs only the same rows of V, so each block is multiplied into a small buffer and
    /// written over V's first columns, and the columns past Y's are given back to the system.
    /// `vectors` held a second n x count matrix beside the space (352 MiB for 46 vectors of
    /// 1e6 DoFs, at the eigen-solve's peak).
    pub(super) fn into_vectors(self, y: &Mat<f64>) -> Mat<f64> {
        let mut v = self.v;
        let (n, dim, count) = (v.nrows(), y.nrows(), y.ncols());
        assert!(count <= dim && dim <= v.ncols(), "{count} Ritz vectors of {dim} in a space of {}", v.ncols());
        v.truncate(n, dim);
        v.as_mut().par_row_chunks_mut(RITZ_ROWS).for_each(|rows| {
            let mut block = Mat::<f64>::zeros(rows.nrows(), count);
            faer::linalg::matmul::matmul(
                block.as_mut(),
                faer::Accum::Replace,
                rows.rb(),
                y.as_ref(),
                1.0,
                faer::Par::Seq,
            );
            rows.subcols_mut(0, count).copy_from(&block);
        });
        if dim > count {
            let stride = v.col_stride() as usize;
            // SAFETY: columns count..dim of v lie inside its allocation (stride values apart,
            // col_stride >= n), and v is truncated to its first count columns right after:
            // nothing reads them again
            unsafe { first_touch::give_back(v.as_ptr_mut().add(count * stride), (dim - count) * stride) };
        }
        v.truncate(n, count);
        v
    }
}

/// Rows of V per block of the in-place Ritz product: 256 rows of a 126-vector space and their
/// 46 products fill some 350 KB, within a core's second-level cache.
const RITZ_ROWS: usize = 256;

/// A block made M-orthonormal: W = Q R, M Q alongside, and the smallest fraction of its M-norm
/// a column of W kept.
pub(super) struct Orthonormal {
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
pub(super) fn at_round_off(w: &Mat<f64>, mw: &Mat<f64>, c: &Mat<f64>) -> bool {
    let c2 = (0..c.ncols()).map(|j| c.col(j).iter().map(|x| x * x).sum::<f64>());
    column_dots(w, mw).into_iter().zip(c2).all(|(w2, c2)| c2 <= 1e-24 * w2)
}

/// a_c . b_c for every column c.
pub fn column_dots(a: &Mat<f64>, b: &Mat<f64>) -> Vec<f64> {
    (0..a.ncols()).map(|c| a.col(c).iter().zip(b.col(c).iter()).map(|(x, y)| x * y).sum()).collect()
}

/// Component `i` of the deterministic pseudo-random vector `seed`, in [-0.5, 0.5) (SplitMix64).
pub(super) fn pseudo_random(seed: u64, i: usize) -> f64 {
    let mut z = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ (i as u64).wrapping_add(0xD1B5_4A32_D192_ED03);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^= z >> 31;
    (z >> 11) as f64 / (1u64 << 53) as f64 - 0.5
}

pub(super) fn m_norm(m: &Sparse, x: &Mat<f64>) -> f64 {
    let mx = mul_new(m, x.as_ref());
    (0..x.nrows()).map(|i| x[(i, 0)] * mx[(i, 0)]).sum::<f64>().max(0.0).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sparse::SpdSolver;
    use crate::test_grids::{diagonal, laplacian};

    /// The Ritz vectors formed in the space's storage equal those formed beside it (the same
    /// products, summed by another blocking), over several row blocks and a block's remainder: a
    /// consistency check of the storage, not of the modes (those are checked against CalculiX
    /// and beam theory in the Python tests).
    #[test]
    fn ritz_vectors_in_place_equal_the_product_beside_the_space() {
        let k = laplacian(11, |_| 6.01);
        let m = diagonal(11, |i| 1.0 + 0.25 * (i % 3) as f64);
        let n = k.nrows();
        assert!(n > 4 * RITZ_ROWS && n % RITZ_ROWS != 0, "{n} rows: several blocks and a remainder");
        let name = |d: usize| format!("row {d}");
        let solver = SpdSolver::new(std::borrow::Cow::Owned(k), "grid", &name).unwrap();
        let mut lanczos = BlockLanczos::new(&m, &start_block(n, 3), None, true, 40).unwrap();
        for _ in 0..8 {
            assert!(lanczos.extend(&solver).unwrap());
        }
        let dim = lanczos.dim();
        assert_eq!(dim, 24);
        let y = Mat::<f64>::from_fn(dim, 7, |i, j| pseudo_random(j as u64, i));
        let beside = lanczos.vectors(&y);
        let in_place = lanczos.into_vectors(&y);
        assert_eq!((in_place.nrows(), in_place.ncols()), (n, 7));
        let scale = beside.norm_max();
        let worst = (&in_place - &beside).norm_max() / scale;
        println!("Ritz vectors in place vs beside the space: {worst:.1e} of the largest entry");
        // the same 24-term sums (measured 0: the same bits here); a few ulps are allowed where
        // the product's kernel blocks the sums otherwise for another shape or CPU
        assert!(worst <= 1e-15, "in place vs beside: {worst:e}");
    }
}
