//! The coupling matrices as fixed matrices combined with a few coefficients:
//!   C_d = sum_k c_k D_k,  C_k = sum_k c_k S_k,
//! with c the body-frame spin w (gyroscopic 2 G_i in C_d), its rate z (G_i + E_i in C_k), the six
//! products w_i w_j (centrifugal O and its prestress), a_B (translational prestress) and each
//! force flange's body-frame wrench (its prestress). The body's own blocks are combined once per
//! reduced body into one matrix per coefficient (O_ij + O_ji + K_ij + K_ji for w_i w_j), where
//! they are several; a single block is read where it lies.
//!
//! A spin-up step needs only how far the coupling moved from the one its transition was made for,
//! as a force: sum over the changed coefficients of dc_k (D_k q' + S_k q). A spin-up about one
//! body axis changes two coefficients (w_a and w_a^2): two matrices read, where forming C_d and
//! C_k at both ends of the step and subtracting the reference read some twenty.

use super::Vec3;
use super::coupling_bound::energy_norm;
use crate::reduced::ReducedBody;
use crate::scalar::Scalar;

/// Coefficients not tied to a flange: w (3), z (3), the products w_i w_j of [`SPIN_PAIRS`] (6),
/// a_B (3).
const MOUNT_TERMS: usize = 15;

/// The products w_i w_j with i <= j: w_i w_j and w_j w_i multiply the same coefficient.
const SPIN_PAIRS: [(usize, usize); 6] = [(0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2)];

/// A term whose contribution to a step, h |dc_k| |B_k| in the energy norm, is below this is left
/// out of the drift force: a hundredth of a double's round-off of the state it moves (rotating
/// base.R leaves 1e-17 in the body-frame components of a spin about a world axis, which would
/// otherwise read every spin term's matrix each step).
const NEGLIGIBLE_DRIFT: f64 = 1e-18;

/// Number of coefficients of a body with `flanges` force flanges: the mount's and six per flange.
pub(crate) fn term_count(flanges: usize) -> usize {
    MOUNT_TERMS + 6 * flanges
}

/// The coefficients of the coupling for body-frame spin `w`, spin rate `z`, acceleration `a`
/// and body-frame flange wrenches, in the order of the terms' `coef` indices.
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

/// The state a term's matrix multiplies: q' (a term of C_d) or q (of C_k).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Acts {
    Velocity,
    Position,
}

/// Where a term's n x n matrix lies: combined here from several of the body's blocks, or one of
/// them read in place.
#[derive(Debug, Clone, PartialEq)]
enum Matrix {
    Combined(Vec<f64>),
    Gyroscopic(usize),
    Spin(usize),
    Centrifugal(usize),
    Euler(usize),
    Translation(usize),
    Flange { flange: usize, component: usize },
}

#[derive(Debug, Clone, PartialEq)]
pub(super) struct Term {
    /// Index of the coefficient it is multiplied by.
    pub(super) coef: usize,
    pub(super) acts: Acts,
    /// The matrix's factor (2 for the gyroscopic 2 G_i).
    scale: f64,
    matrix: Matrix,
    /// Upper bound of the spectral norm of scale times the matrix in the energy norm of the
    /// transition's state (columns of S_k scaled by 1 / omega): see `coupling_bound`.
    pub(super) norm: f64,
}

/// A body's coupling terms, computed once per reduced body and shared by its copies.
#[derive(Debug, Clone, Default, PartialEq)]
pub(super) struct CouplingTerms {
    n: usize,
    terms: Vec<Term>,
}

impl CouplingTerms {
    /// The terms of `body`, in the order of their coefficients (damping before stiffness), with
    /// their norms (power iteration, some n^2 work per matrix and iteration); none for a body
    /// whose modes never couple.
    pub(super) fn of(body: &ReducedBody) -> Self {
        let n = body.n_modes();
        let nn = n * n;
        let mut terms = Vec::new();
        if !body.modes_couple() || n == 0 {
            return Self { n, terms };
        }
        let st = body.stiffening.as_ref();
        let g = body.rotation.as_ref().map(|r| &r.g[..]);
        let o = body.rotation.as_ref().map(|r| &r.o_mat[..]);
        let centrifugal = st.and_then(|s| s.centrifugal.as_deref());
        let euler = st.and_then(|s| s.euler.as_deref());
        let translation = st.and_then(|s| s.translation.as_deref());
        let block = |blocks: Option<&[f64]>, k: usize| blocks.map(|b| b[k * nn..(k + 1) * nn].to_vec());
        let combined = |parts: Vec<Option<Vec<f64>>>| {
            parts.into_iter().flatten().reduce(|mut sum, part| {
                for (s, p) in sum.iter_mut().zip(&part) {
                    *s += p;
                }
                sum
            })
        };
        let mut push = |coef: usize, acts: Acts, scale: f64, matrix: Matrix| {
            terms.push(Term { coef, acts, scale, matrix, norm: 0.0 });
        };
        if g.is_some() {
            for i in 0..3 {
                push(i, Acts::Velocity, 2.0, Matrix::Gyroscopic(i));
            }
        }
        for i in 0..3 {
            match (g.is_some(), euler.is_some()) {
                (true, true) => push(
                    3 + i,
                    Acts::Position,
                    1.0,
                    Matrix::Combined(combined(vec![block(g, i), block(euler, i)]).unwrap_or_default()),
                ),
                (true, false) => push(3 + i, Acts::Position, 1.0, Matrix::Gyroscopic(i)),
                (false, true) => push(3 + i, Acts::Position, 1.0, Matrix::Euler(i)),
                (false, false) => {}
            }
        }
        for (k, &(i, j)) in SPIN_PAIRS.iter().enumerate() {
            let (ij, ji) = (3 * i + j, 3 * j + i);
            let parts = if i == j {
                vec![block(o, ij), block(centrifugal, ij)]
            } else {
                vec![block(o, ij), block(o, ji), block(centrifugal, ij), block(centrifugal, ji)]
            };
            let count = parts.iter().flatten().count();
            if i == j && count == 1 {
                let single = if o.is_some() { Matrix::Spin(ij) } else { Matrix::Centrifugal(ij) };
                push(6 + k, Acts::Position, 1.0, single);
            } else if let Some(sum) = combined(parts) {
                push(6 + k, Acts::Position, 1.0, Matrix::Combined(sum));
            }
        }
        if translation.is_some() {
            for i in 0..3 {
                push(12 + i, Acts::Position, 1.0, Matrix::Translation(i));
            }
        }
        if let Some(st) = st {
            for (flange, _) in st.flanges.iter().enumerate().filter(|(_, k)| !k.is_empty()) {
                for component in 0..6 {
                    push(
                        MOUNT_TERMS + 6 * flange + component,
                        Acts::Position,
                        1.0,
                        Matrix::Flange { flange, component },
                    );
                }
            }
        }
        let mut this = Self { n, terms };
        let mut scratch = (vec![0.0; n], vec![0.0; n]);
        let norms: Vec<f64> = this
            .terms
            .iter()
            .map(|t| {
                let omega = (t.acts == Acts::Position).then_some(&body.omega[..]);
                t.scale.abs() * energy_norm(n, this.matrix(t, body), omega, &mut scratch)
            })
            .collect();
        for (t, norm) in this.terms.iter_mut().zip(norms) {
            t.norm = norm;
        }
        this
    }

    /// A term's n x n matrix (row-major), without its scale.
    pub(super) fn matrix<'a>(&'a self, term: &'a Term, body: &'a ReducedBody) -> &'a [f64] {
        let nn = self.n * self.n;
        let block = |blocks: &'a [f64], k: usize| &blocks[k * nn..(k + 1) * nn];
        let st = body.stiffening.as_ref();
        let missing: &'a [f64] = &[];
        match &term.matrix {
            Matrix::Combined(m) => m,
            Matrix::Gyroscopic(i) => body.rotation.as_ref().map_or(missing, |r| block(&r.g, *i)),
            Matrix::Spin(ij) => body.rotation.as_ref().map_or(missing, |r| block(&r.o_mat, *ij)),
            Matrix::Centrifugal(ij) => st.and_then(|s| s.centrifugal.as_deref()).map_or(missing, |c| block(c, *ij)),
            Matrix::Euler(i) => st.and_then(|s| s.euler.as_deref()).map_or(missing, |e| block(e, *i)),
            Matrix::Translation(i) => st.and_then(|s| s.translation.as_deref()).map_or(missing, |t| block(t, *i)),
            Matrix::Flange { flange, component } => st.map_or(missing, |s| block(&s.flanges[*flange], *component)),
        }
    }

    /// Whether any term's coefficient is nonzero: the modes couple under these inputs.
    pub(super) fn active<T: Scalar>(&self, coef: &[T]) -> bool {
        self.terms.iter().any(|t| !coef[t.coef].is_zero())
    }

    /// Whether the coefficients `a` and `b` make the same coupling: equal wherever a term reads
    /// them (a flange wrench without prestress terms may differ).
    pub(super) fn same_coupling(&self, a: &[f64], b: &[f64]) -> bool {
        self.terms.iter().all(|t| a[t.coef] == b[t.coef])
    }

    /// out[i] = (C_d q' + C_k q)_i for the rows i < out.len(), from the terms of the nonzero
    /// coefficients (the matrices C_d, C_k are not formed).
    pub(super) fn force<T: Scalar>(&self, body: &ReducedBody, coef: &[T], q: &[T], qd: &[T], out: &mut [T]) {
        out.fill(T::zero());
        for t in &self.terms {
            let c = coef[t.coef];
            if c.is_zero() {
                continue;
            }
            self.add_term(t, body, c, q, qd, out);
        }
    }

    /// out += c times the term's scaled matrix applied to q' or q (its rows up to out.len()).
    fn add_term<T: Scalar>(&self, t: &Term, body: &ReducedBody, c: T, q: &[T], qd: &[T], out: &mut [T]) {
        let x = match t.acts {
            Acts::Velocity => qd,
            Acts::Position => q,
        };
        T::add_scaled_mat_vec(self.matrix(t, body), x, c * t.scale, out);
    }

    /// C_d and C_k (row-major n x n) for the coefficients `coef`.
    pub(super) fn fill<T: Scalar>(&self, body: &ReducedBody, coef: &[T], c_d: &mut [T], c_k: &mut [T]) {
        self.fill_rows(body, coef, 0, c_d, c_k);
    }

    /// Rows `first..` of C_d and C_k (row-major, n values a row) for the coefficients `coef`.
    pub(super) fn fill_rows<T: Scalar>(
        &self,
        body: &ReducedBody,
        coef: &[T],
        first: usize,
        c_d: &mut [T],
        c_k: &mut [T],
    ) {
        c_d.fill(T::zero());
        c_k.fill(T::zero());
        for t in &self.terms {
            let c = coef[t.coef];
            if c.is_zero() {
                continue;
            }
            let scale = c * t.scale;
            let target = match t.acts {
                Acts::Velocity => &mut *c_d,
                Acts::Position => &mut *c_k,
            };
            for (x, m) in target.iter_mut().zip(&self.matrix(t, body)[first * self.n..]) {
                *x += scale * *m;
            }
        }
    }

    /// out = (C_d(now) - C_d(reference)) q' + (C_k(now) - C_k(reference)) q: the coupling's force
    /// beyond the transition's, from the terms whose coefficient changed by more than a step's
    /// round-off ([`NEGLIGIBLE_DRIFT`]).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn drift_force(
        &self,
        body: &ReducedBody,
        now: &[f64],
        reference: &[f64],
        h: f64,
        q: &[f64],
        qd: &[f64],
        out: &mut [f64],
    ) {
        out.fill(0.0);
        for t in &self.terms {
            let change = now[t.coef] - reference[t.coef];
            // a NaN change is not skipped: the step reports the non-finite state it makes
            if h * change.abs() * t.norm <= NEGLIGIBLE_DRIFT {
                continue;
            }
            self.add_term(t, body, change, q, qd, out);
        }
    }

    /// An upper bound of the spectral norm of [dC_k Omega^-1, dC_d] between the couplings of the
    /// coefficients `now` and `reference` (each [`term_count`] long): by the triangle inequality
    /// over the terms, sqrt((sum |dc_k| |S_k Omega^-1|)^2 + (sum |dc_k| |D_k|)^2).
    pub(super) fn drift_bound(&self, now: &[f64], reference: &[f64]) -> f64 {
        let (mut k, mut d) = (0.0, 0.0);
        for t in &self.terms {
            let change = (now[t.coef] - reference[t.coef]).abs() * t.norm;
            match t.acts {
                Acts::Velocity => d += change,
                Acts::Position => k += change,
            }
        }
        f64::hypot(k, d)
    }
}

#[cfg(test)]
mod tests {
    use super::bound_tests::{coupled_body, coupling_of};
    use super::*;

    /// The tests' body (nine modes, every term) with its terms, and a state q, q' of it.
    fn nine_modes_in_motion() -> (ReducedBody, CouplingTerms, Vec<f64>, Vec<f64>) {
        let body = coupled_body(9);
        let terms = CouplingTerms::of(&body);
        let n = body.n_modes();
        let q = (0..n).map(|i| 0.1 * (i as f64 + 1.0).sin()).collect();
        let qd = (0..n).map(|i| (0.7 * i as f64).cos()).collect();
        (body, terms, q, qd)
    }

    /// Largest |x - y| over two equally long sequences, and the largest |y|.
    fn worst(x: &[f64], y: &[f64]) -> (f64, f64) {
        assert_eq!(x.len(), y.len());
        let diff = x.iter().zip(y).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
        (diff, y.iter().map(|v| v.abs()).fold(0.0, f64::max))
    }

    /// The terms combine the body's blocks into the matrices the equations of motion sum, term
    /// by term: C_d, C_k from `fill` against the blocks summed one by one (the reference in
    /// `coupling_bound`'s tests) for inputs that set every coefficient. Measured: 1.7e-16 of the
    /// largest entry (round-off of a different order of the same sums); the limit ten times
    /// the few ulps that order can move.
    #[test]
    fn the_terms_make_the_coupling_the_equations_sum() {
        let body = coupled_body(9);
        let terms = CouplingTerms::of(&body);
        let n = body.n_modes();
        let (d, k, coef) = coupling_of(&body, [0.7, -1.3, 4.0], [0.5, 0.2, -2.0], [1.0, -0.4, -9.81], [3.0, -1.0, 2.0]);
        let (mut c_d, mut c_k) = (vec![1.0; n * n], vec![1.0; n * n]);
        terms.fill(&body, &coef, &mut c_d, &mut c_k);
        for (name, found, expected) in [("C_d", &c_d, &d), ("C_k", &c_k, &k)] {
            let (diff, scale) = worst(found, expected);
            eprintln!("{name}: {:.2e} of the largest entry {scale:.3e}", diff / scale);
            assert!(scale > 0.0, "{name} is zero: the inputs set no term");
            assert!(diff <= 2e-15 * scale, "{name}: off by {diff:e} of {scale:e}");
        }
        // the rows from 4 on alone, as Model Exchange's algebraic modes read them
        let (mut rows_d, mut rows_k) = (vec![1.0; (n - 4) * n], vec![1.0; (n - 4) * n]);
        terms.fill_rows(&body, &coef, 4, &mut rows_d, &mut rows_k);
        assert_eq!((&rows_d[..], &rows_k[..]), (&c_d[4 * n..], &c_k[4 * n..]), "rows differ from the whole");
        assert!(terms.active(&coef));
        assert!(!terms.active(&vec![0.0; coef.len()]));
    }

    /// The drift force is (C(now) - C(reference)) applied to (q, q'), the matrices summed from
    /// the blocks; a coefficient that moved by less than a step's round-off is left out, and
    /// one that moved by more is not. Measured: 2.5e-15 of the force's largest entry (the
    /// reference subtracts two couplings of order 1e2 for a difference of order 1e0); the limit
    /// ten times that.
    #[test]
    fn the_drift_force_is_the_difference_of_the_couplings_applied() {
        let (body, terms, q, qd) = nine_modes_in_motion();
        let n = body.n_modes();
        let (d0, k0, c0) = coupling_of(&body, [0.7, -1.3, 4.0], [0.5, 0.2, -2.0], [1.0, -0.4, -9.81], [3.0, -1.0, 2.0]);
        let (d1, k1, c1) = coupling_of(&body, [0.7, -1.3, 4.1], [0.5, 0.2, -1.9], [1.0, -0.4, -9.7], [3.0, -1.1, 2.0]);
        let expected: Vec<f64> = (0..n)
            .map(|i| {
                (0..n).map(|j| (d1[i * n + j] - d0[i * n + j]) * qd[j] + (k1[i * n + j] - k0[i * n + j]) * q[j]).sum()
            })
            .collect();
        let h = 1e-3;
        let mut found = vec![f64::NAN; n];
        terms.drift_force(&body, &c1, &c0, h, &q, &qd, &mut found);
        let (diff, scale) = worst(&found, &expected);
        eprintln!("drift force: {:.2e} of its largest entry {scale:.3e}", diff / scale);
        assert!(scale > 0.0);
        assert!(diff <= 2.5e-14 * scale, "off by {diff:e} of {scale:e}");

        // w_z moved by a step's round-off only: nothing to add; by 1e-9: its two terms
        let mut tiny = c0.clone();
        tiny[2] += 1e-20;
        terms.drift_force(&body, &tiny, &c0, h, &q, &qd, &mut found);
        assert_eq!(found, vec![0.0; n], "a change below round-off read its terms");
        tiny[2] = c0[2] + 1e-9;
        terms.drift_force(&body, &tiny, &c0, h, &q, &qd, &mut found);
        let gyroscopic = terms.matrix(&terms.terms[2], &body);
        assert_eq!(terms.terms[2].coef, 2);
        let change = tiny[2] - c0[2];
        for (i, f) in found.iter().enumerate() {
            let g: f64 = (0..n).map(|j| 2.0 * change * gyroscopic[i * n + j] * qd[j]).sum();
            assert!((f - g).abs() <= 1e-14 * g.abs().max(1e-9), "mode {i}: {f:e} against 2 dw G q' {g:e}");
        }
    }

    /// An evaluation's coupling force from the terms is C_d q' + C_k q with the matrices summed
    /// from the blocks, for every row or the leading ones; coefficients that differ only where
    /// no term reads them make the same coupling. Measured: 9.7e-17 of the force's largest
    /// entry (sums in another order); the limit 5e-15, ten times the few ulps that order can
    /// move in sums of nine terms.
    #[test]
    fn the_force_is_the_coupling_applied() {
        let (body, terms, q, qd) = nine_modes_in_motion();
        let n = body.n_modes();
        let (d, k, coef) = coupling_of(&body, [0.7, -1.3, 4.0], [0.5, 0.2, -2.0], [1.0, -0.4, -9.81], [3.0, -1.0, 2.0]);
        let expected: Vec<f64> =
            (0..n).map(|i| (0..n).map(|j| d[i * n + j] * qd[j] + k[i * n + j] * q[j]).sum()).collect();
        for rows in [n, 4] {
            let mut found = vec![f64::NAN; rows];
            terms.force(&body, &coef, &q, &qd, &mut found);
            let (diff, scale) = worst(&found, &expected[..rows]);
            eprintln!("force of {rows} rows: {:.2e} of its largest entry {scale:.3e}", diff / scale);
            assert!(scale > 0.0);
            assert!(diff <= 5e-15 * scale, "{rows} rows: off by {diff:e} of {scale:e}");
        }
        let mut other = coef.clone();
        assert!(terms.same_coupling(&other, &coef));
        other[2] += 1e-12;
        assert!(!terms.same_coupling(&other, &coef), "a changed spin is the same coupling");
        // a body whose flange has no prestress terms: its wrench reads no matrix
        let mut plain = body.clone();
        if let Some(st) = plain.stiffening.as_mut() {
            st.flanges.iter_mut().for_each(Vec::clear);
        }
        let plain_terms = CouplingTerms::of(&plain);
        let mut wrench_only = coef.clone();
        wrench_only[MOUNT_TERMS] += 5.0;
        assert!(plain_terms.same_coupling(&wrench_only, &coef));
        assert!(!terms.same_coupling(&wrench_only, &coef));
    }
}

#[cfg(test)]
pub(super) mod bound_tests {
    use super::super::Vec3;
    use super::super::coupling_bound::ESTIMATE_MARGIN;
    use super::*;
    use crate::reduced::{ReducedBody, RotationTerms, Stiffening, rotating_two_mode_body};

    /// A spinning body of `n` modes with full, unstructured coupling matrices (every term the
    /// runtime combines, one force flange), from 7 to 5000 rad/s.
    pub(in crate::body) fn coupled_body(n: usize) -> ReducedBody {
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

    /// The coupling matrices (C_d, C_k) and coefficients of body-frame spin `w`, its rate `z`,
    /// acceleration `a` and the first flange's force `f`, the matrices summed from the body's
    /// blocks as the equations of motion write them (not by `coupling_terms`' combination):
    /// C_d = 2 sum w_i G_i, C_k = sum z_i (G_i + E_i) + sum w_i w_j (O_ij + K_ij) + sum a_i T_i
    /// + sum f_i F_i.
    pub(in crate::body) fn coupling_of(
        body: &ReducedBody,
        w: Vec3,
        z: Vec3,
        a: Vec3,
        f: Vec3,
    ) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
        let n = body.n_modes();
        let nn = n * n;
        let (mut c_d, mut c_k) = (vec![0.0; nn], vec![0.0; nn]);
        let add = |target: &mut Vec<f64>, scale: f64, blocks: Option<&[f64]>, k: usize| {
            if let Some(b) = blocks {
                for (t, v) in target.iter_mut().zip(&b[k * nn..(k + 1) * nn]) {
                    *t += scale * v;
                }
            }
        };
        let rot = body.rotation.as_ref();
        let st = body.stiffening.as_ref();
        let g = rot.map(|r| &r.g[..]);
        for i in 0..3 {
            add(&mut c_d, 2.0 * w[i], g, i);
            add(&mut c_k, z[i], g, i);
            add(&mut c_k, z[i], st.and_then(|s| s.euler.as_deref()), i);
            add(&mut c_k, a[i], st.and_then(|s| s.translation.as_deref()), i);
            add(&mut c_k, f[i], st.and_then(|s| s.flanges.first().map(|k| &k[..])), i);
            for j in 0..3 {
                add(&mut c_k, w[i] * w[j], rot.map(|r| &r.o_mat[..]), 3 * i + j);
                add(&mut c_k, w[i] * w[j], st.and_then(|s| s.centrifugal.as_deref()), 3 * i + j);
            }
        }
        let nf = body.flanges.len();
        let mut coef = vec![0.0; term_count(nf)];
        let wrenches = (0..nf).map(|k| if k == 0 { [f[0], f[1], f[2], 0.0, 0.0, 0.0] } else { [0.0; 6] });
        coefficients(w, z, a, wrenches, &mut coef);
        (c_d, c_k, coef)
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
        let terms = CouplingTerms::of(&body);
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
            let bound = terms.drift_bound(&c1, &c0);
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
        assert_eq!(CouplingTerms::of(&body).drift_bound(&coef, &coef), 0.0);
        body.rotation = None;
        body.stiffening = None;
        let terms = CouplingTerms::of(&body);
        let other: Vec<f64> = coef.iter().map(|c| c + 1.0).collect();
        assert_eq!(terms.drift_bound(&other, &coef), 0.0);
    }
}
