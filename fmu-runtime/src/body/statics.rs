//! The static start: the body at rest in the equilibrium of the present inputs.

use super::dense::solve_dense;
use super::{BodyError, Change, FlexibleBody};
use crate::scalar::{Scalar, c};

impl<T: Scalar> FlexibleBody<T> {
    /// Put the body at rest in the static equilibrium of the present inputs: q' = 0 and
    /// (K + C_k) q = p, which for a spinning body includes centrifugal softening and stiffening.
    pub fn settle_static(&mut self) -> Result<(), BodyError> {
        if self.coords.frame.is_some() {
            return Err(BodyError::StaticStartOfFreeBody);
        }
        self.check_inputs()?;
        self.modal_load();
        self.prepare_coupling_rows(0);
        let n = self.coords.q.len();
        if self.derived.coupling.active {
            let mut a = self.derived.coupling.c_k.clone();
            for j in 0..n {
                a[j * n + j] += c(self.body.omega[j] * self.body.omega[j]);
            }
            let mut x = self.derived.load.clone();
            solve_dense(&mut a, &mut x, n, &mut vec![0; n]).map_err(|()| BodyError::NoStaticEquilibrium)?;
            self.coords.q.copy_from_slice(&x);
        } else {
            for j in 0..n {
                self.coords.q[j] = self.derived.load[j] / (self.body.omega[j] * self.body.omega[j]);
            }
        }
        self.coords.qd.fill(T::zero());
        self.derived.invalidate(Change::Coordinates);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::super::FlexibleBody;
    use crate::reduced::two_mode_body;
    use std::sync::Arc;

    #[test]
    fn static_start_has_zero_acceleration_and_stepping_keeps_it() {
        let mut b = FlexibleBody::new(Arc::new(two_mode_body()));
        b.load_mut(0).f = [0.0, 3.0, -1.0];
        b.load_mut(0).t = [0.5, 0.0, 0.0];
        b.settle_static().unwrap();
        assert!(b.qdd().unwrap().iter().all(|a| a.abs() < 1e-9));
        let q0 = b.q().to_vec();
        for _ in 0..100 {
            b.step(0.01).unwrap();
        }
        for (a, b) in q0.iter().zip(b.q()) {
            assert!((a - b).abs() <= 1e-14 * a.abs().max(1e-300));
        }
    }
}
