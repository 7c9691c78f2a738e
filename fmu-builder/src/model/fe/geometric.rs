//! Geometric (stress) stiffness of a prestressed element: the second-order work of the prestress
//! sigma on the displacement gradient, K_sigma[a i, b j] = delta_ij int grad N_a . sigma grad N_b dV.
//! The prestress is that of a linear static displacement field u_e (stress = D B u_e at each Gauss
//! point), which is how the builder turns unit load cases into load-proportional stiffness.

use super::{Elasticity, ElementError, for_each_gauss_point, stiffness_rule, strain_displacement};
use crate::input::element::ElementKind;

/// Scalar geometric stiffness (n x n, row-major): the full 3n x 3n matrix is this Kronecker I3.
/// `u_e` holds the element's nodal displacements of the prestress state (3n, node-major).
pub fn element_geometric_stiffness(
    kind: ElementKind,
    coords: &[[f64; 3]],
    mat: &Elasticity,
    u_e: &[f64],
    out: &mut [f64],
) -> Result<(), ElementError> {
    mat.validate()?;
    let n = kind.nodes_per_element();
    if out.len() != n * n {
        return Err(ElementError::WrongOutputSize { expected: n * n, got: out.len() });
    }
    if u_e.len() != 3 * n {
        return Err(ElementError::WrongOutputSize { expected: 3 * n, got: u_e.len() });
    }
    let d = mat.d_matrix();
    out.fill(0.0);
    // CalculiX adds the stress stiffness in its stiffness loop, with the
    // stresses stored at those points (sti), hence the stiffness rule.
    for_each_gauss_point(kind, stiffness_rule(kind), coords, |_, grad, weight| {
        // engineering strain, then stress (Voigt xx, yy, zz, xy, yz, zx)
        let mut eps = [0.0; 6];
        for a in 0..n {
            let b = strain_displacement(&grad[a]);
            for r in 0..6 {
                for i in 0..3 {
                    eps[r] += b[r][i] * u_e[3 * a + i];
                }
            }
        }
        let mut s = [0.0; 6];
        for r in 0..6 {
            s[r] = (0..6).map(|k| d[r][k] * eps[k]).sum();
        }
        let sigma = [[s[0], s[3], s[5]], [s[3], s[1], s[4]], [s[5], s[4], s[2]]];
        for a in 0..n {
            let ga = grad[a];
            let sg = [
                sigma[0][0] * ga[0] + sigma[0][1] * ga[1] + sigma[0][2] * ga[2],
                sigma[1][0] * ga[0] + sigma[1][1] * ga[1] + sigma[1][2] * ga[2],
                sigma[2][0] * ga[0] + sigma[2][1] * ga[1] + sigma[2][2] * ga[2],
            ];
            for b in 0..n {
                let gb = grad[b];
                out[a * n + b] += (sg[0] * gb[0] + sg[1] * gb[1] + sg[2] * gb[2]) * weight;
            }
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::fe::{tet4, tet10};

    /// A bar under uniform axial stress sigma_xx = s: the geometric stiffness is the "string"
    /// stiffness s A int N_a' N_b' dx for transverse motion; a transverse rigid rotation theta
    /// about z (u_y = theta x) stores energy 1/2 s V theta^2 (s theta^2 per unit volume).
    /// The element is an axis-aligned 2 x 0.3 x 0.2 box (hexahedra) or the corner tetrahedron of
    /// that box (volume 1/6 of it); every rule integrates the constant integrand exactly.
    #[test]
    fn uniform_tension_stores_the_string_energy_of_a_rotation() {
        let size = [2.0, 0.3, 0.2];
        for kind in ElementKind::ALL {
            let (reference, volume): (Vec<[f64; 3]>, f64) = match kind.natural_node_coords() {
                Some(lattice) => (
                    lattice.iter().map(|c| c.map(|v| 0.5 * (f64::from(v) + 1.0))).collect(),
                    size[0] * size[1] * size[2],
                ),
                None if kind == ElementKind::Tet4 => (tet4::NATURAL_COORDS.to_vec(), size[0] * size[1] * size[2] / 6.0),
                None => (tet10::NATURAL_COORDS.to_vec(), size[0] * size[1] * size[2] / 6.0),
            };
            let coords: Vec<[f64; 3]> =
                reference.iter().map(|c| [c[0] * size[0], c[1] * size[1], c[2] * size[2]]).collect();
            let n = coords.len();
            let mat = Elasticity { e: 1e9, nu: 0.0 };
            let strain = 1e-3; // u_x = strain * x: sigma_xx = E strain (nu = 0)
            let u: Vec<f64> = coords.iter().flat_map(|p| [strain * p[0], 0.0, 0.0]).collect();
            let mut k = vec![0.0; n * n];
            element_geometric_stiffness(kind, &coords, &mat, &u, &mut k).unwrap();
            let theta = 0.01;
            let uy: Vec<f64> = coords.iter().map(|p| theta * p[0]).collect();
            let energy: f64 =
                (0..n).map(|a| (0..n).map(|b| uy[a] * k[a * n + b] * uy[b]).sum::<f64>()).sum::<f64>() * 0.5;
            let expected = 0.5 * mat.e * strain * volume * theta * theta;
            assert!((energy - expected).abs() < 1e-10 * expected, "{kind}: {energy} vs {expected}");
            // rigid translation stores nothing
            let e0: f64 = k.iter().sum();
            assert!(e0.abs() < 1e-6 * expected, "{kind}: {e0}");
        }
    }
}
