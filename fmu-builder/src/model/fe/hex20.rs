//! 20-node quadratic serendipity hexahedron (CalculiX/Abaqus C3D20 node
//! ordering).

use crate::input::element::{ElementKind, HEX20_NATURAL_COORDS};

/// Number of nodes of the element.
pub const NODE_COUNT: usize = ElementKind::Hex20.nodes_per_element();

/// Shape functions `n` and their derivatives with respect to the natural
/// coordinates `dn[node] = [dN/dxi, dN/deta, dN/dzeta]` at `xi`.
/// Only the first `NODE_COUNT` entries of the slices are written.
pub fn shape_functions(xi: [f64; 3], n: &mut [f64], dn: &mut [[f64; 3]]) {
    for ((node, n), dn) in HEX20_NATURAL_COORDS.iter().zip(n.iter_mut()).zip(dn.iter_mut()) {
        let s = [f64::from(node[0]), f64::from(node[1]), f64::from(node[2])];
        match node.iter().position(|&c| c == 0) {
            None => corner(xi, s, n, dn),
            Some(axis) => midside(xi, s, axis, n, dn),
        }
    }
}

/// N = 1/8 (1+s0 x0)(1+s1 x1)(1+s2 x2)(s0 x0 + s1 x1 + s2 x2 - 2).
fn corner(xi: [f64; 3], s: [f64; 3], n: &mut f64, dn: &mut [f64; 3]) {
    let f = [1.0 + s[0] * xi[0], 1.0 + s[1] * xi[1], 1.0 + s[2] * xi[2]];
    let sum = s[0] * xi[0] + s[1] * xi[1] + s[2] * xi[2];
    *n = 0.125 * f[0] * f[1] * f[2] * (sum - 2.0);
    for d in 0..3 {
        let (o1, o2) = ((d + 1) % 3, (d + 2) % 3);
        // Product rule: s_d (sum - 2) + (1 + s_d x_d) s_d = s_d (sum + s_d x_d - 1).
        dn[d] = 0.125 * s[d] * f[o1] * f[o2] * (sum + s[d] * xi[d] - 1.0);
    }
}

/// Node in the middle of an edge parallel to `axis` (its natural coordinate
/// along `axis` is 0): N = 1/4 (1 - x_a^2)(1 + s_b x_b)(1 + s_c x_c).
fn midside(xi: [f64; 3], s: [f64; 3], axis: usize, n: &mut f64, dn: &mut [f64; 3]) {
    let (b, c) = ((axis + 1) % 3, (axis + 2) % 3);
    let bubble = 1.0 - xi[axis] * xi[axis];
    let fb = 1.0 + s[b] * xi[b];
    let fc = 1.0 + s[c] * xi[c];
    *n = 0.25 * bubble * fb * fc;
    dn[axis] = -0.5 * xi[axis] * fb * fc;
    dn[b] = 0.25 * bubble * s[b] * fc;
    dn[c] = 0.25 * bubble * fb * s[c];
}
