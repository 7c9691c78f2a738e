//! Craig-Bampton reduction about the mount: the mount's six DoFs are held (its rigid motion is the
//! body frame), every force flange contributes six constraint modes (static shapes of unit flange
//! displacements with the others held: static response to flange loads is exact), and the
//! fixed-interface normal modes (all flanges held) cover the dynamics. The basis is finally
//! orthonormalised so the reduced mass is I and the reduced stiffness diag(omega^2).

use crate::assembly::Assembled;
use crate::eigen;
use crate::error::{BuildError, Result};
use crate::sparse::{SpdSolver, block, mul_compensated, mul_new};
use faer::{Mat, Side};

#[derive(Debug, Clone, Copy)]
pub enum ModeCount {
    Count(usize),
    Below(f64),
}

pub struct Basis {
    /// n_clamped x r, M-orthonormal, K-orthogonal: the shapes of q.
    pub phi: Mat<f64>,
    /// omega_k [rad/s], ascending.
    pub omega: Vec<f64>,
    /// Number of fixed-interface normal modes in the basis (the rest are constraint modes).
    pub n_normal: usize,
    /// Frequencies of the fixed-interface normal modes [rad/s].
    pub fixed_interface_omega: Vec<f64>,
}

/// Eigensolver tolerance: Ritz residual relative to 1/lambda; tight because the reduced model's
/// frequencies are compared with the full model's to 1e-5.
pub const EIGEN_TOL: f64 = 1e-10;

pub fn craig_bampton(model: &Assembled, modes: ModeCount) -> Result<Basis> {
    let d = &model.dofs;
    let ni = d.n_interior;
    let nc = d.n_clamped();
    let nb = nc - ni;
    let k_ii = block(&model.stiffness, 0..ni, 0..ni)?;
    let m_ii = block(&model.mass, 0..ni, 0..ni)?;
    let k_ib = block(&model.stiffness, 0..ni, ni..nc)?;
    let solver = SpdSolver::new(&k_ii, "the stiffness with all flanges held")?;

    // constraint modes: [-K_ii^-1 K_ib; I]
    let mut psi = Mat::<f64>::zeros(ni, nb);
    {
        let identity = Mat::<f64>::identity(nb, nb);
        let rhs = mul_new(&k_ib, identity.as_ref());
        psi.copy_from(&rhs);
        solver.solve_refined(psi.as_mut());
        for j in 0..nb {
            for i in 0..ni {
                psi[(i, j)] = -psi[(i, j)];
            }
        }
    }

    let normal = match modes {
        ModeCount::Count(c) => eigen::lowest(&solver, &m_ii, c, EIGEN_TOL)?,
        ModeCount::Below(f) => eigen::below(&solver, &m_ii, 2.0 * std::f64::consts::PI * f, 0, EIGEN_TOL)?,
    };
    let nm = normal.values.len();
    let r = nm + nb;
    let mut v = Mat::<f64>::zeros(nc, r);
    v.as_mut().submatrix_mut(0, 0, ni, nm).copy_from(&normal.vectors);
    v.as_mut().submatrix_mut(0, nm, ni, nb).copy_from(&psi);
    for j in 0..nb {
        v[(ni + j, nm + j)] = 1.0;
    }
    // Reduced stiffness in closed form: fixed-interface modes are K-orthogonal to each other
    // (diag lambda, accurate from the shift-invert solves) and to the constraint modes (K_ii psi =
    // -K_ib). Forming phi^T K phi by products would cancel ~8 digits on slender parts (|K| phi is
    // 1e8 times K phi for the lowest modes). The constraint block is the condensed stiffness
    // psi^T K psi, taken with compensated products.
    let nc_k = block(&model.stiffness, 0..nc, 0..nc)?;
    let statics = v.subcols(nm, nb);
    let k_statics = mul_compensated(None, 1.0, &nc_k, statics);
    let k_bb = statics.transpose() * &k_statics;
    let mut kr = Mat::<f64>::zeros(r, r);
    for j in 0..nm {
        kr[(j, j)] = normal.values[j];
    }
    for i in 0..nb {
        for j in 0..nb {
            kr[(nm + i, nm + j)] = 0.5 * (k_bb[(i, j)] + k_bb[(j, i)]);
        }
    }
    let nc_m = block(&model.mass, 0..nc, 0..nc)?;
    let mr = v.transpose() * mul_new(&nc_m, v.as_ref());
    let phi_and_omega = orthonormalise(&kr, &mr, &v)?;
    Ok(Basis {
        phi: phi_and_omega.0,
        omega: phi_and_omega.1,
        n_normal: nm,
        fixed_interface_omega: normal.values.iter().map(|l| l.sqrt()).collect(),
    })
}

/// Solve the reduced eigenproblem (V^T K V) x = lambda (V^T M V) x and return V X (M-orthonormal)
/// with omega = sqrt(lambda).
/// `kr`, `mr` are V^T K V and V^T M V.
pub fn orthonormalise(kr: &Mat<f64>, mr: &Mat<f64>, v: &Mat<f64>) -> Result<(Mat<f64>, Vec<f64>)> {
    let r = v.ncols();
    let sym = |a: &Mat<f64>| Mat::<f64>::from_fn(r, r, |i, j| 0.5 * (a[(i, j)] + a[(j, i)]));
    let (kr, mr) = (sym(kr), sym(mr));
    let llt = mr.llt(Side::Lower).map_err(|e| {
        BuildError::Numerical(format!("the reduced mass is singular ({e:?}): the basis has dependent columns"))
    })?;
    let l = llt.L().to_owned();
    // C = L^-1 K_r L^-T
    let mut c = kr.clone();
    faer::linalg::triangular_solve::solve_lower_triangular_in_place(l.as_ref(), c.as_mut(), faer::Par::Seq);
    let mut ct = c.transpose().to_owned();
    faer::linalg::triangular_solve::solve_lower_triangular_in_place(l.as_ref(), ct.as_mut(), faer::Par::Seq);
    let c = sym(&ct);
    let evd = c
        .self_adjoint_eigen(Side::Lower)
        .map_err(|e| BuildError::Numerical(format!("reduced eigenproblem failed: {e:?}")))?;
    let s = evd.S();
    let mut x = evd.U().to_owned();
    // X = L^-T Y
    faer::linalg::triangular_solve::solve_upper_triangular_in_place(l.transpose(), x.as_mut(), faer::Par::Seq);
    let mut omega = Vec::with_capacity(r);
    for i in 0..r {
        let lambda = s[i];
        if !(lambda > 0.0) {
            return Err(BuildError::Numerical(format!(
                "reduced stiffness has a non-positive eigenvalue {lambda:e}: the part is not held by its mount"
            )));
        }
        omega.push(lambda.sqrt());
    }
    Ok((v * &x, omega))
}
