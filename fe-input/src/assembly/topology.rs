//! What the joints make of the bodies, before any geometry: no body connected to nothing, and no
//! group of bodies with more constraint equations than degrees of freedom (Gruebler's count).
//!
//! Bodies joined to each other form a group; joints to the ground and a motion external flange
//! constrain the group they act on. Each group is counted on its own (a free body elsewhere does
//! not make room for an over-constrained group): 6 per body, less weld 6, revolute and prismatic
//! 5, spherical 3, universal 4, one more per driven angle or position, 6 for a motion flange. A
//! group connected neither to the ground nor to a motion flange floats, which is fine.

use super::{AssemblyBodySpec, ExternalFlangeSpec, FlangeRef, JointSpec};
use crate::error::{InputError, Result};
use crate::spec::Role;
use std::path::Path;

/// A motion external flange holds its flange's six coordinates.
const MOTION_FLANGE_CONSTRAINTS: usize = 6;

pub fn check(
    path: &Path,
    bodies: &[AssemblyBodySpec],
    joints: &[JointSpec],
    flanges: &[ExternalFlangeSpec],
) -> Result<()> {
    let body_of = |r: &FlangeRef| match r {
        FlangeRef::Body { body, .. } => Some(*body),
        FlangeRef::Ground => None,
    };
    // bodies nothing names
    for (i, b) in bodies.iter().enumerate() {
        let joined = joints.iter().any(|j| j.between.iter().any(|r| body_of(r) == Some(i)));
        let external = flanges.iter().any(|f| body_of(&f.at) == Some(i));
        if !joined && !external {
            return Err(InputError::field(
                path,
                format!("assembly.bodies[{i}]"),
                format!(
                    "body '{}' is connected to nothing: no joint and no external flange names one of its flanges, so \
                     it would fall freely on its own; join it to another body or the ground, give it an external \
                     flange, or remove it",
                    b.name
                ),
            ));
        }
    }
    // groups of bodies joined to each other
    let mut group: Vec<usize> = (0..bodies.len()).collect();
    fn root(group: &mut [usize], mut i: usize) -> usize {
        while group[i] != i {
            group[i] = group[group[i]];
            i = group[i];
        }
        i
    }
    for j in joints {
        if let (Some(a), Some(b)) = (body_of(&j.between[0]), body_of(&j.between[1])) {
            let (ra, rb) = (root(&mut group, a), root(&mut group, b));
            group[ra] = rb;
        }
    }
    let roots: Vec<usize> = (0..bodies.len()).map(|i| root(&mut group, i)).collect();
    let mut seen = Vec::new();
    for &g in &roots {
        if seen.contains(&g) {
            continue;
        }
        seen.push(g);
        let members: Vec<usize> = (0..bodies.len()).filter(|&i| roots[i] == g).collect();
        let in_group = |r: &FlangeRef| body_of(r).is_some_and(|b| roots[b] == g);
        let mut constraints = Vec::new();
        for j in joints.iter().filter(|j| j.between.iter().any(in_group)) {
            let driven =
                j.drive.filter(|d| d.quantity.is_motion()).map(|d| format!(" with a driven {}", d.quantity.word()));
            constraints.push((
                format!(
                    "joint '{}' ({}{}: {})",
                    j.name,
                    j.joint_type.word(),
                    driven.unwrap_or_default(),
                    j.constraints()
                ),
                j.constraints(),
            ));
        }
        for f in flanges.iter().filter(|f| f.role == Role::Motion && in_group(&f.at)) {
            constraints
                .push((format!("motion flange '{}' ({MOTION_FLANGE_CONSTRAINTS})", f.name), MOTION_FLANGE_CONSTRAINTS));
        }
        let equations: usize = constraints.iter().map(|(_, n)| n).sum();
        let freedoms = 6 * members.len();
        if equations > freedoms {
            let names: Vec<String> = members.iter().map(|&i| format!("'{}'", bodies[i].name)).collect();
            let list: Vec<&str> = constraints.iter().map(|(s, _)| s.as_str()).collect();
            return Err(InputError::field(
                path,
                "assembly.joints",
                format!(
                    "over-constrained: {} more constraint equations than the bodies' 6 x {} = {freedoms} degrees of \
                     freedom (bodies {}; {}, {equations} equations in all); a joint that repeats what others hold \
                     already makes the reactions indeterminate. Remove a joint, or give one a type that holds less \
                     (a spherical in place of a revolute, say), or drop a driven angle or position",
                    equations - freedoms,
                    members.len(),
                    names.join(", "),
                    list.join(", ")
                ),
            ));
        }
    }
    Ok(())
}
