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
use crate::linalg::sparse::{Sparse, SpdSolve, mul_leading};
use crate::model::rigid_coupling::Assembled;
use crate::reduce::basis::{EIGEN_TOL, flange_unit_loads};
use crate::reduce::damping::ComparisonDamping;
use faer::linalg::solvers::Solve;
use faer::{Mat, c64};

/// Ratio of the cut to the band's top for a named band: the modes below it are exact, the
/// Neumann ratio of the rest is at most its inverse squared.
pub const CUT: f64 = 2.0;
/// Most modes below the cut this method takes (beyond, the direct solve per frequency).
pub const MAX_MODES: usize = 300;
/// Most Krylov blocks.
const MAX_BLOCKS: usize = 40;
/// Relative change of the response at the band's top below which the space is complete.
const SETTLED: f64 = 1e-12;

pub struct BandResponse {
    /// Full modes below the cut (n x k, M-orthonormal) and their eigenvalues.
    lambda: Vec<f64>,
    phi: Mat<f64>,
    /// M-orthonormal basis of the complement's Krylov space (n x m) and Q^T K Q.
    q: Mat<f64>,
    kq: Mat<f64>,
    /// Phi^T B and Q^T B.
    phi_b: Mat<f64>,
    q_b: Mat<f64>,
    /// Blocks the space took.
    pub blocks: usize,
    pub modes: usize,
}

impl BandResponse {
    /// None where more than `MAX_MODES` modes lie below the cut. `known`: the full model's
    /// lowest modes where computed already (used when they reach the cut: no eigen-solve).
    pub fn new(
        model: &Assembled,
        k: &dyn SpdSolve,
        top_hz: f64,
        damping: ComparisonDamping,
        known: Option<&eigen::Eigenpairs>,
        cut: f64,
    ) -> Result<Option<Self>> {
        let m = &model.mass;
        let omega_cut = 2.0 * std::f64::consts::PI * top_hz.max(1e-9) * cut;
        let reach = |e: &eigen::Eigenpairs| {
            e.vectors.ncols() == e.values.len()
                && e.vectors.nrows() == k.n()
                && e.values.last().is_some_and(|&l| l.sqrt() >= omega_cut * (1.0 - 1e-12))
        };
        let modes = match known {
            Some(e) if reach(e) => {
                let count = e.values.iter().take_while(|&&l| l.sqrt() < omega_cut).count();
                eigen::Eigenpairs {
                    values: e.values[..count].to_vec(),
                    vectors: e.vectors.subcols(0, count).to_owned(),
                }
            }
            _ => eigen::below(k, m, omega_cut, 1, EIGEN_TOL)?,
        };
        if modes.values.len() > MAX_MODES {
            return Ok(None);
        }
        let b = flange_unit_loads(model);
        let rows: Vec<usize> =
            (0..b.ncols()).map(|j| (0..b.nrows()).find(|&i| b[(i, j)] != 0.0).unwrap_or(0)).collect();
        let phi = modes.vectors;
        let phi_b = phi.transpose() * &b;
        let mut this = Self {
            lambda: modes.values,
            phi_b,
            q: Mat::zeros(b.nrows(), 0),
            kq: Mat::zeros(0, 0),
            q_b: Mat::zeros(0, b.ncols()),
            phi,
            blocks: 0,
            modes: 0,
        };
        this.modes = this.lambda.len();
        // the complement's Krylov space, block by block, until the response at the top settles
        // plain solves: the projection is a Galerkin one on whatever space the blocks span (its
        // K and M exact), so round-off in the blocks costs nothing but the space's reach
        let mut block = b.clone();
        k.solve_plain(block.as_mut());
        let mut previous: Option<Mat<c64>> = None;
        for _ in 0..MAX_BLOCKS {
            let Some(fresh) = this.orthonormal_block(m, block) else { break };
            // next block from this one: K^-1 M V
            let mut next = mul_leading(m, fresh.as_ref(), false);
            k.solve_plain(next.as_mut());
            this.append(m, k, &fresh, &b);
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
            block = next;
        }
        Ok(Some(this))
    }

    /// `w` made M-orthogonal to the modes and to the space (twice), M-orthonormal within (by
    /// Gram-Schmidt, dropping what is already spanned); None when nothing is left.
    fn orthonormal_block(&self, m: &Sparse, mut w: Mat<f64>) -> Option<Mat<f64>> {
        for _ in 0..2 {
            let mw = mul_leading(m, w.as_ref(), false);
            let c = self.phi.transpose() * &mw;
            w -= &self.phi * &c;
            let c = self.q.transpose() * &mw;
            w -= &self.q * &c;
        }
        // within the block: modified Gram-Schmidt twice, M w updated alongside (one product
        // with M for the block)
        let mut mw = mul_leading(m, w.as_ref(), false);
        let scale = (0..w.ncols())
            .map(|j| w.col(j).iter().zip(mw.col(j).iter()).map(|(a, b)| a * b).sum::<f64>())
            .fold(0.0f64, f64::max)
            .sqrt();
        let mut kept: Vec<usize> = Vec::new();
        for j in 0..w.ncols() {
            for _ in 0..2 {
                for &u in &kept {
                    let a: f64 = mw.col(u).iter().zip(w.col(j).iter()).map(|(x, y)| x * y).sum();
                    let (wu, mwu) = (w.col(u).to_owned(), mw.col(u).to_owned());
                    w.col_mut(j).iter_mut().zip(wu.iter()).for_each(|(x, y)| *x -= a * y);
                    mw.col_mut(j).iter_mut().zip(mwu.iter()).for_each(|(x, y)| *x -= a * y);
                }
            }
            let norm = w.col(j).iter().zip(mw.col(j).iter()).map(|(x, y)| x * y).sum::<f64>().max(0.0).sqrt();
            if norm > 1e-10 * scale && norm > 0.0 {
                w.col_mut(j).iter_mut().for_each(|x| *x /= norm);
                mw.col_mut(j).iter_mut().for_each(|x| *x /= norm);
                kept.push(j);
            }
        }
        if kept.is_empty() {
            return None;
        }
        let mut out = Mat::zeros(w.nrows(), kept.len());
        for (j, &c) in kept.iter().enumerate() {
            out.as_mut().col_mut(j).copy_from(w.col(c));
        }
        Some(out)
    }

    /// Append the block `v` to Q, extending Q^T K Q (K v by the factor's matrix: a compensated
    /// product through the solver's residual) and Q^T B.
    fn append(&mut self, _m: &Sparse, k: &dyn SpdSolve, v: &Mat<f64>, b: &Mat<f64>) {
        let (n, old) = (self.q.nrows(), self.q.ncols());
        let add = v.ncols();
        // K v = -(0 - K v): the solver's residual of x = v against b = 0
        let mut kv = Mat::<f64>::zeros(n, add);
        k.residual(kv.as_mut(), v.as_ref());
        let kv = kv * faer::Scale(-1.0);
        let mut q = Mat::<f64>::zeros(n, old + add);
        q.as_mut().subcols_mut(0, old).copy_from(&self.q);
        q.as_mut().subcols_mut(old, add).copy_from(v);
        let cross = q.transpose() * &kv; // (old + add) x add
        let mut kq = Mat::<f64>::zeros(old + add, old + add);
        kq.as_mut().submatrix_mut(0, 0, old, old).copy_from(&self.kq);
        for i in 0..old + add {
            for j in 0..add {
                kq[(i, old + j)] = cross[(i, j)];
                kq[(old + j, i)] = cross[(i, j)];
            }
        }
        self.q = q;
        self.kq = kq;
        self.q_b = self.q.transpose() * b;
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
        let mq = self.q.ncols();
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
        Mat::from_fn(rows.len(), y.ncols(), |i, j| {
            let r = rows[i];
            let mut s = c64::new(0.0, 0.0);
            for kk in 0..y.nrows() {
                s += y[(kk, j)] * self.phi[(r, kk)];
            }
            for kk in 0..w.nrows() {
                s += w[(kk, j)] * self.q[(r, kk)];
            }
            s
        })
    }

    /// [Phi Q]: the columns x is combined from (for quantities linear in x, as stresses).
    pub fn columns(&self) -> Mat<f64> {
        let (n, k, m) = (self.phi.nrows(), self.phi.ncols(), self.q.ncols());
        let mut out = Mat::<f64>::zeros(n, k + m);
        out.as_mut().subcols_mut(0, k).copy_from(&self.phi);
        out.as_mut().subcols_mut(k, m).copy_from(&self.q);
        out
    }
}
