//! How far the FMU can be trusted, as figures (report.json's `verdict`) and in words (the same
//! sentences in the printed summary and on the documentation page). The figures of the accuracy
//! comparison alone ("transfer functions within 1.4e0 over the band") read as "the model is 140 %
//! wrong" when the band reaches beyond what the reduction keeps; the verdict says up to which
//! frequency the reduced model matches the full FE model within a tolerance, how well, and that
//! above it the model is not meant to hold.

use crate::output::plot::esc;
use crate::reduce::accuracy::Accuracy;
use serde::Serialize;

/// The tolerance of the valid range when the scene names none: 1 %, the accuracy a reader of "the
/// model holds" assumes, and ten times what the flange responses of the examples' kept modes
/// reach between their resonances.
pub const DEFAULT_TOLERANCE: f64 = 1e-2;

/// What limits the valid range.
pub const BY_RESPONSE: &str = "flange response";
pub const BY_FREQUENCIES: &str = "eigenfrequencies";
pub const BY_BAND: &str = "band";
pub const BY_MODES_COMPUTED: &str = "modes computed";

#[derive(Debug, Clone, Default, Serialize)]
pub struct Verdict {
    /// The relative error the valid range is measured against (scene.tolerance, else 1e-2).
    pub tolerance: f64,
    /// Upper end of the valid range [Hz]; it starts at 0 (statics are exact, see the compliance).
    /// 0: not even the lowest compared frequency holds.
    pub valid_range_hz: f64,
    /// What ends it: "flange response" (the next compared frequency is off by more than the
    /// tolerance), "eigenfrequencies" (the next full mode is), "band" (everything compared holds:
    /// the band's top, nothing is claimed above), "modes computed" (no transfer functions
    /// compared; every computed mode holds).
    pub limited_by: String,
    /// Largest relative error of the flange transfer functions at the compared frequencies up
    /// to the valid range's end (None: none compared there).
    pub response_error: Option<f64>,
    /// Largest relative error of the stress responses at the recovery points there.
    pub stress_error: Option<f64>,
    /// Largest |relative error| of the eigenfrequencies (reduced vs full, mode by mode) of the
    /// full modes up to the valid range's end, and how many they are.
    pub frequency_error: Option<f64>,
    pub modes_within: usize,
    /// The static flange compliance's deviation (exact by construction: round-off).
    pub static_error: f64,
    /// Where the valid range ends: the first frequency beyond it [Hz] and the error there
    /// (None where the band or the computed modes end it).
    pub first_outside_hz: Option<f64>,
    pub first_outside_error: Option<f64>,
    /// Where the flange response ends the range at a full mode's resonance (within 2 % of its
    /// frequency, the flank of a peak a few half-power widths wide at 1 % damping): that mode [Hz] and how far the reduced model misses its frequency. A lightly
    /// damped peak turns a small shift of it into a large response error (the bracket: 1.6e-4 of
    /// frequency, 3.2e-2 of response at 1 % damping), which the reader should know.
    pub resonance_hz: Option<f64>,
    pub resonance_frequency_error: Option<f64>,
    /// The band the transfer functions were compared over [Hz] and why that band.
    pub band_hz: Option<[f64; 2]>,
    pub band_rule: Option<String>,
}

/// The verdict of an accuracy comparison at `tolerance` (None: `DEFAULT_TOLERANCE`). The valid
/// range ends below the first full mode whose frequency the reduced model misses by more than
/// the tolerance (mode by mode, lowest first) and, where transfer functions were compared, at the
/// last compared frequency of the unbroken run from the lowest up whose error stays within it.
pub fn of(a: &Accuracy, tolerance: Option<f64>) -> Verdict {
    let tol = tolerance.unwrap_or(DEFAULT_TOLERANCE);
    let n = a.relative_error.len().min(a.full_hz.len());
    // NaN fails the comparison, so a broken figure ends the range rather than hiding in it
    let matched = a.relative_error[..n].iter().take_while(|e| e.abs() <= tol).count();
    let mismatch = (matched < n).then(|| (a.full_hz[matched], a.relative_error[matched].abs()));
    let mut v = Verdict { tolerance: tol, static_error: a.compliance_max_relative_error, ..Default::default() };
    match &a.frequency_response {
        Some(fr) if !fr.frequencies_hz.is_empty() => {
            let (f, e) = (&fr.frequencies_hz, &fr.relative_error);
            let below_mismatch = |hz: f64| mismatch.is_none_or(|(m, _)| hz < m);
            let ok = f.iter().zip(e).take_while(|(hz, err)| **err <= tol && below_mismatch(**hz)).count();
            v.band_hz = Some(fr.band_hz);
            v.valid_range_hz = if ok == f.len() && below_mismatch(fr.band_hz[1]) {
                v.limited_by = BY_BAND.into();
                fr.band_hz[1]
            } else {
                match f.get(ok) {
                    Some(&hz) if below_mismatch(hz) => {
                        v.limited_by = BY_RESPONSE.into();
                        v.first_outside_hz = Some(hz);
                        v.first_outside_error = Some(e[ok]);
                        // a shifted peak's error reaches a few half-power widths (+-0.5 % at the
                        // comparison's 1 % damping) from it: the bracket's 1.2e-2 at 1.1 % below
                        let near = (0..n).find(|&i| (a.full_hz[i] - hz).abs() <= 2e-2 * a.full_hz[i]);
                        v.resonance_hz = near.map(|i| a.full_hz[i]);
                        v.resonance_frequency_error = near.map(|i| a.relative_error[i].abs());
                    }
                    _ => {
                        v.limited_by = BY_FREQUENCIES.into();
                        v.first_outside_hz = mismatch.map(|m| m.0);
                        v.first_outside_error = mismatch.map(|m| m.1);
                    }
                }
                if ok == 0 { 0.0 } else { f[ok - 1] }
            };
            let max = |x: &[f64]| x.iter().copied().reduce(f64::max);
            v.response_error = max(&e[..ok]);
            v.stress_error = max(&fr.stress_relative_error[..ok.min(fr.stress_relative_error.len())]);
        }
        _ => {
            v.valid_range_hz = if matched > 0 { a.full_hz[matched - 1] } else { 0.0 };
            v.limited_by = if mismatch.is_some() { BY_FREQUENCIES } else { BY_MODES_COMPUTED }.into();
            v.first_outside_hz = mismatch.map(|m| m.0);
            v.first_outside_error = mismatch.map(|m| m.1);
        }
    }
    let within: Vec<f64> =
        (0..n).filter(|&i| a.full_hz[i] <= v.valid_range_hz).map(|i| a.relative_error[i].abs()).collect();
    v.modes_within = within.len();
    v.frequency_error = within.into_iter().reduce(f64::max);
    v
}

/// A tolerance as a reader says it: 1e-2 -> "1 %", 1e-3 -> "0.1 %", 1e-5 -> "1e-5".
fn tolerance_words(tol: f64) -> String {
    if tol >= 1e-3 {
        let s = format!("{:.3}", 100.0 * tol);
        format!("{} %", s.trim_end_matches('0').trim_end_matches('.'))
    } else {
        format!("{tol:.0e}")
    }
}

/// The verdict in one sentence (no trailing period): the valid range, the errors within it, and
/// that above it the model is not meant to hold.
pub fn sentence(v: &Verdict) -> String {
    let tol = tolerance_words(v.tolerance);
    if v.valid_range_hz <= 0.0 {
        let at = match (v.first_outside_hz, v.first_outside_error) {
            (Some(f), Some(e)) => format!(": the {} is off by {e:.1e} at {f:.1} Hz", v.limited_by),
            _ => String::new(),
        };
        return format!(
            "no valid range at {tol}: not even the lowest compared frequency holds{at}; only the static response is \
             exact (compliance within {:.1e}), the dynamics are not meant to hold",
            v.static_error
        );
    }
    let mut held = Vec::new();
    if let Some(e) = v.response_error {
        held.push(format!("flange response within {e:.1e}"));
    }
    if let Some(e) = v.stress_error {
        held.push(format!("stress responses within {e:.1e}"));
    }
    if let Some(e) = v.frequency_error {
        let modes = if v.modes_within == 1 {
            "1 eigenfrequency".to_string()
        } else {
            format!("{} eigenfrequencies", v.modes_within)
        };
        held.push(format!("{modes} within {e:.1e}"));
    }
    let held = match held.len() {
        0 => "the response".to_string(),
        1 => held.remove(0),
        _ => {
            let last = held.pop().unwrap_or_default();
            format!("{} and {last}", held.join(", "))
        }
    };
    let why = match (v.limited_by.as_str(), v.first_outside_hz, v.first_outside_error) {
        (BY_BAND, ..) => " (the top of the compared band: nothing above it was compared)".to_string(),
        (BY_MODES_COMPUTED, ..) => " (the highest full mode computed: nothing above it was compared)".to_string(),
        (BY_RESPONSE, Some(f), Some(e)) => match (v.resonance_hz, v.resonance_frequency_error) {
            (Some(r), Some(fe)) => format!(
                " (the flange response is off by {e:.1e} at {f:.1} Hz, at the resonance of the full model's mode at \
                 {r:.1} Hz: the reduced model misses its frequency by {fe:.1e}, which the lightly damped peak magnifies)"
            ),
            _ => format!(" (the flange response is off by {e:.1e} at {f:.1} Hz)"),
        },
        (BY_FREQUENCIES, Some(f), Some(e)) => format!(" (the full model's mode at {f:.1} Hz is missed by {e:.1e})"),
        _ => String::new(),
    };
    format!(
        "{held} of the full FE model up to {:.1} Hz, the model's valid range at {tol}; above it the reduction is not \
         meant to hold{why}",
        v.valid_range_hz
    )
}

/// Which band the transfer functions were compared over and why (None without a comparison).
pub fn band_sentence(v: &Verdict) -> Option<String> {
    let b = v.band_hz?;
    let rule = v.band_rule.as_deref().map(|r| format!(": {r}")).unwrap_or_default();
    Some(format!("transfer functions compared with the full FE model over {:.1}..{:.1} Hz{rule}", b[0], b[1]))
}

/// The documentation's paragraph: the verdict and the band, as the summary says them.
pub fn html(v: &Verdict) -> String {
    let mut h = format!("<h3>How far the FMU can be trusted</h3>\n<p>{}.</p>\n", esc(&sentence(v)));
    if let Some(band) = band_sentence(v) {
        h.push_str(&format!("<p>The {}.</p>\n", esc(&band)));
    }
    h
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::reduce::frf::{ComparisonDamping, FrequencyResponse};

    fn accuracy(full_hz: Vec<f64>, relative_error: Vec<f64>, frf: Option<(Vec<f64>, Vec<f64>)>) -> Accuracy {
        Accuracy {
            reduced_hz: full_hz.iter().zip(&relative_error).map(|(f, e)| f * (1.0 + e)).collect(),
            full_hz,
            relative_error,
            compliance_flanges: Vec::new(),
            compliance_full: Vec::new(),
            compliance_reduced: Vec::new(),
            compliance_max_relative_error: 1e-14,
            inertial_cases: Vec::new(),
            inertial_flange_response_full: Vec::new(),
            frequency_response: frf.map(|(f, e)| FrequencyResponse {
                band_hz: [0.0, 100.0],
                damping: ComparisonDamping::new(0.0, 0.0),
                max_relative_error: e.iter().copied().fold(0.0, f64::max),
                frequencies_hz: f,
                relative_error: e,
                driving_point_full: Vec::new(),
                driving_point_reduced: Vec::new(),
                full_matrices: Vec::new(),
                stress_relative_error: Vec::new(),
                stress_full: Vec::new(),
                method: String::new(),
            }),
            pairs: Vec::new(),
        }
    }

    #[test]
    fn the_range_ends_before_the_first_frequency_off_by_more_than_the_tolerance() {
        let a = accuracy(
            vec![10.0, 40.0, 90.0],
            vec![1e-5, 2e-3, 5e-2],
            Some((vec![5.0, 10.0, 30.0, 50.0, 70.0], vec![1e-6, 3e-3, 1e-3, 2e-2, 1e-3])),
        );
        let v = of(&a, None);
        // 50 Hz breaks the run: 70 Hz, within again, is not claimed
        assert_eq!((v.valid_range_hz, v.limited_by.as_str()), (30.0, BY_RESPONSE));
        assert_eq!((v.response_error, v.first_outside_hz, v.first_outside_error), (Some(3e-3), Some(50.0), Some(2e-2)));
        assert_eq!((v.modes_within, v.frequency_error), (1, Some(1e-5)));
        assert_eq!((v.resonance_hz, v.resonance_frequency_error), (None, None));
        let s = sentence(&v);
        assert!(s.contains("up to 30.0 Hz") && s.contains("within 3.0e-3") && s.contains("not meant to hold"), "{s}");
    }

    #[test]
    fn a_resonance_peak_that_ends_the_range_is_named_with_its_frequency_error() {
        let a = accuracy(vec![10.0, 40.0], vec![1e-5, 2e-4], Some((vec![5.0, 39.8, 40.0], vec![1e-6, 2e-2, 3e-2])));
        let v = of(&a, None);
        assert_eq!((v.valid_range_hz, v.resonance_hz, v.resonance_frequency_error), (5.0, Some(40.0), Some(2e-4)));
        assert!(sentence(&v).contains("mode at 40.0 Hz: the reduced model misses its frequency by 2.0e-4"));
    }

    #[test]
    fn a_missed_eigenfrequency_ends_the_range_where_the_response_would_not() {
        let a = accuracy(vec![10.0, 40.0], vec![1e-5, 2e-2], Some((vec![5.0, 10.0, 30.0, 50.0], vec![1e-6; 4])));
        let v = of(&a, None);
        assert_eq!((v.valid_range_hz, v.limited_by.as_str(), v.first_outside_hz), (30.0, BY_FREQUENCIES, Some(40.0)));
    }

    #[test]
    fn everything_within_claims_the_band_and_no_more() {
        let a = accuracy(vec![10.0, 400.0], vec![1e-5, 1e-4], Some((vec![5.0, 10.0, 99.0], vec![1e-6, 1e-5, 1e-4])));
        let v = of(&a, Some(1e-3));
        assert_eq!((v.valid_range_hz, v.limited_by.as_str(), v.modes_within), (100.0, BY_BAND, 1));
        assert!(sentence(&v).contains("at 0.1 %"), "{}", sentence(&v));
    }

    #[test]
    fn nothing_within_says_so() {
        let a = accuracy(vec![10.0], vec![1e-5], Some((vec![5.0, 10.0], vec![0.5, 1e-6])));
        let v = of(&a, None);
        assert_eq!((v.valid_range_hz, v.response_error), (0.0, None));
        assert!(sentence(&v).starts_with("no valid range at 1 %"), "{}", sentence(&v));
    }

    #[test]
    fn the_documentation_says_the_summary_s_sentence_and_the_band() {
        let a = accuracy(vec![10.0], vec![1e-5], Some((vec![5.0, 10.0], vec![1e-6, 2e-6])));
        let mut v = of(&a, None);
        v.band_rule = Some("the scene's band (scene.band)".into());
        let h = html(&v);
        assert!(h.contains(&esc(&sentence(&v))) && h.contains("over 0.0..100.0 Hz: the scene&#39;s band"), "{h}");
    }

    #[test]
    fn without_transfer_functions_the_frequencies_decide() {
        let a = accuracy(vec![10.0, 40.0, 90.0], vec![1e-5, 2e-3, f64::NAN], None);
        let v = of(&a, None);
        assert_eq!((v.valid_range_hz, v.limited_by.as_str(), v.modes_within), (40.0, BY_FREQUENCIES, 2));
        assert_eq!(v.frequency_error, Some(2e-3));
    }
}
