//! The sparsity of a mesh's matrices, known before any element matrix: two nodes couple exactly
//! when an element holds both. Assembly builds this node graph once, expands it to the 3x3 blocks
//! of the stiffness, and adds element matrices in place at each node pair's slot, so no list of
//! (row, column, value) entries as long as all element matrices together is ever held.

use crate::error::{BuildError, Result};
use crate::input::mesh::Mesh;
use faer::sparse::SymbolicSparseColMat;
use std::ops::Range;

/// The node graph as a column-compressed n_nodes x n_nodes pattern: column b lists, ascending,
/// the nodes sharing an element with b (b itself included).
pub(crate) struct NodeGraph {
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
}

impl NodeGraph {
    /// The graph of the mesh's elements; a node no element holds has an empty column.
    pub(crate) fn of_mesh(mesh: &Mesh) -> Result<Self> {
        let nn = mesh.n_nodes();
        if let Some(&bad) = mesh.elements.iter().find(|&&a| a >= nn) {
            return Err(BuildError::internal(format!("an element names node {bad} of a mesh of {nn} nodes")));
        }
        let incidence = Incidence::of_mesh(mesh);
        let mut col_ptr = Vec::with_capacity(nn + 1);
        col_ptr.push(0);
        let mut row_idx = Vec::new();
        // the column that last listed each node: one array for all columns, never cleared
        let mut listed_in = vec![usize::MAX; nn];
        for b in 0..nn {
            let first = row_idx.len();
            for &e in incidence.elements_of(b) {
                for &a in mesh.element(e) {
                    if listed_in[a] != b {
                        listed_in[a] = b;
                        row_idx.push(a);
                    }
                }
            }
            row_idx[first..].sort_unstable();
            col_ptr.push(row_idx.len());
        }
        Ok(Self { col_ptr, row_idx })
    }

    pub(crate) fn n_nodes(&self) -> usize {
        self.col_ptr.len() - 1
    }

    /// Number of coupled node pairs (entries of the scalar nodal matrix).
    pub(crate) fn n_pairs(&self) -> usize {
        self.row_idx.len()
    }

    /// Where column b starts among all pairs (the pair count for b = n_nodes).
    pub(crate) fn column_start(&self, b: usize) -> usize {
        self.col_ptr[b]
    }

    /// `parts` consecutive node ranges covering all nodes, of about equal pair counts.
    pub(crate) fn node_ranges(&self, parts: usize) -> Vec<Range<usize>> {
        let mut start = 0;
        (1..=parts)
            .map(|k| {
                let end = self.col_ptr.partition_point(|&p| p < k * self.n_pairs() / parts).max(start);
                let end = if k == parts { self.n_nodes() } else { end.min(self.n_nodes()) };
                let range = start..end;
                start = end;
                range
            })
            .collect()
    }

    /// Where column b starts among all pairs, and how many nodes it lists.
    pub(crate) fn column(&self, b: usize) -> (usize, usize) {
        (self.col_ptr[b], self.col_ptr[b + 1] - self.col_ptr[b])
    }

    /// Position of node a within column b, if a and b share an element.
    pub(crate) fn slot(&self, a: usize, b: usize) -> Option<usize> {
        self.row_idx[self.col_ptr[b]..self.col_ptr[b + 1]].binary_search(&a).ok()
    }

    /// Pattern of a 3N x 3N matrix of dense 3x3 node blocks (the stiffness): column 3b + j lists
    /// rows 3a, 3a + 1, 3a + 2 for every neighbour a of b, so its node block (a, b) holds entry
    /// (3a + i, 3b + j) at 9 * start(b) + 3 * j * count(b) + 3 * slot + i.
    pub(crate) fn block_pattern(&self) -> SymbolicSparseColMat<usize> {
        let n = 3 * self.n_nodes();
        let mut col_ptr = Vec::with_capacity(n + 1);
        col_ptr.push(0);
        let mut row_idx = Vec::with_capacity(9 * self.n_pairs());
        for b in 0..self.n_nodes() {
            let (start, count) = self.column(b);
            for _ in 0..3 {
                for &a in &self.row_idx[start..start + count] {
                    row_idx.extend_from_slice(&[3 * a, 3 * a + 1, 3 * a + 2]);
                }
                col_ptr.push(row_idx.len());
            }
        }
        SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx)
    }

    /// The scalar pattern itself (the nodal mass), consuming the graph.
    pub(crate) fn into_pattern(self) -> SymbolicSparseColMat<usize> {
        let nn = self.n_nodes();
        SymbolicSparseColMat::new_checked(nn, nn, self.col_ptr, None, self.row_idx)
    }
}

/// The elements holding each node, compressed like a sparse column per node.
struct Incidence {
    first: Vec<usize>,
    elements: Vec<usize>,
}

impl Incidence {
    fn of_mesh(mesh: &Mesh) -> Self {
        let mut first = vec![0; mesh.n_nodes() + 1];
        for &a in &mesh.elements {
            first[a + 1] += 1;
        }
        for a in 0..mesh.n_nodes() {
            first[a + 1] += first[a];
        }
        let mut next = first.clone();
        let mut elements = vec![0; mesh.elements.len()];
        for e in 0..mesh.n_elements() {
            for &a in mesh.element(e) {
                elements[next[a]] = e;
                next[a] += 1;
            }
        }
        Self { first, elements }
    }

    fn elements_of(&self, a: usize) -> &[usize] {
        &self.elements[self.first[a]..self.first[a + 1]]
    }
}
