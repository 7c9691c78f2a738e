//! Sparse assembly of the flange-constrained FE model. The rigid coupling (paper eq. 3) is applied
//! element by element: a slave node's three DoFs are replaced by its flange's six master DoFs
//! through xi_j = u + theta x (x_j - r_c), so the constrained K and M are assembled directly and
//! no unconstrained matrix or dense transformation is ever formed.
//!
//! DoF order of the constrained model: free-node DoFs (3 per node), then the force flanges' master
//! DoFs (6 each: u, theta), then the mount's six master DoFs last, so the clamped model (mount held)
//! is the leading block.

use crate::error::{BuildError, Result};
use crate::fe::{self, ElementKind, Elasticity, MAX_NODES_PER_ELEMENT};
use crate::flange::Flange;
use crate::mesh::Mesh;
use crate::spec::Role;
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
    pub volume: f64,
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
}

/// 3x6 block mapping master (u, theta) to a slave's displacement: [I | S], S theta = theta x d.
fn coupling_block(d: [f64; 3]) -> [[f64; 6]; 3] {
    [
        [1.0, 0.0, 0.0, 0.0, d[2], -d[1]],
        [0.0, 1.0, 0.0, -d[2], 0.0, d[0]],
        [0.0, 0.0, 1.0, d[1], -d[0], 0.0],
    ]
}

pub fn assemble(
    mesh: &Mesh,
    flanges: &[Flange],
    material: Elasticity,
    rho: f64,
    origin: [f64; 3],
) -> Result<Assembled> {
    let dofs = DofMap::new(mesh.n_nodes(), flanges);
    let kind: ElementKind = mesh.kind;
    let nen = kind.nodes_per_element();
    let ne = 3 * nen;
    let mut ke = vec![0.0; ne * ne];
    let mut me = vec![0.0; nen * nen];
    let mut coords_buf = [[0.0; 3]; MAX_NODES_PER_ELEMENT];
    let mut k_trip: Vec<Triplet<usize, usize, f64>> = Vec::new();
    let mut m_trip: Vec<Triplet<usize, usize, f64>> = Vec::new();
    let mut nodal_trip: Vec<Triplet<usize, usize, f64>> = Vec::new();
    let mut props = MassProperties::default();
    // per element: global DoFs and the (ne x nloc) map from them to element DoFs
    let mut global: Vec<usize> = Vec::with_capacity(ne);
    let mut t = vec![0.0; ne * ne];
    let mut kt = vec![0.0; ne * ne];
    for e in 0..mesh.n_elements() {
        let nodes = mesh.element(e);
        let coords = mesh.element_coords(e, &mut coords_buf);
        fe::element_stiffness(kind, coords, &material, &mut ke)
            .map_err(|err| BuildError::Numerical(format!("element {e}: {err}")))?;
        fe::element_mass(kind, coords, rho, &mut me)
            .map_err(|err| BuildError::Numerical(format!("element {e}: {err}")))?;
        accumulate_mass_properties(&mut props, &me, coords, origin, rho);
        for a in 0..nen {
            for b in 0..nen {
                nodal_trip.push(Triplet::new(nodes[a], nodes[b], me[a * nen + b]));
            }
        }

        // local DoF list and transformation
        global.clear();
        let mut has_slave = false;
        for &n in nodes {
            match dofs.node[n] {
                NodeDofs::Free(d) => global.extend([d, d + 1, d + 2]),
                NodeDofs::Slave(k) => {
                    has_slave = true;
                    let f = dofs.flange_first[k];
                    for i in 0..6 {
                        if !global.contains(&(f + i)) {
                            global.push(f + i);
                        }
                    }
                }
            }
        }
        let nloc = global.len();
        if !has_slave {
            push_block(&mut k_trip, &global, &ke, ne);
            for a in 0..nen {
                for b in 0..nen {
                    let v = me[a * nen + b];
                    for i in 0..3 {
                        m_trip.push(Triplet::new(global[3 * a + i], global[3 * b + i], v));
                    }
                }
            }
            continue;
        }
        // T: element DoF (row) <- local DoF (column)
        t[..ne * nloc].fill(0.0);
        for (a, &n) in nodes.iter().enumerate() {
            match dofs.node[n] {
                NodeDofs::Free(d) => {
                    for i in 0..3 {
                        let col = global.iter().position(|&g| g == d + i).unwrap_or(0);
                        t[(3 * a + i) * nloc + col] = 1.0;
                    }
                }
                NodeDofs::Slave(k) => {
                    let r = flanges[k].reference;
                    let p = mesh.nodes[n];
                    let block = coupling_block([p[0] - r[0], p[1] - r[1], p[2] - r[2]]);
                    let f = dofs.flange_first[k];
                    for j in 0..6 {
                        let col = global.iter().position(|&g| g == f + j).unwrap_or(0);
                        for i in 0..3 {
                            t[(3 * a + i) * nloc + col] = block[i][j];
                        }
                    }
                }
            }
        }
        // full element mass (scalar mass (x) I3)
        let mut mfull = vec![0.0; ne * ne];
        for a in 0..nen {
            for b in 0..nen {
                for i in 0..3 {
                    mfull[(3 * a + i) * ne + 3 * b + i] = me[a * nen + b];
                }
            }
        }
        for (mat, trip) in [(&ke, &mut k_trip), (&mfull, &mut m_trip)] {
            // kt = mat * T (ne x nloc), then T^T kt
            for r in 0..ne {
                for c in 0..nloc {
                    let mut s = 0.0;
                    for x in 0..ne {
                        s += mat[r * ne + x] * t[x * nloc + c];
                    }
                    kt[r * nloc + c] = s;
                }
            }
            let mut local = vec![0.0; nloc * nloc];
            for r in 0..nloc {
                for c in 0..nloc {
                    let mut s = 0.0;
                    for x in 0..ne {
                        s += t[x * nloc + r] * kt[x * nloc + c];
                    }
                    local[r * nloc + c] = s;
                }
            }
            push_block(trip, &global, &local, nloc);
        }
    }
    let n = dofs.n_dofs;
    let stiffness = symmetric(n, &k_trip, "stiffness")?;
    let mass = symmetric(n, &m_trip, "mass")?;
    let nn = mesh.n_nodes();
    let nodal_mass = SparseColMat::try_new_from_triplets(nn, nn, &nodal_trip)
        .map_err(|e| BuildError::Numerical(format!("assembling the nodal mass: {e:?}")))?;
    Ok(Assembled { dofs, stiffness, mass, nodal_mass, mass_properties: props })
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

fn push_block(trip: &mut Vec<Triplet<usize, usize, f64>>, global: &[usize], block: &[f64], n: usize) {
    for r in 0..n {
        for c in 0..n {
            let v = block[r * n + c];
            if v != 0.0 {
                trip.push(Triplet::new(global[r], global[c], v));
            }
        }
    }
}

fn accumulate_mass_properties(p: &mut MassProperties, me: &[f64], coords: &[[f64; 3]], o: [f64; 3], rho: f64) {
    let n = coords.len();
    let x: Vec<[f64; 3]> = coords.iter().map(|c| [c[0] - o[0], c[1] - o[1], c[2] - o[2]]).collect();
    for a in 0..n {
        for b in 0..n {
            let m = me[a * n + b];
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
    p.volume = p.mass / rho;
}
