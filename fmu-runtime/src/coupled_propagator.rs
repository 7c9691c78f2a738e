//! Exact propagation of the coupled modal system over one step:
//!   q'' + (D + C_d) q' + (Lambda + C_k) q = p0 + t p1,
//! with D, Lambda diagonal and the coupling C_d (gyroscopic), C_k (centrifugal, angular
//! acceleration, geometric stiffening) held over the step. The system is linear and
//! time-invariant within the step, so its transition is a matrix exponential: no scheme can be
//! more stable or accurate. Gyroscopic coupling is energy-neutral, and the exponential keeps it
//! so at any step size (an explicit treatment of the coupling adds energy each step and blows up
//! an undamped spinning body).
//!
//! In the scaled state y = [Omega q; q'] (Omega = diag(omega)) the system matrix is
//!   A = [[0, Omega], [-(Omega + C_k Omega^-1), -(D + C_d)]],
//! whose norm is that of the frequencies, not of their squares: scaling and squaring then needs
//! half the squarings, and the round-off it accumulates stays at 1e-12 even for one step over
//! many periods of the stiffest mode. The load enters through the phi functions, the top rows of
//! the exponential of the block matrix [[A h, E h, 0], [0, 0, I h], [0, 0, 0]] (E = [0; I]):
//! exp(A h), h phi1(A h) E and h^2 phi2(A h) E (Van Loan; Al-Mohy and Higham). Its structure is
//! used throughout: the Taylor series of phi2 on the scaled A (Paterson and Stockmeyer), then
//! squaring of the blocks, all in 2n x 2n products (a quarter of the full block matrix's work),
//! in the blocked kernel of [`crate::matmul`].
//!
//! The propagator holds only its state, the transition and the coupling it was made for
//! (allocated at construction). The scratch of `prepare` (the exponential) and `advance` is a
//! [`Workspace`] of [`CoupledPropagator::workspace_req`] values that the caller allocated once and
//! lends to each call: neither allocates, and a workspace too small is refused, not a panic.

use crate::matmul::mat_mul_strided;
use crate::matvec::{Store, mat_vec};
use crate::workspace::{Workspace, WorkspaceReq, WorkspaceTooSmall};

/// More squarings than any finite |A h| needs (log2(f64::MAX) = 1024).
const MAX_SQUARINGS: f64 = 1100.0;

/// Result of preparing a step: whether the cached transition was recomputed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Prepared {
    Reused,
    Computed,
}

#[derive(Debug, Clone, Default)]
pub struct CoupledPropagator {
    n: usize,
    /// (h, alpha, beta) and the coupling of the cached transition.
    key: Option<(f64, f64, f64)>,
    key_c_d: Vec<f64>,
    key_c_k: Vec<f64>,
    /// Top 2n rows of exp(X): [P | G1] (row-major 2n x 3n) and G2 (2n x n) apart, read last by
    /// a step and again by the corrector's `add_ramp`: 2n x n values that then still lie in the
    /// second-level cache (the drift force between them reads a few n x n matrices), where rows
    /// of [P | G1 | G2] were read from the third.
    top: Vec<f64>,
    g2: Vec<f64>,
    /// Whether Lambda + sym(C_k) is positive definite for the cached coupling.
    definite: bool,
}

/// Degree of the truncated Taylor series of phi2 and the norm bound it is evaluated at: with
/// |X| <= 1 the remainder is below 1 / 21! ~ 2e-20 of phi2's leading 1/2, under round-off. A
/// higher degree at a larger norm costs fewer products than squarings save: Paterson and
/// Stockmeyer's evaluation takes 7 products for degree 18 (Horner took 12 for degree 12 at
/// |X| <= 1/4), and two squarings fewer.
const TAYLOR_DEGREE: usize = 18;
const SCALED_NORM: f64 = 1.0;
/// The power of the scaled generator Paterson and Stockmeyer's Horner steps multiply by.
const PS_POWER: usize = 4;

impl CoupledPropagator {
    /// A propagator for `n` modes: its transition and reference are allocated here, its scratch
    /// is a `Workspace::new(Self::workspace_req(n))` of the caller's.
    pub fn with_modes(n: usize) -> Self {
        Self {
            n,
            key: None,
            key_c_d: vec![0.0; n * n],
            key_c_k: vec![0.0; n * n],
            top: vec![0.0; 6 * n * n],
            g2: vec![0.0; 2 * n * n],
            definite: true,
        }
    }

    /// The scratch `prepare` and `advance` need for `n` modes: the exponential's eight 2n x 2n
    /// matrices (rows padded to whole cache lines), whose room the definiteness test before it
    /// (n^2) and each advance (4 n) reuse.
    pub const fn workspace_req(n: usize) -> WorkspaceReq {
        WorkspaceReq::slices(&Self::definiteness_slices(n))
            .or(WorkspaceReq::slices(&Self::exponential_slices(n)))
            .or(WorkspaceReq::slices(&Self::advance_slices(n)))
    }

    /// The Cholesky factor of the effective stiffness (n x n).
    const fn definiteness_slices(n: usize) -> [usize; 1] {
        [n * n]
    }

    /// The exponential's scratch, in the order of [`Exponential`]'s fields: the scaled generator
    /// and its square, cube and fourth power, the phi series and a product (2n x 2n each; the
    /// cube and the fourth power also serve as 2n x n scratch); [G1 | G2] and its product with P
    /// (2n x 2n each); rows [`row_stride`] values apart.
    const fn exponential_slices(n: usize) -> [usize; 8] {
        let square = 2 * n * row_stride(2 * n);
        [square; 8]
    }

    /// The scaled state y = [Omega q; q'] at the step's start with the load p0 after it (3n), and
    /// at its end (2n).
    const fn advance_slices(n: usize) -> [usize; 2] {
        [3 * n, 2 * n]
    }

    /// Whether the effective stiffness Lambda + sym(C_k) of the prepared step is positive
    /// definite. If it is not, the body is statically unstable under the present loads (spin
    /// above a critical speed without enough stiffening): its motion may grow without bound,
    /// as the physics says, unless gyroscopic terms stabilise it.
    pub fn definite(&self) -> bool {
        self.definite
    }

    /// Whether a transition for steps of `h` with these Rayleigh coefficients is prepared.
    pub fn is_prepared(&self, h: f64, alpha: f64, beta: f64) -> bool {
        self.key == Some((h, alpha, beta))
    }

    /// (h, alpha, beta) of the prepared transition.
    pub fn key(&self) -> Option<(f64, f64, f64)> {
        self.key
    }

    /// Whether this propagator has the storage for its modes (bodies that can couple).
    pub fn has_storage(&self) -> bool {
        self.n > 0 && self.top.len() == 6 * self.n * self.n && self.g2.len() == 2 * self.n * self.n
    }

    /// The coupling (C_d, C_k) the prepared transition is exact for.
    pub fn reference(&self) -> (&[f64], &[f64]) {
        (&self.key_c_d, &self.key_c_k)
    }

    /// Make the transition for steps of `h` with modal damping d_k = alpha + beta w_k^2 + extra_k
    /// and the coupling `c_d`, `c_k` (row-major n x n) current. Recomputed only when any of them
    /// changed, so a steady spin costs one exponential, in the scratch `ws` lends. Err, with the
    /// propagator unchanged, if `ws` holds less than [`Self::workspace_req`].
    #[allow(clippy::too_many_arguments)]
    pub fn prepare(
        &mut self,
        omega: &[f64],
        alpha: f64,
        beta: f64,
        extra: &[f64],
        c_d: &[f64],
        c_k: &[f64],
        h: f64,
        ws: &mut Workspace,
    ) -> Result<Prepared, WorkspaceTooSmall> {
        let n = self.n;
        debug_assert!(omega.len() == n && c_d.len() == n * n && c_k.len() == n * n);
        // refused before the key changes: a refused call leaves the transition as it was
        ws.check(Self::workspace_req(n))?;
        if self.key == Some((h, alpha, beta)) && self.key_c_d == c_d && self.key_c_k == c_k {
            return Ok(Prepared::Reused);
        }
        self.key = Some((h, alpha, beta));
        self.key_c_d.copy_from_slice(c_d);
        self.key_c_k.copy_from_slice(c_k);
        self.definite = self.effective_stiffness_definite(omega, ws)?;
        let [a, a2, a3, a4, phi, tmp, g, gt] = ws.carve(Self::exponential_slices(n))?;
        let m = 2 * n;
        let ld = row_stride(m);
        // A h in the scaled state, then scaled by 2^-s so that |A h 2^-s|_1 <= SCALED_NORM
        a.fill(0.0);
        for i in 0..n {
            a[i * ld + n + i] = h * omega[i];
            let row = n + i;
            for j in 0..n {
                a[row * ld + j] = -h * c_k[i * n + j] / omega[j];
                a[row * ld + n + j] = -h * c_d[i * n + j];
            }
            a[row * ld + i] -= h * omega[i];
            a[row * ld + n + i] -= h * (alpha + beta * omega[i] * omega[i] + extra[i]);
        }
        let norm = (0..m).map(|j| (0..m).map(|i| a[i * ld + j].abs()).sum::<f64>()).fold(0.0, f64::max);
        // the load blocks have norm h, like A h's time scale: scale them alike
        let norm = norm.max(h);
        // a finite norm needs at most log2(f64::MAX) squarings; an overflowing one (a step of
        // 1e308 s) would ask for i32::MAX of them: its transition is non-finite whatever the
        // count, which the step reports, so the count stays bounded
        let s = if norm > SCALED_NORM { (norm / SCALED_NORM).log2().ceil().min(MAX_SQUARINGS) as i32 } else { 0 };
        let tau = h * 0.5f64.powi(s);
        let scale = 0.5f64.powi(s);
        for v in a.iter_mut() {
            *v *= scale;
        }
        self.exponentiate(s, tau, Exponential { a, a2, a3, a4, phi, tmp, g, gt });
        Ok(Prepared::Computed)
    }

    /// exp of the scaled generator in `x.a` (with its load blocks), squared `s` times back to the
    /// step: the transition [P, G1] in `top`, G2 in `g2`.
    fn exponentiate(&mut self, s: i32, tau: f64, x: Exponential<'_>) {
        let n = self.n;
        let m = 2 * n;
        // square matrices in rows of `ld` values, 2n x n ones (a3, a4 below) of `ldn`; the values
        // past a row's end are never read by a product (elementwise sums may pass over them)
        let (ld, ldn) = (row_stride(m), row_stride(n));
        let mul = |r: usize, k: usize, c: usize, x: (&[f64], usize), y: (&[f64], usize), out: (&mut [f64], usize)| {
            mat_mul_strided(r, k, c, x, y, out)
        };
        let Exponential { a, a2, a3, a4, phi, tmp, g, gt } = x;
        let a = &*a;
        // The block matrix X = [[a, e, 0], [0, 0, tau I], [0, 0, 0]] (a = A tau, e = [0; tau I])
        // has X^k = [[a^k, a^(k-1) e, a^(k-2) e tau], 0, 0], so exp(X) = [[P, G1, G2], [0, I,
        // tau I], [0, 0, I]] with P = I + a + a^2 phi2(a), G1 = phi1(a) e, G2 = phi2(a) e tau,
        // phi1 = I + a phi2 and phi2(a) = sum c_k a^k, c_k = 1 / (k + 2)!.
        mul(m, m, m, (a, ld), (a, ld), (a2, ld));
        mul(m, m, m, (a2, ld), (a, ld), (a3, ld));
        mul(m, m, m, (a2, ld), (a2, ld), (a4, ld));
        let powers: [&[f64]; PS_POWER] = [&[], a, a2, a3];
        // Paterson-Stockmeyer: phi2 = B_0 + a^4 (B_1 + a^4 (B_2 + ...)), each B_j = sum over
        // i < 4 of c_(4j+i) a^i a sum of the powers at hand
        let blocks = TAYLOR_DEGREE / PS_POWER;
        let coefficient = |k: usize| if k <= TAYLOR_DEGREE { 1.0 / factorial(k + 2) } else { 0.0 };
        let (mut acc, mut spare) = (phi, tmp);
        power_sum(m, ld, &powers, |i| coefficient(PS_POWER * blocks + i), acc);
        for j in (0..blocks).rev() {
            mul(m, m, m, (a4, ld), (acc, ld), (spare, ld));
            std::mem::swap(&mut acc, &mut spare);
            add_power_sum(m, ld, &powers, |i| coefficient(PS_POWER * j + i), acc);
        }
        let phi2 = &*acc;
        // [G1 | G2]: G2 = phi2 e tau, the right half columns of phi2 times tau^2; G1 = phi1 e =
        // (e + a phi2 e), the same columns times a plus tau I below
        for r in 0..m {
            for j in 0..n {
                a3[r * ldn + j] = phi2[r * ld + n + j];
                g[r * ld + n + j] = phi2[r * ld + n + j] * tau * tau;
            }
        }
        mul(m, m, n, (a, ld), (a3, ldn), (a4, ldn));
        for r in 0..m {
            for j in 0..n {
                let identity = if r == n + j { 1.0 } else { 0.0 };
                g[r * ld + j] = (a4[r * ldn + j] + identity) * tau;
            }
        }
        // P = I + a + a^2 phi2
        let p = spare;
        mul(m, m, m, (a2, ld), (phi2, ld), (p, ld));
        for (pv, av) in p.iter_mut().zip(a) {
            *pv += av;
        }
        add_identity(m, ld, p, 1.0);
        // squaring: exp(X)^2 = [[P^2, P G1 + G1, P G2 + G1 c + G2], [0, I, 2c I], [0, 0, I]];
        // P [G1 | G2] as one product
        let (mut p, mut p_next) = (p, a3);
        let mut c = tau;
        for _ in 0..s {
            mul(m, m, m, (p, ld), (g, ld), (gt, ld));
            for (row, t_row) in g.chunks_exact_mut(ld).zip(gt.chunks_exact(ld)) {
                let (g1, g2) = row.split_at_mut(n);
                let (t1, t2) = t_row.split_at(n);
                for j in 0..n {
                    g2[j] += t2[j] + g1[j] * c;
                    g1[j] += t1[j];
                }
            }
            mul(m, m, m, (p, ld), (p, ld), (p_next, ld));
            std::mem::swap(&mut p, &mut p_next);
            c *= 2.0;
        }
        let w = 3 * n;
        for r in 0..m {
            self.top[r * w..r * w + m].copy_from_slice(&p[r * ld..r * ld + m]);
            self.top[r * w + m..(r + 1) * w].copy_from_slice(&g[r * ld..r * ld + n]);
            self.g2[r * n..(r + 1) * n].copy_from_slice(&g[r * ld + n..r * ld + m]);
        }
    }

    /// Advance q, q' by the prepared step under the load p0 + t p1 (t from the step's start),
    /// in the scratch `ws` lends. Err, with q, q' unchanged, if `ws` holds less than
    /// [`Self::workspace_req`].
    #[allow(clippy::too_many_arguments)]
    pub fn advance(
        &self,
        omega: &[f64],
        p0: &[f64],
        p1: &[f64],
        q: &mut [f64],
        qd: &mut [f64],
        ws: &mut Workspace,
    ) -> Result<(), WorkspaceTooSmall> {
        let n = self.n;
        // [P | G1] applied to [y; p0] in one product, then G2 p1
        let [y, y1] = ws.carve(Self::advance_slices(n))?;
        for i in 0..n {
            y[i] = omega[i] * q[i];
            y[n + i] = qd[i];
        }
        y[2 * n..].copy_from_slice(p0);
        mat_vec((&self.top, 3 * n), y, y1, Store::Set);
        if p1.iter().any(|v| *v != 0.0) {
            mat_vec((&self.g2, n), p1, y1, Store::AddScaled(1.0));
        }
        for i in 0..n {
            q[i] = y1[i] / omega[i];
            qd[i] = y1[n + i];
        }
        Ok(())
    }

    /// Add to q, q' (already advanced by the prepared step) what a further load ramp `p1` over
    /// the step adds at its end, G2 p1: the step is linear in its load, so advancing with
    /// (p0, a) and then adding b gives the step under (p0, a + b). In the scratch `ws` lends;
    /// Err, with q, q' unchanged, if it holds less than [`Self::workspace_req`].
    pub fn add_ramp(
        &self,
        omega: &[f64],
        p1: &[f64],
        q: &mut [f64],
        qd: &mut [f64],
        ws: &mut Workspace,
    ) -> Result<(), WorkspaceTooSmall> {
        let n = self.n;
        let [_, dy] = ws.carve(Self::advance_slices(n))?;
        mat_vec((&self.g2, n), p1, dy, Store::Set);
        for i in 0..n {
            q[i] += dy[i] / omega[i];
            qd[i] += dy[n + i];
        }
        Ok(())
    }

    /// Cholesky of Lambda + sym(C_k), in place in the workspace.
    fn effective_stiffness_definite(&self, omega: &[f64], ws: &mut Workspace) -> Result<bool, WorkspaceTooSmall> {
        let n = self.n;
        let [a] = ws.carve(Self::definiteness_slices(n))?;
        for i in 0..n {
            for j in 0..n {
                a[i * n + j] = 0.5 * (self.key_c_k[i * n + j] + self.key_c_k[j * n + i]);
            }
            a[i * n + i] += omega[i] * omega[i];
        }
        for j in 0..n {
            let mut d = a[j * n + j];
            for k in 0..j {
                d -= a[j * n + k] * a[j * n + k];
            }
            if d.is_nan() || d <= 0.0 {
                return Ok(false);
            }
            let d = d.sqrt();
            a[j * n + j] = d;
            for i in j + 1..n {
                let mut v = a[i * n + j];
                for k in 0..j {
                    v -= a[i * n + k] * a[j * n + k];
                }
                a[i * n + j] = v / d;
            }
        }
        Ok(true)
    }
}

/// The exponential's scratch, carved from the workspace (see
/// [`CoupledPropagator::exponential_slices`]); written before it is read, so what a previous
/// call left in it does not matter. 2n x 2n each, in rows of [`row_stride`] values.
struct Exponential<'a> {
    /// The scaled generator A tau (its load blocks are implicit) and its powers; the cube and
    /// the fourth power serve as scratch once the series is summed, the cube as P's square.
    a: &'a mut [f64],
    a2: &'a mut [f64],
    a3: &'a mut [f64],
    a4: &'a mut [f64],
    /// The phi2 series and the product it is swapped with; that product becomes P.
    phi: &'a mut [f64],
    tmp: &'a mut [f64],
    /// [G1 | G2] (2n x n each, side by side) and its product with P.
    g: &'a mut [f64],
    gt: &'a mut [f64],
}

/// out = sum over i of coefficient(i) a^i, with powers[i] = a^i for i >= 1 (a^0 = I).
fn power_sum(m: usize, ld: usize, powers: &[&[f64]], coefficient: impl Fn(usize) -> f64, out: &mut [f64]) {
    out.fill(0.0);
    add_power_sum(m, ld, powers, coefficient, out);
}

/// out += sum over i of coefficient(i) a^i (powers as in [`power_sum`]).
fn add_power_sum(m: usize, ld: usize, powers: &[&[f64]], coefficient: impl Fn(usize) -> f64, out: &mut [f64]) {
    add_identity(m, ld, out, coefficient(0));
    for (i, power) in powers.iter().enumerate().skip(1) {
        let c = coefficient(i);
        if c != 0.0 {
            for (o, v) in out.iter_mut().zip(power.iter()) {
                *o += c * v;
            }
        }
    }
}

fn add_identity(m: usize, ld: usize, out: &mut [f64], value: f64) {
    for i in 0..m {
        out[i * ld + i] += value;
    }
}

/// Values between the rows of the exponential's m-column matrices: whole cache lines (8 values).
const fn row_stride(m: usize) -> usize {
    m.next_multiple_of(8)
}

fn factorial(k: usize) -> f64 {
    (1..=k).map(|i| i as f64).product()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::propagator::ModalPropagator;

    /// Without coupling the exponential must equal the closed-form transition of each damped
    /// oscillator (the existing exact propagator, itself tested against analytic solutions),
    /// for ramp loads too, from kHz-stiff to overdamped modes and steps over many periods.
    #[test]
    fn uncoupled_equals_the_closed_form() {
        let omega = [3.0, 250.0, 4.0e4];
        let extra = [0.1, 0.0, 0.0];
        let zero = [0.0; 9];
        for &(h, alpha, beta) in &[(1e-3, 0.0, 0.0), (0.1, 0.5, 1e-4), (2.0, 0.0, 1e-6)] {
            let mut coupled = CoupledPropagator::with_modes(3);
            let mut ws = Workspace::new(CoupledPropagator::workspace_req(3));
            coupled.prepare(&omega, alpha, beta, &extra, &zero, &zero, h, &mut ws).unwrap();
            let mut modal = ModalPropagator::with_modes(3);
            modal.prepare(&omega, alpha, beta, &extra, h);
            let p0 = [1.0, -2.0, 3.0e3];
            let p1 = [0.5, 4.0, -1.0e3];
            let (mut q, mut qd) = ([1e-3, 2e-4, -3e-6], [0.1, -0.2, 0.3]);
            let (mut q2, mut qd2) = (q, qd);
            coupled.advance(&omega, &p0, &p1, &mut q, &mut qd, &mut ws).unwrap();
            modal.advance_ramp(&omega, &p0, &p1, &mut q2, &mut qd2);
            assert_eq!(q.len(), q2.len());
            for k in 0..3 {
                // the two agree to the exponential's round-off, 1e-12 of each mode's amplitude scale
                let qs = q2[k].abs().max(qd2[k].abs() / omega[k]).max(1e-9);
                assert!((q[k] - q2[k]).abs() <= 1e-10 * qs, "h {h} mode {k}: q {} vs {}", q[k], q2[k]);
                assert!((qd[k] - qd2[k]).abs() <= 1e-10 * qs * omega[k], "h {h} mode {k}: qd {} vs {}", qd[k], qd2[k]);
            }
        }
    }

    /// Undamped gyroscopic coupling (skew C_d) conserves 1/2 |q'|^2 + 1/2 q^T Lambda q exactly;
    /// the exponential must keep it over 10^5 steps at any step size.
    #[test]
    fn gyroscopic_energy_is_conserved() {
        let omega = [10.0, 13.0, 400.0];
        let g = 50.0;
        let c_d = [0.0, g, 0.0, -g, 0.0, 0.3 * g, 0.0, -0.3 * g, 0.0];
        let zero = [0.0; 9];
        for &h in &[1e-3, 0.05, 3.0] {
            let mut p = CoupledPropagator::with_modes(3);
            let mut ws = Workspace::new(CoupledPropagator::workspace_req(3));
            p.prepare(&omega, 0.0, 0.0, &[0.0; 3], &c_d, &zero, h, &mut ws).unwrap();
            let (mut q, mut qd) = ([0.01, 0.0, 1e-4], [0.0, 0.2, 0.0]);
            let energy = |q: &[f64; 3], qd: &[f64; 3]| {
                (0..3).map(|k| 0.5 * qd[k] * qd[k] + 0.5 * omega[k] * omega[k] * q[k] * q[k]).sum::<f64>()
            };
            let e0 = energy(&q, &qd);
            for _ in 0..100_000 {
                p.advance(&omega, &[0.0; 3], &[0.0; 3], &mut q, &mut qd, &mut ws).unwrap();
            }
            let e1 = energy(&q, &qd);
            // round-off of the exponential: measured 1.1e-8 over 1e5 steps at h = 3 (13 squarings),
            // less at the shorter steps
            assert!((e1 - e0).abs() <= 1e-7 * e0, "h {h}: energy {e0} -> {e1}");
        }
    }

    /// Van Loan's block matrix [[A h, E h, 0], [0, 0, I h], [0, 0, 0]] (4n x 4n) exponentiated
    /// as a whole, by the textbook's Taylor series at |X 2^-s| <= 1/8 and s plain squarings:
    /// none of the structure the propagator uses (the phi series, Paterson-Stockmeyer, the
    /// blocks' squaring, the kernel). Its top 2n rows, row-major 2n x 4n.
    fn van_loan_reference(omega: &[f64], damping: &[f64], c_d: &[f64], c_k: &[f64], h: f64) -> Vec<f64> {
        let n = omega.len();
        let (m, w) = (2 * n, 4 * n);
        let mut x = vec![0.0; w * w];
        for i in 0..n {
            x[i * w + n + i] = h * omega[i];
            for j in 0..n {
                x[(n + i) * w + j] = -h * c_k[i * n + j] / omega[j];
                x[(n + i) * w + n + j] = -h * c_d[i * n + j];
            }
            x[(n + i) * w + i] -= h * omega[i];
            x[(n + i) * w + n + i] -= h * damping[i];
            x[(n + i) * w + m + i] = h;
            x[(m + i) * w + m + n + i] = h;
        }
        let norm = (0..w).map(|j| (0..w).map(|i| x[i * w + j].abs()).sum::<f64>()).fold(0.0, f64::max);
        let s = (norm / 0.125).log2().ceil().max(0.0) as i32;
        x.iter_mut().for_each(|v| *v *= 0.5f64.powi(s));
        let product = |a: &[f64], b: &[f64]| -> Vec<f64> {
            let mut out = vec![0.0; w * w];
            for i in 0..w {
                for l in 0..w {
                    for j in 0..w {
                        out[i * w + j] += a[i * w + l] * b[l * w + j];
                    }
                }
            }
            out
        };
        let mut e = vec![0.0; w * w];
        let mut term = vec![0.0; w * w];
        for i in 0..w {
            e[i * w + i] = 1.0;
            term[i * w + i] = 1.0;
        }
        for k in 1..=20 {
            term = product(&term, &x);
            term.iter_mut().for_each(|v| *v /= k as f64);
            e.iter_mut().zip(&term).for_each(|(a, b)| *a += b);
        }
        for _ in 0..s {
            e = product(&e, &e);
        }
        e[..m * w].to_vec()
    }

    /// The renewal (the propagator's exponential) against the textbook's exponential of the whole
    /// block matrix, for gyroscopic and centrifugal coupling of modes from 5 Hz to 2 kHz, light
    /// and heavy (overdamped) Rayleigh damping, steps of 1 ms to many periods: every block of the
    /// transition (P, G1, G2) within 1e-12 of its largest entry (the figure), and 1e-10
    /// for a step of 0.5 s (7000 radians of the fastest mode, 16 squarings).
    ///
    /// Measured, largest over the blocks: 1.7e-14, 2.1e-13, 3.9e-13 and 1.1e-11 in the order
    /// of the cases; the propagator before Paterson-Stockmeyer and the blocked kernel measured
    /// 2.1e-14, 3.1e-13, 3.9e-13 and 1.4e-11 against the same reference, so the differences are
    /// the reference's own round-off and the squarings' conditioning.
    #[test]
    fn renewal_equals_the_reference_exponential() {
        let n = 9;
        let omega: Vec<f64> = (0..n).map(|k| 30.0 * 4.0f64.powi(k as i32 / 2) * (1.0 + 0.1 * k as f64)).collect();
        let mut c_d = vec![0.0; n * n];
        let mut c_k = vec![0.0; n * n];
        for i in 0..n {
            for j in 0..n {
                let g = 7.0 * (((i * 5 + j * 3) % 11) as f64 - 5.0) / 5.0;
                c_d[i * n + j] = if i < j { g } else { -g };
                c_k[i * n + j] = -40.0 * (((i + j) % 5) as f64) - if i == j { 100.0 } else { 0.0 };
            }
            c_d[i * n + i] = 0.0;
        }
        let cases =
            [(1e-3, 0.0, 0.0, 1e-12), (1e-3, 1.0, 1e-3, 1e-12), (2e-2, 0.5, 1e-5, 1e-12), (0.5, 0.0, 1e-4, 1e-10)];
        for &(h, alpha, beta, tolerance) in &cases {
            let damping: Vec<f64> = omega.iter().map(|w| alpha + beta * w * w).collect();
            let mut p = CoupledPropagator::with_modes(n);
            let mut ws = Workspace::new(CoupledPropagator::workspace_req(n));
            p.prepare(&omega, alpha, beta, &vec![0.0; n], &c_d, &c_k, h, &mut ws).unwrap();
            let reference = van_loan_reference(&omega, &damping, &c_d, &c_k, h);
            let (m, w) = (2 * n, 4 * n);
            assert_eq!(p.top.len() + p.g2.len(), reference.len());
            let ours = |r: usize, c: usize| if c < 3 * n { p.top[r * 3 * n + c] } else { p.g2[r * n + c - 3 * n] };
            for (block, cols) in [("P", 0..m), ("G1", m..m + n), ("G2", m + n..w)] {
                let largest = (0..m)
                    .flat_map(|r| cols.clone().map(move |c| (r, c)))
                    .map(|(r, c)| reference[r * w + c].abs())
                    .fold(0.0, f64::max);
                for r in 0..m {
                    for c in cols.clone() {
                        let (ours, theirs) = (ours(r, c), reference[r * w + c]);
                        assert!(
                            (ours - theirs).abs() <= tolerance * largest,
                            "h {h}, beta {beta}: {block}[{r},{c}] {ours} vs {theirs} (largest {largest})"
                        );
                    }
                }
            }
        }
    }

    /// The corrector's shortcut: a step under (p0, a) plus `add_ramp(b)` is the step under
    /// (p0, a + b), to round-off.
    #[test]
    fn an_added_ramp_equals_the_step_taken_with_it() {
        let omega = [10.0, 13.0, 400.0];
        let c_d = [0.0, 5.0, 0.0, -5.0, 0.0, 1.0, 0.0, -1.0, 0.0];
        let c_k = [3.0, 0.5, 0.0, 0.5, -2.0, 0.1, 0.0, 0.1, 7.0];
        let mut p = CoupledPropagator::with_modes(3);
        let mut ws = Workspace::new(CoupledPropagator::workspace_req(3));
        p.prepare(&omega, 0.1, 1e-4, &[0.0; 3], &c_d, &c_k, 1e-2, &mut ws).unwrap();
        let (p0, a, b) = ([1.0, -2.0, 3.0], [0.5, 0.0, -4.0], [-3.0, 7.0, 0.25]);
        let (mut q, mut qd) = ([1e-3, -2e-3, 1e-5], [0.1, 0.0, -0.3]);
        let (mut q2, mut qd2) = (q, qd);
        p.advance(&omega, &p0, &a, &mut q, &mut qd, &mut ws).unwrap();
        p.add_ramp(&omega, &b, &mut q, &mut qd, &mut ws).unwrap();
        let sum: Vec<f64> = a.iter().zip(&b).map(|(x, y)| x + y).collect();
        p.advance(&omega, &p0, &sum, &mut q2, &mut qd2, &mut ws).unwrap();
        for k in 0..3 {
            // two sums of the same products in another grouping: a few ulps
            assert!((q[k] - q2[k]).abs() <= 1e-14 * q2[k].abs().max(1e-6), "q[{k}] {} vs {}", q[k], q2[k]);
            assert!((qd[k] - qd2[k]).abs() <= 1e-14 * qd2[k].abs().max(1e-4), "qd[{k}] {} vs {}", qd[k], qd2[k]);
        }
    }

    #[test]
    fn softened_stiffness_is_reported_indefinite() {
        let omega = [10.0, 20.0];
        let mut p = CoupledPropagator::with_modes(2);
        let mut ws = Workspace::new(CoupledPropagator::workspace_req(2));
        let mut definite_at = |softening: f64| {
            let c_k = [-softening, 0.0, 0.0, -softening];
            p.prepare(&omega, 0.0, 0.0, &[0.0; 2], &[0.0; 4], &c_k, 1e-3, &mut ws).unwrap();
            p.definite()
        };
        assert!(definite_at(50.0));
        assert!(!definite_at(150.0));
    }

    /// A workspace made for fewer modes is refused by both hot functions, with the sizes, before
    /// they change anything (no panic: the FMI layer calls them under its C boundary); a larger
    /// one serves, with the same result to the bit (the scratch is written before it is read).
    #[test]
    fn a_workspace_too_small_is_refused_and_a_larger_one_serves() {
        let omega = [10.0, 13.0, 400.0];
        let c_d = [0.0, 5.0, 0.0, -5.0, 0.0, 1.0, 0.0, -1.0, 0.0];
        let c_k = [3.0, 0.5, 0.0, 0.5, -2.0, 0.1, 0.0, 0.1, 7.0];
        let needed = CoupledPropagator::workspace_req(3).len();
        // the exponential's eight 2n x 2n matrices, rows of whole cache lines (8 values for 6)
        assert_eq!(needed, 8 * 6 * 8);
        let mut p = CoupledPropagator::with_modes(3);
        let mut small = Workspace::new(CoupledPropagator::workspace_req(2));
        let refused = p.prepare(&omega, 0.1, 1e-4, &[0.0; 3], &c_d, &c_k, 0.01, &mut small).unwrap_err();
        assert_eq!(refused, WorkspaceTooSmall { needed, available: small.len() });
        assert_eq!(p.key(), None, "a refused prepare leaves the propagator unprepared");
        let run = |ws: &mut Workspace, p: &mut CoupledPropagator| {
            assert_eq!(p.prepare(&omega, 0.1, 1e-4, &[0.0; 3], &c_d, &c_k, 0.01, ws), Ok(Prepared::Computed));
            let (mut q, mut qd) = ([1e-3, -2e-3, 1e-5], [0.1, 0.0, -0.3]);
            for _ in 0..10 {
                p.advance(&omega, &[1.0, 2.0, 3.0], &[0.5, 0.0, 0.0], &mut q, &mut qd, ws).unwrap();
            }
            (q, qd)
        };
        let exact = run(&mut Workspace::new(CoupledPropagator::workspace_req(3)), &mut p.clone());
        // a larger workspace, holding garbage from elsewhere
        let mut large = Workspace::new(CoupledPropagator::workspace_req(5));
        let len = large.len();
        large.carve([len]).unwrap()[0].fill(f64::NAN);
        assert_eq!(run(&mut large, &mut p.clone()), exact);
        // the prepared propagator with a small workspace: advance refused, the state untouched
        let mut prepared = p.clone();
        run(&mut Workspace::new(CoupledPropagator::workspace_req(3)), &mut prepared);
        let mut tiny = Workspace::new(WorkspaceReq::slices(&[5]));
        let (mut q, mut qd) = ([1.0; 3], [2.0; 3]);
        // the advance's [y; p0] (3n) and its end (2n)
        let refused = prepared.advance(&omega, &[0.0; 3], &[0.0; 3], &mut q, &mut qd, &mut tiny).unwrap_err();
        assert_eq!((refused.needed, refused.available, q, qd), (15, 5, [1.0; 3], [2.0; 3]));
    }
}
