//! Element-level verification: shape functions, patch tests, rigid-body
//! modes, spurious zero-energy modes, mass/volume and a cantilever against
//! Timoshenko beam theory.

use super::*;
use crate::mesh::{BoxRegion, mesh_boxes};

const STEEL: Elasticity = Elasticity { e: 210e9, nu: 0.3 };
const KINDS: [ElementKind; 2] = [ElementKind::Hex8, ElementKind::Hex20];

// ---------------------------------------------------------------- helpers

/// Deterministic pseudo-random number in [-1, 1) (no external crates).
fn jitter(seed: &mut u64) -> f64 {
    *seed = seed
        .wrapping_mul(6_364_136_223_846_793_005)
        .wrapping_add(1_442_695_040_888_963_407);
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

fn distorted_element(kind: ElementKind) -> Vec<[f64; 3]> {
    kind.natural_node_coords()
        .iter()
        .map(|c| distorted_map([f64::from(c[0]), f64::from(c[1]), f64::from(c[2])]))
        .collect()
}

fn stiffness(kind: ElementKind, coords: &[[f64; 3]]) -> Vec<f64> {
    let dofs = 3 * kind.nodes_per_element();
    let mut k = vec![0.0; dofs * dofs];
    element_stiffness(kind, coords, &STEEL, &mut k).expect("valid element");
    k
}

fn mat_vec(m: &[f64], v: &[f64]) -> Vec<f64> {
    m.chunks(v.len())
        .map(|row| row.iter().zip(v).map(|(a, b)| a * b).sum())
        .collect()
}

fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

/// Dense Gaussian elimination with partial pivoting; `a` is n x n row-major.
fn solve_dense(mut a: Vec<f64>, mut b: Vec<f64>) -> Vec<f64> {
    let n = b.len();
    for col in 0..n {
        let pivot = (col..n)
            .max_by(|&i, &j| a[i * n + col].abs().total_cmp(&a[j * n + col].abs()))
            .unwrap();
        assert!(a[pivot * n + col].abs() > 0.0, "singular system");
        if pivot != col {
            for j in 0..n {
                a.swap(pivot * n + j, col * n + j);
            }
            b.swap(pivot, col);
        }
        let d = a[col * n + col];
        for row in col + 1..n {
            let f = a[row * n + col] / d;
            if f != 0.0 {
                for j in col..n {
                    a[row * n + j] -= f * a[col * n + j];
                }
                b[row] -= f * b[col];
            }
        }
    }
    let mut x = vec![0.0; n];
    for row in (0..n).rev() {
        let s: f64 = (row + 1..n).map(|j| a[row * n + j] * x[j]).sum();
        x[row] = (b[row] - s) / a[row * n + row];
    }
    x
}

/// Eigenvalues of a symmetric matrix by cyclic Jacobi rotations.
fn jacobi_eigenvalues(mut a: Vec<f64>, n: usize) -> Vec<f64> {
    for _sweep in 0..100 {
        let off: f64 = (0..n)
            .flat_map(|i| (0..n).filter(move |&j| j != i).map(move |j| (i, j)))
            .map(|(i, j)| a[i * n + j] * a[i * n + j])
            .sum();
        let diag: f64 = (0..n).map(|i| a[i * n + i] * a[i * n + i]).sum();
        if off <= 1e-30 * diag {
            break;
        }
        for p in 0..n {
            for q in p + 1..n {
                let apq = a[p * n + q];
                if apq.abs() < 1e-300 {
                    continue;
                }
                let theta = (a[q * n + q] - a[p * n + p]) / (2.0 * apq);
                let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
                let t = if theta == 0.0 { 1.0 } else { t };
                let c = 1.0 / (t * t + 1.0).sqrt();
                let s = t * c;
                for k in 0..n {
                    let (akp, akq) = (a[k * n + p], a[k * n + q]);
                    a[k * n + p] = c * akp - s * akq;
                    a[k * n + q] = s * akp + c * akq;
                }
                for k in 0..n {
                    let (apk, aqk) = (a[p * n + k], a[q * n + k]);
                    a[p * n + k] = c * apk - s * aqk;
                    a[q * n + k] = s * apk + c * aqk;
                }
            }
        }
    }
    let mut ev: Vec<f64> = (0..n).map(|i| a[i * n + i]).collect();
    ev.sort_by(f64::total_cmp);
    ev
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
                        global[(3 * ga + i) * dofs + 3 * gb + j] +=
                            ke[(3 * a + i) * 3 * npe + 3 * b + j];
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
        let stress: Vec<f64> = (0..6)
            .map(|r| (0..6).map(|c| d[r][c] * strain[c]).sum())
            .collect();
        for (i, s) in stress.iter().enumerate() {
            let want = if i == axis { STEEL.e * 1e-3 } else { 0.0 };
            assert!(
                (s - want).abs() < 1e-9 * STEEL.e * 1e-3,
                "axis {axis} component {i}: {s}"
            );
        }
        let mut shear = [0.0; 6];
        shear[3 + axis] = 2e-3;
        for r in 0..6 {
            let tau: f64 = (0..6).map(|c| d[r][c] * shear[c]).sum();
            let want = if r == 3 + axis { g * 2e-3 } else { 0.0 };
            assert!(
                (tau - want).abs() < 1e-9 * g * 2e-3,
                "shear {axis} row {r}: {tau}"
            );
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
        for (a, c) in kind.natural_node_coords().iter().enumerate() {
            let xi = [f64::from(c[0]), f64::from(c[1]), f64::from(c[2])];
            kind.shape_functions(xi, &mut shape[..n], &mut dn[..n]);
            for (b, &v) in shape[..n].iter().enumerate() {
                let want = if a == b { 1.0 } else { 0.0 };
                assert!((v - want).abs() < 1e-14, "{kind}: N{b} at node {a} = {v}");
            }
        }
        let xi = [0.31, -0.72, 0.18];
        kind.shape_functions(xi, &mut shape[..n], &mut dn[..n]);
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
        kind.shape_functions(xi, &mut s[..n], &mut dn[..n]);
        let h = 1e-6;
        for d in 0..3 {
            let (mut p, mut m) = (xi, xi);
            p[d] += h;
            m[d] -= h;
            kind.shape_functions(p, &mut sp[..n], &mut scratch[..n]);
            kind.shape_functions(m, &mut sm[..n], &mut scratch[..n]);
            for a in 0..n {
                let fd = (sp[a] - sm[a]) / (2.0 * h);
                assert!(
                    (fd - dn[a][d]).abs() < 1e-8,
                    "{kind} node {a} axis {d}: {fd} vs {}",
                    dn[a][d]
                );
            }
        }
    }
}

// ---------------------------------------------------------------- patch tests

/// Patch test of the first kind: 2x2x2 elements with every node randomly
/// displaced (curved edges for hex20); the linear field prescribed on the
/// boundary nodes must be reproduced exactly at the interior nodes.
#[test]
fn distorted_patch_reproduces_linear_field() {
    for kind in KINDS {
        // Node lattice with `step` lattice intervals per element edge.
        let step = if kind == ElementKind::Hex8 { 1 } else { 2 };
        let side = 2 * step + 1;
        let is_node = |i: usize, j: usize, k: usize| {
            [i, j, k].iter().filter(|&&v| v % 2 == 1).count() <= 1 || step == 1
        };
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
        for (ez, ey, ex) in
            (0..2).flat_map(|z| (0..2).flat_map(move |y| (0..2).map(move |x| (z, y, x))))
        {
            for c in kind.natural_node_coords() {
                let off = |e: usize, c: i8| e * step + ((i32::from(c) + 1) as usize * step) / 2;
                elements.push(id[off(ex, c[0]) + side * (off(ey, c[1]) + side * off(ez, c[2]))]);
            }
        }
        let k = assemble(kind, &nodes, &elements);
        let dofs = 3 * nodes.len();
        let free: Vec<usize> = (0..dofs).filter(|d| !boundary[d / 3]).collect();
        let exact: Vec<f64> = nodes.iter().flat_map(|&x| linear_field(x)).collect();
        let rhs: Vec<f64> = free
            .iter()
            .map(|&r| {
                -(0..dofs)
                    .filter(|c| boundary[c / 3])
                    .map(|c| k[r * dofs + c] * exact[c])
                    .sum::<f64>()
            })
            .collect();
        let kff: Vec<f64> = free
            .iter()
            .flat_map(|&r| free.iter().map(move |&c| (r, c)))
            .map(|(r, c)| k[r * dofs + c])
            .collect();
        let u = solve_dense(kff, rhs);
        assert!(free.len() == if step == 1 { 3 } else { 21 });
        for (&dof, &got) in free.iter().zip(&u) {
            assert!(
                (got - exact[dof]).abs() < 1e-12,
                "{kind} dof {dof}: {got} vs {}",
                exact[dof]
            );
        }
    }
}

/// Patch test of the second kind on one distorted element: K u_linear must
/// equal the consistent nodal forces of the constant boundary traction,
/// f_a = surface integral of N_a sigma n.
#[test]
fn single_element_forces_equal_consistent_tractions() {
    for kind in KINDS {
        let coords = distorted_element(kind);
        let n = kind.nodes_per_element();
        let u: Vec<f64> = coords.iter().flat_map(|&x| linear_field(x)).collect();
        let f = mat_vec(&stiffness(kind, &coords), &u);

        // Constant stress of the linear field.
        let grad = [
            [2e-3, -1e-3, 0.5e-3],
            [0.7e-3, 1.5e-3, -0.8e-3],
            [-0.3e-3, 0.9e-3, 1.2e-3],
        ];
        let strain = [
            grad[0][0],
            grad[1][1],
            grad[2][2],
            grad[0][1] + grad[1][0],
            grad[1][2] + grad[2][1],
            grad[2][0] + grad[0][2],
        ];
        let d = STEEL.d_matrix();
        let s: Vec<f64> = (0..6)
            .map(|r| (0..6).map(|c| d[r][c] * strain[c]).sum())
            .collect();
        let sigma = [[s[0], s[3], s[5]], [s[3], s[1], s[4]], [s[5], s[4], s[2]]];

        let mut expected = vec![0.0; 3 * n];
        let (pts, wts) = kind.gauss_order().line_rule();
        let (mut shape, mut dn) = ([0.0; 20], [[0.0; 3]; 20]);
        for axis in 0..3 {
            let (t1, t2) = ((axis + 1) % 3, (axis + 2) % 3);
            for side in [-1.0, 1.0] {
                for (p, wp) in pts.iter().zip(wts) {
                    for (q, wq) in pts.iter().zip(wts) {
                        let mut xi = [0.0; 3];
                        (xi[axis], xi[t1], xi[t2]) = (side, *p, *q);
                        kind.shape_functions(xi, &mut shape[..n], &mut dn[..n]);
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
            assert!(
                (got - want).abs() < 1e-10 * scale,
                "{kind} dof {i}: {got} vs {want}"
            );
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
            .map(|d| {
                coords
                    .iter()
                    .flat_map(|_| (0..3).map(move |i| if i == d { 1.0 } else { 0.0 }))
                    .collect()
            })
            .collect();
        for w in [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]] {
            // Infinitesimal rotation u = w x x.
            modes.push(
                coords
                    .iter()
                    .flat_map(|x| {
                        [
                            w[1] * x[2] - w[2] * x[1],
                            w[2] * x[0] - w[0] * x[2],
                            w[0] * x[1] - w[1] * x[0],
                        ]
                    })
                    .collect(),
            );
        }
        for (m, r) in modes.iter().enumerate() {
            let kr = norm(&mat_vec(&k, r));
            assert!(
                kr <= 1e-10 * k_norm * norm(r),
                "{kind} rigid mode {m}: |K r| = {kr:e}"
            );
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
        let ev = jacobi_eigenvalues(stiffness(kind, &distorted_element(kind)), dofs);
        let max = ev[dofs - 1];
        let zeros = ev.iter().filter(|v| v.abs() < 1e-9 * max).count();
        assert_eq!(
            zeros,
            6,
            "{kind} eigenvalues / max: {:?}",
            ev.iter().map(|v| v / max).collect::<Vec<_>>()
        );
        // Clear separation: the softest deformation mode is far from zero.
        assert!(
            ev[6] > 1e-4 * max,
            "{kind}: 7th eigenvalue {} too small",
            ev[6] / max
        );
        assert!(
            ev.iter().all(|&v| v > -1e-9 * max),
            "{kind}: negative eigenvalue"
        );
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
/// edges, which changes the parametrisation but not the volume.
fn frustum(kind: ElementKind) -> Vec<[f64; 3]> {
    kind.natural_node_coords()
        .iter()
        .map(|c| {
            let xi = [f64::from(c[0]), f64::from(c[1]), f64::from(c[2])];
            // Slide midsides by 0.1 of the natural edge length along their edge.
            let mut xi_s = xi;
            if let Some(axis) = c.iter().position(|&v| v == 0) {
                xi_s[axis] = 0.2;
            }
            let z = 0.5 * (xi_s[2] + 1.0);
            let half = 0.5 - 0.25 * z;
            [0.5 + half * xi_s[0], 0.5 + half * xi_s[1], z]
        })
        .collect()
}

#[test]
fn mass_sums_to_rho_times_volume() {
    let rho = 2700.0;
    for kind in KINDS {
        let n = kind.nodes_per_element();
        let mut m = vec![0.0; n * n];
        element_mass(kind, &frustum(kind), rho, &mut m).unwrap();
        let total: f64 = m.iter().sum();
        assert!(
            (total - rho * 7.0 / 12.0).abs() < 1e-12 * rho,
            "{kind}: {total}"
        );
        assert!(
            (0..n).all(|a| m[a * n + a] > 0.0),
            "{kind}: non-positive diagonal"
        );
    }
}

// ---------------------------------------------------------------- errors

#[test]
fn inverted_element_is_refused_with_gauss_point_and_det() {
    for kind in KINDS {
        // Mirroring z turns the element inside out.
        let coords: Vec<[f64; 3]> = distorted_element(kind)
            .iter()
            .map(|x| [x[0], x[1], -x[2]])
            .collect();
        let mut k = vec![0.0; 9 * kind.nodes_per_element().pow(2)];
        match element_stiffness(kind, &coords, &STEEL, &mut k) {
            Err(ElementError::NonPositiveJacobian {
                gauss_point, det, ..
            }) => {
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
    let mesh = mesh_boxes(
        &[BoxRegion {
            min: [0.0; 3],
            max: [l, h, h],
            divisions: [20, 1, 1],
        }],
        ElementKind::Hex20,
    )
    .unwrap();
    let k = assemble(ElementKind::Hex20, &mesh.nodes, &mesh.elements);
    let dofs = 3 * mesh.nodes.len();
    let load = 1000.0;
    let mut f = vec![0.0; dofs];
    let tip: Vec<usize> = (0..mesh.nodes.len())
        .filter(|&i| (mesh.nodes[i][0] - l).abs() < 1e-9)
        .collect();
    assert_eq!(tip.len(), 8);
    for &i in &tip {
        // Consistent load of a uniform traction on an 8-node face:
        // corners -1/12, midsides 1/3 of the resultant.
        let mid = [1, 2]
            .iter()
            .any(|&a| (mesh.nodes[i][a] - 0.5 * h).abs() < 1e-9);
        f[3 * i + 2] = load * if mid { 1.0 / 3.0 } else { -1.0 / 12.0 };
    }
    let free: Vec<usize> = (0..dofs).filter(|d| mesh.nodes[d / 3][0] > 1e-9).collect();
    let k = &k;
    let kff: Vec<f64> = free
        .iter()
        .flat_map(|&r| free.iter().map(move |&c| k[r * dofs + c]))
        .collect();
    let u = solve_dense(kff, free.iter().map(|&d| f[d]).collect());
    let mut full = vec![0.0; dofs];
    for (&d, &v) in free.iter().zip(&u) {
        full[d] = v;
    }
    let tip_deflection = tip.iter().map(|&i| full[3 * i + 2]).sum::<f64>() / tip.len() as f64;

    let (e, nu) = (STEEL.e, STEEL.nu);
    let g = e / (2.0 * (1.0 + nu));
    let (area, inertia) = (h * h, h * h.powi(3) / 12.0);
    let kappa = 10.0 * (1.0 + nu) / (12.0 + 11.0 * nu);
    let theory = load * l.powi(3) / (3.0 * e * inertia) + load * l / (kappa * g * area);
    let rel = (tip_deflection - theory).abs() / theory;
    println!(
        "cantilever tip deflection {tip_deflection:e}, Timoshenko {theory:e}, deviation {:.3} %",
        100.0 * rel
    );
    assert!(
        rel < 0.02,
        "tip deflection {tip_deflection:e} vs Timoshenko {theory:e} ({:.3} %)",
        100.0 * rel
    );
}
