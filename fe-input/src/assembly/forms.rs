//! The forms of an assembly's fields that the schema states too (in its conditionals, which
//! editors check as the user types), checked here first so that the message says why: a body's
//! keys in an assembly, one of flexible or rigid, the axis a joint type needs or refuses, the
//! drives it takes, a reference's shape, one motion flange, reserved names. Also the directions
//! the schema cannot check: a zero axis, universal axes that are not perpendicular.

use super::json::{AssemblyFile, DriveJson, JointJson, JointType};
use super::vectors::{dot, norm, normalised};
use crate::error::{InputError, Result};
use crate::spec::Role;
use crate::variable_names;
use std::path::Path;

/// The body input's keys, which an assembly's bodies carry each in their own input.
pub const BODY_KEYS: [&str; 8] =
    ["geometry", "material", "materials", "damping", "flanges", "scene", "reduction", "outputs"];

/// Largest |cos| between a universal joint's two axes taken as perpendicular.
pub const PERPENDICULAR_COS: f64 = 1e-6;

/// An assembly has none of a body's top-level keys.
pub fn check_no_body_keys(path: &Path, value: &serde_json::Value) -> Result<()> {
    if let Some(key) = BODY_KEYS.iter().find(|k| value.get(**k).is_some()) {
        return Err(InputError::field(
            path,
            *key,
            format!(
                "an assembly (this file has \"assembly\") has no \"{key}\" of its own: each flexible body brings its \
                 geometry, material, flanges and reduction in its body input (assembly.bodies[i].flexible, a file or \
                 written inline); move \"{key}\" there, or remove \"assembly\" if this is one body's input"
            ),
        ));
    }
    Ok(())
}

pub fn check(path: &Path, file: &AssemblyFile) -> Result<()> {
    let a = &file.assembly;
    for (i, b) in a.bodies.iter().enumerate() {
        let at = format!("assembly.bodies[{i}]");
        check_name(path, &format!("{at}.name"), &b.name)?;
        if b.name == "ground" {
            return Err(InputError::field(
                path,
                format!("{at}.name"),
                "\"ground\" names the fixed world in flange references (\"ground\" in a joint's between); call the \
                 body otherwise",
            ));
        }
        match (&b.flexible, &b.rigid) {
            (Some(_), Some(_)) => {
                return Err(InputError::field(
                    path,
                    at,
                    "a body is either flexible or rigid: give one of \"flexible\" and \"rigid\", not both",
                ));
            }
            (None, None) => {
                return Err(InputError::field(
                    path,
                    at,
                    "give the body \"flexible\" (a body input file or an inline body input) or \"rigid\" (mass, \
                     centre_of_mass, inertia, flanges)",
                ));
            }
            _ => {}
        }
        if let Some(r) = &b.rotation
            && norm(r.axis) == 0.0
        {
            return Err(InputError::field(
                path,
                format!("{at}.rotation.axis"),
                "the rotation's axis is the zero vector; give the direction to rotate about (or no rotation)",
            ));
        }
    }
    for (k, j) in a.joints.iter().enumerate() {
        check_joint(path, k, j)?;
    }
    for (i, f) in a.flanges.iter().enumerate() {
        let at = format!("assembly.flanges[{i}]");
        check_name(path, &format!("{at}.name"), &f.name)?;
        if f.at == "ground" {
            return Err(InputError::field(
                path,
                format!("{at}.at"),
                "an external flange is a body's flange, \"body.flange\"; the ground is the fixed world, which the \
                 host cannot connect to",
            ));
        }
        check_reference(path, &format!("{at}.at"), &f.at)?;
    }
    let mounts: Vec<usize> = (0..a.flanges.len()).filter(|&i| a.flanges[i].role == Role::Motion).collect();
    if let [first, second, ..] = mounts[..] {
        return Err(InputError::field(
            path,
            format!("assembly.flanges[{second}].role"),
            format!(
                "a second \"motion\" flange (assembly.flanges[{first}] is one): two frames whose motion the host \
                 prescribes over-constrain the bodies between them, which could then neither move nor deform as the \
                 two motions demand; make this one a \"force\" flange (the host reads its motion), or join it to the \
                 other body with a joint"
            ),
        ));
    }
    Ok(())
}

/// A name of the FMU's variables: not one the FMU's own variables use.
fn check_name(path: &Path, field: &str, name: &str) -> Result<()> {
    if variable_names::RESERVED.contains(&name) {
        return Err(InputError::field(
            path,
            field,
            format!(
                "\"{name}\" is the name of the FMU's own variables ({name}...); the names of an assembly's bodies, joints \
                 and external flanges become its variables' names and would collide with them. Rename it; reserved \
                 names: {}",
                variable_names::RESERVED.join(", ")
            ),
        ));
    }
    Ok(())
}

/// "ground" or "body.flange".
fn check_reference(path: &Path, field: &str, reference: &str) -> Result<()> {
    let stem = |s: &str| {
        s.chars().next().is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
            && s.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
    };
    match reference.split_once('.') {
        _ if reference == "ground" => Ok(()),
        Some((body, flange)) if stem(body) && stem(flange) => Ok(()),
        _ => Err(InputError::field(
            path,
            field,
            format!(
                "\"{reference}\" is not a flange reference: write \"body.flange\" (a body's name, a dot, one of its \
                 flanges' names) or \"ground\""
            ),
        )),
    }
}

fn check_joint(path: &Path, k: usize, j: &JointJson) -> Result<()> {
    let at = format!("assembly.joints[{k}]");
    let t = j.joint_type;
    check_name(path, &format!("{at}.name"), &j.name)?;
    for (e, r) in j.between.iter().enumerate() {
        check_reference(path, &format!("{at}.between[{e}]"), r)?;
    }
    match (t.has_axis(), j.axis) {
        (true, None) => {
            return Err(InputError::field(
                path,
                format!("{at}.axis"),
                format!(
                    "a {} joint needs its axis: the direction, in the world at t = 0, it {} about",
                    t.word(),
                    if t == JointType::Revolute { "rotates" } else { "slides" }
                ),
            ));
        }
        (false, Some(_)) => {
            let instead = if t == JointType::Universal { " (a universal joint has two: \"axes\")" } else { "" };
            return Err(InputError::field(
                path,
                format!("{at}.axis"),
                format!("a {} joint has no axis; only revolute and prismatic joints take one{instead}", t.word()),
            ));
        }
        (true, Some(axis)) if norm(axis) == 0.0 => {
            return Err(InputError::field(path, format!("{at}.axis"), "the axis is the zero vector"));
        }
        _ => {}
    }
    match (t == JointType::Universal, j.axes) {
        (true, None) => {
            return Err(InputError::field(
                path,
                format!("{at}.axes"),
                "a universal joint needs its two axes: perpendicular world vectors at t = 0, the first fixed in the \
                 first flange's body, the second in the second's",
            ));
        }
        (false, Some(_)) => {
            return Err(InputError::field(
                path,
                format!("{at}.axes"),
                format!("a {} joint has no \"axes\"; only a universal joint takes two", t.word()),
            ));
        }
        (true, Some(axes)) => {
            for (e, v) in axes.iter().enumerate() {
                if norm(*v) == 0.0 {
                    return Err(InputError::field(path, format!("{at}.axes[{e}]"), "the axis is the zero vector"));
                }
            }
            let cos = dot(normalised(axes[0]), normalised(axes[1]));
            if cos.abs() >= PERPENDICULAR_COS {
                return Err(InputError::field(
                    path,
                    format!("{at}.axes"),
                    format!(
                        "the two axes must be perpendicular, and they are {:.6} degrees apart (cosine {cos:.3e}; \
                         at most {PERPENDICULAR_COS:e} is taken as perpendicular)",
                        cos.clamp(-1.0, 1.0).acos().to_degrees()
                    ),
                ));
            }
        }
        _ => {}
    }
    if let Some(d) = &j.drive {
        check_drive(path, &at, t, d)?;
    }
    Ok(())
}

fn check_drive(path: &Path, at: &str, t: JointType, d: &DriveJson) -> Result<()> {
    let given: Vec<&str> = [("angle", d.angle), ("torque", d.torque), ("position", d.position), ("force", d.force)]
        .iter()
        .filter(|(_, f)| f.is_some())
        .map(|(k, _)| *k)
        .collect();
    let takes = match t {
        JointType::Revolute => ["angle", "torque"],
        JointType::Prismatic => ["position", "force"],
        _ => {
            return Err(InputError::field(
                path,
                format!("{at}.drive"),
                format!(
                    "a {} joint cannot be driven; only revolute (angle or torque) and prismatic (position or force) \
                     joints take a drive",
                    t.word()
                ),
            ));
        }
    };
    match given[..] {
        [one] if takes.contains(&one) => Ok(()),
        [one] => Err(InputError::field(
            path,
            format!("{at}.drive.{one}"),
            format!("a {} joint's drive is \"{}\" or \"{}\", not \"{one}\"", t.word(), takes[0], takes[1]),
        )),
        _ => Err(InputError::field(
            path,
            format!("{at}.drive"),
            format!(
                "a drive has exactly one key: \"{}\" or \"{}\" for a {} joint (found {})",
                takes[0],
                takes[1],
                t.word(),
                if given.is_empty() { "none".to_string() } else { given.join(", ") }
            ),
        )),
    }
}
