//! Exact propagation of decoupled modes over one step with the modal load held constant
//! (zero-order hold). Each mode q'' + d q' + w^2 q = p has the transition matrix exp(A h) of
//! A = [[0, 1], [-w^2, -d]]; it is exact for any h, so kHz modes stepped at ms stay stable and
//! keep no period error. The coefficients are cached for the last step size and damping.

#[derive(Debug, Clone, Copy, Default, PartialEq)]
struct Transition {
    /// exp(A h) = [[p11, p12], [p21, p22]]
    p11: f64,
    p12: f64,
    p21: f64,
    p22: f64,
}

impl Transition {
    /// exp(A h) = C I + S (A + mu I) with mu = d/2; C and S written per damping regime so that
    /// neither stiff overdamped modes (overflow of cosh) nor near-critical ones (cancellation)
    /// lose accuracy.
    fn new(omega: f64, damping: f64, h: f64) -> Self {
        let mu = 0.5 * damping;
        let w2 = omega * omega;
        let disc = mu * mu - w2;
        let (c, s) = if disc < 0.0 {
            let wd = (-disc).sqrt();
            let e = (-mu * h).exp();
            (e * (wd * h).cos(), e * (wd * h).sin() / wd)
        } else if disc > 0.0 {
            let root = disc.sqrt();
            let lambda_fast = -mu - root;
            let e_fast = (lambda_fast * h).exp();
            if 2.0 * root * h < 1.0 {
                // near-critical: the two exponentials almost cancel in S
                let growth = (2.0 * root * h).exp_m1(); // e_slow / e_fast - 1
                (e_fast * (1.0 + 0.5 * growth), e_fast * growth / (2.0 * root))
            } else {
                // slow root free of cancellation: lambda_slow = -w^2 / (mu + root)
                let e_slow = (-w2 / (mu + root) * h).exp();
                (0.5 * (e_slow + e_fast), 0.5 * (e_slow - e_fast) / root)
            }
        } else {
            let e = (-mu * h).exp();
            (e, e * h)
        };
        Self { p11: c + mu * s, p12: s, p21: -w2 * s, p22: c - mu * s }
    }
}

/// Needs no workspace, unlike [`crate::coupled_propagator::CoupledPropagator`]: its tables are
/// its state (the transition of the prepared step), and `advance` works mode by mode in place.
#[derive(Debug, Default)]
pub struct ModalPropagator {
    key: Option<(f64, f64, f64)>,
    transitions: Vec<Transition>,
    /// Modal damping d_k of the prepared step (for the particular solution of a ramp load).
    damping: Vec<f64>,
}

/// Keeps the table's capacity (a derived Clone would keep only its length): a body restored from
/// an FMU state taken before its first step must not allocate in that step either.
impl Clone for ModalPropagator {
    fn clone(&self) -> Self {
        let mut transitions = Vec::with_capacity(self.transitions.capacity());
        transitions.extend_from_slice(&self.transitions);
        let mut damping = Vec::with_capacity(self.damping.capacity());
        damping.extend_from_slice(&self.damping);
        Self { key: self.key, transitions, damping }
    }
}

impl ModalPropagator {
    /// A propagator for `n` modes whose table never reallocates: `prepare` refills it in place,
    /// so no step allocates, the first one included.
    pub fn with_modes(n: usize) -> Self {
        Self { key: None, transitions: Vec::with_capacity(n), damping: Vec::with_capacity(n) }
    }

    /// Prepare for steps of size `h` with modal damping `d_k = alpha + beta w_k^2 + extra_k`
    /// (`extra`: the body's fixed modal damping, 2 zeta_k w_k). Recomputes only when h or the
    /// Rayleigh coefficients changed, so a fixed-step host pays it once.
    pub fn prepare(&mut self, omega: &[f64], alpha: f64, beta: f64, extra: &[f64], h: f64) {
        let key = (h, alpha, beta);
        if self.key == Some(key) && self.transitions.len() == omega.len() {
            return;
        }
        self.transitions.clear();
        self.transitions
            .extend(omega.iter().zip(extra).map(|(&w, &e)| Transition::new(w, alpha + beta * w * w + e, h)));
        self.damping.clear();
        self.damping.extend(omega.iter().zip(extra).map(|(&w, &e)| alpha + beta * w * w + e));
        self.key = Some(key);
    }

    /// Advance q, qd by the prepared step under the constant modal load p.
    pub fn advance(&self, omega: &[f64], load: &[f64], q: &mut [f64], qd: &mut [f64]) {
        for k in 0..self.transitions.len() {
            let t = &self.transitions[k];
            let q_static = load[k] / (omega[k] * omega[k]);
            let dq = q[k] - q_static;
            let v = qd[k];
            q[k] = q_static + t.p11 * dq + t.p12 * v;
            qd[k] = t.p21 * dq + t.p22 * v;
        }
    }
}

impl ModalPropagator {
    /// Advance q, qd by the prepared step under the load p + r tau, tau in [0, h] (first-order
    /// hold of interpolated inputs): exact for a linear load. The particular solution of
    /// q'' + d q' + w^2 q = p + r tau is q_p = (p + r tau) / w^2 - d r / w^4, and the rest is the
    /// homogeneous motion, which exp(A h) propagates.
    pub fn advance_ramp(&self, omega: &[f64], load: &[f64], rate: &[f64], q: &mut [f64], qd: &mut [f64]) {
        let h = self.key.map_or(0.0, |k| k.0);
        for k in 0..self.transitions.len() {
            let t = &self.transitions[k];
            let w2 = omega[k] * omega[k];
            let shift = self.damping[k] * rate[k] / (w2 * w2);
            let q_start = load[k] / w2 - shift;
            let q_end = (load[k] + rate[k] * h) / w2 - shift;
            let v_p = rate[k] / w2;
            let dq = q[k] - q_start;
            let v = qd[k] - v_p;
            q[k] = q_end + t.p11 * dq + t.p12 * v;
            qd[k] = v_p + t.p21 * dq + t.p22 * v;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// exp(A h) by many tiny RK4 steps: an independent check of the closed forms.
    fn reference(omega: f64, d: f64, h: f64, x0: [f64; 2]) -> [f64; 2] {
        let f = |x: [f64; 2]| [x[1], -omega * omega * x[0] - d * x[1]];
        let n = 20000;
        let dt = h / n as f64;
        let mut x = x0;
        for _ in 0..n {
            let k1 = f(x);
            let k2 = f([x[0] + 0.5 * dt * k1[0], x[1] + 0.5 * dt * k1[1]]);
            let k3 = f([x[0] + 0.5 * dt * k2[0], x[1] + 0.5 * dt * k2[1]]);
            let k4 = f([x[0] + dt * k3[0], x[1] + dt * k3[1]]);
            x[0] += dt / 6.0 * (k1[0] + 2.0 * k2[0] + 2.0 * k3[0] + k4[0]);
            x[1] += dt / 6.0 * (k1[1] + 2.0 * k2[1] + 2.0 * k3[1] + k4[1]);
        }
        x
    }

    #[test]
    fn matches_integration_in_every_damping_regime() {
        // under-, critically (d = 2w), near-critically and over-damped
        for (w, d) in [(10.0, 0.3), (10.0, 20.0), (10.0, 20.0 + 1e-9), (10.0, 19.999999), (10.0, 300.0)] {
            let h = 0.05;
            let t = Transition::new(w, d, h);
            for x0 in [[1.0, 0.0], [0.0, 1.0]] {
                let r = reference(w, d, h, x0);
                let e = [t.p11 * x0[0] + t.p12 * x0[1], t.p21 * x0[0] + t.p22 * x0[1]];
                for i in 0..2 {
                    assert!((e[i] - r[i]).abs() < 1e-9 * (1.0 + r[i].abs()), "w={w} d={d}: {e:?} vs {r:?}");
                }
            }
        }
    }

    #[test]
    fn a_ramp_load_is_propagated_exactly() {
        // q'' + d q' + w^2 q = p + r t from rest, against fine RK4 of the forced equation
        for (w, d) in [(10.0, 0.3), (10.0, 20.0), (10.0, 300.0)] {
            let (p, r, h) = (2.0, -30.0, 0.07);
            let mut prop = ModalPropagator::default();
            prop.prepare(&[w], d, 0.0, &[0.0], h);
            let (mut q, mut qd) = ([0.3], [-1.0]);
            prop.advance_ramp(&[w], &[p], &[r], &mut q, &mut qd);
            let f = |t: f64, x: [f64; 2]| [x[1], p + r * t - w * w * x[0] - d * x[1]];
            let (n, mut x, mut t) = (200_000, [0.3, -1.0], 0.0);
            let dt = h / n as f64;
            for _ in 0..n {
                let k1 = f(t, x);
                let k2 = f(t + 0.5 * dt, [x[0] + 0.5 * dt * k1[0], x[1] + 0.5 * dt * k1[1]]);
                let k3 = f(t + 0.5 * dt, [x[0] + 0.5 * dt * k2[0], x[1] + 0.5 * dt * k2[1]]);
                let k4 = f(t + dt, [x[0] + dt * k3[0], x[1] + dt * k3[1]]);
                x[0] += dt / 6.0 * (k1[0] + 2.0 * k2[0] + 2.0 * k3[0] + k4[0]);
                x[1] += dt / 6.0 * (k1[1] + 2.0 * k2[1] + 2.0 * k3[1] + k4[1]);
                t += dt;
            }
            assert!((q[0] - x[0]).abs() < 1e-10 * (1.0 + x[0].abs()), "w={w} d={d}: {} vs {}", q[0], x[0]);
            assert!((qd[0] - x[1]).abs() < 1e-9 * (1.0 + x[1].abs()), "w={w} d={d}: {} vs {}", qd[0], x[1]);
        }
    }

    #[test]
    fn stiff_modes_at_huge_steps_decay_without_overflow() {
        // 10 kHz modes, h = 10 ms: h w ~ 630; overdamped by beta = 1e-3 (d ~ 4e3 * w)
        let omega = [2.0 * std::f64::consts::PI * 1e4, 50.0];
        let mut p = ModalPropagator::default();
        p.prepare(&omega, 1.0, 1e-3, &[0.0, 0.0], 0.01);
        let (mut q, mut qd) = (vec![1e-3, 1e-3], vec![10.0, 0.0]);
        let load = [0.0, 0.0];
        for _ in 0..10000 {
            p.advance(&omega, &load, &mut q, &mut qd);
            assert!(q.iter().chain(&qd).all(|x| x.is_finite() && x.abs() <= 10.0));
        }
        assert!(q[0].abs() < 1e-12 && q[1].abs() < 1e-12);
        // constant load: settles on the static solution p / w^2
        let load = [3.0, 2.0];
        for _ in 0..10000 {
            p.advance(&omega, &load, &mut q, &mut qd);
        }
        for k in 0..2 {
            assert!((q[k] - load[k] / (omega[k] * omega[k])).abs() <= 1e-12 * (load[k] / (omega[k] * omega[k])));
        }
    }
}
