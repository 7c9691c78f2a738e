//! Co-Simulation's quasi-static modes across load changes. Co-Simulation propagates every mode
//! exactly, but when the host changes a load between steps (a flange force switched on, a
//! staircase of samples, gravity, the mount's linear or angular acceleration, the damping) the
//! algebraic modes, which Model Exchange solves from the inputs, move by the change of their
//! equilibrium instead of starting to ring about the new one: they have no inertia against the
//! loads in the model both interfaces share. Between changes nothing is moved, so a held or
//! ramped load is the exact propagation, step-size independent and energy-conserving for an
//! undamped spinning body; the ringing a jump would give is what a reduced mode above the cutoff
//! cannot represent (its frequency is a Ritz value, not the part's; docs/ARCHITECTURE.md, "One
//! model, two interfaces"). The mount's pose and spin are kinematic: the step moves them by their
//! own rates and the exact propagation carries the modes along, so a host's next orientation or
//! spin is not a jump (comparing it with the step's extrapolation would make every host that
//! holds w while z is set bounce the modes each step).

use super::inputs::SteppedInputs;
use super::step_workspace::JumpWork;
use super::{BodyError, Change, FlexibleBody, StateMismatch, SteppedState};

impl FlexibleBody {
    /// Put the quasi-static modes in equilibrium with the present inputs and dynamic modes, at
    /// rest: how both interfaces start, so that Co-Simulation begins where Model Exchange does
    /// (their start values are calculated, not set). Co-Simulation's steps start from these
    /// inputs.
    pub fn settle_quasi_static(&mut self) -> Result<(), BodyError> {
        self.equilibrate_quasi_static(true)?;
        self.record_stepped_inputs();
        Ok(())
    }

    /// The loads as the last step (or the initialisation) left them.
    pub(super) fn record_stepped_inputs(&mut self) {
        let s = &mut self.stepper.stepped;
        s.a = self.inputs.mount.a;
        s.z = self.inputs.mount.z;
        s.loads.copy_from_slice(&self.inputs.loads);
        s.params = Some(self.inputs.params);
        s.valid = true;
    }

    /// The loads last stepped with, for a saved state (None before the first step).
    pub fn stepped_inputs(&self) -> Option<SteppedState> {
        let s = &self.stepper.stepped;
        match (s.valid, s.params) {
            (true, Some(params)) => Some(SteppedState { a: s.a, z: s.z, loads: s.loads.clone(), params }),
            _ => None,
        }
    }

    /// Restore the loads last stepped with (a loaded state); their sizes are checked.
    pub fn set_stepped_inputs(&mut self, state: &SteppedState) -> Result<(), BodyError> {
        if state.loads.len() != self.inputs.loads.len() {
            return Err(StateMismatch::SteppedLoads { found: state.loads.len(), n: self.inputs.loads.len() }.into());
        }
        let s = &mut self.stepper.stepped;
        s.a = state.a;
        s.z = state.z;
        s.loads.copy_from_slice(&state.loads);
        s.params = Some(state.params);
        s.valid = true;
        Ok(())
    }

    /// Before a step: if the host changed a load since the last step, move the algebraic modes
    /// by the change of their equilibrium (same dynamic modes and mount pose and spin, old and
    /// new loads), keeping their deviation from it and every velocity; `copies`: the step's scratch
    /// for the state before the shift and the old equilibrium.
    pub(super) fn follow_input_change(&mut self, copies: &mut JumpWork) -> Result<(), BodyError> {
        let range = self.algebraic_range();
        if range.is_empty() || !self.stepper.stepped.valid {
            return Ok(());
        }
        let s = &self.stepper.stepped;
        if s.a == self.inputs.mount.a
            && s.z == self.inputs.mount.z
            && s.loads == self.inputs.loads
            && s.params == Some(self.inputs.params)
        {
            return Ok(());
        }
        let mut stepped = std::mem::take(&mut self.stepper.stepped);
        copies.q.copy_from_slice(&self.coords.q);
        copies.qd.copy_from_slice(&self.coords.qd);
        // the equilibrium under the old inputs: swapped in, solved, swapped back
        self.swap_inputs(&mut stepped);
        let old = self.equilibrate_quasi_static(false);
        copies.equilibrium[range.clone()].copy_from_slice(&self.coords.q[range.clone()]);
        self.swap_inputs(&mut stepped);
        self.coords.q.copy_from_slice(&copies.q);
        let new = old.and_then(|_| self.equilibrate_quasi_static(false));
        if new.is_ok() {
            for j in range {
                self.coords.q[j] = copies.q[j] + (self.coords.q[j] - copies.equilibrium[j]);
            }
        } else {
            self.coords.q.copy_from_slice(&copies.q);
        }
        self.coords.qd.copy_from_slice(&copies.qd);
        self.stepper.stepped = stepped;
        self.derived.invalidate(Change::Coordinates);
        new
    }

    fn swap_inputs(&mut self, s: &mut SteppedInputs) {
        let inputs = self.inputs_mut();
        std::mem::swap(&mut inputs.mount.a, &mut s.a);
        std::mem::swap(&mut inputs.mount.z, &mut s.z);
        std::mem::swap(&mut inputs.loads, &mut s.loads);
        if let Some(p) = s.params.as_mut() {
            std::mem::swap(&mut inputs.params, p);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::FlexibleBody;
    use super::JumpWork;
    use crate::reduced::two_mode_body;
    use std::sync::Arc;

    /// The upper mode (above the cutoff) ringing about its equilibrium keeps its deviation and
    /// velocity when the load jumps: only its equilibrium moves, by (p_new - p_old) / omega^2.
    /// Held loads move nothing.
    #[test]
    fn a_load_jump_moves_the_equilibrium_and_keeps_the_ringing() {
        let mut reduced = two_mode_body();
        reduced.alpha = 0.0;
        reduced.beta = 0.0;
        reduced.dynamic_cutoff = 100.0;
        let mut b = FlexibleBody::new(Arc::new(reduced));
        b.load_mut(0).f = [0.0, 1.0, 0.0];
        b.settle_quasi_static().unwrap();
        let p_old = b.qdd().unwrap()[1] + 4.0e6 * b.q()[1];
        // a deviation, as an exact step would leave after a ramp
        b.q_mut()[1] += 1e-9;
        b.qd_mut()[1] = 2e-6;
        let (q_before, qd_before) = (b.q()[1], b.qd()[1]);
        b.follow_input_change(&mut JumpWork::new(2)).unwrap();
        assert_eq!((b.q()[1], b.qd()[1]), (q_before, qd_before), "held loads move nothing");
        b.load_mut(0).f = [0.0, -2.0, 0.5];
        b.follow_input_change(&mut JumpWork::new(2)).unwrap();
        let p_new = b.qdd().unwrap()[1] + 4.0e6 * b.q()[1];
        // equal up to the round-off of the quotients (no coupling: the equilibrium is p / omega^2)
        let expected = q_before + (p_new - p_old) / 4.0e6;
        assert!((b.q()[1] - expected).abs() < 1e-12 * expected.abs().max(1e-9), "{} vs {expected}", b.q()[1]);
        assert_eq!(b.qd()[1], qd_before);
    }
}
