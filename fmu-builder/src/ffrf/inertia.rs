//! Mesh-level fields for the floating frame: the basis expanded to every mesh node (slaves follow
//! their flange rigidly), inertial load cases of frame motion, and the rotation invariants of
//! docs/ARCHITECTURE.md (G_a, O_ab, o_ab). Cross products act per node (E_a w = e_a x w_j), and with the
//! consistent mass M = M_s (x) I3 they commute with M, so every invariant is a product of the
//! nodal mass with per-node cross products of the basis and the positions.
//!
//! The nodal mass is applied once, to all basis columns and components at a time; the cross
//! products are then read off nine mass-weighted component products (`ComponentProducts`), so the
//! cost is one pass over M_s and one reduction over the nodes, not one per invariant.

use crate::ffrf::rows::{Layout, Rows};
use crate::model::flange::Flange;
use crate::model::rigid_coupling::{Assembled, DofOf, NodeDofs};
use faer::{Mat, MatRef};

/// A unit inertial load case of the frame's motion (loads on the body, in the body frame).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LoadCase {
    /// a_B = e_a: body force -rho e_a (gravity and translational acceleration).
    Translation(usize),
    /// angular acceleration e_a: body force -rho e_a x x.
    Euler(usize),
    /// coefficient of w_a w_b (a <= b) in the centrifugal body force -rho w x (w x x).
    Centrifugal(usize, usize),
}

impl LoadCase {
    pub fn translations() -> Vec<LoadCase> {
        (0..3).map(LoadCase::Translation).collect()
    }
    pub fn rotations() -> Vec<LoadCase> {
        let mut v: Vec<LoadCase> = (0..3).map(LoadCase::Euler).collect();
        for a in 0..3 {
            for b in a..3 {
                v.push(LoadCase::Centrifugal(a, b));
            }
        }
        v
    }

    /// The acceleration field of the case at position `x` (the body force is -rho times it).
    /// Each component is a coordinate, its negative or zero, as the cross products give them.
    fn acceleration(self, x: [f64; 3]) -> [f64; 3] {
        let mut out = [0.0; 3];
        match self {
            LoadCase::Translation(a) => out[a] = 1.0,
            LoadCase::Euler(a) => {
                let (b, c) = others(a);
                (out[b], out[c]) = (-x[c], x[b]);
            }
            // e_a x (e_a x x) = e_a x_a - x
            LoadCase::Centrifugal(a, b) if a == b => {
                let (b, c) = others(a);
                (out[b], out[c]) = (-x[b], -x[c]);
            }
            // e_a x (e_b x x) + e_b x (e_a x x) = e_b x_a + e_a x_b
            LoadCase::Centrifugal(a, b) => (out[a], out[b]) = (x[b], x[a]),
        }
        out
    }
}

/// The two axes after `a` in cyclic order: e_a x e_b = e_c.
fn others(a: usize) -> (usize, usize) {
    ((a + 1) % 3, (a + 2) % 3)
}

/// Positions relative to the body origin, one row per node.
fn positions<'a>(layout: &'a Layout, nodes: &[[f64; 3]], origin: [f64; 3]) -> Rows<'a> {
    Rows::from_fn(layout, 3, |n, x| {
        for ((x, p), o) in x.iter_mut().zip(nodes[n]).zip(origin) {
            *x = p - o;
        }
    })
}

/// How a mesh node moves with the constrained model's DoFs.
enum Follows {
    /// its own three DoFs, from this one on
    Dofs(usize),
    /// a flange's master (six DoFs from `first`) rigidly, `arm` from its reference
    Master { first: usize, arm: [f64; 3] },
    /// the mount, held
    Held,
    /// a distributing flange's node with dependent directions (`DofMap::dependent`)
    Partial([DofOf; 3]),
}

fn node_follows(model: &Assembled, nodes: &[[f64; 3]], flanges: &[Flange]) -> Vec<Follows> {
    let d = &model.dofs;
    let nc = d.n_clamped();
    let follows = |(n, nd): (usize, &NodeDofs)| match *nd {
        NodeDofs::Free(first) => Follows::Dofs(first),
        NodeDofs::Slave(k) if d.flange_first[k] >= nc => Follows::Held,
        NodeDofs::Slave(k) => {
            let r = flanges[k].reference;
            let arm = [nodes[n][0] - r[0], nodes[n][1] - r[1], nodes[n][2] - r[2]];
            Follows::Master { first: d.flange_first[k], arm }
        }
        NodeDofs::Partial(dofs) => Follows::Partial(dofs),
    };
    d.node.iter().enumerate().map(follows).collect()
}

/// A constrained-model field (n_clamped x k; the mount held) on every mesh node (3N x k).
pub fn expand(model: &Assembled, nodes: &[[f64; 3]], flanges: &[Flange], phi: MatRef<'_, f64>) -> Mat<f64> {
    let follows = node_follows(model, nodes, flanges);
    let mut out = Mat::<f64>::zeros(3 * nodes.len(), phi.ncols());
    // column by column: both matrices are read and written down their columns
    for j in 0..phi.ncols() {
        let (src, mut dst) = (phi.col(j), out.col_mut(j));
        for (n, how) in follows.iter().enumerate() {
            let u = match *how {
                Follows::Dofs(first) => [src[first], src[first + 1], src[first + 2]],
                Follows::Master { first, arm: x } => {
                    let u = [src[first], src[first + 1], src[first + 2]];
                    let t = [src[first + 3], src[first + 4], src[first + 5]];
                    // u + theta x x
                    [
                        u[0] + t[1] * x[2] - t[2] * x[1],
                        u[1] + t[2] * x[0] - t[0] * x[2],
                        u[2] + t[0] * x[1] - t[1] * x[0],
                    ]
                }
                Follows::Held => continue,
                Follows::Partial(dofs) => dofs.map(|dof| match dof {
                    DofOf::Own(g) => src[g],
                    // the held mount's terms are zero
                    DofOf::Dependent(j) => model.dofs.dependent[j]
                        .image
                        .iter()
                        .filter(|t| t.0 < src.nrows())
                        .map(|&(g, c)| c * src[g])
                        .sum(),
                }),
            };
            for (i, u) in u.into_iter().enumerate() {
                dst[3 * n + i] = u;
            }
        }
    }
    out
}

/// Nodal forces on the mesh (3N x k) as loads on the constrained model (n_clamped x k): slave
/// forces move to their flange's master as force and moment; the mount's slaves are held.
pub fn restrict(model: &Assembled, nodes: &[[f64; 3]], flanges: &[Flange], f: MatRef<'_, f64>) -> Mat<f64> {
    let follows = node_follows(model, nodes, flanges);
    let n_clamped = model.dofs.n_clamped();
    let mut out = Mat::<f64>::zeros(n_clamped, f.ncols());
    for j in 0..f.ncols() {
        let (src, mut dst) = (f.col(j), out.col_mut(j));
        for (n, how) in follows.iter().enumerate() {
            let fj = [src[3 * n], src[3 * n + 1], src[3 * n + 2]];
            match *how {
                Follows::Dofs(first) => {
                    for (i, f) in fj.into_iter().enumerate() {
                        dst[first + i] += f;
                    }
                }
                Follows::Master { first, arm: x } => {
                    for (i, f) in fj.into_iter().enumerate() {
                        dst[first + i] += f;
                    }
                    // moment x x f
                    dst[first + 3] += x[1] * fj[2] - x[2] * fj[1];
                    dst[first + 4] += x[2] * fj[0] - x[0] * fj[2];
                    dst[first + 5] += x[0] * fj[1] - x[1] * fj[0];
                }
                Follows::Held => {}
                Follows::Partial(dofs) => {
                    for (dof, f) in dofs.into_iter().zip(fj) {
                        match dof {
                            DofOf::Own(g) => dst[g] += f,
                            DofOf::Dependent(j) => {
                                for &(g, c) in model.dofs.dependent[j].image.iter().filter(|t| t.0 < n_clamped) {
                                    dst[g] += c * f;
                                }
                            }
                        }
                    }
                }
            }
        }
    }
    out
}

/// Mesh-level nodal forces of a unit inertial load case.
pub fn inertial_load(model: &Assembled, nodes: &[[f64; 3]], origin: [f64; 3], case: LoadCase) -> Mat<f64> {
    // three values a node: the mesh's numbering is near enough in memory
    let layout = Layout::natural(nodes.len());
    let field = Rows::from_fn(&layout, 3, |n, a| {
        let x = [nodes[n][0] - origin[0], nodes[n][1] - origin[1], nodes[n][2] - origin[2]];
        a.copy_from_slice(&case.acceleration(x));
    });
    let m_field = Rows::symmetric_times(&model.nodal_mass, &field);
    Mat::from_fn(3 * nodes.len(), 1, |i, _| -m_field.row(i / 3)[i % 3])
}

/// G_a (3 x r x r), O_ab (3 x 3 x r x r) and o_ab (3 x 3 x r), row-major, from the mesh-level
/// basis `phi` (3N x r).
pub struct RotationInvariants {
    pub g: Vec<f64>,
    pub o_mat: Vec<f64>,
    pub o_vec: Vec<f64>,
}

/// The mass-weighted products of basis components every rotation invariant is made of:
/// s(c, d, i, j) = (M phi_i)_c . (phi_j)_d and t(c, d, i) = (M phi_i)_c . x_d, each a sum over
/// the nodes of component c of one field times component d of another.
struct ComponentProducts {
    r: usize,
    /// 3r x 3r: block (c, d) is s(c, d, ., .)
    s: Mat<f64>,
    /// 3r x 3: column d of block c is t(c, d, .)
    t: Mat<f64>,
}

impl ComponentProducts {
    fn new(model: &Assembled, nodes: &[[f64; 3]], origin: [f64; 3], phi: MatRef<'_, f64>) -> Self {
        let layout = Layout::spatial(nodes);
        let phi_rows = Rows::by_node(&layout, phi);
        let m_phi = Rows::symmetric_times(&model.nodal_mass, &phi_rows);
        let s = m_phi.inner(&phi_rows);
        let t = m_phi.inner(&positions(&layout, nodes, origin));
        Self { r: phi.ncols(), s, t }
    }
    fn s(&self, c: usize, d: usize, i: usize, j: usize) -> f64 {
        self.s[(c * self.r + i, d * self.r + j)]
    }
    fn t(&self, c: usize, d: usize, i: usize) -> f64 {
        self.t[(c * self.r + i, d)]
    }
}

/// w . (e_a x v) from the component products p(c, d) = w_c v_d: (e_a x v)_b = -v_c and
/// (e_a x v)_c = v_b for the cyclic (a, b, c).
fn cross(a: usize, p: impl Fn(usize, usize) -> f64) -> f64 {
    let (b, c) = others(a);
    p(c, b) - p(b, c)
}

/// w . (e_a x (e_b x v)) from the component products p(c, d) = w_c v_d, by
/// e_a x (e_b x v) = e_b v_a - delta_ab v. For a = b the sum runs over the two other axes only,
/// as the cross products have it, instead of adding and then cancelling w_a v_a.
fn double_cross(a: usize, b: usize, p: impl Fn(usize, usize) -> f64) -> f64 {
    if a == b {
        let (b, c) = others(a);
        -(p(b, b) + p(c, c))
    } else {
        p(b, a)
    }
}

/// The rotation invariants of the mesh-level basis `phi` (the mass products here on every
/// back-end, as `invariants::invariants`'s).
pub fn rotation_invariants(
    model: &Assembled,
    nodes: &[[f64; 3]],
    origin: [f64; 3],
    phi: MatRef<'_, f64>,
) -> RotationInvariants {
    let r = phi.ncols();
    let p = ComponentProducts::new(model, nodes, origin, phi);
    let mut g = vec![0.0; 3 * r * r];
    let mut o_mat = vec![0.0; 9 * r * r];
    let mut o_vec = vec![0.0; 9 * r];
    for a in 0..3 {
        for i in 0..r {
            for j in 0..r {
                let ga = |i, j| cross(a, |c, d| p.s(c, d, i, j));
                // exactly skew: average out round-off
                g[(a * r + i) * r + j] = 0.5 * (ga(i, j) - ga(j, i));
            }
        }
        for b in 0..3 {
            for i in 0..r {
                for j in 0..r {
                    o_mat[((3 * a + b) * r + i) * r + j] = double_cross(a, b, |c, d| p.s(c, d, i, j));
                }
                o_vec[(3 * a + b) * r + i] = double_cross(a, b, |c, d| p.t(c, d, i));
            }
        }
    }
    RotationInvariants { g, o_mat, o_vec }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::error::BuildError;
    use crate::input::element::ElementKind;
    use crate::input::mesh::{BoxRegion, mesh_boxes};
    use crate::input::spec::Role;
    use crate::linalg::sparse::mul_new;
    use crate::model::assembly::{SolidMaterial, uncoupled};
    use crate::model::fe::Elasticity;
    use crate::model::flange::FlangeCoupling;
    use crate::model::rigid_coupling::rigid_coupling;

    /// A hex20 bar (consistent mass with negative couplings) held at x = 0 by the mount, a force
    /// flange at x = 2, the origin off every axis of the mesh; and a dense field on the
    /// constrained model with columns of different sizes.
    pub(crate) struct Bar {
        pub nodes: Vec<[f64; 3]>,
        pub flanges: Vec<Flange>,
        pub model: Assembled,
        pub origin: [f64; 3],
        /// n_clamped x columns
        pub phi: Mat<f64>,
    }

    pub(crate) fn bar(columns: usize) -> Bar {
        let boxes = [BoxRegion { min: [0.0; 3], max: [2.0, 0.5, 0.4], divisions: [3, 2, 1] }];
        let mesh = mesh_boxes(&boxes, ElementKind::Hex20).unwrap();
        let steel = SolidMaterial { name: "steel".into(), elasticity: Elasticity { e: 2.1e11, nu: 0.3 }, rho: 7850.0 };
        let free = uncoupled(&mesh, &[steel], &|e, m| BuildError::numerical(format!("{e}: {m}"))).unwrap();
        let on = |x: f64| (0..mesh.n_nodes()).filter(|&n| mesh.nodes[n][0] == x).collect::<Vec<_>>();
        let flanges = vec![
            Flange {
                name: "base".into(),
                role: Role::Motion,
                reference: [0.0, 0.25, 0.0],
                slaves: on(0.0),
                coupling: FlangeCoupling::Rigid,
            },
            Flange {
                name: "arm".into(),
                role: Role::Force,
                reference: [2.3, 0.2, 0.1],
                slaves: on(2.0),
                coupling: FlangeCoupling::Rigid,
            },
        ];
        let origin = [0.1, 0.3, -0.2];
        let model = rigid_coupling(&free, &mesh.nodes, &flanges, origin).unwrap();
        let nc = model.dofs.n_clamped();
        let phi = Mat::from_fn(nc, columns, |i, j| ((i * 37 + j * 11) % 17) as f64 / 17.0 - 0.4 + j as f64);
        Bar { nodes: mesh.nodes, flanges, model, origin, phi }
    }

    /// The straightforward formulation the fast one replaced: whole mesh fields E_a w, their
    /// products with M = M_s (x) I3 column by column, and one dense product per invariant.
    mod reference {
        use super::*;

        pub fn positions(nodes: &[[f64; 3]], origin: [f64; 3]) -> Mat<f64> {
            Mat::from_fn(3 * nodes.len(), 1, |r, _| nodes[r / 3][r % 3] - origin[r % 3])
        }

        /// E_a w: e_a x w per node, for every column.
        pub fn cross_axis(a: usize, w: MatRef<'_, f64>) -> Mat<f64> {
            let mut out = Mat::<f64>::zeros(w.nrows(), w.ncols());
            let (b, c) = others(a);
            for j in 0..w.ncols() {
                for node in 0..w.nrows() / 3 {
                    out[(3 * node + b, j)] = -w[(3 * node + c, j)];
                    out[(3 * node + c, j)] = w[(3 * node + b, j)];
                }
            }
            out
        }

        /// (M_s (x) I3) w
        pub fn mass_times(model: &Assembled, w: MatRef<'_, f64>) -> Mat<f64> {
            let n = w.nrows() / 3;
            let mut out = Mat::<f64>::zeros(w.nrows(), w.ncols());
            for comp in 0..3 {
                let part = Mat::<f64>::from_fn(n, w.ncols(), |i, j| w[(3 * i + comp, j)]);
                let mp = mul_new(&model.nodal_mass, part.as_ref());
                for i in 0..n {
                    for j in 0..w.ncols() {
                        out[(3 * i + comp, j)] = mp[(i, j)];
                    }
                }
            }
            out
        }

        pub fn inertial_load(model: &Assembled, nodes: &[[f64; 3]], origin: [f64; 3], case: LoadCase) -> Mat<f64> {
            let x = positions(nodes, origin);
            let field = match case {
                LoadCase::Translation(a) => Mat::from_fn(x.nrows(), 1, |r, _| if r % 3 == a { 1.0 } else { 0.0 }),
                LoadCase::Euler(a) => cross_axis(a, x.as_ref()),
                LoadCase::Centrifugal(a, b) => {
                    let ab = cross_axis(a, cross_axis(b, x.as_ref()).as_ref());
                    if a == b { ab } else { &ab + &cross_axis(b, cross_axis(a, x.as_ref()).as_ref()) }
                }
            };
            -mass_times(model, field.as_ref())
        }

        pub fn rotation_invariants(
            model: &Assembled,
            nodes: &[[f64; 3]],
            origin: [f64; 3],
            phi: MatRef<'_, f64>,
        ) -> RotationInvariants {
            let r = phi.ncols();
            let m_phi = mass_times(model, phi);
            let x = positions(nodes, origin);
            let mut g = vec![0.0; 3 * r * r];
            let mut o_mat = vec![0.0; 9 * r * r];
            let mut o_vec = vec![0.0; 9 * r];
            for a in 0..3 {
                let ga = m_phi.transpose() * cross_axis(a, phi);
                for i in 0..r {
                    for j in 0..r {
                        g[(a * r + i) * r + j] = 0.5 * (ga[(i, j)] - ga[(j, i)]);
                    }
                }
                for b in 0..3 {
                    let oab = m_phi.transpose() * cross_axis(a, cross_axis(b, phi).as_ref());
                    let v = m_phi.transpose() * cross_axis(a, cross_axis(b, x.as_ref()).as_ref());
                    for i in 0..r {
                        for j in 0..r {
                            o_mat[((3 * a + b) * r + i) * r + j] = oab[(i, j)];
                        }
                        o_vec[(3 * a + b) * r + i] = v[(i, 0)];
                    }
                }
            }
            RotationInvariants { g, o_mat, o_vec }
        }
    }

    /// Entry by entry within `rel` of the largest entry of `expected`, same length. The fast
    /// route sums the same products in another order (nine component products instead of one
    /// dense product per invariant), so the two differ by round-off: a few units of 1e-16 times
    /// the sum of the magnitudes summed, which for these fields is within a small factor of the
    /// largest entry; 1e-12 leaves room for that and still catches any wrong sign or index.
    pub(crate) fn assert_close(got: &[f64], expected: &[f64], rel: f64, what: &str) {
        assert_eq!(got.len(), expected.len(), "{what}: length");
        let scale = expected.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        assert!(scale > 0.0, "{what}: all zero");
        for (k, (g, e)) in got.iter().zip(expected).enumerate() {
            assert!((g - e).abs() <= rel * scale, "{what}[{k}]: {g} vs {e} (scale {scale})");
        }
    }

    fn entries(m: MatRef<'_, f64>) -> Vec<f64> {
        (0..m.ncols()).flat_map(|j| (0..m.nrows()).map(move |i| m[(i, j)])).collect()
    }

    #[test]
    fn rotation_invariants_equal_the_reference_formulation() {
        let Bar { nodes, flanges, model, origin, phi: phi_c } = bar(4);
        let phi = expand(&model, &nodes, &flanges, phi_c.as_ref());
        let fast = rotation_invariants(&model, &nodes, origin, phi.as_ref());
        let slow = reference::rotation_invariants(&model, &nodes, origin, phi.as_ref());
        assert_eq!((fast.g.len(), fast.o_mat.len(), fast.o_vec.len()), (3 * 16, 9 * 16, 9 * 4));
        assert_close(&fast.g, &slow.g, 1e-12, "G_a");
        assert_close(&fast.o_mat, &slow.o_mat, 1e-12, "O_ab");
        assert_close(&fast.o_vec, &slow.o_vec, 1e-12, "o_ab");
    }

    #[test]
    fn inertial_loads_equal_the_reference_formulation() {
        let Bar { nodes, model, origin, .. } = bar(1);
        for case in LoadCase::translations().into_iter().chain(LoadCase::rotations()) {
            let fast = inertial_load(&model, &nodes, origin, case);
            let slow = reference::inertial_load(&model, &nodes, origin, case);
            assert_eq!((fast.nrows(), fast.ncols()), (3 * nodes.len(), 1));
            assert_close(&entries(fast.as_ref()), &entries(slow.as_ref()), 1e-12, &format!("{case:?}"));
        }
    }

    /// restrict is the transpose of expand (virtual work of mesh forces on expanded shapes).
    #[test]
    fn restrict_is_the_transpose_of_expand() {
        let Bar { nodes, flanges, model, origin, phi: phi_c } = bar(3);
        let phi = expand(&model, &nodes, &flanges, phi_c.as_ref());
        let held: Vec<usize> = flanges[0].slaves.iter().flat_map(|&n| 3 * n..3 * n + 3).collect();
        assert!(held.iter().all(|&i| (0..3).all(|j| phi[(i, j)] == 0.0)), "the mount's slaves are held");
        let mut f = Mat::<f64>::zeros(3 * nodes.len(), 2);
        f.as_mut().col_mut(0).copy_from(inertial_load(&model, &nodes, origin, LoadCase::Euler(1)).col(0));
        f.as_mut().col_mut(1).copy_from(inertial_load(&model, &nodes, origin, LoadCase::Centrifugal(0, 2)).col(0));
        let on_mesh = f.transpose() * &phi;
        let on_model = restrict(&model, &nodes, &flanges, f.as_ref()).transpose() * &phi_c;
        assert_close(&entries(on_model.as_ref()), &entries(on_mesh.as_ref()), 1e-12, "f^T expand(phi)");
    }
}
