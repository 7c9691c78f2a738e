//! The order selection by tolerance: the smallest dominant selection of a rich candidate basis
//! whose flange transfer functions meet the scene's tolerance over its band.

use crate::error::{BuildError, Result};
use crate::input::spec::Spec;
use crate::linalg::eigen;
use crate::linalg::sparse::{self, SpdSolve, SpdSolver};
use crate::model::rigid_coupling::Assembled;
use crate::reduce::basis::{self, Basis};
use crate::reduce::compared_band::band_of;
use crate::reduce::frf::{self, ComparisonDamping};
use crate::reduce::order;
use faer::Mat;
use std::f64::consts::PI;

/// The full model's responses the candidates are measured against.
struct Reference {
    band: [f64; 2],
    freqs: Vec<f64>,
    responses: Vec<Mat<faer::c64>>,
}

/// The smallest dominant selection of `rich` meeting `tol`. `inertial_loads`: the scene's
/// inertial load cases on the mounted DoFs (their static shapes are kept exact as the flanges'
/// are).
pub fn choose_order(
    spec: &Spec,
    model: &Assembled,
    solver: &SpdSolver,
    inertial_loads: Option<&Mat<f64>>,
    rich: Basis,
    tol: f64,
) -> Result<Basis> {
    let nc = model.dofs.n_clamped();
    let b = basis::flange_unit_loads(model);
    let rows: Vec<usize> = (0..b.ncols()).map(|j| (0..nc).find(|&i| b[(i, j)] != 0.0).unwrap_or(0)).collect();
    let phi_b = Mat::<f64>::from_fn(rows.len(), rich.omega.len(), |i, k| rich.phi[(rows[i], k)]);
    let loads = loads_in_rich_coordinates(&phi_b, &rich, inertial_loads);
    let damping = ComparisonDamping::new(spec.damping.alpha, spec.damping.beta);
    let reference = full_reference(spec, model, solver, damping)?;
    // unit-free scaling by the static compliance diagonal
    let mut g = b.clone();
    solver.solve_refined(g.as_mut());
    let scale: Vec<f64> = rows.iter().enumerate().map(|(j, &r)| 1.0 / g[(r, j)].abs().sqrt().max(1e-300)).collect();
    let ranking = order::dominance_order(&rich.omega, &phi_b, damping, &reference.freqs);
    let mut best = f64::INFINITY;
    for count in 0..=ranking.len() {
        let mut kept: Vec<usize> = ranking[..count].to_vec();
        kept.sort_unstable();
        let sel = order::select(&rich.omega, &kept, &loads);
        let err = order::frf_error(&sel, &phi_b, damping, &reference.freqs, &reference.responses, &scale);
        best = best.min(err);
        if err <= tol {
            let phi = &rich.phi * &sel.y;
            return Ok(Basis {
                phi,
                omega: sel.omega,
                n_normal: sel.kept_modes,
                fixed_interface_omega: rich.fixed_interface_omega,
            });
        }
    }
    Err(not_met(spec, tol, reference.band, rich.omega.len(), best))
}

/// The loads whose static response every selection keeps exact, in the rich model's
/// coordinates: the flange unit loads, then the scene's inertial loads.
fn loads_in_rich_coordinates(phi_b: &Mat<f64>, rich: &Basis, inertial_loads: Option<&Mat<f64>>) -> Mat<f64> {
    let loads = phi_b.transpose().to_owned();
    let Some(fc) = inertial_loads else { return loads };
    let p = rich.phi.transpose() * fc;
    let mut both = Mat::<f64>::zeros(loads.nrows(), loads.ncols() + p.ncols());
    both.as_mut().subcols_mut(0, loads.ncols()).copy_from(&loads);
    both.as_mut().subcols_mut(loads.ncols(), p.ncols()).copy_from(&p);
    both
}

/// The full model's flange responses on a grid over the band (sampled evenly plus at every
/// eigenfrequency in it).
fn full_reference(spec: &Spec, model: &Assembled, solver: &SpdSolver, damping: ComparisonDamping) -> Result<Reference> {
    let nc = model.dofs.n_clamped();
    let m = sparse::block(&model.mass, 0..nc, 0..nc)?;
    let full_modes = eigen::lowest(solver, &m, 10, basis::EIGEN_TOL)?;
    let full_hz: Vec<f64> = full_modes.values.iter().map(|l| l.sqrt() / (2.0 * PI)).collect();
    let band = band_of(spec, &full_hz);
    let in_band = eigen::below(solver, &m, 2.0 * PI * band[1] * 1.01, 1, basis::EIGEN_TOL)?;
    let eigen_hz: Vec<f64> = in_band.values.iter().map(|l| l.sqrt() / (2.0 * PI)).collect();
    let freqs = frf::grid(band, &eigen_hz, 60);
    let top = freqs.iter().copied().fold(band[1], f64::max);
    let responses = frf::full_responses(model, solver, damping, top, &freqs)?;
    Ok(Reference { band, freqs, responses })
}

fn not_met(spec: &Spec, tol: f64, band: [f64; 2], candidates: usize, best: f64) -> BuildError {
    BuildError::input(
        std::path::Path::new(&spec.name),
        "scene.tolerance",
        format!(
            "the tolerance {tol:e} is not met over {:.4}..{:.4} Hz even with all {candidates} modes of the candidate model (best {best:.2e}): give the reduction more modes or expansion points",
            band[0], band[1],
        ),
    )
}
