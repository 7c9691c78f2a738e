//! Value references onto the body: get and set, the range of what the host sets, and the
//! derivatives of the values (directional and along time), each through the variable's family.

use super::BodyFmu;
use super::error::VariableError;
use crate::body::{BodyError, FlexibleBody, OutOfRange, REAL_LIMIT};
use crate::interface::{Quantity, Value};
use crate::kinematics as k3;
use crate::scalar::Dual;

impl BodyFmu {
    pub(super) fn real(&mut self, vr: u32) -> Result<f64, VariableError> {
        let q = self.quantity(vr)?;
        if matches!(q.family.value, Value::Switch) {
            return Err(VariableError::BooleanAsReal { vr, name: self.name(vr) });
        }
        real_value(&mut self.body, q)
    }

    /// fmi2SetReal; the FMI layer has checked `admissible` (finite, in range) before.
    pub(super) fn set_value(&mut self, vr: u32, value: f64) -> Result<(), VariableError> {
        let q = self.quantity(vr)?;
        match q.family.write {
            Some(write) => {
                write(&mut self.body, q.at, value);
                Ok(())
            }
            None => Err(VariableError::NotSettable(self.table.get(vr).map(|v| v.name.clone()).unwrap_or_default())),
        }
    }

    pub(super) fn set_input_rate(&mut self, vr: u32, value: f64) -> Result<(), VariableError> {
        let q = self.quantity(vr)?;
        match q.family.rate {
            Some(rate) => {
                rate(&mut self.body, q.at, value);
                Ok(())
            }
            None => Err(VariableError::NotAnInput(vr)),
        }
    }

    pub(super) fn switch(&self, vr: u32) -> Result<bool, VariableError> {
        match self.quantity(vr)?.family.value {
            Value::Switch => Ok(self.static_start),
            Value::Real(_) => Err(VariableError::NotABoolean(vr)),
        }
    }

    pub(super) fn set_switch(&mut self, vr: u32, value: bool) -> Result<(), VariableError> {
        match self.quantity(vr)?.family.value {
            Value::Switch => {
                self.static_start = value;
                Ok(())
            }
            Value::Real(_) => Err(VariableError::NotABoolean(vr)),
        }
    }

    /// A rotation matrix is one only as a whole: a call that sets all nine entries of the
    /// mount's orientation hands over a complete matrix, refused here unless it is a rotation
    /// within the tolerance the step and the evaluations use. Set entry by entry, the matrix
    /// passes through non-rotations on its way (from one rotation to the next), so a partial
    /// call is accepted and the whole matrix is checked where it is used: the next evaluation
    /// answers fmi2Discard, the next step refuses its inputs (fmi2Error), each naming base.R, and
    /// the instance stays usable.
    pub(super) fn admissible_rotation(&self, vrs: &[u32], values: &[f64]) -> Result<(), BodyError> {
        let mut rot = self.body.host_rotation();
        let mut set = [false; 9];
        for (&vr, &value) in vrs.iter().zip(values) {
            if let Ok(q) = self.quantity(vr)
                && q.role() == Some(crate::interface::Role::MountRotation)
            {
                rot[3 * q.at.i + q.at.j] = value;
                set[3 * q.at.i + q.at.j] = true;
            }
        }
        if set.iter().all(|s| *s) { self.body.check_rotation(&rot) } else { Ok(()) }
    }

    /// dv_unknown = (d unknowns / d knowns) dv_known at the present state and inputs, exact:
    /// the body's equations in dual numbers along the direction dv_known.
    pub(super) fn directional(
        &mut self,
        unknowns: &[u32],
        knowns: &[u32],
        dv_known: &[f64],
        dv_unknown: &mut [f64],
    ) -> Result<(), VariableError> {
        let mut d = self.body.to_dual();
        for (&vr, &dv) in knowns.iter().zip(dv_known) {
            let q = self.quantity(vr)?;
            let x = q
                .family
                .seed
                .and_then(|seed| seed(&mut d, q.at))
                .ok_or_else(|| VariableError::NotSeedable(self.name(vr)))?;
            x.d += dv;
        }
        for (&vr, out) in unknowns.iter().zip(dv_unknown.iter_mut()) {
            *out = dual_value(&mut d, self.quantity(vr)?)?.d;
        }
        Ok(())
    }

    /// d/dt of a Real output at the present instant, along the body's own motion: the modes
    /// and a free body's frame move at their rates; the mount moves as its inputs say it does
    /// (r' = v, R' = w~ R, v' = a, w' = z), and a, z and the flange loads change at the rates
    /// fmi2SetRealInputDerivatives set for the next step (zero when none are set: held).
    pub(super) fn output_derivative(&mut self, vr: u32) -> Result<f64, VariableError> {
        let quantity = self.quantity(vr)?;
        let mut d = self.body.to_dual();
        let qdd = self.body.qdd()?.to_vec();
        for (j, &qdd) in qdd.iter().enumerate() {
            d.q_mut()[j].d = self.body.qd()[j];
            d.qd_mut()[j].d = qdd;
        }
        if self.body.frame().is_some() {
            let rate = self.body.frame_rate()?;
            let f = d.frame_mut().ok_or(BodyError::NotFreeFloating)?;
            for i in 0..3 {
                f.r[i].d = rate.r[i];
                f.v[i].d = rate.v[i];
                f.w_body[i].d = rate.w_body[i];
            }
            for i in 0..4 {
                f.quat[i].d = rate.quat[i];
            }
        } else {
            self.mount_motion_along_time(&mut d);
        }
        for (k, rate) in self.body.input_rates().loads.iter().enumerate() {
            let l = d.load_mut(k);
            for i in 0..3 {
                l.f[i].d = rate.f[i];
                l.t[i].d = rate.t[i];
            }
        }
        Ok(dual_value(&mut d, quantity)?.d)
    }

    /// The mount's inputs' rates as the inputs say (r' = v, R' = w~ R, v' = a, w' = z) and as
    /// fmi2SetRealInputDerivatives set them (a, z).
    fn mount_motion_along_time(&self, d: &mut FlexibleBody<Dual>) {
        let m = *self.body.mount();
        let rates = &self.body.input_rates().mount;
        let dm = d.mount_mut();
        // R' = w~ R, row by row: (w x R e_j) per column j
        for j in 0..3 {
            let col = k3::cross(m.w, [m.rot[j], m.rot[3 + j], m.rot[6 + j]]);
            for (i, &rate) in col.iter().enumerate() {
                dm.rot[3 * i + j].d = rate;
            }
        }
        for i in 0..3 {
            dm.r[i].d = m.v[i];
            dm.v[i].d = m.a[i];
            dm.w[i].d = m.z[i];
            dm.a[i].d = rates.a[i];
            dm.z[i].d = rates.z[i];
        }
    }
}

/// A Real variable's value (fmi2GetReal).
pub(super) fn real_value(b: &mut FlexibleBody, q: Quantity) -> Result<f64, VariableError> {
    match q.family.value {
        Value::Real(read) => Ok((read.real)(b, q.at)?),
        Value::Switch => Err(VariableError::BooleanFamily(q.family.pattern)),
    }
}

fn dual_value(d: &mut FlexibleBody<Dual>, q: Quantity) -> Result<Dual, VariableError> {
    match q.family.value {
        Value::Real(read) => Ok((read.dual)(d, q.at)?),
        Value::Switch => Err(VariableError::BooleanFamily(q.family.pattern)),
    }
}

/// Whether `value` is in the physical range of `quantity` (the host's values are finite: the
/// FMI layer has checked).
pub(super) fn admissible(quantity: Quantity, value: f64) -> Result<(), OutOfRange> {
    if !value.is_finite() {
        return Err(OutOfRange::NotFinite(value));
    }
    if value.abs() > REAL_LIMIT {
        return Err(OutOfRange::Beyond(value));
    }
    quantity.family.range.check(value)
}
