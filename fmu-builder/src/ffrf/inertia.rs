//! Mesh-level fields for the floating frame: the basis expanded to every mesh node (slaves follow
//! their flange rigidly), inertial load cases of frame motion, and the rotation invariants of
//! docs/ARCHITECTURE.md (G_a, O_ab, o_ab). Cross products act per node (E_a w = e_a x w_j), and with the
//! consistent mass M = M_s (x) I3 they commute with M, so every invariant is a product of the
//! nodal mass with per-node cross products of the basis and the positions.

use crate::linalg::sparse::mul_new;
use crate::model::flange::Flange;
use crate::model::rigid_coupling::{Assembled, NodeDofs};
use faer::{Mat, MatRef};

/// A unit inertial load case of the frame's motion (loads on the body, in the body frame).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LoadCase {
    /// a_B = e_a: body force -rho e_a (gravity and translational acceleration).
    Translation(usize),
    /// angular acceleration e_a: body force -rho e_a x x.
    Euler(usize),
    /// coefficient of w_a w_b (a <= b) in the centrifugal body force -rho w x (w x x).
    Centrifugal(usize, usize),
}

impl LoadCase {
    pub fn translations() -> Vec<LoadCase> {
        (0..3).map(LoadCase::Translation).collect()
    }
    pub fn rotations() -> Vec<LoadCase> {
        let mut v: Vec<LoadCase> = (0..3).map(LoadCase::Euler).collect();
        for a in 0..3 {
            for b in a..3 {
                v.push(LoadCase::Centrifugal(a, b));
            }
        }
        v
    }
}

/// Positions relative to the body origin as a mesh field (3N x 1, node-major).
pub fn positions(nodes: &[[f64; 3]], origin: [f64; 3]) -> Mat<f64> {
    Mat::from_fn(3 * nodes.len(), 1, |r, _| nodes[r / 3][r % 3] - origin[r % 3])
}

/// E_a w: e_a x w per node, for every column.
pub fn cross_axis(a: usize, w: MatRef<'_, f64>) -> Mat<f64> {
    let n = w.nrows() / 3;
    let mut out = Mat::<f64>::zeros(w.nrows(), w.ncols());
    let (b, c) = ((a + 1) % 3, (a + 2) % 3);
    for j in 0..w.ncols() {
        for node in 0..n {
            // (e_a x w)_b = -w_c, (e_a x w)_c = w_b (cyclic a, b, c)
            out[(3 * node + b, j)] = -w[(3 * node + c, j)];
            out[(3 * node + c, j)] = w[(3 * node + b, j)];
        }
    }
    out
}

/// (M_s (x) I3) w
pub fn mass_times(model: &Assembled, w: MatRef<'_, f64>) -> Mat<f64> {
    let n = w.nrows() / 3;
    let mut out = Mat::<f64>::zeros(w.nrows(), w.ncols());
    for comp in 0..3 {
        let part = Mat::<f64>::from_fn(n, w.ncols(), |i, j| w[(3 * i + comp, j)]);
        let mp = mul_new(&model.nodal_mass, part.as_ref());
        for i in 0..n {
            for j in 0..w.ncols() {
                out[(3 * i + comp, j)] = mp[(i, j)];
            }
        }
    }
    out
}

/// A constrained-model field (n_clamped x k; the mount held) on every mesh node (3N x k).
pub fn expand(model: &Assembled, nodes: &[[f64; 3]], flanges: &[Flange], phi: MatRef<'_, f64>) -> Mat<f64> {
    let d = &model.dofs;
    let nc = d.n_clamped();
    let mut out = Mat::<f64>::zeros(3 * nodes.len(), phi.ncols());
    for (n, nd) in d.node.iter().enumerate() {
        match *nd {
            NodeDofs::Free(first) => {
                for i in 0..3 {
                    for j in 0..phi.ncols() {
                        out[(3 * n + i, j)] = phi[(first + i, j)];
                    }
                }
            }
            NodeDofs::Slave(k) => {
                let first = d.flange_first[k];
                if first >= nc {
                    continue; // the mount: held
                }
                let r = flanges[k].reference;
                let x = [nodes[n][0] - r[0], nodes[n][1] - r[1], nodes[n][2] - r[2]];
                for j in 0..phi.ncols() {
                    let u = [phi[(first, j)], phi[(first + 1, j)], phi[(first + 2, j)]];
                    let t = [phi[(first + 3, j)], phi[(first + 4, j)], phi[(first + 5, j)]];
                    // u + theta x x
                    out[(3 * n, j)] = u[0] + t[1] * x[2] - t[2] * x[1];
                    out[(3 * n + 1, j)] = u[1] + t[2] * x[0] - t[0] * x[2];
                    out[(3 * n + 2, j)] = u[2] + t[0] * x[1] - t[1] * x[0];
                }
            }
        }
    }
    out
}

/// Nodal forces on the mesh (3N x k) as loads on the constrained model (n_clamped x k): slave
/// forces move to their flange's master as force and moment; the mount's slaves are held.
pub fn restrict(model: &Assembled, nodes: &[[f64; 3]], flanges: &[Flange], f: MatRef<'_, f64>) -> Mat<f64> {
    let d = &model.dofs;
    let nc = d.n_clamped();
    let mut out = Mat::<f64>::zeros(nc, f.ncols());
    for (n, nd) in d.node.iter().enumerate() {
        match *nd {
            NodeDofs::Free(first) => {
                for i in 0..3 {
                    for j in 0..f.ncols() {
                        out[(first + i, j)] += f[(3 * n + i, j)];
                    }
                }
            }
            NodeDofs::Slave(k) => {
                let first = d.flange_first[k];
                if first >= nc {
                    continue;
                }
                let r = flanges[k].reference;
                let x = [nodes[n][0] - r[0], nodes[n][1] - r[1], nodes[n][2] - r[2]];
                for j in 0..f.ncols() {
                    let fj = [f[(3 * n, j)], f[(3 * n + 1, j)], f[(3 * n + 2, j)]];
                    for i in 0..3 {
                        out[(first + i, j)] += fj[i];
                    }
                    // moment x x f
                    out[(first + 3, j)] += x[1] * fj[2] - x[2] * fj[1];
                    out[(first + 4, j)] += x[2] * fj[0] - x[0] * fj[2];
                    out[(first + 5, j)] += x[0] * fj[1] - x[1] * fj[0];
                }
            }
        }
    }
    out
}

/// Mesh-level nodal forces of a unit inertial load case.
pub fn inertial_load(model: &Assembled, nodes: &[[f64; 3]], origin: [f64; 3], case: LoadCase) -> Mat<f64> {
    let x = positions(nodes, origin);
    let field = match case {
        LoadCase::Translation(a) => Mat::from_fn(x.nrows(), 1, |r, _| if r % 3 == a { 1.0 } else { 0.0 }),
        LoadCase::Euler(a) => cross_axis(a, x.as_ref()),
        LoadCase::Centrifugal(a, b) => {
            let ab = cross_axis(a, cross_axis(b, x.as_ref()).as_ref());
            if a == b {
                ab
            } else {
                let ba = cross_axis(b, cross_axis(a, x.as_ref()).as_ref());
                &ab + &ba
            }
        }
    };
    let mut f = mass_times(model, field.as_ref());
    for v in f.col_mut(0).iter_mut() {
        *v = -*v;
    }
    f
}

/// G_a (3 x r x r), O_ab (3 x 3 x r x r) and o_ab (3 x 3 x r), row-major, from the mesh-level
/// basis `phi` (3N x r).
pub struct RotationInvariants {
    pub g: Vec<f64>,
    pub o_mat: Vec<f64>,
    pub o_vec: Vec<f64>,
}

pub fn rotation_invariants(
    model: &Assembled,
    nodes: &[[f64; 3]],
    origin: [f64; 3],
    phi: MatRef<'_, f64>,
) -> RotationInvariants {
    let r = phi.ncols();
    let m_phi = mass_times(model, phi);
    let x = positions(nodes, origin);
    let mut g = vec![0.0; 3 * r * r];
    let mut o_mat = vec![0.0; 9 * r * r];
    let mut o_vec = vec![0.0; 9 * r];
    for a in 0..3 {
        let ea_phi = cross_axis(a, phi);
        let ga = m_phi.transpose() * &ea_phi;
        for i in 0..r {
            for j in 0..r {
                // exactly skew: average out round-off
                g[(a * r + i) * r + j] = 0.5 * (ga[(i, j)] - ga[(j, i)]);
            }
        }
        for b in 0..3 {
            let eab_phi = cross_axis(a, cross_axis(b, phi).as_ref());
            let oab = m_phi.transpose() * &eab_phi;
            for i in 0..r {
                for j in 0..r {
                    o_mat[((3 * a + b) * r + i) * r + j] = oab[(i, j)];
                }
            }
            let eab_x = cross_axis(a, cross_axis(b, x.as_ref()).as_ref());
            let v = m_phi.transpose() * &eab_x;
            for i in 0..r {
                o_vec[(3 * a + b) * r + i] = v[(i, 0)];
            }
        }
    }
    RotationInvariants { g, o_mat, o_vec }
}
