//! 10-node quadratic tetrahedron (CalculiX/Abaqus C3D10 node ordering).

use super::tet4::{BARYCENTRIC_GRAD, barycentric};
use crate::input::element::{ElementKind, TET10_EDGES};

/// Number of nodes of the element.
pub const NODE_COUNT: usize = ElementKind::Tet10.nodes_per_element();

/// Natural coordinates of the nodes in C3D10 order: the corners of C3D4, then
/// the midpoints of the edges `TET10_EDGES`.
pub const NATURAL_COORDS: [[f64; 3]; NODE_COUNT] = [
    [0.0, 0.0, 0.0],
    [1.0, 0.0, 0.0],
    [0.0, 1.0, 0.0],
    [0.0, 0.0, 1.0],
    [0.5, 0.0, 0.0],
    [0.5, 0.5, 0.0],
    [0.0, 0.5, 0.0],
    [0.0, 0.0, 0.5],
    [0.5, 0.0, 0.5],
    [0.0, 0.5, 0.5],
];

/// Shape functions `n` and their derivatives with respect to the natural
/// coordinates `dn[node] = [dN/dxi, dN/deta, dN/dzeta]` at `xi`: corners
/// L (2L - 1), midsides 4 L_i L_j in the barycentric coordinates L.
/// Only the first `NODE_COUNT` entries of the slices are written.
pub fn shape_functions(xi: [f64; 3], n: &mut [f64], dn: &mut [[f64; 3]]) {
    let l = barycentric(xi);
    let g = BARYCENTRIC_GRAD;
    for c in 0..4 {
        n[c] = l[c] * (2.0 * l[c] - 1.0);
        let f = 4.0 * l[c] - 1.0;
        dn[c] = [f * g[c][0], f * g[c][1], f * g[c][2]];
    }
    for (m, &(i, j)) in TET10_EDGES.iter().enumerate() {
        n[4 + m] = 4.0 * l[i] * l[j];
        dn[4 + m] = [
            4.0 * (l[j] * g[i][0] + l[i] * g[j][0]),
            4.0 * (l[j] * g[i][1] + l[i] * g[j][1]),
            4.0 * (l[j] * g[i][2] + l[i] * g[j][2]),
        ];
    }
}
