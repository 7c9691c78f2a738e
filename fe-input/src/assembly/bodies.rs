//! An assembly's bodies: flexible ones read by the body input's own code (from their file, or
//! written inline), rigid ones' mass properties checked, each placed by its position and rotation.

use super::json::{BodyJson, RigidBodySpec};
use super::vectors::{IDENTITY, rotation_matrix, symmetric_eigenvalues};
use super::{AssemblyBodySpec, BodyKind};
use crate::error::{InputError, Result};
use crate::spec::Spec;
use std::path::Path;

/// Relative allowance of the inertia checks (the principal moments come out of a cubic's roots):
/// a thin plate's Izz = Ixx + Iyy exactly is admitted.
const INERTIA_ROUNDING: f64 = 1e-12;

/// Every inline flexible body (an object at `assembly.bodies[i].flexible`) read as a body input,
/// its fields named below that path; None where body `i` is not one. Run before the schema, which
/// would say of a problem inside one only that the body matches none of its forms.
pub fn inline_bodies(path: &Path, value: &serde_json::Value) -> Result<Vec<Option<Spec>>> {
    let Some(bodies) = value.pointer("/assembly/bodies").and_then(|b| b.as_array()) else {
        return Ok(Vec::new());
    };
    let mut out = Vec::with_capacity(bodies.len());
    for (i, b) in bodies.iter().enumerate() {
        let at = format!("assembly.bodies[{i}].flexible");
        match b.get("flexible") {
            Some(inline @ serde_json::Value::Object(fields)) => {
                if fields.contains_key("assembly") {
                    return Err(InputError::field(
                        path,
                        format!("{at}.assembly"),
                        "a body of an assembly is one body's input (geometry, material, flanges, reduction), not \
                         another assembly; list the inner assembly's bodies and joints in this one",
                    ));
                }
                out.push(Some(Spec::from_value(path, inline.clone(), &at)?));
            }
            _ => out.push(None),
        }
    }
    Ok(out)
}

/// Body `i`; `inline` is its inline body input, read already.
pub fn resolve(path: &Path, i: usize, b: &BodyJson, inline: Option<Spec>) -> Result<AssemblyBodySpec> {
    let at = format!("assembly.bodies[{i}]");
    let kind = match (&b.flexible, &b.rigid, inline) {
        (_, _, Some(spec)) => flexible(path, &at, spec, None)?,
        (Some(serde_json::Value::String(name)), _, None) => {
            let field = format!("{at}.flexible");
            let file = Spec::readable_file(path, &field, name)?;
            let spec = Spec::from_file(&file)?;
            flexible(path, &at, spec, Some(file))?
        }
        (_, Some(r), None) => {
            check_rigid(path, &at, r)?;
            BodyKind::Rigid(r.clone())
        }
        // the schema and `forms` admit nothing else
        _ => return Err(InputError::field(path, at, "give \"flexible\" or \"rigid\"")),
    };
    Ok(AssemblyBodySpec {
        name: b.name.clone(),
        kind,
        position: b.position,
        rotation: b.rotation.map_or(IDENTITY, |r| rotation_matrix(r.axis, r.angle)),
    })
}

/// A flexible body needs its mount: its motion flange is the body's frame.
fn flexible(path: &Path, at: &str, spec: Spec, file: Option<std::path::PathBuf>) -> Result<BodyKind> {
    if spec.mount_index().is_none() {
        let which = match &file {
            Some(f) => format!("the body input {}", f.display()),
            None => "the body input written here".to_string(),
        };
        return Err(InputError::field(
            path,
            format!("{at}.flexible"),
            format!(
                "{which} has no flange of role \"motion\": a free-floating flexible body is not supported in an \
                 assembly yet. Give it one motion flange: its reference point, with the part's axes, is the body's \
                 frame, which position and rotation place (a joint may attach there)"
            ),
        ));
    }
    Ok(BodyKind::Flexible { spec: Box::new(spec), file })
}

/// Flange names of their own; an inertia a rigid body can have.
fn check_rigid(path: &Path, at: &str, r: &RigidBodySpec) -> Result<()> {
    for (j, f) in r.flanges.iter().enumerate() {
        if let Some(first) = r.flanges[..j].iter().position(|g| g.name == f.name) {
            return Err(InputError::field(
                path,
                format!("{at}.rigid.flanges[{j}].name"),
                format!("\"{}\" is already the name of {at}.rigid.flanges[{first}]", f.name),
            ));
        }
    }
    let field = format!("{at}.rigid.inertia");
    let [lo, mid, hi] = symmetric_eigenvalues(r.inertia);
    let scale = lo.abs() + mid.abs() + hi.abs();
    let principal = format!("principal moments {lo:.4e}, {mid:.4e}, {hi:.4e} kg m^2");
    if !(lo > INERTIA_ROUNDING * scale) {
        return Err(InputError::field(
            path,
            field,
            format!(
                "the inertia tensor [Ixx, Iyy, Izz, Ixy, Iyz, Izx] = {:?} is not positive definite ({principal}): \
                 every principal moment of a body with mass is positive; check the signs of the products and that \
                 they are given about the centre of mass",
                r.inertia
            ),
        ));
    }
    if lo + mid < hi * (1.0 - INERTIA_ROUNDING) {
        return Err(InputError::field(
            path,
            field,
            format!(
                "no body has this inertia: its {principal} break the triangle inequality (the two smaller must add \
                 up to at least the largest; {lo:.4e} + {mid:.4e} < {hi:.4e}), which holds for any distribution of \
                 mass; check the values and their order [Ixx, Iyy, Izz, Ixy, Iyz, Izx]"
            ),
        ));
    }
    Ok(())
}
