//! Model Exchange's state vector: q, q' of the dynamic modes, q of the relaxing modes, a free
//! body's frame, and its time derivative.

use super::BodyFmu;
use crate::body::{BodyError, FrameState};

impl BodyFmu {
    /// Model Exchange's modal states: q, q' of the dynamic modes and q of the relaxing ones.
    pub(super) fn n_modal_states(&self) -> usize {
        2 * self.body.n_dynamic() + self.body.n_relaxing()
    }

    /// d/dt of Model Exchange's states: q, q' of the dynamic modes, q of the relaxing ones, a
    /// free body's frame.
    pub(super) fn state_derivatives(&mut self, dx: &mut [f64]) -> Result<(), BodyError> {
        let (n, nr) = (self.body.n_dynamic(), self.body.n_relaxing());
        let (modal, frame_part) = dx.split_at_mut(2 * n + nr);
        let (dq, rest) = modal.split_at_mut(n);
        let (dqd, dr) = rest.split_at_mut(n);
        self.body.derivatives(dq, dqd)?;
        // a relaxing mode's rate is its q', solved with the evaluation
        dr.copy_from_slice(&self.body.qd()[n..n + nr]);
        if self.body.frame().is_some() {
            let rate = self.body.frame_rate()?;
            write_frame(frame_part, &rate);
        }
        Ok(())
    }

    pub(super) fn continuous_states(&self, x: &mut [f64]) {
        let (n, nr) = (self.body.n_dynamic(), self.body.n_relaxing());
        x[..n].copy_from_slice(&self.body.q()[..n]);
        x[n..2 * n].copy_from_slice(&self.body.qd()[..n]);
        x[2 * n..2 * n + nr].copy_from_slice(&self.body.q()[n..n + nr]);
        if let Some(f) = self.body.frame() {
            write_frame(&mut x[2 * n + nr..], f);
        }
    }

    pub(super) fn set_states(&mut self, x: &[f64]) {
        let (n, nr) = (self.body.n_dynamic(), self.body.n_relaxing());
        self.body.set_state(&x[..n], &x[n..2 * n]);
        self.body.set_relaxing(&x[2 * n..2 * n + nr]);
        if let Some(f) = self.body.frame_mut() {
            let y = &x[2 * n + nr..];
            *f = FrameState {
                r: [y[0], y[1], y[2]],
                quat: [y[3], y[4], y[5], y[6]],
                v: [y[7], y[8], y[9]],
                w_body: [y[10], y[11], y[12]],
            };
        }
    }
}

fn write_frame(x: &mut [f64], f: &FrameState) {
    x[..3].copy_from_slice(&f.r);
    x[3..7].copy_from_slice(&f.quat);
    x[7..10].copy_from_slice(&f.v);
    x[10..13].copy_from_slice(&f.w_body);
}
