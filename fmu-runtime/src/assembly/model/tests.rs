//! Rigid limits against Lagrange's equations, integrated here by classical Runge-Kutta at a
//! step a hundred times shorter; energy; redundant and misassembled joints refused.

use super::*;
use crate::assembly::description::{
    BodyDescription, BodyModel, Drive, DriveFunction, DriveQuantity, JointDescription, Side, SolverSettings,
};

const L: f64 = 1.0;
const M: f64 = 7850.0 * 1.0 * 0.01 * 0.02;
const G: f64 = 9.81;

fn bar(name: &str, position: Vec3, rotation: Mat3) -> BodyDescription {
    let iyy = M * (L * L + 0.02 * 0.02) / 12.0;
    let ixx = M * (0.01f64.powi(2) + 0.02f64.powi(2)) / 12.0;
    let izz = M * (L * L + 0.01 * 0.01) / 12.0;
    BodyDescription {
        name: name.into(),
        position,
        rotation,
        model: BodyModel::Rigid {
            mass: M,
            centre: [L / 2.0, 0.0, 0.0],
            inertia_at_centre: [ixx, 0.0, 0.0, 0.0, iyy, 0.0, 0.0, 0.0, izz],
            flanges: vec![("base".into(), [0.0; 3]), ("tip".into(), [L, 0.0, 0.0])],
        },
    }
}

fn revolute(name: &str, first: Side, second: Side) -> JointDescription {
    JointDescription {
        name: name.into(),
        kind: JointKind::Revolute,
        first,
        second,
        axes: [[0.0, 1.0, 0.0], [0.0; 3]],
        drive: None,
    }
}

fn double_pendulum(settings: SolverSettings) -> AssemblyDescription {
    let rot = rotation_of([0.0, std::f64::consts::FRAC_PI_4, 0.0]);
    let elbow = k3::mul(&rot, [L, 0.0, 0.0]);
    AssemblyDescription {
        guid: String::new(),
        model_name: "DoublePendulum".into(),
        gravity: [0.0, 0.0, -G],
        bodies: vec![bar("upper", [0.0; 3], rot), bar("lower", elbow, rot)],
        joints: vec![
            revolute("pivot", Side::Ground, Side::Body { body: 0, marker: 0 }),
            revolute("elbow", Side::Body { body: 0, marker: 1 }, Side::Body { body: 1, marker: 0 }),
        ],
        flanges: vec![],
        solver: settings,
    }
}

/// Two uniform bars end to end from a pivot, absolute angles from the downward vertical.
fn lagrange_rates(y: [f64; 4]) -> [f64; 4] {
    let [p1, p2, w1, w2] = y;
    let (c, inertia) = (L / 2.0, M * (L * L + 0.02 * 0.02) / 12.0);
    let d = p1 - p2;
    let m11 = inertia + M * c * c + M * L * L;
    let m12 = M * L * c * d.cos();
    let m22 = inertia + M * c * c;
    let f1 = -M * L * c * d.sin() * w2 * w2 - (M * c + M * L) * G * p1.sin();
    let f2 = M * L * c * d.sin() * w1 * w1 - M * c * G * p2.sin();
    let det = m11 * m22 - m12 * m12;
    [w1, w2, (m22 * f1 - m12 * f2) / det, (m11 * f2 - m12 * f1) / det]
}

fn lagrange(seconds: f64, dt: f64) -> Vec<[f64; 4]> {
    let mut y = [std::f64::consts::FRAC_PI_4; 2].iter().chain(&[0.0, 0.0]).copied().collect::<Vec<_>>();
    let mut out = Vec::new();
    let steps = (seconds / dt).round() as usize;
    let point =
        |y: &[f64]| [L * y[0].sin(), -L * y[0].cos(), L * (y[0].sin() + y[1].sin()), -L * (y[0].cos() + y[1].cos())];
    out.push(point(&y));
    for _ in 0..steps {
        let s = |y: &[f64], k: &[f64; 4], f: f64| -> [f64; 4] { std::array::from_fn(|i| y[i] + f * dt * k[i]) };
        let k1 = lagrange_rates([y[0], y[1], y[2], y[3]]);
        let k2 = lagrange_rates(s(&y, &k1, 0.5));
        let k3_ = lagrange_rates(s(&y, &k2, 0.5));
        let k4 = lagrange_rates(s(&y, &k3_, 1.0));
        for i in 0..4 {
            y[i] += dt / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3_[i] + k4[i]);
        }
        out.push(point(&y));
    }
    out
}

fn run(settings: SolverSettings, h: f64, seconds: f64) -> (Vec<[f64; 4]>, Vec<f64>, Assembly) {
    let mut a = Assembly::new(&double_pendulum(settings)).unwrap();
    a.start_run(0.0).unwrap();
    let mut cr = vec![0.0; 12];
    let mut points = Vec::new();
    let mut energy = Vec::new();
    let steps = (seconds / h).round() as usize;
    for k in 0..=steps {
        if k > 0 {
            a.do_step(h).unwrap();
        }
        let elbow = a.system.marker_pose(&a.motion.pos, 0, 1).p;
        let tip = a.system.marker_pose(&a.motion.pos, 1, 1).p;
        points.push([elbow[0], elbow[2], tip[0], tip[2]]);
        energy.push(a.energies(&mut cr).iter().sum());
    }
    (points, energy, a)
}

fn max_error(ours: &[[f64; 4]], theirs: &[[f64; 4]], every: usize) -> f64 {
    ours.iter()
        .enumerate()
        .map(|(k, p)| (0..4).map(|i| (p[i] - theirs[k * every][i]).abs()).fold(0.0, f64::max))
        .fold(0.0, f64::max)
}

#[test]
fn rigid_double_pendulum_follows_lagrange_at_second_order() {
    let settings = SolverSettings { spectral_radius: 1.0, tolerance: 1e-12, max_iterations: 12, max_step: 1.0 };
    let reference = lagrange(2.0, 1e-5);
    let (coarse, energy, a) = run(settings, 2e-3, 2.0);
    let (fine, _, _) = run(settings, 1e-3, 2.0);
    let (e_coarse, e_fine) = (max_error(&coarse, &reference, 200), max_error(&fine, &reference, 100));
    // the elbow and tip swing over about 2 m; second order: halving h quarters the error
    assert!(e_fine < 2e-3, "error at h = 1 ms: {e_fine} m");
    let order = (e_coarse / e_fine).log2();
    assert!((1.7..2.4).contains(&order), "order {order} ({e_coarse} -> {e_fine})");
    let swing = M * G * L; // the energies' scale
    let drift = energy.iter().map(|e| (e - energy[0]).abs()).fold(0.0, f64::max);
    // trapezoidal on a nonlinear system: bounded oscillation of order (h w)^2, no growth
    assert!(drift < 1e-3 * swing, "energy drift {drift} J");
    assert!(a.drift() < 1e-11, "joints hold at position level: {}", a.drift());
}

#[test]
fn joint_outputs_follow_the_pendulum() {
    let settings = SolverSettings { spectral_radius: 1.0, tolerance: 1e-12, max_iterations: 12, max_step: 1.0 };
    let mut a = Assembly::new(&double_pendulum(settings)).unwrap();
    a.start_run(0.0).unwrap();
    // at rest at the start, the pivot carries both bars' weight less what accelerates: check
    // that the elbow's reaction on the lower bar plus its weight gives its momentum's rate
    for _ in 0..300 {
        a.do_step(1e-3).unwrap();
    }
    let (angle, rate) = a.joint_motion(0);
    let (before, _) = a.joint_motion(0);
    assert_eq!(angle, before);
    let pose = a.system.marker_pose(&a.motion.pos, 0, 0);
    let x = axis(&pose.frame, 0);
    // the angle about y from the start's axis (45 degrees below the horizontal)
    let start = [std::f64::consts::FRAC_1_SQRT_2, 0.0, -std::f64::consts::FRAC_1_SQRT_2];
    let measured = k3::dot(k3::cross(start, x), [0.0, 1.0, 0.0]).atan2(k3::dot(start, x));
    assert!((angle - measured).abs() < 1e-12, "{angle} vs {measured}");
    assert!(rate.abs() > 0.1);
    // lower bar: m a_c = f_elbow + m g, f from the elbow joint's reaction (first side's axes =
    // the upper bar's joint frame)
    a.settle_outputs().unwrap();
    let (f_local, _) = a.joint_reaction(1);
    let j = &a.system.joints[1];
    let frames = a.system.frames_of(&a.motion.pos, &j.a, &j.b, &a.now().host);
    let f = k3::mul(&frames.fa, f_local);
    let acc = a.output_accelerations().to_vec();
    let (acc_origin, _) = a.system.marker_rates(&a.motion.pos, &a.motion.vel, Some(&acc), 1, 0);
    let b = &a.system.bodies[1];
    let (_, rot, _) = a.system.body_pose(&a.motion.pos, 1);
    let w = super::super::inertia::vel3(&a.motion.vel[b.slot..], 3);
    let wd = super::super::inertia::vel3(&acc[b.slot..], 3);
    let c = [L / 2.0, 0.0, 0.0];
    let a_c = k3::add(acc_origin, k3::mul(&rot, k3::add(k3::cross(wd, c), k3::cross(w, k3::cross(w, c)))));
    for i in 0..3 {
        let balance = M * a_c[i] - f[i] - M * [0.0, 0.0, -G][i];
        assert!(balance.abs() < 1e-8 * M * G, "component {i}: {balance}");
    }
}

#[test]
fn a_driven_crank_turns_as_driven() {
    let mut d = double_pendulum(SolverSettings::default());
    d.bodies.truncate(1);
    d.joints.truncate(1);
    d.joints[0].drive =
        Some(Drive { quantity: DriveQuantity::Motion, function: DriveFunction::SpinUp { speed: 6.0, time: 0.5 } });
    let mut a = Assembly::new(&d).unwrap();
    a.start_run(0.0).unwrap();
    for _ in 0..1000 {
        a.do_step(1e-3).unwrap();
    }
    let (angle, rate) = a.joint_motion(0);
    let [target, target_rate, _] = DriveFunction::SpinUp { speed: 6.0, time: 0.5 }.at(1.0, 0.0);
    // the drive's angle is held to Newton's tolerance; it passes a whole turn
    assert!(angle > std::f64::consts::TAU * 0.6);
    assert!((angle - target).abs() < 1e-9, "{angle} vs {target}");
    // index 3 holds positions exactly, velocities to second order in h: measured 2e-5 rad/s
    assert!((rate - target_rate).abs() < 2e-4, "{rate} vs {target_rate}");
}

#[test]
fn a_closed_loop_of_revolute_joints_is_refused_as_redundant() {
    // two bars from the ground to a common point, both revolute about y, and a third revolute
    // joint between their tips: planar loops lock out-of-plane motion twice
    let mut d = double_pendulum(SolverSettings::default());
    d.joints.push(revolute("extra", Side::Ground, Side::Body { body: 1, marker: 1 }));
    match Assembly::new(&d) {
        Err(AssemblyError::Redundant { joints }) => assert!(joints.contains(&"extra".to_string()), "{joints:?}"),
        other => panic!("{other:?}"),
    }
}

#[test]
fn a_gap_at_a_joint_is_refused() {
    let mut d = double_pendulum(SolverSettings::default());
    d.bodies[1].position[0] += 0.01;
    match Assembly::new(&d) {
        Err(AssemblyError::Misassembled { joint, gap }) => {
            assert_eq!(joint, "elbow");
            assert!((gap - 0.01).abs() < 1e-12);
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn a_driven_crank_needs_the_torque_of_its_inertia_and_weight() {
    let mut d = double_pendulum(SolverSettings { tolerance: 1e-12, ..SolverSettings::default() });
    d.bodies.truncate(1);
    d.bodies[0].rotation = k3::IDENTITY;
    d.joints.truncate(1);
    let law = DriveFunction::SpinUp { speed: 6.0, time: 0.5 };
    d.joints[0].drive = Some(Drive { quantity: DriveQuantity::Motion, function: law });
    let mut a = Assembly::new(&d).unwrap();
    a.start_run(0.0).unwrap();
    let j_pivot = M * (L * L + 0.02 * 0.02) / 12.0 + M * L * L / 4.0;
    for k in 1..=400 {
        a.do_step(1e-3).unwrap();
        if k % 50 == 0 {
            let [theta, _, theta_dd] = law.at(a.time, 0.0);
            let expected = j_pivot * theta_dd - M * G * L / 2.0 * theta.cos();
            a.settle_outputs().unwrap();
            let (_, t) = a.joint_reaction(0);
            // the joint frame's third axis is the joint's axis, y
            assert!((t[2] - expected).abs() < 1e-3 * M * G * L, "t = {}: {} vs {expected}", a.time, t[2]);
        }
    }
}

#[test]
fn a_reset_returns_to_the_start_and_its_parameters() {
    let mut a = Assembly::new(&double_pendulum(SolverSettings::default())).unwrap();
    let start = a.motion.pos.clone();
    a.system.gravity = [0.0, 0.0, -1.0];
    a.start_run(0.0).unwrap();
    for _ in 0..50 {
        a.do_step(1e-3).unwrap();
    }
    assert_ne!(a.motion.pos, start);
    a.reset();
    assert_eq!(a.motion.pos, start);
    assert_eq!(a.system.gravity, [0.0, 0.0, -G]);
    assert_eq!(a.time, 0.0);
}
