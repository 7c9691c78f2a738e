//! The distributing coupling (RBE3; CalculiX's `*DISTRIBUTING COUPLING`): a flange's reference
//! point moves as the weighted average of its nodes and its force and torque are spread over
//! them, with no stiffness added. The average is the weighted least-squares rigid motion of the
//! nodes: translation the weighted mean of their displacements, rotation
//! theta = J^-1 sum_i w_i d_i x u_i (d_i the node's offset from the weighted centroid, J the
//! weights' polar tensor about it), carried from the centroid to the reference point. Rigid
//! motions are reproduced exactly, so the frame terms of a floating body stay exact.
//!
//! In the constrained model the reference point's six DoFs stay (as a rigid flange's master),
//! the nodes keep their own DoFs, and six of them become dependent: u_dep = D^-1 (u_ref -
//! C_ind u_ind), D the constraint's columns of those six (chosen by complete pivoting). The
//! congruence with that map is the constrained system exactly: its loads at the reference point
//! are C^T F on the nodes, and the reference point's motion is C u.

use crate::input::element::ElementKind;
use crate::input::mesh::Mesh;
use nalgebra::{Matrix3, Matrix6, Vector3};

/// The constraint u_ref = sum_i C_i u_i: one 6 x 3 block per node (rows u, theta).
pub struct Constraint {
    pub blocks: Vec<[[f64; 3]; 6]>,
}

/// Why a node set cannot define a distributing coupling.
#[derive(Debug, Clone, PartialEq)]
pub enum Refusal {
    /// fewer than three nodes with weight, or all on one line: no rotation is defined
    Collinear,
    /// the weights sum to zero or are not finite
    NoWeight,
}

/// The constraint of nodes at `points` with `weights` (any positive scale) about `reference`.
pub fn constraint(points: &[[f64; 3]], weights: &[f64], reference: [f64; 3]) -> Result<Constraint, Refusal> {
    let total: f64 = weights.iter().sum();
    if !(total > 0.0 && total.is_finite()) || weights.len() != points.len() {
        return Err(Refusal::NoWeight);
    }
    let w: Vec<f64> = weights.iter().map(|w| w / total).collect();
    let centroid = points.iter().zip(&w).fold(Vector3::zeros(), |c, (p, w)| c + Vector3::from(*p) * *w);
    // J = sum w (|d|^2 I - d d^T): the weights' polar tensor about the centroid
    let mut j = Matrix3::zeros();
    for (p, &wi) in points.iter().zip(&w) {
        let d = Vector3::from(*p) - centroid;
        j += (Matrix3::identity() * d.norm_squared() - d * d.transpose()) * wi;
    }
    // a line of nodes leaves the rotation about it undefined: J's smallest eigenvalue is then
    // zero (relative to the largest)
    let eig = j.symmetric_eigen().eigenvalues;
    let (lo, hi) = eig.iter().fold((f64::INFINITY, 0.0f64), |(l, h), &e| (l.min(e), h.max(e)));
    if !(lo > 1e-10 * hi) {
        return Err(Refusal::Collinear);
    }
    let j_inv = j.try_inverse().ok_or(Refusal::Collinear)?;
    // the fitted motion at the reference point: u_ref = u_mean + theta x (reference - centroid)
    // = u_mean + a x theta with a = centroid - reference (cross_matrix: a x .)
    let a = centroid - Vector3::from(reference);
    let s_a = a.cross_matrix();
    let blocks = points
        .iter()
        .zip(&w)
        .map(|(p, &wi)| {
            let d = Vector3::from(*p) - centroid;
            // theta contribution: J^-1 w_i (d x u_i)
            let rot = j_inv * d.cross_matrix() * wi;
            let trans = Matrix3::identity() * wi + s_a * rot;
            let mut block = [[0.0; 3]; 6];
            for r in 0..3 {
                for c in 0..3 {
                    block[r][c] = trans[(r, c)];
                    block[3 + r][c] = rot[(r, c)];
                }
            }
            block
        })
        .collect();
    Ok(Constraint { blocks })
}

/// The six DoFs the constraint eliminates (node index into the flange's nodes, direction) and
/// each one's image: u_dep[k] = sum_m master[k][m] u_ref[m] + sum over the other nodes' DoFs of
/// `others[k]` (node, direction, coefficient).
pub struct Elimination {
    pub dependent: [(usize, usize); 6],
    pub master: [[f64; 6]; 6],
    pub others: Vec<Vec<(usize, usize, f64)>>,
}

/// Choose the dependent DoFs by complete pivoting on the 6 x 3n constraint (the best
/// conditioned 6 x 6 block D greedily) and express them through the rest.
pub fn eliminate(c: &Constraint) -> Result<Elimination, Refusal> {
    let n = 3 * c.blocks.len();
    let entry = |r: usize, col: usize| c.blocks[col / 3][r][col % 3];
    // Gaussian elimination with complete pivoting on a working copy (6 x 3n)
    let mut work: Vec<Vec<f64>> = (0..6).map(|r| (0..n).map(|col| entry(r, col)).collect()).collect();
    let scale = work.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
    let mut rows_left: Vec<usize> = (0..6).collect();
    let mut chosen = Vec::with_capacity(6);
    for _ in 0..6 {
        let (mut best, mut at) = (0.0f64, (0, 0));
        for &r in &rows_left {
            for (col, v) in work[r].iter().enumerate() {
                if v.abs() > best {
                    best = v.abs();
                    at = (r, col);
                }
            }
        }
        if !(best > 1e-12 * scale) {
            return Err(Refusal::Collinear);
        }
        let (pr, pc) = at;
        rows_left.retain(|&r| r != pr);
        let pivot_row = work[pr].clone();
        for &r in &rows_left {
            let f = work[r][pc] / pivot_row[pc];
            if f != 0.0 {
                for (x, p) in work[r].iter_mut().zip(&pivot_row) {
                    *x -= f * p;
                }
            }
        }
        chosen.push(pc);
    }
    chosen.sort_unstable();
    // D (6 x 6) and its inverse, from the original constraint
    let d = Matrix6::from_fn(|r, k| entry(r, chosen[k]));
    let d_inv = d.try_inverse().ok_or(Refusal::Collinear)?;
    let mut master = [[0.0; 6]; 6];
    let mut others = vec![Vec::new(); 6];
    for k in 0..6 {
        for m in 0..6 {
            master[k][m] = d_inv[(k, m)];
        }
        for col in (0..n).filter(|col| !chosen.contains(col)) {
            let v: f64 = -(0..6).map(|r| d_inv[(k, r)] * entry(r, col)).sum::<f64>();
            if v != 0.0 {
                others[k].push((col / 3, col % 3, v));
            }
        }
    }
    let dependent = std::array::from_fn(|k| (chosen[k] / 3, chosen[k] % 3));
    Ok(Elimination { dependent, master, others })
}

/// Each node's tributary area on the surface the nodes cover: the boundary faces of the mesh
/// whose nodes (corners and midsides) all belong to `nodes`, split into flat triangles through
/// their midside nodes, each triangle's area shared equally by its three corners. Nodes on no
/// such face get zero. `nodes` ascending.
pub fn tributary_areas(mesh: &Mesh, nodes: &[usize]) -> Vec<f64> {
    let index = |g: usize| nodes.binary_search(&g).ok();
    let mut area = vec![0.0; nodes.len()];
    for (e, f) in mesh.boundary_faces() {
        let (conn, kind) = (mesh.element(e), mesh.kind(e));
        let face = kind.corner_faces()[f];
        let corners: Vec<usize> = face.iter().map(|&i| conn[i]).collect();
        // the midside between consecutive corners (quadratic elements)
        let mids: Vec<usize> = (0..face.len())
            .filter_map(|i| midside(kind, face[i], face[(i + 1) % face.len()]).map(|m| conn[m]))
            .collect();
        if corners.iter().chain(&mids).any(|&g| index(g).is_none()) {
            continue;
        }
        if mids.is_empty() && corners.len() == 4 {
            // a bilinear face: its consistent nodal areas (integral of N_i dA, 2 x 2 Gauss,
            // exact on a flat parallelogram), as CalculiX weighs a distributing surface
            for (g, a) in corners.iter().zip(bilinear_areas(corners.iter().map(|&g| mesh.nodes[g]))) {
                if let Some(i) = index(*g) {
                    area[i] += a;
                }
            }
            continue;
        }
        for tri in flat_triangles(&corners, &mids) {
            let p = tri.map(|g| Vector3::from(mesh.nodes[g]));
            let a = 0.5 * (p[1] - p[0]).cross(&(p[2] - p[0])).norm();
            for g in tri {
                if let Some(i) = index(g) {
                    area[i] += a / 3.0;
                }
            }
        }
    }
    area
}

/// The integral of each corner's bilinear shape function over a 4-node face.
fn bilinear_areas(corners: impl Iterator<Item = [f64; 3]>) -> [f64; 4] {
    let x: Vec<Vector3<f64>> = corners.map(Vector3::from).collect();
    let (xi, eta) = ([-1.0, 1.0, 1.0, -1.0], [-1.0, -1.0, 1.0, 1.0]);
    let g = 1.0 / 3f64.sqrt();
    let mut out = [0.0; 4];
    for (a, b) in [(-g, -g), (g, -g), (g, g), (-g, g)] {
        let n = |i: usize| 0.25 * (1.0 + xi[i] * a) * (1.0 + eta[i] * b);
        let dx_da: Vector3<f64> = (0..4).map(|i| x[i] * (0.25 * xi[i] * (1.0 + eta[i] * b))).sum();
        let dx_db: Vector3<f64> = (0..4).map(|i| x[i] * (0.25 * eta[i] * (1.0 + xi[i] * a))).sum();
        let da = dx_da.cross(&dx_db).norm();
        for (i, o) in out.iter_mut().enumerate() {
            *o += n(i) * da;
        }
    }
    out
}

/// The midside node (connectivity position) on the edge between corners `a` and `b`.
fn midside(kind: ElementKind, a: usize, b: usize) -> Option<usize> {
    let corners = kind.corner_nodes();
    kind.midside_edges().iter().position(|&(x, y)| (x, y) == (a, b) || (x, y) == (b, a)).map(|k| corners + k)
}

/// A face as flat triangles: a linear face fanned from its first corner; a quadratic one cut
/// at its midsides (a corner triangle at each corner, the midsides' polygon fanned).
fn flat_triangles(corners: &[usize], mids: &[usize]) -> Vec<[usize; 3]> {
    let k = corners.len();
    if mids.len() != k {
        return (1..k - 1).map(|i| [corners[0], corners[i], corners[i + 1]]).collect();
    }
    // mids[i] lies between corners[i] and corners[i + 1]
    let mut out: Vec<[usize; 3]> = (0..k).map(|i| [corners[i], mids[i], mids[(i + k - 1) % k]]).collect();
    out.extend((1..k - 1).map(|i| [mids[0], mids[i], mids[i + 1]]));
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn apply(c: &Constraint, u: &[[f64; 3]]) -> [f64; 6] {
        let mut out = [0.0; 6];
        for (b, ui) in c.blocks.iter().zip(u) {
            for r in 0..6 {
                out[r] += (0..3).map(|k| b[r][k] * ui[k]).sum::<f64>();
            }
        }
        out
    }

    fn points() -> Vec<[f64; 3]> {
        vec![[1.0, 0.0, 0.0], [1.0, 2.0, 0.1], [1.0, 0.3, 1.5], [1.2, 1.7, 1.9], [0.9, 1.0, 0.8]]
    }

    #[test]
    fn rigid_motions_are_reproduced_at_any_reference_point() {
        let pts = points();
        let weights = [1.0, 2.0, 0.5, 1.5, 3.0];
        for reference in [[1.0, 1.0, 1.0], [3.0, -2.0, 0.5]] {
            let c = constraint(&pts, &weights, reference).unwrap();
            let (t, th) = ([0.3, -0.2, 0.7], [0.05, -0.11, 0.02]);
            let u: Vec<[f64; 3]> = pts
                .iter()
                .map(|p| {
                    let d = Vector3::from(*p) - Vector3::from(reference);
                    let v = Vector3::from(t) + Vector3::from(th).cross(&d);
                    [v[0], v[1], v[2]]
                })
                .collect();
            let got = apply(&c, &u);
            let want = [t[0], t[1], t[2], th[0], th[1], th[2]];
            assert_eq!(got.len(), want.len());
            for (g, w) in got.iter().zip(want) {
                assert!((g - w).abs() < 1e-14, "{got:?} vs {want:?}");
            }
        }
    }

    #[test]
    fn translation_is_the_weighted_mean_at_the_centroid() {
        let pts = points();
        let weights = [1.0, 2.0, 0.5, 1.5, 3.0];
        let total: f64 = weights.iter().sum();
        let centroid: [f64; 3] =
            std::array::from_fn(|a| pts.iter().zip(&weights).map(|(p, w)| p[a] * w).sum::<f64>() / total);
        let c = constraint(&pts, &weights, centroid).unwrap();
        let u: Vec<[f64; 3]> = (0..pts.len()).map(|i| [i as f64, (i * i) as f64, 1.0 - i as f64]).collect();
        let got = apply(&c, &u);
        for a in 0..3 {
            let mean = u.iter().zip(&weights).map(|(ui, w)| ui[a] * w).sum::<f64>() / total;
            assert!((got[a] - mean).abs() < 1e-14);
        }
    }

    #[test]
    fn collinear_nodes_and_no_weight_are_refused() {
        let line = [[0.0, 0.0, 0.0], [1.0, 1.0, 1.0], [2.0, 2.0, 2.0]];
        assert_eq!(constraint(&line, &[1.0; 3], [0.0; 3]).err(), Some(Refusal::Collinear));
        assert_eq!(constraint(&points(), &[0.0; 5], [0.0; 3]).err(), Some(Refusal::NoWeight));
    }

    #[test]
    fn the_elimination_satisfies_the_constraint() {
        let pts = points();
        let c = constraint(&pts, &[1.0; 5], [1.0, 1.0, 1.0]).unwrap();
        let e = eliminate(&c).unwrap();
        // any independent DoFs and reference motion: the dependent ones make C u = u_ref
        let u_ref = [0.1, -0.4, 0.3, 0.02, 0.07, -0.05];
        let mut u: Vec<[f64; 3]> = (0..pts.len()).map(|i| [0.1 * i as f64, -0.2, 0.05 * (i * i) as f64]).collect();
        for (k, &(node, dir)) in e.dependent.iter().enumerate() {
            let v = (0..6).map(|m| e.master[k][m] * u_ref[m]).sum::<f64>()
                + e.others[k].iter().map(|&(n, d, c)| c * u[n][d]).sum::<f64>();
            // others never name a dependent DoF, so the order of filling is free
            assert!(e.others[k].iter().all(|&(n, d, _)| !e.dependent.contains(&(n, d))));
            u[node][dir] = v;
        }
        let got = apply(&c, &u);
        assert_eq!(got.len(), u_ref.len());
        for (g, w) in got.iter().zip(u_ref) {
            assert!((g - w).abs() < 1e-13, "{got:?}");
        }
    }

    #[test]
    fn a_rectangle_gives_each_corner_a_quarter() {
        let a = bilinear_areas([[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [2.0, 3.0, 0.0], [0.0, 3.0, 0.0]].into_iter());
        assert_eq!(a.len(), 4);
        for v in a {
            assert!((v - 1.5).abs() < 1e-14, "{a:?}");
        }
    }

    #[test]
    fn quadratic_face_areas_sum_to_the_face() {
        // a 6-node triangle's split: 4 flat triangles covering it
        let tris = flat_triangles(&[0, 1, 2], &[3, 4, 5]);
        assert_eq!(tris.len(), 4);
        // an 8-node quadrilateral: 4 corner triangles + the midsides' quad as 2
        assert_eq!(flat_triangles(&[0, 1, 2, 3], &[4, 5, 6, 7]).len(), 6);
        assert_eq!(flat_triangles(&[0, 1, 2, 3], &[]).len(), 2);
    }
}
