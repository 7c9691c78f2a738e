//! What Model Exchange integrates and why, in words: the same sentences in the summary and in
//! the FMU's documentation, so the two never disagree.

use crate::output::report::Report;
use crate::reduce::experiment::{PERIODS_PER_OUTPUT, USUAL_OUTPUT_INTERVAL};

/// The sentences, plain text (the documentation escapes them).
pub fn sentences(r: &Report) -> Vec<String> {
    let mut out = Vec::new();
    let quasi_static = r.order - r.dynamic_modes;
    let e = &r.default_experiment;
    match r.dynamic_cutoff_hz {
        Some(hz) if quasi_static > 0 => {
            let relaxing = if r.relaxing_modes > 0 {
                format!(
                    " ({} of them relaxing: damped slower than the cutoff, one state each; {} states in all)",
                    r.relaxing_modes,
                    2 * r.dynamic_modes + r.relaxing_modes
                )
            } else {
                String::new()
            };
            out.push(format!(
                "Model Exchange: {} dynamic modes (states q, qd) up to {hz:.4} Hz, {quasi_static} quasi-static above \
                 (no states: solved from the loads at every evaluation, their static response exact){relaxing}; \
                 cutoff: {}.",
                r.dynamic_modes, r.dynamic_cutoff_rule
            ));
            if r.scene_cutoff_hz.is_none_or(|s| s > hz * (1.0 + 1e-9)) && r.host_cutoff_hz <= hz * (1.0 + 1e-9) {
                out.push(format!(
                    "Why: a Model Exchange host at its defaults (an output point every {:.0e} s or 1 ms, at most 500 \
                     solver steps between two, tolerance 1e-4 to 1e-6) integrates about {PERIODS_PER_OUTPUT} periods \
                     of a lightly damped mode per output interval; faster dynamic modes stop CVode (\"mxstep\") or \
                     lose accuracy. Co-Simulation propagates all {} modes exactly at any step. To keep more modes \
                     dynamic in Model Exchange, set reduction.dynamic_cutoff [Hz] (the default experiment's step \
                     follows it) and run the host at that output interval. What the lower cutoff costs: a \
                     quasi-static mode has no velocity in Model Exchange, so under a changing load the flange \
                     velocities miss the rate of its static correction (the L-beam example under a 2 Hz sine: \
                     4.9e-3 of its tip angular velocity's swing at its 200 Hz cutoff, 4.5e-4 with every normal \
                     mode dynamic).",
                    e.step_size.max(USUAL_OUTPUT_INTERVAL),
                    r.order
                ));
            }
        }
        _ => out.push(format!(
            "Model Exchange: all {} modes dynamic ({} states); Co-Simulation propagates them exactly.",
            r.order,
            2 * r.order
        )),
    }
    out.push(format!(
        "Default experiment: stop {:e} s, tolerance {:.0e}, step {:e} s: {}. Co-Simulation is exact at any step, \
         so a master may take longer ones.",
        e.stop_time, e.tolerance, e.step_size, r.default_step_rule
    ));
    if r.undamped_dynamic_modes > 0 {
        out.push(format!(
            "{} dynamic modes are undamped: a variable-step host's error in them grows with every period they ring \
             (the undamped L-beam example, 10 s: 1.4e-3 of its tip's angular velocity swing at tolerance 1e-6, \
             1e-2 over 2 s at 1e-4). Ask for a tighter tolerance with experiment.tolerance (1e-8), add damping, or \
             use Co-Simulation (exact at any step); the FMU warns a host that sets a tolerance looser than 1e-6.",
            r.undamped_dynamic_modes
        ));
    }
    out.push(if r.explicit_euler_step > 0.0 {
        format!(
            "Explicit fixed-step hosts (Euler) need a step below {:.2e} s (mode at {:.4} Hz); the FMU warns at the \
             host's first steps when its step is longer.",
            r.explicit_euler_step,
            r.explicit_euler_mode_hz.unwrap_or(f64::NAN)
        )
    } else {
        format!(
            "Explicit fixed-step hosts (Euler) cannot carry it: the dynamic mode at {:.4} Hz is undamped, and every \
             explicit Euler step multiplies its amplitude by sqrt(1 + (h omega)^2); the FMU warns at the host's \
             first steps. Use a variable-step implicit solver (CVode, BDF) or Co-Simulation.",
            r.explicit_euler_mode_hz.unwrap_or(f64::NAN)
        )
    });
    out
}
