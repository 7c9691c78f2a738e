//! No heap allocation in an assembly's step: a flexible body (the two-mode fixture with its
//! rotating-frame terms) on a revolute joint driven by a torque input, a rigid bar on a
//! spherical joint at its tip loaded through an external force flange, stepped through the FMI
//! model trait with the inputs ramped by their rates and every kind of output read after each
//! step (positions, reactions, accelerations, energy, drift), including steps that form the
//! iteration matrix again and the outputs' index-1 solve.

use fmi2::Model;
use fmu_runtime::assembly::description::{
    AssemblyDescription, BodyDescription, BodyModel, Drive, DriveFunction, DriveQuantity, ExternalFlange, FlangeRole,
    JointDescription, Side, SolverSettings,
};
use fmu_runtime::assembly::joint::JointKind;
use fmu_runtime::fmu::assembly::AssemblyFmu;
use fmu_runtime::kinematics::IDENTITY;
use fmu_runtime::reduced::rotating_two_mode_body;
use test_support::alloc::{Counting, assert_no_allocation};

#[global_allocator]
static ALLOCATOR: Counting = Counting;

/// The two-mode fixture with its invariants made those of a body whose modes carry no
/// momentum of their own (C_t = C_r = 0): its synthetic numbers otherwise make no positive mass
/// matrix.
fn arm() -> fmu_runtime::reduced::ReducedBody {
    let mut body = rotating_two_mode_body();
    body.c_t.fill(0.0);
    body.c_r.fill(0.0);
    body
}

fn pendulum() -> AssemblyDescription {
    let bar = BodyModel::Rigid {
        mass: 2.0,
        centre: [0.5, 0.0, 0.0],
        inertia_at_centre: [0.01, 0.0, 0.0, 0.0, 0.2, 0.0, 0.0, 0.0, 0.2],
        flanges: vec![("pin".into(), [0.0; 3]), ("end".into(), [1.0, 0.0, 0.0])],
    };
    AssemblyDescription {
        guid: "{test}".into(),
        model_name: "Pendulum".into(),
        gravity: [0.0, 0.0, -9.81],
        bodies: vec![
            BodyDescription {
                name: "arm".into(),
                position: [0.0; 3],
                rotation: IDENTITY,
                model: BodyModel::Flexible(Box::new(arm())),
            },
            BodyDescription { name: "bar".into(), position: [1.0, 0.0, 0.0], rotation: IDENTITY, model: bar },
        ],
        joints: vec![
            JointDescription {
                name: "pivot".into(),
                kind: JointKind::Revolute,
                first: Side::Ground,
                second: Side::Body { body: 0, marker: 0 },
                axes: [[0.0, 1.0, 0.0], [0.0; 3]],
                drive: Some(Drive { quantity: DriveQuantity::Load, function: DriveFunction::Input }),
            },
            JointDescription {
                name: "ball".into(),
                kind: JointKind::Spherical,
                first: Side::Body { body: 0, marker: 1 },
                second: Side::Body { body: 1, marker: 0 },
                axes: [[0.0; 3]; 2],
                drive: None,
            },
        ],
        flanges: vec![ExternalFlange { name: "end".into(), role: FlangeRole::Force, body: 1, marker: 1 }],
        solver: SolverSettings::default(),
    }
}

#[test]
fn an_assembly_steps_and_answers_without_allocating() {
    let mut fmu = AssemblyFmu::new(&pendulum()).unwrap();
    let vr = |name: &str| fmu.table().value_reference(name).unwrap_or_else(|| panic!("{name}"));
    let (torque, load) = (vr("pivot.drive_torque"), vr("end.f[3]"));
    let reads: Vec<u32> = [
        "bar.end.r[1]",
        "bar.end.v[3]",
        "end.a[3]",
        "ball.f[1]",
        "pivot.t[2]",
        "pivot.angle",
        "energy.total",
        "joints.drift",
    ]
    .iter()
    .map(|n| vr(n))
    .collect();
    fmu.enter_initialization(0.0).unwrap();
    fmu.exit_initialization().unwrap();
    let mut sum = 0.0;
    assert_no_allocation("assembly steps, inputs and outputs", || {
        for k in 0..300 {
            fmu.set_real(torque, (k as f64 * 0.01).sin()).unwrap();
            fmu.set_real_input_derivative(load, 0.5).unwrap();
            fmu.set_real(load, -1.0).unwrap();
            // a step of another length forms the iteration matrix again
            let h = if k % 100 == 99 { 2e-3 } else { 1e-3 };
            fmu.do_step(k as f64 * 1e-3, h).unwrap();
            for &r in &reads {
                sum += fmu.get_real(r).unwrap();
            }
        }
    });
    assert!(sum.is_finite());
}
