//! Sparse assembly of the flange-constrained FE model, in two steps that follow the data: the
//! free-free part (`uncoupled`: element by element from a mesh, or given as matrices by the user),
//! then the rigid coupling of the flanges (`rigid_coupling`, paper eq. 3): a slave node's three
//! DoFs are replaced by its flange's six master DoFs through xi_j = u + theta x (x_j - r_c),
//! entry by entry of the sparse matrices, so no dense transformation is ever formed. Both input
//! kinds pass through the same coupling, so a part given as a mesh and the same part given as
//! its assembled matrices give bit-identical constrained models.
//!
//! DoF order of the constrained model: free-node DoFs (3 per node), then the force flanges' master
//! DoFs (6 each: u, theta), then the mount's six master DoFs last, so the clamped model (mount held)
//! is the leading block.

use crate::error::{BuildError, Result};
use crate::model::fe::{self, ElementKind, Elasticity, MAX_NODES_PER_ELEMENT};
use crate::model::flange::Flange;
use crate::input::mesh::Mesh;
use crate::input::spec::Role;
use faer::sparse::{SparseColMat, Triplet};

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

    /// Size of the model with the mount held (all DoFs for a free-floating body).
    pub fn n_clamped(&self) -> usize {
        self.n_dofs - if self.mount.is_some() { 6 } else { 0 }
    }
}

/// Rigid-body mass properties of the mesh about an origin, from the consistent mass (exact for
/// the FE interpolation, since positions are linear in the element coordinates).
#[derive(Debug, Clone, Copy, Default)]
pub struct MassProperties {
    pub mass: f64,
    pub first_moment: [f64; 3],
    /// Row-major inertia tensor about the origin.
    pub inertia: [f64; 9],
    /// None for a part given by its matrices.
    pub volume: Option<f64>,
}

/// An isotropic linear elastic solid material, resolved for every element of the part.
#[derive(Debug, Clone, PartialEq)]
pub struct SolidMaterial {
    pub name: String,
    pub elasticity: Elasticity,
    pub rho: f64,
}

/// The free-free model of the part before any flange is tied (3 DoFs per node, node-major).
pub struct Uncoupled {
    pub stiffness: SparseColMat<usize, f64>,
    pub mass: SparseColMat<usize, f64>,
    pub damping: Option<SparseColMat<usize, f64>>,
    /// Scalar mass of the nodes (n_nodes x n_nodes): `mass` is this matrix times the 3x3 identity.
    pub nodal_mass: SparseColMat<usize, f64>,
    /// Volume of the elements; unknown for a part given by its matrices.
    pub volume: Option<f64>,
}

pub struct Assembled {
    pub dofs: DofMap,
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
    [
        [1.0, 0.0, 0.0, 0.0, d[2], -d[1]],
        [0.0, 1.0, 0.0, -d[2], 0.0, d[0]],
        [0.0, 0.0, 1.0, d[1], -d[0], 0.0],
    ]
}

/// Free-free stiffness and mass of the mesh, element by element with each element's material.
pub fn uncoupled(mesh: &Mesh, materials: &[SolidMaterial]) -> Result<Uncoupled> {
    let n = 3 * mesh.n_nodes();
    let mut ke = vec![0.0; (3 * MAX_NODES_PER_ELEMENT).pow(2)];
    let mut me = vec![0.0; MAX_NODES_PER_ELEMENT.pow(2)];
    let mut coords_buf = [[0.0; 3]; MAX_NODES_PER_ELEMENT];
    let entries: usize = (0..mesh.n_elements()).map(|e| mesh.kind(e).nodes_per_element().pow(2)).sum();
    let mut k_trip: Vec<Triplet<usize, usize, f64>> = Vec::with_capacity(9 * entries);
    let mut nodal_trip: Vec<Triplet<usize, usize, f64>> = Vec::with_capacity(entries);
    let mut volume = 0.0;
    for e in 0..mesh.n_elements() {
        let kind: ElementKind = mesh.kind(e);
        let material = &materials[mesh.material[e]];
        let nen = kind.nodes_per_element();
        let ne = 3 * nen;
        let nodes = mesh.element(e);
        let coords = mesh.element_coords(e, &mut coords_buf);
        fe::element_stiffness(kind, coords, &material.elasticity, &mut ke[..ne * ne])
            .map_err(|err| BuildError::Numerical(format!("element {e}: {err}")))?;
        fe::element_mass(kind, coords, material.rho, &mut me[..nen * nen])
            .map_err(|err| BuildError::Numerical(format!("element {e}: {err}")))?;
        volume += me[..nen * nen].iter().sum::<f64>() / material.rho;
        for a in 0..nen {
            for b in 0..nen {
                nodal_trip.push(Triplet::new(nodes[a], nodes[b], me[a * nen + b]));
                for i in 0..3 {
                    for j in 0..3 {
                        k_trip.push(Triplet::new(3 * nodes[a] + i, 3 * nodes[b] + j, ke[(3 * a + i) * ne + 3 * b + j]));
                    }
                }
            }
        }
    }
    let stiffness = SparseColMat::try_new_from_triplets(n, n, &k_trip)
        .map_err(|e| BuildError::Numerical(format!("assembling the stiffness: {e:?}")))?;
    drop(k_trip);
    let nn = mesh.n_nodes();
    let nodal_mass = SparseColMat::try_new_from_triplets(nn, nn, &nodal_trip)
        .map_err(|e| BuildError::Numerical(format!("assembling the nodal mass: {e:?}")))?;
    drop(nodal_trip);
    let mass = isotropic_mass(&nodal_mass)?;
    Ok(Uncoupled { stiffness, mass, damping: None, nodal_mass, volume: Some(volume) })
}

/// The 3N x 3N mass m_ab delta_ij of a scalar nodal mass m_ab.
pub fn isotropic_mass(nodal: &SparseColMat<usize, f64>) -> Result<SparseColMat<usize, f64>> {
    let nn = nodal.nrows();
    let mut trip = Vec::with_capacity(3 * nodal.val().len());
    for b in 0..nn {
        for (&a, &v) in nodal.row_idx_of_col_raw(b).iter().zip(nodal.val_of_col(b)) {
            for i in 0..3 {
                trip.push(Triplet::new(3 * a + i, 3 * b + i, v));
            }
        }
    }
    SparseColMat::try_new_from_triplets(3 * nn, 3 * nn, &trip)
        .map_err(|e| BuildError::Numerical(format!("assembling the mass: {e:?}")))
}

/// Where a DoF of the free-free model goes in the constrained model: at most three
/// (constrained DoF, coefficient) pairs (a slave's translation is u + theta x d).
fn dof_images(dofs: &DofMap, nodes: &[[f64; 3]], flanges: &[Flange]) -> Vec<([(usize, f64); 3], u8)> {
    let mut images = Vec::with_capacity(3 * nodes.len());
    for (n, p) in nodes.iter().enumerate() {
        for i in 0..3 {
            let mut img = [(0, 0.0); 3];
            let mut len = 0;
            match dofs.node[n] {
                NodeDofs::Free(d) => {
                    img[0] = (d + i, 1.0);
                    len = 1;
                }
                NodeDofs::Slave(k) => {
                    let r = flanges[k].reference;
                    let block = coupling_block([p[0] - r[0], p[1] - r[1], p[2] - r[2]]);
                    let f = dofs.flange_first[k];
                    for (j, &c) in block[i].iter().enumerate() {
                        if c != 0.0 {
                            img[len] = (f + j, c);
                            len += 1;
                        }
                    }
                }
            }
            images.push((img, len as u8));
        }
    }
    images
}

/// T^T A T for the rigid-coupling map T, made bit-exactly symmetric.
fn couple_matrix(
    a: &SparseColMat<usize, f64>,
    images: &[([(usize, f64); 3], u8)],
    n: usize,
    what: &str,
) -> Result<SparseColMat<usize, f64>> {
    let mut trip = Vec::with_capacity(a.val().len() + a.val().len() / 4);
    for j in 0..a.ncols() {
        let (img_j, len_j) = &images[j];
        for (&i, &v) in a.row_idx_of_col_raw(j).iter().zip(a.val_of_col(j)) {
            let (img_i, len_i) = &images[i];
            for &(gi, ci) in &img_i[..*len_i as usize] {
                for &(gj, cj) in &img_j[..*len_j as usize] {
                    trip.push(Triplet::new(gi, gj, ci * v * cj));
                }
            }
        }
    }
    symmetric(n, &trip, what)
}

/// Tie the flanges to the free-free part: the constrained K, M (and D) and the rigid-body mass
/// properties about `origin`.
pub fn rigid_coupling(part: &Uncoupled, nodes: &[[f64; 3]], flanges: &[Flange], origin: [f64; 3]) -> Result<Assembled> {
    let dofs = DofMap::new(nodes.len(), flanges);
    let images = dof_images(&dofs, nodes, flanges);
    let n = dofs.n_dofs;
    let stiffness = couple_matrix(&part.stiffness, &images, n, "stiffness")?;
    let mass = couple_matrix(&part.mass, &images, n, "mass")?;
    let damping = part.damping.as_ref().map(|d| couple_matrix(d, &images, n, "damping")).transpose()?;
    let mass_properties = mass_properties(&part.nodal_mass, nodes, origin, part.volume);
    Ok(Assembled { dofs, stiffness, mass, nodal_mass: part.nodal_mass.clone(), mass_properties, damping })
}

/// The matrix of the triplets made bit-exactly symmetric, (A + A^T) / 2: coupled elements'
/// T^T K T products and summation order leave round-off asymmetry, and an exported matrix read
/// back by another solver (mirrored from one triangle) must be the very matrix we factor.
fn symmetric(n: usize, trip: &[Triplet<usize, usize, f64>], what: &str) -> Result<SparseColMat<usize, f64>> {
    let a = SparseColMat::try_new_from_triplets(n, n, trip)
        .map_err(|e| BuildError::Numerical(format!("assembling the {what}: {e:?}")))?;
    let mut both = Vec::with_capacity(2 * a.val().len());
    for j in 0..n {
        for (&i, &v) in a.row_idx_of_col_raw(j).iter().zip(a.val_of_col(j)) {
            both.push(Triplet::new(i, j, 0.5 * v));
            both.push(Triplet::new(j, i, 0.5 * v));
        }
    }
    SparseColMat::try_new_from_triplets(n, n, &both).map_err(|e| BuildError::Numerical(format!("assembling the {what}: {e:?}")))
}

/// Rigid-body mass properties from the scalar nodal mass: exact for the FE interpolation, since
/// positions are linear in the nodal coordinates.
fn mass_properties(nodal: &SparseColMat<usize, f64>, nodes: &[[f64; 3]], o: [f64; 3], volume: Option<f64>) -> MassProperties {
    let mut p = MassProperties { volume, ..Default::default() };
    let x: Vec<[f64; 3]> = nodes.iter().map(|c| [c[0] - o[0], c[1] - o[1], c[2] - o[2]]).collect();
    for b in 0..nodal.ncols() {
        for (&a, &m) in nodal.row_idx_of_col_raw(b).iter().zip(nodal.val_of_col(b)) {
            p.mass += m;
            for i in 0..3 {
                p.first_moment[i] += m * x[b][i];
            }
            // integral of rho (|x|^2 I - x x^T) with both factors interpolated
            let dot = x[a][0] * x[b][0] + x[a][1] * x[b][1] + x[a][2] * x[b][2];
            for i in 0..3 {
                for j in 0..3 {
                    p.inertia[3 * i + j] += m * (if i == j { dot } else { 0.0 } - x[a][i] * x[b][j]);
                }
            }
        }
    }
    p
}
