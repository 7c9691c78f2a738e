//! Stresses at an element's nodes, recovered as CalculiX recovers its nodal stresses
//! (extrapolate.f): sigma = D B u at the stiffness rule's integration points, extrapolated to the
//! nodes, then (by the caller, `model::stress`) averaged over the elements sharing a node.
//!
//! | kind   | points | to the nodes                                                        |
//! |--------|--------|---------------------------------------------------------------------|
//! | tet4   | 1      | the point's value at every node                                     |
//! | tet10  | 4      | linear in the corners through the 4 points; midsides: mean of the edge's corners |
//! | hex8   | 8      | trilinear in the corners through the 8 points                       |
//! | hex20r | 8      | as hex8 for the corners; midsides: mean of the edge's corners       |
//! | hex20  | 27     | least-squares fit of the 20 serendipity functions to the 27 points  |
//!
//! The matrices are computed here exactly from the rules and shape functions; CalculiX's tables
//! hold the same matrices rounded to 3 to 5 decimals (1.92705 and -0.30902 for the tetrahedron,
//! 2.549 .. -0.04904 for the hexahedron), which moves its nodal stresses by up to about 1e-5 of
//! the stress (1e-4 for hexahedra) and leaves a uniform stress not quite uniform.
//!
//! Components in the order xx, yy, zz, xy, yz, zx (shear as stress, not strain).

use super::{
    Elasticity, ElementError, for_each_gauss_point, hex8, shape_functions, stiffness_rule, strain_displacement,
};
use crate::input::element::{ElementKind, HEX20_NATURAL_COORDS, MAX_NODES_PER_ELEMENT, TET10_EDGES};
use nalgebra::DMatrix;
use std::sync::OnceLock;

/// Most integration points of a stiffness rule (hex20: 3 x 3 x 3).
const MAX_POINTS: usize = 27;

/// Corner pairs of the hex20 midside nodes 9..20 (0-based 8..19), as in HEX20_NATURAL_COORDS.
const HEX20_EDGES: [(usize, usize); 12] =
    [(0, 1), (1, 2), (2, 3), (3, 0), (4, 5), (5, 6), (6, 7), (7, 4), (0, 4), (1, 5), (2, 6), (3, 7)];

/// How an element's integration-point values become nodal values: `direct` nodes (the first
/// ones) from the points through `matrix` (direct x points, row-major), every other node the
/// mean of two direct ones.
struct Extrapolation {
    direct: usize,
    points: usize,
    matrix: Vec<f64>,
    midsides: &'static [(usize, usize)],
}

fn extrapolation(kind: ElementKind) -> &'static Extrapolation {
    static TABLES: OnceLock<[Extrapolation; 5]> = OnceLock::new();
    let tables = TABLES.get_or_init(|| {
        [
            Extrapolation { direct: 4, points: 1, matrix: vec![1.0; 4], midsides: &[] },
            corner_extrapolation(ElementKind::Tet10, 4, &TET10_EDGES),
            corner_extrapolation(ElementKind::Hex8, 8, &[]),
            corner_extrapolation(ElementKind::Hex20R, 8, &HEX20_EDGES),
            least_squares_extrapolation(ElementKind::Hex20),
        ]
    });
    &tables[match kind {
        ElementKind::Tet4 => 0,
        ElementKind::Tet10 => 1,
        ElementKind::Hex8 => 2,
        ElementKind::Hex20R => 3,
        ElementKind::Hex20 => 4,
    }]
}

/// Values of the corner (linear or trilinear) shape functions at the rule's points (points x
/// corners), inverted: the corner values whose interpolation passes through the points' values.
fn corner_extrapolation(kind: ElementKind, corners: usize, midsides: &'static [(usize, usize)]) -> Extrapolation {
    let points: Vec<[f64; 3]> = stiffness_rule(kind).points().map(|(xi, _)| xi).collect();
    let mut n = [0.0; MAX_NODES_PER_ELEMENT];
    let mut dn = [[0.0; 3]; MAX_NODES_PER_ELEMENT];
    let p = DMatrix::from_fn(points.len(), corners, |i, j| {
        if corners == 4 {
            shape_functions(ElementKind::Tet4, points[i], &mut n[..4], &mut dn[..4]);
        } else {
            hex8::shape_functions(points[i], &mut n[..8], &mut dn[..8]);
        }
        n[j]
    });
    let inverse = p.try_inverse().expect("the corner interpolation at a symmetric rule's points is regular");
    Extrapolation {
        direct: corners,
        points: points.len(),
        matrix: (0..corners)
            .flat_map(|i| (0..points.len()).map(move |j| (i, j)))
            .map(|(i, j)| inverse[(i, j)])
            .collect(),
        midsides,
    }
}

/// (N^T N)^-1 N^T with N (points x nodes) the element's shape functions at the rule's points.
fn least_squares_extrapolation(kind: ElementKind) -> Extrapolation {
    let nodes = kind.nodes_per_element();
    let points: Vec<[f64; 3]> = stiffness_rule(kind).points().map(|(xi, _)| xi).collect();
    let mut n = [0.0; MAX_NODES_PER_ELEMENT];
    let mut dn = [[0.0; 3]; MAX_NODES_PER_ELEMENT];
    let a = DMatrix::from_fn(points.len(), nodes, |i, j| {
        shape_functions(kind, points[i], &mut n[..nodes], &mut dn[..nodes]);
        n[j]
    });
    let normal = a.transpose() * &a;
    let fit = normal.cholesky().expect("27 points determine the 20 serendipity coefficients").solve(&a.transpose());
    debug_assert_eq!(HEX20_NATURAL_COORDS.len(), nodes);
    Extrapolation {
        direct: nodes,
        points: points.len(),
        matrix: (0..nodes).flat_map(|i| (0..points.len()).map(move |j| (i, j))).map(|(i, j)| fit[(i, j)]).collect(),
        midsides: &[],
    }
}

/// Nodal stresses of one element for `k` displacement fields: `u` holds the element's DoFs
/// (node-major, 3 per node) by rows, k values per row; `out` receives nodes x k stress vectors
/// (node-major).
pub fn element_nodal_stresses(
    kind: ElementKind,
    coords: &[[f64; 3]],
    mat: &Elasticity,
    u: &[f64],
    k: usize,
    out: &mut [[f64; 6]],
) -> Result<(), ElementError> {
    mat.validate()?;
    let n = kind.nodes_per_element();
    if u.len() != 3 * n * k {
        return Err(ElementError::WrongOutputSize { expected: 3 * n * k, got: u.len() });
    }
    if out.len() != n * k {
        return Err(ElementError::WrongOutputSize { expected: n * k, got: out.len() });
    }
    let d = mat.d_matrix();
    let ex = extrapolation(kind);
    // stresses at the points, point-major, k per point (the largest rule: 27 x k)
    let mut at_points = vec![[0.0; 6]; ex.points * k];
    let mut point = 0;
    for_each_gauss_point(kind, stiffness_rule(kind), coords, |_, grad, _| {
        for c in 0..k {
            let mut strain = [0.0; 6];
            for (a, g) in grad.iter().enumerate().take(n) {
                let b = strain_displacement(g);
                let ua = [u[(3 * a) * k + c], u[(3 * a + 1) * k + c], u[(3 * a + 2) * k + c]];
                for (r, e) in strain.iter_mut().enumerate() {
                    *e += b[r][0] * ua[0] + b[r][1] * ua[1] + b[r][2] * ua[2];
                }
            }
            let s = &mut at_points[point * k + c];
            for (r, s) in s.iter_mut().enumerate() {
                *s = (0..6).map(|j| d[r][j] * strain[j]).sum();
            }
        }
        point += 1;
    })?;
    debug_assert!(ex.points <= MAX_POINTS && point == ex.points);
    for node in 0..ex.direct {
        let row = &ex.matrix[node * ex.points..(node + 1) * ex.points];
        for c in 0..k {
            let mut s = [0.0; 6];
            for (p, w) in row.iter().enumerate() {
                let sp = &at_points[p * k + c];
                for r in 0..6 {
                    s[r] += w * sp[r];
                }
            }
            out[node * k + c] = s;
        }
    }
    for (m, &(a, b)) in ex.midsides.iter().enumerate() {
        let node = ex.direct + m;
        for c in 0..k {
            let (sa, sb) = (out[a * k + c], out[b * k + c]);
            out[node * k + c] = std::array::from_fn(|r| 0.5 * (sa[r] + sb[r]));
        }
    }
    Ok(())
}

/// Von Mises equivalent stress of (xx, yy, zz, xy, yz, zx).
pub fn von_mises(s: &[f64; 6]) -> f64 {
    let (dxy, dyz, dzx) = (s[0] - s[1], s[1] - s[2], s[2] - s[0]);
    (0.5 * (dxy * dxy + dyz * dyz + dzx * dzx) + 3.0 * (s[3] * s[3] + s[4] * s[4] + s[5] * s[5])).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit_element(kind: ElementKind) -> Vec<[f64; 3]> {
        // a distorted element: the recovery must not rely on a parallelepiped
        let natural: Vec<[f64; 3]> = match kind {
            ElementKind::Tet4 | ElementKind::Tet10 => {
                crate::model::fe::tet10::NATURAL_COORDS[..kind.nodes_per_element()].to_vec()
            }
            _ => HEX20_NATURAL_COORDS[..kind.nodes_per_element()].iter().map(|p| p.map(f64::from)).collect(),
        };
        natural
            .iter()
            .map(|p| [2.0 * p[0] + 0.3 * p[1] * p[2], 1.5 * p[1] + 0.1 * p[0], 0.8 * p[2] + 0.05 * p[0] * p[1]])
            .collect()
    }

    const KINDS: [ElementKind; 5] =
        [ElementKind::Tet4, ElementKind::Tet10, ElementKind::Hex8, ElementKind::Hex20R, ElementKind::Hex20];

    /// A linear displacement field is a uniform strain: every element must return D eps exactly
    /// at every node (the extrapolation rows sum to one), whatever the element's shape.
    #[test]
    fn uniform_strain_gives_the_same_stress_at_every_node() {
        let mat = Elasticity { e: 210e9, nu: 0.3 };
        let grad = [[1e-3, 2e-4, -3e-4], [5e-4, -2e-3, 1e-4], [-1e-4, 3e-4, 7e-4]];
        let eps = [
            grad[0][0],
            grad[1][1],
            grad[2][2],
            grad[0][1] + grad[1][0],
            grad[1][2] + grad[2][1],
            grad[2][0] + grad[0][2],
        ];
        let d = mat.d_matrix();
        let expected: [f64; 6] = std::array::from_fn(|r| (0..6).map(|j| d[r][j] * eps[j]).sum());
        for kind in KINDS {
            let coords = unit_element(kind);
            let n = coords.len();
            let u: Vec<f64> = coords
                .iter()
                .flat_map(|x| (0..3).map(move |i| (0..3).map(|j| grad[i][j] * x[j]).sum::<f64>()))
                .collect();
            let mut out = vec![[0.0; 6]; n];
            element_nodal_stresses(kind, &coords, &mat, &u, 1, &mut out).unwrap();
            assert_eq!(out.len(), n);
            for s in &out {
                for r in 0..6 {
                    // round-off of sums of ~30 terms of the size of the stress
                    assert!((s[r] - expected[r]).abs() <= 1e-12 * 1e9, "{kind:?}: {s:?} vs {expected:?}");
                }
            }
        }
    }

    /// The tables against CalculiX's (extrapolate.f), which are the same matrices rounded to a
    /// few decimals: the tetrahedron's 1.92705 and -0.30902, the 2x2x2 hexahedron's 2.549,
    /// -0.683, 0.183, -0.04904, and entries of the 27-point fit 2.37499, -0.12559, 0.32628.
    #[test]
    fn tables_equal_calculix_rounded() {
        let tet = extrapolation(ElementKind::Tet10);
        assert_eq!(tet.matrix.len(), 16);
        assert!((tet.matrix[0] - 1.92705).abs() < 5e-6 && (tet.matrix[1] + 0.30902).abs() < 5e-6);
        let hex = extrapolation(ElementKind::Hex8);
        let mut entries: Vec<f64> = hex.matrix[..8].to_vec();
        entries.sort_by(f64::total_cmp);
        let expected = [-0.683, -0.683, -0.683, -0.04904, 0.183, 0.183, 0.183, 2.549];
        assert_eq!(entries.len(), expected.len());
        for (a, b) in entries.iter().zip(expected) {
            assert!((a - b).abs() < 5e-4, "{a} vs {b}");
        }
        let fit = extrapolation(ElementKind::Hex20);
        assert_eq!((fit.direct, fit.points), (20, 27));
        // node 1 from point 1, node 2 from point 1, node 9 from point 1 (CalculiX's a27(1..9, 1))
        for (value, expected) in [(fit.matrix[0], 2.37499), (fit.matrix[27], -0.12559), (fit.matrix[8 * 27], 0.32628)] {
            assert!((value - expected).abs() < 5e-6, "{value} vs {expected}");
        }
    }

    #[test]
    fn von_mises_of_uniaxial_and_pure_shear() {
        assert!((von_mises(&[100.0, 0.0, 0.0, 0.0, 0.0, 0.0]) - 100.0).abs() < 1e-12);
        assert!((von_mises(&[0.0, 0.0, 0.0, 10.0, 0.0, 0.0]) - 10.0 * 3f64.sqrt()).abs() < 1e-12);
        assert_eq!(von_mises(&[5.0, 5.0, 5.0, 0.0, 0.0, 0.0]), 0.0);
    }
}
