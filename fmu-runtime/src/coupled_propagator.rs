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
//! used throughout: Taylor series of phi2 on the scaled A, then squaring of the blocks, all in
//! 2n x 2n and 2n x n products (a quarter of the full block matrix's work).
//!
//! The propagator holds only its state, the transition and the coupling it was made for
//! (allocated at construction). The scratch of `prepare` (the exponential) and `advance` is a
//! [`Workspace`] of [`CoupledPropagator::workspace_req`] values that the caller allocated once and
//! lends to each call: neither allocates, and a workspace too small is refused, not a panic.

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
    /// Top 2n rows of exp(X), row-major 2n x 4n: [P | G1 | G2].
    top: Vec<f64>,
    /// Whether Lambda + sym(C_k) is positive definite for the cached coupling.
    definite: bool,
}

/// Degree of the truncated Taylor series and the norm bound it is evaluated at: with
/// |X| <= 1/4 the remainder is below (1/4)^13 / 13! ~ 2e-18 relative, under round-off.
const TAYLOR_DEGREE: usize = 12;
const SCALED_NORM: f64 = 0.25;

impl CoupledPropagator {
    /// A propagator for `n` modes: its transition and reference are allocated here, its scratch
    /// is a `Workspace::new(Self::workspace_req(n))` of the caller's.
    pub fn with_modes(n: usize) -> Self {
        let m = 4 * n;
        Self {
            n,
            key: None,
            key_c_d: vec![0.0; n * n],
            key_c_k: vec![0.0; n * n],
            top: vec![0.0; 2 * n * m],
            definite: true,
        }
    }

    /// The scratch `prepare` and `advance` need for `n` modes: the exponential's 22 n^2 values,
    /// whose room the definiteness test before it (n^2) and each advance (4 n) reuse.
    pub const fn workspace_req(n: usize) -> WorkspaceReq {
        WorkspaceReq::slices(&Self::definiteness_slices(n))
            .or(WorkspaceReq::slices(&Self::exponential_slices(n)))
            .or(WorkspaceReq::slices(&Self::advance_slices(n)))
    }

    /// The Cholesky factor of the effective stiffness (n x n).
    const fn definiteness_slices(n: usize) -> [usize; 1] {
        [n * n]
    }

    /// The exponential's scratch, in the order of [`Exponential`]'s fields: the scaled generator,
    /// the phi series, P and their product (2n x 2n each); G1, G2 and their product (2n x n each).
    const fn exponential_slices(n: usize) -> [usize; 7] {
        let (square, tall) = (4 * n * n, 2 * n * n);
        [square, square, square, square, tall, tall, tall]
    }

    /// The scaled state y = [Omega q; q'] at the step's start and end (2n each).
    const fn advance_slices(n: usize) -> [usize; 2] {
        [2 * n, 2 * n]
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
        self.n > 0 && self.top.len() == 8 * self.n * self.n
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
        let [a, phi, p, tmp, g1, g2, gt] = ws.carve(Self::exponential_slices(n))?;
        let m = 2 * n;
        // A h in the scaled state, then scaled by 2^-s so that |A h 2^-s|_1 <= SCALED_NORM
        a.fill(0.0);
        for i in 0..n {
            a[i * m + n + i] = h * omega[i];
            let row = n + i;
            for j in 0..n {
                a[row * m + j] = -h * c_k[i * n + j] / omega[j];
                a[row * m + n + j] = -h * c_d[i * n + j];
            }
            a[row * m + i] -= h * omega[i];
            a[row * m + n + i] -= h * (alpha + beta * omega[i] * omega[i] + extra[i]);
        }
        let norm = (0..m).map(|j| (0..m).map(|i| a[i * m + j].abs()).sum::<f64>()).fold(0.0, f64::max);
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
        self.exponentiate(s, tau, Exponential { a, phi, p, tmp, g1, g2, gt });
        Ok(Prepared::Computed)
    }

    /// exp of the scaled generator in `x.a` (with its load blocks), squared `s` times back to the
    /// step: the transition `top` = [P, G1, G2].
    fn exponentiate(&mut self, s: i32, tau: f64, x: Exponential<'_>) {
        let n = self.n;
        let m = 2 * n;
        let Exponential { a, mut phi, mut p, mut tmp, g1, g2, gt } = x;
        let a = &*a;
        // The block matrix X = [[a, e, 0], [0, 0, tau I], [0, 0, 0]] (a = A tau, e = [0; tau I])
        // has X^k = [[a^k, a^(k-1) e, a^(k-2) e tau], 0, 0], so exp(X) = [[P, G1, G2], [0, I,
        // tau I], [0, 0, I]] with P = I + a phi1(a), G1 = phi1(a) e, G2 = phi2(a) e tau, and
        // phi2(a) = sum a^k / (k + 2)! by Horner, phi1 = I + a phi2.
        identity_scaled(m, phi, 1.0 / factorial(TAYLOR_DEGREE + 2));
        for k in (0..TAYLOR_DEGREE).rev() {
            mat_mul(m, m, m, a, phi, tmp);
            std::mem::swap(&mut phi, &mut tmp);
            add_identity(m, phi, 1.0 / factorial(k + 2));
        }
        // G2 = phi2 e tau: the right half columns of phi2, times tau^2
        for r in 0..m {
            for j in 0..n {
                g2[r * n + j] = phi[r * m + n + j] * tau * tau;
            }
        }
        // phi1 = I + a phi2
        mat_mul(m, m, m, a, phi, tmp);
        std::mem::swap(&mut phi, &mut tmp);
        add_identity(m, phi, 1.0);
        for r in 0..m {
            for j in 0..n {
                g1[r * n + j] = phi[r * m + n + j] * tau;
            }
        }
        // P = I + a phi1
        mat_mul(m, m, m, a, phi, p);
        add_identity(m, p, 1.0);
        // squaring: exp(X)^2 = [[P^2, P G1 + G1, P G2 + G1 c + G2], [0, I, 2c I], [0, 0, I]]
        let mut c = tau;
        for _ in 0..s {
            mat_mul(m, m, n, p, g2, gt);
            for (g, (pg, g1v)) in g2.iter_mut().zip(gt.iter().zip(g1.iter())) {
                *g += pg + g1v * c;
            }
            mat_mul(m, m, n, p, g1, gt);
            for (g, pg) in g1.iter_mut().zip(gt.iter()) {
                *g += pg;
            }
            mat_mul(m, m, m, p, p, tmp);
            std::mem::swap(&mut p, &mut tmp);
            c *= 2.0;
        }
        let w = 4 * n;
        for r in 0..m {
            self.top[r * w..r * w + m].copy_from_slice(&p[r * m..(r + 1) * m]);
            self.top[r * w + m..r * w + m + n].copy_from_slice(&g1[r * n..(r + 1) * n]);
            self.top[r * w + m + n..(r + 1) * w].copy_from_slice(&g2[r * n..(r + 1) * n]);
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
        let m = 4 * n;
        let [y, y1] = ws.carve(Self::advance_slices(n))?;
        for i in 0..n {
            y[i] = omega[i] * q[i];
            y[n + i] = qd[i];
        }
        let ramp = p1.iter().any(|v| *v != 0.0);
        for (row, out) in self.top.chunks_exact(m).zip(y1.iter_mut()) {
            let (p, g) = row.split_at(2 * n);
            let (g1, g2) = g.split_at(n);
            let mut acc = dot(p, y) + dot(g1, p0);
            if ramp {
                acc += dot(g2, p1);
            }
            *out = acc;
        }
        for i in 0..n {
            q[i] = y1[i] / omega[i];
            qd[i] = y1[n + i];
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
/// call left in it does not matter.
struct Exponential<'a> {
    /// The scaled generator A tau with its load blocks (2n x 2n).
    a: &'a mut [f64],
    /// Horner's phi series, P while squaring, and the product each is swapped with (2n x 2n).
    phi: &'a mut [f64],
    p: &'a mut [f64],
    tmp: &'a mut [f64],
    /// G1, G2 while squaring, and their product with P (2n x n).
    g1: &'a mut [f64],
    g2: &'a mut [f64],
    gt: &'a mut [f64],
}

/// a . b with four partial sums (independent chains the compiler can keep in flight).
#[inline]
fn dot(a: &[f64], b: &[f64]) -> f64 {
    let mut s = [0.0; 4];
    let (ca, cb) = (a.chunks_exact(4), b.chunks_exact(4));
    let (ra, rb) = (ca.remainder(), cb.remainder());
    for (x, y) in ca.zip(cb) {
        for k in 0..4 {
            s[k] += x[k] * y[k];
        }
    }
    let mut tail = 0.0;
    for (x, y) in ra.iter().zip(rb) {
        tail += x * y;
    }
    (s[0] + s[1]) + (s[2] + s[3]) + tail
}

/// out = a b with a r x k, b k x c, out r x c, row-major; out must not alias a or b.
fn mat_mul(r: usize, k: usize, c: usize, a: &[f64], b: &[f64], out: &mut [f64]) {
    out[..r * c].fill(0.0);
    for i in 0..r {
        let row = &mut out[i * c..(i + 1) * c];
        for l in 0..k {
            let ail = a[i * k + l];
            if ail == 0.0 {
                continue;
            }
            let bl = &b[l * c..(l + 1) * c];
            for (o, bv) in row.iter_mut().zip(bl) {
                *o += ail * bv;
            }
        }
    }
}

fn identity_scaled(m: usize, out: &mut [f64], value: f64) {
    out.fill(0.0);
    for i in 0..m {
        out[i * m + i] = value;
    }
}

fn add_identity(m: usize, out: &mut [f64], value: f64) {
    for i in 0..m {
        out[i * m + i] += value;
    }
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
        assert_eq!(needed, 22 * 9);
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
        let refused = prepared.advance(&omega, &[0.0; 3], &[0.0; 3], &mut q, &mut qd, &mut tiny).unwrap_err();
        assert_eq!((refused.needed, refused.available, q, qd), (12, 5, [1.0; 3], [2.0; 3]));
    }
}
