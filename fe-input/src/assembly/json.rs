//! An assembly's input as written: the serde types of the file's fields, before their names are
//! resolved to bodies and flanges. Each takes exactly the keys the schema's assembly form
//! declares (`deny_unknown_fields`), and writes back only those.

use crate::spec::{Experiment, Role};
use serde::{Deserialize, Serialize};

/// A whole assembly file.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct AssemblyFile {
    #[serde(rename = "$schema", default, skip_serializing_if = "Option::is_none")]
    pub schema: Option<String>,
    pub name: String,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub description: Option<String>,
    pub assembly: AssemblyJson,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub experiment: Option<Experiment>,
}

/// `assembly`.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct AssemblyJson {
    #[serde(default = "standard_gravity")]
    pub gravity: [f64; 3],
    pub bodies: Vec<BodyJson>,
    #[serde(default)]
    pub joints: Vec<JointJson>,
    #[serde(default)]
    pub flanges: Vec<ExternalFlangeJson>,
    #[serde(default)]
    pub solver: SolverSpec,
}

/// [m/s^2], world: the default `gravity`.
pub const STANDARD_GRAVITY: [f64; 3] = [0.0, 0.0, -9.81];

fn standard_gravity() -> [f64; 3] {
    STANDARD_GRAVITY
}

/// `assembly.bodies[i]`.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct BodyJson {
    pub name: String,
    /// A path (a JSON string) or an inline body input (an object), read by the body's own code.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub flexible: Option<serde_json::Value>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rigid: Option<RigidBodySpec>,
    #[serde(default)]
    pub position: [f64; 3],
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rotation: Option<RotationJson>,
}

/// `rotation`: `angle` degrees about `axis`.
#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RotationJson {
    pub axis: [f64; 3],
    /// [deg]
    pub angle: f64,
}

/// A rigid body: its mass properties and flanges, all in its body frame.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RigidBodySpec {
    /// [kg], positive.
    pub mass: f64,
    /// [m], body frame.
    #[serde(default)]
    pub centre_of_mass: [f64; 3],
    /// [Ixx, Iyy, Izz, Ixy, Iyz, Izx] [kg m^2] about the centre of mass in body axes: positive
    /// definite, its principal moments satisfying the triangle inequalities.
    pub inertia: [f64; 6],
    /// At least one, each name its own.
    pub flanges: Vec<RigidFlangeSpec>,
}

/// A rigid body's flange: a point fixed in the body, with the body's axes.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RigidFlangeSpec {
    pub name: String,
    /// [m], body frame.
    #[serde(default)]
    pub position: [f64; 3],
}

/// `type` of a joint: what relative motion of its two flanges it leaves free.
#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq, Eq, Hash)]
#[serde(rename_all = "lowercase")]
pub enum JointType {
    /// No relative motion.
    Weld,
    /// Rotation about `axis`.
    Revolute,
    /// Translation along `axis`.
    Prismatic,
    /// Any rotation about the common point.
    Spherical,
    /// Rotation about two perpendicular `axes`.
    Universal,
}

impl JointType {
    /// Every type, in the schema's order.
    pub const ALL: [JointType; 5] =
        [JointType::Weld, JointType::Revolute, JointType::Prismatic, JointType::Spherical, JointType::Universal];

    /// The constraint equations the joint imposes (six less its free motions), a drive aside.
    pub fn constraints(self) -> usize {
        match self {
            JointType::Weld => 6,
            JointType::Revolute | JointType::Prismatic => 5,
            JointType::Spherical => 3,
            JointType::Universal => 4,
        }
    }

    /// The name the input uses ("revolute").
    pub fn word(self) -> &'static str {
        match self {
            JointType::Weld => "weld",
            JointType::Revolute => "revolute",
            JointType::Prismatic => "prismatic",
            JointType::Spherical => "spherical",
            JointType::Universal => "universal",
        }
    }

    /// Whether the joint has one `axis` (revolute, prismatic), which a drive may act along.
    pub fn has_axis(self) -> bool {
        matches!(self, JointType::Revolute | JointType::Prismatic)
    }
}

/// `assembly.joints[k]`.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct JointJson {
    pub name: String,
    #[serde(rename = "type")]
    pub joint_type: JointType,
    pub between: [String; 2],
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub axis: Option<[f64; 3]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub axes: Option<[[f64; 3]; 2]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub drive: Option<DriveJson>,
}

/// `drive`: exactly one of its keys (the schema and the checks see to it).
#[derive(Debug, Clone, Default, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct DriveJson {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub angle: Option<DriveFunctionJson>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub torque: Option<DriveFunctionJson>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub position: Option<DriveFunctionJson>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub force: Option<DriveFunctionJson>,
}

/// A drive's function as written: `"input"`, `{"constant": v}`, `{"spin_up": {...}}` or
/// `{"sine": {...}}` (phase in degrees).
#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum DriveFunctionJson {
    Input,
    Constant(f64),
    SpinUp {
        speed: f64,
        time: f64,
    },
    Sine {
        amplitude: f64,
        frequency: f64,
        /// [deg]
        #[serde(default)]
        phase: f64,
        #[serde(default)]
        offset: f64,
    },
}

/// `assembly.flanges[i]`.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ExternalFlangeJson {
    pub name: String,
    pub role: Role,
    pub at: String,
}

/// `assembly.solver`: the assembly's time integration.
#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SolverSpec {
    /// Numerical damping at high frequencies, the spectral radius at infinite frequency, in
    /// [0, 1]: 1 damps nothing, 0 the most.
    #[serde(default = "SolverSpec::default_spectral_radius")]
    pub spectral_radius: f64,
    /// Convergence tolerance of the iteration that meets the joints' constraints in a step, > 0.
    #[serde(default = "SolverSpec::default_tolerance")]
    pub tolerance: f64,
    /// Most iterations per step, in [2, 100].
    #[serde(default = "SolverSpec::default_max_iterations")]
    pub max_iterations: usize,
    /// The longest step the solver takes [s], > 0; a longer communication step is split
    /// (default: the experiment's step_size, at most 1 ms).
    #[serde(default)]
    pub max_step: Option<f64>,
}

impl SolverSpec {
    fn default_spectral_radius() -> f64 {
        1.0
    }
    fn default_tolerance() -> f64 {
        1e-10
    }
    fn default_max_iterations() -> usize {
        12
    }
}

impl Default for SolverSpec {
    fn default() -> Self {
        SolverSpec {
            spectral_radius: Self::default_spectral_radius(),
            tolerance: Self::default_tolerance(),
            max_iterations: Self::default_max_iterations(),
            max_step: None,
        }
    }
}
