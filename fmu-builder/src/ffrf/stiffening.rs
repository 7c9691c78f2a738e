//! Reduced geometric stiffness of unit prestress states: K_G = Phi^T K_sigma(u_L) Phi for the
//! static response u_L to a unit load case, accumulated element by element so the full K_sigma is
//! never assembled. Linear in the load: the runtime scales each case by its present load.

use crate::error::{BuildError, Result};
use crate::input::element::{ElementKind, MAX_NODES_PER_ELEMENT};
use crate::input::mesh::Mesh;
use crate::model::assembly::SolidMaterial;
use crate::model::fe::geometric::element_geometric_stiffness;
use faer::{Mat, MatRef};

/// Phi^T K_sigma(u) Phi (r x r, symmetric) for the mesh-level prestress displacement `u` (3N) and
/// mesh-level basis `phi` (3N x r).
pub fn reduced_geometric_stiffness(
    mesh: &Mesh,
    materials: &[SolidMaterial],
    u: &[f64],
    phi: MatRef<'_, f64>,
) -> Result<Mat<f64>> {
    let r = phi.ncols();
    let mut out = Mat::<f64>::zeros(r, r);
    let mut coords_buf = [[0.0; 3]; MAX_NODES_PER_ELEMENT];
    let mut ue_buf = vec![0.0; 3 * MAX_NODES_PER_ELEMENT];
    let mut ks_buf = vec![0.0; MAX_NODES_PER_ELEMENT * MAX_NODES_PER_ELEMENT];
    for e in 0..mesh.n_elements() {
        let kind: ElementKind = mesh.kind(e);
        let material = &materials[mesh.material[e]].elasticity;
        let nen = kind.nodes_per_element();
        let ue = &mut ue_buf[..3 * nen];
        let ks = &mut ks_buf[..nen * nen];
        let mut p = Mat::<f64>::zeros(nen, r);
        let nodes = mesh.element(e);
        for (a, &n) in nodes.iter().enumerate() {
            for i in 0..3 {
                ue[3 * a + i] = u[3 * n + i];
            }
        }
        let coords = mesh.element_coords(e, &mut coords_buf);
        element_geometric_stiffness(kind, coords, material, ue, ks)
            .map_err(|err| BuildError::numerical(format!("element {e}: {err}")).caused_by(err))?;
        let k = Mat::<f64>::from_fn(nen, nen, |a, b| ks[a * nen + b]);
        for i in 0..3 {
            for (a, &n) in nodes.iter().enumerate() {
                for j in 0..r {
                    p[(a, j)] = phi[(3 * n + i, j)];
                }
            }
            out += p.transpose() * (&k * &p);
        }
    }
    let sym = Mat::<f64>::from_fn(r, r, |i, j| 0.5 * (out[(i, j)] + out[(j, i)]));
    Ok(sym)
}
