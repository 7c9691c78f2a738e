//! What the reduction costs in accuracy, measured against the full FE model on the same mesh:
//! eigenfrequencies (full vs reduced, mounted or free-free) and the static compliance of the
//! force flanges (full sparse solve vs reduced model), and the checks every build must pass
//! before it becomes an FMU.

use crate::error::{BuildError, Result};
use crate::linalg::eigen::{self, Deflation};
use crate::linalg::sparse::SpdSolver;
use crate::model::rigid_coupling::Assembled;
use crate::reduce::basis::{self, Basis, EIGEN_TOL};
use faer::Mat;
use serde::Serialize;

#[derive(Debug, Clone, Serialize)]
pub struct Accuracy {
    /// Eigenfrequencies of the mounted body [Hz], reduced and full, lowest first.
    pub reduced_hz: Vec<f64>,
    pub full_hz: Vec<f64>,
    pub relative_error: Vec<f64>,
    /// Force flanges in the order of the compliance rows (6 per flange: u_x..z, phi_x..z).
    pub compliance_flanges: Vec<String>,
    /// Static compliance [m/N, rad/(N m), ...] of the force flanges, full model, row-major.
    pub compliance_full: Vec<Vec<f64>>,
    pub compliance_reduced: Vec<Vec<f64>>,
    /// max |C_red - C_full| / max |C_full|
    pub compliance_max_relative_error: f64,
    /// The scene's unit inertial load cases (e.g. "translation x", "centrifugal xy") and, per case,
    /// the full model's static displacement of the force flanges (6 per flange, as the compliance
    /// rows): what the FMU must reproduce exactly in statics.
    pub inertial_cases: Vec<String>,
    pub inertial_flange_response_full: Vec<Vec<f64>>,
    /// Flange transfer functions full vs reduced over the band (mounted bodies with force flanges).
    pub frequency_response: Option<crate::reduce::frf::FrequencyResponse>,
    /// Each reduced mode with the full mode its shape resembles most (modal assurance criterion),
    /// where the full modes' shapes were computed.
    pub pairs: Vec<ModePair>,
}

/// A reduced mode and the full mode of the most similar shape.
#[derive(Debug, Clone, Serialize)]
pub struct ModePair {
    /// 1-based mode numbers.
    pub reduced: usize,
    /// None: no computed full mode resembles it (MAC below `MAC_PAIRED`): the reduced mode lies
    /// beyond the frequencies the model represents (a constraint or residual-flexibility mode).
    pub full: Option<usize>,
    pub mac: f64,
    pub reduced_hz: f64,
    pub full_hz: Option<f64>,
    pub relative_error: Option<f64>,
}

/// Least modal assurance criterion for a reduced mode to be the same as a full mode.
pub const MAC_PAIRED: f64 = 0.9;

/// Pairs by the modal assurance criterion MAC_ij = (phi_i^T M x_j)^2 (both M-normalised):
/// `phi` the reduced modes on the constrained DoFs, `full` the full model's modes.
pub fn mac_pairs(model: &Assembled, basis: &Basis, full: &eigen::Eigenpairs) -> Vec<ModePair> {
    let (r, k) = (basis.omega.len(), full.values.len());
    if k == 0 || full.vectors.ncols() != k || full.vectors.nrows() != basis.phi.nrows() {
        return Vec::new();
    }
    let m_full = crate::linalg::sparse::mul_leading(&model.mass, full.vectors.as_ref(), false);
    let c = basis.phi.transpose() * &m_full;
    let two_pi = 2.0 * std::f64::consts::PI;
    (0..r)
        .map(|i| {
            let (j, mac) =
                (0..k).map(|j| (j, c[(i, j)] * c[(i, j)])).fold((0, 0.0), |b, x| if x.1 > b.1 { x } else { b });
            let reduced_hz = basis.omega[i] / two_pi;
            let paired = mac >= MAC_PAIRED;
            let full_hz = paired.then(|| full.values[j].max(0.0).sqrt() / two_pi);
            ModePair {
                reduced: i + 1,
                full: paired.then_some(j + 1),
                mac,
                reduced_hz,
                full_hz,
                relative_error: full_hz.map(|f| (reduced_hz - f) / f),
            }
        })
        .collect()
}

/// Full-vs-reduced comparison. `n_full` eigenfrequencies of the full clamped model are computed.
/// `solver` factors the stiffness of the mounted body (mount held); `flange_shapes` is its
/// refined static response to unit loads at the force flanges (`basis::flange_unit_loads`, the
/// flanges in the order of `force_flanges`). `computed`: the full model's lowest modes where the
/// reduction computed them already (`basis::craig_bampton`), used when there are enough.
pub fn accuracy(
    model: &Assembled,
    solver: &SpdSolver,
    flange_shapes: &Mat<f64>,
    basis: &Basis,
    force_flanges: &[(String, usize)],
    n_full: usize,
    computed: Option<eigen::Eigenpairs>,
) -> Result<(Accuracy, eigen::Eigenpairs)> {
    let nc = model.dofs.n_clamped();
    let full = match computed {
        Some(full) if full.values.len() >= n_full => full,
        _ => eigen::lowest(solver, &model.mass, n_full, EIGEN_TOL)?,
    };
    let pairs = mac_pairs(model, basis, &full);
    let full_values = full.values[..n_full.min(full.values.len())].to_vec();
    let two_pi = 2.0 * std::f64::consts::PI;
    let full_hz: Vec<f64> = full_values.iter().map(|l| l.sqrt() / two_pi).collect();
    let reduced_hz: Vec<f64> = basis.omega.iter().map(|w| w / two_pi).collect();
    let relative_error = reduced_hz.iter().zip(&full_hz).map(|(r, f)| (r - f) / f).collect();

    // static compliance: B^T K^-1 B with B the unit loads at the force flanges' master DoFs
    let x = flange_shapes;
    if x.nrows() != nc || x.ncols() != 6 * force_flanges.len() {
        return Err(BuildError::internal(format!(
            "accuracy comparison: {} x {} flange shapes for {nc} DoFs and {} force flanges",
            x.nrows(),
            x.ncols(),
            force_flanges.len()
        )));
    }
    let rows: Vec<usize> = force_flanges.iter().flat_map(|(_, first)| (0..6).map(move |i| first + i)).collect();
    let (compliance_full, compliance_reduced, compliance_max_relative_error) = compare_compliance(&rows, x, basis);
    let accuracy = Accuracy {
        reduced_hz,
        full_hz,
        relative_error,
        compliance_flanges: force_flanges.iter().map(|(n, _)| n.clone()).collect(),
        compliance_full,
        compliance_reduced,
        compliance_max_relative_error,
        inertial_cases: Vec::new(),
        inertial_flange_response_full: Vec::new(),
        frequency_response: None,
        pairs,
    };
    Ok((accuracy, full))
}

/// Full compliance (rows of the static responses `x` at the flange DoFs `rows`) against the
/// reduced model's Phi_b diag(1/omega^2) Phi_b^T, and their largest deviation relative to the
/// largest full entry.
pub fn compare_compliance(rows: &[usize], x: &Mat<f64>, basis: &Basis) -> (Vec<Vec<f64>>, Vec<Vec<f64>>, f64) {
    let full: Vec<Vec<f64>> = rows.iter().map(|&r| (0..rows.len()).map(|c| x[(r, c)]).collect()).collect();
    let reduced: Vec<Vec<f64>> = rows
        .iter()
        .map(|&r| {
            rows.iter()
                .map(|&c| {
                    (0..basis.omega.len()).map(|j| basis.phi[(r, j)] * basis.phi[(c, j)] / basis.omega[j].powi(2)).sum()
                })
                .collect()
        })
        .collect();
    let scale = full.iter().flatten().fold(0.0f64, |a, v| a.max(v.abs()));
    let diff = full.iter().flatten().zip(reduced.iter().flatten()).fold(0.0f64, |a, (f, r)| a.max((f - r).abs()));
    (full, reduced, if scale > 0.0 { diff / scale } else { 0.0 })
}

/// A reduced eigenfrequency may lie below the full model's by no more than this (relative):
/// the reduced frequencies come from a dense eigensolve with absolute error eps |K_r|, which for
/// the spread of a many-mode basis (1e9) is 1e-7 of the lowest eigenvalue; a lost Rayleigh-Ritz
/// bound, as the failure this check guards against, shows as 1e-3 .. 1e-2.
pub const RAYLEIGH_RITZ_TOL: f64 = 1e-6;

/// Largest accepted deviation of the reduced static flange compliance from the full model's,
/// relative to its largest entry. Every basis contains the flange loads' static shapes, so the
/// deviation is round-off (measured 7e-14 .. 3e-13 on the beams with 12 .. 600 modes, whose
/// cond(K) ~ 1e10; left room for worse-conditioned parts); a dropped static direction shows
/// as 1e-4 and more.
pub const COMPLIANCE_TOL: f64 = 1e-8;

/// The checks every build must pass before it becomes an FMU: a Galerkin projection never lowers
/// an eigenvalue (reduced >= full, mode by mode), and static flange loads are exact. A failure is
/// an error with the figures, never a wrong FMU.
pub fn enforce(accuracy: &Accuracy) -> Result<()> {
    let n = accuracy.reduced_hz.len().min(accuracy.full_hz.len());
    let below: Vec<usize> =
        (0..n).filter(|&i| accuracy.reduced_hz[i] < accuracy.full_hz[i] * (1.0 - RAYLEIGH_RITZ_TOL)).collect();
    if let Some(&i) = below.first() {
        return Err(BuildError::inaccurate(format!(
            "the reduced model is not a valid projection of the FE model: {} of its {n} lowest frequencies lie below the full model's (mode {}: {:.6} Hz reduced vs {:.6} Hz full); the reduction basis lost accuracy, no FMU was written",
            below.len(),
            i + 1,
            accuracy.reduced_hz[i],
            accuracy.full_hz[i]
        )));
    }
    let e = accuracy.compliance_max_relative_error;
    if !(e <= COMPLIANCE_TOL) {
        return Err(BuildError::inaccurate(format!(
            "the reduced model's static flange compliance deviates from the full model's by {e:.2e} (relative to its largest entry; accepted {COMPLIANCE_TOL:.0e}): the reduction basis lost a static direction, no FMU was written"
        )));
    }
    Ok(())
}

/// Free-free elastic frequencies and inertia-relief flange compliance, full vs reduced.
pub fn free_free_accuracy(
    model: &Assembled,
    solver: &SpdSolver,
    shift: f64,
    rigid: &Deflation,
    basis: &Basis,
) -> Result<Accuracy> {
    let full = eigen::lowest_shifted(solver, &model.mass, basis.omega.len(), EIGEN_TOL, shift, Some(rigid))?;
    let pairs = mac_pairs(model, basis, &full);
    let two_pi = 2.0 * std::f64::consts::PI;
    let full_hz: Vec<f64> = full.values.iter().map(|l| l.max(0.0).sqrt() / two_pi).collect();
    let reduced_hz: Vec<f64> = basis.omega.iter().map(|w| w / two_pi).collect();
    let relative_error = reduced_hz.iter().zip(&full_hz).map(|(r, f)| (r - f) / f).collect();
    let d = &model.dofs;
    let force: Vec<usize> = (0..d.flange_first.len()).map(|k| d.flange_first[k]).collect();
    let rows: Vec<usize> = force.iter().flat_map(|first| (0..6).map(move |i| first + i)).collect();
    let mut unit = Mat::<f64>::zeros(d.n_dofs, rows.len());
    for (c, &r) in rows.iter().enumerate() {
        unit[(r, c)] = 1.0;
    }
    let x = basis::inertia_relief_solve(solver, &model.mass, shift, rigid, &unit);
    // the flexibility seen at the flanges: B^T u with the rigid part of the load removed
    let (compliance_full, compliance_reduced, compliance_max_relative_error) = compare_compliance(&rows, &x, basis);
    Ok(Accuracy {
        reduced_hz,
        full_hz,
        relative_error,
        compliance_flanges: Vec::new(),
        compliance_full,
        compliance_reduced,
        compliance_max_relative_error,
        inertial_cases: Vec::new(),
        inertial_flange_response_full: Vec::new(),
        frequency_response: None,
        pairs,
    })
}
