//! The default experiment the FMU proposes to its hosts: a run of ten periods of the slowest
//! mode, and the relative tolerance the body's dynamic modes need over it.
//!
//! A damped mode forgets the integrator's error within a few decay times; an undamped one (or
//! one damped so lightly that it rings on through the run) carries every step's local error to
//! the end, so the error a host's variable-step solver leaves grows with the number of periods
//! the longest-ringing mode completes. Measured with FMPy's CVode (ME, force step, worst flange
//! output against an exact Co-Simulation, as a fraction of its swing): the undamped free block
//! (modes to 221 Hz, 0.2 s, 44 periods) 5.1e-3 at rtol 1e-6, 4.9e-5 at 1e-8; the undamped
//! L-beam (74 dynamic modes to 4.3 kHz, 1 s, 4300 periods) 0.11 at 1e-6, 1.6e-2 at 1e-8, 4.3e-4
//! at 1e-10 - about 100 rtol per period or less. The damped examples (Rayleigh, 1 % modal)
//! hold 1e-4 at rtol 1e-6.

use fmu_runtime::reduced::ReducedBody;
use std::f64::consts::PI;

/// The tolerance for bodies whose dynamic modes settle within a few periods.
pub const DAMPED_TOLERANCE: f64 = 1e-6;
/// The error the tolerance aims at, as a fraction of an output's swing, with ERROR_PER_PERIOD.
const TARGET_ERROR: f64 = 1e-3;
/// Error per ringing period and unit tolerance (the measured 100, see above).
const ERROR_PER_PERIOD: f64 = 100.0;
/// Below this, double precision's round-off in the states takes over from the tolerance.
const TIGHTEST_TOLERANCE: f64 = 1e-12;

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DefaultExperiment {
    pub stop: f64,
    pub tolerance: f64,
    /// Periods the longest-ringing dynamic mode completes within the run (before its amplitude
    /// has decayed by e).
    pub ringing_periods: f64,
}

pub fn default_experiment(reduced: &ReducedBody) -> DefaultExperiment {
    let slowest = reduced.omega.first().copied().filter(|w| *w > 0.0).unwrap_or(1.0);
    let stop = (10.0 * 2.0 * PI / slowest).max(1e-3);
    let ringing_periods = (0..reduced.n_dynamic())
        .map(|j| ringing_periods(reduced.omega[j], reduced.damping_rate(j, reduced.alpha, reduced.beta), stop))
        .fold(0.0, f64::max);
    DefaultExperiment { stop, tolerance: tolerance_for(ringing_periods), ringing_periods }
}

/// The power of ten at or below TARGET_ERROR / (ERROR_PER_PERIOD periods), between
/// TIGHTEST_TOLERANCE and DAMPED_TOLERANCE.
fn tolerance_for(periods: f64) -> f64 {
    let wanted = (TARGET_ERROR / (ERROR_PER_PERIOD * periods.max(1.0))).min(DAMPED_TOLERANCE);
    // the small margin keeps an exact power of ten (1e-5 / 10 periods) from rounding down
    10f64.powf((wanted.log10() + 1e-9).floor()).max(TIGHTEST_TOLERANCE)
}

/// Periods a mode of q'' + d q' + omega^2 q = 0 completes within `stop` before its amplitude
/// decays by e (zero when it does not oscillate).
fn ringing_periods(omega: f64, d: f64, stop: f64) -> f64 {
    let damped2 = omega * omega - 0.25 * d * d;
    if damped2 <= 0.0 {
        return 0.0;
    }
    let decay_time = if d > 0.0 { 2.0 / d } else { f64::INFINITY };
    damped2.sqrt() / (2.0 * PI) * stop.min(decay_time)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn undamped_modes_ring_through_the_run_and_damped_ones_for_their_decay_time() {
        // undamped: every period of the run
        assert!((ringing_periods(2.0 * PI * 100.0, 0.0, 2.0) - 200.0).abs() < 1e-9);
        // 1 % of critical: 1 / (2 pi zeta sqrt(1 - zeta^2)) periods, about 15.9, whatever the run
        let w = 2.0 * PI * 500.0;
        let n = ringing_periods(w, 2.0 * 0.01 * w, 100.0);
        assert!((n - (1.0 - 1e-4f64).sqrt() / (2.0 * PI * 0.01)).abs() < 1e-9, "{n}");
        // overdamped: no ringing
        assert_eq!(ringing_periods(10.0, 30.0, 1.0), 0.0);
    }

    #[test]
    fn an_undamped_body_asks_for_the_tight_tolerance_and_a_damped_one_does_not() {
        let mut body = fmu_runtime::reduced::two_mode_body();
        body.alpha = 0.0;
        body.beta = 0.0;
        body.modal_damping.iter_mut().for_each(|d| *d = 0.0);
        body.dynamic_cutoff = f64::INFINITY;
        let undamped = default_experiment(&body);
        let fastest = body.omega.last().unwrap() / (2.0 * PI);
        let expected = fastest * undamped.stop;
        assert!((undamped.ringing_periods - expected).abs() < 1e-9 * expected, "{undamped:?}");
        // 318 Hz over ten periods of 1.6 Hz: 2000 periods, 1e-3 / (100 * 2000) = 5e-9 -> 1e-9
        assert!((expected - 2000.0).abs() < 1e-6, "{expected}");
        assert_eq!(undamped.tolerance, 1e-9);
        // 5 % of critical on every mode: about 3 periods each
        for (j, w) in body.omega.clone().iter().enumerate() {
            body.modal_damping[j] = 2.0 * 0.05 * w;
        }
        let damped = default_experiment(&body);
        assert!(damped.ringing_periods < 4.0, "{damped:?}");
        assert_eq!(damped.tolerance, DAMPED_TOLERANCE);
    }

    #[test]
    fn the_tolerance_falls_a_decade_per_decade_of_ringing_periods() {
        assert_eq!(tolerance_for(0.0), 1e-6);
        assert_eq!(tolerance_for(10.0), 1e-6);
        assert_eq!(tolerance_for(11.0), 1e-7);
        assert_eq!(tolerance_for(21.7), 1e-7);
        assert_eq!(tolerance_for(29791.0), 1e-10);
        assert_eq!(tolerance_for(1e12), 1e-12);
    }
}
