//! The assembly's equations over all bodies at once: where each flange is, the joints'
//! equations and their Jacobian in the bodies' velocity slots, and the residual of the equations
//! of motion with the joints' forces. Positions are stored per body as r (3), R (9, row-major),
//! q (n); velocities and accelerations per body as in [`super::inertia`].

use super::description::{
    AssemblyDescription, BodyModel, Drive, DriveFunction, DriveQuantity, FlangeRole, JointDescription, Side,
};
use super::error::AssemblyError;
use super::inertia::{Inertia, vel3};
use super::joint::{self, Equations, Frames, JointKind, axis, frame_about, frame_of_pair, transpose};
use crate::body::dense::shape_dot;
use crate::kinematics::{self as k3, IDENTITY, Mat3, Vec3, rotation_of};

#[derive(Debug, Clone)]
pub struct SystemBody {
    pub name: String,
    pub inertia: Inertia,
    /// First velocity slot and first position entry of the body.
    pub slot: usize,
    pub at: usize,
}

impl SystemBody {
    pub fn n_modes(&self) -> usize {
        self.inertia.n_modes()
    }
}

/// Where a joint frame sits.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Attach {
    /// Fixed in the world.
    Ground { position: Vec3, frame: Mat3 },
    /// The frame the host prescribes (a motion flange).
    Host,
    /// On a body's flange, `frame` in the flange's axes.
    Body { body: usize, marker: usize, frame: Mat3 },
}

#[derive(Debug, Clone)]
pub struct SystemJoint {
    pub name: String,
    pub kind: JointKind,
    pub a: Attach,
    pub b: Attach,
    /// A prismatic joint's B in A's axes at the start.
    pub offset: Vec3,
    pub drive: Option<Drive>,
    /// Index of the drive's input among the FMU's drive inputs.
    pub input: Option<usize>,
    /// First multiplier and number of equations.
    pub row: usize,
    pub rows: usize,
}

impl SystemJoint {
    fn motion_drive(&self) -> Option<&Drive> {
        self.drive.as_ref().filter(|d| d.quantity == DriveQuantity::Motion)
    }
}

/// Where a flange is and how its frame turns with the modes.
#[derive(Debug, Clone, Copy)]
pub struct MarkerPose {
    pub p: Vec3,
    /// The flange's axes in the world: R exp(phi~).
    pub frame: Mat3,
    /// The flange's point in the body frame, deformed.
    pub s: Vec3,
    /// The body's rotation.
    pub rot: Mat3,
    /// Left Jacobian of exp at the flange's small rotation phi: its world rate is R J_L Psi q'.
    pub lj: Mat3,
}

/// The host's prescribed frame at one instant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HostPose {
    pub r: Vec3,
    pub rot: Mat3,
}

/// What the FMU's inputs set at one instant of a step.
#[derive(Debug, Clone, Copy)]
pub struct Instant<'a> {
    pub t: f64,
    pub host: HostPose,
    /// Drive inputs, in joint order of the drives set by inputs.
    pub drives: &'a [f64],
    /// External force flanges' (f, t), world, six per force flange in flange order.
    pub loads: &'a [f64],
}

#[derive(Debug, Clone)]
pub struct System {
    pub bodies: Vec<SystemBody>,
    pub joints: Vec<SystemJoint>,
    /// External flanges: (name, role, body, marker); a motion flange's weld is among `joints`.
    pub flanges: Vec<(String, FlangeRole, usize, usize)>,
    pub gravity: Vec3,
    /// Velocity slots, position entries, joint equations.
    pub n_vel: usize,
    pub n_pos: usize,
    pub n_eq: usize,
    /// Drives set by inputs, as (joint, quantity).
    pub drive_inputs: Vec<(usize, DriveQuantity)>,
}

fn left_jacobian(phi: Vec3) -> Mat3 {
    let t2 = k3::dot(phi, phi);
    let (a, b) = if t2 < 1e-8 {
        (0.5 - t2 / 24.0, 1.0 / 6.0 - t2 / 120.0)
    } else {
        let t = t2.sqrt();
        ((1.0 - t.cos()) / t2, (t - t.sin()) / (t2 * t))
    };
    let s = [0.0, -phi[2], phi[1], phi[2], 0.0, -phi[0], -phi[1], phi[0], 0.0];
    let s2 = k3::mat_mul(&s, &s);
    std::array::from_fn(|i| IDENTITY[i] + a * s[i] + b * s2[i])
}

impl System {
    /// The system of `d` at its start pose (the bodies as placed, modes at rest).
    pub fn new(d: &AssemblyDescription) -> Result<(Self, Vec<f64>), AssemblyError> {
        let mut bodies = Vec::new();
        let (mut slot, mut at) = (0, 0);
        for b in &d.bodies {
            let inertia = match &b.model {
                BodyModel::Flexible(r) => {
                    let mut inertia = Inertia::flexible(&b.name, r, r.alpha, r.beta)?;
                    inertia.resolve_within(d.solver.max_step);
                    inertia
                }
                BodyModel::Rigid { mass, centre, inertia_at_centre, flanges } => {
                    Inertia::rigid(&b.name, *mass, *centre, *inertia_at_centre, flanges)?
                }
            };
            let n = inertia.n_modes();
            bodies.push(SystemBody { name: b.name.clone(), inertia, slot, at });
            slot += 6 + n;
            at += 12 + n;
        }
        let mut pos = vec![0.0; at];
        for (b, desc) in bodies.iter().zip(&d.bodies) {
            pos[b.at..b.at + 3].copy_from_slice(&desc.position);
            pos[b.at + 3..b.at + 12].copy_from_slice(&desc.rotation);
        }
        let mut system = Self {
            bodies,
            joints: Vec::new(),
            flanges: d.flanges.iter().map(|f| (f.name.clone(), f.role, f.body, f.marker)).collect(),
            gravity: d.gravity,
            n_vel: slot,
            n_pos: at,
            n_eq: 0,
            drive_inputs: Vec::new(),
        };
        for j in &d.joints {
            system.add_joint(j, &pos)?;
        }
        for f in &d.flanges {
            if f.role == FlangeRole::Motion {
                let b = Attach::Body { body: f.body, marker: f.marker, frame: IDENTITY };
                system.push_joint(format!("{}.mount", f.name), JointKind::Weld, Attach::Host, b, [0.0; 3], None);
            }
        }
        Ok((system, pos))
    }

    fn push_joint(&mut self, name: String, kind: JointKind, a: Attach, b: Attach, offset: Vec3, drive: Option<Drive>) {
        let rows = kind.equations() + usize::from(drive.is_some_and(|d| d.quantity == DriveQuantity::Motion));
        let input = drive.filter(|d| d.function == DriveFunction::Input).map(|d| {
            self.drive_inputs.push((self.joints.len(), d.quantity));
            self.drive_inputs.len() - 1
        });
        self.joints.push(SystemJoint { name, kind, a, b, offset, drive, input, row: self.n_eq, rows });
        self.n_eq += rows;
    }

    fn add_joint(&mut self, j: &JointDescription, pos: &[f64]) -> Result<(), AssemblyError> {
        let err = |reason: String| AssemblyError::Joint { joint: j.name.clone(), reason };
        let frame0 = match j.kind {
            JointKind::Revolute | JointKind::Prismatic => frame_about(j.axes[0]),
            JointKind::Universal => {
                if k3::dot(j.axes[0], j.axes[1]).abs() > 1e-6 {
                    return Err(err("its two axes are not perpendicular".into()));
                }
                frame_of_pair(j.axes[0], j.axes[1])
            }
            JointKind::Weld | JointKind::Spherical => IDENTITY,
        };
        let point = |s: Side| match s {
            Side::Ground => None,
            Side::Body { body, marker } => Some(self.marker_pose(pos, body, marker)),
        };
        let (pa, pb) = (point(j.first), point(j.second));
        let attach = |s: Side, pose: Option<MarkerPose>, other: Option<MarkerPose>| match (s, pose) {
            (Side::Body { body, marker }, Some(p)) => {
                Attach::Body { body, marker, frame: k3::mat_mul(&transpose(&p.frame), &frame0) }
            }
            _ => Attach::Ground { position: other.map_or([0.0; 3], |o| o.p), frame: frame0 },
        };
        let (a, b) = (attach(j.first, pa, pb), attach(j.second, pb, pa));
        if matches!((a, b), (Attach::Ground { .. }, Attach::Ground { .. })) {
            return Err(err("both its sides are the ground".into()));
        }
        let frames = self.frames_of(pos, &a, &b, &HostPose { r: [0.0; 3], rot: IDENTITY });
        let d = k3::sub(frames.pb, frames.pa);
        let offset = if j.kind == JointKind::Prismatic { k3::mul_t(&frames.fa, d) } else { [0.0; 3] };
        self.push_joint(j.name.clone(), j.kind, a, b, offset, j.drive);
        Ok(())
    }

    /// The pose of a body's flange.
    pub fn marker_pose(&self, pos: &[f64], body: usize, marker: usize) -> MarkerPose {
        let b = &self.bodies[body];
        let n = b.n_modes();
        let (r, rot, q) = self.body_pose(pos, body);
        let m = &b.inertia.markers[marker];
        let row = |i: usize| if n == 0 { 0.0 } else { shape_dot(&m.shapes[i * n..(i + 1) * n], q) };
        let u = [row(0), row(1), row(2)];
        let phi = [row(3), row(4), row(5)];
        let s = k3::add(m.position, u);
        let frame = if n == 0 { rot } else { k3::mat_mul(&rot, &rotation_of(phi)) };
        MarkerPose { p: k3::add(r, k3::mul(&rot, s)), frame, s, rot, lj: left_jacobian(phi) }
    }

    /// r, R, q of a body.
    pub fn body_pose<'p>(&self, pos: &'p [f64], body: usize) -> (Vec3, Mat3, &'p [f64]) {
        let b = &self.bodies[body];
        let p = &pos[b.at..];
        ([p[0], p[1], p[2]], std::array::from_fn(|i| p[3 + i]), &p[12..12 + b.n_modes()])
    }

    /// Where a joint frame is, and the flange's pose under it (None for the ground and the host).
    fn attach_frame(&self, pos: &[f64], a: &Attach, host: &HostPose) -> (Vec3, Mat3, Option<MarkerPose>) {
        match a {
            Attach::Ground { position, frame } => (*position, *frame, None),
            Attach::Host => (host.r, host.rot, None),
            Attach::Body { body, marker, frame } => {
                let p = self.marker_pose(pos, *body, *marker);
                (p.p, k3::mat_mul(&p.frame, frame), Some(p))
            }
        }
    }

    pub fn frames_of(&self, pos: &[f64], a: &Attach, b: &Attach, host: &HostPose) -> Frames {
        self.frames_and_poses(pos, a, b, host).0
    }

    /// The joint frames and the flange poses under them.
    fn frames_and_poses(
        &self,
        pos: &[f64],
        a: &Attach,
        b: &Attach,
        host: &HostPose,
    ) -> (Frames, [Option<MarkerPose>; 2]) {
        let ((pa, fa, pose_a), (pb, fb, pose_b)) = (self.attach_frame(pos, a, host), self.attach_frame(pos, b, host));
        (Frames { pa, fa, pb, fb }, [pose_a, pose_b])
    }

    /// The driven value of a joint's drive at `now`.
    pub fn drive_value(&self, joint: &SystemJoint, now: &Instant) -> f64 {
        joint.drive.map_or(0.0, |d| d.function.at(now.t, joint.input.map_or(0.0, |i| now.drives[i]))[0])
    }

    /// Joint `j`'s equations at `pos`.
    pub fn joint_equations(&self, pos: &[f64], j: usize, now: &Instant) -> Equations {
        self.equations_and_poses(pos, j, now).0
    }

    /// Joint `j`'s equations and the poses of its flanges.
    fn equations_and_poses(&self, pos: &[f64], j: usize, now: &Instant) -> (Equations, [Option<MarkerPose>; 2]) {
        let joint = &self.joints[j];
        let (frames, poses) = self.frames_and_poses(pos, &joint.a, &joint.b, &now.host);
        let drive = joint.motion_drive().map(|_| self.drive_value(joint, now));
        (joint::equations(joint.kind, &frames, joint.offset, drive), poses)
    }

    /// Adds scale * (gp . dp + gt . dtheta) of a flange's motion, in its body's velocity slots,
    /// to `out` (the body's slots): a row of the joints' Jacobian, or the generalised force of
    /// a world force gp and torque gt at the flange.
    pub fn add_gradient(&self, out: &mut [f64], body: usize, marker: usize, pose: &MarkerPose, gp: Vec3, gt: Vec3) {
        let b = &self.bodies[body];
        let n = b.n_modes();
        let gp_b = k3::mul_t(&pose.rot, gp);
        let gt_b = k3::mul_t(&pose.rot, gt);
        for i in 0..3 {
            out[i] += gp[i];
        }
        let w = k3::add(k3::cross(pose.s, gp_b), gt_b);
        for i in 0..3 {
            out[3 + i] += w[i];
        }
        if n > 0 {
            let gt_m = k3::mul_t(&pose.lj, gt_b);
            let shapes = &b.inertia.markers[marker].shapes;
            for k in 0..n {
                let mut s = 0.0;
                for i in 0..3 {
                    s += shapes[i * n + k] * gp_b[i] + shapes[(3 + i) * n + k] * gt_m[i];
                }
                out[6 + k] += s;
            }
        }
    }

    /// The joints' equations (phi, n_eq) and Jacobian (n_eq x n_vel, row-major) at `pos`.
    pub fn constraints(&self, pos: &[f64], now: &Instant, phi: &mut [f64], jac: &mut [f64]) {
        jac.fill(0.0);
        for (j, joint) in self.joints.iter().enumerate() {
            let (e, poses) = self.equations_and_poses(pos, j, now);
            for (side, attach) in [(0, &joint.a), (1, &joint.b)] {
                if let (Attach::Body { body, marker, .. }, Some(pose)) = (*attach, poses[side]) {
                    let slot = self.bodies[body].slot;
                    let width = 6 + self.bodies[body].n_modes();
                    for k in 0..e.len {
                        let g = &e.grad[k];
                        let row = &mut jac[(joint.row + k) * self.n_vel + slot..][..width];
                        let gp = [g[6 * side], g[6 * side + 1], g[6 * side + 2]];
                        let gt = [g[6 * side + 3], g[6 * side + 4], g[6 * side + 5]];
                        self.add_gradient(row, body, marker, &pose, gp, gt);
                    }
                }
            }
            phi[joint.row..joint.row + e.len].copy_from_slice(&e.value[..e.len]);
        }
    }

    /// The joints' equations alone, without their Jacobian.
    pub fn constraint_values(&self, pos: &[f64], now: &Instant, phi: &mut [f64]) {
        for (j, joint) in self.joints.iter().enumerate() {
            let (e, _) = self.equations_and_poses(pos, j, now);
            phi[joint.row..joint.row + e.len].copy_from_slice(&e.value[..e.len]);
        }
    }

    /// The forces the inputs apply (external force flanges, load drives) in the velocity slots,
    /// added to `out`.
    pub fn add_applied(&self, pos: &[f64], now: &Instant, out: &mut [f64]) {
        let mut k = 0;
        for (_, role, body, marker) in &self.flanges {
            if *role == FlangeRole::Force {
                let l = &now.loads[6 * k..6 * k + 6];
                k += 1;
                let pose = self.marker_pose(pos, *body, *marker);
                let slot = self.bodies[*body].slot;
                self.add_gradient(&mut out[slot..], *body, *marker, &pose, [l[0], l[1], l[2]], [l[3], l[4], l[5]]);
            }
        }
        for joint in &self.joints {
            let Some(d) = joint.drive.filter(|d| d.quantity == DriveQuantity::Load) else { continue };
            let load = d.function.at(now.t, joint.input.map_or(0.0, |i| now.drives[i]))[0];
            let frames = self.frames_of(pos, &joint.a, &joint.b, &now.host);
            let dir = k3::scale(load, axis(&frames.fa, 2));
            // torque (revolute) or force (prismatic) along the joint's axis on B, opposite on A
            let (on_b, on_a) = if joint.kind == JointKind::Revolute {
                (([0.0; 3], dir), ([0.0; 3], k3::scale(-1.0, dir)))
            } else {
                ((dir, [0.0; 3]), (k3::scale(-1.0, dir), [0.0; 3]))
            };
            for (attach, (f, t)) in [(&joint.b, on_b), (&joint.a, on_a)] {
                if let Attach::Body { body, marker, .. } = *attach {
                    let pose = self.marker_pose(pos, body, marker);
                    let slot = self.bodies[body].slot;
                    self.add_gradient(&mut out[slot..], body, marker, &pose, f, t);
                }
            }
        }
    }

    /// Every body's inertial, elastic and damping forces less its weight (`out`, n_vel).
    pub fn body_forces(&self, pos: &[f64], vel: &[f64], acc: &[f64], cr_q: &mut [f64], out: &mut [f64]) {
        for i in 0..self.bodies.len() {
            self.body_force(i, pos, vel, acc, cr_q, out);
        }
    }

    /// Body `i`'s part of [`Self::body_forces`].
    pub fn body_force(&self, i: usize, pos: &[f64], vel: &[f64], acc: &[f64], cr_q: &mut [f64], out: &mut [f64]) {
        let b = &self.bodies[i];
        let (_, rot, q) = self.body_pose(pos, i);
        let w = 6 + b.n_modes();
        let s = b.slot;
        b.inertia.forces(&rot, q, &vel[s..s + w], &acc[s..s + w], self.gravity, cr_q, &mut out[s..s + w]);
    }

    /// [`Self::body_forces`], and every body's mass matrix into its diagonal block of `matrix`
    /// (row stride `stride`) from the same deformed inertia.
    #[allow(clippy::too_many_arguments)]
    pub fn forces_and_mass(
        &self,
        pos: &[f64],
        vel: &[f64],
        acc: &[f64],
        cr_q: &mut [f64],
        forces: &mut [f64],
        matrix: &mut [f64],
        stride: usize,
    ) {
        for (i, b) in self.bodies.iter().enumerate() {
            let (_, rot, q) = self.body_pose(pos, i);
            let (w, at) = (6 + b.n_modes(), b.slot);
            let (s, j) = b.inertia.forces(
                &rot,
                q,
                &vel[at..at + w],
                &acc[at..at + w],
                self.gravity,
                cr_q,
                &mut forces[at..at + w],
            );
            b.inertia.mass_matrix(&rot, s, &j, cr_q, &mut matrix[at * stride + at..], stride);
        }
    }

    /// Every body's [`Inertia::iteration_block`] into its diagonal block of `matrix`.
    #[allow(clippy::too_many_arguments)]
    pub fn iteration_blocks(
        &self,
        pos: &[f64],
        vel: &[f64],
        cr_q: &mut [f64],
        pos_gain: f64,
        vel_gain: f64,
        matrix: &mut [f64],
        stride: usize,
    ) {
        for (i, b) in self.bodies.iter().enumerate() {
            let (_, rot, q) = self.body_pose(pos, i);
            let (s, j, _) = b.inertia.deformed(q, &vel[b.slot + 6..b.slot + 6 + b.inertia.n_moving], cr_q);
            let block = &mut matrix[b.slot * stride + b.slot..];
            b.inertia.iteration_block(&rot, s, &j, cr_q, pos_gain, vel_gain, block, stride);
        }
    }

    /// `pos` moved by the increment `dx` in the velocity slots: r + dr, R exp(dtheta~), q + dq.
    pub fn advance(&self, pos: &[f64], dx: &[f64], out: &mut [f64]) {
        for b in &self.bodies {
            let (p, d, o) = (&pos[b.at..], &dx[b.slot..], &mut out[b.at..]);
            for i in 0..3 {
                o[i] = p[i] + d[i];
            }
            let rot: Mat3 = std::array::from_fn(|i| p[3 + i]);
            let turned = k3::mat_mul(&rot, &rotation_of(vel3(d, 3)));
            o[3..12].copy_from_slice(&turned);
            for k in 0..b.n_modes() {
                o[12 + k] = p[12 + k] + d[6 + k];
            }
        }
    }

    /// Kinetic, strain and gravity energy of all bodies.
    pub fn energies(&self, pos: &[f64], vel: &[f64], cr_q: &mut [f64]) -> [f64; 3] {
        let mut e = [0.0; 3];
        for (i, b) in self.bodies.iter().enumerate() {
            let (r, rot, q) = self.body_pose(pos, i);
            let v = &vel[b.slot..b.slot + 6 + b.n_modes()];
            e[0] += b.inertia.kinetic_energy(&rot, q, v, cr_q);
            e[1] += b.inertia.strain_energy(q);
            e[2] += b.inertia.gravity_energy(r, &rot, q, self.gravity);
        }
        e
    }

    /// Zero the entries of modes from `from(body)` on: the accelerations of the modes without
    /// inertia, the velocities of the algebraic ones (their coordinates are solved in each step).
    pub fn zero_modes_from(&self, x: &mut [f64], from: impl Fn(&Inertia) -> usize) {
        for b in &self.bodies {
            x[b.slot + 6 + from(&b.inertia)..b.slot + 6 + b.n_modes()].fill(0.0);
        }
    }

    /// The largest modal count (scratch sizes).
    pub fn max_modes(&self) -> usize {
        self.bodies.iter().map(|b| b.n_modes()).max().unwrap_or(0)
    }

    /// A flange's world velocity and angular velocity.
    pub fn marker_velocity(&self, pos: &[f64], vel: &[f64], body: usize, marker: usize) -> (Vec3, Vec3) {
        self.marker_rates(pos, vel, None, body, marker)
    }

    /// A flange's world (v, w) from `vel`, or its (a, z) from `acc` with `vel` (the rate terms).
    pub fn marker_rates(
        &self,
        pos: &[f64],
        vel: &[f64],
        acc: Option<&[f64]>,
        body: usize,
        marker: usize,
    ) -> (Vec3, Vec3) {
        let b = &self.bodies[body];
        let n = b.n_modes();
        let pose = self.marker_pose(pos, body, marker);
        let shapes = &b.inertia.markers[marker].shapes;
        let rows = |x: &[f64], from: usize| -> Vec3 {
            if n == 0 { [0.0; 3] } else { std::array::from_fn(|i| shape_dot(&shapes[(from + i) * n..][..n], x)) }
        };
        let v = &vel[b.slot..];
        let (w, qd) = (vel3(v, 3), &v[6..6 + b.inertia.n_moving]);
        let (u_d, phi_d) = (rows(qd, 0), k3::mul(&pose.lj, rows(qd, 3)));
        match acc {
            None => (
                k3::add(vel3(v, 0), k3::mul(&pose.rot, k3::add(k3::cross(w, pose.s), u_d))),
                k3::mul(&pose.rot, k3::add(w, phi_d)),
            ),
            Some(acc) => {
                let a = &acc[b.slot..];
                let (w_d, qdd) = (vel3(a, 3), &a[6..6 + b.inertia.n_dynamic]);
                let (u_dd, phi_dd) = (rows(qdd, 0), k3::mul(&pose.lj, rows(qdd, 3)));
                let body_a = k3::add(
                    k3::add(k3::cross(w_d, pose.s), k3::cross(w, k3::cross(w, pose.s))),
                    k3::add(k3::scale(2.0, k3::cross(w, u_d)), u_dd),
                );
                (
                    k3::add(vel3(a, 0), k3::mul(&pose.rot, body_a)),
                    k3::mul(&pose.rot, k3::add(k3::add(w_d, phi_dd), k3::cross(w, phi_d))),
                )
            }
        }
    }

    /// A joint's wrench on its B side (world force at B's point, world torque) from its
    /// multipliers, and the frames it is resolved in.
    pub fn joint_wrench(&self, pos: &[f64], j: usize, now: &Instant, lambda: &[f64]) -> (Vec3, Vec3, Frames) {
        let joint = &self.joints[j];
        let e = self.joint_equations(pos, j, now);
        let (mut f, mut t) = ([0.0; 3], [0.0; 3]);
        for k in 0..e.len {
            let l = lambda[joint.row + k];
            for i in 0..3 {
                f[i] += l * e.grad[k][6 + i];
                t[i] += l * e.grad[k][9 + i];
            }
        }
        (f, t, self.frames_of(pos, &joint.a, &joint.b, &now.host))
    }
}
