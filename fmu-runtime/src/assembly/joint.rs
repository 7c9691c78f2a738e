//! Joints as constraint equations between two joint frames, A (on the first flange) and B (on the
//! second), each a point p and axes (columns of a rotation matrix, world): a1 a2 a3 and b1 b2 b3.
//! Every equation comes with its gradient with respect to a small motion of each frame: a shift
//! dp and a turn dtheta, both in world axes (12 numbers: dpA, dthetaA, dpB, dthetaB), from which
//! the assembly chains the bodies' velocities. The frames coincide at the start (a prismatic
//! joint's B may sit anywhere: its offset in A's axes at the start is kept).
//!
//! | joint | equations |
//! |---|---|
//! | weld | d = pB - pA = 0; a2.b3 = a3.b1 = a1.b2 = 0 |
//! | revolute about a3 | d = 0; a1.b3 = a2.b3 = 0 |
//! | prismatic along a3 | a1.d = c1, a2.d = c2; a2.b3 = a3.b1 = a1.b2 = 0 |
//! | spherical | d = 0 |
//! | universal, a1 on A, b2 on B | d = 0; a1.b2 = 0 |
//!
//! A driven revolute joint adds angle(A, B) = theta(t), the angle of b1 about a3 from a1; a
//! driven prismatic joint adds a3.d - c3 = s(t).

use crate::kinematics::{self as k3, Mat3, Vec3};

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum JointKind {
    Weld,
    Revolute,
    Prismatic,
    Spherical,
    Universal,
}

impl JointKind {
    /// Equations without a drive.
    pub fn equations(self) -> usize {
        match self {
            JointKind::Weld => 6,
            JointKind::Revolute | JointKind::Prismatic => 5,
            JointKind::Spherical => 3,
            JointKind::Universal => 4,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            JointKind::Weld => "weld",
            JointKind::Revolute => "revolute",
            JointKind::Prismatic => "prismatic",
            JointKind::Spherical => "spherical",
            JointKind::Universal => "universal",
        }
    }

    pub fn from_name(name: &str) -> Option<Self> {
        [JointKind::Weld, JointKind::Revolute, JointKind::Prismatic, JointKind::Spherical, JointKind::Universal]
            .into_iter()
            .find(|k| k.name() == name)
    }
}

/// The two joint frames at one instant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Frames {
    pub pa: Vec3,
    pub fa: Mat3,
    pub pb: Vec3,
    pub fb: Mat3,
}

/// Axis i of a frame (column i).
#[inline]
pub fn axis(f: &Mat3, i: usize) -> Vec3 {
    [f[i], f[3 + i], f[6 + i]]
}

/// Up to six equations: values and gradients [dpA, dthetaA, dpB, dthetaB].
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Equations {
    pub len: usize,
    pub value: [f64; 6],
    pub grad: [[f64; 12]; 6],
}

impl Equations {
    fn push(&mut self, value: f64, grad: [f64; 12]) {
        self.value[self.len] = value;
        self.grad[self.len] = grad;
        self.len += 1;
    }

    /// pB - pA = 0, three equations.
    fn coincide(&mut self, f: &Frames) {
        for i in 0..3 {
            let mut g = [0.0; 12];
            g[i] = -1.0;
            g[6 + i] = 1.0;
            self.push(f.pb[i] - f.pa[i], g);
        }
    }

    /// a_i . b_j = 0.
    fn perpendicular(&mut self, f: &Frames, i: usize, j: usize) {
        let (a, b) = (axis(&f.fa, i), axis(&f.fb, j));
        let ga = k3::cross(a, b);
        let mut g = [0.0; 12];
        g[3..6].copy_from_slice(&ga);
        g[9..12].copy_from_slice(&k3::scale(-1.0, ga));
        self.push(k3::dot(a, b), g);
    }

    /// a_i . (pB - pA) = c.
    fn along(&mut self, f: &Frames, i: usize, c: f64) {
        let a = axis(&f.fa, i);
        let d = k3::sub(f.pb, f.pa);
        let mut g = [0.0; 12];
        g[..3].copy_from_slice(&k3::scale(-1.0, a));
        g[3..6].copy_from_slice(&k3::cross(a, d));
        g[6..9].copy_from_slice(&a);
        self.push(k3::dot(a, d) - c, g);
    }

    /// angle(A, B) - target, wrapped into (-pi, pi].
    fn angle(&mut self, f: &Frames, target: f64) {
        let (a1, a2, b1) = (axis(&f.fa, 0), axis(&f.fa, 1), axis(&f.fb, 0));
        let (x, y) = (k3::dot(a1, b1), k3::dot(a2, b1));
        let r2 = x * x + y * y;
        // d(atan2(y, x)) = (x dy - y dx) / r2; d(a_i . b1) = dthetaA . (a_i x b1) - dthetaB . (a_i x b1)
        let ga: Vec3 = std::array::from_fn(|k| (x * k3::cross(a2, b1)[k] - y * k3::cross(a1, b1)[k]) / r2);
        let mut g = [0.0; 12];
        g[3..6].copy_from_slice(&ga);
        g[9..12].copy_from_slice(&k3::scale(-1.0, ga));
        self.push(wrap(y.atan2(x) - target), g);
    }
}

/// x wrapped into (-pi, pi].
pub fn wrap(x: f64) -> f64 {
    let t = std::f64::consts::TAU;
    let w = x - t * (x / t).round();
    if w <= -std::f64::consts::PI { w + t } else { w }
}

/// The joint's equations at `frames`. `offset`: a prismatic joint's B in A's axes at the start;
/// `drive`: the driven angle (revolute) or position along a3 (prismatic) at this instant.
pub fn equations(kind: JointKind, frames: &Frames, offset: Vec3, drive: Option<f64>) -> Equations {
    let mut e = Equations::default();
    let f = frames;
    match kind {
        JointKind::Weld => {
            e.coincide(f);
            e.perpendicular(f, 1, 2);
            e.perpendicular(f, 2, 0);
            e.perpendicular(f, 0, 1);
        }
        JointKind::Revolute => {
            e.coincide(f);
            e.perpendicular(f, 0, 2);
            e.perpendicular(f, 1, 2);
            if let Some(theta) = drive {
                e.angle(f, theta);
            }
        }
        JointKind::Prismatic => {
            e.along(f, 0, offset[0]);
            e.along(f, 1, offset[1]);
            e.perpendicular(f, 1, 2);
            e.perpendicular(f, 2, 0);
            e.perpendicular(f, 0, 1);
            if let Some(s) = drive {
                e.along(f, 2, offset[2] + s);
            }
        }
        JointKind::Spherical => e.coincide(f),
        JointKind::Universal => {
            e.coincide(f);
            e.perpendicular(f, 0, 1);
        }
    }
    e
}

/// The angle of b1 about a3 from a1 (revolute), wrapped into (-pi, pi].
pub fn relative_angle(frames: &Frames) -> f64 {
    let (a1, a2, b1) = (axis(&frames.fa, 0), axis(&frames.fa, 1), axis(&frames.fb, 0));
    k3::dot(a2, b1).atan2(k3::dot(a1, b1))
}

/// B's position along a3 from A, less the start's offset (prismatic).
pub fn relative_position(frames: &Frames, offset: Vec3) -> f64 {
    k3::dot(axis(&frames.fa, 2), k3::sub(frames.pb, frames.pa)) - offset[2]
}

/// A frame (columns) whose third axis is `axis` (unit), the first chosen perpendicular to it.
pub fn frame_about(axis3: Vec3) -> Mat3 {
    let pick = if axis3[0].abs() < 0.9 { [1.0, 0.0, 0.0] } else { [0.0, 1.0, 0.0] };
    let e1 = normalized(k3::sub(pick, k3::scale(k3::dot(pick, axis3), axis3)));
    let e2 = k3::cross(axis3, e1);
    columns(e1, e2, axis3)
}

/// A frame whose first axis is `first` and second `second` (unit, perpendicular).
pub fn frame_of_pair(first: Vec3, second: Vec3) -> Mat3 {
    columns(first, second, k3::cross(first, second))
}

pub fn columns(e1: Vec3, e2: Vec3, e3: Vec3) -> Mat3 {
    [e1[0], e2[0], e3[0], e1[1], e2[1], e3[1], e1[2], e2[2], e3[2]]
}

pub fn normalized(v: Vec3) -> Vec3 {
    let n = k3::dot(v, v).sqrt();
    k3::scale(1.0 / n, v)
}

/// R^T of a rotation matrix.
pub fn transpose(m: &Mat3) -> Mat3 {
    [m[0], m[3], m[6], m[1], m[4], m[7], m[2], m[5], m[8]]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kinematics::rotation_of;

    fn frames(seed: f64) -> Frames {
        let fa = rotation_of([0.3 + seed, -0.2, 0.5]);
        let fb = k3::mat_mul(&rotation_of([0.01, -0.02, 0.7 * seed]), &fa);
        Frames { pa: [0.1, 0.2, 0.3], fa, pb: [0.11, 0.19, 0.32 + seed], fb }
    }

    /// Moved by e_k * h in the 12 coordinates: shifts, and turns about world axes.
    fn moved(f: &Frames, k: usize, h: f64) -> Frames {
        let mut d = [0.0; 3];
        d[k % 3] = h;
        let mut g = *f;
        match k / 3 {
            0 => g.pa = k3::add(g.pa, d),
            1 => g.fa = k3::mat_mul(&rotation_of(d), &g.fa),
            2 => g.pb = k3::add(g.pb, d),
            _ => g.fb = k3::mat_mul(&rotation_of(d), &g.fb),
        }
        g
    }

    #[test]
    fn gradients_match_central_differences() {
        let h = 1e-6;
        for kind in
            [JointKind::Weld, JointKind::Revolute, JointKind::Prismatic, JointKind::Spherical, JointKind::Universal]
        {
            for drive in [None, Some(0.4)] {
                if drive.is_some() && !matches!(kind, JointKind::Revolute | JointKind::Prismatic) {
                    continue;
                }
                let f = frames(0.05);
                let offset = [0.01, -0.02, 0.03];
                let e = equations(kind, &f, offset, drive);
                assert_eq!(e.len, kind.equations() + usize::from(drive.is_some()), "{kind:?}");
                for k in 0..12 {
                    let (up, down) = (
                        equations(kind, &moved(&f, k, h), offset, drive),
                        equations(kind, &moved(&f, k, -h), offset, drive),
                    );
                    for i in 0..e.len {
                        let fd = (up.value[i] - down.value[i]) / (2.0 * h);
                        // central differences at h = 1e-6 of functions of size 1: about 1e-10
                        assert!(
                            (fd - e.grad[i][k]).abs() < 1e-8,
                            "{kind:?} eq {i} coord {k}: {fd} vs {}",
                            e.grad[i][k]
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn coincident_frames_satisfy_every_joint() {
        let fa = rotation_of([0.3, -0.2, 0.5]);
        let f = Frames { pa: [1.0, 2.0, 3.0], fa, pb: [1.0, 2.0, 3.0], fb: fa };
        for kind in
            [JointKind::Weld, JointKind::Revolute, JointKind::Prismatic, JointKind::Spherical, JointKind::Universal]
        {
            let e = equations(kind, &f, [0.0; 3], Some(0.0));
            assert!(e.value[..e.len].iter().all(|v| v.abs() < 1e-15), "{kind:?}");
        }
    }

    #[test]
    fn revolute_leaves_its_axis_free_and_measures_the_angle() {
        let fa = rotation_of([0.3, -0.2, 0.5]);
        let turn = rotation_of(k3::scale(2.5, axis(&fa, 2)));
        let f = Frames { pa: [0.0; 3], fa, pb: [0.0; 3], fb: k3::mat_mul(&turn, &fa) };
        let e = equations(JointKind::Revolute, &f, [0.0; 3], None);
        assert!(e.value[..5].iter().all(|v| v.abs() < 1e-15));
        assert!((relative_angle(&f) - 2.5).abs() < 1e-14);
        let driven = equations(JointKind::Revolute, &f, [0.0; 3], Some(2.5 - std::f64::consts::TAU));
        assert!(driven.value[5].abs() < 1e-13, "the drive's target is taken modulo a turn");
    }

    #[test]
    fn wrap_is_into_the_half_open_interval() {
        use std::f64::consts::PI;
        assert_eq!(wrap(0.0), 0.0);
        assert!((wrap(3.0 * PI) - PI).abs() < 1e-15);
        assert!((wrap(-PI) - PI).abs() < 1e-15);
        assert!((wrap(7.0) - (7.0 - 2.0 * PI)).abs() < 1e-15);
    }
}
