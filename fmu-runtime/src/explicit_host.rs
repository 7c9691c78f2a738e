//! What a Model Exchange host's integrator cannot carry, said early and once: a host that
//! integrates by explicit Euler (the FMI Compliance Checker, fmusim's default: fixed steps, one
//! derivative evaluation each) at a step too long for the dynamic modes, instead of letting them
//! grow to NaN hundreds of steps later; a tolerance too loose for undamped dynamic modes.

use crate::reduced::ReducedBody;
use std::f64::consts::PI;

/// Equal steps of one evaluation each before the host counts as explicit Euler: a variable-step
/// solver changes its step or evaluates more than once per step within that many.
const EQUAL_STEPS: u32 = 3;

#[derive(Debug, Clone, Default)]
pub struct StepWatch {
    last_time: Option<f64>,
    last_step: f64,
    equal_steps: u32,
    evaluations: u32,
    warned: bool,
}

impl StepWatch {
    /// A derivative evaluation (fmi2GetDerivatives).
    pub fn evaluated(&mut self) {
        self.evaluations = self.evaluations.saturating_add(1);
    }

    /// A completed integrator step at `time`: the warning, once, when the steps so far are
    /// explicit Euler's and too long for the body at damping alpha, beta.
    pub fn completed(&mut self, time: f64, body: &ReducedBody, alpha: f64, beta: f64) -> Option<String> {
        let evaluations = std::mem::take(&mut self.evaluations);
        let previous = self.last_time.replace(time)?;
        let h = time - previous;
        if self.warned || !(h > 0.0) {
            return None;
        }
        let same = (h - self.last_step).abs() <= 1e-9 * h.max(self.last_step);
        self.equal_steps = if same && evaluations == 1 { self.equal_steps + 1 } else { 0 };
        self.last_step = h;
        if self.equal_steps + 1 < EQUAL_STEPS {
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::reduced::two_mode_body;

    fn run(watch: &mut StepWatch, body: &ReducedBody, h: f64, steps: usize, evaluations: usize) -> Vec<String> {
        let mut out = Vec::new();
        for k in 0..=steps {
            for _ in 0..evaluations {
                watch.evaluated();
            }
            out.extend(watch.completed(k as f64 * h, body, body.alpha, body.beta));
        }
        out
    }

    #[test]
    fn a_loose_tolerance_is_named_only_for_undamped_modes_in_model_exchange() {
        let advice = tolerance_advice(true, 3, 1e-4).expect("undamped at 1e-4");
        assert!(advice.contains("1e-4") && advice.contains("3 undamped") && advice.contains("1e-6"), "{advice}");
        assert!(tolerance_advice(true, 3, 1e-6).is_none());
        assert!(tolerance_advice(true, 0, 1e-3).is_none(), "damped modes forget the error");
        assert!(tolerance_advice(false, 3, 1e-3).is_none(), "Co-Simulation's step is exact");
    }

    #[test]
    fn euler_too_long_for_the_modes_is_named_once_with_the_step_it_needs() {
        let body = two_mode_body();
        let (limit, _) = body.explicit_euler_limit(body.alpha, body.beta);
        let warnings = run(&mut StepWatch::default(), &body, 10.0 * limit, 50, 1);
        assert_eq!(warnings.len(), 1, "{warnings:?}");
        assert!(warnings[0].contains(&format!("h = {:.3e} s", 10.0 * limit)), "{}", warnings[0]);
        assert!(warnings[0].contains(&format!("below {limit:.3e} s")), "{}", warnings[0]);
        assert!(warnings[0].contains("Co-Simulation"));
    }

    #[test]
    fn stable_euler_and_variable_step_solvers_are_left_alone() {
        let body = two_mode_body();
        let (limit, _) = body.explicit_euler_limit(body.alpha, body.beta);
        assert!(run(&mut StepWatch::default(), &body, 0.5 * limit, 50, 1).is_empty());
        // several evaluations per step: not Euler (an implicit or multi-stage solver)
        assert!(run(&mut StepWatch::default(), &body, 10.0 * limit, 50, 3).is_empty());
        // changing steps: a variable-step solver
        let mut watch = StepWatch::default();
        let mut t = 0.0;
        for k in 0..50 {
            watch.evaluated();
            assert!(watch.completed(t, &body, body.alpha, body.beta).is_none());
            t += limit * (2.0 + (k % 3) as f64);
        }
    }

    #[test]
    fn an_undamped_mode_has_no_stable_step_and_the_cutoff_that_helps_is_named() {
        let mut body = two_mode_body();
        body.alpha = 0.0;
        body.beta = 0.0;
        // the slow mode damped (5 %), the fast one undamped
        body.modal_damping = vec![2.0 * 0.05 * body.omega[0], 0.0];
        let warnings = run(&mut StepWatch::default(), &body, 1e-4, 10, 1);
        assert_eq!(warnings.len(), 1);
        let w = &warnings[0];
        assert!(w.contains("mode 2") && w.contains("undamped"), "{w}");
        assert!(w.contains(&format!("dynamic_cutoff = {:.4} Hz", body.omega[0] / (2.0 * PI))), "{w}");
    }
}
