//! Element matrices for linear isotropic elasticity on isoparametric
//! hexahedra and tetrahedra: the formulation (shape functions, quadrature) of
//! the kinds of the element catalogue `crate::input::element`, which says
//! what each kind is (names, node order).
//!
//! The formulation mirrors CalculiX 2.20 (e_c3d.f) so that eigenfrequencies
//! computed from these matrices match CalculiX on the same mesh. e_c3d.f
//! integrates stiffness and consistent mass in one loop over the same points
//! (`mint3d`, chosen from the element type when `intscheme = 0`, which is what
//! *FREQUENCY passes, arpack.c), so every type integrates its mass with its
//! stiffness rule, reduced or not:
//!
//! | kind   | CalculiX | stiffness and mass rule            |
//! |--------|----------|------------------------------------|
//! | hex8   | C3D8     | 2x2x2 Gauss (gauss3d2), no incompatible modes |
//! | hex20  | C3D20    | 3x3x3 Gauss (gauss3d3)             |
//! | hex20r | C3D20R   | 2x2x2 Gauss (gauss3d2)             |
//! | tet4   | C3D4     | 1 point at the centroid (gauss3d4) |
//! | tet10  | C3D10    | 4 points, degree 2 (gauss3d5)      |
//!
//! Consequently the scalar element mass has at most one rank per point: C3D4
//! is rho V / 16 in every entry (rank 1 of 4), C3D10 has rank 4 of 10 and
//! C3D20R rank 8 of 20. Singular per element, the assembled mass is regular
//! only once enough elements share the nodes. That is CalculiX's model,
//! reproduced on purpose (eigenfrequencies would move by percents otherwise).
//! Stiffness and mass rules are still separate (`stiffness_rule`,
//! `mass_rule`) because CalculiX itself switches rules with `intscheme = 1`
//! (C3D4 to 4 points, C3D20R to 27, for initial accelerations of dynamic
//! steps).
//!
//! Degrees of freedom are three translations per node, node-major:
//! `[u0x, u0y, u0z, u1x, u1y, u1z, ...]`.

pub mod gauss;
pub mod geometric;
pub mod hex20;
pub mod hex8;
pub mod stress;
pub mod tet10;
pub mod tet4;

use crate::input::element::{ElementKind, MAX_NODES_PER_ELEMENT};
use gauss::{GaussOrder, Rule};

/// Quadrature of the stiffness and of the geometric (stress) stiffness,
/// which CalculiX evaluates at the same points (e_c3d.f, `mint3d`).
pub const fn stiffness_rule(kind: ElementKind) -> Rule {
    match kind {
        ElementKind::Hex8 | ElementKind::Hex20R => Rule::Hex(GaussOrder::Two),
        ElementKind::Hex20 => Rule::Hex(GaussOrder::Three),
        ElementKind::Tet4 => Rule::TetOne,
        ElementKind::Tet10 => Rule::TetFour,
    }
}

/// Quadrature of the consistent mass. CalculiX accumulates the mass in the
/// stiffness loop, so this is the stiffness rule for every kind, including
/// the reduced C3D20R and the one-point C3D4 (verified entry by entry
/// against `*FREQUENCY, SOLVER=MATRIXSTORAGE` of ccx 2.20).
pub const fn mass_rule(kind: ElementKind) -> Rule {
    stiffness_rule(kind)
}

/// Shape functions `n` and their derivatives with respect to the natural
/// coordinates `dn[node] = [dN/dxi, dN/deta, dN/dzeta]` of `kind` at `xi`.
/// Only the first `kind.nodes_per_element()` entries of the slices are written.
pub(crate) fn shape_functions(kind: ElementKind, xi: [f64; 3], n: &mut [f64], dn: &mut [[f64; 3]]) {
    match kind {
        ElementKind::Hex8 => hex8::shape_functions(xi, n, dn),
        ElementKind::Hex20 | ElementKind::Hex20R => hex20::shape_functions(xi, n, dn),
        ElementKind::Tet4 => tet4::shape_functions(xi, n, dn),
        ElementKind::Tet10 => tet10::shape_functions(xi, n, dn),
    }
}

/// Isotropic linear elastic material.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Elasticity {
    /// Young's modulus.
    pub e: f64,
    /// Poisson's ratio.
    pub nu: f64,
}

impl Elasticity {
    /// Positive-definite strain energy needs E > 0 and -1 < nu < 0.5.
    pub fn validate(&self) -> Result<(), ElementError> {
        let ok = self.e.is_finite() && self.e > 0.0 && self.nu > -1.0 && self.nu < 0.5;
        if ok { Ok(()) } else { Err(ElementError::InvalidMaterial { e: self.e, nu: self.nu }) }
    }

    /// Lame parameters (lambda, mu).
    pub fn lame(&self) -> (f64, f64) {
        let lambda = self.e * self.nu / ((1.0 + self.nu) * (1.0 - 2.0 * self.nu));
        let mu = self.e / (2.0 * (1.0 + self.nu));
        (lambda, mu)
    }

    /// 6x6 constitutive matrix in Voigt order xx, yy, zz, xy, yz, zx acting on
    /// engineering shear strains (gamma = 2 epsilon). CalculiX orders the
    /// shear components xy, xz, yz; for an isotropic material the matrix is
    /// invariant under that permutation, so the element matrices are equal.
    pub fn d_matrix(&self) -> [[f64; 6]; 6] {
        let (lambda, mu) = self.lame();
        let mut d = [[0.0; 6]; 6];
        for (i, row) in d.iter_mut().enumerate().take(3) {
            for (j, v) in row.iter_mut().enumerate().take(3) {
                *v = if i == j { lambda + 2.0 * mu } else { lambda };
            }
        }
        for (i, row) in d.iter_mut().enumerate().skip(3) {
            row[i] = mu;
        }
        d
    }
}

/// Why an element matrix could not be computed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ElementError {
    /// `coords` does not hold one point per element node.
    #[error("{kind} element needs {expected} node coordinates, got {got}")]
    WrongNodeCount { kind: ElementKind, expected: usize, got: usize },
    /// The output buffer has the wrong length.
    #[error("element matrix buffer must hold {expected} entries, got {got}")]
    WrongOutputSize { expected: usize, got: usize },
    /// A node coordinate is NaN or infinite.
    #[error("element node {node} has a non-finite coordinate")]
    NonFiniteCoordinate { node: usize },
    /// E <= 0 or nu outside (-1, 0.5).
    #[error("invalid elastic material (E = {e}, nu = {nu}): need E > 0 and -1 < nu < 0.5")]
    InvalidMaterial { e: f64, nu: f64 },
    /// Density not finite and positive.
    #[error("invalid density {rho}: must be finite and positive")]
    InvalidDensity { rho: f64 },
    /// Inverted or degenerate element: det J <= 0 at a Gauss point.
    #[error(
        "{kind} element is inverted or degenerate: Jacobian determinant {det:e} at Gauss point {gauss_point} \
         (natural coordinates {:.4}, {:.4}, {:.4})",
        .xi[0], .xi[1], .xi[2]
    )]
    NonPositiveJacobian { kind: ElementKind, gauss_point: usize, xi: [f64; 3], det: f64 },
}

/// Element stiffness matrix (3n x 3n, row-major, node-major DoFs) written to
/// `out`, which must have exactly `(3n)^2` entries.
pub fn element_stiffness(
    kind: ElementKind,
    coords: &[[f64; 3]],
    mat: &Elasticity,
    out: &mut [f64],
) -> Result<(), ElementError> {
    mat.validate()?;
    let n = kind.nodes_per_element();
    let dofs = 3 * n;
    check_output(out, dofs * dofs)?;
    let d = mat.d_matrix();
    out.fill(0.0);

    // D * B_b for every node, reused for all node pairs at one Gauss point.
    let mut db = [[[0.0; 3]; 6]; MAX_NODES_PER_ELEMENT];
    for_each_gauss_point(kind, stiffness_rule(kind), coords, |_, grad, weight| {
        for (db_b, g) in db.iter_mut().zip(grad) {
            let b = strain_displacement(g);
            for (r, row) in db_b.iter_mut().enumerate() {
                for (j, v) in row.iter_mut().enumerate() {
                    *v = (0..6).map(|k| d[r][k] * b[k][j]).sum::<f64>() * weight;
                }
            }
        }
        // Only the upper triangle is accumulated; the mirror below keeps the
        // matrix exactly symmetric regardless of rounding.
        for a in 0..n {
            let b_a = strain_displacement(&grad[a]);
            for (b, db_b) in db.iter().enumerate().take(n).skip(a) {
                for i in 0..3 {
                    let first_j = if b == a { i } else { 0 };
                    for j in first_j..3 {
                        let k: f64 = (0..6).map(|r| b_a[r][i] * db_b[r][j]).sum();
                        out[(3 * a + i) * dofs + 3 * b + j] += k;
                    }
                }
            }
        }
    })?;
    mirror_upper_triangle(out, 3 * n);
    Ok(())
}

/// Scalar consistent mass matrix (n x n, row-major) `M_ab = int rho N_a N_b dV`
/// written to `out`, which must have exactly `n^2` entries.
///
/// The full 3n x 3n mass matrix for node-major DoFs is this matrix Kronecker
/// the 3x3 identity (`M_full[3a+i][3b+j] = M[a][b] * delta_ij`); the caller
/// expands it, which keeps the element output 9 times smaller.
pub fn element_mass(kind: ElementKind, coords: &[[f64; 3]], rho: f64, out: &mut [f64]) -> Result<(), ElementError> {
    if !(rho.is_finite() && rho > 0.0) {
        return Err(ElementError::InvalidDensity { rho });
    }
    let n = kind.nodes_per_element();
    check_output(out, n * n)?;
    out.fill(0.0);
    for_each_gauss_point(kind, mass_rule(kind), coords, |shape, _, weight| {
        for a in 0..n {
            for b in a..n {
                out[a * n + b] += rho * shape[a] * shape[b] * weight;
            }
        }
    })?;
    mirror_upper_triangle(out, n);
    Ok(())
}

fn check_output(out: &[f64], expected: usize) -> Result<(), ElementError> {
    if out.len() == expected { Ok(()) } else { Err(ElementError::WrongOutputSize { expected, got: out.len() }) }
}

/// Strain-displacement block of one node for engineering strains in Voigt
/// order xx, yy, zz, xy, yz, zx; `g` is the physical gradient of its shape
/// function.
pub(crate) fn strain_displacement(g: &[f64; 3]) -> [[f64; 3]; 6] {
    [[g[0], 0.0, 0.0], [0.0, g[1], 0.0], [0.0, 0.0, g[2]], [g[1], g[0], 0.0], [0.0, g[2], g[1]], [g[2], 0.0, g[0]]]
}

/// Copies the upper triangle of the `size` x `size` matrix onto the lower.
fn mirror_upper_triangle(m: &mut [f64], size: usize) {
    for row in 1..size {
        for col in 0..row {
            m[row * size + col] = m[col * size + row];
        }
    }
}

/// Runs `f(shape, physical_gradients, det_j * weight)` at every point of
/// `rule`. Only the first `nodes_per_element` entries of the slices passed to
/// `f` are meaningful.
pub(crate) fn for_each_gauss_point(
    kind: ElementKind,
    rule: Rule,
    coords: &[[f64; 3]],
    mut f: impl FnMut(&[f64], &[[f64; 3]], f64),
) -> Result<(), ElementError> {
    let n = kind.nodes_per_element();
    if coords.len() != n {
        return Err(ElementError::WrongNodeCount { kind, expected: n, got: coords.len() });
    }
    if let Some(node) = coords.iter().position(|p| p.iter().any(|c| !c.is_finite())) {
        return Err(ElementError::NonFiniteCoordinate { node });
    }
    let mut shape = [0.0; MAX_NODES_PER_ELEMENT];
    let mut dn = [[0.0; 3]; MAX_NODES_PER_ELEMENT];
    let mut grad = [[0.0; 3]; MAX_NODES_PER_ELEMENT];
    for (gauss_point, (xi, weight)) in rule.points().enumerate() {
        shape_functions(kind, xi, &mut shape[..n], &mut dn[..n]);
        // J[i][j] = d x_j / d xi_i.
        let mut jac = [[0.0; 3]; 3];
        for (dn_a, x_a) in dn.iter().zip(coords) {
            for i in 0..3 {
                for j in 0..3 {
                    jac[i][j] += dn_a[i] * x_a[j];
                }
            }
        }
        let (det, inv) = invert3(&jac);
        if det.is_nan() || det <= 0.0 {
            return Err(ElementError::NonPositiveJacobian { kind, gauss_point, xi, det });
        }
        // dN/dx = J^-1 dN/dxi.
        for (g, dn_a) in grad.iter_mut().zip(&dn).take(n) {
            for (i, g_i) in g.iter_mut().enumerate() {
                *g_i = inv[i][0] * dn_a[0] + inv[i][1] * dn_a[1] + inv[i][2] * dn_a[2];
            }
        }
        f(&shape[..n], &grad[..n], det * weight);
    }
    Ok(())
}

/// Determinant and inverse (via the adjugate) of a 3x3 matrix. The inverse is
/// meaningless when the determinant is zero; callers check it first.
fn invert3(m: &[[f64; 3]; 3]) -> (f64, [[f64; 3]; 3]) {
    let c00 = m[1][1] * m[2][2] - m[1][2] * m[2][1];
    let c01 = m[1][2] * m[2][0] - m[1][0] * m[2][2];
    let c02 = m[1][0] * m[2][1] - m[1][1] * m[2][0];
    let det = m[0][0] * c00 + m[0][1] * c01 + m[0][2] * c02;
    let r = 1.0 / det;
    let inv = [
        [c00 * r, (m[0][2] * m[2][1] - m[0][1] * m[2][2]) * r, (m[0][1] * m[1][2] - m[0][2] * m[1][1]) * r],
        [c01 * r, (m[0][0] * m[2][2] - m[0][2] * m[2][0]) * r, (m[0][2] * m[1][0] - m[0][0] * m[1][2]) * r],
        [c02 * r, (m[0][1] * m[2][0] - m[0][0] * m[2][1]) * r, (m[0][0] * m[1][1] - m[0][1] * m[1][0]) * r],
    ];
    (det, inv)
}

#[cfg(test)]
mod tests;
