//! Every family of FMU variables, in the order of the table: adding a variable is adding its
//! family here (and a test of its value). Names follow Naming: flange `tip` has inputs
//! `tip.f[i]`, `tip.t[i]`, outputs `tip.r[i]`, `tip.R[i,j]`, ...

use super::family::{
    Family, Initially, Nominal, Range, Role, Scope, Shape, StartRule, StateOf, Value, input, local, output, parameter,
    read,
};
use crate::body::{BodyError, FlexibleBody, FrameState};
use crate::scalar::{Scalar, c};
use fmi2::Initial;

fn frame<T: Scalar>(b: &FlexibleBody<T>) -> Result<FrameState<T>, BodyError> {
    b.frame().copied().ok_or(BodyError::NotFreeFloating)
}

/// The quantities of a stress recovery point, in component order; the names are
/// `STRESS_COMPONENTS`.
const fn stress(pattern: &'static str, description: &'static str, component: usize) -> Family {
    output(pattern, description, read!(? |b, at| b.stress(at.owner, at.i)))
        .scope(Scope::StressPoint)
        .shape(Shape::Component(component))
        .unit("Pa")
        // stresses follow the deformation as the flange displacements do
        .depends(|s, _, k| s.deformation(k))
}

pub static FAMILIES: &[Family] = &[
    // the mount's motion, set by the host, and the reaction it answers with
    input(
        "<mount>.r[i]",
        "Mount position, {axis} component, world frame",
        Role::MountPosition,
        read!(|b, at| b.mount().r[at.i]),
    )
    .scope(Scope::Mounted)
    .unit("m")
    .write(|b, at, x| b.mount_mut().r[at.i] = x)
    .seed(|b, at| Some(&mut b.mount_mut().r[at.i]))
    .rate(|b, at, x| b.mount_rate_mut().r[at.i] = x),
    input(
        "<mount>.R[i,j]",
        "Mount orientation, row {row} column {column} (columns: frame axes in world)",
        Role::MountRotation,
        read!(|b, at| b.mount().rot[3 * at.i + at.j]),
    )
    .scope(Scope::Mounted)
    .shape(Shape::Matrix)
    .start(StartRule::Identity)
    .unit("1")
    .range(Range::RotationEntry)
    .write(|b, at, x| b.set_mount_rotation(3 * at.i + at.j, x))
    .seed(|b, at| Some(&mut b.mount_mut().rot[3 * at.i + at.j]))
    .rate(|b, at, x| b.mount_rate_mut().rot[3 * at.i + at.j] = x),
    input(
        "<mount>.v[i]",
        "Mount velocity, {axis} component, world frame",
        Role::MountVelocity,
        read!(|b, at| b.mount().v[at.i]),
    )
    .scope(Scope::Mounted)
    .unit("m/s")
    .write(|b, at, x| b.mount_mut().v[at.i] = x)
    .seed(|b, at| Some(&mut b.mount_mut().v[at.i]))
    .rate(|b, at, x| b.mount_rate_mut().v[at.i] = x),
    input(
        "<mount>.w[i]",
        "Mount angular velocity, {axis} component, world frame",
        Role::MountSpin,
        read!(|b, at| b.mount().w[at.i]),
    )
    .scope(Scope::Mounted)
    .unit("rad/s")
    .write(|b, at, x| b.set_mount_spin(at.i, x))
    .seed(|b, at| Some(&mut b.mount_mut().w[at.i]))
    .rate(|b, at, x| b.mount_rate_mut().w[at.i] = x),
    input(
        "<mount>.a[i]",
        "Mount acceleration, {axis} component, world frame",
        Role::MountAcceleration,
        read!(|b, at| b.mount().a[at.i]),
    )
    .scope(Scope::Mounted)
    .unit("m/s2")
    .write(|b, at, x| b.mount_mut().a[at.i] = x)
    .seed(|b, at| Some(&mut b.mount_mut().a[at.i]))
    .rate(|b, at, x| b.mount_rate_mut().a[at.i] = x),
    input(
        "<mount>.z[i]",
        "Mount angular acceleration, {axis} component, world frame",
        Role::MountAngularAcceleration,
        read!(|b, at| b.mount().z[at.i]),
    )
    .scope(Scope::Mounted)
    .unit("rad/s2")
    .write(|b, at, x| b.mount_mut().z[at.i] = x)
    .seed(|b, at| Some(&mut b.mount_mut().z[at.i]))
    .rate(|b, at, x| b.mount_rate_mut().z[at.i] = x),
    output(
        "<mount>.f[i]",
        "Force the mount applies to the body, {axis} component, world frame",
        read!(|b, at| b.mount_reaction()?.0[at.i]),
    )
    .scope(Scope::Mounted)
    .unit("N")
    .depends(|s, _, k| s.relaxing_rate(k))
    .initially(Initially::ThroughAcceleration),
    output(
        "<mount>.t[i]",
        "Torque the mount applies to the body about the mount point, {axis} component, world frame",
        read!(|b, at| b.mount_reaction()?.1[at.i]),
    )
    .scope(Scope::Mounted)
    .unit("N.m")
    .depends(|s, _, k| s.relaxing_rate(k))
    .initially(Initially::ThroughAcceleration),
    // each force flange: its loads, set by the host, and its motion
    input(
        "<flange>.f[i]",
        "Force applied to the flange, {axis} component, world frame",
        Role::FlangeForce,
        read!(|b, at| b.loads()[at.owner].f[at.i]),
    )
    .scope(Scope::Flange)
    .unit("N")
    .write(|b, at, x| b.load_mut(at.owner).f[at.i] = x)
    .seed(|b, at| Some(&mut b.load_mut(at.owner).f[at.i]))
    .rate(|b, at, x| b.load_rate_mut(at.owner).f[at.i] = x),
    input(
        "<flange>.t[i]",
        "Torque applied to the flange about its reference point, {axis} component, world frame",
        Role::FlangeTorque,
        read!(|b, at| b.loads()[at.owner].t[at.i]),
    )
    .scope(Scope::Flange)
    .unit("N.m")
    .write(|b, at, x| b.load_mut(at.owner).t[at.i] = x)
    .seed(|b, at| Some(&mut b.load_mut(at.owner).t[at.i]))
    .rate(|b, at, x| b.load_rate_mut(at.owner).t[at.i] = x),
    output(
        "<flange>.r[i]",
        "Flange position, {axis} component, world frame",
        read!(|b, at| b.flange_motion(at.owner)?.r[at.i]),
    )
    .scope(Scope::Flange)
    .unit("m")
    .depends(|s, _, k| matches!(k.role(), Some(Role::MountPosition | Role::MountRotation)) || s.deformation(k)),
    output(
        "<flange>.R[i,j]",
        "Flange orientation, row {row} column {column} (columns: frame axes in world)",
        read!(|b, at| b.flange_motion(at.owner)?.rot[3 * at.i + at.j]),
    )
    .scope(Scope::Flange)
    .shape(Shape::Matrix)
    .unit("1")
    .depends(|s, _, k| k.role() == Some(Role::MountRotation) || s.deformation(k)),
    // the relaxing modes' rates follow the loads and motion as their accelerations do
    output(
        "<flange>.v[i]",
        "Flange velocity, {axis} component, world frame",
        read!(|b, at| b.flange_motion(at.owner)?.v[at.i]),
    )
    .scope(Scope::Flange)
    .unit("m/s")
    .depends(|s, _, k| {
        matches!(k.role(), Some(Role::MountVelocity | Role::MountSpin | Role::MountRotation))
            || s.deformation(k)
            || s.dynamic_velocity(k)
            || s.has_relaxing_modes() && s.relaxing_rate(k)
    }),
    output(
        "<flange>.w[i]",
        "Flange angular velocity, {axis} component, world frame",
        read!(|b, at| b.flange_motion(at.owner)?.w[at.i]),
    )
    .scope(Scope::Flange)
    .unit("rad/s")
    .depends(|s, _, k| {
        matches!(k.role(), Some(Role::MountSpin | Role::MountRotation))
            || s.dynamic_velocity(k)
            || s.has_relaxing_modes() && s.relaxing_rate(k)
    }),
    output(
        "<flange>.a[i]",
        "Flange acceleration, {axis} component, world frame",
        read!(|b, at| b.flange_motion(at.owner)?.a[at.i]),
    )
    .scope(Scope::Flange)
    .unit("m/s2")
    .depends(|s, _, k| s.relaxing_rate(k))
    .initially(Initially::ThroughAcceleration),
    output(
        "<flange>.z[i]",
        "Flange angular acceleration, {axis} component, world frame",
        read!(|b, at| b.flange_motion(at.owner)?.z[at.i]),
    )
    .scope(Scope::Flange)
    .unit("rad/s2")
    .depends(|s, _, k| s.relaxing_rate(k))
    .initially(Initially::ThroughAcceleration),
    output(
        "<flange>.u[i]",
        "Flange displacement relative to the mount, {axis} component, body frame",
        read!(|b, at| b.flange_motion(at.owner)?.u[at.i]),
    )
    .scope(Scope::Flange)
    .unit("m")
    .depends(|s, _, k| s.deformation(k)),
    output(
        "<flange>.phi[i]",
        "Flange rotation relative to the mount (rotation vector), {axis} component, body frame",
        read!(|b, at| b.flange_motion(at.owner)?.phi[at.i]),
    )
    .scope(Scope::Flange)
    .unit("rad")
    .depends(|s, _, k| s.deformation(k)),
    stress("<point>.sxx", "Normal stress sxx, body frame, at {point}", 0),
    stress("<point>.syy", "Normal stress syy, body frame, at {point}", 1),
    stress("<point>.szz", "Normal stress szz, body frame, at {point}", 2),
    stress("<point>.sxy", "Shear stress sxy, body frame, at {point}", 3),
    stress("<point>.syz", "Shear stress syz, body frame, at {point}", 4),
    stress("<point>.szx", "Shear stress szx, body frame, at {point}", 5),
    stress("<point>.mises", "Von Mises equivalent stress, at {point}", 6),
    // parameters
    parameter(
        "g[i]",
        "Gravitational acceleration, {axis} component, world frame",
        Role::Gravity,
        Value::Real(read!(|b, at| c(b.parameters().g[at.i]))),
    )
    .unit("m/s2")
    .write(|b, at, x| b.parameters_mut().g[at.i] = x),
    parameter(
        "damping.alpha",
        "Rayleigh damping: mass-proportional coefficient (D = alpha M + beta K)",
        Role::MassDamping,
        Value::Real(read!(|b, _| c(b.parameters().alpha))),
    )
    .shape(Shape::Scalar)
    .start(StartRule::MassDamping)
    .unit("1/s")
    .range(Range::NonNegative)
    .write(|b, _, x| b.parameters_mut().alpha = x),
    parameter(
        "damping.beta",
        "Rayleigh damping: stiffness-proportional coefficient",
        Role::StiffnessDamping,
        Value::Real(read!(|b, _| c(b.parameters().beta))),
    )
    .shape(Shape::Scalar)
    .start(StartRule::StiffnessDamping)
    .unit("s")
    .range(Range::NonNegative)
    .write(|b, _, x| b.parameters_mut().beta = x),
    parameter(
        "static_start",
        "Start in static equilibrium under the initial inputs (q' = 0, q = K^-1 p) instead of at the start values of q, qd",
        Role::StaticStart,
        Value::Switch,
    )
    .scope(Scope::Mounted)
    .shape(Shape::Scalar)
    .start(StartRule::False),
    parameter(
        "initial.r[i]",
        "Initial position of the centre of mass, {axis} component, world frame",
        Role::InitialPosition,
        Value::Real(read!(|b, at| c(b.initial_frame().r[at.i]))),
    )
    .scope(Scope::Free)
    .unit("m")
    .write(|b, at, x| b.initial_frame_mut().r[at.i] = x),
    parameter(
        "initial.phi[i]",
        "Initial orientation as a rotation vector (from the axes as meshed), {axis} component, world frame",
        Role::InitialRotation,
        Value::Real(read!(|b, at| c(b.initial_frame().phi[at.i]))),
    )
    .scope(Scope::Free)
    .unit("rad")
    .write(|b, at, x| b.initial_frame_mut().phi[at.i] = x),
    parameter(
        "initial.v[i]",
        "Initial velocity of the centre of mass, {axis} component, world frame",
        Role::InitialVelocity,
        Value::Real(read!(|b, at| c(b.initial_frame().v[at.i]))),
    )
    .scope(Scope::Free)
    .unit("m/s")
    .write(|b, at, x| b.initial_frame_mut().v[at.i] = x),
    parameter(
        "initial.w[i]",
        "Initial angular velocity, {axis} component, world frame",
        Role::InitialSpin,
        Value::Real(read!(|b, at| c(b.initial_frame().w[at.i]))),
    )
    .scope(Scope::Free)
    .unit("rad/s")
    .write(|b, at, x| b.initial_frame_mut().w[at.i] = x),
    // the modes; modal coordinates carry sqrt(kg) m, left unitless in the XML, so their rates
    // are 1/s and 1/s2
    local("q[k]", "Modal coordinate {mode} ({frequency} Hz{kind})", read!(|b, at| b.q()[at.i]))
        .shape(Shape::Modes)
        .start(StartRule::DynamicModes)
        .nominal(Nominal::ModalCoordinate)
        .role(Role::ModalCoordinate)
        .state(StateOf::IntegratedModes)
        .write(|b, at, x| b.q_mut()[at.i] = x)
        .seed(|b, at| Some(&mut b.q_mut()[at.i]))
        // the states are unknowns of the initialisation: with `static_start` a mounted body
        // starts in the static equilibrium of its loads, else at the start values
        .initially(Initially::StartsFrom(|s, k| !s.free && k.role().is_some_and(Role::sets_static_equilibrium))),
    local("qd[k]", "Modal velocity {mode}{kind}", read!(|b, at| b.qd()[at.i]))
        .shape(Shape::Modes)
        .start(StartRule::DynamicModes)
        .unit("1/s")
        .nominal(Nominal::ModalVelocity)
        .role(Role::ModalVelocity)
        .derivative_of(Role::ModalCoordinate)
        .state(StateOf::DynamicModes)
        .write(|b, at, x| b.qd_mut()[at.i] = x)
        .seed(|b, at| Some(&mut b.qd_mut()[at.i]))
        .depends(|s, at, k| {
            if s.relaxing(at.i) {
                s.relaxing_rate(k)
            } else {
                k.role() == Some(Role::ModalVelocity) && k.at.i == at.i
            }
        })
        // q' starts at rest or at its start value
        .initially(Initially::StartsFrom(|_, k| k.role() == Some(Role::StaticStart))),
    local("der(qd[k])", "Modal acceleration {mode}{kind}", read!(|b, at| b.qdd()?[at.i]))
        .shape(Shape::Modes)
        .unit("1/s2")
        .derivative_of(Role::ModalVelocity)
        .depends(|s, _, k| s.relaxing_rate(k))
        .initially(Initially::ThroughAcceleration),
    // a free body's frame: centre-of-mass position and velocity, quaternion, body-frame angular
    // velocity, starting from the `initial.*` parameters
    frame_state("frame.r[i]", "Centre-of-mass position, {axis}, world (state)", read!(|b, at| frame(b)?.r[at.i]))
        .unit("m")
        .role(Role::FramePosition)
        .seed(|b, at| Some(&mut b.frame_mut()?.r[at.i])),
    frame_state(
        "frame.Q[i]",
        "Orientation quaternion component {index} (w, x, y, z; state)",
        read!(|b, at| frame(b)?.quat[at.i]),
    )
    .shape(Shape::Vector(4))
    .unit("1")
    .role(Role::FrameQuaternion)
    .seed(|b, at| Some(&mut b.frame_mut()?.quat[at.i])),
    frame_state("frame.v[i]", "Centre-of-mass velocity, {axis}, world (state)", read!(|b, at| frame(b)?.v[at.i]))
        .unit("m/s")
        .role(Role::FrameVelocity)
        .derivative_of(Role::FramePosition)
        .seed(|b, at| Some(&mut b.frame_mut()?.v[at.i])),
    frame_state("frame.W[i]", "Angular velocity, {axis}, body frame (state)", read!(|b, at| frame(b)?.w_body[at.i]))
        .unit("rad/s")
        .role(Role::FrameSpin)
        .seed(|b, at| Some(&mut b.frame_mut()?.w_body[at.i])),
    local("der(frame.Q[i])", "Quaternion rate {index}", read!(|b, at| b.frame_rate()?.quat[at.i]))
        .scope(Scope::Free)
        .shape(Shape::Vector(4))
        .unit("1/s")
        .derivative_of(Role::FrameQuaternion),
    local("der(frame.v[i])", "Centre-of-mass acceleration, {axis}, world", read!(|b, at| b.frame_rate()?.v[at.i]))
        .scope(Scope::Free)
        .unit("m/s2")
        .derivative_of(Role::FrameVelocity),
    local("der(frame.W[i])", "Angular acceleration, {axis}, body frame", read!(|b, at| b.frame_rate()?.w_body[at.i]))
        .scope(Scope::Free)
        .unit("rad/s2")
        .derivative_of(Role::FrameSpin),
    // a free body's outputs; its orientation and spin are those the body's equations keep
    // as the mount's, up to date after the frame's rate
    output(
        "body.R[i,j]",
        "Body orientation, row {row} column {column} (columns: body axes in world)",
        read!(|b, at| {
            b.frame_rate()?;
            b.mount().rot[3 * at.i + at.j]
        }),
    )
    .scope(Scope::Free)
    .shape(Shape::Matrix)
    .unit("1"),
    output(
        "body.w[i]",
        "Body angular velocity, {axis}, world frame",
        read!(|b, at| {
            b.frame_rate()?;
            b.mount().w[at.i]
        }),
    )
    .scope(Scope::Free)
    .unit("rad/s"),
    output(
        "body.z[i]",
        "Body angular acceleration, {axis}, world frame",
        read!(|b, at| {
            b.frame_rate()?;
            b.mount().z[at.i]
        }),
    )
    .scope(Scope::Free)
    .unit("rad/s2"),
    output("body.energy", "Total energy: kinetic, elastic and gravitational", read!(|b, _| b.invariants()?.energy))
        .scope(Scope::Free)
        .shape(Shape::Scalar)
        .unit("J"),
    output("body.p[i]", "Linear momentum, {axis}, world frame", read!(|b, at| b.invariants()?.momentum[at.i]))
        .scope(Scope::Free)
        .unit("N.s"),
    output(
        "body.h[i]",
        "Angular momentum about the world origin, {axis}, world frame",
        read!(|b, at| b.invariants()?.angular_momentum[at.i]),
    )
    .scope(Scope::Free)
    .unit("J.s"),
];

/// A state of a free body's frame, calculated at initialisation from the `initial.*` parameters.
const fn frame_state(pattern: &'static str, description: &'static str, read: super::family::Read) -> Family {
    local(pattern, description, read)
        .scope(Scope::Free)
        .initial(Initial::Calculated)
        .state(StateOf::Always)
        .initially(Initially::StartsFrom(|_, k| k.role().is_some_and(Role::is_initial_frame)))
}
