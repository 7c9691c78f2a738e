//! 4-node linear tetrahedron (CalculiX/Abaqus C3D4 node ordering).
//!
//! Both tetrahedra are parametrised like CalculiX's shape4tet/shape10tet: on
//! the unit tetrahedron with node 1 at the origin and nodes 2, 3, 4 at the unit
//! points of xi, eta, zeta, so that the quadrature points of gauss.rs land on
//! the same physical points as CalculiX's.

use crate::input::element::ElementKind;

/// Number of nodes of the element.
pub const NODE_COUNT: usize = ElementKind::Tet4.nodes_per_element();

/// Natural coordinates of the nodes in C3D4 order.
pub const NATURAL_COORDS: [[f64; 3]; NODE_COUNT] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

/// Gradients of the barycentric coordinates with respect to (xi, eta, zeta).
pub(crate) const BARYCENTRIC_GRAD: [[f64; 3]; NODE_COUNT] =
    [[-1.0, -1.0, -1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

/// Barycentric coordinates of the point `xi`, one per corner node.
pub(crate) fn barycentric(xi: [f64; 3]) -> [f64; NODE_COUNT] {
    [1.0 - xi[0] - xi[1] - xi[2], xi[0], xi[1], xi[2]]
}

/// Shape functions `n` and their derivatives with respect to the natural
/// coordinates `dn[node] = [dN/dxi, dN/deta, dN/dzeta]` at `xi`.
/// Only the first `NODE_COUNT` entries of the slices are written.
pub fn shape_functions(xi: [f64; 3], n: &mut [f64], dn: &mut [[f64; 3]]) {
    let l = barycentric(xi);
    for (((n, dn), l), g) in n.iter_mut().zip(dn.iter_mut()).zip(l).zip(BARYCENTRIC_GRAD) {
        *n = l;
        *dn = g;
    }
}
