//! Element-level verification: shape functions, patch tests, rigid-body
//! modes, spurious zero-energy modes, mass/volume and a cantilever against
//! Timoshenko beam theory.

use super::*;
use crate::input::mesh::{BoxRegion, mesh_boxes};
use nalgebra::{DMatrix, DVector};

const STEEL: Elasticity = Elasticity { e: 210e9, nu: 0.3 };
const KINDS: [ElementKind; 5] = ElementKind::ALL;
const HEX_KINDS: [ElementKind; 3] = [ElementKind::Hex8, ElementKind::Hex20, ElementKind::Hex20R];
const TET_KINDS: [ElementKind; 2] = [ElementKind::Tet4, ElementKind::Tet10];

// ---------------------------------------------------------------- helpers

/// Deterministic pseudo-random number in [-1, 1) (no external crates).
fn jitter(seed: &mut u64) -> f64 {
    *seed = seed.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
    ((*seed >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
}

/// A curved, non-affine image of the reference cube; node positions of the
/// element are sampled from it, so hex20 edges are genuinely curved.
fn distorted_map(xi: [f64; 3]) -> [f64; 3] {
    let [x, y, z] = xi;
    [
        1.0 + 0.9 * x + 0.08 * y * z + 0.05 * y * y,
        -0.5 + 0.7 * y + 0.1 * x * y + 0.06 * z * z,
        0.3 + 1.1 * z + 0.07 * x * z - 0.05 * x * x + 0.1 * y,
    ]
}

fn is_tet(kind: ElementKind) -> bool {
    TET_KINDS.contains(&kind)
}

/// Natural coordinates of the nodes in CalculiX order, for every kind.
fn reference_coords(kind: ElementKind) -> Vec<[f64; 3]> {
    match kind.natural_node_coords() {
        Some(lattice) => lattice.iter().map(|c| [f64::from(c[0]), f64::from(c[1]), f64::from(c[2])]).collect(),
        None if kind == ElementKind::Tet4 => tet4::NATURAL_COORDS.to_vec(),
        None => tet10::NATURAL_COORDS.to_vec(),
    }
}

/// The distorted image of the element's reference nodes; a tetrahedron is
/// placed on the corner (-1,-1,-1) of the reference cube so that the same
/// curved map applies (curved edges for tet10, as for hex20).
fn distorted_element(kind: ElementKind) -> Vec<[f64; 3]> {
    reference_coords(kind)
        .into_iter()
        .map(|c| {
            if is_tet(kind) {
                distorted_map([2.0 * c[0] - 1.0, 2.0 * c[1] - 1.0, 2.0 * c[2] - 1.0])
            } else {
                distorted_map(c)
            }
        })
        .collect()
}

/// The two corner nodes of every midside node of a quadratic kind (empty for
/// the linear kinds), as node indices.
fn midside_edges(kind: ElementKind) -> Vec<(usize, usize, usize)> {
    let corners = kind.corner_nodes();
    kind.midside_edges().iter().enumerate().map(|(m, &(i, j))| (corners + m, i, j)).collect()
}

/// Moves every midside node to the middle of its corners: straight edges,
/// hence a trilinear (hex) or affine (tet) geometry map.
fn straighten(kind: ElementKind, coords: &mut [[f64; 3]]) {
    for (m, i, j) in midside_edges(kind) {
        coords[m] = [0, 1, 2].map(|d| 0.5 * (coords[i][d] + coords[j][d]));
    }
}

fn straight_distorted_element(kind: ElementKind) -> Vec<[f64; 3]> {
    let mut coords = distorted_element(kind);
    straighten(kind, &mut coords);
    coords
}

fn stiffness(kind: ElementKind, coords: &[[f64; 3]]) -> Vec<f64> {
    let dofs = 3 * kind.nodes_per_element();
    let mut k = vec![0.0; dofs * dofs];
    element_stiffness(kind, coords, &STEEL, &mut k).expect("valid element");
    k
}

fn mat_vec(m: &[f64], v: &[f64]) -> Vec<f64> {
    m.chunks(v.len()).map(|row| row.iter().zip(v).map(|(a, b)| a * b).sum()).collect()
}

fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

/// Assembles the global dense stiffness of a small mesh.
fn assemble(kind: ElementKind, nodes: &[[f64; 3]], elements: &[usize]) -> Vec<f64> {
    let npe = kind.nodes_per_element();
    let dofs = 3 * nodes.len();
    let mut global = vec![0.0; dofs * dofs];
    let mut ke = vec![0.0; 9 * npe * npe];
    for conn in elements.chunks(npe) {
        let coords: Vec<[f64; 3]> = conn.iter().map(|&i| nodes[i]).collect();
        element_stiffness(kind, &coords, &STEEL, &mut ke).expect("valid element");
        for (a, &ga) in conn.iter().enumerate() {
            for (b, &gb) in conn.iter().enumerate() {
                for i in 0..3 {
                    for j in 0..3 {
                        global[(3 * ga + i) * dofs + 3 * gb + j] += ke[(3 * a + i) * 3 * npe + 3 * b + j];
                    }
                }
            }
        }
    }
    global
}

/// Arbitrary full linear displacement field (includes shear and rotation).
fn linear_field(x: [f64; 3]) -> [f64; 3] {
    [
        1e-3 + 2e-3 * x[0] - 1e-3 * x[1] + 0.5e-3 * x[2],
        -2e-3 + 0.7e-3 * x[0] + 1.5e-3 * x[1] - 0.8e-3 * x[2],
        0.5e-3 - 0.3e-3 * x[0] + 0.9e-3 * x[1] + 1.2e-3 * x[2],
    ]
}

// ---------------------------------------------------------------- material

/// Uniaxial stress (lateral contraction -nu) must give sigma_xx = E eps with
/// zero lateral stress, and engineering shear gamma must give tau = G gamma.
#[test]
fn d_matrix_reproduces_engineering_constants() {
    let d = STEEL.d_matrix();
    let g = STEEL.e / (2.0 * (1.0 + STEEL.nu));
    for axis in 0..3 {
        let mut strain = [0.0; 6];
        for (i, s) in strain.iter_mut().enumerate().take(3) {
            *s = if i == axis { 1e-3 } else { -STEEL.nu * 1e-3 };
        }
        let stress: Vec<f64> = (0..6).map(|r| (0..6).map(|c| d[r][c] * strain[c]).sum()).collect();
        for (i, s) in stress.iter().enumerate() {
            let want = if i == axis { STEEL.e * 1e-3 } else { 0.0 };
            assert!((s - want).abs() < 1e-9 * STEEL.e * 1e-3, "axis {axis} component {i}: {s}");
        }
        let mut shear = [0.0; 6];
        shear[3 + axis] = 2e-3;
        for r in 0..6 {
            let tau: f64 = (0..6).map(|c| d[r][c] * shear[c]).sum();
            let want = if r == 3 + axis { g * 2e-3 } else { 0.0 };
            assert!((tau - want).abs() < 1e-9 * g * 2e-3, "shear {axis} row {r}: {tau}");
        }
    }
}

// ---------------------------------------------------------------- shape functions

#[test]
fn shape_functions_interpolate_and_sum_to_one() {
    for kind in KINDS {
        let n = kind.nodes_per_element();
        let mut shape = [0.0; MAX_NODES_PER_ELEMENT];
        let mut dn = [[0.0; 3]; MAX_NODES_PER_ELEMENT];
        for (a, xi) in reference_coords(kind).into_iter().enumerate() {
            shape_functions(kind, xi, &mut shape[..n], &mut dn[..n]);
            for (b, &v) in shape[..n].iter().enumerate() {
                let want = if a == b { 1.0 } else { 0.0 };
                assert!((v - want).abs() < 1e-14, "{kind}: N{b} at node {a} = {v}");
            }
        }
        let xi = [0.31, -0.72, 0.18];
        shape_functions(kind, xi, &mut shape[..n], &mut dn[..n]);
        assert!((shape[..n].iter().sum::<f64>() - 1.0).abs() < 1e-14);
        for d in 0..3 {
            assert!(dn[..n].iter().map(|g| g[d]).sum::<f64>().abs() < 1e-14);
        }
    }
}

#[test]
fn shape_derivatives_match_finite_differences() {
    for kind in KINDS {
        let n = kind.nodes_per_element();
        let (mut s, mut dn, mut sp, mut sm) = ([0.0; 20], [[0.0; 3]; 20], [0.0; 20], [0.0; 20]);
        let mut scratch = [[0.0; 3]; 20];
        let xi = [0.23, -0.41, 0.67];
        shape_functions(kind, xi, &mut s[..n], &mut dn[..n]);
        let h = 1e-6;
        for d in 0..3 {
            let (mut p, mut m) = (xi, xi);
            p[d] += h;
            m[d] -= h;
            shape_functions(kind, p, &mut sp[..n], &mut scratch[..n]);
            shape_functions(kind, m, &mut sm[..n], &mut scratch[..n]);
            for a in 0..n {
                let fd = (sp[a] - sm[a]) / (2.0 * h);
                assert!((fd - dn[a][d]).abs() < 1e-8, "{kind} node {a} axis {d}: {fd} vs {}", dn[a][d]);
            }
        }
    }
}

// ---------------------------------------------------------------- patch tests

/// Patch test of the first kind: 2x2x2 elements with every node randomly
/// displaced (curved edges for hex20); the linear field prescribed on the
/// boundary nodes must be reproduced exactly at the interior nodes.
///
/// Hex20R gets straight edges: with 2x2x2 points the internal forces of a
/// constant stress, sum over points of adj(J) dN/dxi, are exact only while the
/// geometry map is trilinear (degree 3 per axis), so on curved edges CalculiX's
/// C3D20R itself fails this test.
#[test]
fn distorted_patch_reproduces_linear_field() {
    for kind in HEX_KINDS {
        // Node lattice with `step` lattice intervals per element edge.
        let step = if kind == ElementKind::Hex8 { 1 } else { 2 };
        let side = 2 * step + 1;
        let is_node =
            |i: usize, j: usize, k: usize| [i, j, k].iter().filter(|&&v| v % 2 == 1).count() <= 1 || step == 1;
        let mut id = vec![usize::MAX; side * side * side];
        let mut nodes = Vec::new();
        let mut boundary = Vec::new();
        let mut seed = 7;
        let spacing = 1.0 / (2 * step) as f64;
        for k in 0..side {
            for j in 0..side {
                for i in 0..side {
                    if !is_node(i, j, k) {
                        continue;
                    }
                    id[i + side * (j + side * k)] = nodes.len();
                    let amp = 0.2 * spacing;
                    nodes.push([
                        i as f64 * spacing + amp * jitter(&mut seed),
                        j as f64 * spacing + amp * jitter(&mut seed),
                        k as f64 * spacing + amp * jitter(&mut seed),
                    ]);
                    boundary.push([i, j, k].iter().any(|&v| v == 0 || v == side - 1));
                }
            }
        }
        let mut elements = Vec::new();
        for (ez, ey, ex) in (0..2).flat_map(|z| (0..2).flat_map(move |y| (0..2).map(move |x| (z, y, x)))) {
            for c in kind.natural_node_coords().expect("hexahedron") {
                let off = |e: usize, c: i8| e * step + ((i32::from(c) + 1) as usize * step) / 2;
                elements.push(id[off(ex, c[0]) + side * (off(ey, c[1]) + side * off(ez, c[2]))]);
            }
        }
        if kind == ElementKind::Hex20R {
            let npe = kind.nodes_per_element();
            for conn in elements.chunks(npe) {
                for (m, i, j) in midside_edges(kind) {
                    let (a, b) = (nodes[conn[i]], nodes[conn[j]]);
                    nodes[conn[m]] = [0, 1, 2].map(|d| 0.5 * (a[d] + b[d]));
                }
            }
        }
        check_patch(kind, &nodes, &elements, &boundary, if step == 1 { 3 } else { 21 });
    }
}

/// Solves the patch with the linear field prescribed at the `boundary` nodes
/// and checks that the `free_dofs` interior DoFs reproduce it.
fn check_patch(kind: ElementKind, nodes: &[[f64; 3]], elements: &[usize], boundary: &[bool], free_dofs: usize) {
    let k = assemble(kind, nodes, elements);
    let dofs = 3 * nodes.len();
    let free: Vec<usize> = (0..dofs).filter(|d| !boundary[d / 3]).collect();
    let exact: Vec<f64> = nodes.iter().flat_map(|&x| linear_field(x)).collect();
    let rhs: Vec<f64> = free
        .iter()
        .map(|&r| -(0..dofs).filter(|c| boundary[c / 3]).map(|c| k[r * dofs + c] * exact[c]).sum::<f64>())
        .collect();
    let kff: Vec<f64> =
        free.iter().flat_map(|&r| free.iter().map(move |&c| (r, c))).map(|(r, c)| k[r * dofs + c]).collect();
    let n = free.len();
    let u = DMatrix::from_row_slice(n, n, &kff).lu().solve(&DVector::from_vec(rhs)).expect("regular system");
    assert_eq!(n, free_dofs, "{kind}");
    for (&dof, &got) in free.iter().zip(u.iter()) {
        assert!((got - exact[dof]).abs() < 1e-12, "{kind} dof {dof}: {got} vs {}", exact[dof]);
    }
}

/// Kuhn triangulation of a 2x2x2 block of jittered unit cubes: six
/// tetrahedra per cube around its main diagonal, conforming across cubes.
/// Tet10 midside nodes sit on the straight edges, shared between elements.
/// Returns nodes, connectivity and which nodes are on the block boundary.
fn tet_patch(kind: ElementKind) -> (Vec<[f64; 3]>, Vec<usize>, Vec<bool>) {
    let side = 3;
    let spacing = 0.5;
    let mut seed = 11;
    let mut nodes = Vec::new();
    let mut boundary = Vec::new();
    for k in 0..side {
        for j in 0..side {
            for i in 0..side {
                let amp = 0.1 * spacing;
                nodes.push([
                    i as f64 * spacing + amp * jitter(&mut seed),
                    j as f64 * spacing + amp * jitter(&mut seed),
                    k as f64 * spacing + amp * jitter(&mut seed),
                ]);
                boundary.push([i, j, k].iter().any(|&v| v == 0 || v == side - 1));
            }
        }
    }
    let id = |p: [usize; 3]| p[0] + side * (p[1] + side * p[2]);
    let perms = [[0, 1, 2], [0, 2, 1], [1, 0, 2], [1, 2, 0], [2, 0, 1], [2, 1, 0]];
    let mut corners = Vec::new();
    for (cz, cy, cx) in (0..2).flat_map(|z| (0..2).flat_map(move |y| (0..2).map(move |x| (z, y, x)))) {
        for perm in perms {
            let mut p = [cx, cy, cz];
            let mut tet = [id(p); 4];
            for (v, &axis) in perm.iter().enumerate() {
                p[axis] += 1;
                tet[v + 1] = id(p);
            }
            // Odd permutations are left-handed: swap two nodes to make det J > 0.
            let (a, b, c, d) = (nodes[tet[0]], nodes[tet[1]], nodes[tet[2]], nodes[tet[3]]);
            let e = |q: [f64; 3]| [q[0] - a[0], q[1] - a[1], q[2] - a[2]];
            let (u, v, w) = (e(b), e(c), e(d));
            let det = u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0])
                + u[2] * (v[0] * w[1] - v[1] * w[0]);
            if det < 0.0 {
                tet.swap(1, 2);
            }
            corners.push(tet);
        }
    }
    let mut elements = Vec::new();
    let mut midsides = std::collections::HashMap::new();
    for tet in corners {
        elements.extend_from_slice(&tet);
        if kind == ElementKind::Tet10 {
            for &(i, j) in ElementKind::Tet10.midside_edges() {
                let key = (tet[i].min(tet[j]), tet[i].max(tet[j]));
                let m = *midsides.entry(key).or_insert_with(|| {
                    let (a, b) = (nodes[tet[i]], nodes[tet[j]]);
                    nodes.push([0, 1, 2].map(|d| 0.5 * (a[d] + b[d])));
                    // An edge joining two boundary nodes may cut through the
                    // interior; prescribing the exact field there is harmless.
                    boundary.push(boundary[tet[i]] && boundary[tet[j]]);
                    nodes.len() - 1
                });
                elements.push(m);
            }
        }
    }
    (nodes, elements, boundary)
}

/// Patch test of the first kind for the tetrahedra on a jittered Kuhn block.
#[test]
fn tet_patch_reproduces_linear_field() {
    for kind in TET_KINDS {
        let (nodes, elements, boundary) = tet_patch(kind);
        assert_eq!(elements.len(), 48 * kind.nodes_per_element());
        let interior = boundary.iter().filter(|&&b| !b).count();
        // tet4: the centre node; tet10: plus the midsides of its 14 edges.
        assert_eq!(interior, if kind == ElementKind::Tet4 { 1 } else { 15 });
        check_patch(kind, &nodes, &elements, &boundary, 3 * interior);
    }
}

/// Constant stress of `linear_field`.
fn linear_field_stress() -> [[f64; 3]; 3] {
    let grad = [[2e-3, -1e-3, 0.5e-3], [0.7e-3, 1.5e-3, -0.8e-3], [-0.3e-3, 0.9e-3, 1.2e-3]];
    let strain =
        [grad[0][0], grad[1][1], grad[2][2], grad[0][1] + grad[1][0], grad[1][2] + grad[2][1], grad[2][0] + grad[0][2]];
    let d = STEEL.d_matrix();
    let s: Vec<f64> = (0..6).map(|r| (0..6).map(|c| d[r][c] * strain[c]).sum()).collect();
    [[s[0], s[3], s[5]], [s[3], s[1], s[4]], [s[5], s[4], s[2]]]
}

/// Patch test of the second kind on one distorted element: K u_linear must
/// equal the consistent nodal forces of the constant boundary traction,
/// f_a = surface integral of N_a sigma n. Hex20R is straight-edged for the
/// reason given at `distorted_patch_reproduces_linear_field`.
#[test]
fn single_element_forces_equal_consistent_tractions() {
    for kind in HEX_KINDS {
        let coords =
            if kind == ElementKind::Hex20R { straight_distorted_element(kind) } else { distorted_element(kind) };
        let n = kind.nodes_per_element();
        let u: Vec<f64> = coords.iter().flat_map(|&x| linear_field(x)).collect();
        let f = mat_vec(&stiffness(kind, &coords), &u);
        let sigma = linear_field_stress();

        let mut expected = vec![0.0; 3 * n];
        // 3 points per axis integrate the face integrands of all hex kinds exactly.
        let (pts, wts) = GaussOrder::Three.line_rule();
        let (mut shape, mut dn) = ([0.0; 20], [[0.0; 3]; 20]);
        for axis in 0..3 {
            let (t1, t2) = ((axis + 1) % 3, (axis + 2) % 3);
            for side in [-1.0, 1.0] {
                for (p, wp) in pts.iter().zip(wts) {
                    for (q, wq) in pts.iter().zip(wts) {
                        let mut xi = [0.0; 3];
                        (xi[axis], xi[t1], xi[t2]) = (side, *p, *q);
                        shape_functions(kind, xi, &mut shape[..n], &mut dn[..n]);
                        let tangent = |dir: usize| {
                            let mut t = [0.0; 3];
                            for (g, x) in dn[..n].iter().zip(&coords) {
                                for j in 0..3 {
                                    t[j] += g[dir] * x[j];
                                }
                            }
                            t
                        };
                        let (a, b) = (tangent(t1), tangent(t2));
                        // Cyclic tangents give the +xi_axis direction; flip on the minus face.
                        let area = [
                            side * (a[1] * b[2] - a[2] * b[1]) * wp * wq,
                            side * (a[2] * b[0] - a[0] * b[2]) * wp * wq,
                            side * (a[0] * b[1] - a[1] * b[0]) * wp * wq,
                        ];
                        for node in 0..n {
                            for i in 0..3 {
                                let traction: f64 = (0..3).map(|j| sigma[i][j] * area[j]).sum();
                                expected[3 * node + i] += shape[node] * traction;
                            }
                        }
                    }
                }
            }
        }
        let scale = norm(&expected);
        for (i, (got, want)) in f.iter().zip(&expected).enumerate() {
            assert!((got - want).abs() < 1e-10 * scale, "{kind} dof {i}: {got} vs {want}");
        }
    }
}

/// The same for the tetrahedra with straight edges, whose consistent loads of
/// a constant traction on a flat face are known in closed form: a third of
/// the face force at each corner (tet4), or at each midside node and nothing
/// at the corners (tet10).
#[test]
fn tet_forces_equal_consistent_tractions() {
    for kind in TET_KINDS {
        let coords = straight_distorted_element(kind);
        let n = kind.nodes_per_element();
        let u: Vec<f64> = coords.iter().flat_map(|&x| linear_field(x)).collect();
        let f = mat_vec(&stiffness(kind, &coords), &u);
        let sigma = linear_field_stress();
        let mut expected = vec![0.0; 3 * n];
        for opposite in 0..4 {
            let face: Vec<usize> = (0..4).filter(|&c| c != opposite).collect();
            let (a, b, c) = (coords[face[0]], coords[face[1]], coords[face[2]]);
            let e = |p: [f64; 3], q: [f64; 3]| [q[0] - p[0], q[1] - p[1], q[2] - p[2]];
            let (u1, u2) = (e(a, b), e(a, c));
            let mut area = [
                0.5 * (u1[1] * u2[2] - u1[2] * u2[1]),
                0.5 * (u1[2] * u2[0] - u1[0] * u2[2]),
                0.5 * (u1[0] * u2[1] - u1[1] * u2[0]),
            ];
            let inward = e(a, coords[opposite]);
            if (0..3).map(|d| area[d] * inward[d]).sum::<f64>() > 0.0 {
                area = area.map(|v| -v);
            }
            let force: Vec<f64> = (0..3).map(|i| (0..3).map(|j| sigma[i][j] * area[j]).sum()).collect();
            let loaded: Vec<usize> = if kind == ElementKind::Tet4 {
                face.clone()
            } else {
                midside_edges(kind)
                    .into_iter()
                    .filter(|(_, i, j)| face.contains(i) && face.contains(j))
                    .map(|(m, _, _)| m)
                    .collect()
            };
            assert_eq!(loaded.len(), 3);
            for node in loaded {
                for i in 0..3 {
                    expected[3 * node + i] += force[i] / 3.0;
                }
            }
        }
        let scale = norm(&expected);
        for (i, (got, want)) in f.iter().zip(&expected).enumerate() {
            assert!((got - want).abs() < 1e-10 * scale, "{kind} dof {i}: {got} vs {want}");
        }
    }
}

// ---------------------------------------------------------------- rigid body and spurious modes

#[test]
fn rigid_body_modes_have_zero_energy() {
    for kind in KINDS {
        let coords = distorted_element(kind);
        let k = stiffness(kind, &coords);
        let k_norm = norm(&k);
        let mut modes: Vec<Vec<f64>> = (0..3)
            .map(|d| coords.iter().flat_map(|_| (0..3).map(move |i| if i == d { 1.0 } else { 0.0 })).collect())
            .collect();
        for w in [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]] {
            // Infinitesimal rotation u = w x x.
            modes.push(
                coords
                    .iter()
                    .flat_map(|x| [w[1] * x[2] - w[2] * x[1], w[2] * x[0] - w[0] * x[2], w[0] * x[1] - w[1] * x[0]])
                    .collect(),
            );
        }
        for (m, r) in modes.iter().enumerate() {
            let kr = norm(&mat_vec(&k, r));
            assert!(kr <= 1e-10 * k_norm * norm(r), "{kind} rigid mode {m}: |K r| = {kr:e}");
        }
        // A pure stretch is not rigid: guards against a trivially zero K.
        let stretch: Vec<f64> = coords.iter().flat_map(|x| [x[0], 0.0, 0.0]).collect();
        assert!(norm(&mat_vec(&k, &stretch)) > 1e-3 * k_norm * norm(&stretch));
    }
}

#[test]
fn stiffness_has_exactly_six_zero_eigenvalues() {
    for kind in KINDS {
        let dofs = 3 * kind.nodes_per_element();
        let ev = test_support::reference::jacobi_eigenvalues(stiffness(kind, &distorted_element(kind)), dofs);
        let max = ev[dofs - 1];
        let zeros = ev.iter().filter(|v| v.abs() < 1e-9 * max).count();
        // A lone C3D20R has 6 hourglass modes on top of the 6 rigid-body modes:
        // 8 points x 6 strains give rank 48 for 60 DoFs. See
        // `hex20r_hourglass_modes_vanish_in_meshes` for assembled meshes.
        let expected = if kind == ElementKind::Hex20R { 12 } else { 6 };
        assert_eq!(zeros, expected, "{kind} eigenvalues / max: {:?}", ev.iter().map(|v| v / max).collect::<Vec<_>>());
        // Clear separation: the softest deformation mode is far from zero.
        assert!(ev[expected] > 1e-4 * max, "{kind}: first deformation eigenvalue {} too small", ev[expected] / max);
        assert!(ev.iter().all(|&v| v > -1e-9 * max), "{kind}: negative eigenvalue");
    }
}

/// Zero-energy modes of regular C3D20R box meshes: the single element's six
/// hourglass modes are not all suppressed by one neighbour (2x1x1 keeps 3),
/// but two elements across two directions leave only the 6 rigid-body modes.
/// The same counts hold for CalculiX, whose matrices these equal; 2x2x2 is the
/// mesh of the ccx comparison. Built by the box mesher, which takes hex20r as
/// hex20.
#[test]
fn hex20r_hourglass_modes_vanish_in_meshes() {
    for (divisions, expected) in [([1, 1, 1], 12), ([2, 1, 1], 9), ([2, 2, 1], 6), ([2, 2, 2], 6)] {
        let mesh =
            mesh_boxes(&[BoxRegion { min: [0.0; 3], max: [1.0, 0.6, 0.5], divisions }], ElementKind::Hex20R).unwrap();
        let dofs = 3 * mesh.nodes.len();
        let k = assemble(ElementKind::Hex20R, &mesh.nodes, &mesh.elements);
        let ev = test_support::reference::jacobi_eigenvalues(k, dofs);
        let max = ev[dofs - 1];
        let zeros = ev.iter().filter(|v| v.abs() < 1e-9 * max).count();
        assert_eq!(zeros, expected, "{divisions:?}: {:?}", &ev[..expected + 1]);
        assert!(ev[expected] > 1e-6 * max, "{divisions:?}: {}", ev[expected] / max);
    }
}

#[test]
fn matrices_are_symmetric() {
    for kind in KINDS {
        let coords = distorted_element(kind);
        let n = kind.nodes_per_element();
        let k = stiffness(kind, &coords);
        let mut m = vec![0.0; n * n];
        element_mass(kind, &coords, 7850.0, &mut m).unwrap();
        for (mat, size) in [(&k, 3 * n), (&m, n)] {
            for i in 0..size {
                for j in 0..size {
                    assert_eq!(mat[i * size + j], mat[j * size + i], "{kind} ({i},{j})");
                }
            }
        }
    }
}

// ---------------------------------------------------------------- mass

/// Frustum of a square pyramid: bottom 1x1 at z = 0, top 0.5x0.5 at z = 1,
/// volume h/3 (A1 + A2 + sqrt(A1 A2)) = 7/12. Its trilinear map is exact and
/// not affine. For hex20 the midside nodes are slid along their (straight)
/// edges, which changes the parametrisation but not the volume. Not for
/// hex20r: 2x2x2 points integrate det J exactly only for a trilinear map, so
/// a slid parametrisation changes C3D20R's (and CalculiX's) element mass.
fn frustum(kind: ElementKind) -> Vec<[f64; 3]> {
    kind.natural_node_coords()
        .expect("hexahedron")
        .iter()
        .map(|c| {
            let xi = [f64::from(c[0]), f64::from(c[1]), f64::from(c[2])];
            // Slide midsides by 0.1 of the natural edge length along their edge.
            let mut xi_s = xi;
            if kind == ElementKind::Hex20
                && let Some(axis) = c.iter().position(|&v| v == 0)
            {
                xi_s[axis] = 0.2;
            }
            let z = 0.5 * (xi_s[2] + 1.0);
            let half = 0.5 - 0.25 * z;
            [0.5 + half * xi_s[0], 0.5 + half * xi_s[1], z]
        })
        .collect()
}

/// Volume of the tetrahedron spanned by the first four points.
fn tet_volume(c: &[[f64; 3]]) -> f64 {
    let e = |q: [f64; 3]| [q[0] - c[0][0], q[1] - c[0][1], q[2] - c[0][2]];
    let (u, v, w) = (e(c[1]), e(c[2]), e(c[3]));
    (u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) + u[2] * (v[0] * w[1] - v[1] * w[0])) / 6.0
}

#[test]
fn mass_sums_to_rho_times_volume() {
    let rho = 2700.0;
    for kind in KINDS {
        let n = kind.nodes_per_element();
        // Straight tet edges keep det J constant, which the tet rules integrate
        // exactly; curved ones would need degree 3.
        let (coords, volume) = if is_tet(kind) {
            let c = straight_distorted_element(kind);
            let v = tet_volume(&c);
            (c, v)
        } else {
            (frustum(kind), 7.0 / 12.0)
        };
        let mut m = vec![0.0; n * n];
        element_mass(kind, &coords, rho, &mut m).unwrap();
        let total: f64 = m.iter().sum();
        assert!((total - rho * volume).abs() < 1e-12 * rho, "{kind}: {total} vs {}", rho * volume);
        assert!((0..n).all(|a| m[a * n + a] > 0.0), "{kind}: non-positive diagonal");
    }
}

/// CalculiX integrates the mass with the stiffness rule, which is too weak for
/// a regular mass matrix of C3D4 (one point: rho V / 16 in every entry, rank
/// one) and of C3D20R (eight points: rank 8 of 20). Pinned here because the
/// *FREQUENCY parity depends on it.
#[test]
fn reduced_masses_have_the_rank_of_their_rule() {
    let rho = 7850.0;
    let coords = distorted_element(ElementKind::Tet4);
    let mut m = [0.0; 16];
    element_mass(ElementKind::Tet4, &coords, rho, &mut m).unwrap();
    let each = rho * tet_volume(&coords) / 16.0;
    assert!(m.iter().all(|&v| (v - each).abs() < 1e-13 * each), "{m:?}");

    for (kind, rank) in [(ElementKind::Hex20R, 8), (ElementKind::Hex20, 20), (ElementKind::Tet10, 4)] {
        let n = kind.nodes_per_element();
        let mut m = vec![0.0; n * n];
        element_mass(kind, &distorted_element(kind), rho, &mut m).unwrap();
        let ev = test_support::reference::jacobi_eigenvalues(m, n);
        let max = ev[n - 1];
        let nonzero = ev.iter().filter(|&&v| v > 1e-10 * max).count();
        assert_eq!(nonzero, rank, "{kind}: {ev:?}");
    }
}

// ---------------------------------------------------------------- errors

#[test]
fn inverted_element_is_refused_with_gauss_point_and_det() {
    for kind in KINDS {
        // Mirroring z turns the element inside out.
        let coords: Vec<[f64; 3]> = distorted_element(kind).iter().map(|x| [x[0], x[1], -x[2]]).collect();
        let mut k = vec![0.0; 9 * kind.nodes_per_element().pow(2)];
        match element_stiffness(kind, &coords, &STEEL, &mut k) {
            Err(ElementError::NonPositiveJacobian { gauss_point, det, .. }) => {
                assert_eq!(gauss_point, 0);
                assert!(det < 0.0);
            }
            other => panic!("{kind}: expected NonPositiveJacobian, got {other:?}"),
        }
        let mut m = vec![0.0; kind.nodes_per_element().pow(2)];
        let err = element_mass(kind, &coords, 1.0, &mut m).unwrap_err();
        assert!(err.to_string().contains("Gauss point 0"), "{err}");
    }
}

/// The usual defect of imported tetrahedral meshes: two corners swapped
/// (left-handed numbering), and a flat tetrahedron.
#[test]
fn left_handed_and_flat_tets_are_refused() {
    for kind in TET_KINDS {
        let n = kind.nodes_per_element();
        let mut coords = straight_distorted_element(kind);
        coords.swap(1, 2);
        straighten(kind, &mut coords);
        let mut k = vec![0.0; 9 * n * n];
        assert!(matches!(
            element_stiffness(kind, &coords, &STEEL, &mut k),
            Err(ElementError::NonPositiveJacobian { det, .. }) if det < 0.0
        ));
        let mut flat = straight_distorted_element(kind);
        flat[3] = [0, 1, 2].map(|d| (flat[0][d] + flat[1][d] + flat[2][d]) / 3.0);
        straighten(kind, &mut flat);
        let mut m = vec![0.0; n * n];
        assert!(matches!(element_mass(kind, &flat, 1.0, &mut m), Err(ElementError::NonPositiveJacobian { .. })));
    }
}

/// Our hex8 agrees with what CalculiX 2.20 wrote to job.sti / job.mas
/// (`*FREQUENCY, SOLVER=MATRIXSTORAGE`) for the unit cube (E 210000, nu 0.3,
/// rho 7.85e-9), node-major as in its job.dof, to the 14 digits CalculiX
/// prints.
#[test]
fn hex8_matches_calculix_matrixstorage() {
    let cube = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
        [1.0, 0.0, 1.0],
        [1.0, 1.0, 1.0],
        [0.0, 1.0, 1.0],
    ];
    let mut k = vec![0.0; 576];
    let mat = Elasticity { e: 210000.0, nu: 0.3 };
    element_stiffness(ElementKind::Hex8, &cube, &mat, &mut k).unwrap();
    let mut m = vec![0.0; 64];
    element_mass(ElementKind::Hex8, &cube, 7.85e-9, &mut m).unwrap();
    // (row, column, value) as in job.sti, 1-based
    for (i, j, v) in [
        (1, 1, 4.9358974358974e+04),
        (1, 2, 1.6826923076923e+04),
        (1, 4, -2.2435897435897e+04),
        (1, 7, -1.7948717948718e+04),
        (2, 8, -1.7948717948718e+04),
        (22, 24, -1.6826923076923e+04),
    ] {
        let got = k[(i - 1) * 24 + j - 1];
        assert!((got - v).abs() <= 1e-13 * v.abs(), "K({i},{j}) = {got} vs {v}");
    }
    // job.mas: M(1,1) = 2.9074074074074e-10, M(1,4) = 1.4537037037037e-10
    assert!((m[0] - 2.9074074074074e-10).abs() < 1e-23);
    assert!((m[1] - 1.4537037037037e-10).abs() < 1e-23);
}

#[test]
fn bad_inputs_are_errors_not_panics() {
    let coords = distorted_element(ElementKind::Hex8);
    let mut k = vec![0.0; 24 * 24];
    let bad_nu = Elasticity { e: 1.0, nu: 0.5 };
    assert!(matches!(
        element_stiffness(ElementKind::Hex8, &coords, &bad_nu, &mut k),
        Err(ElementError::InvalidMaterial { .. })
    ));
    assert!(matches!(
        element_stiffness(ElementKind::Hex8, &coords[..7], &STEEL, &mut k),
        Err(ElementError::WrongNodeCount { .. })
    ));
    assert!(matches!(
        element_stiffness(ElementKind::Hex8, &coords, &STEEL, &mut k[..10]),
        Err(ElementError::WrongOutputSize { .. })
    ));
    assert!(matches!(
        element_mass(ElementKind::Hex8, &coords, -1.0, &mut k[..64]),
        Err(ElementError::InvalidDensity { .. })
    ));
    let mut nan = coords.clone();
    nan[3][1] = f64::NAN;
    assert!(matches!(
        element_mass(ElementKind::Hex8, &nan, 1.0, &mut k[..64]),
        Err(ElementError::NonFiniteCoordinate { node: 3 })
    ));
}

// ---------------------------------------------------------------- cantilever

/// 20x1x1 hex20 beam clamped at x = 0 with a transverse tip load: tip
/// deflection within 2 % of Timoshenko beam theory.
#[test]
fn hex20_cantilever_matches_timoshenko() {
    let (l, h) = (1.0, 0.1);
    let mesh =
        mesh_boxes(&[BoxRegion { min: [0.0; 3], max: [l, h, h], divisions: [20, 1, 1] }], ElementKind::Hex20).unwrap();
    let k = assemble(ElementKind::Hex20, &mesh.nodes, &mesh.elements);
    let dofs = 3 * mesh.nodes.len();
    let load = 1000.0;
    let mut f = vec![0.0; dofs];
    let tip: Vec<usize> = (0..mesh.nodes.len()).filter(|&i| (mesh.nodes[i][0] - l).abs() < 1e-9).collect();
    assert_eq!(tip.len(), 8);
    for &i in &tip {
        // Consistent load of a uniform traction on an 8-node face:
        // corners -1/12, midsides 1/3 of the resultant.
        let mid = [1, 2].iter().any(|&a| (mesh.nodes[i][a] - 0.5 * h).abs() < 1e-9);
        f[3 * i + 2] = load * if mid { 1.0 / 3.0 } else { -1.0 / 12.0 };
    }
    let free: Vec<usize> = (0..dofs).filter(|d| mesh.nodes[d / 3][0] > 1e-9).collect();
    let k = &k;
    let kff: Vec<f64> = free.iter().flat_map(|&r| free.iter().map(move |&c| k[r * dofs + c])).collect();
    let n = free.len();
    let u = DMatrix::from_row_slice(n, n, &kff)
        .lu()
        .solve(&DVector::from_iterator(n, free.iter().map(|&d| f[d])))
        .expect("regular system");
    let mut full = vec![0.0; dofs];
    for (&d, &v) in free.iter().zip(u.iter()) {
        full[d] = v;
    }
    let tip_deflection = tip.iter().map(|&i| full[3 * i + 2]).sum::<f64>() / tip.len() as f64;

    let (e, nu) = (STEEL.e, STEEL.nu);
    let g = e / (2.0 * (1.0 + nu));
    let (area, inertia) = (h * h, h * h.powi(3) / 12.0);
    let kappa = 10.0 * (1.0 + nu) / (12.0 + 11.0 * nu);
    let theory = load * l.powi(3) / (3.0 * e * inertia) + load * l / (kappa * g * area);
    let rel = (tip_deflection - theory).abs() / theory;
    println!("cantilever tip deflection {tip_deflection:e}, Timoshenko {theory:e}, deviation {:.3} %", 100.0 * rel);
    assert!(rel < 0.02, "tip deflection {tip_deflection:e} vs Timoshenko {theory:e} ({:.3} %)", 100.0 * rel);
}
