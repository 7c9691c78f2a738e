//! Which band the report's frequency-response comparison covers, and why.

use crate::input::spec::Spec;
use crate::reduce::basis::Basis;
use crate::reduce::cutoff::{BAND_MULTIPLE, dynamic_cutoff};
use std::f64::consts::PI;

/// Ratio of the highest full mode computed to the top of the band compared when the scene names
/// none: those modes are then all the band method needs (no eigen-solve of its own), and the
/// rest converges by (1/3)^2 per Krylov block.
pub const DEFAULT_CUT: f64 = 3.0;

/// The band of the scene, or 0 to the tenth eigenfrequency of the mounted body.
pub fn band_of(spec: &Spec, full_hz: &[f64]) -> [f64; 2] {
    spec.scene
        .as_ref()
        .and_then(|s| s.band)
        .unwrap_or_else(|| [0.0, full_hz.get(9).or(full_hz.last()).copied().unwrap_or(1.0)])
}

/// The band compared when the scene names none, and why: the range the model claims to
/// represent, a tenth of its dynamic cutoff (the highest kept normal mode unless the input names
/// the cutoff), as a scene band's cutoff is ten times the band: the modes left out answer there
/// within 1 % of their static response, which the static shapes carry exactly. Compared above it,
/// the transfer functions measure what the reduction never meant to represent (the bracket, kept
/// modes to 19 kHz: 1.2e-1 over the former default band to 10 kHz, the comparison's error figure
/// read as "12 % wrong"; the verdict now finds 0.3 % up to 0.9 kHz within this band).
/// At most a third of the highest full mode computed, whose modes are then all the band method
/// needs; a reduction without a finite cutoff (Krylov at s = 0 only) is compared up to there.
pub fn default_band(spec: &Spec, basis: &Basis, full_hz: &[f64]) -> ([f64; 2], String) {
    let computed = full_hz.last().copied().unwrap_or(1.0) / DEFAULT_CUT;
    let (cutoff, rule) = dynamic_cutoff(spec, basis);
    let claimed = cutoff / (2.0 * PI * BAND_MULTIPLE);
    if claimed.is_finite() && claimed < computed {
        let hz = cutoff / (2.0 * PI);
        (
            [0.0, claimed],
            format!(
                "by default a tenth of the reduction's cutoff ({rule}, {hz:.1} Hz), the range the reduction is built \
                 for: the modes it leaves out answer there within 1 % of their static response, which its static \
                 shapes carry exactly (scene.band compares another)"
            ),
        )
    } else {
        (
            [0.0, computed],
            format!(
                "by default a third of the highest full mode computed ({:.1} Hz): the reduction names no dynamic \
                 cutoff below it (scene.band compares another)",
                DEFAULT_CUT * computed
            ),
        )
    }
}

/// The band the comparison covers and the rule that chose it: the scene's band; with a
/// tolerance but no band, the order selection's band; otherwise `default_band`. `named`: the
/// scene names a band or a tolerance.
pub fn compared_band(spec: &Spec, basis: &Basis, full_hz: &[f64]) -> ([f64; 2], String, bool) {
    let named = spec.scene.as_ref().is_some_and(|s| s.band.is_some() || s.tolerance.is_some());
    let (band, rule) = match (named, spec.scene.as_ref().and_then(|s| s.band)) {
        (true, Some(band)) => (band, "the scene's band (scene.band)".to_string()),
        (true, None) => (
            band_of(spec, full_hz),
            "0 to the mounted body's tenth eigenfrequency, the band of the order selection (scene.tolerance \
             without scene.band)"
                .to_string(),
        ),
        (false, _) => default_band(spec, basis, full_hz),
    };
    (band, rule, named)
}
