//! Gauss-Legendre quadrature on the reference line [-1, 1] and its tensor
//! product on the reference hexahedron [-1, 1]^3.

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
/// fastest. The index of a point in this sequence is the Gauss-point number
/// reported in element errors.
pub fn hex_points(order: GaussOrder) -> impl Iterator<Item = ([f64; 3], f64)> {
    let (p, w) = order.line_rule();
    let n = p.len();
    (0..n * n * n).map(move |idx| {
        let (i, j, k) = (idx % n, (idx / n) % n, idx / (n * n));
        ([p[i], p[j], p[k]], w[i] * w[j] * w[k])
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Exact integral of x^a y^b z^c over [-1,1]^3.
    fn exact_monomial(a: u32, b: u32, c: u32) -> f64 {
        let line = |p: u32| {
            if p % 2 == 1 {
                0.0
            } else {
                2.0 / (p as f64 + 1.0)
            }
        };
        line(a) * line(b) * line(c)
    }

    fn integrate(order: GaussOrder, a: u32, b: u32, c: u32) -> f64 {
        hex_points(order)
            .map(|(x, w)| w * x[0].powi(a as i32) * x[1].powi(b as i32) * x[2].powi(c as i32))
            .sum()
    }

    #[test]
    fn rules_are_exact_up_to_their_degree() {
        for (order, max_degree) in [(GaussOrder::Two, 3), (GaussOrder::Three, 5)] {
            for a in 0..=max_degree {
                for b in 0..=max_degree {
                    for c in 0..=max_degree {
                        let got = integrate(order, a, b, c);
                        let want = exact_monomial(a, b, c);
                        assert!(
                            (got - want).abs() < 1e-14,
                            "{order:?} x^{a} y^{b} z^{c}: {got} vs {want}"
                        );
                    }
                }
            }
        }
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
