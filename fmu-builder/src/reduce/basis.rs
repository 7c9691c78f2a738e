//! Craig-Bampton reduction about the mount: the mount's six DoFs are held (its rigid motion is the
//! body frame), every force flange contributes six constraint modes (static shapes of unit flange
//! displacements with the others held: static response to flange loads is exact), and the
//! fixed-interface normal modes (all flanges held) cover the dynamics. The basis is finally
//! orthonormalised so the reduced mass is I and the reduced stiffness diag(omega^2).

use crate::error::{BuildError, Result};
use crate::linalg::eigen::{self, column_dots};
use crate::linalg::held::HeldSolver;
use crate::linalg::sparse::{SpdSolve, SpdSolver, block, mul_leading, mul_new};
use crate::linalg::symmetric_eigen::graded_spd_eigen;
use crate::model::rigid_coupling::Assembled;
use faer::reborrow::{Reborrow, ReborrowMut};
use faer::{ColMut, ColRef, Mat, MatMut, MatRef};
use std::borrow::Cow;

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

/// A basis column whose M-orthogonal remainder is below this fraction of its M-norm is taken as
/// dependent on the columns before it (after two Gram-Schmidt passes round-off leaves 1e-15).
const DEPENDENT: f64 = 1e-10;

/// Eigensolver tolerance: Ritz residual relative to 1/lambda; tight because the reduced model's
/// frequencies are compared with the full model's to 1e-5.
pub const EIGEN_TOL: f64 = 1e-8;

/// `static_shapes` (n_clamped x s): static responses to the scene's inertial loads, appended to
/// the basis so that those loads, too, are reproduced exactly in statics.
/// `mounted` factors the stiffness of the mounted body (n_clamped rows); the flanges are held
/// through it (`HeldSolver`), without a factor of their own. `flange_shapes` = K^-1 B, the
/// mounted body's refined static response to unit loads at the force flanges
/// (`flange_unit_loads`), from which the held solves and the constraint modes follow.
/// `whole_modes`: also compute that many of the mounted body's own lowest modes (for the
/// accuracy comparison), in the same Krylov space as the fixed-interface modes where their
/// count is given (`eigen::lowest_and_held`); they come back beside the basis.
pub fn craig_bampton(
    model: &Assembled,
    mounted: &SpdSolver,
    flange_shapes: &Mat<f64>,
    modes: ModeCount,
    static_shapes: Option<&Mat<f64>>,
    whole_modes: Option<usize>,
) -> Result<(Basis, Option<eigen::Eigenpairs>)> {
    let d = &model.dofs;
    let ni = d.n_interior;
    let nc = d.n_clamped();
    let nb = nc - ni;
    // the force flanges' masters are the rows from ni on, in the order of their unit loads
    let solver = HeldSolver::with_shapes(mounted, ni, Cow::Borrowed(flange_shapes))?;

    // constraint modes: [-K_ii^-1 K_ib; I], from the flange shapes
    let psi = phases::phase("constraint modes", || {
        phases::note(|| format!("{nb} flange DoFs, from their unit-load shapes (no further solve)"));
        solver.constraint_modes()
    });

    let (normal, whole) = match (modes, whole_modes) {
        (ModeCount::Count(c), Some(count)) => {
            // the whole model's mass: the products take its leading blocks (no copy)
            let (whole, normal) = eigen::lowest_and_held(mounted, &model.mass, count, &solver, c, EIGEN_TOL)?;
            // the vectors stay for the comparison's pairing of modes by shape (n x count, freed
            // there; below the eigen-solve's peak)
            (normal, Some(whole))
        }
        (ModeCount::Count(c), None) => (eigen::lowest(&solver, &model.mass, c, EIGEN_TOL)?, None),
        (ModeCount::Below(f), _) => {
            (eigen::below(&solver, &model.mass, 2.0 * std::f64::consts::PI * f, 0, EIGEN_TOL)?, None)
        }
    };
    let nm = normal.values.len();
    let ns = static_shapes.map_or(0, |m| m.ncols());
    let r = nm + nb + ns;
    // static shapes first (see `orthonormalise`): constraint modes, load shapes, then the modes
    let mut v = Mat::<f64>::zeros(nc, r);
    v.as_mut().submatrix_mut(0, 0, nc, nb).copy_from(&psi);
    if let Some(shapes) = static_shapes {
        v.as_mut().submatrix_mut(0, nb, nc, ns).copy_from(shapes);
    }
    v.as_mut().submatrix_mut(0, nb + ns, ni, nm).copy_from(&normal.vectors);
    let (phi, omega) = orthonormalise(model, v)?;
    let basis =
        Basis { phi, omega, n_normal: nm, fixed_interface_omega: normal.values.iter().map(|l| l.sqrt()).collect() };
    Ok((basis, whole))
}

/// Rayleigh-Ritz on span(V): an M-orthonormal basis W of the span first (twice, dropping
/// directions dependent to round-off), then the symmetric eigenproblem of W^T K W, and
/// Phi = W Y with Phi^T M Phi = I, Phi^T K Phi = diag(omega^2).
///
/// Why not Cholesky of V^T M V: constraint modes of a light flange span directions of tiny
/// mass, and L^-1 (V^T K V) L^-T amplifies the round-off of V^T K V by cond(V^T M V); for a
/// complete basis that cost the lowest frequency its third digit. Forming W explicitly and
/// taking K W with compensated sums keeps every Ritz value at round-off of itself.
pub fn orthonormalise(model: &Assembled, v: Mat<f64>) -> Result<(Mat<f64>, Vec<f64>)> {
    // products with the clamped K and M through the whole matrices: no copy of either
    // unit M-norm columns first: static shapes of stiff directions are 1e-9 of the modes, and the
    // dependency test below must judge directions, not their units. One product with M for the
    // whole block: M W scales with W.
    let mut w = v;
    let mut mw = mul_leading(&model.mass, w.as_ref(), false);
    let norms0 = scale_to_unit_m_norm(&mut w, &mut mw);
    let kept = gram_schmidt(model, &mut w, &mut mw, &norms0);
    if kept == 0 {
        return Err(BuildError::numerical(
            "the reduction basis is empty: every candidate shape (modes, static flange and load shapes) depends on the \
             others or has no mass; request modes (reduction.modes or max_frequency) or a force flange, and check material.rho",
        ));
    }
    drop(mw);
    rayleigh_ritz(model, w, kept)
}

/// Every column of W with a positive M-norm scaled to M-norm one, M W alongside; the norms they had.
fn scale_to_unit_m_norm(w: &mut Mat<f64>, mw: &mut Mat<f64>) -> Vec<f64> {
    let norms0: Vec<f64> = column_dots(w, mw).into_iter().map(|d| d.max(0.0).sqrt()).collect();
    for (j, norm) in norms0.iter().enumerate() {
        if *norm > 0.0 {
            let s = 1.0 / norm;
            w.col_mut(j).iter_mut().for_each(|x| *x *= s);
            mw.col_mut(j).iter_mut().for_each(|x| *x *= s);
        }
    }
    norms0
}

/// Gram-Schmidt in the columns' order, each column twice against those kept. Callers put the
/// static shapes first: their K-products are then formed as they are (exact compliance),
/// and the modes after them change only by a small, soft correction. The other order makes
/// the static shapes' remainder carry W^T K W = psi^T K psi + m^T Lambda m with m the modes'
/// mass coupling, from which the Cholesky takes m^T Lambda m away again: a cancellation of
/// 1e6 on a slender part, which cost the 200-mode L-beam's compliance its tenth digit
/// (1.6e-9). A symmetric orthonormalisation would mix every column into every other.
///
/// The columns go in panels: each panel against the columns kept before it by matrix
/// products (one read of the kept basis per pass for the whole panel; column by column,
/// those reads cost 0.6 s at 249k DoFs), then column by column within the panel. Classical
/// Gram-Schmidt twice either way, so the same basis to round-off.
/// The kept columns are compacted into w and M w themselves (column `kept` <= the one being
/// processed, whose panel is copied out first): no second n x r pair at the build's peak
///
/// Returns the number of columns kept, compacted to the front of `basis` and `m_basis`.
fn gram_schmidt(model: &Assembled, basis: &mut Mat<f64>, m_basis: &mut Mat<f64>, norms0: &[f64]) -> usize {
    let m_times = |x: MatRef<'_, f64>| mul_leading(&model.mass, x, false);
    let mut kept = 0;
    for start in (0..basis.ncols()).step_by(PANEL) {
        let width = PANEL.min(basis.ncols() - start);
        let mut panel = basis.subcols(start, width).to_owned();
        let mut m_panel = m_basis.subcols(start, width).to_owned();
        let before = kept;
        for _ in 0..2 {
            project_out(panel.as_mut(), m_panel.as_mut(), basis.subcols(0, before), m_basis.subcols(0, before));
        }
        for i in 0..width {
            if !(norms0[start + i] > 0.0) {
                continue;
            }
            // M v follows v's updates (M v = M w_j - M B c): exact to a few ulps of |M w_j|, so
            // to a few ulps of itself where v kept half its norm or more; below that a fresh
            // product (one single-column product per column cost 0.5 s at 249k DoFs)
            let (mut v, mut mv) = (panel.col_mut(i), m_panel.col_mut(i));
            for _ in 0..2 {
                for b in before..kept {
                    let a = dot(m_basis.col(b), v.rb());
                    axpy(v.rb_mut(), -a, basis.col(b));
                    axpy(mv.rb_mut(), -a, m_basis.col(b));
                }
            }
            let mut norm = dot(v.rb(), mv.rb()).max(0.0).sqrt();
            if norm < 0.5 {
                mv.copy_from(m_times(v.rb().as_mat()).col(0));
                norm = dot(v.rb(), mv.rb()).max(0.0).sqrt();
            }
            // a remainder at round-off of the column is a dependent direction: kept, it would be
            // noise with a spurious stiff frequency
            if norm <= DEPENDENT {
                continue;
            }
            basis.col_mut(kept).iter_mut().zip(v.iter()).for_each(|(b, x)| *b = x / norm);
            m_basis.col_mut(kept).iter_mut().zip(mv.iter()).for_each(|(b, x)| *b = x / norm);
            kept += 1;
        }
    }
    kept
}

/// The eigenpairs of the reduced stiffness W^T K W on the first `kept` columns of W: Phi = W Y and omega.
fn rayleigh_ritz(model: &Assembled, mut w: Mat<f64>, kept: usize) -> Result<(Mat<f64>, Vec<f64>)> {
    let rows = w.nrows();
    w.truncate(rows, kept);
    let kw = mul_leading(&model.stiffness, w.as_ref(), true);
    let r = w.ncols();
    let kr = w.transpose() * &kw;
    let c = Mat::<f64>::from_fn(r, r, |i, j| 0.5 * (kr[(i, j)] + kr[(j, i)]));
    let evd = graded_spd_eigen(&c, "the reduced stiffness").map_err(|e| {
        BuildError::singular(
            "the reduced stiffness is not positive definite: the part can move without deforming (a mounted part not held \
             by its mount, or a mechanism: pieces joined only at a node or an edge)",
        )
        .caused_by(e)
    })?;
    let s = &evd.values;
    let mut omega = Vec::with_capacity(r);
    for i in 0..r {
        let lambda = s[i];
        if !(lambda > 0.0) {
            return Err(BuildError::singular(format!(
                "reduced stiffness has a non-positive eigenvalue {lambda:e}: the part can move without deforming (a mounted \
                 part not held by its mount, or a mechanism: pieces joined only at a node or an edge)"
            )));
        }
        omega.push(lambda.sqrt());
    }
    Ok((&w * &evd.vectors, omega))
}

/// Columns per panel of `orthonormalise`'s Gram-Schmidt.
const PANEL: usize = 8;

fn dot(a: ColRef<'_, f64>, b: ColRef<'_, f64>) -> f64 {
    a.iter().zip(b.iter()).map(|(x, y)| x * y).sum()
}

/// y += a x
fn axpy(y: ColMut<'_, f64>, a: f64, x: ColRef<'_, f64>) {
    y.iter_mut().zip(x.iter()).for_each(|(y, x)| *y += a * x);
}

/// x -= B B^T M x with `m_b` = M B (B M-orthonormal), and M x alongside.
fn project_out(mut x: MatMut<'_, f64>, mut mx: MatMut<'_, f64>, b: MatRef<'_, f64>, m_b: MatRef<'_, f64>) {
    use faer::linalg::matmul::matmul;
    if b.ncols() == 0 {
        return;
    }
    let par = faer::get_global_parallelism();
    let c = m_b.transpose() * x.rb();
    matmul(x.rb_mut(), faer::Accum::Add, b, c.as_ref(), -1.0, par);
    matmul(mx.rb_mut(), faer::Accum::Add, m_b, c.as_ref(), -1.0, par);
}

/// A free-floating body: the frame follows the body's mean motion (origin at the centre of mass,
/// elastic shapes M-orthogonal to the six rigid-body fields: mean axes, so C_t = 0 and C_r = 0),
/// and the basis is free-interface elastic modes plus inertia-relief attachment shapes of every
/// force flange (the flange loads' static response, exact, with the rigid-body acceleration they
/// cause taken out). `k_shifted` factors K + shift M; `rigid` holds the six rigid-body fields.
pub fn free_free(
    model: &Assembled,
    k_shifted: &SpdSolver,
    shift: f64,
    rigid: &eigen::Deflation,
    modes: ModeCount,
) -> Result<Basis> {
    let n = model.dofs.n_dofs;
    let m = &model.mass;
    let normal = match modes {
        ModeCount::Count(c) => eigen::lowest_shifted(k_shifted, m, c, EIGEN_TOL, shift, Some(rigid))?,
        ModeCount::Below(f) => {
            eigen::below_shifted(k_shifted, m, 2.0 * std::f64::consts::PI * f, 0, EIGEN_TOL, shift, Some(rigid))?
        }
    };
    let nm = normal.values.len();
    let force: Vec<usize> = model
        .dofs
        .flange_first
        .iter()
        .enumerate()
        .filter(|(k, _)| Some(*k) != model.dofs.mount)
        .map(|(_, f)| *f)
        .collect();
    let nb = 6 * force.len();
    let mut unit = Mat::<f64>::zeros(n, nb);
    for (f, first) in force.iter().enumerate() {
        for i in 0..6 {
            unit[(first + i, 6 * f + i)] = 1.0;
        }
    }
    let attachments = inertia_relief_solve(k_shifted, m, shift, rigid, &unit);
    let mut v = Mat::<f64>::zeros(n, nm + nb);
    v.as_mut().subcols_mut(0, nb).copy_from(&attachments);
    v.as_mut().subcols_mut(nb, nm).copy_from(&normal.vectors);
    let (phi, omega) = orthonormalise(model, v)?;
    Ok(Basis {
        phi,
        omega,
        n_normal: nm,
        fixed_interface_omega: normal.values.iter().map(|l| l.max(0.0).sqrt()).collect(),
    })
}

/// Static response of a free body to loads `f` with inertia relief: the self-equilibrated part
/// f - M Y Y^T f (Y: M-orthonormal rigid fields) solved with the singular K, the answer taken
/// M-orthogonal to the rigid fields. Solved as u <- (K + s M)^-1 (f_eq + s M u), which converges
/// by the factor s / (lambda_1 + s) per sweep on the elastic part.
pub fn inertia_relief_solve(
    k_shifted: &SpdSolver,
    m: &crate::linalg::sparse::Sparse,
    shift: f64,
    rigid: &eigen::Deflation,
    f: &Mat<f64>,
) -> Mat<f64> {
    let c = rigid.vectors.transpose() * f;
    let f_eq = f - &rigid.m_vectors * &c;
    let mut u = Mat::<f64>::zeros(f.nrows(), f.ncols());
    for _ in 0..60 {
        let mut rhs = &f_eq + mul_new(m, u.as_ref()) * faer::Scale(shift);
        k_shifted.solve_refined(rhs.as_mut());
        let c = rigid.m_vectors.transpose() * &rhs;
        rhs -= &rigid.vectors * &c;
        let change = (&rhs - &u).norm_max();
        let size = rhs.norm_max();
        u = rhs;
        if change <= 1e-14 * size {
            break;
        }
    }
    u
}

/// Columns of `flange_unit_loads`: six per force flange.
pub fn flange_unit_loads_count(model: &Assembled) -> usize {
    let d = &model.dofs;
    6 * (0..d.flange_first.len()).filter(|&k| Some(k) != d.mount).count()
}

/// Unit loads at the force flanges' master DoFs (n_clamped x 6 per flange).
pub fn flange_unit_loads(model: &Assembled) -> Mat<f64> {
    let rows = flange_unit_load_rows(model);
    let mut b = Mat::<f64>::zeros(model.dofs.n_clamped(), rows.len());
    for (j, &r) in rows.iter().enumerate() {
        b[(r, j)] = 1.0;
    }
    b
}

/// The row of each column's unit load in `flange_unit_loads` (its flange master DoF): the
/// response at the loads without the n x 6 matrix.
pub fn flange_unit_load_rows(model: &Assembled) -> Vec<usize> {
    let d = &model.dofs;
    (0..d.flange_first.len())
        .filter(|&k| Some(k) != d.mount)
        .flat_map(|k| (0..6).map(move |i| d.flange_first[k] + i))
        .collect()
}

/// Modal reduction with residual flexibility (static correction): the normal modes of the
/// mounted body (force flanges free) plus the static shapes of unit flange loads, so the static
/// response is exact and the modes carry the dynamics.
pub fn modal(
    model: &Assembled,
    solver: &SpdSolver,
    modes: ModeCount,
    static_shapes: Option<&Mat<f64>>,
) -> Result<Basis> {
    let nc = model.dofs.n_clamped();
    let m = block(&model.mass, 0..nc, 0..nc)?;
    let normal = match modes {
        ModeCount::Count(c) => eigen::lowest(solver, &m, c, EIGEN_TOL)?,
        ModeCount::Below(f) => eigen::below(solver, &m, 2.0 * std::f64::consts::PI * f, 0, EIGEN_TOL)?,
    };
    let mut attachment = flange_unit_loads(model);
    solver.solve_refined(attachment.as_mut());
    let nm = normal.values.len();
    let v = concat(&[&attachment, static_shapes.unwrap_or(&Mat::zeros(nc, 0)), &normal.vectors]);
    let (phi, omega) = orthonormalise(model, v)?;
    Ok(Basis { phi, omega, n_normal: nm, fixed_interface_omega: normal.values.iter().map(|l| l.sqrt()).collect() })
}

fn concat(parts: &[&Mat<f64>]) -> Mat<f64> {
    let n = parts[0].nrows();
    let total = parts.iter().map(|p| p.ncols()).sum();
    let mut out = Mat::<f64>::zeros(n, total);
    let mut c = 0;
    for p in parts {
        out.as_mut().subcols_mut(c, p.ncols()).copy_from(*p);
        c += p.ncols();
    }
    out
}

/// Second-order Krylov moment matching (undamped, block, real): at each expansion point s = i w0
/// the moments R_0 = (K - w0^2 M)^-1 B, R_j = (K - w0^2 M)^-1 M R_(j-1) of the flange transfer
/// function, M-orthogonalised block by block against everything before (twice: Gram-Schmidt
/// keeps orthogonality only when repeated) with deflation of directions already spanned. The
/// static point w0 = 0 is always the first, so flange statics stay exact; imaginary points
/// keep the basis real because the undamped K - w0^2 M is real.
pub fn krylov(
    model: &Assembled,
    solver: &SpdSolver,
    points_hz: &[f64],
    real_points: &[f64],
    moments: usize,
    static_shapes: Option<&Mat<f64>>,
) -> Result<Basis> {
    let nc = model.dofs.n_clamped();
    let k = block(&model.stiffness, 0..nc, 0..nc)?;
    let m = block(&model.mass, 0..nc, 0..nc)?;
    let b = flange_unit_loads(model);
    // (K + s^2 M) at s = i 2 pi f is K - (2 pi f)^2 M; at real s = sigma, K + sigma^2 M
    let mut shifts: Vec<f64> = vec![0.0];
    for &p in points_hz {
        let w = 2.0 * std::f64::consts::PI * p;
        if p > 0.0 && !shifts.contains(&(-w * w)) {
            shifts.push(-w * w);
        }
    }
    for &sigma in real_points {
        if sigma > 0.0 && !shifts.contains(&(sigma * sigma)) {
            shifts.push(sigma * sigma);
        }
    }
    let mut basis = Mat::<f64>::zeros(nc, 0);
    let mut m_basis = Mat::<f64>::zeros(nc, 0);
    for &shift in &shifts {
        let lu = if shift == 0.0 {
            None
        } else {
            let a = crate::linalg::sparse::add_scaled(&k, shift, &m)?;
            let what = if shift < 0.0 {
                format!(
                    "K - w^2 M at the expansion point {} Hz (an eigenfrequency?)",
                    (-shift).sqrt() / (2.0 * std::f64::consts::PI)
                )
            } else {
                format!("K + s^2 M at the real expansion point s = {}", shift.sqrt())
            };
            Some(crate::linalg::sparse::LuSolver::new(&a, &what)?)
        };
        let apply = |x: &mut Mat<f64>| match &lu {
            Some(lu) => lu.solve_refined(x.as_mut()),
            None => solver.solve_refined(x.as_mut()),
        };
        let mut block_ = b.clone();
        apply(&mut block_);
        for j in 0..moments {
            if j > 0 {
                block_ = mul_new(&m, block_.as_ref());
                apply(&mut block_);
            }
            let kept = m_orthogonal_extend(&mut basis, &mut m_basis, &block_, &m);
            if kept == 0 {
                break; // the Krylov space is exhausted at this point
            }
        }
    }
    if let Some(s) = static_shapes {
        m_orthogonal_extend(&mut basis, &mut m_basis, s, &m);
    }
    let (phi, omega) = orthonormalise(model, basis)?;
    Ok(Basis { phi, omega, n_normal: 0, fixed_interface_omega: Vec::new() })
}

/// Append the columns of `new` to the M-orthonormal `basis` after M-orthogonalising them against
/// it and each other (twice), dropping those that are spanned already: a remainder below 1e-7
/// of the column's M-norm is mostly round-off of the solves, and kept it would only add a
/// spurious stiff direction that costs the reduced eigenproblem its conditioning. Returns how
/// many were kept.
fn m_orthogonal_extend(
    basis: &mut Mat<f64>,
    m_basis: &mut Mat<f64>,
    new: &Mat<f64>,
    m: &crate::linalg::sparse::Sparse,
) -> usize {
    let n = new.nrows();
    let mut kept = 0;
    for j in 0..new.ncols() {
        let mut v = new.col(j).to_owned().as_mat().to_owned();
        let norm0 = m_norm(&v, m);
        if !(norm0 > 0.0) {
            continue;
        }
        for _ in 0..2 {
            let c = m_basis.transpose() * &v;
            v -= &*basis * &c;
        }
        let norm = m_norm(&v, m);
        if norm <= 1e-7 * norm0 {
            continue;
        }
        v *= faer::Scale(1.0 / norm);
        let mv = mul_new(m, v.as_ref());
        let mut grown = Mat::<f64>::zeros(n, basis.ncols() + 1);
        grown.as_mut().subcols_mut(0, basis.ncols()).copy_from(&*basis);
        grown.as_mut().col_mut(basis.ncols()).copy_from(v.col(0));
        let mut grown_m = Mat::<f64>::zeros(n, basis.ncols() + 1);
        grown_m.as_mut().subcols_mut(0, basis.ncols()).copy_from(&*m_basis);
        grown_m.as_mut().col_mut(basis.ncols()).copy_from(mv.col(0));
        *basis = grown;
        *m_basis = grown_m;
        kept += 1;
    }
    kept
}

fn m_norm(v: &Mat<f64>, m: &crate::linalg::sparse::Sparse) -> f64 {
    let mv = mul_new(m, v.as_ref());
    (0..v.nrows()).map(|i| v[(i, 0)] * mv[(i, 0)]).sum::<f64>().max(0.0).sqrt()
}
