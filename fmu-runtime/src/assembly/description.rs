//! What an assembly FMU carries in its resources: the bodies (each flexible one its reduced
//! model, each rigid one its mass properties and flanges), the joints, the drives, the external
//! flanges and the solver's settings, in one file of the shared container format
//! ([`crate::format`]), each body's entries nested under `body.<i>.`.

use super::joint::JointKind;
use crate::format::{Container, FormatError, GUID_ENTRY};
use crate::kinematics::{Mat3, Vec3};
use crate::reduced::ReducedBody;

/// Name of the assembly's file inside the FMU's `resources/` folder.
pub const ASSEMBLY_FILE: &str = "assembly.bin";
/// The entry that tells an assembly's file from a body's.
const KIND_ENTRY: &str = "kind";
const KIND: &str = "assembly";

#[derive(Debug, Clone, PartialEq)]
pub enum BodyModel {
    Flexible(Box<ReducedBody>),
    Rigid { mass: f64, centre: Vec3, inertia_at_centre: Mat3, flanges: Vec<(String, Vec3)> },
}

#[derive(Debug, Clone, PartialEq)]
pub struct BodyDescription {
    pub name: String,
    /// The body frame at the start: origin (world) and axes (body to world, row-major).
    pub position: Vec3,
    pub rotation: Mat3,
    pub model: BodyModel,
}

impl BodyDescription {
    /// Flange names in marker order: a flexible body's mount (its frame) first.
    pub fn flange_names(&self) -> Vec<&str> {
        match &self.model {
            BodyModel::Flexible(b) => {
                std::iter::once(b.mount.as_str()).chain(b.flanges.iter().map(|f| f.name.as_str())).collect()
            }
            BodyModel::Rigid { flanges, .. } => flanges.iter().map(|(n, _)| n.as_str()).collect(),
        }
    }
}

/// One side of a joint: the fixed world, or a body's flange (its marker index: for a flexible
/// body 0 is the mount, 1.. its force flanges).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Side {
    Ground,
    Body { body: usize, marker: usize },
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub enum DriveFunction {
    /// An FMU input sets it.
    Input,
    Constant(f64),
    /// Rate speed (1 - cos(pi t / time)) / 2 until `time`, then `speed`; the value its integral.
    SpinUp {
        speed: f64,
        time: f64,
    },
    /// offset + amplitude sin(2 pi frequency t + phase), phase in rad.
    Sine {
        amplitude: f64,
        frequency: f64,
        phase: f64,
        offset: f64,
    },
}

impl DriveFunction {
    /// Value, rate and second rate at `t` (an input's are its value and zero rates).
    pub fn at(&self, t: f64, input: f64) -> [f64; 3] {
        use std::f64::consts::PI;
        match *self {
            DriveFunction::Input => [input, 0.0, 0.0],
            DriveFunction::Constant(v) => [v, 0.0, 0.0],
            DriveFunction::SpinUp { speed, time } => {
                if t < time {
                    let s = PI * t / time;
                    [
                        speed / 2.0 * (t - time / PI * s.sin()),
                        speed / 2.0 * (1.0 - s.cos()),
                        speed * PI / (2.0 * time) * s.sin(),
                    ]
                } else {
                    [speed / 2.0 * time + speed * (t - time), speed, 0.0]
                }
            }
            DriveFunction::Sine { amplitude, frequency, phase, offset } => {
                let w = 2.0 * PI * frequency;
                let a = w * t + phase;
                [offset + amplitude * a.sin(), amplitude * w * a.cos(), -amplitude * w * w * a.sin()]
            }
        }
    }
}

/// What a drive sets: the joint's motion (angle or position, an equation) or its load (torque or
/// force, a pair of opposite loads on the joint's two sides).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DriveQuantity {
    Motion,
    Load,
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Drive {
    pub quantity: DriveQuantity,
    pub function: DriveFunction,
}

#[derive(Debug, Clone, PartialEq)]
pub struct JointDescription {
    pub name: String,
    pub kind: JointKind,
    pub first: Side,
    pub second: Side,
    /// Revolute and prismatic: axes[0] is the axis (world, at the start). Universal: axes[0] is
    /// fixed in the first side, axes[1] in the second. Unit vectors; unused ones zero.
    pub axes: [Vec3; 2],
    pub drive: Option<Drive>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FlangeRole {
    /// The host applies a force and torque and reads the flange's motion.
    Force,
    /// The host prescribes the flange's motion and reads the reaction.
    Motion,
}

#[derive(Debug, Clone, PartialEq)]
pub struct ExternalFlange {
    pub name: String,
    pub role: FlangeRole,
    pub body: usize,
    pub marker: usize,
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SolverSettings {
    /// Generalised-alpha's spectral radius at infinite frequency: 1 conserves energy, lower
    /// values damp what the step cannot resolve.
    pub spectral_radius: f64,
    /// Newton's tolerance on the position increments [m, and modal units].
    pub tolerance: f64,
    pub max_iterations: usize,
    /// The longest internal step [s]; a longer communication step is split.
    pub max_step: f64,
}

impl Default for SolverSettings {
    fn default() -> Self {
        Self { spectral_radius: 1.0, tolerance: 1e-10, max_iterations: 12, max_step: 1e-3 }
    }
}

#[derive(Debug, Clone, PartialEq)]
pub struct AssemblyDescription {
    pub guid: String,
    pub model_name: String,
    pub gravity: Vec3,
    pub bodies: Vec<BodyDescription>,
    pub joints: Vec<JointDescription>,
    pub flanges: Vec<ExternalFlange>,
    pub solver: SolverSettings,
}

fn side_code(s: Side) -> [f64; 2] {
    match s {
        Side::Ground => [-1.0, 0.0],
        Side::Body { body, marker } => [body as f64, marker as f64],
    }
}

fn index(x: f64, len: usize, what: &str) -> Result<usize, FormatError> {
    if x >= 0.0 && x.fract() == 0.0 && (x as usize) < len {
        Ok(x as usize)
    } else {
        Err(FormatError::Malformed(format!("{what} = {x} is no index below {len}")))
    }
}

impl AssemblyDescription {
    /// Whether `c` holds an assembly (rather than one body).
    pub fn is_assembly(c: &Container) -> bool {
        c.text(KIND_ENTRY).is_ok_and(|k| k == KIND)
    }

    pub fn to_container(&self) -> Container {
        let mut c = Container::new();
        c.put_text(KIND_ENTRY, KIND);
        c.put_text(GUID_ENTRY, &self.guid);
        c.put_text("model_name", &self.model_name);
        c.put_array("gravity", &[3], &self.gravity);
        let s = &self.solver;
        c.put_array("solver", &[4], &[s.spectral_radius, s.tolerance, s.max_iterations as f64, s.max_step]);
        c.put_array("body.count", &[1], &[self.bodies.len() as f64]);
        for (i, b) in self.bodies.iter().enumerate() {
            let p = format!("body.{i}.");
            c.put_text(&format!("{p}name"), &b.name);
            c.put_array(&format!("{p}position"), &[3], &b.position);
            c.put_array(&format!("{p}rotation"), &[3, 3], &b.rotation);
            match &b.model {
                BodyModel::Flexible(r) => c.nest(&format!("{p}flexible."), &r.to_container()),
                BodyModel::Rigid { mass, centre, inertia_at_centre, flanges } => {
                    c.put_array(&format!("{p}rigid.mass"), &[1], &[*mass]);
                    c.put_array(&format!("{p}rigid.centre"), &[3], centre);
                    c.put_array(&format!("{p}rigid.inertia"), &[3, 3], inertia_at_centre);
                    c.put_array(&format!("{p}rigid.flange.count"), &[1], &[flanges.len() as f64]);
                    for (k, (name, at)) in flanges.iter().enumerate() {
                        c.put_text(&format!("{p}rigid.flange.{k}.name"), name);
                        c.put_array(&format!("{p}rigid.flange.{k}.position"), &[3], at);
                    }
                }
            }
        }
        c.put_array("joint.count", &[1], &[self.joints.len() as f64]);
        for (i, j) in self.joints.iter().enumerate() {
            let p = format!("joint.{i}.");
            c.put_text(&format!("{p}name"), &j.name);
            c.put_text(&format!("{p}kind"), j.kind.name());
            let [f, s] = [side_code(j.first), side_code(j.second)];
            c.put_array(&format!("{p}sides"), &[4], &[f[0], f[1], s[0], s[1]]);
            c.put_array(&format!("{p}axes"), &[2, 3], &[j.axes[0], j.axes[1]].concat());
            if let Some(d) = &j.drive {
                let q = match d.quantity {
                    DriveQuantity::Motion => 0.0,
                    DriveQuantity::Load => 1.0,
                };
                let f = match d.function {
                    DriveFunction::Input => [0.0, 0.0, 0.0, 0.0, 0.0],
                    DriveFunction::Constant(v) => [1.0, v, 0.0, 0.0, 0.0],
                    DriveFunction::SpinUp { speed, time } => [2.0, speed, time, 0.0, 0.0],
                    DriveFunction::Sine { amplitude, frequency, phase, offset } => {
                        [3.0, amplitude, frequency, phase, offset]
                    }
                };
                c.put_array(&format!("{p}drive"), &[6], &[q, f[0], f[1], f[2], f[3], f[4]]);
            }
        }
        c.put_array("flange.count", &[1], &[self.flanges.len() as f64]);
        for (i, f) in self.flanges.iter().enumerate() {
            let p = format!("flange.{i}.");
            c.put_text(&format!("{p}name"), &f.name);
            let role = match f.role {
                FlangeRole::Force => 0.0,
                FlangeRole::Motion => 1.0,
            };
            c.put_array(&format!("{p}at"), &[3], &[role, f.body as f64, f.marker as f64]);
        }
        c
    }

    pub fn from_container(c: &Container) -> Result<Self, FormatError> {
        if !Self::is_assembly(c) {
            return Err(FormatError::Malformed("it is not an assembly's file".into()));
        }
        let count = |name: &str| -> Result<usize, FormatError> {
            let x = c.scalar(name)?;
            if x >= 0.0 && x.fract() == 0.0 && x <= 10_000.0 {
                Ok(x as usize)
            } else {
                Err(FormatError::Malformed(format!("{name} = {x}")))
            }
        };
        let s = c.array("solver", &[4])?;
        let solver =
            SolverSettings { spectral_radius: s[0], tolerance: s[1], max_iterations: s[2] as usize, max_step: s[3] };
        if !(0.0..=1.0).contains(&solver.spectral_radius)
            || !(solver.tolerance > 0.0)
            || !(2..=100).contains(&solver.max_iterations)
            || !(solver.max_step > 0.0)
        {
            return Err(FormatError::Malformed(format!("solver settings {s:?} out of range")));
        }
        let mut bodies = Vec::new();
        for i in 0..count("body.count")? {
            let p = format!("body.{i}.");
            let model = if c.contains(&format!("{p}rigid.mass")) {
                let mut flanges = Vec::new();
                for k in 0..count(&format!("{p}rigid.flange.count"))? {
                    flanges.push((
                        c.text(&format!("{p}rigid.flange.{k}.name"))?.to_owned(),
                        to3(c.array(&format!("{p}rigid.flange.{k}.position"), &[3])?),
                    ));
                }
                BodyModel::Rigid {
                    mass: c.scalar(&format!("{p}rigid.mass"))?,
                    centre: to3(c.array(&format!("{p}rigid.centre"), &[3])?),
                    inertia_at_centre: to9(c.array(&format!("{p}rigid.inertia"), &[3, 3])?),
                    flanges,
                }
            } else {
                BodyModel::Flexible(Box::new(ReducedBody::from_container(&c.nested(&format!("{p}flexible.")))?))
            };
            bodies.push(BodyDescription {
                name: c.text(&format!("{p}name"))?.to_owned(),
                position: to3(c.array(&format!("{p}position"), &[3])?),
                rotation: to9(c.array(&format!("{p}rotation"), &[3, 3])?),
                model,
            });
        }
        let markers: Vec<usize> = bodies.iter().map(|b| b.flange_names().len()).collect();
        let side = |body: f64, marker: f64, what: &str| -> Result<Side, FormatError> {
            if body == -1.0 {
                return Ok(Side::Ground);
            }
            let body = index(body, bodies.len(), what)?;
            Ok(Side::Body { body, marker: index(marker, markers[body], what)? })
        };
        let mut joints = Vec::new();
        for i in 0..count("joint.count")? {
            let p = format!("joint.{i}.");
            let kind_name = c.text(&format!("{p}kind"))?;
            let kind = JointKind::from_name(kind_name)
                .ok_or_else(|| FormatError::Malformed(format!("{p}kind '{kind_name}' is no joint type")))?;
            let sides = c.array(&format!("{p}sides"), &[4])?;
            let axes = c.array(&format!("{p}axes"), &[2, 3])?;
            let drive = if c.contains(&format!("{p}drive")) {
                let d = c.array(&format!("{p}drive"), &[6])?;
                let quantity = if d[0] == 0.0 { DriveQuantity::Motion } else { DriveQuantity::Load };
                let function = match d[1] as i64 {
                    0 => DriveFunction::Input,
                    1 => DriveFunction::Constant(d[2]),
                    2 => DriveFunction::SpinUp { speed: d[2], time: d[3] },
                    3 => DriveFunction::Sine { amplitude: d[2], frequency: d[3], phase: d[4], offset: d[5] },
                    _ => return Err(FormatError::Malformed(format!("{p}drive function {}", d[1]))),
                };
                Some(Drive { quantity, function })
            } else {
                None
            };
            joints.push(JointDescription {
                name: c.text(&format!("{p}name"))?.to_owned(),
                kind,
                first: side(sides[0], sides[1], &format!("{p}sides"))?,
                second: side(sides[2], sides[3], &format!("{p}sides"))?,
                axes: [to3(&axes[..3]), to3(&axes[3..])],
                drive,
            });
        }
        let mut flanges = Vec::new();
        for i in 0..count("flange.count")? {
            let p = format!("flange.{i}.");
            let at = c.array(&format!("{p}at"), &[3])?;
            let body = index(at[1], bodies.len(), &format!("{p}at"))?;
            flanges.push(ExternalFlange {
                name: c.text(&format!("{p}name"))?.to_owned(),
                role: if at[0] == 0.0 { FlangeRole::Force } else { FlangeRole::Motion },
                body,
                marker: index(at[2], markers[body], &format!("{p}at"))?,
            });
        }
        Ok(Self {
            guid: c.text(GUID_ENTRY)?.to_owned(),
            model_name: c.text("model_name")?.to_owned(),
            gravity: to3(c.array("gravity", &[3])?),
            bodies,
            joints,
            flanges,
            solver,
        })
    }

    /// Give the assembly the GUID of its content (what the builder does before writing it).
    pub fn seal(&mut self) {
        self.guid.clear();
        self.guid = self.to_container().content_guid();
    }

    pub fn to_bytes(&self) -> Vec<u8> {
        self.to_container().to_bytes()
    }

    /// The assembly of an FMU's file: the stored GUID must be the content's.
    pub fn from_sealed_bytes(bytes: &[u8]) -> Result<Self, FormatError> {
        Self::from_container(&Container::from_sealed_bytes(bytes)?)
    }
}

fn to3(x: &[f64]) -> Vec3 {
    [x[0], x[1], x[2]]
}

fn to9(x: &[f64]) -> Mat3 {
    std::array::from_fn(|i| x[i])
}
