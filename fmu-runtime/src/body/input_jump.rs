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

use super::{FlangeLoad, FlexibleBody, Parameters, SteppedState};
use crate::kinematics::Vec3;

/// The loads a Co-Simulation step ended with (host-given rates applied), and workspace of the
/// shift.
#[derive(Debug, Clone, Default)]
pub(super) struct SteppedInputs {
    pub(super) valid: bool,
    /// The mount's acceleration a and angular acceleration z.
    pub(super) a: Vec3,
    pub(super) z: Vec3,
    pub(super) loads: Vec<FlangeLoad>,
    pub(super) params: Option<Parameters>,
    q: Vec<f64>,
    qd: Vec<f64>,
    equilibrium: Vec<f64>,
}

impl SteppedInputs {
    pub(super) fn new(n: usize, flanges: usize) -> Self {
        Self {
            valid: false,
            a: [0.0; 3],
            z: [0.0; 3],
            loads: vec![FlangeLoad::default(); flanges],
            params: None,
            q: vec![0.0; n],
            qd: vec![0.0; n],
            equilibrium: vec![0.0; n],
        }
    }
}

impl FlexibleBody {
    /// Put the quasi-static modes in equilibrium with the present inputs and dynamic modes, at
    /// rest: how both interfaces start, so that Co-Simulation begins where Model Exchange does
    /// (their start values are calculated, not set). Co-Simulation's steps start from these
    /// inputs.
    pub fn settle_quasi_static(&mut self) -> Result<(), String> {
        self.equilibrate_quasi_static(true)?;
        self.record_stepped_inputs();
        Ok(())
    }

    /// The loads as the last step (or the initialisation) left them.
    pub(super) fn record_stepped_inputs(&mut self) {
        let s = &mut self.stepped;
        s.a = self.mount.a;
        s.z = self.mount.z;
        s.loads.copy_from_slice(&self.loads);
        s.params = Some(self.params);
        s.valid = true;
    }

    /// The loads last stepped with, for a saved state (None before the first step).
    pub fn stepped_inputs(&self) -> Option<SteppedState> {
        let s = &self.stepped;
        match (s.valid, s.params) {
            (true, Some(params)) => Some(SteppedState { a: s.a, z: s.z, loads: s.loads.clone(), params }),
            _ => None,
        }
    }

    /// Restore the loads last stepped with (a loaded state); their sizes are checked.
    pub fn set_stepped_inputs(&mut self, state: &SteppedState) -> Result<(), String> {
        if state.loads.len() != self.loads.len() {
            return Err(format!(
                "the state has stepped loads on {} flanges, the body {}",
                state.loads.len(),
                self.loads.len()
            ));
        }
        let s = &mut self.stepped;
        s.a = state.a;
        s.z = state.z;
        s.loads.copy_from_slice(&state.loads);
        s.params = Some(state.params);
        s.valid = true;
        Ok(())
    }

    /// Before a step: if the host changed a load since the last step, move the algebraic modes
    /// by the change of their equilibrium (same dynamic modes and mount pose and spin, old and
    /// new loads), keeping their deviation from it and every velocity.
    pub(super) fn follow_input_change(&mut self) -> Result<(), String> {
        let range = self.algebraic_range();
        if range.is_empty() || !self.stepped.valid {
            return Ok(());
        }
        let s = &self.stepped;
        if s.a == self.mount.a && s.z == self.mount.z && s.loads == self.loads && s.params == Some(self.params) {
            return Ok(());
        }
        let mut work = std::mem::take(&mut self.stepped);
        work.q.copy_from_slice(&self.q);
        work.qd.copy_from_slice(&self.qd);
        // the equilibrium under the old inputs: swapped in, solved, swapped back
        self.swap_inputs(&mut work);
        let old = self.equilibrate_quasi_static(false);
        work.equilibrium[range.clone()].copy_from_slice(&self.q[range.clone()]);
        self.swap_inputs(&mut work);
        self.q.copy_from_slice(&work.q);
        let new = old.and_then(|_| self.equilibrate_quasi_static(false));
        if new.is_ok() {
            for j in range {
                self.q[j] = work.q[j] + (self.q[j] - work.equilibrium[j]);
            }
        } else {
            self.q.copy_from_slice(&work.q);
        }
        self.qd.copy_from_slice(&work.qd);
        self.stepped = work;
        self.eval.valid = false;
        new
    }

    fn swap_inputs(&mut self, s: &mut SteppedInputs) {
        std::mem::swap(&mut self.mount.a, &mut s.a);
        std::mem::swap(&mut self.mount.z, &mut s.z);
        std::mem::swap(&mut self.loads, &mut s.loads);
        if let Some(p) = s.params.as_mut() {
            std::mem::swap(&mut self.params, p);
        }
        self.coupling.valid = false;
        self.eval.valid = false;
    }
}
