//! Physical ranges of the numbers a user gives. The schema only asks for positive numbers, and
//! an absurd but finite value (E = 1e-300 Pa, a damping ratio of 1e300) builds an FMU whose every
//! output is NaN, or an eigenproblem no solver converges on. These ranges cover every real
//! engineering material and every damping a structure has, and keep the reduced equations
//! finite in double precision; a value outside is refused with its field and range.

/// Young's modulus [Pa]: from soft gels and open-cell foams (about 1e3 Pa; 1e2 leaves a decade
/// for the softest tissues) to diamond and carbon nanotubes (about 1.2e12 Pa; 1e13 leaves a
/// decade). A value far outside is a unit slip (MPa for Pa) or a typo.
pub const E_RANGE: (f64, f64) = (1e2, 1e13);

/// Density [kg/m^3]: from aerogels (about 1 kg/m^3; the lightest solids reach 0.16) to osmium
/// (22 590 kg/m^3; 1e5 leaves a margin). A density of 7.85e-9 is steel in t/mm^3: the builder
/// works in SI.
pub const RHO_RANGE: (f64, f64) = (1e-1, 1e5);

/// Poisson's ratio: auxetic foams reach -0.8, rubbers 0.4999. At nu -> 0.5 the volumetric
/// stiffness grows like 1 / (1 - 2 nu): at 0.49999 it is 1e5 times the shear stiffness, beyond
/// which the stiffness matrix loses the digits the eigensolver's residual checks need.
pub const NU_RANGE: (f64, f64) = (-0.999, 0.49999);

/// Rayleigh alpha [1/s]: alpha / (2 omega) is a mode's damping ratio, so 1e6 1/s damps a 1 kHz
/// mode 80 times critically, far beyond any structure; above it the damping terms swamp the
/// stiffness terms of the reduced equations in double precision.
pub const ALPHA_MAX: f64 = 1e6;

/// Rayleigh beta [s]: beta omega / 2 is a mode's damping ratio; beta = 10 s makes a 1 Hz mode
/// 30 times overdamped (real materials: 1e-6 to 1e-2 s). The slow root near -1/beta stays
/// representable and the FMU's relaxing modes finite.
pub const BETA_MAX: f64 = 10.0;

/// Modal damping ratio: 1 is critical damping, 100 a hundred times that (no structure comes
/// close; rubber mounts reach 0.2). The runtime's exact propagator uses sqrt(zeta^2 - 1) omega,
/// which must not overflow for the highest reduced frequencies.
pub const RATIO_MAX: f64 = 100.0;

/// Whether `v` lies in [lo, hi] (NaN does not).
pub fn within(v: f64, (lo, hi): (f64, f64)) -> bool {
    v >= lo && v <= hi
}

/// The complaint about a material property out of its range, or None. `what` names the property
/// for the user (`E`, `nu`, `rho`).
pub fn material_problem(what: &str, v: f64) -> Option<String> {
    let (range, unit, why) = match what {
        "E" => (E_RANGE, " Pa", "from soft foams and gels to diamond; check the units (SI: Pa, not MPa)"),
        "rho" => (RHO_RANGE, " kg/m^3", "from aerogels to osmium; check the units (SI: kg/m^3, not t/mm^3)"),
        _ => (NU_RANGE, "", "from auxetic foams to nearly incompressible rubber"),
    };
    (!within(v, range)).then(|| {
        format!(
            "{what} = {v:e}{unit} is outside [{:e}, {:e}]{unit}, the range of real solids ({why})",
            range.0, range.1
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn real_materials_pass_and_absurd_ones_are_named() {
        // steel, aluminium, rubber, polyurethane foam, diamond
        for (e, nu, rho) in [
            (2.1e11, 0.3, 7850.0),
            (7e10, 0.33, 2700.0),
            (1e6, 0.4999, 1100.0),
            (1e5, 0.0, 30.0),
            (1.2e12, 0.07, 3500.0),
        ] {
            assert!(material_problem("E", e).is_none() && material_problem("nu", nu).is_none());
            assert!(material_problem("rho", rho).is_none());
        }
        let m = material_problem("E", 1e-300).unwrap();
        assert!(m.contains("E = 1e-300") && m.contains("1e2"), "{m}");
        assert!(material_problem("rho", 7.85e-9).unwrap().contains("t/mm^3"));
        assert!(material_problem("E", f64::NAN).is_some());
    }
}
