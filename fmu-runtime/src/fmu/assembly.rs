//! `fmi2::Model` for an assembly: Co-Simulation only. Its step solves an index-3 system of
//! equations (the bodies' and the joints') by Newton's method; a Model Exchange host would have
//! to integrate that differential-algebraic system itself, which FMI 2.0's ODE interface cannot
//! hand over (see docs/CONNECTING.md).

use super::resource::load_resource;
use crate::assembly::AssemblyError;
use crate::assembly::description::{ASSEMBLY_FILE, AssemblyDescription};
use crate::assembly::model::{Assembly, Checkpoint};
use crate::interface::assembly::{AssemblyTable, Slot};
use crate::kinematics as k3;
use fmi2::bytes::{DecodeError, Reader, Writer};
use fmi2::{Interface, Model, ModelError, VarInfo, VarType};
use std::fmt;
use std::sync::Arc;

/// Version of an assembly's serialized state.
/// Layout, little-endian: version (u32); position entries, multipliers, drive inputs and loads
/// (u32 each, checked against the assembly); then f64s: time, start time, g[3], positions,
/// velocities, accelerations, pseudo-accelerations, multipliers, revolute angles, the host
/// frame's r[3] R[9] v[3] w[3] a[3] z[3], drive inputs and their rates, loads and their rates;
/// then the solver's: first step (u8), a kept iteration matrix (u8) and, where kept, its step
/// (f64) and the matrix as formed (f64, dimension^2; version 1: its factors and pivots, u32
/// each, which a restore drops).
pub const ASSEMBLY_STATE_VERSION: u32 = 2;

#[derive(Debug, Clone)]
pub struct AssemblyFmu {
    table: Arc<AssemblyTable>,
    guid: String,
    assembly: Assembly,
    /// What a step changes, kept at its start so that a step not taken changes nothing.
    step_start: Checkpoint,
    start_time: f64,
    scratch: Vec<f64>,
    /// Where a restored state's iteration matrix is read to.
    matrix_buffer: Vec<f64>,
}

/// Why a variable or a call is refused.
#[derive(Debug, Clone, PartialEq)]
pub enum AssemblyFmuError {
    NoModelExchange,
    NotAVariable(u32),
    NotSettable(String),
    OutOfRange { name: String, value: f64, why: &'static str },
    OtherAssembly,
    NewerState(u32),
}

impl fmt::Display for AssemblyFmuError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            AssemblyFmuError::NoModelExchange => f.write_str(
                "an assembly FMU runs in Co-Simulation only: its joints make a differential-algebraic system that \
                 the FMU solves in its own steps",
            ),
            AssemblyFmuError::NotAVariable(vr) => write!(f, "no Real variable with value reference {vr}"),
            AssemblyFmuError::NotSettable(n) => write!(f, "{n} is an output"),
            AssemblyFmuError::OutOfRange { name, value, why } => write!(f, "{name} = {value}: {why}"),
            AssemblyFmuError::OtherAssembly => f.write_str("the state is of an assembly of other sizes"),
            AssemblyFmuError::NewerState(v) => {
                write!(f, "the state has version {v}; this runtime reads up to {ASSEMBLY_STATE_VERSION}")
            }
        }
    }
}

impl std::error::Error for AssemblyFmuError {}

impl AssemblyFmu {
    pub fn new(description: &AssemblyDescription) -> Result<Self, AssemblyError> {
        let assembly = Assembly::new(description)?;
        let table = Arc::new(AssemblyTable::new(description, &assembly));
        let scratch = vec![0.0; crate::assembly::inertia::Inertia::scratch_len(assembly.system.max_modes())];
        let dim = assembly.solver.dimension();
        Ok(Self {
            table,
            guid: description.guid.clone(),
            step_start: assembly.checkpoint(),
            assembly,
            start_time: 0.0,
            scratch,
            matrix_buffer: vec![0.0; dim * dim],
        })
    }

    pub fn table(&self) -> &AssemblyTable {
        &self.table
    }

    pub fn assembly(&self) -> &Assembly {
        &self.assembly
    }

    fn slot(&self, vr: u32) -> Result<(Slot, &str), ModelError> {
        self.table
            .get(vr)
            .map(|v| (v.slot, v.name.as_str()))
            .ok_or_else(|| ModelError::refused(AssemblyFmuError::NotAVariable(vr)))
    }

    fn value(&mut self, slot: Slot) -> Result<f64, AssemblyError> {
        if matches!(slot, Slot::JointReaction(..) | Slot::MountReaction(_) | Slot::Flange(_, _, 4 | 5, _)) {
            self.assembly.settle_outputs()?;
        }
        let a = &self.assembly;
        let s = &a.system;
        let value = match slot {
            Slot::Gravity(k) => s.gravity[k],
            Slot::DriveInput(i) => a.inputs.drives[i],
            Slot::Load(f, k) => a.inputs.loads[6 * f + k],
            Slot::Host(q, k) => {
                let h = &a.inputs.host;
                match q {
                    0 => h.r[k],
                    1 => h.rot[k],
                    2 => h.v[k],
                    3 => h.w[k],
                    4 => h.a[k],
                    _ => h.z[k],
                }
            }
            Slot::JointValue(j) => a.joint_motion(j).0,
            Slot::JointRate(j) => a.joint_motion(j).1,
            Slot::JointReaction(j, k) => {
                let (f, t) = a.joint_reaction(j);
                if k < 3 { f[k] } else { t[k - 3] }
            }
            Slot::Flange(b, m, q, k) => {
                let (pos, vel) = (&a.motion.pos, &a.motion.vel);
                match q {
                    0 => s.marker_pose(pos, b, m).p[k],
                    1 => s.marker_pose(pos, b, m).frame[k],
                    2 => s.marker_velocity(pos, vel, b, m).0[k],
                    3 => s.marker_velocity(pos, vel, b, m).1[k],
                    4 => s.marker_rates(pos, vel, Some(a.output_accelerations()), b, m).0[k],
                    _ => s.marker_rates(pos, vel, Some(a.output_accelerations()), b, m).1[k],
                }
            }
            Slot::MountReaction(k) => {
                let (f, t) = a.mount_reaction();
                if k < 3 { f[k] } else { t[k - 3] }
            }
            Slot::Energy(k) => {
                let e = a.energies(&mut self.scratch);
                if k < 3 { e[k] } else { e.iter().sum() }
            }
            Slot::Drift => a.drift(),
        };
        Ok(value)
    }

    fn write_state(&self, out: &mut Vec<u8>) {
        let a = &self.assembly;
        let mut w = Writer::new(out);
        w.u32(ASSEMBLY_STATE_VERSION);
        for n in [a.motion.pos.len(), a.motion.lambda.len(), a.inputs.drives.len(), a.inputs.loads.len()] {
            w.u32(n as u32);
        }
        w.f64(a.time);
        w.f64(self.start_time);
        w.f64s(&a.system.gravity);
        for v in [&a.motion.pos, &a.motion.vel, &a.motion.acc, &a.motion.pseudo, &a.motion.lambda, &a.angles] {
            w.f64s(v);
        }
        let h = &a.inputs.host;
        for v in [&h.r[..], &h.rot[..], &h.v[..], &h.w[..], &h.a[..], &h.z[..]] {
            w.f64s(v);
        }
        for v in [&a.inputs.drives, &a.inputs.drive_rates, &a.inputs.loads, &a.inputs.load_rates] {
            w.f64s(v);
        }
        // the kept iteration matrix decides Newton's path to its tolerance: a restored state
        // continues bit for bit only with it
        let (first, step, matrix) = a.solver.kept();
        w.bool(first);
        w.bool(step.is_some());
        if let Some(h) = step {
            w.f64(h);
            w.f64s(matrix);
        }
    }

    fn read_state(&mut self, bytes: &[u8]) -> Result<(), DecodeError> {
        let mut r = Reader::new(bytes);
        let version = r.u32("assembly state version")?;
        if version == 0 || version > ASSEMBLY_STATE_VERSION {
            return Err(DecodeError::invalid(AssemblyFmuError::NewerState(version)));
        }
        let a = &mut self.assembly;
        for (n, what) in [
            (a.motion.pos.len(), "positions"),
            (a.motion.lambda.len(), "multipliers"),
            (a.inputs.drives.len(), "drive inputs"),
            (a.inputs.loads.len(), "loads"),
        ] {
            if r.u32(what)? as usize != n {
                return Err(DecodeError::invalid(AssemblyFmuError::OtherAssembly));
            }
        }
        a.time = r.f64("time")?;
        self.start_time = r.f64("start time")?;
        r.f64s_into(&mut a.system.gravity, "g")?;
        r.f64s_into(&mut a.motion.pos, "positions")?;
        r.f64s_into(&mut a.motion.vel, "velocities")?;
        r.f64s_into(&mut a.motion.acc, "accelerations")?;
        r.f64s_into(&mut a.motion.pseudo, "pseudo-accelerations")?;
        r.f64s_into(&mut a.motion.lambda, "multipliers")?;
        r.f64s_into(&mut a.angles, "joint angles")?;
        let h = &mut a.inputs.host;
        r.f64s_into(&mut h.r, "host r")?;
        r.f64s_into(&mut h.rot, "host R")?;
        r.f64s_into(&mut h.v, "host v")?;
        r.f64s_into(&mut h.w, "host w")?;
        r.f64s_into(&mut h.a, "host a")?;
        r.f64s_into(&mut h.z, "host z")?;
        r.f64s_into(&mut a.inputs.drives, "drive inputs")?;
        r.f64s_into(&mut a.inputs.drive_rates, "drive input rates")?;
        r.f64s_into(&mut a.inputs.loads, "loads")?;
        r.f64s_into(&mut a.inputs.load_rates, "load rates")?;
        let first = r.bool("first step")?;
        let dim = a.solver.dimension();
        let mut matrix = std::mem::take(&mut self.matrix_buffer);
        let step = if r.bool("kept iteration matrix")? {
            let h = r.f64("kept matrix's step")?;
            r.f64s_into(&mut matrix, "kept matrix")?;
            // version 1 kept the matrix's factors and pivots: dropped (the next step forms one)
            let mut valid = true;
            if version == 1 {
                for i in 0..dim {
                    let v = r.u32("kept pivots")? as usize;
                    if v < i || v >= dim {
                        return Err(DecodeError::invalid(AssemblyFmuError::OtherAssembly));
                    }
                }
                valid = false;
            }
            Some(h).filter(|_| valid)
        } else {
            None
        };
        r.finish("assembly state")?;
        for b in &a.system.bodies {
            let rot: k3::Mat3 = std::array::from_fn(|i| a.motion.pos[b.at + 3 + i]);
            if k3::rotation_defect(&rot) > 1e-9 {
                return Err(DecodeError::invalid(AssemblyFmuError::OutOfRange {
                    name: format!("{} R", b.name),
                    value: k3::rotation_defect(&rot),
                    why: "is no rotation",
                }));
            }
        }
        a.solver.invalidate();
        match step {
            Some(h) => a.solver.restore_kept(first, Some(h), &matrix),
            None => a.solver.set_first(first),
        }
        self.matrix_buffer = matrix;
        a.forget_outputs();
        Ok(())
    }
}

impl Model for AssemblyFmu {
    fn instantiate(resources: Option<&std::path::Path>, interface: Interface) -> Result<Self, ModelError> {
        if interface == Interface::ModelExchange {
            return Err(ModelError::failed(AssemblyFmuError::NoModelExchange));
        }
        let d = load_resource(resources, ASSEMBLY_FILE, AssemblyDescription::from_sealed_bytes)?;
        Self::new(&d).map_err(ModelError::failed)
    }

    fn guid(&self) -> &str {
        &self.guid
    }

    fn var_info(&self, vr: u32) -> Option<VarInfo> {
        self.table.get(vr).map(|v| VarInfo {
            var_type: VarType::Real,
            causality: v.causality,
            variability: v.variability,
            initial: v.initial,
        })
    }

    fn var_name(&self, vr: u32) -> Option<&str> {
        self.table.get(vr).map(|v| v.name.as_str())
    }

    fn get_real(&mut self, vr: u32) -> Result<f64, ModelError> {
        let (slot, _) = self.slot(vr)?;
        self.value(slot).map_err(ModelError::discard)
    }

    fn admissible_real(&self, vr: u32, value: f64) -> Result<(), ModelError> {
        let (slot, name) = self.slot(vr)?;
        let refuse = |why| Err(ModelError::refused(AssemblyFmuError::OutOfRange { name: name.into(), value, why }));
        if value.abs() > 1e100 {
            return refuse("beyond 1e100, where products overflow");
        }
        if matches!(slot, Slot::Host(1, _)) && value.abs() > 1.0 {
            return refuse("a rotation matrix's entries lie in [-1, 1]");
        }
        Ok(())
    }

    fn admissible_direction(&self, vr: u32, value: f64) -> Result<(), ModelError> {
        self.admissible_real(vr, value)
    }

    fn set_real(&mut self, vr: u32, value: f64) -> Result<(), ModelError> {
        let table = Arc::clone(&self.table);
        let variable = table.get(vr).ok_or_else(|| ModelError::refused(AssemblyFmuError::NotAVariable(vr)))?;
        let a = &mut self.assembly;
        match variable.slot {
            Slot::Gravity(k) => a.system.gravity[k] = value,
            Slot::DriveInput(i) => a.inputs.drives[i] = value,
            Slot::Load(f, k) => a.inputs.loads[6 * f + k] = value,
            Slot::Host(q, k) => {
                let h = &mut a.inputs.host;
                match q {
                    0 => h.r[k] = value,
                    1 => h.rot[k] = value,
                    2 => h.v[k] = value,
                    3 => h.w[k] = value,
                    4 => h.a[k] = value,
                    _ => h.z[k] = value,
                }
            }
            _ => return Err(ModelError::refused(AssemblyFmuError::NotSettable(variable.name.clone()))),
        }
        a.forget_outputs();
        Ok(())
    }

    fn can_interpolate_inputs(&self) -> bool {
        true
    }

    /// Drive inputs and loads ramp over the step with their rates; the host frame's motion
    /// follows its own velocity and acceleration inputs, so rates of those are not needed.
    fn set_real_input_derivative(&mut self, vr: u32, value: f64) -> Result<(), ModelError> {
        let (slot, _) = self.slot(vr)?;
        let a = &mut self.assembly;
        match slot {
            Slot::DriveInput(i) => a.inputs.drive_rates[i] = value,
            Slot::Load(f, k) => a.inputs.load_rates[6 * f + k] = value,
            _ => {}
        }
        Ok(())
    }

    fn get_integer(&mut self, vr: u32) -> Result<i32, ModelError> {
        Err(ModelError::refused(AssemblyFmuError::NotAVariable(vr)))
    }
    fn set_integer(&mut self, vr: u32, _value: i32) -> Result<(), ModelError> {
        Err(ModelError::refused(AssemblyFmuError::NotAVariable(vr)))
    }
    fn get_boolean(&mut self, vr: u32) -> Result<bool, ModelError> {
        Err(ModelError::refused(AssemblyFmuError::NotAVariable(vr)))
    }
    fn set_boolean(&mut self, vr: u32, _value: bool) -> Result<(), ModelError> {
        Err(ModelError::refused(AssemblyFmuError::NotAVariable(vr)))
    }
    fn get_string(&mut self, vr: u32) -> Result<String, ModelError> {
        Err(ModelError::refused(AssemblyFmuError::NotAVariable(vr)))
    }
    fn set_string(&mut self, vr: u32, _value: &str) -> Result<(), ModelError> {
        Err(ModelError::refused(AssemblyFmuError::NotAVariable(vr)))
    }
    fn n_states(&self) -> usize {
        0
    }
    fn n_event_indicators(&self) -> usize {
        0
    }
    fn set_time(&mut self, _t: f64) {}
    fn get_continuous_states(&self, _x: &mut [f64]) {}
    fn set_continuous_states(&mut self, _x: &[f64]) {}
    fn get_derivatives(&mut self, _dx: &mut [f64]) -> Result<(), ModelError> {
        Ok(())
    }
    fn get_nominals(&self, _nominals: &mut [f64]) {}
    fn get_event_indicators(&mut self, _z: &mut [f64]) -> Result<(), ModelError> {
        Ok(())
    }

    fn enter_initialization(&mut self, start_time: f64) -> Result<(), ModelError> {
        self.start_time = start_time;
        Ok(())
    }

    fn exit_initialization(&mut self) -> Result<(), ModelError> {
        self.assembly.start_run(self.start_time).map_err(ModelError::failed)
    }

    /// A step that does not converge is not taken: the assembly is as at its start.
    fn do_step(&mut self, _t: f64, h: f64) -> Result<(), ModelError> {
        self.assembly.keep(&mut self.step_start);
        self.assembly.do_step(h).map_err(|e| {
            self.assembly.restore(&self.step_start);
            ModelError::discard(e)
        })
    }

    fn reset(&mut self) -> Result<(), ModelError> {
        self.assembly.reset();
        self.start_time = 0.0;
        Ok(())
    }

    fn save_state(&self, out: &mut Vec<u8>) {
        self.write_state(out)
    }

    fn load_state(&mut self, bytes: &[u8]) -> Result<(), DecodeError> {
        self.read_state(bytes)
    }
}
