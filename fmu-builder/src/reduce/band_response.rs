//! The full model's response to the unit flange loads over a band, without a complex
//! factorisation per frequency: the dynamic stiffness Z(w) = a K + c M (a = 1 + i eta + i w beta,
//! c = i w alpha - w^2) is inverted exactly on the full model's modes below twice the band's top
//! (modal superposition: they diagonalise K and M), and on their M-orthogonal complement by a
//! Galerkin projection on the block Krylov space of K^-1 M started from the loads' static
//! response. On that complement K^-1 M has eigenvalues at most 1 / lambda_cut, so Z^-1 is a
//! Neumann series in c / (a lambda) of ratio at most (w_top / w_cut)^2 = 1/4: each block gains
//! that factor, and the blocks grow until the response at the band's top stops changing
//! (1e-13). Every frequency then costs a dense solve of the projection's order; the whole band
//! costs one eigen-solve and a few block solves with the one real factor the build has.

use crate::error::Result;
use crate::linalg::eigen;
use crate::linalg::sparse::{Sparse, SpdSolve};
use crate::linalg::symmetric_product;
use crate::model::rigid_coupling::Assembled;
use crate::reduce::basis::{EIGEN_TOL, flange_unit_load_rows, flange_unit_loads};
use crate::reduce::damping::ComparisonDamping;
use faer::linalg::matmul;
use faer::linalg::solvers::Solve;
use faer::reborrow::{Reborrow, ReborrowMut};
use faer::{Accum, ColRef, Mat, MatMut, MatRef, c64};
use std::borrow::Cow;

fn dot(a: ColRef<'_, f64>, b: ColRef<'_, f64>) -> f64 {
    a.iter().zip(b.iter()).map(|(x, y)| x * y).sum()
}

/// w -= V (V^T M w), given M w: w made M-orthogonal to V's M-orthonormal columns.
fn project_out(w: MatMut<'_, f64>, v: MatRef<'_, f64>, mw: MatRef<'_, f64>) {
    let c = v.transpose() * mw;
    matmul::matmul(w, Accum::Add, v, c.as_ref(), -1.0, faer::get_global_parallelism());
}

/// Ratio of the cut to the band's top for a named band: the modes below it are exact, the
/// Neumann ratio of the rest is at most its inverse squared.
pub const CUT: f64 = 2.0;
/// Most modes below the cut this method takes (beyond, the direct solve per frequency).
pub const MAX_MODES: usize = 300;
/// Most Krylov blocks.
const MAX_BLOCKS: usize = 40;
/// Relative change of the response at the band's top below which the space is complete.
const SETTLED: f64 = 1e-12;

/// What the build already has of the full model, so the band method need not compute it again.
#[derive(Clone, Copy, Default)]
pub struct Known<'a> {
    /// The lowest modes, used where they reach the cut (then no eigen-solve).
    pub modes: Option<&'a eigen::Eigenpairs>,
    /// K^-1 B for the unit flange loads: the Krylov space's first block (then no solve).
    pub static_response: Option<&'a Mat<f64>>,
}

pub struct BandResponse<'a> {
    /// Full modes below the cut: the first `lambda.len()` columns of `phi` (M-orthonormal,
    /// borrowed where the build computed them) and their eigenvalues.
    lambda: Vec<f64>,
    phi: Cow<'a, Mat<f64>>,
    /// M-orthonormal basis of the complement's Krylov space, block by block (n x m in all),
    /// and Q^T K Q.
    q: Vec<Mat<f64>>,
    kq: Mat<f64>,
    /// Phi^T B and Q^T B.
    phi_b: Mat<f64>,
    q_b: Mat<f64>,
    /// Blocks the space took.
    pub blocks: usize,
    pub modes: usize,
}

impl<'a> BandResponse<'a> {
    /// None where more than `MAX_MODES` modes lie below the cut.
    pub fn new(
        model: &Assembled,
        k: &dyn SpdSolve,
        top_hz: f64,
        damping: ComparisonDamping,
        known: Known<'a>,
        cut: f64,
    ) -> Result<Option<Self>> {
        let m = &model.mass;
        let omega_cut = 2.0 * std::f64::consts::PI * top_hz.max(1e-9) * cut;
        let reach = |e: &eigen::Eigenpairs| {
            e.vectors.ncols() == e.values.len()
                && e.vectors.nrows() == k.n()
                && e.values.last().is_some_and(|&l| l.sqrt() >= omega_cut * (1.0 - 1e-12))
        };
        let (lambda, phi) = match known.modes {
            Some(e) if reach(e) => {
                let count = e.values.iter().take_while(|&&l| l.sqrt() < omega_cut).count();
                (e.values[..count].to_vec(), Cow::Borrowed(&e.vectors))
            }
            _ => {
                let modes = eigen::below(k, m, omega_cut, 1, EIGEN_TOL)?;
                (modes.values, Cow::Owned(modes.vectors))
            }
        };
        if lambda.len() > MAX_MODES {
            return Ok(None);
        }
        let rows = flange_unit_load_rows(model);
        let nb = rows.len();
        let phi_b = Mat::from_fn(lambda.len(), nb, |i, j| phi[(rows[j], i)]);
        let mut this = Self {
            modes: lambda.len(),
            lambda,
            phi,
            phi_b,
            q: Vec::new(),
            kq: Mat::zeros(0, 0),
            q_b: Mat::zeros(0, nb),
            blocks: 0,
        };
        // the complement's Krylov space, block by block, until the response at the top settles;
        // plain solves: the projection is a Galerkin one on whatever space the blocks span (its
        // K and M exact), so round-off in the blocks costs nothing but the space's reach
        let mut block = match known.static_response {
            Some(g) if g.nrows() == k.n() && g.ncols() == nb => g.clone(),
            _ => {
                let mut g = flange_unit_loads(model);
                k.solve_plain(g.as_mut());
                g
            }
        };
        let mut previous: Option<Mat<c64>> = None;
        for _ in 0..MAX_BLOCKS {
            let Some((fresh, m_fresh)) = this.orthonormal_block(m, block) else { break };
            this.append(k, fresh, &rows);
            this.blocks += 1;
            let (y, w) = this.coefficients(damping, top_hz);
            let now = this.rows_of(&rows, &y, &w);
            if let Some(prev) = &previous {
                let (mut num, mut den) = (0.0, 0.0);
                for i in 0..now.nrows() {
                    for j in 0..now.ncols() {
                        num += (now[(i, j)] - prev[(i, j)]).norm_sqr();
                        den += now[(i, j)].norm_sqr();
                    }
                }
                if num <= SETTLED * SETTLED * den {
                    break;
                }
            }
            previous = Some(now);
            // the next block from this one: K^-1 M V
            block = m_fresh;
            k.solve_plain(block.as_mut());
        }
        Ok(Some(this))
    }

    fn phi(&self) -> MatRef<'_, f64> {
        self.phi.subcols(0, self.lambda.len())
    }

    /// `w` made M-orthogonal to the modes and to the space (twice), M-orthonormal within (by
    /// Gram-Schmidt, dropping what is already spanned), with M times it; None when nothing is
    /// left.
    fn orthonormal_block(&self, m: &Sparse, mut w: Mat<f64>) -> Option<(Mat<f64>, Mat<f64>)> {
        // one buffer for M w and the projections in place: no n x block temporaries (fresh
        // pages cost more than these products)
        let mut mw = Mat::<f64>::zeros(w.nrows(), w.ncols());
        for _ in 0..2 {
            symmetric_product::mul(mw.as_mut(), m, w.as_ref());
            project_out(w.as_mut(), self.phi(), mw.as_ref());
            for v in &self.q {
                project_out(w.as_mut(), v.as_ref(), mw.as_ref());
            }
        }
        symmetric_product::mul(mw.as_mut(), m, w.as_ref());
        // within the block: modified Gram-Schmidt twice, M w updated alongside
        let scale = (0..w.ncols()).map(|j| dot(w.col(j), mw.col(j))).fold(0.0f64, f64::max).sqrt();
        let mut kept: Vec<usize> = Vec::new();
        for j in 0..w.ncols() {
            // the kept columns lie left of j
            let (w_done, mut w_rest) = w.as_mut().split_at_col_mut(j);
            let (mw_done, mut mw_rest) = mw.as_mut().split_at_col_mut(j);
            let (mut wj, mut mwj) = (w_rest.rb_mut().col_mut(0), mw_rest.rb_mut().col_mut(0));
            for _ in 0..2 {
                for &u in &kept {
                    let a = dot(mw_done.rb().col(u), wj.rb());
                    wj.rb_mut().iter_mut().zip(w_done.rb().col(u).iter()).for_each(|(x, y)| *x -= a * y);
                    mwj.rb_mut().iter_mut().zip(mw_done.rb().col(u).iter()).for_each(|(x, y)| *x -= a * y);
                }
            }
            let norm = dot(wj.rb(), mwj.rb()).max(0.0).sqrt();
            if norm > 1e-10 * scale && norm > 0.0 {
                wj.iter_mut().for_each(|x| *x /= norm);
                mwj.iter_mut().for_each(|x| *x /= norm);
                kept.push(j);
            }
        }
        if kept.is_empty() {
            return None;
        }
        if kept.len() == w.ncols() {
            return Some((w, mw));
        }
        let pick = |a: &Mat<f64>| Mat::from_fn(a.nrows(), kept.len(), |i, j| a[(i, kept[j])]);
        Some((pick(&w), pick(&mw)))
    }

    /// Append the block `v` to Q, extending Q^T K Q (K v by the factor's matrix: a compensated
    /// product through the solver's residual) and Q^T B (B's columns are unit loads at `rows`).
    fn append(&mut self, k: &dyn SpdSolve, v: Mat<f64>, rows: &[usize]) {
        let old = self.kq.nrows();
        let add = v.ncols();
        // K v = -(0 - K v): the solver's residual of x = v against b = 0
        let mut kv = Mat::<f64>::zeros(v.nrows(), add);
        k.residual(kv.as_mut(), v.as_ref());
        let mut kq = Mat::<f64>::zeros(old + add, old + add);
        kq.as_mut().submatrix_mut(0, 0, old, old).copy_from(&self.kq);
        let mut at = 0;
        for block in self.q.iter().chain(std::iter::once(&v)) {
            let cross = block.transpose() * &kv; // block's columns x add, of -K
            for i in 0..block.ncols() {
                for j in 0..add {
                    kq[(at + i, old + j)] = -cross[(i, j)];
                    kq[(old + j, at + i)] = -cross[(i, j)];
                }
            }
            at += block.ncols();
        }
        let mut q_b = Mat::<f64>::zeros(old + add, self.q_b.ncols());
        q_b.as_mut().subrows_mut(0, old).copy_from(&self.q_b);
        for i in 0..add {
            for (j, &r) in rows.iter().enumerate() {
                q_b[(old + i, j)] = v[(r, i)];
            }
        }
        self.q.push(v);
        self.kq = kq;
        self.q_b = q_b;
    }

    /// The response's coordinates at `hz` on the modes (k x nb) and on the complement's basis
    /// (m x nb): x = Phi y + Q w.
    pub fn coefficients(&self, damping: ComparisonDamping, hz: f64) -> (Mat<c64>, Mat<c64>) {
        let w = 2.0 * std::f64::consts::PI * hz;
        let a = c64::new(1.0, damping.loss_factor + w * damping.beta);
        let c = c64::new(-w * w, w * damping.alpha);
        let nb = self.phi_b.ncols();
        // modes: y_k = phi_k^T b / (a lambda_k + c)
        let y = Mat::<c64>::from_fn(self.lambda.len(), nb, |kk, j| {
            c64::new(self.phi_b[(kk, j)], 0.0) / (a * self.lambda[kk] + c)
        });
        // complement: (a Q^T K Q + c I) w = Q^T b
        let mq = self.kq.nrows();
        let wq = if mq > 0 {
            let z =
                Mat::<c64>::from_fn(mq, mq, |i, j| a * self.kq[(i, j)] + if i == j { c } else { c64::new(0.0, 0.0) });
            let rhs = Mat::<c64>::from_fn(mq, nb, |i, j| c64::new(self.q_b[(i, j)], 0.0));
            z.partial_piv_lu().solve(&rhs)
        } else {
            Mat::zeros(0, nb)
        };
        (y, wq)
    }

    /// Rows `rows` of x = Phi y + Q w (rows x nb).
    pub fn rows_of(&self, rows: &[usize], y: &Mat<c64>, w: &Mat<c64>) -> Mat<c64> {
        let phi = self.phi();
        Mat::from_fn(rows.len(), y.ncols(), |i, j| {
            let r = rows[i];
            let mut s = c64::new(0.0, 0.0);
            for kk in 0..y.nrows() {
                s += y[(kk, j)] * phi[(r, kk)];
            }
            let mut kk = 0;
            for v in &self.q {
                for c in 0..v.ncols() {
                    s += w[(kk, j)] * v[(r, c)];
                    kk += 1;
                }
            }
            s
        })
    }

    /// [Phi Q]: the columns x is combined from (for quantities linear in x, as stresses).
    pub fn columns(&self) -> Mat<f64> {
        let (n, k) = (self.phi.nrows(), self.lambda.len());
        let mut out = Mat::<f64>::zeros(n, k + self.kq.nrows());
        out.as_mut().subcols_mut(0, k).copy_from(self.phi());
        let mut at = k;
        for v in &self.q {
            out.as_mut().subcols_mut(at, v.ncols()).copy_from(v);
            at += v.ncols();
        }
        out
    }
}
