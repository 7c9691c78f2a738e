//! What a Model Exchange host's integrator cannot carry, said early and once: a host that
//! integrates by explicit Euler (the FMI Compliance Checker, fmusim's default: fixed steps, one
//! derivative evaluation each) at a step too long for the dynamic modes, instead of letting them
//! grow to NaN hundreds of steps later; a tolerance too loose for undamped dynamic modes.

use crate::reduced::ReducedBody;
use std::f64::consts::PI;

/// Steps of explicit Euler's form in a row before the host counts as explicit Euler.
const EULER_STEPS: u32 = 3;
/// How exactly a step must be x + h f(x) (relative to the states and the update): explicit
/// Euler's states are that to rounding; a variable-step solver's (CVode interpolating to an
/// output point, BDF, Runge-Kutta stages) are not.
const EULER_MATCH: f64 = 1e-10;

/// Explicit Euler's fingerprint: every completed step has one derivative evaluation, at the
/// states x the previous step ended with, and ends at exactly x + h f(x), h the same each time.
#[derive(Debug, Clone, Default)]
pub struct StepWatch {
    /// States, derivatives and time of the last evaluation (buffers sized at instantiation).
    x_eval: Vec<f64>,
    dx_eval: Vec<f64>,
    t_eval: Option<f64>,
    /// The states at the last completed step.
    x_now: Vec<f64>,
    evaluations: u32,
    last_step: f64,
    euler_steps: u32,
    warned: bool,
}

impl StepWatch {
    /// A watch for `nx` continuous states.
    pub fn new(nx: usize) -> Self {
        Self { x_eval: vec![0.0; nx], dx_eval: vec![0.0; nx], x_now: vec![0.0; nx], ..Self::default() }
    }

    /// The states buffer, taken out for the host's model to fill with the states of the
    /// evaluation (no allocation); [`StepWatch::evaluated`] takes it back.
    pub fn take_state_buffer(&mut self) -> Vec<f64> {
        std::mem::take(&mut self.x_eval)
    }

    /// A derivative evaluation at `time`: the states `x` (the buffer taken out) and derivatives.
    pub fn evaluated(&mut self, time: f64, x: Vec<f64>, dx: &[f64]) {
        self.x_eval = x;
        if dx.len() == self.dx_eval.len() && self.x_eval.len() == dx.len() {
            self.dx_eval.copy_from_slice(dx);
            self.t_eval = Some(time);
        }
        self.evaluations = self.evaluations.saturating_add(1);
    }

    /// A buffer for the states at a completed step, taken out for the host's model to fill;
    /// [`StepWatch::completed`] takes it back.
    pub fn take_state_buffer_now(&mut self) -> Vec<f64> {
        std::mem::take(&mut self.x_now)
    }

    /// A completed integrator step at `time` with states `x` (the buffer taken out): the
    /// warning, once, when the steps so far are explicit Euler's and too long for the body at
    /// damping alpha, beta.
    pub fn completed(&mut self, time: f64, x: Vec<f64>, body: &ReducedBody, alpha: f64, beta: f64) -> Option<String> {
        self.x_now = x;
        let evaluations = std::mem::take(&mut self.evaluations);
        let t0 = self.t_eval.take()?;
        let h = time - t0;
        if self.warned || !(h > 0.0) || self.x_now.len() != self.x_eval.len() {
            return None;
        }
        let x = &self.x_now;
        let same = (h - self.last_step).abs() <= 1e-9 * h.max(self.last_step);
        self.last_step = h;
        self.euler_steps =
            if evaluations == 1 && euler_update(x, &self.x_eval, &self.dx_eval, h) && (same || self.euler_steps == 0) {
                self.euler_steps + 1
            } else {
                0
            };
        if self.euler_steps < EULER_STEPS {
            return None;
        }
        let (limit, mode) = body.explicit_euler_limit(alpha, beta);
        let j = mode?;
        if h <= limit {
            return None;
        }
        self.warned = true;
        Some(euler_warning(body, alpha, beta, h, j, limit))
    }
}

/// Whether x = x0 + h dx0 to rounding, with an update that moves the states at all (at rest any
/// solver's step is that).
fn euler_update(x: &[f64], x0: &[f64], dx0: &[f64], h: f64) -> bool {
    let mut moved = 0.0f64;
    for ((&x, &x0), &d) in x.iter().zip(x0).zip(dx0) {
        let update = h * d;
        if (x - (x0 + update)).abs() > EULER_MATCH * (x0.abs() + update.abs()) {
            return false;
        }
        moved = moved.max(update.abs() / (x0.abs() + f64::MIN_POSITIVE));
    }
    moved > EULER_MATCH
}

fn euler_warning(body: &ReducedBody, alpha: f64, beta: f64, h: f64, j: usize, limit: f64) -> String {
    let hz = |k: usize| body.omega[k] / (2.0 * PI);
    let (w, d) = (body.omega[j], body.damping_rate(j, alpha, beta));
    let growth = if j >= body.n_dynamic() {
        (1.0 - h * w * w / d).abs()
    } else if d < 2.0 * w {
        (1.0 - h * d + h * h * w * w).max(0.0).sqrt()
    } else {
        // overdamped: the fast real root -(d/2 + sqrt(d^2/4 - w^2)) is the one that grows
        (1.0 - h * (0.5 * d + (0.25 * d * d - w * w).sqrt())).abs()
    };
    let need = if limit > 0.0 {
        format!("needs a step below {limit:.3e} s (damping {d:.3e} 1/s)")
    } else {
        "is undamped: no explicit Euler step is stable".to_string()
    };
    // the modes explicit Euler carries at h, from the slowest up: the cutoff that keeps only them
    let carried = (0..body.n_modes()).take_while(|&k| body.explicit_euler_step(k, alpha, beta, false) >= h).count();
    let cutoff = if carried > 0 {
        format!(
            "rebuild with reduction.dynamic_cutoff = {:.4} Hz (the modes explicit Euler carries at this step), ",
            hz(carried - 1)
        )
    } else {
        String::new()
    };
    format!(
        "the host integrates by explicit Euler (fixed steps of h = {h:.3e} s, one derivative evaluation each). \
         It cannot carry this body's dynamic modes: mode {} ({:.4} Hz) {need}, and each step multiplies its \
         amplitude by {growth:.4}, so the run will grow to NaN. Use a variable-step implicit solver (CVode, BDF, \
         Radau) or Co-Simulation (exact at any step), {cutoff}or a step below {limit:.3e} s.",
        j + 1,
        hz(j)
    )
}

/// The loosest tolerance at which undamped dynamic modes keep a variable-step host within about
/// 1e-3 of an output's swing over a run of some hundred periods (the undamped L-beam over 2 s:
/// 3.6e-4 at 1e-6, 1.06e-2 at 1e-4).
pub const UNDAMPED_TOLERANCE: f64 = 1e-6;

/// The warning for a Model Exchange host (`model_exchange`) that integrates `undamped` undamped
/// dynamic modes at a relative tolerance looser than UNDAMPED_TOLERANCE.
pub fn tolerance_advice(model_exchange: bool, undamped: usize, tolerance: f64) -> Option<String> {
    (model_exchange && undamped > 0 && tolerance > UNDAMPED_TOLERANCE).then(|| {
        format!(
            "relative tolerance {tolerance:.0e} with {undamped} undamped dynamic modes: an integrator's error in an \
             undamped mode is never forgotten and grows with every period it rings (about 1e-2 of an output's swing \
             over a few hundred periods at 1e-4). Use a tolerance of {UNDAMPED_TOLERANCE:.0e} or tighter (the FMU's \
             default experiment names one), or Co-Simulation, whose step is exact for these modes."
        )
    })
}

/// The warning for a Model Exchange host that states no tolerance (fmusim calls no
/// fmi2SetupExperiment with one), where [`tolerance_advice`] would warn at the usual host
/// default of 1e-4: a body with undamped dynamic modes.
pub fn unstated_tolerance_advice(model_exchange: bool, undamped: usize) -> Option<String> {
    tolerance_advice(model_exchange, undamped, 1e-4).map(|_| {
        format!(
            "the host stated no tolerance (no fmi2SetupExperiment with one), so it integrates at its own (1e-4 in \
             most hosts), and this body has {undamped} undamped dynamic modes: an integrator's error in an undamped \
             mode is never forgotten and grows with every period it rings (about 1e-2 of an output's swing over a \
             few hundred periods at 1e-4). Give the host a tolerance of {UNDAMPED_TOLERANCE:.0e} or tighter (the \
             FMU's default experiment names one), or use Co-Simulation, whose step is exact for these modes."
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::reduced::two_mode_body;

    /// A host stepping one oscillator (q, q'; omega, d) from q = 1: explicit Euler, or the exact
    /// solution sampled at the same instants with `evaluations` evaluations per step (what a
    /// variable-step solver interpolating to output points hands over).
    fn run(
        watch: &mut StepWatch,
        body: &ReducedBody,
        h: f64,
        steps: usize,
        euler: bool,
        evaluations: usize,
    ) -> Vec<String> {
        let (w, d) = (body.omega[0], body.damping_rate(0, body.alpha, body.beta));
        let f = |x: [f64; 2]| [x[1], -w * w * x[0] - d * x[1]];
        let exact = |t: f64| {
            let wd = (w * w - 0.25 * d * d).sqrt();
            let e = (-0.5 * d * t).exp();
            let q = e * ((wd * t).cos() + 0.5 * d / wd * (wd * t).sin());
            let qd = -e * w * w / wd * (wd * t).sin();
            [q, qd]
        };
        let mut out = Vec::new();
        let mut x = [1.0, 0.0];
        for k in 0..steps {
            let t = k as f64 * h;
            for _ in 0..evaluations {
                watch.evaluated(t, x.to_vec(), &f(x));
            }
            x = if euler { [x[0] + h * f(x)[0], x[1] + h * f(x)[1]] } else { exact(t + h) };
            out.extend(watch.completed(t + h, x.to_vec(), body, body.alpha, body.beta));
        }
        out
    }

    /// The two-mode body with only its slow mode a state, 1 % damped.
    fn one_state_body() -> ReducedBody {
        let mut body = two_mode_body();
        body.dynamic_cutoff = 100.0;
        body.alpha = 0.0;
        body.beta = 0.0;
        body.modal_damping = vec![2.0 * 0.01 * body.omega[0], 0.0];
        body
    }

    #[test]
    fn euler_too_long_for_the_modes_is_named_once_with_the_step_it_needs() {
        let body = one_state_body();
        let (limit, _) = body.explicit_euler_limit(body.alpha, body.beta);
        let mut watch = StepWatch::new(2);
        let warnings = run(&mut watch, &body, 10.0 * limit, 50, true, 1);
        assert_eq!(warnings.len(), 1, "{warnings:?}");
        assert!(warnings[0].contains(&format!("h = {:.3e} s", 10.0 * limit)), "{}", warnings[0]);
        assert!(warnings[0].contains(&format!("below {limit:.3e} s")), "{}", warnings[0]);
        assert!(warnings[0].contains("Co-Simulation"));
    }

    #[test]
    fn stable_euler_and_other_solvers_are_left_alone() {
        let body = one_state_body();
        let (limit, _) = body.explicit_euler_limit(body.alpha, body.beta);
        assert!(run(&mut StepWatch::new(2), &body, 0.5 * limit, 50, true, 1).is_empty());
        // a solver whose states are not x + h f(x), even with one evaluation per equal step (CVode
        // interpolating to output points)
        assert!(run(&mut StepWatch::new(2), &body, 10.0 * limit, 50, false, 1).is_empty());
        // several evaluations per step (an implicit or multi-stage solver)
        assert!(run(&mut StepWatch::new(2), &body, 10.0 * limit, 50, true, 3).is_empty());
    }

    #[test]
    fn an_undamped_mode_has_no_stable_step_and_the_cutoff_that_helps_is_named() {
        let mut body = two_mode_body();
        body.alpha = 0.0;
        body.beta = 0.0;
        // the slow mode damped (5 %), the fast one undamped
        body.modal_damping = vec![2.0 * 0.05 * body.omega[0], 0.0];
        let (w0, w1) = (body.omega[0], body.omega[1]);
        let f = |x: [f64; 4]| [x[2], x[3], -w0 * w0 * x[0] - 0.1 * w0 * x[2], -w1 * w1 * x[1]];
        let mut watch = StepWatch::new(4);
        let (h, mut x, mut warnings) = (1e-4, [1.0, 1.0, 0.0, 0.0], Vec::new());
        for k in 0..10 {
            let d = f(x);
            watch.evaluated(k as f64 * h, x.to_vec(), &d);
            x = [x[0] + h * d[0], x[1] + h * d[1], x[2] + h * d[2], x[3] + h * d[3]];
            warnings.extend(watch.completed((k + 1) as f64 * h, x.to_vec(), &body, 0.0, 0.0));
        }
        assert_eq!(warnings.len(), 1);
        let w = &warnings[0];
        assert!(w.contains("mode 2") && w.contains("undamped"), "{w}");
        assert!(w.contains(&format!("dynamic_cutoff = {:.4} Hz", body.omega[0] / (2.0 * PI))), "{w}");
    }

    #[test]
    fn a_loose_tolerance_is_named_only_for_undamped_modes_in_model_exchange() {
        let advice = tolerance_advice(true, 3, 1e-4).expect("undamped at 1e-4");
        assert!(advice.contains("1e-4") && advice.contains("3 undamped") && advice.contains("1e-6"), "{advice}");
        assert!(tolerance_advice(true, 3, 1e-6).is_none());
        assert!(tolerance_advice(true, 0, 1e-3).is_none(), "damped modes forget the error");
        assert!(tolerance_advice(false, 3, 1e-3).is_none(), "Co-Simulation's step is exact");
        assert!(unstated_tolerance_advice(true, 3).expect("undamped, no tolerance").contains("stated no tolerance"));
        assert!(unstated_tolerance_advice(true, 0).is_none());
        assert!(unstated_tolerance_advice(false, 3).is_none());
    }
}
