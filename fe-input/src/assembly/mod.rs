//! An assembly's input: several bodies (flexible ones given by body inputs, rigid ones by their
//! mass properties) and the joints between them, in one FMU. A file is an assembly when its
//! top-level object has the key `assembly` (`is_assembly`); it then has none of a body's keys.
//!
//! The file is checked in this order: JSON, duplicate keys, a body's keys where an assembly has
//! none, every inline flexible body by the body input's own checks (its fields named below
//! `assembly.bodies[i].flexible`), the forms the schema's conditionals express too but in words
//! that say why (`forms`), the schema, then what needs the names resolved: body files read, rigid
//! bodies' inertia, flange references, names unique, the count of degrees of freedom and
//! bodies connected to nothing (`bodies`, `joints`, `topology`).
//!
//! What needs the flanges' places (the two flanges of a joint coincide at t = 0, for every type
//! but prismatic) is known only once the flexible bodies are meshed, and is checked there.

mod bodies;
mod forms;
mod joints;
pub mod json;
mod topology;
pub mod vectors;

#[cfg(test)]
mod tests;

use crate::error::{InputError, Result};
use crate::json_keys;
use crate::spec::{self, Experiment, Spec};
pub use json::{JointType, RigidBodySpec, RigidFlangeSpec, STANDARD_GRAVITY, SolverSpec};
pub use spec::Role;
use std::path::{Path, PathBuf};

/// A parsed and checked assembly: every name resolved, every direction normalised, every angle
/// in radians.
#[derive(Debug, Clone, serde::Serialize)]
pub struct AssemblySpec {
    /// The FMU's model name.
    pub name: String,
    pub description: Option<String>,
    /// The whole assembly's DefaultExperiment (checked as a body's is).
    pub experiment: Option<Experiment>,
    /// [m/s^2], world.
    pub gravity: [f64; 3],
    pub bodies: Vec<AssemblyBodySpec>,
    pub joints: Vec<JointSpec>,
    /// The external flanges: where the host connects; at most one of role motion.
    pub flanges: Vec<ExternalFlangeSpec>,
    pub solver: SolverSpec,
    /// The assembly's file: the folder inline bodies' file names resolve from.
    pub file: PathBuf,
}

/// One body of the assembly and where its frame is at t = 0.
#[derive(Debug, Clone, serde::Serialize)]
pub struct AssemblyBodySpec {
    /// Unique, a variable-name stem, not `ground`.
    pub name: String,
    pub kind: BodyKind,
    /// [m], world: the body frame's origin at t = 0. A flexible body's frame is its mount's
    /// (motion flange's) reference point with the part's own axes; a rigid body's is the frame
    /// its centre of mass, inertia and flanges are given in.
    pub position: [f64; 3],
    /// The body frame's axes in the world at t = 0, row-major: a vector's world components are
    /// `rotation * body components` (identity where the input gives no rotation).
    pub rotation: [f64; 9],
}

/// What a body is made of.
#[derive(Debug, Clone, serde::Serialize)]
pub enum BodyKind {
    /// A body input, loaded and checked by `Spec`'s own code; it has exactly one motion flange
    /// (the body frame). `file` is the body input file as resolved, or None for a body written
    /// inline in the assembly (its file names then resolve from the assembly's file).
    Flexible {
        spec: Box<Spec>,
        file: Option<PathBuf>,
    },
    Rigid(RigidBodySpec),
}

/// A flange a joint or an external flange names: the fixed world, or a flange of a body.
#[derive(Debug, Clone, PartialEq, Eq, Hash, serde::Serialize)]
pub enum FlangeRef {
    /// The fixed world; a joint to it sits where its other flange is at t = 0.
    Ground,
    /// Flange `flange` of `bodies[body]`: any flange of a flexible body's input (its motion
    /// flange, the body frame, or a force flange), one of a rigid body's `flanges`.
    Body { body: usize, flange: String },
}

/// A joint between two flanges.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct JointSpec {
    /// Unique among the joints, bodies and external flanges.
    pub name: String,
    pub joint_type: JointType,
    /// Two different flanges, at most one of them the ground, not both on one body. Both must
    /// coincide at t = 0 for every type but prismatic (checked once the flanges are placed).
    pub between: [FlangeRef; 2],
    /// Revolute and prismatic joints (only): the axis, world at t = 0, unit length.
    pub axis: Option<[f64; 3]>,
    /// Universal joints (only): two perpendicular unit vectors, world at t = 0, the first fixed
    /// in the first flange's body, the second in the second's.
    pub axes: Option<[[f64; 3]; 2]>,
    /// Revolute and prismatic joints only.
    pub drive: Option<Drive>,
}

impl JointSpec {
    /// The constraint equations it imposes: its type's, and one more for a driven angle or
    /// position.
    pub fn constraints(&self) -> usize {
        self.joint_type.constraints() + usize::from(self.drive.is_some_and(|d| d.quantity.is_motion()))
    }
}

/// What drives a revolute or prismatic joint.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Drive {
    pub quantity: DriveQuantity,
    pub function: DriveFunction,
}

/// The quantity a drive prescribes. Angles and positions count from the configuration at t = 0
/// (a driven angle of 0 is the initial pose); a torque or force acts on the second flange's body
/// and its reverse on the first's.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum DriveQuantity {
    /// A revolute joint's rotation [rad].
    Angle,
    /// About a revolute joint's axis [N m].
    Torque,
    /// A prismatic joint's translation [m].
    Position,
    /// Along a prismatic joint's axis [N].
    Force,
}

impl DriveQuantity {
    /// Whether it prescribes motion (one more constraint equation), not a load.
    pub fn is_motion(self) -> bool {
        matches!(self, DriveQuantity::Angle | DriveQuantity::Position)
    }

    /// The key the input uses ("angle").
    pub fn word(self) -> &'static str {
        match self {
            DriveQuantity::Angle => "angle",
            DriveQuantity::Torque => "torque",
            DriveQuantity::Position => "position",
            DriveQuantity::Force => "force",
        }
    }
}

/// A drive's value over time t [s]. Units are the quantity's: rad, m, N m or N, rates in rad/s or
/// m/s.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub enum DriveFunction {
    /// An FMU input variable sets it.
    Input,
    /// The value at every time.
    Constant(f64),
    /// A smooth start: the rate `speed (1 - cos(pi t / time)) / 2` until `time` (> 0), then
    /// `speed`; an angle or position is its integral from 0, a torque or force the rate's curve
    /// itself.
    SpinUp { speed: f64, time: f64 },
    /// `offset + amplitude sin(2 pi frequency t + phase_rad)`, frequency [Hz] >= 0.
    Sine { amplitude: f64, frequency: f64, phase_rad: f64, offset: f64 },
}

/// An external flange: a body flange the host connects to.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct ExternalFlangeSpec {
    /// Unique among the external flanges, bodies and joints.
    pub name: String,
    /// `Force`: the host applies force and torque and reads the motion; `Motion`: the host
    /// prescribes the motion and reads the reaction (one such flange at most).
    pub role: Role,
    /// Always a body's flange, never `Ground`; it may carry joints too.
    pub at: FlangeRef,
}

/// Whether `text` is an assembly's input: a JSON object with the key `assembly` at its top
/// level. Anything else (a body's input, or text that is not a JSON object) is not, so that the
/// body's reading reports it.
pub fn is_assembly(text: &str) -> bool {
    fn present<'de, D: serde::Deserializer<'de>>(d: D) -> std::result::Result<bool, D::Error> {
        serde::de::IgnoredAny::deserialize(d).map(|_| true)
    }
    use serde::Deserialize;
    #[derive(Deserialize)]
    struct Probe {
        #[serde(default, deserialize_with = "present")]
        assembly: bool,
    }
    // (serde would take a struct from an array too)
    text.trim_start().starts_with('{') && serde_json::from_str::<Probe>(text).is_ok_and(|p| p.assembly)
}

impl AssemblySpec {
    /// Read and check the assembly in `path`.
    pub fn from_file(path: &Path) -> Result<Self> {
        use crate::{file_read, size::Memory};
        let text = file_read::read_text(path, file_read::FileKind::Input, Memory::of_this_machine().bytes)
            .map_err(|source| InputError::Unreadable { path: path.to_owned(), source })?;
        Self::from_str(path, &text)
    }

    /// Parse and check `text`, read from `path` (named in messages; body files and inline
    /// bodies' files resolve from its folder).
    pub fn from_str(path: &Path, text: &str) -> Result<Self> {
        let value: serde_json::Value = serde_json::from_str(text).map_err(|e| crate::spec::not_json(path, e))?;
        json_keys::check_unique_keys(path, text)?;
        if value.get("assembly").is_none() {
            return Err(InputError::field(
                path,
                "",
                "has no \"assembly\": this is one body's input (or not an input at all), where an assembly's is expected",
            ));
        }
        forms::check_no_body_keys(path, &value)?;
        let inline = bodies::inline_bodies(path, &value)?;
        let by_schema = spec::check_against_schema(path, &value, "");
        // the forms the schema's conditionals refuse, said with their reason before the schema's
        // plainer words
        let file: std::result::Result<json::AssemblyFile, _> = serde_json::from_value(value);
        if let Ok(file) = &file {
            forms::check(path, file)?;
        }
        by_schema?;
        let file = file.map_err(|e| {
            InputError::field(path, "", format!("does not match the assembly input format: {e}")).caused_by(e)
        })?;
        Self::resolve(path, file, inline)
    }

    fn resolve(path: &Path, file: json::AssemblyFile, mut inline: Vec<Option<Spec>>) -> Result<Self> {
        spec::check_experiment(path, file.experiment.as_ref())?;
        let a = file.assembly;
        joints::check_names(path, &a)?;
        let bodies = a
            .bodies
            .iter()
            .enumerate()
            .map(|(i, b)| bodies::resolve(path, i, b, inline.get_mut(i).and_then(Option::take)))
            .collect::<Result<Vec<_>>>()?;
        let joints = a
            .joints
            .iter()
            .enumerate()
            .map(|(k, j)| joints::resolve(path, k, j, &bodies))
            .collect::<Result<Vec<_>>>()?;
        let flanges = a
            .flanges
            .iter()
            .enumerate()
            .map(|(i, f)| joints::external(path, i, f, &bodies))
            .collect::<Result<Vec<_>>>()?;
        topology::check(path, &bodies, &joints, &flanges)?;
        Ok(AssemblySpec {
            name: file.name,
            description: file.description,
            experiment: file.experiment,
            gravity: a.gravity,
            bodies,
            joints,
            flanges,
            solver: a.solver,
            file: path.to_owned(),
        })
    }

    /// The index of the body called `name`.
    pub fn body_index(&self, name: &str) -> Option<usize> {
        self.bodies.iter().position(|b| b.name == name)
    }

    /// Body `i`'s input if it is flexible, with the path its file names resolve from (its own
    /// file, or the assembly's for an inline body).
    pub fn flexible_input(&self, i: usize) -> Option<(&Spec, &Path)> {
        match &self.bodies.get(i)?.kind {
            BodyKind::Flexible { spec, file } => Some((spec, file.as_deref().unwrap_or(&self.file))),
            BodyKind::Rigid(_) => None,
        }
    }

    /// The files the assembly names, resolved as the build resolves them: the body input files
    /// and the files those name (meshes, matrices), as well as those inline bodies name; each
    /// once. What no output may overwrite.
    pub fn input_files(&self) -> Vec<PathBuf> {
        let mut out: Vec<PathBuf> = Vec::new();
        for i in 0..self.bodies.len() {
            let Some((spec, from)) = self.flexible_input(i) else { continue };
            let own = match &self.bodies[i].kind {
                BodyKind::Flexible { file: Some(f), .. } => Some(f.clone()),
                _ => None,
            };
            for f in own.into_iter().chain(spec.input_files(from)) {
                if !out.contains(&f) {
                    out.push(f);
                }
            }
        }
        out
    }
}

impl AssemblyBodySpec {
    /// The names of the body's flanges, as references name them.
    pub fn flange_names(&self) -> Vec<&str> {
        match &self.kind {
            BodyKind::Flexible { spec, .. } => spec.flanges.iter().map(|f| f.name.as_str()).collect(),
            BodyKind::Rigid(r) => r.flanges.iter().map(|f| f.name.as_str()).collect(),
        }
    }

    pub fn is_flexible(&self) -> bool {
        matches!(self.kind, BodyKind::Flexible { .. })
    }
}
