//! Floating-frame invariants of the reduced body (docs/ARCHITECTURE.md, "Equations"): what the runtime
//! needs to couple the elastic coordinates to the body frame's rigid motion. All are projections
//! of the consistent mass onto rigid-body fields and the basis, computed once here.

use crate::linalg::sparse::mul_new;
use crate::model::flange::Flange;
use crate::model::rigid_coupling::{Assembled, NodeDofs};
use crate::reduce::basis::Basis;
use faer::Mat;

pub struct Invariants {
    /// C_t = T^T M Phi, 3 x r row-major.
    pub c_t: Vec<f64>,
    /// C_r = R^T M Phi (R: rigid rotations about the origin), 3 x r row-major.
    pub c_r: Vec<f64>,
    /// Per flange in input order (the mount's shapes are zero): 6 x r row-major.
    pub flange_shapes: Vec<Vec<f64>>,
    /// Mass from the rigid translation fields of the constrained model: equals the mesh mass,
    /// a check that the coupling kept rigid motion exact.
    pub rigid_mass: [f64; 3],
}

/// The six rigid-body fields of the constrained model about `origin` (n_dofs x 6):
/// columns 0..3 translations, 3..6 infinitesimal rotations.
pub fn rigid_fields(model: &Assembled, nodes: &[[f64; 3]], flanges: &[Flange], origin: [f64; 3]) -> Mat<f64> {
    let d = &model.dofs;
    let mut r = Mat::<f64>::zeros(d.n_dofs, 6);
    let mut put = |first: usize, p: [f64; 3], with_rotation: bool| {
        let x = [p[0] - origin[0], p[1] - origin[1], p[2] - origin[2]];
        for a in 0..3 {
            r[(first + a, a)] = 1.0;
        }
        // e_a x x
        let rot = [[0.0, -x[2], x[1]], [x[2], 0.0, -x[0]], [-x[1], x[0], 0.0]];
        for a in 0..3 {
            for i in 0..3 {
                r[(first + i, 3 + a)] = rot[a][i];
            }
            if with_rotation {
                r[(first + 3 + a, 3 + a)] = 1.0;
            }
        }
    };
    for (n, nd) in d.node.iter().enumerate() {
        if let NodeDofs::Free(first) = nd {
            put(*first, nodes[n], false);
        }
    }
    for (k, f) in flanges.iter().enumerate() {
        put(d.flange_first[k], f.reference, true);
    }
    r
}

pub fn invariants(
    model: &Assembled,
    nodes: &[[f64; 3]],
    flanges: &[Flange],
    origin: [f64; 3],
    basis: &Basis,
) -> Invariants {
    let d = &model.dofs;
    let nc = d.n_clamped();
    let rb = basis.phi.ncols();
    let rigid = rigid_fields(model, nodes, flanges, origin);
    let m_rigid = mul_new(&model.mass, rigid.as_ref());
    // (M R)^T Phi over the clamped DoFs (Phi vanishes on the mount's)
    let proj = m_rigid.subrows(0, nc).transpose() * &basis.phi;
    let mut c_t = vec![0.0; 3 * rb];
    let mut c_r = vec![0.0; 3 * rb];
    for a in 0..3 {
        for j in 0..rb {
            c_t[a * rb + j] = proj[(a, j)];
            c_r[a * rb + j] = proj[(3 + a, j)];
        }
    }
    let mut rigid_mass = [0.0; 3];
    for a in 0..3 {
        rigid_mass[a] = (0..d.n_dofs).map(|i| rigid[(i, a)] * m_rigid[(i, a)]).sum();
    }
    let flange_shapes = flanges
        .iter()
        .enumerate()
        .map(|(k, _)| {
            let mut s = vec![0.0; 6 * rb];
            if Some(k) != d.mount {
                let first = d.flange_first[k];
                for i in 0..6 {
                    for j in 0..rb {
                        s[i * rb + j] = basis.phi[(first + i, j)];
                    }
                }
            }
            s
        })
        .collect();
    Invariants { c_t, c_r, flange_shapes, rigid_mass }
}
