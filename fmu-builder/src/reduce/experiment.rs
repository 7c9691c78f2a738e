//! What a Model Exchange host integrates at its defaults: the FMU's DefaultExperiment (stop
//! time, output step, tolerance) and the dynamic cutoff, chosen together.
//!
//! Hosts do not integrate what the FMU proposes but what their defaults allow: FMPy's CVode
//! takes an output point every ~1/1000 of the run (1 ms for a 1 s run) and at most 500 steps
//! between two of them; fmusim and OMSimulator take the DefaultExperiment's step as output
//! interval (or largest step) and their own tolerance (1e-4); the FMI Compliance Checker and
//! fmusim's default integrate explicitly. A lightly damped dynamic mode that CVode's error test
//! sees needs some 40 to 80 steps per period (the bracket, measured with FMPy: 30 kHz modes at
//! 1 % damping pass with 6 periods per output interval and fail with 12), so the dynamic modes
//! must stay below a few periods per output interval of the run the user is likely to start:
//! the DefaultExperiment's and, for users who set their own stop time, the 1 ms output interval
//! of a 1 s run. Modes above are quasi-static (exact in their static response); Co-Simulation
//! still propagates every mode exactly.

use crate::input::spec::Spec;
use crate::reduce::basis::Basis;
use crate::reduce::cutoff::dynamic_cutoff;
use fmu_runtime::reduced::ReducedBody;
use std::f64::consts::PI;

/// Periods of the fastest dynamic mode per output interval that CVode (500 steps between output
/// points) carries with a margin of three to six against the measured failures.
pub const PERIODS_PER_OUTPUT: f64 = 2.0;
/// The output interval a host user most often runs at (FMPy's for a 1 s run, a 1 kHz master).
pub const USUAL_OUTPUT_INTERVAL: f64 = 1e-3;
/// The tolerance the FMU proposes unless the input names one: what Modelica tools and
/// co-simulation masters use or tighter (1e-4 .. 1e-6); the dynamic modes a host resolves at it
/// are accurate to about 1e-3 of the response's swing.
pub const DEFAULT_TOLERANCE: f64 = 1e-6;
/// Output points per period of the slowest mode the default step gives at least: a sampled
/// oscillation shows its shape at ten points a period (at fewer its peaks are cut, at two it
/// aliases). A shorter step shows nothing more: Co-Simulation is exact at any step, and a Model
/// Exchange host's own steps between output points do not depend on it up to
/// USUAL_OUTPUT_INTERVAL.
pub const POINTS_PER_PERIOD: f64 = 10.0;
/// Periods of the slowest mode the default run shows (and at least three of its decay times, up
/// to MOST_PERIODS periods, so a damped body settles within it).
const SLOWEST_PERIODS: f64 = 10.0;
const MOST_PERIODS: f64 = 100.0;

/// The Model Exchange plan: cutoff [rad/s] and why, and the DefaultExperiment.
#[derive(Debug, Clone, PartialEq)]
pub struct HostPlan {
    pub cutoff: f64,
    pub rule: String,
    /// The scene's own cutoff [rad/s] before the host's limit (infinite: every mode).
    pub scene_cutoff: f64,
    /// The fastest dynamic mode a host resolves at the output interval below [rad/s].
    pub host_cutoff: f64,
    pub stop: f64,
    pub step: f64,
    /// Why that step, in words.
    pub step_rule: String,
    pub tolerance: f64,
}

/// The plan for a reduced body (its frequencies and damping; its own `dynamic_cutoff` is not
/// read, so the plan is the same before and after it is set).
pub fn plan(spec: &Spec, basis: &Basis, reduced: &ReducedBody) -> HostPlan {
    let (scene_cutoff, scene_rule) = dynamic_cutoff(spec, basis);
    let experiment = spec.experiment.clone().unwrap_or_default();
    let stop = experiment.stop_time.unwrap_or_else(|| default_stop(reduced));
    let explicit_cutoff = spec.reduction.dynamic_cutoff.is_some();
    // a cutoff the input names sets the output step the host needs for it
    let (step, step_rule) = match experiment.step_size {
        Some(h) => (h, "the input's experiment.step_size".to_string()),
        None => {
            let (auto, why) = default_step(stop, reduced);
            let fits = round_down_125(PERIODS_PER_OUTPUT * 2.0 * PI / scene_cutoff);
            if explicit_cutoff && fits < auto {
                (fits, format!("{PERIODS_PER_OUTPUT} periods of reduction.dynamic_cutoff per output interval"))
            } else {
                (auto, why)
            }
        }
    };
    // the output interval the dynamic modes must fit: the DefaultExperiment's, and a 1 s run's
    // (1 ms) unless the input names the step it runs at
    let interval = if experiment.step_size.is_some() { step } else { step.max(USUAL_OUTPUT_INTERVAL) };
    let host_cutoff = PERIODS_PER_OUTPUT * 2.0 * PI / interval;
    let (cutoff, rule) = if explicit_cutoff || scene_cutoff <= host_cutoff {
        (scene_cutoff, scene_rule.to_string())
    } else {
        // an infinite scene cutoff (a static-only basis) is no bound to name beside a finite one
        let below = if scene_cutoff.is_finite() {
            format!(", below {scene_rule} ({:.4} Hz)", scene_cutoff / (2.0 * PI))
        } else {
            format!("; the scene sets {scene_rule}")
        };
        (
            host_cutoff,
            format!(
                "what a host resolves at an output interval of {interval:.0e} s, {PERIODS_PER_OUTPUT} periods of \
                 the fastest dynamic mode{below}"
            ),
        )
    };
    // the slowest mode stays dynamic whatever the limit: a body without dynamics tells a host
    // nothing it could not get from a static solve
    let (cutoff, rule) = match reduced.omega.first() {
        Some(&w1) if w1 > cutoff && !explicit_cutoff => {
            (w1 * (1.0 + 1e-9), format!("the slowest mode, above what a host resolves ({rule})"))
        }
        _ => (cutoff, rule),
    };
    HostPlan {
        cutoff,
        rule,
        scene_cutoff,
        host_cutoff,
        stop,
        step,
        step_rule,
        tolerance: experiment.tolerance.unwrap_or(DEFAULT_TOLERANCE),
    }
}

/// The default output step of a run of `stop` seconds, and why: the longest 1-2-5 step with
/// POINTS_PER_PERIOD points a period of the slowest mode, at most USUAL_OUTPUT_INTERVAL (beyond
/// it a Model Exchange host's dynamic modes would have to be fewer), and at least FMPy's
/// interval for the run (at most a thousand points).
fn default_step(stop: f64, reduced: &ReducedBody) -> (f64, String) {
    let fmpy = fmpy_output_interval(stop);
    let Some(&w1) = reduced.omega.first().filter(|w| **w > 0.0) else {
        return (fmpy, "FMPy's output interval for the run (a thousandth of it, rounded)".to_string());
    };
    let hz = w1 / (2.0 * PI);
    let resolved = round_down_125(1.0 / (hz * POINTS_PER_PERIOD)).min(USUAL_OUTPUT_INTERVAL);
    let points = |h: f64| 1.0 / (hz * h);
    if resolved < fmpy {
        let why = format!(
            "a thousandth of the run, as FMPy rounds it (the slowest mode, {hz:.4} Hz, has {:.0} points a period)",
            points(fmpy)
        );
        (fmpy, why)
    } else if resolved < USUAL_OUTPUT_INTERVAL {
        let why = format!(
            "the longest 1-2-5 step with at least {POINTS_PER_PERIOD} output points a period of the slowest mode \
             ({hz:.4} Hz: {:.0})",
            points(resolved)
        );
        (resolved, why)
    } else {
        let why = format!(
            "the longest step at which a Model Exchange host keeps the dynamic modes (the slowest mode, {hz:.4} Hz, \
             has {:.0} points a period)",
            points(resolved)
        );
        (resolved, why)
    }
}

/// Ten periods of the slowest mode and three of its decay times (at most a hundred periods),
/// rounded up to 1, 2 or 5 times a power of ten.
fn default_stop(reduced: &ReducedBody) -> f64 {
    let Some(&w1) = reduced.omega.first().filter(|w| **w > 0.0) else { return 1.0 };
    let period = 2.0 * PI / w1;
    let d = reduced.damping_rate(0, reduced.alpha, reduced.beta);
    let settle = if d > 0.0 { 3.0 * 2.0 / d } else { 0.0 };
    round_up_125((SLOWEST_PERIODS * period).max(settle.min(MOST_PERIODS * period)))
}

/// FMPy's output interval for a run of `stop` seconds (simulate_fmu: a power of ten near
/// stop / 1000, doubled until at most 1000 intervals), which fmusim and OMSimulator take from
/// the DefaultExperiment's step: one output grid for every host.
pub fn fmpy_output_interval(stop: f64) -> f64 {
    let mut dt = 10f64.powf(stop.log10().round() - 3.0);
    while stop / dt > 1000.0 * (1.0 + 1e-12) {
        dt *= 2.0;
    }
    dt
}

fn round_up_125(x: f64) -> f64 {
    let decade = 10f64.powf(x.log10().floor());
    [1.0, 2.0, 5.0, 10.0].iter().map(|m| m * decade).find(|v| *v >= x * (1.0 - 1e-12)).unwrap_or(10.0 * decade)
}

fn round_down_125(x: f64) -> f64 {
    let decade = 10f64.powf(x.log10().floor());
    [5.0, 2.0, 1.0].iter().map(|m| m * decade).find(|v| *v <= x * (1.0 + 1e-12)).unwrap_or(decade)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_output_interval_is_fmpys() {
        // fmpy.simulation.simulate_fmu: 10 ** (round(log10(T)) - 3), doubled to <= 1000 points
        assert_eq!(fmpy_output_interval(1.0), 1e-3);
        assert!((fmpy_output_interval(2.0) - 2e-3).abs() < 1e-15);
        assert!((fmpy_output_interval(0.3) - 4e-4).abs() < 1e-15);
        assert!((fmpy_output_interval(0.2) - 2e-4).abs() < 1e-15);
        assert!((fmpy_output_interval(10.0) - 1e-2).abs() < 1e-15);
        assert!((fmpy_output_interval(6.93) - 1e-2).abs() < 1e-15);
    }

    #[test]
    fn rounding_keeps_one_two_five() {
        assert_eq!(round_up_125(0.0168), 0.02);
        assert_eq!(round_up_125(0.2), 0.2);
        assert_eq!(round_up_125(6.93), 10.0);
        assert_eq!(round_up_125(1.0), 1.0);
        assert_eq!(round_down_125(3.3e-4), 2e-4);
        assert_eq!(round_down_125(1e-3), 1e-3);
    }

    #[test]
    fn a_damped_body_runs_until_it_settles_and_an_undamped_one_ten_periods() {
        let mut body = fmu_runtime::reduced::two_mode_body();
        body.alpha = 0.0;
        body.beta = 0.0;
        body.modal_damping.iter_mut().for_each(|d| *d = 0.0);
        let period = 2.0 * PI / body.omega[0];
        let undamped = default_stop(&body);
        assert_eq!(undamped, round_up_125(10.0 * period));
        // 1 % damping: three decay times are 3 / (0.01 omega) = 48 periods
        body.modal_damping[0] = 2.0 * 0.01 * body.omega[0];
        let damped = default_stop(&body);
        assert_eq!(damped, round_up_125(3.0 / (0.01 * body.omega[0])));
        assert!(damped > undamped);
        // 0.01 % damping rings longer than a hundred periods: capped there
        body.modal_damping[0] = 2.0 * 1e-4 * body.omega[0];
        assert_eq!(default_stop(&body), round_up_125(100.0 * period));
    }
}
