//! The variables of an assembly's FMU: the one table from which the builder writes
//! modelDescription.xml and through which the runtime answers fmi2Get/Set.
//!
//! | who | inputs | outputs |
//! |---|---|---|
//! | the assembly | parameter `g[1..3]` | `energy.kinetic`, `.strain`, `.potential`, `.total`, `joints.drift` |
//! | a joint `j` | `j.drive_angle`, `_torque`, `_position` or `_force` where an input drives it | `j.angle` (revolute) or `j.position` (prismatic) and `j.rate`; `j.f[1..3]`, `j.t[1..3]` |
//! | a body's flange `b.f` | | `b.f.r[1..3]`, `b.f.R[i,j]`, `b.f.v[1..3]`, `b.f.w[1..3]` |
//! | an external force flange `x` | `x.f[1..3]`, `x.t[1..3]` | `x.r`, `x.R`, `x.v`, `x.w`, `x.a`, `x.z` |
//! | an external motion flange `x` | `x.r`, `x.R`, `x.v`, `x.w`, `x.a`, `x.z` | `x.f[1..3]`, `x.t[1..3]` |
//!
//! Vectors are in world axes, except a joint's reaction: the force and torque the joint applies
//! to its second side, at that side's flange, in the first side's joint axes (a3 the axis of a
//! revolute or prismatic joint; a1 the first axis of a universal one).

use crate::assembly::description::{AssemblyDescription, DriveQuantity, FlangeRole};
use crate::assembly::joint::JointKind;
use crate::assembly::model::Assembly;
use fmi2::{Causality, Initial, Variability};

/// What a variable reads or sets.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Slot {
    Gravity(usize),
    DriveInput(usize),
    /// External force flange (index among the force flanges), component 0..6 (f, t).
    Load(usize, usize),
    /// The host's frame: 0 r, 1 R (9), 2 v, 3 w, 4 a, 5 z; component.
    Host(usize, usize),
    JointValue(usize),
    JointRate(usize),
    /// Joint, component 0..6 (f, t).
    JointReaction(usize, usize),
    /// Body, marker, quantity (0 r, 1 R, 2 v, 3 w, 4 a, 5 z), component.
    Flange(usize, usize, usize, usize),
    /// The motion flange's reaction, component 0..6.
    MountReaction(usize),
    /// 0 kinetic, 1 strain, 2 potential, 3 total.
    Energy(usize),
    Drift,
}

#[derive(Debug, Clone, PartialEq)]
pub struct AssemblyVariable {
    pub vr: u32,
    pub name: String,
    pub description: String,
    pub causality: Causality,
    pub variability: Variability,
    pub initial: Option<Initial>,
    pub start: Option<f64>,
    pub unit: Option<&'static str>,
    pub slot: Slot,
}

#[derive(Debug, Clone)]
pub struct AssemblyTable {
    pub variables: Vec<AssemblyVariable>,
}

const QUANTITIES: [(&str, &str, &str); 6] = [
    ("r", "m", "position"),
    ("R", "", "rotation matrix, columns the flange's axes"),
    ("v", "m/s", "velocity"),
    ("w", "rad/s", "angular velocity"),
    ("a", "m/s2", "acceleration"),
    ("z", "rad/s2", "angular acceleration"),
];

fn component_names(stem: &str, quantity: usize) -> Vec<String> {
    if quantity == 1 {
        (0..9).map(|k| format!("{stem}.R[{},{}]", k / 3 + 1, k % 3 + 1)).collect()
    } else {
        (0..3).map(|k| format!("{stem}.{}[{}]", QUANTITIES[quantity].0, k + 1)).collect()
    }
}

impl AssemblyTable {
    pub fn new(d: &AssemblyDescription, a: &Assembly) -> Self {
        let mut t = Vec::new();
        let mut add = |name: String, description: String, causality, unit: &'static str, start: Option<f64>, slot| {
            let variability =
                if causality == Causality::Parameter { Variability::Fixed } else { Variability::Continuous };
            t.push(AssemblyVariable {
                vr: t.len() as u32 + 1,
                name,
                description,
                causality,
                variability,
                initial: None,
                start,
                unit: (!unit.is_empty()).then_some(unit),
                slot,
            });
        };
        for k in 0..3 {
            add(
                format!("g[{}]", k + 1),
                "gravity, world".into(),
                Causality::Parameter,
                "m/s2",
                Some(d.gravity[k]),
                Slot::Gravity(k),
            );
        }
        let s = &a.system;
        for (i, (j, quantity)) in s.drive_inputs.iter().enumerate() {
            let joint = &s.joints[*j];
            let (what, unit) = match (joint.kind, quantity) {
                (JointKind::Revolute, DriveQuantity::Motion) => ("angle", "rad"),
                (JointKind::Revolute, DriveQuantity::Load) => ("torque", "N.m"),
                (_, DriveQuantity::Motion) => ("position", "m"),
                (_, DriveQuantity::Load) => ("force", "N"),
            };
            let description = if *quantity == DriveQuantity::Motion {
                format!("driven {what} of joint {} from its start", joint.name)
            } else {
                format!("driving {what} of joint {} about (along) its axis, on its second side", joint.name)
            };
            add(
                format!("{}.drive_{what}", joint.name),
                description,
                Causality::Input,
                unit,
                Some(0.0),
                Slot::DriveInput(i),
            );
        }
        let mut force_flange = 0;
        for (name, role, body, marker) in &s.flanges {
            match role {
                FlangeRole::Force => {
                    for k in 0..6 {
                        let (q, unit) = if k < 3 { ("f", "N") } else { ("t", "N.m") };
                        add(
                            format!("{name}.{q}[{}]", k % 3 + 1),
                            format!("{} applied at the flange, world", if k < 3 { "force" } else { "torque" }),
                            Causality::Input,
                            unit,
                            Some(0.0),
                            Slot::Load(force_flange, k),
                        );
                    }
                    force_flange += 1;
                    for q in 0..6 {
                        for (k, n) in component_names(name, q).into_iter().enumerate() {
                            add(
                                n,
                                format!("flange {}, world", QUANTITIES[q].2),
                                Causality::Output,
                                QUANTITIES[q].1,
                                None,
                                Slot::Flange(*body, *marker, q, k),
                            );
                        }
                    }
                }
                FlangeRole::Motion => {
                    let host = a.inputs.host;
                    for q in 0..6 {
                        for (k, n) in component_names(name, q).into_iter().enumerate() {
                            let start = match q {
                                0 => host.r[k],
                                1 => host.rot[k],
                                _ => 0.0,
                            };
                            add(
                                n,
                                format!("prescribed flange {}, world", QUANTITIES[q].2),
                                Causality::Input,
                                QUANTITIES[q].1,
                                Some(start),
                                Slot::Host(q, k),
                            );
                        }
                    }
                    for k in 0..6 {
                        let (q, unit) = if k < 3 { ("f", "N") } else { ("t", "N.m") };
                        add(
                            format!("{name}.{q}[{}]", k % 3 + 1),
                            format!("{} the mount applies to the body, world", if k < 3 { "force" } else { "torque" }),
                            Causality::Output,
                            unit,
                            None,
                            Slot::MountReaction(k),
                        );
                    }
                }
            }
        }
        for (j, joint) in s.joints.iter().enumerate() {
            if joint.a == crate::assembly::system::Attach::Host {
                continue;
            }
            match joint.kind {
                JointKind::Revolute => {
                    add(
                        format!("{}.angle", joint.name),
                        "angle of the second side about the axis".into(),
                        Causality::Output,
                        "rad",
                        None,
                        Slot::JointValue(j),
                    );
                    add(
                        format!("{}.rate", joint.name),
                        "angular rate about the axis".into(),
                        Causality::Output,
                        "rad/s",
                        None,
                        Slot::JointRate(j),
                    );
                }
                JointKind::Prismatic => {
                    add(
                        format!("{}.position", joint.name),
                        "position of the second side along the axis".into(),
                        Causality::Output,
                        "m",
                        None,
                        Slot::JointValue(j),
                    );
                    add(
                        format!("{}.rate", joint.name),
                        "rate along the axis".into(),
                        Causality::Output,
                        "m/s",
                        None,
                        Slot::JointRate(j),
                    );
                }
                _ => {}
            }
            for k in 0..6 {
                let (q, unit, what) = if k < 3 { ("f", "N", "force") } else { ("t", "N.m", "torque") };
                add(
                    format!("{}.{q}[{}]", joint.name, k % 3 + 1),
                    format!("{what} of the joint on its second side, in its joint axes"),
                    Causality::Output,
                    unit,
                    None,
                    Slot::JointReaction(j, k),
                );
            }
        }
        for (b, body) in s.bodies.iter().enumerate() {
            for (m, marker) in body.inertia.markers.iter().enumerate() {
                let stem = format!("{}.{}", body.name, marker.name);
                for q in 0..4 {
                    for (k, n) in component_names(&stem, q).into_iter().enumerate() {
                        add(
                            n,
                            format!("flange {}, world", QUANTITIES[q].2),
                            Causality::Output,
                            QUANTITIES[q].1,
                            None,
                            Slot::Flange(b, m, q, k),
                        );
                    }
                }
            }
        }
        for (k, what) in ["kinetic", "strain", "potential", "total"].into_iter().enumerate() {
            let description = match k {
                2 => "potential energy of the weight".to_string(),
                3 => "kinetic + strain + potential energy".to_string(),
                _ => format!("{what} energy of all bodies"),
            };
            add(format!("energy.{what}"), description, Causality::Output, "J", None, Slot::Energy(k));
        }
        add(
            "joints.drift".into(),
            "largest violation of a joint's equations (m, or rad)".into(),
            Causality::Output,
            "m",
            None,
            Slot::Drift,
        );
        Self { variables: t }
    }

    pub fn get(&self, vr: u32) -> Option<&AssemblyVariable> {
        (vr as usize).checked_sub(1).and_then(|i| self.variables.get(i))
    }

    pub fn value_reference(&self, name: &str) -> Option<u32> {
        self.variables.iter().find(|v| v.name == name).map(|v| v.vr)
    }
}
