//! Checks of an imported matrix model: positive diagonals, a positive
//! semi-definite mass and, for a free-free part, a stiffness that does not
//! resist rigid-body motion.

use super::DIRECTIONS;
use super::matrix_market::SymMatrix;
use crate::import::ImportError;
use faer::sparse::{SparseColMat, Triplet};
use faer::{Mat, Side};
use std::path::Path;

/// Largest rigid-body residual a free-free stiffness may have.
pub const FREE_FREE_TOLERANCE: f64 = 1e-6;

/// Names of the six rigid-body motions in the order of
/// [`rigid_body_residual`].
pub const RIGID_BODY_MOTIONS: [&str; 6] =
    ["translation x", "translation y", "translation z", "rotation about x", "rotation about y", "rotation about z"];

/// Refuses a non-positive (or missing) diagonal entry.
pub(super) fn check_positive_diagonal(
    m: &SymMatrix,
    path: &Path,
    what: &str,
    label: &dyn Fn(usize) -> String,
) -> Result<(), ImportError> {
    let mut diag: Vec<Option<(f64, usize)>> = vec![None; m.n];
    for e in m.upper.iter().filter(|e| e.i == e.j) {
        if let Some(d) = diag.get_mut(e.i as usize) {
            *d = Some((e.v, e.line));
        }
    }
    for (r, d) in diag.iter().enumerate() {
        match *d {
            Some((v, _)) if v > 0.0 => {}
            Some((v, line)) => {
                return Err(ImportError::new(
                    path,
                    line,
                    format!(
                        "{what} diagonal entry of {} is {v:e}, expected a positive value: every DoF of a \
                         solid has positive {what}",
                        label(r)
                    ),
                ));
            }
            None => {
                return Err(ImportError::new(
                    path,
                    0,
                    format!(
                        "{what} matrix has no diagonal entry for {}, expected a positive value: every DoF \
                         of a solid has positive {what}",
                        label(r)
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// Refuses an indefinite mass.
pub(super) fn check_mass_semidefinite(mass: &SparseColMat<usize, f64>, path: &Path) -> Result<(), ImportError> {
    // A consistent mass may be singular (CalculiX integrates C3D4, C3D10 and C3D20R masses with
    // their stiffness rules: rank 1, 4 and 8 per element), so the check is for indefiniteness:
    // M + 1e-8 diag(M) must factor. A singular semidefinite M passes, a negative eigenvalue
    // beyond round-off does not.
    let lifted = {
        let mut t: Vec<faer::sparse::Triplet<usize, usize, f64>> = Vec::with_capacity(mass.val().len() + mass.nrows());
        for j in 0..mass.ncols() {
            for (&i, &v) in mass.row_idx_of_col_raw(j).iter().zip(mass.val_of_col(j)) {
                t.push(faer::sparse::Triplet::new(i, j, v));
                if i == j {
                    t.push(faer::sparse::Triplet::new(i, j, 1e-8 * v));
                }
            }
        }
        SparseColMat::try_new_from_triplets(mass.nrows(), mass.ncols(), &t).map_err(|e| {
            ImportError::new(path, 0, format!("mass matrix: {}", fe_linalg::faer_error::creation(&e))).caused_by(e)
        })?
    };
    if let Err(e) = lifted.sp_cholesky(Side::Lower) {
        let why = match &e {
            faer::sparse::linalg::LltError::Numeric(_) => {
                "its Cholesky factorisation meets a non-positive pivot".to_string()
            }
            faer::sparse::linalg::LltError::Generic(g) => {
                format!("the factorisation failed ({g:?})")
            }
        };
        return Err(ImportError::new(
            path,
            0,
            format!(
                "mass matrix is indefinite (not positive semi-definite): {why}. Check that the mass matrix \
                 belongs to the same model and DoF order as the stiffness and the DoF map"
            ),
        )
        .caused_by(e));
    }
    Ok(())
}

/// The rigid-body residual of `stiffness` ([`rigid_body_residual`]); for a
/// part declared `free_free`, an error naming the resisted motions and the
/// node of the largest reaction when any exceeds [`FREE_FREE_TOLERANCE`].
pub(super) fn check_free_free(
    stiffness: &SparseColMat<usize, f64>,
    nodes: &[[f64; 3]],
    node_ids: &[u64],
    free_free: bool,
    path: &Path,
) -> Result<[f64; 6], ImportError> {
    let check = rigid_body_check(stiffness, nodes);
    let rigid_body_residual = check.map(|(r, _)| r);
    if free_free {
        let resisted: Vec<usize> = (0..6)
            .filter(|&c| rigid_body_residual[c] > FREE_FREE_TOLERANCE || rigid_body_residual[c].is_nan())
            .collect();
        if let Some(&worst) =
            resisted.iter().max_by(|&&a, &&b| rigid_body_residual[a].total_cmp(&rigid_body_residual[b]))
        {
            let list = resisted
                .iter()
                .map(|&c| format!("{} (residual {:.2e})", RIGID_BODY_MOTIONS[c], rigid_body_residual[c]))
                .collect::<Vec<_>>()
                .join(", ");
            let dof = check[worst].1;
            let node = node_ids.get(dof / 3).copied().unwrap_or(0);
            return Err(ImportError::new(
                path,
                0,
                format!(
                    "the stiffness matrix resists rigid-body {list}, above the free-free tolerance \
                     {FREE_FREE_TOLERANCE:e}; the largest reaction to the {} is at node {node} {}. \
                     The stiffness seems to carry supports (boundary conditions, springs to ground) \
                     while the input says the part is free-free: export the stiffness of the \
                     unsupported part, or do not declare it free-free",
                    RIGID_BODY_MOTIONS[worst],
                    DIRECTIONS[dof % 3]
                ),
            ));
        }
    }
    Ok(rigid_body_residual)
}

/// How far the stiffness `k` (DoF `3 * node + direction`) is from being free
/// of the six rigid-body fields about the centroid of `nodes`: for each field
/// `r` (translations x, y, z, then small rotations about x, y, z) the value
/// `||K r||_inf / (max_ij |K_ij| * ||r||_inf)`.
///
/// The max-norm is used because a support acts on a few DoFs: its reaction
/// shows in the max-norm at full size whatever the model size, where a
/// 2-norm would dilute it by the square root of the node count. Dividing by
/// `max |K_ij| ||r||_inf` bounds the value by the nonzeros per row for any
/// field and makes it independent of units and of the field's scale, so the
/// rotations (scaled by the largest distance from the centroid) compare
/// directly with the translations. `K r` is summed in double-double, so for
/// a free stiffness the value is the rounding of the stored entries
/// (~1e-16 per digit-exact entry, ~1e-13 for the 14 digits CalculiX writes),
/// and a support spring `s` at the farthest node gives about
/// `s / max |K_ij|`.
///
/// Returns NaN for all six when `k` is not `3 nodes.len()` square; a field
/// that vanishes (rotations of a single node or about the axis of collinear
/// nodes) or an all-zero `k` gives 0.
pub fn rigid_body_residual(k: &SparseColMat<usize, f64>, nodes: &[[f64; 3]]) -> [f64; 6] {
    rigid_body_check(k, nodes).map(|(r, _)| r)
}

/// [`rigid_body_residual`] with, per field, the DoF of the largest reaction.
fn rigid_body_check(k: &SparseColMat<usize, f64>, nodes: &[[f64; 3]]) -> [(f64, usize); 6] {
    let n = 3 * nodes.len();
    if k.nrows() != n || k.ncols() != n {
        return [(f64::NAN, 0); 6];
    }
    if n == 0 {
        return [(0.0, 0); 6];
    }
    // mul_compensated walks col_ptr ranges, which is only right for compact
    // storage; a caller's matrix with per-column counts is rebuilt first.
    let compact;
    let k = if k.symbolic().col_nnz().is_some() {
        match compacted(k, n) {
            Some(m) => {
                compact = m;
                &compact
            }
            None => return [(f64::NAN, 0); 6],
        }
    } else {
        k
    };
    let mut kmax = 0.0f64;
    for j in 0..n {
        for &v in k.val_of_col(j) {
            kmax = kmax.max(v.abs());
        }
    }

    let r = rigid_body_fields(nodes);
    let kr = fe_linalg::sparse::mul_compensated(None, 1.0, k, r.as_ref());
    largest_reactions(&kr, &r, kmax)
}

/// `k` rebuilt in compact storage; None where that fails.
fn compacted(k: &SparseColMat<usize, f64>, n: usize) -> Option<SparseColMat<usize, f64>> {
    let mut trip = Vec::new();
    for j in 0..n {
        for (&i, &v) in k.row_idx_of_col_raw(j).iter().zip(k.val_of_col(j)) {
            trip.push(Triplet::new(i, j, v));
        }
    }
    SparseColMat::try_new_from_triplets(n, n, &trip).ok()
}

/// The six rigid-body displacement fields of `nodes` (3 per node): translations along x, y, z,
/// and rotations about the centroid, scaled so the farthest node moves by one.
fn rigid_body_fields(nodes: &[[f64; 3]]) -> Mat<f64> {
    let n = 3 * nodes.len();
    let count = nodes.len() as f64;
    let mut c = [0.0; 3];
    for p in nodes {
        for d in 0..3 {
            c[d] += p[d] / count;
        }
    }
    let size = nodes
        .iter()
        .map(|p| ((p[0] - c[0]).powi(2) + (p[1] - c[1]).powi(2) + (p[2] - c[2]).powi(2)).sqrt())
        .fold(0.0, f64::max);
    let scale = if size > 0.0 { 1.0 / size } else { 0.0 };
    let mut r = Mat::<f64>::zeros(n, 6);
    for (a, p) in nodes.iter().enumerate() {
        let x = [0, 1, 2].map(|d| (p[d] - c[d]) * scale);
        for t in 0..3 {
            r[(3 * a + t, t)] = 1.0;
        }
        // omega x (p - c) for omega = e_x, e_y, e_z.
        r[(3 * a + 1, 3)] = -x[2];
        r[(3 * a + 2, 3)] = x[1];
        r[(3 * a, 4)] = x[2];
        r[(3 * a + 2, 4)] = -x[0];
        r[(3 * a, 5)] = -x[1];
        r[(3 * a + 1, 5)] = x[0];
    }
    r
}

/// Per field, |K r| at its largest relative to max |K_ij| max |r|, and the DoF where it is.
fn largest_reactions(kr: &Mat<f64>, r: &Mat<f64>, kmax: f64) -> [(f64, usize); 6] {
    let n = r.nrows();
    let mut out = [(0.0, 0); 6];
    for (col, o) in out.iter_mut().enumerate() {
        let mut rmax = 0.0f64;
        let mut num = 0.0f64;
        let mut arg = 0;
        for i in 0..n {
            rmax = rmax.max(r[(i, col)].abs());
            let v = kr[(i, col)].abs();
            if v > num || v.is_nan() {
                num = v;
                arg = i;
            }
        }
        let den = kmax * rmax;
        *o = (
            if den > 0.0 {
                num / den
            } else if num.is_nan() {
                f64::NAN
            } else {
                0.0
            },
            arg,
        );
    }
    out
}
#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rigid_body_residual_edge_cases() {
        let k = SparseColMat::<usize, f64>::try_new_from_triplets(3, 3, &[Triplet::new(0, 0, 1.0)]).unwrap();
        assert!(rigid_body_residual(&k, &[[0.0; 3], [1.0; 3]]).iter().all(|r| r.is_nan()));
        // One node: rotations vanish; a spring on x resists translation x only.
        assert_eq!(rigid_body_residual(&k, &[[1.0, 2.0, 3.0]]), [1.0, 0.0, 0.0, 0.0, 0.0, 0.0]);
        let zero = SparseColMat::<usize, f64>::try_new_from_triplets(3, 3, &[]).unwrap();
        assert_eq!(rigid_body_residual(&zero, &[[1.0, 2.0, 3.0]]), [0.0; 6]);
    }
}
