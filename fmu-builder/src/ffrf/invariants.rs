//! Floating-frame invariants of the reduced body (docs/ARCHITECTURE.md, "Equations"): what the runtime
//! needs to couple the elastic coordinates to the body frame's rigid motion. All are projections
//! of the consistent mass onto rigid-body fields and the basis, computed once here.

use crate::ffrf::rows::{Layout, Rows, transpose_times};
use crate::model::flange::Flange;
use crate::model::rigid_coupling::{Assembled, DofOf, NodeDofs};
use crate::reduce::basis::Basis;
use faer::{Mat, MatRef};

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
    let layout = Layout::natural(model.dofs.n_dofs);
    rigid_rows(&layout, model, nodes, flanges, origin).as_mat().to_owned()
}

/// `rigid_fields` with a DoF's six values side by side, as the mass product wants them.
fn rigid_rows<'a>(
    layout: &'a Layout,
    model: &Assembled,
    nodes: &[[f64; 3]],
    flanges: &[Flange],
    origin: [f64; 3],
) -> Rows<'a> {
    let d = &model.dofs;
    let mut r = Rows::from_fn(layout, 6, |_, _| {});
    // DoF g as direction i of a point at p (moving rigidly); a master's rotation DoFs rotate
    let put = |r: &mut Rows<'a>, g: usize, p: [f64; 3], i: usize| {
        let x = [p[0] - origin[0], p[1] - origin[1], p[2] - origin[2]];
        // rot[a] = e_a x x
        let rot = [[0.0, -x[2], x[1]], [x[2], 0.0, -x[0]], [-x[1], x[0], 0.0]];
        let row = r.row_mut(g);
        row[i] = 1.0;
        for (a, rot_a) in rot.iter().enumerate() {
            row[3 + a] = rot_a[i];
        }
    };
    for (n, nd) in d.node.iter().enumerate() {
        match *nd {
            NodeDofs::Free(first) => (0..3).for_each(|i| put(&mut r, first + i, nodes[n], i)),
            // a distributing flange's node: its own directions (the dependent ones follow)
            NodeDofs::Partial(dofs) => {
                for (i, dof) in dofs.iter().enumerate() {
                    if let DofOf::Own(g) = *dof {
                        put(&mut r, g, nodes[n], i);
                    }
                }
            }
            NodeDofs::Slave(_) => {}
        }
    }
    for (k, f) in flanges.iter().enumerate() {
        (0..3).for_each(|i| put(&mut r, d.flange_first[k] + i, f.reference, i));
        for i in 0..3 {
            r.row_mut(d.flange_first[k] + 3 + i)[3 + i] = 1.0;
        }
    }
    r
}

/// The invariants of `basis`. The mass products run here on every back-end: the builder holds
/// the mass, they cost a few sparse products, and the same order of operations makes the
/// invariants of equal bases equal to the bit.
pub fn invariants(
    model: &Assembled,
    nodes: &[[f64; 3]],
    flanges: &[Flange],
    origin: [f64; 3],
    basis: &Basis,
) -> Invariants {
    let (c_t, c_r, rigid_mass) = rigid_projections(model, nodes, flanges, origin, basis.phi.as_ref());
    let flange_shapes = flange_shapes(model, flanges, basis.phi.as_ref());
    Invariants { c_t, c_r, flange_shapes, rigid_mass }
}

/// C_t and C_r (3 x r row-major each) and the rigid translation masses. The coupled mass is
/// applied to the six rigid fields in one pass over its entries (it is symmetric, as
/// `Rows::symmetric_times` needs).
fn rigid_projections(
    model: &Assembled,
    nodes: &[[f64; 3]],
    flanges: &[Flange],
    origin: [f64; 3],
    phi: MatRef<'_, f64>,
) -> (Vec<f64>, Vec<f64>, [f64; 3]) {
    let d = &model.dofs;
    let rb = phi.ncols();
    // six values a DoF fit the cache in any order: the natural one keeps the clamped DoFs first
    let layout = Layout::natural(d.n_dofs);
    let rigid = rigid_rows(&layout, model, nodes, flanges, origin);
    let m_rigid = Rows::symmetric_times(&model.mass, &rigid);
    // (M R)^T Phi over the clamped DoFs (Phi vanishes on the mount's)
    let proj = transpose_times(m_rigid.as_mat().subrows(0, d.n_clamped()), phi);
    let mut c_t = vec![0.0; 3 * rb];
    let mut c_r = vec![0.0; 3 * rb];
    for a in 0..3 {
        for j in 0..rb {
            c_t[a * rb + j] = proj[(a, j)];
            c_r[a * rb + j] = proj[(3 + a, j)];
        }
    }
    let mut rigid_mass = [0.0; 3];
    for (a, mass) in rigid_mass.iter_mut().enumerate() {
        *mass = (0..d.n_dofs).map(|i| rigid.row(i)[a] * m_rigid.row(i)[a]).sum();
    }
    (c_t, c_r, rigid_mass)
}

/// Per flange in input order, its master's six rows of the basis (zero for the mount).
fn flange_shapes(model: &Assembled, flanges: &[Flange], phi: MatRef<'_, f64>) -> Vec<Vec<f64>> {
    let d = &model.dofs;
    let rb = phi.ncols();
    (0..flanges.len())
        .map(|k| {
            let mut s = vec![0.0; 6 * rb];
            if Some(k) != d.mount {
                let first = d.flange_first[k];
                for i in 0..6 {
                    for j in 0..rb {
                        s[i * rb + j] = phi[(first + i, j)];
                    }
                }
            }
            s
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ffrf::inertia::tests::{Bar, assert_close, bar};
    use crate::linalg::sparse::mul_new;

    /// The straightforward formulation the fast one replaced: the dense rigid fields through
    /// faer's sparse product, then one dense product.
    fn reference(
        model: &Assembled,
        nodes: &[[f64; 3]],
        flanges: &[Flange],
        origin: [f64; 3],
        phi: MatRef<'_, f64>,
    ) -> (Mat<f64>, [f64; 3]) {
        let rigid = rigid_fields(model, nodes, flanges, origin);
        let m_rigid = mul_new(&model.mass, rigid.as_ref());
        let proj = m_rigid.subrows(0, model.dofs.n_clamped()).transpose() * phi;
        let mass = std::array::from_fn(|a| (0..model.dofs.n_dofs).map(|i| rigid[(i, a)] * m_rigid[(i, a)]).sum());
        (proj, mass)
    }

    #[test]
    fn rigid_projections_equal_the_reference_formulation() {
        let Bar { nodes, flanges, model, origin, phi } = bar(4);
        let (c_t, c_r, mass) = rigid_projections(&model, &nodes, &flanges, origin, phi.as_ref());
        let (proj, expected_mass) = reference(&model, &nodes, &flanges, origin, phi.as_ref());
        let rows = |from: usize| -> Vec<f64> {
            (from..from + 3).flat_map(|a| (0..4).map(move |j| (a, j))).map(|(a, j)| proj[(a, j)]).collect()
        };
        // same products summed in another order: round-off (see `assert_close`)
        assert_close(&c_t, &rows(0), 1e-12, "C_t");
        assert_close(&c_r, &rows(3), 1e-12, "C_r");
        assert_close(&mass, &expected_mass, 1e-12, "rigid mass");
        // the coupling keeps rigid translation exact: the mesh's mass, to round-off
        assert_close(&mass, &[model.mass_properties.mass; 3], 1e-12, "mesh mass");
    }

    #[test]
    fn flange_shapes_are_the_masters_rows() {
        let Bar { flanges, model, phi, .. } = bar(2);
        let shapes = flange_shapes(&model, &flanges, phi.as_ref());
        assert_eq!(shapes.len(), 2);
        assert!(shapes[0].iter().all(|&v| v == 0.0), "the mount's shapes are zero");
        let first = model.dofs.flange_first[1];
        assert_eq!(shapes[1].len(), 12);
        assert_eq!(shapes[1][2 * 2 + 1], phi[(first + 2, 1)]);
    }
}
