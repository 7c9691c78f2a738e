//! Sparse assembly of the free-free part, element by element with each element's material, and
//! its rigid-body mass properties. The flanges are tied afterwards (`rigid_coupling`), so a part
//! given as a mesh and the same part given as its assembled matrices pass through the same
//! coupling.

use crate::error::{BuildError, Result};
use crate::input::element::{ElementKind, MAX_NODES_PER_ELEMENT};
use crate::input::mesh::Mesh;
use crate::linalg::faer_error;
use crate::model::fe::{self, Elasticity};
use faer::sparse::{SparseColMat, Triplet};

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

/// Free-free stiffness and mass of the mesh, element by element with each element's material.
/// `element_error` names an element the formulation refuses the way the user knows it (file id,
/// box), which only the part knows.
pub fn uncoupled(
    mesh: &Mesh,
    materials: &[SolidMaterial],
    element_error: &dyn Fn(usize, String) -> BuildError,
) -> Result<Uncoupled> {
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
            .map_err(|err| element_error(e, err.to_string()))?;
        fe::element_mass(kind, coords, material.rho, &mut me[..nen * nen])
            .map_err(|err| element_error(e, err.to_string()))?;
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
        .map_err(|e| BuildError::Numerical(format!("assembling the stiffness: {}", faer_error::creation(&e))))?;
    drop(k_trip);
    let nn = mesh.n_nodes();
    let nodal_mass = SparseColMat::try_new_from_triplets(nn, nn, &nodal_trip)
        .map_err(|e| BuildError::Numerical(format!("assembling the nodal mass: {}", faer_error::creation(&e))))?;
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
        .map_err(|e| BuildError::Numerical(format!("assembling the mass: {}", faer_error::creation(&e))))
}

/// The matrix of the triplets made bit-exactly symmetric, (A + A^T) / 2: coupled elements'
/// T^T K T products and summation order leave round-off asymmetry, and an exported matrix read
/// back by another solver (mirrored from one triangle) must be the very matrix we factor.
pub(crate) fn symmetric(n: usize, trip: &[Triplet<usize, usize, f64>], what: &str) -> Result<SparseColMat<usize, f64>> {
    let a = SparseColMat::try_new_from_triplets(n, n, trip)
        .map_err(|e| BuildError::Numerical(format!("assembling the {what}: {}", faer_error::creation(&e))))?;
    let mut both = Vec::with_capacity(2 * a.val().len());
    for j in 0..n {
        for (&i, &v) in a.row_idx_of_col_raw(j).iter().zip(a.val_of_col(j)) {
            both.push(Triplet::new(i, j, 0.5 * v));
            both.push(Triplet::new(j, i, 0.5 * v));
        }
    }
    SparseColMat::try_new_from_triplets(n, n, &both)
        .map_err(|e| BuildError::Numerical(format!("assembling the {what}: {}", faer_error::creation(&e))))
}

/// Rigid-body mass properties from the scalar nodal mass: exact for the FE interpolation, since
/// positions are linear in the nodal coordinates.
pub fn mass_properties(
    nodal: &SparseColMat<usize, f64>,
    nodes: &[[f64; 3]],
    o: [f64; 3],
    volume: Option<f64>,
) -> MassProperties {
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
