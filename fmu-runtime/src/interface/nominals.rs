//! The nominals of the modal states.

use crate::reduced::ReducedBody;

/// The fraction of a mode's unit static response that its nominal is. Hosts take
/// atol = rtol x nominal. Once a lightly damped mode has settled on a static load, the relative
/// part rtol |q| of the error test is as large as the deflection, and only atol keeps the host
/// from stepping over the mode's ringing: with the unit response itself as nominal, FMPy's CVode
/// at rtol 1e-4 left the bracket ringing at 16 % of the swing of its mount force a second after a
/// gravity step (steps longer than the period alias the oscillation, and the error test does not
/// see it); at 1e-2 of it 5e-3, at 1e-3 2.3e-3, smaller fractions gain nothing (the relative
/// part takes over) at the same cost (`tests/test_me_host_defaults.py`, the benchmark
/// `bench/me_host_defaults.py`).
pub const NOMINAL_FRACTION: f64 = 1e-3;

/// The nominal of each modal coordinate: NOMINAL_FRACTION of its largest static response to a
/// unit force or torque (1 N, 1 N m) at a force flange and to 1 g of the mount's acceleration or
/// gravity along any axis, |p_k| / omega_k^2. A mode no such load excites gets 1e-6 of the
/// largest (a nominal must be positive).
pub fn modal_nominals(body: &ReducedBody) -> Vec<f64> {
    const G: f64 = 9.81;
    let n = body.n_modes();
    let mut out: Vec<f64> = (0..n)
        .map(|k| {
            let mut load = 0.0f64;
            for flange in &body.flanges {
                for row in 0..6 {
                    load = load.max(flange.shapes[row * n + k].abs());
                }
            }
            for a in 0..3 {
                load = load.max(G * body.c_t[a * n + k].abs());
            }
            let w2 = body.omega[k] * body.omega[k];
            if w2 > 0.0 && load.is_finite() { load / w2 } else { 0.0 }
        })
        .collect();
    let largest = out.iter().fold(0.0f64, |m, v| m.max(*v));
    let floor = if largest > 0.0 { 1e-6 * largest } else { 1.0 };
    for v in out.iter_mut() {
        *v = NOMINAL_FRACTION * v.max(floor);
    }
    out
}
