//! Sparse assembly of the free-free part, element by element with each element's material, and
//! its rigid-body mass properties. The flanges are tied afterwards (`rigid_coupling`), so a part
//! given as a mesh and the same part given as its assembled matrices pass through the same
//! coupling.

use crate::error::{BuildError, Result};
use crate::input::element::{ElementKind, MAX_NODES_PER_ELEMENT};
use crate::input::mesh::Mesh;
use crate::linalg::first_touch;
use crate::model::fe::{self, Elasticity};
use crate::model::node_graph::NodeGraph;
use faer::sparse::{SparseColMat, SymbolicSparseColMat};
use rayon::prelude::*;
use std::ops::Range;

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
///
/// The pattern comes from the node graph first; element matrices are then computed a batch at a
/// time on all cores and added into their node pairs' slots, each column summing its elements
/// in mesh order, so the sums (and the FMU's bytes) do not depend on the number of threads.
pub fn uncoupled(
    mesh: &Mesh,
    materials: &[SolidMaterial],
    element_error: &dyn Fn(usize, String) -> BuildError,
) -> Result<Uncoupled> {
    let graph = NodeGraph::of_mesh(mesh)?;
    // touched first: the adding step's scatter would otherwise fault its pages in at random,
    // and took longer on two threads than on one (`first_touch`)
    let mut stiffness = first_touch::touched_zeros(9 * graph.n_pairs());
    let mut nodal_mass = first_touch::touched_zeros(graph.n_pairs());
    let mut shares = ColumnShare::split(&graph, &mut stiffness, &mut nodal_mass);
    let mut batch = ElementBatch::for_mesh(mesh);
    let mut volume = 0.0;
    for first in (0..mesh.n_elements()).step_by(batch.capacity) {
        let elements = first..mesh.n_elements().min(first + batch.capacity);
        batch
            .compute(&graph, mesh, materials, elements.clone())
            .map_err(|(e, err)| element_error(e, err.to_string()).caused_by(err))?;
        shares.par_iter_mut().try_for_each(|share| share.add_batch(&graph, mesh, &batch, elements.clone()))?;
        batch.add_volume(mesh, materials, elements, &mut volume);
    }
    drop(batch);
    let stiffness = SparseColMat::new(graph.block_pattern(), stiffness);
    let nodal_mass = SparseColMat::new(graph.into_pattern(), nodal_mass);
    let mass = isotropic_mass(&nodal_mass)?;
    Ok(Uncoupled { stiffness, mass, damping: None, nodal_mass, volume: Some(volume) })
}

/// Element matrices of a batch of elements, one fixed-size slot each (sized for the mesh's
/// largest element), so the batch is allocated once for the whole mesh.
struct ElementBatch {
    stiffness: Vec<f64>,
    mass: Vec<f64>,
    /// Per element, the slot of node a in node b's column of the graph at a * n + b
    /// (`NOT_IN_PATTERN` if missing), looked up with the element matrices, on all cores.
    pair_slots: Vec<u32>,
    stiffness_slot: usize,
    mass_slot: usize,
    capacity: usize,
}

const NOT_IN_PATTERN: u32 = u32::MAX;

/// Memory of one batch's stiffness slots: a few hundred to a few thousand elements, enough to
/// keep all cores busy, small beside the assembled stiffness.
const BATCH_BYTES: usize = 4 << 20;

impl ElementBatch {
    fn for_mesh(mesh: &Mesh) -> Self {
        let nen = mesh.kinds.iter().map(|k| k.nodes_per_element()).max().unwrap_or(1);
        let (stiffness_slot, mass_slot) = ((3 * nen).pow(2), nen.pow(2));
        let capacity = (BATCH_BYTES / (8 * stiffness_slot)).clamp(1, mesh.n_elements().max(1));
        Self {
            stiffness: vec![0.0; capacity * stiffness_slot],
            mass: vec![0.0; capacity * mass_slot],
            pair_slots: vec![0; capacity * mass_slot],
            stiffness_slot,
            mass_slot,
            capacity,
        }
    }

    /// Computes the matrices of `elements` (at most `capacity`) in parallel. The error is that of
    /// the first refused element in mesh order, whichever thread met it first.
    fn compute(
        &mut self,
        graph: &NodeGraph,
        mesh: &Mesh,
        materials: &[SolidMaterial],
        elements: Range<usize>,
    ) -> std::result::Result<(), (usize, fe::ElementError)> {
        let refused = self.stiffness[..elements.len() * self.stiffness_slot]
            .par_chunks_mut(self.stiffness_slot)
            .zip(self.mass.par_chunks_mut(self.mass_slot))
            .zip(self.pair_slots.par_chunks_mut(self.mass_slot))
            .zip(elements)
            .filter_map(|(((ke, me), slots), e)| {
                find_pair_slots(graph, mesh.element(e), slots);
                element_matrices(mesh, materials, e, ke, me).err().map(|err| (e, err))
            })
            .min_by_key(|(e, _)| *e);
        refused.map_or(Ok(()), Err)
    }

    /// Stiffness (3n x 3n), scalar mass (n x n) and pair slots (n x n) of the batch's element
    /// number `k`, row-major.
    fn matrices(&self, k: usize, nen: usize) -> (&[f64], &[f64], &[u32]) {
        let ke = &self.stiffness[k * self.stiffness_slot..][..9 * nen * nen];
        let me = &self.mass[k * self.mass_slot..][..nen * nen];
        let slots = &self.pair_slots[k * self.mass_slot..][..nen * nen];
        (ke, me, slots)
    }

    /// Adds the batch's elements' volumes (mass over density) one by one, as mesh order sums them.
    fn add_volume(&self, mesh: &Mesh, materials: &[SolidMaterial], elements: Range<usize>, volume: &mut f64) {
        for (k, e) in elements.enumerate() {
            let (_, me, _) = self.matrices(k, mesh.kind(e).nodes_per_element());
            *volume += me.iter().sum::<f64>() / materials[mesh.material[e]].rho;
        }
    }
}

/// Where each node pair of an element sits in the graph: the slot of node a in node b's column
/// at a * n + b.
fn find_pair_slots(graph: &NodeGraph, nodes: &[usize], slots: &mut [u32]) {
    for (a, &node_a) in nodes.iter().enumerate() {
        for (b, &node_b) in nodes.iter().enumerate() {
            let slot = graph.slot(node_a, node_b).and_then(|s| u32::try_from(s).ok());
            slots[a * nodes.len() + b] = slot.unwrap_or(NOT_IN_PATTERN);
        }
    }
}

/// Stiffness and scalar mass of element `e` into the front of its slots.
fn element_matrices(
    mesh: &Mesh,
    materials: &[SolidMaterial],
    e: usize,
    ke: &mut [f64],
    me: &mut [f64],
) -> std::result::Result<(), fe::ElementError> {
    let kind: ElementKind = mesh.kind(e);
    let material = &materials[mesh.material[e]];
    let nen = kind.nodes_per_element();
    let mut coords_buf = [[0.0; 3]; MAX_NODES_PER_ELEMENT];
    let coords = mesh.element_coords(e, &mut coords_buf);
    fe::element_stiffness(kind, coords, &material.elasticity, &mut ke[..9 * nen * nen])?;
    fe::element_mass(kind, coords, material.rho, &mut me[..nen * nen])
}

/// Node ranges the element matrices are added on in parallel, each owning the columns of its
/// nodes: every column sums its elements in mesh order, whatever the number of threads.
const COLUMN_SHARES: usize = 8;

/// The assembled values of the columns of `nodes`: stiffness in 3x3 node blocks (see
/// `NodeGraph::block_pattern`) from `9 * first_pair`, scalar nodal mass from `first_pair`, the
/// graph's pair index of the range's first node.
struct ColumnShare<'a> {
    nodes: Range<usize>,
    first_pair: usize,
    stiffness: &'a mut [f64],
    nodal_mass: &'a mut [f64],
}

impl<'a> ColumnShare<'a> {
    /// The values split into node ranges of about equal pair counts.
    fn split(graph: &NodeGraph, mut stiffness: &'a mut [f64], mut nodal_mass: &'a mut [f64]) -> Vec<Self> {
        let mut shares = Vec::with_capacity(COLUMN_SHARES);
        for nodes in graph.node_ranges(COLUMN_SHARES) {
            let first_pair = graph.column_start(nodes.start);
            let pairs = graph.column_start(nodes.end) - first_pair;
            let (share_k, rest_k) = std::mem::take(&mut stiffness).split_at_mut(9 * pairs);
            let (share_m, rest_m) = std::mem::take(&mut nodal_mass).split_at_mut(pairs);
            shares.push(Self { nodes, first_pair, stiffness: share_k, nodal_mass: share_m });
            (stiffness, nodal_mass) = (rest_k, rest_m);
        }
        shares
    }

    fn add_batch(
        &mut self,
        graph: &NodeGraph,
        mesh: &Mesh,
        batch: &ElementBatch,
        elements: Range<usize>,
    ) -> Result<()> {
        for (k, e) in elements.enumerate() {
            let (ke, me, slots) = batch.matrices(k, mesh.kind(e).nodes_per_element());
            self.add_element(graph, mesh.element(e), ke, me, slots)?;
        }
        Ok(())
    }

    /// Adds the columns this share owns of one element's stiffness `ke` (3n x 3n) and scalar
    /// mass `me` (n x n) at its node pairs' `slots`.
    fn add_element(&mut self, graph: &NodeGraph, nodes: &[usize], ke: &[f64], me: &[f64], slots: &[u32]) -> Result<()> {
        let (nen, ne) = (nodes.len(), 3 * nodes.len());
        for (b, &node_b) in nodes.iter().enumerate().filter(|(_, n)| self.nodes.contains(n)) {
            let (start, count) = graph.column(node_b);
            let start = start - self.first_pair;
            for a in 0..nen {
                let slot = slots[a * nen + b];
                if slot == NOT_IN_PATTERN {
                    let node_a = nodes[a];
                    return Err(BuildError::internal(format!(
                        "nodes {node_a} and {node_b} share an element but not the pattern"
                    )));
                }
                let slot = slot as usize;
                self.nodal_mass[start + slot] += me[a * nen + b];
                let block = 9 * start + 3 * slot;
                for j in 0..3 {
                    let column = &mut self.stiffness[block + 3 * j * count..][..3];
                    for (i, k) in column.iter_mut().enumerate() {
                        *k += ke[(3 * a + i) * ne + 3 * b + j];
                    }
                }
            }
        }
        Ok(())
    }
}

/// The 3N x 3N mass m_ab delta_ij of a scalar nodal mass m_ab: column 3b + i holds m_ab at row
/// 3a + i, in the nodal matrix's row order.
pub fn isotropic_mass(nodal: &SparseColMat<usize, f64>) -> Result<SparseColMat<usize, f64>> {
    let nn = nodal.ncols();
    if nodal.nrows() != nn {
        return Err(BuildError::internal(format!("the nodal mass is {} x {nn}, not square", nodal.nrows())));
    }
    let entries: usize = (0..nn).map(|b| nodal.row_idx_of_col_raw(b).len()).sum();
    let mut col_ptr = Vec::with_capacity(3 * nn + 1);
    col_ptr.push(0);
    let mut row_idx = Vec::with_capacity(3 * entries);
    let mut val = Vec::with_capacity(3 * entries);
    for b in 0..nn {
        for i in 0..3 {
            row_idx.extend(nodal.row_idx_of_col_raw(b).iter().map(|&a| 3 * a + i));
            val.extend_from_slice(nodal.val_of_col(b));
            col_ptr.push(row_idx.len());
        }
    }
    let pattern = SymbolicSparseColMat::new_unsorted_checked(3 * nn, 3 * nn, col_ptr, None, row_idx);
    Ok(SparseColMat::new(pattern, val))
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

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::input::mesh::{BoxRegion, mesh_boxes};
    use faer::sparse::Triplet;

    fn node_at(mesh: &mut Mesh, p: [f64; 3]) -> usize {
        match mesh.nodes.iter().position(|q| q == &p) {
            Some(n) => n,
            None => {
                mesh.nodes.push(p);
                mesh.nodes.len() - 1
            }
        }
    }

    /// Two hex20 of one material, and a hex8, a tet4 and a tet10 of another on the box's faces
    /// (sharing its corner nodes, not conforming: assembly does not care).
    pub(crate) fn mixed_mesh() -> (Mesh, Vec<SolidMaterial>) {
        let boxes = [BoxRegion { min: [0.0; 3], max: [2.0, 1.0, 1.0], divisions: [2, 1, 1] }];
        let mut mesh = mesh_boxes(&boxes, ElementKind::Hex20).unwrap();
        let hex8 = [
            [2., 0., 0.],
            [3., 0., 0.],
            [3., 1., 0.],
            [2., 1., 0.],
            [2., 0., 1.],
            [3., 0., 1.],
            [3., 1., 1.],
            [2., 1., 1.],
        ];
        let hex8: Vec<usize> = hex8.iter().map(|&p| node_at(&mut mesh, p)).collect();
        mesh.push_element(ElementKind::Hex8, &hex8, 1);
        let tet4 = [[0., 0., 1.], [1., 0., 1.], [0., 1., 1.], [0.3, 0.3, 1.6]];
        let tet4: Vec<usize> = tet4.iter().map(|&p| node_at(&mut mesh, p)).collect();
        mesh.push_element(ElementKind::Tet4, &tet4, 1);
        let corners = [[1., 0., 1.], [2., 0., 1.], [1., 1., 1.], [1.4, 0.4, 1.7]];
        let mid = |a: usize, b: usize| std::array::from_fn(|i| 0.5 * (corners[a][i] + corners[b][i]));
        let edges = [(0, 1), (1, 2), (2, 0), (0, 3), (1, 3), (2, 3)];
        let points: Vec<[f64; 3]> = corners.iter().copied().chain(edges.iter().map(|&(a, b)| mid(a, b))).collect();
        let tet10: Vec<usize> = points.iter().map(|&p| node_at(&mut mesh, p)).collect();
        mesh.push_element(ElementKind::Tet10, &tet10, 0);
        let steel = SolidMaterial { name: "steel".into(), elasticity: Elasticity { e: 2.1e11, nu: 0.3 }, rho: 7850.0 };
        let aluminium = SolidMaterial { name: "al".into(), elasticity: Elasticity { e: 7e10, nu: 0.33 }, rho: 2700.0 };
        (mesh, vec![steel, aluminium])
    }

    /// The straightforward assembly: every element entry as a triplet, summed by faer.
    fn triplet_assembly(
        mesh: &Mesh,
        materials: &[SolidMaterial],
    ) -> (SparseColMat<usize, f64>, SparseColMat<usize, f64>) {
        let (mut k, mut m) = (Vec::new(), Vec::new());
        let (mut ke, mut me) = (vec![0.0; 3600], vec![0.0; 400]);
        for e in 0..mesh.n_elements() {
            let (nodes, nen) = (mesh.element(e), mesh.kind(e).nodes_per_element());
            element_matrices(mesh, materials, e, &mut ke, &mut me).unwrap();
            for a in 0..nen {
                for b in 0..nen {
                    m.push(Triplet::new(nodes[a], nodes[b], me[a * nen + b]));
                    for (i, j) in (0..3).flat_map(|i| (0..3).map(move |j| (i, j))) {
                        k.push(Triplet::new(3 * nodes[a] + i, 3 * nodes[b] + j, ke[(3 * a + i) * 3 * nen + 3 * b + j]));
                    }
                }
            }
        }
        let (n, nn) = (3 * mesh.n_nodes(), mesh.n_nodes());
        (
            SparseColMat::try_new_from_triplets(n, n, &k).unwrap(),
            SparseColMat::try_new_from_triplets(nn, nn, &m).unwrap(),
        )
    }

    /// Same pattern, and values equal to round-off: an entry sums a handful of element terms in
    /// possibly another order, so it may differ by a few ulps of the largest term.
    pub(crate) fn assert_same(a: &SparseColMat<usize, f64>, b: &SparseColMat<usize, f64>, what: &str) {
        assert_eq!(a.symbolic().col_ptr(), b.symbolic().col_ptr(), "{what}");
        assert_eq!(a.symbolic().row_idx(), b.symbolic().row_idx(), "{what}");
        let scale = b.val().iter().fold(0.0f64, |m, v| m.max(v.abs()));
        for (x, y) in a.val().iter().zip(b.val()) {
            assert!((x - y).abs() <= 1e-14 * scale, "{what}: {x} vs {y}");
        }
    }

    #[test]
    fn assembly_equals_the_triplet_route() {
        let (mesh, materials) = mixed_mesh();
        let free = uncoupled(&mesh, &materials, &|e, m| BuildError::numerical(format!("{e}: {m}"))).unwrap();
        let (k, nodal) = triplet_assembly(&mesh, &materials);
        assert_same(&free.stiffness, &k, "stiffness");
        assert_same(&free.nodal_mass, &nodal, "nodal mass");
        // M = nodal mass (x) I3, entry by entry
        let m = &free.mass;
        assert_eq!(m.val().len(), 3 * nodal.val().len());
        for b in 0..mesh.n_nodes() {
            for (&a, &v) in nodal.row_idx_of_col_raw(b).iter().zip(nodal.val_of_col(b)) {
                for i in 0..3 {
                    let p = m.row_idx_of_col_raw(3 * b + i).binary_search(&(3 * a + i)).unwrap();
                    assert_eq!(m.val_of_col(3 * b + i)[p].to_bits(), free.nodal_mass.val_of_col(b)[p].to_bits());
                    assert!((m.val_of_col(3 * b + i)[p] - v).abs() <= 1e-14 * v.abs());
                }
            }
        }
        // exactly symmetric: element matrices are, and both mirrors sum in the same order
        for j in 0..k.ncols() {
            for (&i, &v) in free.stiffness.row_idx_of_col_raw(j).iter().zip(free.stiffness.val_of_col(j)) {
                let p = free.stiffness.row_idx_of_col_raw(i).binary_search(&j).unwrap();
                assert_eq!(free.stiffness.val_of_col(i)[p].to_bits(), v.to_bits());
            }
        }
        let volume = 2.0 + 1.0 + 0.6 / 6.0 + 0.7 / 6.0;
        assert!((free.volume.unwrap() - volume).abs() < 1e-12, "{:?}", free.volume);
    }

    /// The element turned inside out: hex8 top and bottom faces swapped, tet4 corners 2 and 3.
    fn invert(mesh: &mut Mesh, e: usize) {
        let first = mesh.offsets[e];
        match mesh.kind(e) {
            ElementKind::Hex8 => (0..4).for_each(|k| mesh.elements.swap(first + k, first + 4 + k)),
            _ => mesh.elements.swap(first + 1, first + 2),
        }
    }

    #[test]
    fn a_refused_element_is_the_first_in_mesh_order() {
        let refused = |inverted: &[usize]| {
            let (mut mesh, materials) = mixed_mesh();
            inverted.iter().for_each(|&e| invert(&mut mesh, e));
            let err = uncoupled(&mesh, &materials, &|e, m| BuildError::numerical(format!("element {e}: {m}")));
            err.err().unwrap().to_string()
        };
        // the hex8 is element 2, the tet4 element 3, computed in one batch by any thread
        assert!(refused(&[3]).contains("element 3:"));
        assert!(refused(&[3, 2]).contains("element 2:"));
    }

    #[test]
    fn isotropic_mass_of_a_nodal_mass() {
        let nodal = SparseColMat::try_new_from_triplets(
            2,
            2,
            &[Triplet::new(0, 0, 2.0), Triplet::new(1, 0, 0.5), Triplet::new(0, 1, 0.5), Triplet::new(1, 1, 3.0)],
        )
        .unwrap();
        let m = isotropic_mass(&nodal).unwrap().to_dense();
        for (r, c) in (0..6).flat_map(|r| (0..6).map(move |c| (r, c))) {
            let expected = if r % 3 == c % 3 { [[2.0, 0.5], [0.5, 3.0]][r / 3][c / 3] } else { 0.0 };
            assert_eq!(m[(r, c)], expected, "({r}, {c})");
        }
    }
}
