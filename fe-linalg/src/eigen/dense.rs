//! Small models: every pair at once, checked as Lanczos's are.

use super::checks::{checked, worst_of};
use super::shift_invert_ritz::shift_invert_ritz;
use super::{Deflation, Eigenpairs, MAX_MODES, RESIDUAL_TOL, Want};
use crate::error::{LinalgError, Result};
use crate::sparse::{Sparse, SpdSolve};

/// `search` for a small model: every pair at once (`dense_eigen`), the wanted ones kept and
/// checked as Lanczos's are; None where the dense path does not apply (M singular).
pub(super) fn dense_search(
    k: &dyn SpdSolve,
    m: &Sparse,
    want: Want,
    shift: f64,
    deflate: Option<&Deflation>,
) -> Result<Option<Eigenpairs>> {
    phases::phase("eigen-solve (dense, a small model)", || {
        let n = k.n();
        let leading;
        let m = if m.nrows() > n {
            leading = crate::sparse::block(m, 0..n, 0..n)?;
            &leading
        } else {
            m
        };
        use crate::dense_eigen::{complement_basis, mass_definite};
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
        phases::note(|| format!("{keep} of {available} modes, {n} DoFs"));
        if worst > RESIDUAL_TOL {
            return Err(LinalgError::NotConverged(format!(
                "eigensolver: mode {} of the dense solve of this {n}-DoF model has the residual {worst:.1e} \
                 (accepted {RESIDUAL_TOL:.0e}): check the mesh for extreme element proportions",
                at + 1
            )));
        }
        Ok(Some(pairs))
    })
}
