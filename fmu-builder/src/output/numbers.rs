//! Numbers as the summary and the documentation print them: without a sign on a zero, and
//! without round-off residue posing as a value.

/// `v` with `decimals` places, where a value that rounds to zero (-0.0, -1e-9) prints as 0: a
/// minus sign on a zero reads as a direction the part does not have.
pub fn fixed(v: f64, decimals: usize) -> String {
    let s = format!("{v:.decimals$}");
    match s.strip_prefix('-') {
        Some(magnitude) if magnitude.chars().all(|c| c == '0' || c == '.') => magnitude.to_string(),
        _ => s,
    }
}

/// Below this fraction of the largest entry of a vector or tensor an entry is round-off of the
/// assembly (a beam's products of inertia come out at 1e-18 next to 0.5 kg m^2), not a value.
const ROUND_OFF: f64 = 1e-12;

/// The entries of `values` in scientific notation with six places, those below round-off of
/// the largest printed as 0 (never -0).
pub fn scientific(values: &[f64]) -> Vec<String> {
    let largest = values.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    values.iter().map(|&v| if v.abs() <= ROUND_OFF * largest { "0".to_string() } else { format!("{v:.6e}") }).collect()
}

#[cfg(test)]
mod tests {
    use super::{fixed, scientific};

    #[test]
    fn zeros_print_without_a_sign() {
        assert_eq!(fixed(-0.0, 6), "0.000000");
        assert_eq!(fixed(-4e-9, 6), "0.000000");
        assert_eq!(fixed(-4e-6, 6), "-0.000004");
        assert_eq!(fixed(0.0300745, 6), "0.030075");
        assert_eq!(fixed(-1.0, 0), "-1");
    }

    #[test]
    fn round_off_prints_as_zero() {
        let printed = scientific(&[6.541667e-5, -9.431712e-19, -0.0, 0.5233464]);
        assert_eq!(printed, ["6.541667e-5", "0", "0", "5.233464e-1"]);
        // a genuinely small entry stays
        assert_eq!(scientific(&[1.0, 2e-9]), ["1.000000e0", "2.000000e-9"]);
    }
}
