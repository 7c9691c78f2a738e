//! The coupling of the flanges to the part. Rigid (RBE2, paper eq. 3): a slave node's three DoFs
//! are replaced by its flange's six master DoFs through xi_j = u + theta x (x_j - r_c).
//! Distributing (RBE3, `distributing`): the nodes keep their DoFs but six, which follow the
//! master and the rest. Either way entry by entry of the sparse matrices (T^T A T with T's rows
//! in `congruence`), so no dense transformation is ever formed.
//!
//! DoF order of the constrained model: free-node DoFs (3 per node), then the force flanges' master
//! DoFs (6 each: u, theta), then the mount's six master DoFs last, so the clamped model (mount held)
//! is the leading block.

use crate::error::{BuildError, Result};
use crate::input::spec::Role;
use crate::model::assembly::{MassProperties, Uncoupled, mass_properties};
use crate::model::congruence::{Images, symmetric_congruence};
use crate::model::distributing;
use crate::model::flange::{Flange, FlangeCoupling};
use faer::sparse::SparseColMat;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NodeDofs {
    /// Three own DoFs, from this one.
    Free(usize),
    /// Rigidly tied to this flange's master.
    Slave(usize),
    /// A distributing flange's node with some of its directions among the flange's six
    /// dependent DoFs: per direction, its own DoF or its entry in `DofMap::dependent`.
    Partial([DofOf; 3]),
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DofOf {
    Own(usize),
    Dependent(usize),
}

/// A DoF a distributing coupling eliminates: its value in terms of the constrained DoFs (its
/// flange's master and the other nodes' own DoFs).
#[derive(Debug, Clone)]
pub struct DependentDof {
    pub node: usize,
    pub direction: usize,
    pub image: Vec<(usize, f64)>,
}

#[derive(Debug, Clone)]
pub struct DofMap {
    pub node: Vec<NodeDofs>,
    /// First of the six master DoFs, per flange in input order.
    pub flange_first: Vec<usize>,
    /// Number of the nodes' own DoFs (the interior of Craig-Bampton).
    pub n_interior: usize,
    pub n_dofs: usize,
    /// The mount flange, whose six DoFs come last and are held; None for a free-floating body.
    pub mount: Option<usize>,
    pub dependent: Vec<DependentDof>,
}

impl DofMap {
    pub fn new(nodes: &[[f64; 3]], flanges: &[Flange]) -> Result<Self> {
        let mut node = vec![NodeDofs::Free(0); nodes.len()];
        let Couplings { eliminations, dependent_at, slot_of } = couplings(nodes, flanges, &mut node)?;
        let n_interior = number_node_dofs(&mut node, &slot_of, &dependent_at);
        let mut next = n_interior;
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
        let mut this = Self { node, flange_first, n_interior, n_dofs: next, mount, dependent: Vec::new() };
        // the dependent DoFs' images, now that every own DoF has its number
        this.push_dependent(flanges, eliminations);
        Ok(this)
    }

    /// The dependent DoFs of the distributing flanges' `eliminations`, each with its image in
    /// the own DoFs and the flange masters.
    fn push_dependent(&mut self, flanges: &[Flange], eliminations: Vec<(usize, distributing::Elimination)>) {
        for (k, e) in eliminations {
            let f = &flanges[k];
            for (j, &(i, dir)) in e.dependent.iter().enumerate() {
                let master = (0..6).map(|m| (self.flange_first[k] + m, e.master[j][m]));
                let others = e.others[j].iter().map(|&(o, d, c)| match self.node[f.slaves[o]] {
                    NodeDofs::Free(first) => (first + d, c),
                    NodeDofs::Partial(dofs) => match dofs[d] {
                        DofOf::Own(g) => (g, c),
                        DofOf::Dependent(_) => unreachable!("the elimination's others are independent"),
                    },
                    NodeDofs::Slave(_) => unreachable!("a node belongs to one flange"),
                });
                let mut image: Vec<(usize, f64)> = master.chain(others).filter(|t| t.1 != 0.0).collect();
                image.sort_unstable_by_key(|t| t.0);
                self.dependent.push(DependentDof { node: f.slaves[i], direction: dir, image });
            }
        }
    }

    /// What DoF `d` of the constrained model is, for messages: a node's direction (the node
    /// named by `node_label`) or a flange master's component.
    pub fn describe(&self, d: usize, flanges: &[Flange], node_label: &dyn Fn(usize) -> String) -> String {
        const DIR: [&str; 3] = ["x", "y", "z"];
        const MASTER: [&str; 6] = ["u_x", "u_y", "u_z", "theta_x", "theta_y", "theta_z"];
        if d < self.n_interior {
            let found = self.node.iter().enumerate().find_map(|(n, nd)| match *nd {
                NodeDofs::Free(first) if (first..first + 3).contains(&d) => Some((n, d - first)),
                NodeDofs::Partial(dofs) => dofs.iter().position(|x| *x == DofOf::Own(d)).map(|dir| (n, dir)),
                _ => None,
            });
            return match found {
                Some((n, dir)) => format!("the {} direction of {}", DIR[dir], node_label(n)),
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

/// The flanges' couplings by node: rigid flanges' slaves marked in `node`, and the distributing
/// flanges' eliminations (flange, elimination) with, per node having dependent directions (its
/// slot), the dependent DoF of each direction.
struct Couplings {
    eliminations: Vec<(usize, distributing::Elimination)>,
    dependent_at: Vec<[Option<usize>; 3]>,
    slot_of: std::collections::HashMap<usize, usize>,
}

/// The flanges' couplings; an error where a distributing one is singular.
fn couplings(nodes: &[[f64; 3]], flanges: &[Flange], node: &mut [NodeDofs]) -> Result<Couplings> {
    let mut eliminations = Vec::new();
    let mut dependent_at: Vec<[Option<usize>; 3]> = Vec::new();
    let mut slot_of = std::collections::HashMap::new();
    for (k, f) in flanges.iter().enumerate() {
        match &f.coupling {
            FlangeCoupling::Rigid => {
                for &s in &f.slaves {
                    node[s] = NodeDofs::Slave(k);
                }
            }
            FlangeCoupling::Distributing { weights } => {
                let points: Vec<[f64; 3]> = f.slaves.iter().map(|&s| nodes[s]).collect();
                let refused = |why| {
                    BuildError::singular(format!(
                        "the distributing coupling of flange \"{}\" is singular ({why:?})",
                        f.name
                    ))
                };
                let c = distributing::constraint(&points, weights, f.reference).map_err(refused)?;
                let e = distributing::eliminate(&c).map_err(refused)?;
                for (j, &(i, dir)) in e.dependent.iter().enumerate() {
                    let n = f.slaves[i];
                    let slot = *slot_of.entry(n).or_insert_with(|| {
                        dependent_at.push([None; 3]);
                        dependent_at.len() - 1
                    });
                    dependent_at[slot][dir] = Some(6 * eliminations.len() + j);
                }
                eliminations.push((k, e));
            }
        }
    }
    Ok(Couplings { eliminations, dependent_at, slot_of })
}

/// Numbers the nodes' own DoFs in node order, three per free node and one per own direction of
/// a node with dependent ones; returns how many there are.
fn number_node_dofs(
    node: &mut [NodeDofs],
    slot_of: &std::collections::HashMap<usize, usize>,
    dependent_at: &[[Option<usize>; 3]],
) -> usize {
    let mut next = 0;
    for (n, nd) in node.iter_mut().enumerate() {
        match slot_of.get(&n) {
            Some(&slot) => {
                *nd = NodeDofs::Partial(std::array::from_fn(|dir| match dependent_at[slot][dir] {
                    Some(j) => DofOf::Dependent(j),
                    None => {
                        next += 1;
                        DofOf::Own(next - 1)
                    }
                }))
            }
            None => {
                if let NodeDofs::Free(d) = nd {
                    *d = next;
                    next += 3;
                }
            }
        }
    }
    next
}

pub struct Assembled {
    pub dofs: DofMap,
    /// n_dofs square as coupled; a mounted body's build keeps only its leading n_clamped block
    /// once the mount is held (`pipeline::mounted`), since no later stage reads the mount's rows.
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

/// Where each DoF of the free-free model goes in the constrained model (the rows of the map T):
/// a free DoF to its own, a rigid slave's to u + theta x d (its zeros left out: a slave on the
/// reference's axis keeps fewer terms), a distributing flange's dependent DoF to its image.
fn dof_images(dofs: &DofMap, nodes: &[[f64; 3]], flanges: &[Flange]) -> Images {
    let mut images = Images::with_capacity(3 * nodes.len());
    for (n, p) in nodes.iter().enumerate() {
        for i in 0..3 {
            match dofs.node[n] {
                NodeDofs::Free(d) => images.push([(d + i, 1.0)]),
                NodeDofs::Slave(k) => {
                    let r = flanges[k].reference;
                    let block = coupling_block([p[0] - r[0], p[1] - r[1], p[2] - r[2]]);
                    let f = dofs.flange_first[k];
                    images.push(block[i].iter().enumerate().filter(|(_, c)| **c != 0.0).map(|(j, &c)| (f + j, c)));
                }
                NodeDofs::Partial(own) => match own[i] {
                    DofOf::Own(d) => images.push([(d, 1.0)]),
                    DofOf::Dependent(j) => images.push(dofs.dependent[j].image.iter().copied()),
                },
            }
        }
    }
    images
}

/// Tie the flanges to the free-free part: the constrained K, M (and D) and the rigid-body mass
/// properties about `origin`.
pub fn rigid_coupling(part: &Uncoupled, nodes: &[[f64; 3]], flanges: &[Flange], origin: [f64; 3]) -> Result<Assembled> {
    let dofs = DofMap::new(nodes, flanges)?;
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
            Flange {
                name: "arm".into(),
                role: Role::Force,
                reference: [3.2, 0.5, 0.5],
                slaves: on(3.0),
                coupling: FlangeCoupling::Rigid,
            },
            Flange {
                name: "base".into(),
                role: Role::Motion,
                reference: [0.0, 0.5, 0.0],
                slaves: on(0.0),
                coupling: FlangeCoupling::Rigid,
            },
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
                    NodeDofs::Partial(own) => match own[i] {
                        DofOf::Own(d) => t[(3 * n + i, d)] = 1.0,
                        DofOf::Dependent(j) => {
                            for &(g, c) in &dofs.dependent[j].image {
                                t[(3 * n + i, g)] = c;
                            }
                        }
                    },
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
        let mut free = uncoupled(&mesh, &materials, &|e, m| BuildError::numerical(format!("{e}: {m}"))).unwrap();
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
