//! The dynamic cutoff: the frequency above which a reduced mode is quasi-static in Model
//! Exchange. Such modes keep their static contribution exactly (they are solved from the loads
//! at every evaluation) but give the host's integrator no states, so its step is bounded by the
//! scene's dynamics rather than by the highest reduced frequency (constraint modes of a stiff part
//! reach 1e5 Hz, where a lightly damped mode defeats BDF and explicit hosts alike).

use crate::input::spec::{Method, Role, Spec};
use crate::reduce::basis::Basis;
use std::f64::consts::PI;

/// Default cutoff as a multiple of the scene band's upper edge: a mode at ten times the highest
/// frequency of interest answers it within 1 % of its static response ((f/f_k)^2 = 1e-2), and that
/// mode's contribution is itself a small part of the response.
pub const BAND_MULTIPLE: f64 = 10.0;

/// Ritz frequencies of the kept normal modes lie at or below the normal modes themselves
/// (min-max); this margin only absorbs round-off where they are equal.
const ROUND_OFF: f64 = 1e-6;

/// The cutoff [rad/s] and how it was chosen: the input's `reduction.dynamic_cutoff` [Hz]; else
/// `BAND_MULTIPLE` times the scene band's upper edge; else the highest kept normal mode (fixed-
/// interface, mounted or free-free), so that constraint modes, residual-flexibility and load shapes
/// are quasi-static; else (Krylov) `BAND_MULTIPLE` times the highest expansion frequency; with only
/// the static point the scene sets no cutoff (infinite: what a host resolves decides).
pub fn dynamic_cutoff(spec: &Spec, basis: &Basis) -> (f64, &'static str) {
    if let Some(hz) = spec.reduction.dynamic_cutoff {
        return (2.0 * PI * hz, "reduction.dynamic_cutoff");
    }
    if let Some([_, hi]) = spec.scene.as_ref().and_then(|s| s.band) {
        return (BAND_MULTIPLE * 2.0 * PI * hi, "ten times the scene band's upper edge");
    }
    let kept = basis.n_normal.min(basis.fixed_interface_omega.len());
    if kept > 0 {
        let highest = basis.fixed_interface_omega[..kept].iter().fold(0.0f64, |m, &w| m.max(w));
        let mounted = spec.flanges.iter().any(|f| f.role == Role::Motion);
        let what = match spec.reduction.method {
            _ if !mounted => "the highest free-free mode",
            Method::CraigBampton => "the highest fixed-interface mode",
            _ => "the highest kept normal mode",
        };
        return (highest * (1.0 + ROUND_OFF), what);
    }
    let highest_point = spec.reduction.expansion_points.iter().flatten().fold(0.0f64, |m, &f| m.max(f));
    if highest_point > 0.0 {
        return (BAND_MULTIPLE * 2.0 * PI * highest_point, "ten times the highest expansion point");
    }
    (f64::INFINITY, "no cutoff (no normal mode, band or expansion point)")
}
