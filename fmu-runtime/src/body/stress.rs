//! Stresses at the recovery points: linear in q (each point's stress modes, 6 x n), with the von
//! Mises stress of the six components, evaluated on demand.

use super::{BodyError, FlexibleBody};
use crate::scalar::Scalar;

impl<T: Scalar> FlexibleBody<T> {
    /// Component `component` of the stress at recovery point `point` from the present q: xx,
    /// yy, zz, xy, yz, zx in the body frame (0..6), the von Mises stress (6).
    pub fn stress(&mut self, point: usize, component: usize) -> Result<T, BodyError> {
        self.evaluate()?;
        let generation = self.derived.eval.generation;
        if self.derived.eval.stresses[point].1 != generation {
            // the six rows in one pass, six independent sums: one dot product after another
            // waits on each addition (a point cost 450 ns so, 7 outputs read one by one)
            let n = self.coords.q.len();
            let modes = &self.body.stress_points[point].modes;
            let mut s = [T::zero(); 6];
            for (j, &q) in self.coords.q.iter().enumerate() {
                for (r, s) in s.iter_mut().enumerate() {
                    *s += q * modes[r * n + j];
                }
            }
            let values = [s[0], s[1], s[2], s[3], s[4], s[5], von_mises(s)];
            self.derived.eval.stresses[point] = (values, generation);
        }
        Ok(self.derived.eval.stresses[point].0[component])
    }
}

/// sqrt(((sxx-syy)^2 + (syy-szz)^2 + (szz-sxx)^2) / 2 + 3 (sxy^2 + syz^2 + szx^2)). Not
/// differentiable at zero stress, where its derivative is taken as zero (the square root's
/// argument and its derivative vanish together there).
pub fn von_mises<T: Scalar>(s: [T; 6]) -> T {
    let (a, b, c) = (s[0] - s[1], s[1] - s[2], s[2] - s[0]);
    ((a * a + b * b + c * c) * 0.5 + (s[3] * s[3] + s[4] * s[4] + s[5] * s[5]) * 3.0).sqrt()
}

#[cfg(test)]
mod tests {
    use super::von_mises;
    use crate::scalar::{Dual, Scalar};

    #[test]
    fn von_mises_of_uniaxial_shear_and_hydrostatic_stress() {
        assert!((von_mises([100.0, 0.0, 0.0, 0.0, 0.0, 0.0]) - 100.0).abs() < 1e-12);
        assert!((von_mises([0.0, 0.0, 0.0, 0.0, 10.0, 0.0]) - 10.0 * 3f64.sqrt()).abs() < 1e-12);
        assert_eq!(von_mises([7.0, 7.0, 7.0, 0.0, 0.0, 0.0]), 0.0);
    }

    #[test]
    fn von_mises_derivative_is_finite_at_zero_and_exact_elsewhere() {
        let at = |x: f64, d: f64| Dual { v: x, d };
        let zero = von_mises([at(0.0, 1.0), at(0.0, 0.0), at(0.0, 0.0), at(0.0, 0.0), at(0.0, 0.0), at(0.0, 0.0)]);
        assert_eq!((zero.value(), zero.d), (0.0, 0.0));
        // uniaxial: d vm / d sxx = 1
        let uni = von_mises([at(50.0, 1.0), at(0.0, 0.0), at(0.0, 0.0), at(0.0, 0.0), at(0.0, 0.0), at(0.0, 0.0)]);
        assert!((uni.d - 1.0).abs() < 1e-14);
    }
}
