//! 8-node trilinear hexahedron (CalculiX/Abaqus C3D8 node ordering).

use crate::input::element::{ElementKind, HEX8_NATURAL_COORDS};

/// Number of nodes of the element.
pub const NODE_COUNT: usize = ElementKind::Hex8.nodes_per_element();

/// Shape functions `n` and their derivatives with respect to the natural
/// coordinates `dn[node] = [dN/dxi, dN/deta, dN/dzeta]` at `xi`.
/// Only the first `NODE_COUNT` entries of the slices are written.
pub fn shape_functions(xi: [f64; 3], n: &mut [f64], dn: &mut [[f64; 3]]) {
    for ((node, n), dn) in HEX8_NATURAL_COORDS.iter().zip(n.iter_mut()).zip(dn.iter_mut()) {
        let s = [f64::from(node[0]), f64::from(node[1]), f64::from(node[2])];
        let a = 1.0 + s[0] * xi[0];
        let b = 1.0 + s[1] * xi[1];
        let c = 1.0 + s[2] * xi[2];
        *n = 0.125 * a * b * c;
        *dn = [0.125 * s[0] * b * c, 0.125 * a * s[1] * c, 0.125 * a * b * s[2]];
    }
}
