//! How far the coupling has moved from the one the coupled transition was made for, bounded
//! from the few coefficients the coupling matrices are combined with (the body-frame spin w,
//! its rate z, the mount's acceleration a_B and the flange wrenches; see `fill_coupling`).
//!
//! A spin-up step keeps the exact transition of a reference coupling and treats the difference
//! dC as a load (the predictor-corrector of `cosim_step`), which is accurate while h |dC| is
//! small in the norm of the transition's own state [Omega q; q'], the energy norm: the spectral
//! norm of [dC_k Omega^-1, dC_d]. Each coefficient c_k multiplies a fixed matrix B_k, so
//!   |[dC_k Omega^-1, dC_d]| <= sqrt((sum |dc_k| |B_k,stiffness|)^2 + (sum |dc_k| |B_k,damping|)^2),
//! with the spectral norms of the B_k computed once per body: a test of a few dozen
//! multiply-adds per step in place of a norm of two n x n matrices. The matrices' largest row
//! sums, which the test used before, exceed the spectral norm 2.5 times on a spinning beam, so
//! the reference was renewed (one exponential) 2.5 times as often as the energy needs.

use super::Vec3;
use crate::reduced::ReducedBody;
use crate::scalar::Scalar;

/// Coefficients not tied to a flange: w (3), z (3), the products w_i w_j of [`SPIN_PAIRS`] (6),
/// a_B (3).
const MOUNT_TERMS: usize = 15;

/// The products w_i w_j with i <= j: w_i w_j and w_j w_i multiply the same coefficient.
const SPIN_PAIRS: [(usize, usize); 6] = [(0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2)];

/// The spectral norms are estimated by power iteration, which approaches from below; the
/// estimate is raised by this factor (the iteration stops once it changes by less than 1e-6 of
/// itself; on the unit test's 12-mode body it is then within 1e-6 of the exact norm).
const ESTIMATE_MARGIN: f64 = 1.05;

/// Number of coefficients of a body with `flanges` force flanges: the mount's and six per flange.
pub(crate) fn term_count(flanges: usize) -> usize {
    MOUNT_TERMS + 6 * flanges
}

/// The coefficients of the coupling for body-frame spin `w`, spin rate `z`, acceleration `a`
/// and body-frame flange wrenches, in the order [`TermNorms`] holds their matrices' norms.
pub(super) fn coefficients<T: Scalar>(
    w: Vec3<T>,
    z: Vec3<T>,
    a: Vec3<T>,
    wrenches: impl Iterator<Item = [T; 6]>,
    out: &mut [T],
) {
    out[..3].copy_from_slice(&w);
    out[3..6].copy_from_slice(&z);
    for (o, &(i, j)) in out[6..12].iter_mut().zip(&SPIN_PAIRS) {
        *o = w[i] * w[j];
    }
    out[12..15].copy_from_slice(&a);
    for (o, wrench) in out[MOUNT_TERMS..].chunks_exact_mut(6).zip(wrenches) {
        o.copy_from_slice(&wrench);
    }
}

/// Spectral norms of the matrices each coefficient multiplies: in C_k (columns scaled by
/// 1 / omega, as the transition's state scales q) and in C_d. Zero where a body has no such term.
#[derive(Debug, Clone, Default, PartialEq)]
pub(super) struct TermNorms {
    stiffness: Vec<f64>,
    damping: Vec<f64>,
}

impl TermNorms {
    /// The norms of `body`'s coupling matrices (power iteration, some n^2 work per matrix and
    /// iteration, done once per body; none for a body whose modes never couple).
    pub(super) fn of(body: &ReducedBody) -> Self {
        let n = body.n_modes();
        let nn = n * n;
        let count = term_count(body.flanges.len());
        let mut norms = Self { stiffness: vec![0.0; count], damping: vec![0.0; count] };
        if !body.modes_couple() || n == 0 {
            return norms;
        }
        let inv_omega: Vec<f64> = body.omega.iter().map(|w| 1.0 / w).collect();
        let mut matrix = vec![0.0; nn];
        let mut scratch = (vec![0.0; n], vec![0.0; n]);
        let st = body.stiffening.as_ref();
        let g = body.rotation.as_ref().map(|r| &r.g[..]);
        let o = body.rotation.as_ref().map(|r| &r.o_mat[..]);
        let centrifugal = st.and_then(|s| s.centrifugal.as_deref());
        let euler = st.and_then(|s| s.euler.as_deref());
        let translation = st.and_then(|s| s.translation.as_deref());
        let mut norm_of = |parts: &[Option<&[f64]>], scaled: bool| {
            matrix.fill(0.0);
            let mut any = false;
            for part in parts.iter().flatten() {
                any = true;
                for (m, p) in matrix.iter_mut().zip(*part) {
                    *m += p;
                }
            }
            if !any {
                return 0.0;
            }
            if scaled {
                for row in matrix.chunks_exact_mut(n) {
                    for (m, s) in row.iter_mut().zip(&inv_omega) {
                        *m *= s;
                    }
                }
            }
            ESTIMATE_MARGIN * spectral_norm(n, &matrix, &mut scratch)
        };
        for i in 0..3 {
            // C_d gains 2 w_i G_i; C_k gains z_i (G_i + E_i)
            norms.damping[i] = 2.0 * norm_of(&[block_of(g, i, nn)], false);
            norms.stiffness[3 + i] = norm_of(&[block_of(g, i, nn), block_of(euler, i, nn)], true);
            norms.stiffness[12 + i] = norm_of(&[block_of(translation, i, nn)], true);
        }
        for (k, &(i, j)) in SPIN_PAIRS.iter().enumerate() {
            let (ij, ji) = (3 * i + j, 3 * j + i);
            let parts = if i == j {
                vec![block_of(o, ij, nn), block_of(centrifugal, ij, nn)]
            } else {
                vec![
                    block_of(o, ij, nn),
                    block_of(o, ji, nn),
                    block_of(centrifugal, ij, nn),
                    block_of(centrifugal, ji, nn),
                ]
            };
            norms.stiffness[6 + k] = norm_of(&parts, true);
        }
        if let Some(st) = st {
            for (f, k) in st.flanges.iter().enumerate().filter(|(_, k)| !k.is_empty()) {
                for c in 0..6 {
                    norms.stiffness[MOUNT_TERMS + 6 * f + c] = norm_of(&[Some(&k[c * nn..(c + 1) * nn])], true);
                }
            }
        }
        norms
    }

    /// An upper bound of the spectral norm of [dC_k Omega^-1, dC_d] between the couplings of the
    /// coefficients `now` and `reference` (each [`term_count`] long).
    pub(super) fn bound(&self, now: &[f64], reference: &[f64]) -> f64 {
        let (mut k, mut d) = (0.0, 0.0);
        for (((c, r), ks), ds) in now.iter().zip(reference).zip(&self.stiffness).zip(&self.damping) {
            let change = (c - r).abs();
            k += change * ks;
            d += change * ds;
        }
        k.hypot(d)
    }
}

/// Block k (nn values) of stacked matrices, where there are any.
fn block_of(blocks: Option<&[f64]>, k: usize, nn: usize) -> Option<&[f64]> {
    blocks.map(|b| &b[k * nn..(k + 1) * nn])
}

/// Largest singular value of the n x n row-major `b`: power iteration on b^T b from a vector
/// with no symmetry of its own, until the estimate changes by less than 1e-6 of itself.
fn spectral_norm(n: usize, b: &[f64], (v, u): &mut (Vec<f64>, Vec<f64>)) -> f64 {
    for (j, x) in v.iter_mut().enumerate() {
        *x = 1.0 + ((j * 7919) % 31) as f64 / 31.0;
    }
    let mut estimate = 0.0;
    for _ in 0..1000 {
        let norm_v = v.iter().map(|x| x * x).sum::<f64>().sqrt();
        if norm_v == 0.0 || !norm_v.is_finite() {
            return estimate;
        }
        for x in v.iter_mut() {
            *x /= norm_v;
        }
        // u = b v, |u| the estimate; v = b^T u
        for (i, ui) in u.iter_mut().enumerate() {
            *ui = b[i * n..(i + 1) * n].iter().zip(v.iter()).map(|(x, y)| x * y).sum();
        }
        let next = u.iter().map(|x| x * x).sum::<f64>().sqrt();
        v.fill(0.0);
        for (i, ui) in u.iter().enumerate() {
            for (x, bij) in v.iter_mut().zip(&b[i * n..(i + 1) * n]) {
                *x += bij * ui;
            }
        }
        let settled = (next - estimate).abs() <= 1e-6 * next;
        estimate = next;
        if settled {
            break;
        }
    }
    estimate
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::reduced::{RotationTerms, Stiffening, rotating_two_mode_body};

    /// A spinning body of `n` modes with full, unstructured coupling matrices (every term the
    /// runtime combines, one force flange), from 7 to 5000 rad/s.
    fn coupled_body(n: usize) -> ReducedBody {
        let mut body = rotating_two_mode_body();
        let nn = n * n;
        let mut seed = 12345u64;
        let mut values = |count: usize, scale: f64| -> Vec<f64> {
            (0..count)
                .map(|_| {
                    seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                    scale * (((seed >> 11) as f64 / (1u64 << 53) as f64) - 0.5)
                })
                .collect()
        };
        body.omega = (0..n).map(|k| 7.0 * (1.0 + k as f64).powf(2.4)).collect();
        body.modal_damping = vec![0.0; n];
        body.c_t = values(3 * n, 1.0);
        body.c_r = values(3 * n, 1.0);
        let g = values(3 * nn, 1.0);
        body.rotation = Some(RotationTerms { g, o_mat: values(9 * nn, 3.0), o_vec: values(9 * n, 1.0) });
        let flanges = body.flanges.len();
        body.stiffening = Some(Stiffening {
            centrifugal: Some(values(9 * nn, 2.0)),
            euler: Some(values(3 * nn, 1.0)),
            translation: Some(values(3 * nn, 0.5)),
            flanges: (0..flanges).map(|_| values(6 * nn, 0.1)).collect(),
        });
        body
    }

    /// Exact spectral norm of [dC_k Omega^-1, dC_d] (n x 2n): the square root of the largest
    /// eigenvalue of its product with its transpose (n x n).
    fn exact_drift_norm(body: &ReducedBody, dc_k: &[f64], dc_d: &[f64]) -> f64 {
        let n = body.n_modes();
        let row = |i: usize| -> Vec<f64> {
            (0..n).map(|j| dc_k[i * n + j] / body.omega[j]).chain((0..n).map(|j| dc_d[i * n + j])).collect()
        };
        let rows: Vec<Vec<f64>> = (0..n).map(row).collect();
        let mut mmt = vec![0.0; n * n];
        for i in 0..n {
            for j in 0..n {
                mmt[i * n + j] = rows[i].iter().zip(&rows[j]).map(|(x, y)| x * y).sum();
            }
        }
        // the largest eigenvalue by cyclic Jacobi rotations (the textbook's method, nothing of
        // the power iteration)
        let eigenvalues = test_support::reference::jacobi_eigenvalues(mmt, n);
        eigenvalues.last().copied().unwrap_or(0.0).max(0.0).sqrt()
    }

    /// The coupling matrices of coefficient vector `coef`, by the runtime's own `fill_coupling`
    /// for the inputs the coefficients stand for.
    fn coupling_of(body: &ReducedBody, w: Vec3, z: Vec3, a: Vec3, f: Vec3) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
        use super::super::mounted::fill_coupling;
        use super::super::{Coupling, FlangeLoad, MountMotion};
        let n = body.n_modes();
        let nf = body.flanges.len();
        let mut c = Coupling {
            c_d: vec![0.0; n * n],
            c_k: vec![0.0; n * n],
            coef: vec![0.0; term_count(nf)],
            ..Coupling::default()
        };
        let mount = MountMotion { w, z, a, ..MountMotion::default() };
        let mut loads = vec![FlangeLoad::default(); nf];
        if let Some(l) = loads.first_mut() {
            l.f = f;
        }
        fill_coupling(body, &crate::kinematics::IDENTITY, &mount, &loads, [0.0; 3], &mut c);
        (c.c_d, c.c_k, c.coef)
    }

    /// The bound against the exact spectral norm of the matrices' difference (Jacobi on the
    /// difference times its transpose), for changes of one input at a time (where the bound
    /// is the norm of one term, so it must equal the exact norm within the power iteration's
    /// convergence and ESTIMATE_MARGIN) and of all at once (where it may exceed it, never fall
    /// below). Measured: one input, bound / exact 1.050000 (the margin, to six digits); the
    /// spin (four coefficients) 1.41, all inputs 2.11.
    #[test]
    fn the_bound_holds_and_is_tight_for_one_term() {
        let body = coupled_body(12);
        let norms = TermNorms::of(&body);
        let base = ([0.3, -1.2, 4.0], [0.5, 0.1, -2.0], [1.0, 0.0, -9.81], [3.0, -1.0, 2.0]);
        let (d0, k0, c0) = coupling_of(&body, base.0, base.1, base.2, base.3);
        assert_eq!(c0.len(), term_count(body.flanges.len()));
        let cases: [(&str, Vec3, Vec3, Vec3, Vec3); 5] = [
            ("z only", base.0, [0.5, 0.1, -1.7], base.2, base.3),
            ("a only", base.0, base.1, [1.0, 0.4, -9.81], base.3),
            ("flange force only", base.0, base.1, base.2, [3.0, -1.0, 2.5]),
            ("w_z (gyroscopic and centrifugal)", [0.3, -1.2, 4.1], base.1, base.2, base.3),
            ("everything", [0.4, -1.1, 4.2], [0.6, 0.0, -1.9], [1.1, 0.1, -9.7], [2.0, -1.5, 2.2]),
        ];
        for (what, w, z, a, f) in cases {
            let (d1, k1, c1) = coupling_of(&body, w, z, a, f);
            let dd: Vec<f64> = d1.iter().zip(&d0).map(|(x, y)| x - y).collect();
            let dk: Vec<f64> = k1.iter().zip(&k0).map(|(x, y)| x - y).collect();
            let exact = exact_drift_norm(&body, &dk, &dd);
            let bound = norms.bound(&c1, &c0);
            let ratio = bound / exact;
            eprintln!("{what}: exact {exact:.6e}, bound {bound:.6e}, ratio {ratio:.6}");
            // never below the exact norm (to the Jacobi reference's round-off, 1e-12)
            assert!(ratio >= 1.0 - 1e-12, "{what}: bound {bound} below the exact norm {exact}");
            if what.ends_with("only") {
                // one term: the estimate's margin and its convergence; the stopping rule (1e-6
                // relative change per iteration) allows some 3e-6 below the norm, ten times that
                assert!((ratio - ESTIMATE_MARGIN).abs() <= 3e-5 * ESTIMATE_MARGIN, "{what}: ratio {ratio}");
            } else {
                // several terms add by the triangle inequality: at most their count over
                assert!(ratio <= 10.0, "{what}: ratio {ratio}");
            }
        }
    }

    /// A body without coupling terms has zero norms, and equal coefficients no drift.
    #[test]
    fn no_terms_no_drift() {
        let mut body = coupled_body(4);
        let coef = vec![1.5; term_count(body.flanges.len())];
        assert_eq!(TermNorms::of(&body).bound(&coef, &coef), 0.0);
        body.rotation = None;
        body.stiffening = None;
        let norms = TermNorms::of(&body);
        let other: Vec<f64> = coef.iter().map(|c| c + 1.0).collect();
        assert_eq!(norms.bound(&other, &coef), 0.0);
    }
}
