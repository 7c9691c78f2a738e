//! An assembly as a simulated model, with nothing of FMI: its inputs (the host's frame, drive
//! inputs, external loads, each with an optional rate over the step), its start, its step split
//! into the solver's steps, and the values its outputs read.

use super::description::{AssemblyDescription, FlangeRole};
use super::error::AssemblyError;
use super::joint::{self, JointKind, axis};
use super::solver::{Motion, Solver};
use super::system::{Attach, HostPose, Instant, System};
use crate::kinematics::{self as k3, Mat3, Vec3, rotation_of};

/// The host's prescribed frame at a communication point, with its rates (a motion flange).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HostMotion {
    pub r: Vec3,
    pub rot: Mat3,
    pub v: Vec3,
    pub w: Vec3,
    pub a: Vec3,
    pub z: Vec3,
}

impl HostMotion {
    /// The frame tau after the communication point: second order in the rates.
    pub fn at(&self, tau: f64) -> HostPose {
        let dr = k3::add(k3::scale(tau, self.v), k3::scale(0.5 * tau * tau, self.a));
        let turn = k3::add(k3::scale(tau, self.w), k3::scale(0.5 * tau * tau, self.z));
        HostPose { r: k3::add(self.r, dr), rot: k3::mat_mul(&rotation_of(turn), &self.rot) }
    }
}

/// The inputs over the next step: values at the communication point and their rates.
#[derive(Debug, Clone, PartialEq)]
pub struct Inputs {
    pub host: HostMotion,
    pub drives: Vec<f64>,
    pub drive_rates: Vec<f64>,
    pub loads: Vec<f64>,
    pub load_rates: Vec<f64>,
}

/// What a step changes, kept to undo a step that is not taken.
#[derive(Debug, Clone)]
pub struct Checkpoint {
    motion: Motion,
    inputs: Inputs,
    angles: Vec<f64>,
    time: f64,
}

#[derive(Debug, Clone)]
pub struct Assembly {
    pub system: System,
    pub solver: Solver,
    pub motion: Motion,
    pub inputs: Inputs,
    /// Communication time.
    pub time: f64,
    /// Revolute joints' angles, followed through whole turns (others: 0).
    pub angles: Vec<f64>,
    /// The start, for a reset (gravity is a parameter the host may set before initialising).
    start: (Motion, Inputs, [f64; 3]),
    /// The accelerations and multipliers the outputs use (index 1 at the communication point),
    /// and whether they belong to the present state and inputs.
    out_acc: Vec<f64>,
    out_lambda: Vec<f64>,
    out_valid: bool,
    /// Trial buffers of the inputs at a solver step's end.
    drives_now: Vec<f64>,
    loads_now: Vec<f64>,
}

/// The relative excess over `max_step` a host's step may have and still be taken in one.
const STEP_SLACK: f64 = 1e-6;

/// Halvings of a solver step whose Newton iteration fails (see `Assembly::advance`).
const HALVINGS: u32 = 4;

impl Assembly {
    pub fn new(d: &AssemblyDescription) -> Result<Self, AssemblyError> {
        let (system, pos) = System::new(d)?;
        let nv = system.n_vel;
        let motion = Motion {
            pos,
            vel: vec![0.0; nv],
            acc: vec![0.0; nv],
            pseudo: vec![0.0; nv],
            lambda: vec![0.0; system.n_eq],
        };
        let n_loads = 6 * system.flanges.iter().filter(|f| f.1 == FlangeRole::Force).count();
        let host = match system.flanges.iter().find(|f| f.1 == FlangeRole::Motion) {
            Some((_, _, body, marker)) => {
                let p = system.marker_pose(&motion.pos, *body, *marker);
                HostMotion { r: p.p, rot: p.frame, v: [0.0; 3], w: [0.0; 3], a: [0.0; 3], z: [0.0; 3] }
            }
            None => HostMotion { r: [0.0; 3], rot: k3::IDENTITY, v: [0.0; 3], w: [0.0; 3], a: [0.0; 3], z: [0.0; 3] },
        };
        let nd = system.drive_inputs.len();
        let inputs = Inputs {
            host,
            drives: vec![0.0; nd],
            drive_rates: vec![0.0; nd],
            loads: vec![0.0; n_loads],
            load_rates: vec![0.0; n_loads],
        };
        let solver = Solver::new(&system, d.solver);
        let n_joints = system.joints.len();
        let n_eq = system.n_eq;
        let a = Self {
            system,
            solver,
            motion: motion.clone(),
            inputs: inputs.clone(),
            time: 0.0,
            angles: vec![0.0; n_joints],
            start: (motion, inputs, d.gravity),
            drives_now: vec![0.0; nd],
            loads_now: vec![0.0; n_loads],
            out_acc: vec![0.0; nv],
            out_lambda: vec![0.0; n_eq],
            out_valid: false,
        };
        a.check_start()?;
        Ok(a)
    }

    /// The joints hold at the start pose, and their equations are independent.
    fn check_start(&self) -> Result<(), AssemblyError> {
        let s = &self.system;
        let (drives, loads) = (self.inputs.drives.clone(), self.inputs.loads.clone());
        let now = self.instant_at(self.time, &self.inputs, &drives, &loads);
        let size = 1.0 + self.motion.pos.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        for j in 0..s.joints.len() {
            let e = s.joint_equations(&self.motion.pos, j, &now);
            let gap = e.value[..e.len].iter().fold(0.0f64, |m, x| m.max(x.abs()));
            // the builder places bodies from the input's numbers: a gap beyond round-off is an
            // input that does not close
            if gap > 1e-6 * size {
                return Err(AssemblyError::Misassembled { joint: s.joints[j].name.clone(), gap });
            }
        }
        let (ne, nv) = (s.n_eq, s.n_vel);
        let mut phi = vec![0.0; ne];
        let mut jac = vec![0.0; ne * nv];
        s.constraints(&self.motion.pos, &now, &mut phi, &mut jac);
        if let Some(rows) = dependent_rows(&jac, ne, nv) {
            let mut joints: Vec<String> = Vec::new();
            for r in rows {
                let j = s.joints.iter().find(|j| (j.row..j.row + j.rows).contains(&r)).map(|j| j.name.clone());
                if let Some(j) = j.filter(|j| !joints.contains(j)) {
                    joints.push(j);
                }
            }
            return Err(AssemblyError::Redundant { joints });
        }
        Ok(())
    }

    fn instant_at<'a>(&self, t: f64, inputs: &Inputs, drives: &'a [f64], loads: &'a [f64]) -> Instant<'a> {
        Instant { t, host: inputs.host.at(t - self.time), drives, loads }
    }

    /// A checkpoint of the present state (allocates: made once).
    pub fn checkpoint(&self) -> Checkpoint {
        Checkpoint {
            motion: self.motion.clone(),
            inputs: self.inputs.clone(),
            angles: self.angles.clone(),
            time: self.time,
        }
    }

    /// Copy the present state into `c` (no allocation).
    pub fn keep(&self, c: &mut Checkpoint) {
        copy_motion(&mut c.motion, &self.motion);
        copy_inputs(&mut c.inputs, &self.inputs);
        c.angles.copy_from_slice(&self.angles);
        c.time = self.time;
    }

    /// Back to the state kept in `c` (no allocation).
    pub fn restore(&mut self, c: &Checkpoint) {
        self.out_valid = false;
        copy_motion(&mut self.motion, &c.motion);
        copy_inputs(&mut self.inputs, &c.inputs);
        self.angles.copy_from_slice(&c.angles);
        self.time = c.time;
        self.solver.invalidate();
    }

    /// Back to the start (inputs at their start values).
    pub fn reset(&mut self) {
        self.out_valid = false;
        (self.motion, self.inputs, self.system.gravity) = self.start.clone();
        self.time = 0.0;
        self.angles.fill(0.0);
        self.solver.invalidate();
    }

    /// Move the whole assembly rigidly so that its motion flange starts where the host's frame
    /// is, then settle the accelerations: the start of a run at `t0`.
    pub fn start_run(&mut self, t0: f64) -> Result<(), AssemblyError> {
        self.out_valid = false;
        self.time = t0;
        if let Some((name, _, body, marker)) = self.system.flanges.iter().find(|f| f.1 == FlangeRole::Motion).cloned() {
            let p = self.system.marker_pose(&self.motion.pos, body, marker);
            let host = self.inputs.host;
            let moved = k3::sub(host.r, p.p).iter().any(|x| x.abs() > 1e-12)
                || host.rot.iter().zip(&p.frame).any(|(a, b)| (a - b).abs() > 1e-12);
            if moved {
                if self
                    .system
                    .joints
                    .iter()
                    .any(|j| matches!(j.a, Attach::Ground { .. }) || matches!(j.b, Attach::Ground { .. }))
                {
                    return Err(AssemblyError::Joint {
                        joint: format!("{name}.mount"),
                        reason: "the host's start frame differs from the flange's, and joints to the ground keep the \
                                 bodies where they are: start the host's frame at the flange's pose"
                            .into(),
                    });
                }
                self.move_rigidly(p.p, &p.frame, &host);
            }
        }
        self.drives_now.copy_from_slice(&self.inputs.drives);
        self.loads_now.copy_from_slice(&self.inputs.loads);
        let now = Instant { t: t0, host: self.inputs.host.at(0.0), drives: &self.drives_now, loads: &self.loads_now };
        self.solver.settle_accelerations(&self.system, &mut self.motion, &now)?;
        Self::update_angles(&self.system, &self.motion.pos, &now.host, &mut self.angles);
        Ok(())
    }

    /// Every body moved by the rigid motion taking the frame (p, f) onto the host's.
    fn move_rigidly(&mut self, p: Vec3, f: &Mat3, host: &HostMotion) {
        let turn = k3::mat_mul(&host.rot, &joint::transpose(f));
        for b in &self.system.bodies {
            let x = &mut self.motion.pos[b.at..];
            let r = k3::add(host.r, k3::mul(&turn, k3::sub([x[0], x[1], x[2]], p)));
            let rot: Mat3 = std::array::from_fn(|i| x[3 + i]);
            x[..3].copy_from_slice(&r);
            x[3..12].copy_from_slice(&k3::mat_mul(&turn, &rot));
        }
    }

    /// Advance from the communication point `self.time` by h, in steps of at most the solver's.
    pub fn do_step(&mut self, h: f64) -> Result<(), AssemblyError> {
        self.out_valid = false;
        // a host's step a little over max_step is one step: FMPy's steps are differences of
        // communication points, libcosim's whole nanoseconds, both off by up to 1e-11 of 1 ms
        // late in a run (splitting them alternated the step length, which generalised alpha
        // carries into the energy)
        let steps = ((h / self.solver.settings.max_step) * (1.0 - STEP_SLACK)).ceil().max(1.0) as usize;
        let hs = h / steps as f64;
        for k in 0..steps {
            self.advance(hs * k as f64, hs, 0)?;
        }
        // the inputs' values at the new communication point, as the host would set them
        for i in 0..self.drives_now.len() {
            self.inputs.drives[i] += h * self.inputs.drive_rates[i];
        }
        for i in 0..self.loads_now.len() {
            self.inputs.loads[i] += h * self.inputs.load_rates[i];
        }
        let host = &mut self.inputs.host;
        let pose = host.at(h);
        host.v = k3::add(host.v, k3::scale(h, host.a));
        host.w = k3::add(host.w, k3::scale(h, host.z));
        (host.r, host.rot) = (pose.r, pose.rot);
        self.time += h;
        Ok(())
    }

    /// One solver step of `len` from `tau` after the communication point; where Newton fails
    /// (a whip faster than the step resolves), two steps of half the length instead, down to
    /// 2^-HALVINGS of it.
    fn advance(&mut self, tau: f64, len: f64, depth: u32) -> Result<(), AssemblyError> {
        match self.solve_to(tau + len, len) {
            Err(AssemblyError::NotConverged { .. }) if depth < HALVINGS => {
                self.advance(tau, 0.5 * len, depth + 1)?;
                self.advance(tau + 0.5 * len, 0.5 * len, depth + 1)
            }
            done => done,
        }
    }

    /// One solver step of `len` ending `tau` after the communication point.
    fn solve_to(&mut self, tau: f64, len: f64) -> Result<(), AssemblyError> {
        for i in 0..self.drives_now.len() {
            self.drives_now[i] = self.inputs.drives[i] + tau * self.inputs.drive_rates[i];
        }
        for i in 0..self.loads_now.len() {
            self.loads_now[i] = self.inputs.loads[i] + tau * self.inputs.load_rates[i];
        }
        let now = Instant {
            t: self.time + tau,
            host: self.inputs.host.at(tau),
            drives: &self.drives_now,
            loads: &self.loads_now,
        };
        self.solver.step(&self.system, &mut self.motion, len, &now)?;
        Self::update_angles(&self.system, &self.motion.pos, &now.host, &mut self.angles);
        Ok(())
    }

    fn update_angles(system: &System, pos: &[f64], host: &HostPose, angles: &mut [f64]) {
        for (j, joint) in system.joints.iter().enumerate() {
            if joint.kind == JointKind::Revolute {
                let f = system.frames_of(pos, &joint.a, &joint.b, host);
                let raw = joint::relative_angle(&f);
                angles[j] += joint::wrap(raw - angles[j]);
            }
        }
    }

    /// The state or the inputs changed: the outputs' accelerations and multipliers are solved
    /// again when next read.
    pub fn forget_outputs(&mut self) {
        self.out_valid = false;
    }

    /// The accelerations and multipliers of the present state and inputs (index 1).
    pub fn settle_outputs(&mut self) -> Result<(), AssemblyError> {
        if self.out_valid {
            return Ok(());
        }
        let now = Instant {
            t: self.time,
            host: self.inputs.host.at(0.0),
            drives: &self.inputs.drives,
            loads: &self.inputs.loads,
        };
        self.solver.consistent(&self.system, &self.motion, &now, &mut self.out_acc, &mut self.out_lambda)?;
        self.out_valid = true;
        Ok(())
    }

    /// The accelerations the outputs use (valid after [`Self::settle_outputs`]).
    pub fn output_accelerations(&self) -> &[f64] {
        &self.out_acc
    }

    /// The instant of the communication point (inputs at their present values).
    pub fn now(&self) -> Instant<'_> {
        Instant { t: self.time, host: self.inputs.host.at(0.0), drives: &self.inputs.drives, loads: &self.inputs.loads }
    }

    /// A joint's angle (revolute) or position (prismatic), and its rate.
    pub fn joint_motion(&self, j: usize) -> (f64, f64) {
        let s = &self.system;
        let joint = &s.joints[j];
        let now = self.now();
        let f = s.frames_of(&self.motion.pos, &joint.a, &joint.b, &now.host);
        let rates = |a: &Attach| match *a {
            Attach::Body { body, marker, .. } => s.marker_velocity(&self.motion.pos, &self.motion.vel, body, marker),
            Attach::Host => (self.inputs.host.v, self.inputs.host.w),
            Attach::Ground { .. } => ([0.0; 3], [0.0; 3]),
        };
        let ((va, wa), (vb, wb)) = (rates(&joint.a), rates(&joint.b));
        let e3 = axis(&f.fa, 2);
        match joint.kind {
            JointKind::Revolute => (self.angles[j], k3::dot(e3, k3::sub(wb, wa))),
            JointKind::Prismatic => (joint::relative_position(&f, joint.offset), k3::dot(e3, k3::sub(vb, va))),
            _ => (0.0, 0.0),
        }
    }

    /// A joint's force and torque on its second side, in the first side's joint axes (after
    /// [`Self::settle_outputs`]).
    pub fn joint_reaction(&self, j: usize) -> (Vec3, Vec3) {
        let (f, t, frames) = self.system.joint_wrench(&self.motion.pos, j, &self.now(), &self.out_lambda);
        (k3::mul_t(&frames.fa, f), k3::mul_t(&frames.fa, t))
    }

    /// The force and torque (world) the host's frame applies to the body at a motion flange.
    pub fn mount_reaction(&self) -> (Vec3, Vec3) {
        let j = self.system.joints.iter().position(|j| j.a == Attach::Host);
        j.map_or(([0.0; 3], [0.0; 3]), |j| {
            let (f, t, _) = self.system.joint_wrench(&self.motion.pos, j, &self.now(), &self.out_lambda);
            (f, t)
        })
    }

    /// The largest violation of a joint's equations at position level [m, or rad].
    pub fn drift(&self) -> f64 {
        let now = self.now();
        (0..self.system.joints.len())
            .map(|j| {
                let e = self.system.joint_equations(&self.motion.pos, j, &now);
                e.value[..e.len].iter().fold(0.0f64, |m, x| m.max(x.abs()))
            })
            .fold(0.0, f64::max)
    }

    /// Kinetic, strain and gravity energy.
    pub fn energies(&self, cr_q: &mut [f64]) -> [f64; 3] {
        self.system.energies(&self.motion.pos, &self.motion.vel, cr_q)
    }
}

fn copy_motion(to: &mut Motion, from: &Motion) {
    to.pos.copy_from_slice(&from.pos);
    to.vel.copy_from_slice(&from.vel);
    to.acc.copy_from_slice(&from.acc);
    to.pseudo.copy_from_slice(&from.pseudo);
    to.lambda.copy_from_slice(&from.lambda);
}

fn copy_inputs(to: &mut Inputs, from: &Inputs) {
    to.host = from.host;
    to.drives.copy_from_slice(&from.drives);
    to.drive_rates.copy_from_slice(&from.drive_rates);
    to.loads.copy_from_slice(&from.loads);
    to.load_rates.copy_from_slice(&from.load_rates);
}

/// Rows of `jac` (rows x cols) that depend on earlier ones, with the earlier rows they combine
/// (modified Gram-Schmidt with the combinations kept); None when all are independent.
pub fn dependent_rows(jac: &[f64], rows: usize, cols: usize) -> Option<Vec<usize>> {
    let mut basis: Vec<(Vec<f64>, Vec<f64>)> = Vec::new(); // (orthonormal row, its combination of rows)
    for r in 0..rows {
        let mut v = jac[r * cols..(r + 1) * cols].to_vec();
        let norm0 = v.iter().map(|x| x * x).sum::<f64>().sqrt();
        let mut comb = vec![0.0; rows];
        comb[r] = 1.0;
        for (q, qc) in &basis {
            let d: f64 = q.iter().zip(&v).map(|(a, b)| a * b).sum();
            for (x, y) in v.iter_mut().zip(q) {
                *x -= d * y;
            }
            for (x, y) in comb.iter_mut().zip(qc) {
                *x -= d * y;
            }
        }
        let norm = v.iter().map(|x| x * x).sum::<f64>().sqrt();
        // a row whose part outside the earlier rows' span is round-off
        if norm <= 1e-9 * norm0.max(1e-300) {
            let mut involved: Vec<usize> = (0..rows).filter(|&k| comb[k].abs() > 1e-9).collect();
            involved.sort_unstable();
            return Some(involved);
        }
        for x in &mut v {
            *x /= norm;
        }
        for x in &mut comb {
            *x /= norm;
        }
        basis.push((v, comb));
    }
    None
}

#[cfg(test)]
mod tests;
