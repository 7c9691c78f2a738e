//! The rigid coupling of the flanges (RBE2, paper eq. 3): a slave node's three DoFs are replaced
//! by its flange's six master DoFs through xi_j = u + theta x (x_j - r_c), entry by entry of the
//! sparse matrices, so no dense transformation is ever formed.
//!
//! DoF order of the constrained model: free-node DoFs (3 per node), then the force flanges' master
//! DoFs (6 each: u, theta), then the mount's six master DoFs last, so the clamped model (mount held)
//! is the leading block.

use crate::error::Result;
use crate::input::spec::Role;
use crate::model::assembly::{MassProperties, Uncoupled, mass_properties};
use crate::model::congruence::{DofImage, symmetric_congruence};
use crate::model::flange::Flange;
use faer::sparse::SparseColMat;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NodeDofs {
    Free(usize),
    Slave(usize),
}

#[derive(Debug, Clone)]
pub struct DofMap {
    pub node: Vec<NodeDofs>,
    /// First of the six master DoFs, per flange in input order.
    pub flange_first: Vec<usize>,
    /// Number of free-node DoFs (the interior of Craig-Bampton).
    pub n_interior: usize,
    pub n_dofs: usize,
    /// The mount flange, whose six DoFs come last and are held; None for a free-floating body.
    pub mount: Option<usize>,
}

impl DofMap {
    pub fn new(n_nodes: usize, flanges: &[Flange]) -> Self {
        let mut node = vec![NodeDofs::Free(0); n_nodes];
        for (k, f) in flanges.iter().enumerate() {
            for &s in &f.slaves {
                node[s] = NodeDofs::Slave(k);
            }
        }
        let mut next = 0;
        for n in node.iter_mut() {
            if let NodeDofs::Free(d) = n {
                *d = next;
                next += 3;
            }
        }
        let n_interior = next;
        let mut flange_first = vec![0; flanges.len()];
        for (k, f) in flanges.iter().enumerate() {
            if f.role == Role::Force {
                flange_first[k] = next;
                next += 6;
            }
        }
        let mount = flanges.iter().position(|f| f.role == Role::Motion);
        if let Some(mount) = mount {
            flange_first[mount] = next;
            next += 6;
        }
        Self { node, flange_first, n_interior, n_dofs: next, mount }
    }

    /// What DoF `d` of the constrained model is, for messages: a node's direction (the node
    /// named by `node_label`) or a flange master's component.
    pub fn describe(&self, d: usize, flanges: &[Flange], node_label: &dyn Fn(usize) -> String) -> String {
        const DIR: [&str; 3] = ["x", "y", "z"];
        const MASTER: [&str; 6] = ["u_x", "u_y", "u_z", "theta_x", "theta_y", "theta_z"];
        if d < self.n_interior {
            let node = self.node.iter().position(|n| *n == NodeDofs::Free(d - d % 3));
            return match node {
                Some(n) => format!("the {} direction of {}", DIR[d % 3], node_label(n)),
                None => format!("DoF {d}"),
            };
        }
        match self.flange_first.iter().position(|&f| (f..f + 6).contains(&d)) {
            Some(k) => format!("{} of flange \"{}\"'s master", MASTER[d - self.flange_first[k]], flanges[k].name),
            None => format!("DoF {d}"),
        }
    }

    /// Size of the model with the mount held (all DoFs for a free-floating body).
    pub fn n_clamped(&self) -> usize {
        self.n_dofs - if self.mount.is_some() { 6 } else { 0 }
    }
}

pub struct Assembled {
    pub dofs: DofMap,
    /// n_dofs square as coupled; a mounted body's build keeps only its leading n_clamped block
    /// once the mount is held (`build::mounted`), since no later stage reads the mount's rows.
    pub stiffness: SparseColMat<usize, f64>,
    pub mass: SparseColMat<usize, f64>,
    /// Scalar consistent mass of the mesh nodes (n_nodes x n_nodes, before coupling): the mass
    /// of a nodal field w is this matrix applied to each component. Rigid-motion invariants of
    /// the floating frame (cross products per node) are taken with it.
    pub nodal_mass: SparseColMat<usize, f64>,
    pub mass_properties: MassProperties,
    /// The user's damping matrix, coupled like K and M (matrix input only).
    pub damping: Option<SparseColMat<usize, f64>>,
}

/// 3x6 block mapping master (u, theta) to a slave's displacement: [I | S], S theta = theta x d.
fn coupling_block(d: [f64; 3]) -> [[f64; 6]; 3] {
    [[1.0, 0.0, 0.0, 0.0, d[2], -d[1]], [0.0, 1.0, 0.0, -d[2], 0.0, d[0]], [0.0, 0.0, 1.0, d[1], -d[0], 0.0]]
}

/// Where each DoF of the free-free model goes in the constrained model: at most three
/// (constrained DoF, coefficient) pairs (a slave's translation is u + theta x d).
fn dof_images(dofs: &DofMap, nodes: &[[f64; 3]], flanges: &[Flange]) -> Vec<DofImage> {
    let mut images = Vec::with_capacity(3 * nodes.len());
    for (n, p) in nodes.iter().enumerate() {
        for i in 0..3 {
            images.push(match dofs.node[n] {
                NodeDofs::Free(d) => DofImage::NONE.with(d + i, 1.0),
                NodeDofs::Slave(k) => {
                    let r = flanges[k].reference;
                    let block = coupling_block([p[0] - r[0], p[1] - r[1], p[2] - r[2]]);
                    let f = dofs.flange_first[k];
                    // the row's zeros are left out: a slave on the reference's axis keeps fewer terms
                    let terms = block[i].iter().enumerate().filter(|(_, c)| **c != 0.0);
                    terms.fold(DofImage::NONE, |image, (j, &c)| image.with(f + j, c))
                }
            });
        }
    }
    images
}

/// Tie the flanges to the free-free part: the constrained K, M (and D) and the rigid-body mass
/// properties about `origin`.
pub fn rigid_coupling(part: &Uncoupled, nodes: &[[f64; 3]], flanges: &[Flange], origin: [f64; 3]) -> Result<Assembled> {
    let dofs = DofMap::new(nodes.len(), flanges);
    let images = dof_images(&dofs, nodes, flanges);
    let n = dofs.n_dofs;
    let stiffness = symmetric_congruence(&part.stiffness, &images, n, "stiffness")?;
    let mass = symmetric_congruence(&part.mass, &images, n, "mass")?;
    let damping = part.damping.as_ref().map(|d| symmetric_congruence(d, &images, n, "damping")).transpose()?;
    let mass_properties = mass_properties(&part.nodal_mass, nodes, origin, part.volume);
    Ok(Assembled { dofs, stiffness, mass, nodal_mass: part.nodal_mass.clone(), mass_properties, damping })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::error::BuildError;
    use crate::model::assembly::tests::mixed_mesh;
    use crate::model::assembly::uncoupled;
    use faer::Mat;

    /// The mixed mesh's x = 0 face held by the mount (its reference on the face's midline, so
    /// some slaves' lever arms have zero components), the hex8's x = 3 face by a force flange.
    fn flanges(nodes: &[[f64; 3]]) -> Vec<Flange> {
        let on = |x: f64| (0..nodes.len()).filter(|&n| nodes[n][0] == x).collect::<Vec<_>>();
        vec![
            Flange { name: "arm".into(), role: Role::Force, reference: [3.2, 0.5, 0.5], slaves: on(3.0) },
            Flange { name: "base".into(), role: Role::Motion, reference: [0.0, 0.5, 0.0], slaves: on(0.0) },
        ]
    }

    /// The coupling map densely, from its definition: T[3n + i, d + i] = 1 for a free node,
    /// T[3n + i, f + j] = [I | S](i, j) for a slave of the flange whose master DoFs start at f.
    fn dense_map(dofs: &DofMap, nodes: &[[f64; 3]], flanges: &[Flange]) -> Mat<f64> {
        let mut t = Mat::zeros(3 * nodes.len(), dofs.n_dofs);
        for (n, p) in nodes.iter().enumerate() {
            for i in 0..3 {
                match dofs.node[n] {
                    NodeDofs::Free(d) => t[(3 * n + i, d + i)] = 1.0,
                    NodeDofs::Slave(k) => {
                        let r = flanges[k].reference;
                        let block = coupling_block([p[0] - r[0], p[1] - r[1], p[2] - r[2]]);
                        (0..6).for_each(|j| t[(3 * n + i, dofs.flange_first[k] + j)] = block[i][j]);
                    }
                }
            }
        }
        t
    }

    fn assert_exactly_symmetric(s: &SparseColMat<usize, f64>, what: &str) {
        for j in 0..s.ncols() {
            for (&i, &v) in s.row_idx_of_col_raw(j).iter().zip(s.val_of_col(j)) {
                let p = s.row_idx_of_col_raw(i).binary_search(&j).expect("mirror in the pattern");
                assert_eq!(s.val_of_col(i)[p].to_bits(), v.to_bits(), "{what} ({i}, {j})");
            }
        }
    }

    #[test]
    fn coupled_matrices_are_the_congruence_and_exactly_symmetric() {
        let (mesh, materials) = mixed_mesh();
        let mut free = uncoupled(&mesh, &materials, &|e, m| BuildError::Numerical(format!("{e}: {m}"))).unwrap();
        free.damping = Some(free.mass.clone());
        let flanges = flanges(&mesh.nodes);
        let model = rigid_coupling(&free, &mesh.nodes, &flanges, [1.0, 0.5, 0.5]).unwrap();
        assert_eq!(model.dofs.n_dofs, model.dofs.n_interior + 12);
        let t = dense_map(&model.dofs, &mesh.nodes, &flanges);
        for (coupled, a, what) in [(&model.stiffness, &free.stiffness, "stiffness"), (&model.mass, &free.mass, "mass")]
        {
            assert_exactly_symmetric(coupled, what);
            let b = t.transpose() * a.to_dense() * &t;
            let dense = coupled.to_dense();
            // round-off of sums of a few hundred products in another order, against the largest
            let scale = b.norm_max();
            for (i, j) in (0..b.nrows()).flat_map(|i| (0..b.ncols()).map(move |j| (i, j))) {
                assert!((dense[(i, j)] - b[(i, j)]).abs() <= 1e-13 * scale, "{what} ({i}, {j})");
            }
        }
        let damping = model.damping.unwrap();
        assert_eq!(damping.val(), model.mass.val());
        assert_eq!(damping.symbolic().row_idx(), model.mass.symbolic().row_idx());
    }
}
