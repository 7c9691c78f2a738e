//! Names and references: bodies, joints and external flanges each named once (they all become
//! stems of the FMU's variable names), every "body.flange" a flange that exists, a joint's two
//! flanges on two different bodies (or one and the ground), drives and directions in their
//! resolved form.

use super::json::{AssemblyJson, DriveFunctionJson, ExternalFlangeJson, JointJson};
use super::vectors::normalised;
use super::{AssemblyBodySpec, Drive, DriveFunction, DriveQuantity, ExternalFlangeSpec, FlangeRef, JointSpec};
use crate::error::{InputError, Result};
use std::path::Path;

/// Every name once among the bodies, the joints and the external flanges.
pub fn check_names(path: &Path, a: &AssemblyJson) -> Result<()> {
    let mut seen: Vec<(&str, String)> = Vec::new();
    let named = a
        .bodies
        .iter()
        .enumerate()
        .map(|(i, b)| (b.name.as_str(), format!("assembly.bodies[{i}]")))
        .chain(a.joints.iter().enumerate().map(|(k, j)| (j.name.as_str(), format!("assembly.joints[{k}]"))))
        .chain(a.flanges.iter().enumerate().map(|(i, f)| (f.name.as_str(), format!("assembly.flanges[{i}]"))));
    for (name, at) in named {
        if let Some((_, first)) = seen.iter().find(|(n, _)| *n == name) {
            let why = if first.split('[').next() == at.split('[').next() {
                String::new()
            } else {
                "; bodies, joints and external flanges all name variables of the FMU, so each needs a name of its own"
                    .to_string()
            };
            return Err(InputError::field(
                path,
                format!("{at}.name"),
                format!("\"{name}\" is already the name of {first}{why}"),
            ));
        }
        seen.push((name, at));
    }
    Ok(())
}

/// The flange `reference` ("ground" or "body.flange") names, at `field`.
fn reference(path: &Path, field: &str, reference: &str, bodies: &[AssemblyBodySpec]) -> Result<FlangeRef> {
    if reference == "ground" {
        return Ok(FlangeRef::Ground);
    }
    // `forms` saw to the shape
    let (body, flange) = reference.split_once('.').unwrap_or((reference, ""));
    let Some(index) = bodies.iter().position(|b| b.name == body) else {
        let names: Vec<&str> = bodies.iter().map(|b| b.name.as_str()).collect();
        return Err(InputError::field(
            path,
            field,
            format!("there is no body '{body}' (the bodies: {}; or \"ground\")", names.join(", ")),
        ));
    };
    let flanges = bodies[index].flange_names();
    if !flanges.contains(&flange) {
        return Err(InputError::field(
            path,
            field,
            format!("body '{body}' has no flange '{flange}' (its flanges: {})", flanges.join(", ")),
        ));
    }
    Ok(FlangeRef::Body { body: index, flange: flange.to_string() })
}

/// Joint `k`, its references resolved.
pub fn resolve(path: &Path, k: usize, j: &JointJson, bodies: &[AssemblyBodySpec]) -> Result<JointSpec> {
    let at = format!("assembly.joints[{k}]");
    let first = reference(path, &format!("{at}.between[0]"), &j.between[0], bodies)?;
    let second = reference(path, &format!("{at}.between[1]"), &j.between[1], bodies)?;
    let problem = match (&first, &second) {
        (FlangeRef::Ground, FlangeRef::Ground) => {
            Some("both flanges are the ground: a joint holds a body to the ground or to another body".to_string())
        }
        (FlangeRef::Body { body: a, flange: fa }, FlangeRef::Body { body: b, flange: fb }) if a == b => {
            let name = &bodies[*a].name;
            Some(if fa == fb {
                format!("both ends are the same flange '{name}.{fa}'; a joint joins two different bodies")
            } else {
                format!(
                    "both flanges ('{name}.{fa}', '{name}.{fb}') are on body '{name}': a joint joins two different \
                     bodies (or a body and the ground); a body's own flanges move with it already"
                )
            })
        }
        _ => None,
    };
    if let Some(problem) = problem {
        return Err(InputError::field(path, format!("{at}.between"), problem));
    }
    Ok(JointSpec {
        name: j.name.clone(),
        joint_type: j.joint_type,
        between: [first, second],
        axis: j.axis.map(normalised),
        axes: j.axes.map(|a| a.map(normalised)),
        drive: j.drive.as_ref().and_then(|d| {
            let given = [
                (DriveQuantity::Angle, d.angle),
                (DriveQuantity::Torque, d.torque),
                (DriveQuantity::Position, d.position),
                (DriveQuantity::Force, d.force),
            ];
            // `forms` saw to exactly one, of the joint's kind
            given.into_iter().find_map(|(quantity, f)| f.map(|f| Drive { quantity, function: function(f) }))
        }),
    })
}

fn function(f: DriveFunctionJson) -> DriveFunction {
    match f {
        DriveFunctionJson::Input => DriveFunction::Input,
        DriveFunctionJson::Constant(v) => DriveFunction::Constant(v),
        DriveFunctionJson::SpinUp { speed, time } => DriveFunction::SpinUp { speed, time },
        DriveFunctionJson::Sine { amplitude, frequency, phase, offset } => {
            DriveFunction::Sine { amplitude, frequency, phase_rad: phase.to_radians(), offset }
        }
    }
}

/// External flange `i`, its body flange resolved.
pub fn external(
    path: &Path,
    i: usize,
    f: &ExternalFlangeJson,
    bodies: &[AssemblyBodySpec],
) -> Result<ExternalFlangeSpec> {
    let at = reference(path, &format!("assembly.flanges[{i}].at"), &f.at, bodies)?;
    Ok(ExternalFlangeSpec { name: f.name.clone(), role: f.role, at })
}
