//! Quadrature rules of the reference elements: Gauss-Legendre on the line
//! [-1, 1] and its tensor product on the hexahedron [-1, 1]^3, and the
//! symmetric 1- and 4-point rules on the unit tetrahedron (vertices (0,0,0),
//! (1,0,0), (0,1,0), (0,0,1), volume 1/6).
//!
//! These are the rules of CalculiX's gauss.f (gauss3d2, gauss3d3, gauss3d4,
//! gauss3d5). CalculiX writes its constants with 15 significant digits; here
//! they are the correctly rounded doubles of the exact values, a relative
//! difference below 1e-14 that no eigenfrequency comparison can resolve.

/// Number of Gauss points per axis. Only the orders the hexahedra need exist,
/// so an unsupported order is unrepresentable instead of a runtime error.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum GaussOrder {
    /// 2 points per axis, exact for polynomials of degree 3 (hex8: 8 points).
    Two,
    /// 3 points per axis, exact for polynomials of degree 5 (hex20: 27 points).
    Three,
}

// Literal constants (rather than computed square roots) so that every run and
// every platform integrates with bit-identical abscissae.
const ONE_OVER_SQRT_3: f64 = 0.577_350_269_189_625_8;
const SQRT_3_OVER_5: f64 = 0.774_596_669_241_483_4;

// (5 - sqrt 5) / 20 and (5 + 3 sqrt 5) / 20: the barycentric coordinates of
// the 4-point tetrahedron rule, exact for polynomials of degree 2.
const TET4_A: f64 = 0.138_196_601_125_010_5;
const TET4_B: f64 = 0.585_410_196_624_968_4;

const POINTS_2: [f64; 2] = [-ONE_OVER_SQRT_3, ONE_OVER_SQRT_3];
const WEIGHTS_2: [f64; 2] = [1.0, 1.0];
const POINTS_3: [f64; 3] = [-SQRT_3_OVER_5, 0.0, SQRT_3_OVER_5];
const WEIGHTS_3: [f64; 3] = [5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0];

impl GaussOrder {
    /// Abscissae and weights on [-1, 1].
    pub fn line_rule(self) -> (&'static [f64], &'static [f64]) {
        match self {
            GaussOrder::Two => (&POINTS_2, &WEIGHTS_2),
            GaussOrder::Three => (&POINTS_3, &WEIGHTS_3),
        }
    }

    /// Number of points of the tensor-product rule on the hexahedron.
    pub fn hex_point_count(self) -> usize {
        let n = self.line_rule().0.len();
        n * n * n
    }
}

/// Tensor-product points `(xi, eta, zeta)` with their weights, xi running
/// fastest (the order of gauss3d2/gauss3d3).
pub fn hex_points(order: GaussOrder) -> impl Iterator<Item = ([f64; 3], f64)> {
    Rule::Hex(order).points()
}

const TET1_POINTS: [[f64; 3]; 1] = [[0.25, 0.25, 0.25]];
const TET4_POINTS: [[f64; 3]; 4] =
    [[TET4_A, TET4_A, TET4_A], [TET4_B, TET4_A, TET4_A], [TET4_A, TET4_B, TET4_A], [TET4_A, TET4_A, TET4_B]];

/// A quadrature rule on the reference domain of an element.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Rule {
    /// Tensor-product Gauss rule on [-1, 1]^3.
    Hex(GaussOrder),
    /// Centroid of the unit tetrahedron, exact for degree 1 (gauss3d4).
    TetOne,
    /// Symmetric 4-point rule on the unit tetrahedron, exact for degree 2
    /// (gauss3d5).
    TetFour,
}

impl Rule {
    pub fn point_count(self) -> usize {
        match self {
            Rule::Hex(order) => order.hex_point_count(),
            Rule::TetOne => TET1_POINTS.len(),
            Rule::TetFour => TET4_POINTS.len(),
        }
    }

    /// Polynomial degree integrated exactly: per axis for the hexahedron
    /// rules (x^a y^b z^c with a, b, c <= degree), total degree a + b + c for
    /// the tetrahedron rules.
    pub fn degree(self) -> u32 {
        match self {
            Rule::Hex(GaussOrder::Two) => 3,
            Rule::Hex(GaussOrder::Three) => 5,
            Rule::TetOne => 1,
            Rule::TetFour => 2,
        }
    }

    /// Points `(xi, eta, zeta)` with their weights, in CalculiX's order. The
    /// index of a point in this sequence is the Gauss-point number reported
    /// in element errors.
    pub fn points(self) -> impl Iterator<Item = ([f64; 3], f64)> {
        (0..self.point_count()).map(move |idx| self.point(idx))
    }

    /// `idx` must be below `point_count()`; only `points` calls this.
    fn point(self, idx: usize) -> ([f64; 3], f64) {
        match self {
            Rule::Hex(order) => {
                let (p, w) = order.line_rule();
                let n = p.len();
                let (i, j, k) = (idx % n, (idx / n) % n, idx / (n * n));
                ([p[i], p[j], p[k]], w[i] * w[j] * w[k])
            }
            Rule::TetOne => (TET1_POINTS[idx], 1.0 / 6.0),
            Rule::TetFour => (TET4_POINTS[idx], 1.0 / 24.0),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Exact integral of x^a y^b z^c over [-1,1]^3.
    fn exact_monomial(a: u32, b: u32, c: u32) -> f64 {
        let line = |p: u32| {
            if p % 2 == 1 { 0.0 } else { 2.0 / (p as f64 + 1.0) }
        };
        line(a) * line(b) * line(c)
    }

    fn integrate(order: GaussOrder, a: u32, b: u32, c: u32) -> f64 {
        hex_points(order).map(|(x, w)| w * x[0].powi(a as i32) * x[1].powi(b as i32) * x[2].powi(c as i32)).sum()
    }

    #[test]
    fn rules_are_exact_up_to_their_degree() {
        for (order, max_degree) in [(GaussOrder::Two, 3), (GaussOrder::Three, 5)] {
            for a in 0..=max_degree {
                for b in 0..=max_degree {
                    for c in 0..=max_degree {
                        let got = integrate(order, a, b, c);
                        let want = exact_monomial(a, b, c);
                        assert!((got - want).abs() < 1e-14, "{order:?} x^{a} y^{b} z^{c}: {got} vs {want}");
                    }
                }
            }
        }
    }

    /// Exact integral of x^a y^b z^c over the unit tetrahedron:
    /// a! b! c! / (a + b + c + 3)!.
    fn exact_tet_monomial(a: u32, b: u32, c: u32) -> f64 {
        let fact = |n: u32| (1..=n).map(f64::from).product::<f64>();
        fact(a) * fact(b) * fact(c) / fact(a + b + c + 3)
    }

    fn integrate_rule(rule: Rule, a: u32, b: u32, c: u32) -> f64 {
        rule.points().map(|(x, w)| w * x[0].powi(a as i32) * x[1].powi(b as i32) * x[2].powi(c as i32)).sum()
    }

    #[test]
    fn tet_rules_are_exact_up_to_their_degree_and_not_beyond() {
        for rule in [Rule::TetOne, Rule::TetFour] {
            let degree = rule.degree();
            for a in 0..=degree {
                for b in 0..=degree - a {
                    for c in 0..=degree - a - b {
                        let got = integrate_rule(rule, a, b, c);
                        let want = exact_tet_monomial(a, b, c);
                        assert!((got - want).abs() < 1e-15, "{rule:?} x^{a} y^{b} z^{c}: {got} vs {want}");
                    }
                }
            }
            // One degree higher must fail: CalculiX parity depends on using
            // exactly this rule, not a more accurate one.
            let over = degree + 1;
            let err = (integrate_rule(rule, over, 0, 0) - exact_tet_monomial(over, 0, 0)).abs();
            assert!(err > 1e-3 * exact_tet_monomial(over, 0, 0), "{rule:?}: {err}");
        }
        assert_eq!(Rule::TetOne.point_count(), 1);
        assert_eq!(Rule::TetFour.point_count(), 4);
    }

    #[test]
    fn hex_rule_matches_hex_points() {
        for order in [GaussOrder::Two, GaussOrder::Three] {
            let a: Vec<_> = hex_points(order).collect();
            let b: Vec<_> = Rule::Hex(order).points().collect();
            assert_eq!(a, b);
            assert_eq!(Rule::Hex(order).point_count(), a.len());
        }
    }

    /// The literal abscissae are the correctly rounded exact values.
    #[test]
    fn tet_abscissae_are_the_exact_roots() {
        let s5 = 5f64.sqrt();
        assert!((TET4_A - (5.0 - s5) / 20.0).abs() <= f64::EPSILON * TET4_A);
        assert!((TET4_B - (5.0 + 3.0 * s5) / 20.0).abs() <= f64::EPSILON * TET4_B);
        assert!((TET4_B + 3.0 * TET4_A - 1.0).abs() <= 2.0 * f64::EPSILON);
    }

    #[test]
    fn rules_are_not_exact_beyond_their_degree() {
        // Guards against accidentally using a higher-order rule than intended:
        // CalculiX parity depends on the exact point set.
        assert!((integrate(GaussOrder::Two, 4, 0, 0) - exact_monomial(4, 0, 0)).abs() > 1e-3);
        assert!((integrate(GaussOrder::Three, 6, 0, 0) - exact_monomial(6, 0, 0)).abs() > 1e-3);
        assert_eq!(GaussOrder::Two.hex_point_count(), 8);
        assert_eq!(GaussOrder::Three.hex_point_count(), 27);
    }
}
