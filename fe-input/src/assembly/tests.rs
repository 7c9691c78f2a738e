use super::*;
use serde_json::{Value, json};

/// A small flexible link: a box mesh, mount at x = 0, force flange at x = 1.
fn link() -> Value {
    json!({
        "name": "Link",
        "geometry": { "element": "hex8", "boxes": [ { "min": [0, -0.005, -0.01], "max": [1, 0.005, 0.01], "elements": [10, 1, 1] } ] },
        "material": { "E": 2e11, "nu": 0.3, "rho": 7850 },
        "flanges": [
            { "name": "base", "role": "motion", "nodes": { "box_face": { "box": 0, "face": "-x" } } },
            { "name": "tip", "role": "force", "nodes": { "box_face": { "box": 0, "face": "+x" } } }
        ],
        "reduction": { "modes": 2 }
    })
}

/// A flexible link hinged to the ground, a rigid crank on a ball joint at its tip, a torque
/// driving the hinge: 12 - 5 - 3 = 4 degrees of freedom.
fn good() -> Value {
    json!({
        "$schema": "../schemas/fmu-builder-input.schema.json",
        "name": "Pendulum",
        "description": "a test",
        "assembly": {
            "bodies": [
                { "name": "upper", "flexible": link(), "rotation": { "axis": [0, 2, 0], "angle": 90 } },
                { "name": "crank", "position": [0, 0, -1],
                  "rigid": { "mass": 0.098, "centre_of_mass": [0.125, 0, 0], "inertia": [1e-5, 5.1e-4, 5.1e-4, 0, 0, 0],
                             "flanges": [ { "name": "centre" }, { "name": "pin", "position": [0.25, 0, 0] } ] } }
            ],
            "joints": [
                { "name": "pivot", "type": "revolute", "between": ["ground", "upper.base"], "axis": [0, 3, 0],
                  "drive": { "torque": { "sine": { "amplitude": 2, "frequency": 1, "phase": 90 } } } },
                { "name": "elbow", "type": "spherical", "between": ["upper.tip", "crank.centre"] }
            ],
            "flanges": [ { "name": "load", "role": "force", "at": "crank.pin" } ],
            "solver": { "max_iterations": 20 }
        },
        "experiment": { "stop_time": 2.0, "step_size": 0.001 }
    })
}

fn parse(doc: &Value) -> Result<AssemblySpec> {
    AssemblySpec::from_str(Path::new("arm.json"), &doc.to_string())
}

/// The message of `doc`'s refusal, which must contain every one of `parts`.
#[track_caller]
fn refused(doc: &Value, parts: &[&str]) -> String {
    let e = parse(doc).expect_err("refused").to_string();
    for part in parts {
        assert!(e.contains(part), "{part:?} not in: {e}");
    }
    e
}

/// `good()` changed by `edit`.
fn with(edit: impl FnOnce(&mut Value)) -> Value {
    let mut d = good();
    edit(&mut d);
    d
}

#[test]
fn a_good_assembly_parses_with_names_resolved() {
    let a = parse(&good()).unwrap();
    assert_eq!(a.name, "Pendulum");
    assert_eq!(a.gravity, STANDARD_GRAVITY);
    assert_eq!(a.solver, SolverSpec { max_iterations: 20, ..SolverSpec::default() });
    assert_eq!((a.solver.spectral_radius, a.solver.tolerance), (1.0, 1e-10));
    assert_eq!(a.experiment.as_ref().unwrap().stop_time, Some(2.0));
    assert_eq!(a.bodies.len(), 2);
    assert!(a.bodies[0].is_flexible() && !a.bodies[1].is_flexible());
    assert_eq!(a.bodies[0].flange_names(), ["base", "tip"]);
    // 90 degrees about y: the body's x is the world's -z
    let r = a.bodies[0].rotation;
    assert!((r[6] + 1.0).abs() < 1e-15 && r[0].abs() < 1e-15, "{r:?}");
    assert_eq!(a.bodies[1].rotation, vectors::IDENTITY);
    assert_eq!(a.bodies[1].position, [0.0, 0.0, -1.0]);
    let pivot = &a.joints[0];
    assert_eq!(pivot.between, [FlangeRef::Ground, FlangeRef::Body { body: 0, flange: "base".into() }]);
    assert_eq!(pivot.axis, Some([0.0, 1.0, 0.0]));
    let Some(Drive {
        quantity: DriveQuantity::Torque,
        function: DriveFunction::Sine { amplitude, frequency, phase_rad, offset },
    }) = pivot.drive
    else {
        panic!("{:?}", pivot.drive)
    };
    assert_eq!((amplitude, frequency, offset), (2.0, 1.0, 0.0));
    assert!((phase_rad - std::f64::consts::FRAC_PI_2).abs() < 1e-15);
    assert_eq!(pivot.constraints(), 5);
    assert_eq!(a.joints[1].between[1], FlangeRef::Body { body: 1, flange: "centre".into() });
    assert_eq!(
        a.flanges[0],
        ExternalFlangeSpec {
            name: "load".into(),
            role: Role::Force,
            at: FlangeRef::Body { body: 1, flange: "pin".into() }
        }
    );
    let (spec, from) = a.flexible_input(0).unwrap();
    assert_eq!((spec.name.as_str(), from), ("Link", Path::new("arm.json")));
    assert!(a.flexible_input(1).is_none() && a.input_files().is_empty());
    assert_eq!(a.body_index("crank"), Some(1));
}

#[test]
fn every_joint_type_and_drive_function_reads() {
    // a chain of rigid bodies, each held to the ground by one joint
    let rigid = json!({ "mass": 1.0, "inertia": [1, 1, 1, 0, 0, 0], "flanges": [ { "name": "f" } ] });
    let joints = [
        json!({ "type": "weld" }),
        json!({ "type": "revolute", "axis": [0, 0, 1], "drive": { "angle": { "spin_up": { "speed": 6.5, "time": 1.0 } } } }),
        json!({ "type": "prismatic", "axis": [1, 0, 0], "drive": { "position": { "constant": 0.1 } } }),
        json!({ "type": "prismatic", "axis": [1, 0, 0], "drive": { "force": "input" } }),
        json!({ "type": "revolute", "axis": [1, 0, 0], "drive": { "angle": "input" } }),
        json!({ "type": "spherical" }),
        json!({ "type": "universal", "axes": [[0, 1, 0], [0, 0, 2]] }),
    ];
    let bodies: Vec<Value> = (0..joints.len()).map(|i| json!({ "name": format!("b{i}"), "rigid": rigid })).collect();
    let joints: Vec<Value> = joints
        .iter()
        .enumerate()
        .map(|(i, j)| {
            let mut j = j.clone();
            j["name"] = json!(format!("j{i}"));
            j["between"] = json!(["ground", format!("b{i}.f")]);
            j
        })
        .collect();
    let doc = json!({ "name": "Chain", "assembly": { "gravity": [0, -9.81, 0], "bodies": bodies, "joints": joints } });
    let a = parse(&doc).unwrap();
    assert_eq!(a.gravity, [0.0, -9.81, 0.0]);
    let types: Vec<JointType> = a.joints.iter().map(|j| j.joint_type).collect();
    use JointType::*;
    assert_eq!(types, [Weld, Revolute, Prismatic, Prismatic, Revolute, Spherical, Universal]);
    let counts: Vec<usize> = a.joints.iter().map(JointSpec::constraints).collect();
    assert_eq!(counts, [6, 6, 6, 5, 6, 3, 4]);
    assert_eq!(
        a.joints[1].drive,
        Some(Drive { quantity: DriveQuantity::Angle, function: DriveFunction::SpinUp { speed: 6.5, time: 1.0 } })
    );
    assert_eq!(a.joints[2].drive.unwrap().function, DriveFunction::Constant(0.1));
    assert_eq!(a.joints[3].drive, Some(Drive { quantity: DriveQuantity::Force, function: DriveFunction::Input }));
    assert_eq!(a.joints[6].axes, Some([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]));
    assert!(a.joints[6].axis.is_none() && a.joints[0].drive.is_none());
}

#[test]
fn body_files_resolve_from_the_assembly_and_their_errors_name_them() {
    let dir = std::env::temp_dir().join(format!("fe-input-assembly-{}", std::process::id()));
    std::fs::create_dir_all(dir.join("parts")).unwrap();
    let mut body = link();
    body["geometry"] = json!({ "mesh": "link.inp" });
    body.as_object_mut().unwrap().remove("material");
    body["flanges"] = json!([
        { "name": "base", "role": "motion", "nodes": { "node_set": "BASE" } },
        { "name": "tip", "role": "force", "nodes": { "node_set": "TIP" } }
    ]);
    std::fs::write(dir.join("parts/link.json"), body.to_string()).unwrap();
    let assembly = dir.join("arm.json");
    let doc = with(|d| d["assembly"]["bodies"][0]["flexible"] = json!("parts/link.json"));
    let a = AssemblySpec::from_str(&assembly, &doc.to_string()).unwrap();
    let file = dir.join("parts/link.json");
    assert!(matches!(&a.bodies[0].kind, BodyKind::Flexible { file: Some(f), .. } if *f == file));
    assert_eq!(a.flexible_input(0).unwrap().1, file);
    assert_eq!(a.input_files(), [file.clone(), dir.join("parts/link.inp")]);
    // a problem inside the body file is that file's
    std::fs::write(&file, body.to_string().replace("\"modes\":2", "\"modes\":2,\"modez\":1")).unwrap();
    let e = AssemblySpec::from_str(&assembly, &doc.to_string()).unwrap_err().to_string();
    assert!(e.starts_with(&format!("{}: reduction.modez", file.display())) && e.contains("did you mean"), "{e}");
    // an assembly where a body's input is expected
    std::fs::write(&file, good().to_string()).unwrap();
    let e = AssemblySpec::from_str(&assembly, &doc.to_string()).unwrap_err().to_string();
    assert!(e.starts_with(&format!("{}: assembly: this file is an assembly's input", file.display())), "{e}");
    // a missing file: the field, the path as resolved, the folder
    let doc = with(|d| d["assembly"]["bodies"][0]["flexible"] = json!("parts/lnk.json"));
    let e = AssemblySpec::from_str(&assembly, &doc.to_string()).unwrap_err().to_string();
    for part in
        ["arm.json: assembly.bodies[0].flexible: \"parts/lnk.json\"", "cannot be read", "relative paths resolve"]
    {
        assert!(e.contains(part), "{part:?} not in {e}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn an_inline_body_is_checked_as_a_body_input_below_its_field() {
    refused(
        &with(|d| d["assembly"]["bodies"][0]["flexible"]["material"]["E"] = json!(0)),
        &["arm.json: assembly.bodies[0].flexible.material.E: "],
    );
    refused(
        &with(|d| d["assembly"]["bodies"][0]["flexible"]["flanges"][1]["name"] = json!("base")),
        &["assembly.bodies[0].flexible.flanges[1].name: "],
    );
    refused(
        &with(|d| d["assembly"]["bodies"][0]["flexible"]["reduction"] = json!({ "mods": 2 })),
        &["assembly.bodies[0].flexible.reduction.mods: unknown key", "did you mean \"modes\""],
    );
    refused(
        &with(|d| d["assembly"]["bodies"][0]["flexible"]["assembly"] = json!({})),
        &["assembly.bodies[0].flexible.assembly: ", "not another assembly"],
    );
    // free-floating: no motion flange
    refused(
        &with(|d| d["assembly"]["bodies"][0]["flexible"]["flanges"][0]["role"] = json!("force")),
        &["assembly.bodies[0].flexible: ", "no flange of role \"motion\"", "free-floating"],
    );
}

#[test]
fn references_must_name_bodies_and_their_flanges() {
    refused(
        &with(|d| d["assembly"]["joints"][1]["between"][0] = json!("upper.tipp")),
        &["arm.json: assembly.joints[1].between[0]: body 'upper' has no flange 'tipp' (its flanges: base, tip)"],
    );
    refused(
        &with(|d| d["assembly"]["joints"][1]["between"][1] = json!("lower.base")),
        &["assembly.joints[1].between[1]: there is no body 'lower' (the bodies: upper, crank"],
    );
    refused(
        &with(|d| d["assembly"]["flanges"][0]["at"] = json!("crank.pn")),
        &["assembly.flanges[0].at: body 'crank' has no flange 'pn' (its flanges: centre, pin)"],
    );
    refused(
        &with(|d| d["assembly"]["flanges"][0]["at"] = json!("ground")),
        &["assembly.flanges[0].at: ", "fixed world"],
    );
    refused(
        &with(|d| d["assembly"]["joints"][1]["between"][0] = json!("upper")),
        &["assembly.joints[1].between[0]: \"upper\" is not a flange reference"],
    );
    refused(
        &with(|d| d["assembly"]["joints"][0]["between"] = json!(["ground", "ground"])),
        &["assembly.joints[0].between: both flanges are the ground"],
    );
    refused(
        &with(|d| d["assembly"]["joints"][1]["between"] = json!(["crank.pin", "crank.centre"])),
        &["assembly.joints[1].between: both flanges ('crank.pin', 'crank.centre') are on body 'crank'"],
    );
    refused(
        &with(|d| d["assembly"]["joints"][1]["between"] = json!(["upper.tip", "upper.tip"])),
        &["assembly.joints[1].between: both ends are the same flange"],
    );
    refused(&with(|d| d["assembly"]["joints"][1]["between"] = json!(["upper.tip"])), &["assembly.joints[1].between"]);
}

#[test]
fn axes_and_drives_fit_the_joint_type() {
    let joint = |d: &mut Value, j: Value| d["assembly"]["joints"][1] = j;
    refused(
        &with(|d| joint(d, json!({ "name": "elbow", "type": "revolute", "between": ["upper.tip", "crank.centre"] }))),
        &["assembly.joints[1].axis: a revolute joint needs its axis"],
    );
    refused(
        &with(|d| {
            joint(
                d,
                json!({ "name": "elbow", "type": "spherical", "between": ["upper.tip", "crank.centre"], "axis": [0, 1, 0] }),
            )
        }),
        &["assembly.joints[1].axis: a spherical joint has no axis"],
    );
    refused(
        &with(|d| joint(d, json!({ "name": "elbow", "type": "universal", "between": ["upper.tip", "crank.centre"] }))),
        &["assembly.joints[1].axes: a universal joint needs its two axes"],
    );
    refused(
        &with(|d| {
            joint(
                d,
                json!({ "name": "elbow", "type": "universal", "between": ["upper.tip", "crank.centre"],
                             "axes": [[0, 1, 0], [0, 1, 1e-3]] }),
            )
        }),
        &["assembly.joints[1].axes: the two axes must be perpendicular"],
    );
    refused(
        &with(|d| {
            joint(
                d,
                json!({ "name": "elbow", "type": "universal", "between": ["upper.tip", "crank.centre"],
                             "axes": [[0, 0, 0], [0, 1, 0]] }),
            )
        }),
        &["assembly.joints[1].axes[0]: the axis is the zero vector"],
    );
    refused(
        &with(|d| d["assembly"]["joints"][0]["axis"] = json!([0, 0, 0])),
        &["assembly.joints[0].axis: the axis is the zero vector"],
    );
    refused(
        &with(|d| d["assembly"]["joints"][0]["axes"] = json!([[1, 0, 0], [0, 1, 0]])),
        &["assembly.joints[0].axes: a revolute joint has no \"axes\""],
    );
    refused(
        &with(|d| d["assembly"]["joints"][0]["drive"] = json!({ "force": "input" })),
        &["assembly.joints[0].drive.force: a revolute joint's drive is \"angle\" or \"torque\", not \"force\""],
    );
    refused(
        &with(|d| d["assembly"]["joints"][0]["drive"] = json!({ "angle": "input", "torque": "input" })),
        &["assembly.joints[0].drive: a drive has exactly one key"],
    );
    refused(
        &with(|d| d["assembly"]["joints"][1]["drive"] = json!({ "torque": "input" })),
        &["assembly.joints[1].drive: a spherical joint cannot be driven"],
    );
    refused(
        &with(|d| d["assembly"]["joints"][0]["drive"] = json!({ "torque": { "spin_up": { "speed": 1, "time": 0 } } })),
        &["assembly.joints[0].drive.torque.spin_up.time: found 0"],
    );
    refused(
        &with(|d| {
            d["assembly"]["joints"][0]["drive"] = json!({ "torque": { "sine": { "amplitude": 1, "frequency": -1 } } })
        }),
        &["assembly.joints[0].drive.torque.sine.frequency: found -1"],
    );
    refused(
        &with(|d| d["assembly"]["joints"][0]["drive"] = json!({ "torque": "inpt" })),
        &["assembly.joints[0].drive.torque: ", "\"input\""],
    );
    // only the type: its axis and drive are not refused for a type it does not have
    let e = refused(
        &with(|d| d["assembly"]["joints"][0]["type"] = json!("hinge")),
        &["assembly.joints[0].type: found \"hinge\", expected one of \"weld\""],
    );
    assert!(!e.contains("axis") && !e.contains("drive"), "{e}");
    // where the schema speaks first (an unknown key beside), a key the type rules out is named
    refused(
        &with(|d| {
            d["assembly"]["joints"][1]["axis"] = json!([0, 1, 0]);
            d["assembly"]["joints"][1]["colour"] = json!(1);
        }),
        &[
            "assembly.joints[1].colour: unknown key",
            "assembly.joints[1].axis: found [0,1,0]: \"axis\" is not allowed here",
        ],
    );
}

#[test]
fn one_motion_flange_at_most() {
    let e = refused(
        &with(|d| {
            d["assembly"]["flanges"] = json!([
                { "name": "mount", "role": "motion", "at": "upper.tip" },
                { "name": "other", "role": "motion", "at": "crank.pin" }
            ])
        }),
        &["assembly.flanges[1].role: a second \"motion\" flange (assembly.flanges[0] is one)", "over-constrain"],
    );
    assert!(!e.contains("schema"), "{e}");
}

#[test]
fn over_constrained_groups_and_loose_bodies_are_refused() {
    // a weld and a revolute to the ground on one body: 6 - 11
    let e = refused(
        &with(|d| {
            d["assembly"]["joints"][1] =
                json!({ "name": "elbow", "type": "weld", "between": ["upper.tip", "crank.centre"] });
            d["assembly"]["joints"]
                .as_array_mut()
                .unwrap()
                .push(json!({ "name": "stay", "type": "weld", "between": ["ground", "crank.pin"] }));
        }),
        &[
            "arm.json: assembly.joints: over-constrained: 5 more constraint equations than the bodies' 6 x 2 = 12 degrees of freedom",
            "joint 'pivot' (revolute: 5)",
            "joint 'elbow' (weld: 6)",
            "joint 'stay' (weld: 6)",
        ],
    );
    assert!(e.contains("bodies 'upper', 'crank'"), "{e}");
    // a motion flange counts six, a driven angle one
    refused(
        &with(|d| {
            d["assembly"]["joints"][0]["drive"] = json!({ "angle": "input" });
            d["assembly"]["flanges"][0] = json!({ "name": "mount", "role": "motion", "at": "crank.pin" });
        }),
        &["over-constrained: 3 more", "with a driven angle: 6", "motion flange 'mount' (6)"],
    );
    // a body nothing names
    refused(
        &with(|d| {
            d["assembly"]["bodies"].as_array_mut().unwrap().push(json!({ "name": "loose",
                "rigid": { "mass": 1, "inertia": [1, 1, 1, 0, 0, 0], "flanges": [ { "name": "f" } ] } }))
        }),
        &["assembly.bodies[2]: body 'loose' is connected to nothing"],
    );
    // bodies joined to each other but to nothing fixed float together; an external force flange
    // alone connects a body
    parse(&with(|d| {
        d["assembly"]["joints"][0]["between"] = json!(["crank.pin", "upper.base"]);
        d["assembly"]["bodies"].as_array_mut().unwrap().push(json!({ "name": "free",
            "rigid": { "mass": 1, "inertia": [1, 1, 1, 0, 0, 0], "flanges": [ { "name": "f" } ] } }));
        d["assembly"]["flanges"][0]["at"] = json!("free.f");
    }))
    .unwrap();
}

#[test]
fn names_are_unique_across_bodies_joints_and_flanges() {
    refused(
        &with(|d| d["assembly"]["bodies"][1]["name"] = json!("upper")),
        &["assembly.bodies[1].name: \"upper\" is already the name of assembly.bodies[0]"],
    );
    refused(
        &with(|d| d["assembly"]["joints"][1]["name"] = json!("crank")),
        &[
            "assembly.joints[1].name: \"crank\" is already the name of assembly.bodies[1]; bodies, joints and external flanges",
        ],
    );
    refused(
        &with(|d| d["assembly"]["flanges"][0]["name"] = json!("pivot")),
        &["assembly.flanges[0].name: \"pivot\" is already the name of assembly.joints[0]"],
    );
    refused(
        &with(|d| d["assembly"]["bodies"][1]["rigid"]["flanges"][1]["name"] = json!("centre")),
        &[
            "assembly.bodies[1].rigid.flanges[1].name: \"centre\" is already the name of assembly.bodies[1].rigid.flanges[0]",
        ],
    );
    refused(
        &with(|d| d["assembly"]["bodies"][1]["name"] = json!("ground")),
        &["assembly.bodies[1].name: \"ground\" names the fixed world"],
    );
    refused(
        &with(|d| d["assembly"]["joints"][1]["name"] = json!("time")),
        &["assembly.joints[1].name: \"time\" is the name of the FMU's own variables"],
    );
    refused(&with(|d| d["assembly"]["bodies"][1]["name"] = json!("2nd")), &["assembly.bodies[1].name: found \"2nd\""]);
}

#[test]
fn rigid_bodies_have_an_inertia_a_body_can_have() {
    let inertia = |v: Value| with(|d| d["assembly"]["bodies"][1]["rigid"]["inertia"] = v);
    refused(&inertia(json!([1, 1, -1, 0, 0, 0])), &["assembly.bodies[1].rigid.inertia: ", "not positive definite"]);
    // positive diagonal, but the products make it indefinite
    refused(&inertia(json!([1, 1, 1, 2, 0, 0])), &["not positive definite"]);
    refused(&inertia(json!([1, 1, 3, 0, 0, 0])), &["assembly.bodies[1].rigid.inertia: ", "triangle inequality"]);
    // a thin plate (Izz = Ixx + Iyy) and a turned principal frame are fine
    parse(&inertia(json!([1, 2, 3, 0, 0, 0]))).unwrap();
    parse(&inertia(json!([1.25, 1.75, 3, 0.4330127018922193, 0, 0]))).unwrap();
    refused(
        &with(|d| d["assembly"]["bodies"][1]["rigid"]["mass"] = json!(0)),
        &["assembly.bodies[1].rigid.mass: found 0"],
    );
    refused(
        &with(|d| d["assembly"]["bodies"][1]["rigid"]["flanges"] = json!([])),
        &["assembly.bodies[1].rigid.flanges"],
    );
}

#[test]
fn bodies_are_flexible_or_rigid_and_placed_by_a_real_rotation() {
    refused(
        &with(|d| d["assembly"]["bodies"][0]["rotation"]["axis"] = json!([0, 0, 0])),
        &["assembly.bodies[0].rotation.axis: the rotation's axis is the zero vector"],
    );
    refused(
        &with(|d| d["assembly"]["bodies"][1]["flexible"] = json!("link.json")),
        &["assembly.bodies[1]: a body is either flexible or rigid"],
    );
    refused(
        &with(|d| d["assembly"]["bodies"][1].as_object_mut().unwrap().remove("rigid").map(drop).unwrap()),
        &["assembly.bodies[1]: give the body \"flexible\""],
    );
    refused(
        &with(|d| d["assembly"]["bodies"][0]["flexible"] = json!(3)),
        &["assembly.bodies[0].flexible: found 3, which matches none of the forms", "the path of a body input file"],
    );
}

#[test]
fn unknown_keys_get_the_nearest_valid_one_and_body_keys_are_refused() {
    refused(
        &with(|d| d["assembly"]["solver"] = json!({ "spectral_radious": 0.5 })),
        &["arm.json: assembly.solver.spectral_radious: unknown key", "did you mean \"spectral_radius\"?"],
    );
    refused(
        &with(|d| d["assembly"]["joints"][0]["axiss"] = json!([0, 1, 0])),
        &["assembly.joints[0].axiss: unknown key", "did you mean \"axis\"?"],
    );
    refused(
        &with(|d| d["assembly"]["bodys"] = json!([])),
        &["assembly.bodys: unknown key", "did you mean \"bodies\"?"],
    );
    refused(&with(|d| d["geometry"] = json!({})), &["arm.json: geometry: an assembly", "has no \"geometry\""]);
    refused(
        &with(|d| d["assembly"]["solver"]["max_iterations"] = json!(1)),
        &["assembly.solver.max_iterations: found 1"],
    );
    refused(
        &with(|d| d["assembly"]["solver"]["spectral_radius"] = json!(1.5)),
        &["assembly.solver.spectral_radius: found 1.5"],
    );
    refused(&with(|d| d["experiment"]["step_size"] = json!(3.0)), &["experiment.step_size: ", "longer than"]);
    // a repeated key, with its line
    let text = good().to_string().replace("\"solver\":{", "\"solver\":{\"tolerance\":1e-9,\"tolerance\":1e-8,");
    let e = AssemblySpec::from_str(Path::new("arm.json"), &text).unwrap_err().to_string();
    assert!(e.contains("assembly.solver.tolerance") && e.contains("twice"), "{e}");
}

/// The body inputs of the examples are still bodies, and `is_assembly` tells the two apart.
#[test]
fn the_examples_parse_and_is_assembly_tells_them_apart() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples");
    let mut files = Vec::new();
    for entry in std::fs::read_dir(&root).unwrap() {
        let p = entry.unwrap().path();
        if p.is_dir() {
            files.extend(std::fs::read_dir(&p).unwrap().map(|e| e.unwrap().path()));
        } else {
            files.push(p);
        }
    }
    files.retain(|p| p.extension().is_some_and(|e| e == "json"));
    assert!(files.len() >= 8, "{files:?}");
    let mut assemblies = 0;
    for f in &files {
        let text = std::fs::read_to_string(f).unwrap();
        // examples/assemblies holds assemblies, every other example is a body
        let in_assemblies = f.parent().is_some_and(|d| d.ends_with("assemblies"));
        assert_eq!(is_assembly(&text), in_assemblies, "{}", f.display());
        if in_assemblies {
            AssemblySpec::from_str(f, &text).unwrap_or_else(|e| panic!("{e}"));
            let e = Spec::from_str(f, &text).unwrap_err().to_string();
            assert!(e.contains("this file is an assembly's input"), "{e}");
            assemblies += 1;
        } else {
            Spec::from_str(f, &text).unwrap_or_else(|e| panic!("{e}"));
            let e = AssemblySpec::from_str(f, &text).unwrap_err().to_string();
            assert!(e.contains("has no \"assembly\""), "{e}");
        }
    }
    assert!(assemblies >= 5, "{files:?}");
    let text = good().to_string();
    assert!(is_assembly(&text));
    let e = Spec::from_str(Path::new("arm.json"), &text).unwrap_err().to_string();
    assert!(e.starts_with("arm.json: assembly: this file is an assembly's input"), "{e}");
    assert!(is_assembly(r#"{"assembly": null}"#) && !is_assembly("[1]") && !is_assembly("{") && !is_assembly("{}"));
}

/// The schema refuses what the reading refuses for names and types, so editors flag them too.
#[test]
fn the_schema_lists_the_reserved_names_and_the_joint_types() {
    let schema: Value = serde_json::from_str(spec::SCHEMA).unwrap();
    let listed = |pointer: &str| -> Vec<String> {
        let mut v: Vec<String> = schema
            .pointer(pointer)
            .unwrap_or_else(|| panic!("{pointer}"))
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_str().unwrap().to_string())
            .collect();
        v.sort_unstable();
        v
    };
    let mut reserved: Vec<String> = crate::variable_names::RESERVED.iter().map(|s| s.to_string()).collect();
    reserved.sort_unstable();
    assert_eq!(listed("/$defs/joint/properties/name/not/enum"), reserved);
    assert_eq!(listed("/$defs/assembly_flange/properties/name/not/enum"), reserved);
    reserved.push("ground".into());
    reserved.sort_unstable();
    assert_eq!(listed("/$defs/assembly_body/properties/name/not/enum"), reserved);
    let mut types: Vec<String> = JointType::ALL.iter().map(|t| t.word().to_string()).collect();
    types.sort_unstable();
    assert_eq!(listed("/$defs/joint/properties/type/enum"), types);
    assert_eq!(forms::BODY_KEYS.len(), schema["then"]["properties"].as_object().unwrap().len());
    for key in forms::BODY_KEYS {
        assert_eq!(schema["then"]["properties"][key], Value::Bool(false), "{key}");
    }
}
