//! The damping of the reduced coordinates: the input's modal ratios per mode, plus the diagonal
//! of a user damping matrix projected on the basis.

use crate::error::Result;
use crate::input::spec::Spec;
use crate::linalg::sparse;
use crate::model::rigid_coupling::Assembled;
use crate::reduce::basis::Basis;
use serde::Serialize;

/// 2 zeta_k omega_k per mode from the input's modal damping ratios.
pub fn modal_damping(spec: &Spec, omega: &[f64]) -> Vec<f64> {
    omega.iter().map(|w| 2.0 * spec.damping.modal_ratio_at(w / (2.0 * std::f64::consts::PI)) * w).collect()
}

/// Modal damping plus the diagonal of Phi^T D Phi for a user damping matrix D (matrix input).
/// The off-diagonal coupling is dropped: the runtime integrates decoupled modes. Rayleigh-like
/// D projects exactly diagonal on our K- and M-orthogonal basis.
pub fn with_user_damping(mut modal: Vec<f64>, model: &Assembled, basis: &Basis) -> Result<Vec<f64>> {
    let Some(d) = &model.damping else {
        return Ok(modal);
    };
    let n = basis.phi.nrows();
    let d = sparse::block(d, 0..n, 0..n)?;
    let dphi = sparse::mul_new(&d, basis.phi.as_ref());
    for (k, m) in modal.iter_mut().enumerate() {
        *m += (0..n).map(|i| basis.phi[(i, k)] * dphi[(i, k)]).sum::<f64>();
    }
    Ok(modal)
}

/// The damping both models are compared with: the input's Rayleigh damping, or a 1 % structural
/// loss factor when it has none (an undamped response is infinite at the eigenfrequencies).
#[derive(Debug, Clone, Copy, Serialize)]
pub struct ComparisonDamping {
    pub alpha: f64,
    pub beta: f64,
    pub loss_factor: f64,
}

impl ComparisonDamping {
    pub fn new(alpha: f64, beta: f64) -> Self {
        if alpha == 0.0 && beta == 0.0 {
            Self { alpha, beta, loss_factor: 0.01 }
        } else {
            Self { alpha, beta, loss_factor: 0.0 }
        }
    }
}
