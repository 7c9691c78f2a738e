//! The input file: JSON checked against `schemas/fmu-builder-input.schema.json` (the single
//! source of truth, embedded at compile time), then read into typed structs. Checks the schema
//! cannot express (a flange naming a box that does not exist, two mounts) follow here; checks
//! that need the mesh (a flange selecting no node) live with the mesh and flanges.

use crate::element::ElementKind;
use crate::error::{InputError, Result};
use crate::{json_keys, ranges, schema_errors, variable_names};
pub use fe_linalg::eigen::MAX_MODES;
use petsc_backend::{Backend, PetscBackend, launcher_words};
use serde::Deserialize;
use std::path::Path;

pub const SCHEMA: &str = include_str!("../../schemas/fmu-builder-input.schema.json");

#[derive(Debug, Clone, Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct Spec {
    #[serde(rename = "$schema", default)]
    pub schema: Option<String>,
    pub name: String,
    #[serde(default)]
    pub description: Option<String>,
    pub geometry: Geometry,
    #[serde(default)]
    pub material: Option<MaterialSpec>,
    /// Per-material overrides keyed by the mesh file's material names.
    #[serde(default)]
    pub materials: std::collections::BTreeMap<String, MaterialSpec>,
    #[serde(default)]
    pub damping: Damping,
    pub flanges: Vec<FlangeSpec>,
    #[serde(default)]
    pub scene: Option<Scene>,
    pub reduction: Reduction,
    #[serde(default)]
    pub outputs: Option<Outputs>,
    /// The FMU's DefaultExperiment, where the input names it (else chosen from the body).
    #[serde(default)]
    pub experiment: Option<Experiment>,
}

/// `experiment`: the run the FMU proposes to its hosts (modelDescription.xml's
/// DefaultExperiment); the dynamic cutoff's default follows its step.
#[derive(Debug, Clone, Default, Deserialize, serde::Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Experiment {
    /// [s]
    #[serde(default)]
    pub stop_time: Option<f64>,
    /// The output interval (fmusim, OMSimulator) or communication step [s].
    #[serde(default)]
    pub step_size: Option<f64>,
    /// Relative tolerance for variable-step hosts.
    #[serde(default)]
    pub tolerance: Option<f64>,
}

/// What the FMU reports beside the flanges' motion.
#[derive(Debug, Clone, Deserialize, serde::Serialize, Default)]
#[serde(deny_unknown_fields)]
pub struct Outputs {
    #[serde(default)]
    pub stress: Option<StressOutputs>,
}

/// Where the FMU recovers stresses: nodes of named sets, the nodes nearest to points, and the
/// hot spots the builder finds.
#[derive(Debug, Clone, Deserialize, serde::Serialize, Default)]
#[serde(deny_unknown_fields)]
pub struct StressOutputs {
    #[serde(default)]
    pub node_sets: Vec<String>,
    #[serde(default)]
    pub points: Vec<[f64; 3]>,
    #[serde(default)]
    pub hot_spots: usize,
}

/// Most stress recovery points a build accepts (seven outputs each).
pub const MAX_STRESS_POINTS: usize = 1000;

#[derive(Debug, Clone, Copy, Deserialize, serde::Serialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum SceneLoad {
    Gravity,
    Acceleration,
    Rotation,
}

#[derive(Debug, Clone, Deserialize, serde::Serialize, Default, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    #[serde(default)]
    pub loads: Vec<SceneLoad>,
    #[serde(default)]
    pub geometric_stiffening: bool,
    #[serde(default)]
    pub band: Option<[f64; 2]>,
    #[serde(default)]
    pub tolerance: Option<f64>,
    #[serde(default)]
    pub connected: Option<Vec<String>>,
}

impl Spec {
    /// Whether the FMU keeps the rotating-frame terms: unless a scene says the body never rotates.
    pub fn rotates(&self) -> bool {
        self.scene.as_ref().is_none_or(|s| s.loads.contains(&SceneLoad::Rotation))
    }
    /// Whether the scene declares the load (a missing scene declares none).
    pub fn declares(&self, load: SceneLoad) -> bool {
        self.scene.as_ref().is_some_and(|s| s.loads.contains(&load))
    }
    pub fn stiffening(&self) -> bool {
        self.scene.as_ref().is_some_and(|s| s.geometric_stiffening)
    }
}

#[derive(Debug, Clone, Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct Geometry {
    /// Element kind of the box mesher (the schema allows the hexahedra only; the mesher refuses
    /// the others). Mesh files name their element types themselves.
    #[serde(default)]
    pub element: ElementKind,
    /// Empty unless the part is a union of boxes.
    #[serde(default)]
    pub boxes: Vec<BoxSpec>,
    /// Mesh file (.inp or .msh), relative to the input file.
    #[serde(default)]
    pub mesh: Option<String>,
    #[serde(default)]
    pub matrices: Option<MatrixSpec>,
    /// The unit of every length of the geometry: the mesh file's coordinates, the boxes, the
    /// flange selectors and reference points and the stress points. Material data and
    /// everything else stay SI.
    #[serde(default)]
    pub length_unit: LengthUnit,
}

/// `geometry.length_unit`: CAD and Gmsh meshes come in millimetres as often as in metres; the
/// builder scales the geometry to metres before anything else, so a mesh in mm needs no editing.
#[derive(Debug, Clone, Copy, Default, Deserialize, serde::Serialize, PartialEq, Eq)]
pub enum LengthUnit {
    #[default]
    #[serde(rename = "m")]
    Metre,
    #[serde(rename = "cm")]
    Centimetre,
    #[serde(rename = "mm")]
    Millimetre,
    #[serde(rename = "in")]
    Inch,
    #[serde(rename = "ft")]
    Foot,
}

impl LengthUnit {
    /// Every unit, in the schema's order.
    pub const ALL: [LengthUnit; 5] =
        [LengthUnit::Metre, LengthUnit::Centimetre, LengthUnit::Millimetre, LengthUnit::Inch, LengthUnit::Foot];

    /// One of this unit in metres (the inch and the foot exactly, by their 1959 definition).
    pub fn metres(self) -> f64 {
        match self {
            LengthUnit::Metre => 1.0,
            LengthUnit::Centimetre => 0.01,
            LengthUnit::Millimetre => 0.001,
            LengthUnit::Inch => 0.0254,
            LengthUnit::Foot => 0.3048,
        }
    }

    /// The name the input uses ("mm").
    pub fn symbol(self) -> &'static str {
        match self {
            LengthUnit::Metre => "m",
            LengthUnit::Centimetre => "cm",
            LengthUnit::Millimetre => "mm",
            LengthUnit::Inch => "in",
            LengthUnit::Foot => "ft",
        }
    }
}

#[derive(Debug, Clone, Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct MatrixSpec {
    pub stiffness: String,
    pub mass: String,
    #[serde(default)]
    pub damping: Option<String>,
    pub dofs: String,
    pub nodes: String,
    #[serde(default = "yes")]
    pub free_free: bool,
}

fn yes() -> bool {
    true
}

#[derive(Debug, Clone, Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct BoxSpec {
    pub min: [f64; 3],
    pub max: [f64; 3],
    pub elements: [usize; 3],
}

/// Material properties given in the input: each overrides what a mesh file says.
#[derive(Debug, Clone, Copy, Deserialize, serde::Serialize, Default, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct MaterialSpec {
    #[serde(rename = "E", default)]
    pub e: Option<f64>,
    #[serde(default)]
    pub nu: Option<f64>,
    #[serde(default)]
    pub rho: Option<f64>,
}

#[derive(Debug, Clone, Deserialize, serde::Serialize, Default)]
#[serde(deny_unknown_fields)]
pub struct Damping {
    #[serde(default)]
    pub alpha: f64,
    #[serde(default)]
    pub beta: f64,
    #[serde(default)]
    pub modal_ratio: Option<f64>,
    #[serde(default)]
    pub modal_bands: Option<Vec<DampingBand>>,
}

#[derive(Debug, Clone, Copy, Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct DampingBand {
    pub below: f64,
    pub ratio: f64,
}

impl Damping {
    /// Modal damping ratio of a mode at `hz` (added to the Rayleigh damping).
    pub fn modal_ratio_at(&self, hz: f64) -> f64 {
        if let Some(r) = self.modal_ratio {
            return r;
        }
        self.modal_bands.as_ref().and_then(|bands| bands.iter().find(|b| hz < b.below).map(|b| b.ratio)).unwrap_or(0.0)
    }
}

#[derive(Debug, Clone, Copy, Deserialize, serde::Serialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum Role {
    Motion,
    Force,
}

/// How a flange's reference point is tied to its nodes.
#[derive(Debug, Clone, Copy, Default, Deserialize, serde::Serialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum Coupling {
    /// RBE2: the nodes move rigidly with the reference point (stiffens the part there).
    #[default]
    Rigid,
    /// RBE3: the reference point moves as the weighted average of its nodes; loads are
    /// distributed over them; no stiffness is added.
    Distributing,
}

/// A distributing flange's node weights.
#[derive(Debug, Clone, Copy, Default, Deserialize, serde::Serialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum Weights {
    #[default]
    Uniform,
    /// Each node's share of the surface the flange's nodes cover (the element faces whose
    /// nodes all belong to the flange).
    Area,
}

#[derive(Debug, Clone, Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct FlangeSpec {
    pub name: String,
    pub role: Role,
    pub nodes: NodeSelector,
    #[serde(default)]
    pub reference_point: Option<[f64; 3]>,
    #[serde(default)]
    pub coupling: Coupling,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub weights: Option<Weights>,
}

#[derive(Debug, Clone, Deserialize, serde::Serialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum NodeSelector {
    BoxFace {
        #[serde(rename = "box")]
        box_index: usize,
        face: Face,
    },
    Plane {
        point: [f64; 3],
        normal: [f64; 3],
        #[serde(default)]
        tolerance: Option<f64>,
    },
    NodeSet(String),
    Box {
        min: [f64; 3],
        max: [f64; 3],
    },
    Sphere {
        center: [f64; 3],
        radius: f64,
    },
    Cylinder {
        point: [f64; 3],
        axis: [f64; 3],
        radius: f64,
        #[serde(default)]
        length: Option<f64>,
    },
}

impl NodeSelector {
    /// The selector with its lengths (points, sizes, tolerances) multiplied by `scale`: a
    /// selector is given in the geometry's length unit, and the part is meshed in metres.
    pub fn scaled(&self, scale: f64) -> NodeSelector {
        let p = |v: &[f64; 3]| v.map(|c| c * scale);
        match self {
            NodeSelector::BoxFace { .. } | NodeSelector::NodeSet(_) => self.clone(),
            // a normal and an axis are directions: no unit
            NodeSelector::Plane { point, normal, tolerance } => {
                NodeSelector::Plane { point: p(point), normal: *normal, tolerance: tolerance.map(|t| t * scale) }
            }
            NodeSelector::Box { min, max } => NodeSelector::Box { min: p(min), max: p(max) },
            NodeSelector::Sphere { center, radius } => {
                NodeSelector::Sphere { center: p(center), radius: radius * scale }
            }
            NodeSelector::Cylinder { point, axis, radius, length } => NodeSelector::Cylinder {
                point: p(point),
                axis: *axis,
                radius: radius * scale,
                length: length.map(|l| l * scale),
            },
        }
    }
}

#[derive(Debug, Clone, Copy, Deserialize, serde::Serialize, PartialEq, Eq)]
pub enum Face {
    #[serde(rename = "-x")]
    MinusX,
    #[serde(rename = "+x")]
    PlusX,
    #[serde(rename = "-y")]
    MinusY,
    #[serde(rename = "+y")]
    PlusY,
    #[serde(rename = "-z")]
    MinusZ,
    #[serde(rename = "+z")]
    PlusZ,
}

impl Face {
    /// (axis, upper side?)
    pub fn axis_side(self) -> (usize, bool) {
        match self {
            Face::MinusX => (0, false),
            Face::PlusX => (0, true),
            Face::MinusY => (1, false),
            Face::PlusY => (1, true),
            Face::MinusZ => (2, false),
            Face::PlusZ => (2, true),
        }
    }
}

#[derive(Debug, Clone, Copy, Deserialize, serde::Serialize, PartialEq, Eq, Default)]
#[serde(rename_all = "snake_case")]
pub enum Method {
    #[default]
    CraigBampton,
    Modal,
    Krylov,
}

#[derive(Debug, Clone, Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct Reduction {
    #[serde(default)]
    pub method: Method,
    #[serde(default)]
    pub modes: Option<usize>,
    #[serde(default)]
    pub max_frequency: Option<f64>,
    #[serde(default)]
    pub expansion_points: Option<Vec<f64>>,
    #[serde(default)]
    pub moments: Option<usize>,
    #[serde(default)]
    pub real_expansion_points: Option<Vec<f64>>,
    /// Modes above this frequency [Hz] are quasi-static in Model Exchange.
    #[serde(default)]
    pub dynamic_cutoff: Option<f64>,
    /// Where the linear algebra runs (the command line may override it).
    #[serde(default)]
    pub backend: BackendSpec,
}

#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum BackendKind {
    #[default]
    InProcess,
    Petsc,
}

/// `reduction.backend`: every field optional, so that the command line's can fill or override
/// the input's (`merged`).
#[derive(Debug, Clone, Default, PartialEq, Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct BackendSpec {
    #[serde(default)]
    pub kind: Option<BackendKind>,
    #[serde(default)]
    pub ranks: Option<usize>,
    #[serde(default)]
    pub launcher: Option<String>,
    #[serde(default)]
    pub python: Option<String>,
    #[serde(default)]
    pub host: Option<String>,
    #[serde(default)]
    pub job_folder: Option<std::path::PathBuf>,
    #[serde(default)]
    pub partitioner: Option<String>,
    #[serde(default)]
    pub connect_timeout: Option<f64>,
}

impl BackendSpec {
    /// What of it the FMU's copy of the input keeps: the kind. The ranks, the launcher, the
    /// Python, the host and the folders are the building machine's, not the model's: FMUs of one
    /// input built on two machines or rank counts must not differ by them.
    pub fn packaged(&self) -> BackendSpec {
        BackendSpec { kind: self.kind, ..Default::default() }
    }

    /// The launcher, where one is named, refused when it does not split into words.
    pub fn check_launcher(&self, file: &Path) -> Result<()> {
        match self.launcher.as_deref().map(launcher_words) {
            Some(Err(why)) => Err(InputError::field(
                file,
                "reduction.backend.launcher (or --launcher)",
                format!("\"{}\" {why}", self.launcher.as_deref().unwrap_or_default()),
            )),
            _ => Ok(()),
        }
    }

    /// These fields where `over` leaves them unset, `over`'s where it sets them.
    pub fn merged(&self, over: &BackendSpec) -> BackendSpec {
        BackendSpec {
            kind: over.kind.or(self.kind),
            ranks: over.ranks.or(self.ranks),
            launcher: over.launcher.clone().or_else(|| self.launcher.clone()),
            python: over.python.clone().or_else(|| self.python.clone()),
            host: over.host.clone().or_else(|| self.host.clone()),
            job_folder: over.job_folder.clone().or_else(|| self.job_folder.clone()),
            partitioner: over.partitioner.clone().or_else(|| self.partitioner.clone()),
            connect_timeout: over.connect_timeout.or(self.connect_timeout),
        }
    }

    /// The back-end these fields describe; a relative job folder is taken from `base` (the
    /// input file's folder).
    pub fn backend(&self, base: &Path) -> Backend {
        if self.kind != Some(BackendKind::Petsc) {
            return Backend::InProcess;
        }
        let default = PetscBackend::default();
        Backend::Petsc(PetscBackend {
            ranks: self.ranks.unwrap_or(default.ranks),
            // refused before the build where it does not split (`check_launcher`)
            launcher: self.launcher.as_deref().and_then(|l| launcher_words(l).ok()).unwrap_or(default.launcher),
            python: self.python.clone().unwrap_or(default.python),
            host: self.host.clone().unwrap_or(default.host),
            job_folder: self.job_folder.as_ref().map(|f| base.join(f)),
            partitioner: self.partitioner.clone().unwrap_or(default.partitioner),
            keep_job_folder: default.keep_job_folder,
            connect_timeout_seconds: self.connect_timeout.unwrap_or(default.connect_timeout_seconds),
        })
    }
}

/// Longest over shortest element edge of a box mesh. A solid element's stiffness conditioning
/// grows with the square of its aspect ratio: at 1e4 that is 1e8 on top of the part's own
/// (1e6 to 1e10 for slender parts), which leaves double precision nothing for the residual
/// checks, and the factorisation reports the part as a mechanism.
const MAX_ELEMENT_ASPECT: f64 = 1e4;

/// Coordinates this many box sizes from the origin keep fewer than 16 - 8 digits of the element
/// edges: Jacobians turn negative by round-off alone.
const MAX_OFFSET_IN_SIZES: f64 = 1e8;

fn check_box_proportions(path: &Path, i: usize, b: &BoxSpec, unit: LengthUnit) -> Result<()> {
    let unit = unit.symbol();
    let edge: Vec<f64> = (0..3).map(|a| (b.max[a] - b.min[a]) / b.elements[a].max(1) as f64).collect();
    let (short, long) = edge.iter().fold((f64::INFINITY, 0.0f64), |(s, l), &e| (s.min(e), l.max(e)));
    if long > MAX_ELEMENT_ASPECT * short {
        let suggest: Vec<String> = (0..3)
            .map(|a| format!("{:.0}", ((b.max[a] - b.min[a]) / (MAX_ELEMENT_ASPECT.sqrt() * short)).ceil().max(1.0)))
            .collect();
        return Err(InputError::field(
            path,
            format!("geometry.boxes[{i}].elements"),
            format!(
                "{:?} elements give edges of {:.3e}, {:.3e} and {:.3e} {unit}: an aspect ratio of {:.1e}, above {MAX_ELEMENT_ASPECT:.0e}, \
                 where the stiffness loses the digits the solver needs; choose counts in the box's proportions \
                 (e.g. [{}]) or check the box's min and max",
                b.elements,
                edge[0],
                edge[1],
                edge[2],
                long / short,
                suggest.join(", ")
            ),
        ));
    }
    let size = (0..3).map(|a| b.max[a] - b.min[a]).fold(f64::INFINITY, f64::min);
    let far = b.min.iter().chain(&b.max).fold(0.0f64, |m, c| m.max(c.abs()));
    if far > MAX_OFFSET_IN_SIZES * size {
        return Err(InputError::field(
            path,
            format!("geometry.boxes[{i}]"),
            format!(
                "the box lies {far:.3e} {unit} from the origin, more than {MAX_OFFSET_IN_SIZES:.0e} times its smallest side {size:.3e} {unit}: \
                 its coordinates keep too few digits for the element shapes; move the part near the origin"
            ),
        ));
    }
    Ok(())
}

/// A run a host can start: positive finite times, a step within the run, a tolerance a
/// double-precision integrator can meet.
pub(crate) fn check_experiment(path: &Path, experiment: Option<&Experiment>) -> Result<()> {
    let Some(e) = experiment else { return Ok(()) };
    for (field, v) in [("experiment.stop_time", e.stop_time), ("experiment.step_size", e.step_size)] {
        if let Some(v) = v
            && !(v > 0.0 && v <= 1e9)
        {
            return Err(InputError::field(path, field, format!("{v:e} s must be positive and at most 1e9 s")));
        }
    }
    if let (Some(stop), Some(step)) = (e.stop_time, e.step_size)
        && step > stop
    {
        return Err(InputError::field(
            path,
            "experiment.step_size",
            format!("{step:e} s is longer than experiment.stop_time = {stop:e} s"),
        ));
    }
    if let Some(tol) = e.tolerance
        && !(1e-14..1.0).contains(&tol)
    {
        return Err(InputError::field(
            path,
            "experiment.tolerance",
            format!("{tol:e} must lie in [1e-14, 1): a relative tolerance double precision can meet"),
        ));
    }
    Ok(())
}

/// `value` checked against the input's schema; the problems, every one, as one error whose
/// fields lie below `at` (empty: the whole file).
pub(crate) fn check_against_schema(path: &Path, value: &serde_json::Value, at: &str) -> Result<()> {
    let schema: serde_json::Value =
        serde_json::from_str(SCHEMA).map_err(|e| internal(format!("embedded schema: {e}"), e))?;
    let validator = jsonschema::validator_for(&schema)
        .map_err(|e| internal(format!("embedded schema does not compile: {e}"), e))?;
    let problems = schema_errors::explain(&schema, validator.iter_errors(value));
    if let Some((first, rest)) = problems.split_first() {
        let shown =
            |f: &str| if f.is_empty() && at.is_empty() { "(top level)".to_string() } else { below_field(at, f) };
        let mut message = first.message.clone();
        for p in rest {
            message.push_str(&format!("\n  and {}: {}", shown(&p.field), p.message));
        }
        message.push_str("\n  (the input's schema: fmu-builder --print-schema)");
        return Err(InputError::field(path, shown(&first.field), message));
    }
    Ok(())
}

/// `field` of a value found at `at` (`assembly.bodies[1].flexible` + `material.E`).
pub(crate) fn below_field(at: &str, field: &str) -> String {
    match (at.is_empty(), field.is_empty()) {
        (true, _) => field.to_string(),
        (false, true) => at.to_string(),
        (false, false) => format!("{at}.{field}"),
    }
}

/// `e` with its field put below `at`.
/// Text that does not parse as JSON, put at its line and column.
pub(crate) fn not_json(path: &Path, e: serde_json::Error) -> InputError {
    InputError::field(path, format!("line {} column {}", e.line(), e.column()), format!("not valid JSON: {e}"))
        .caused_by(e)
}

/// A failure of what the builder carries inside itself, with the error it came from.
fn internal(message: String, cause: impl std::error::Error + Send + Sync + 'static) -> InputError {
    InputError::Internal { message, cause: None }.caused_by(cause)
}

pub(crate) fn below(at: &str, e: InputError) -> InputError {
    match e {
        InputError::Field { file, field, message, cause } => {
            InputError::Field { file, field: below_field(at, &field), message, cause }
        }
        other => other,
    }
}

/// Flange names the FMU's own variables use, checked before the schema so the message says why
/// (the schema's `not` would only say the name "is not allowed").
fn check_flange_names(path: &Path, value: &serde_json::Value) -> Result<()> {
    let Some(flanges) = value.get("flanges").and_then(|f| f.as_array()) else {
        return Ok(());
    };
    for (k, f) in flanges.iter().enumerate() {
        if let Some(problem) = f.get("name").and_then(|n| n.as_str()).and_then(variable_names::flange_name_problem) {
            return Err(InputError::field(path, format!("flanges[{k}].name"), problem));
        }
    }
    Ok(())
}

impl Spec {
    pub fn from_file(path: &Path) -> Result<Self> {
        use crate::{file_read, size::Memory};
        let text = file_read::read_text(path, file_read::FileKind::Input, Memory::of_this_machine().bytes)
            .map_err(|source| InputError::Unreadable { path: path.to_owned(), source })?;
        Self::from_str(path, &text)
    }

    /// The files this input names (its mesh or matrices), resolved as the build resolves them:
    /// what no output may overwrite.
    pub fn input_files(&self, input: &Path) -> Vec<std::path::PathBuf> {
        let mut names: Vec<&str> = self.geometry.mesh.iter().map(String::as_str).collect();
        if let Some(m) = &self.geometry.matrices {
            names.extend([m.stiffness.as_str(), m.mass.as_str(), m.dofs.as_str(), m.nodes.as_str()]);
        }
        names.into_iter().map(|n| Self::resolve(input, n)).collect()
    }

    /// Parse `text` (read from `path`, used in messages).
    pub fn from_str(path: &Path, text: &str) -> Result<Self> {
        let value: serde_json::Value = serde_json::from_str(text).map_err(|e| not_json(path, e))?;
        json_keys::check_unique_keys(path, text)?;
        if value.get("assembly").is_some() {
            return Err(InputError::field(
                path,
                "assembly",
                "this file is an assembly's input (bodies and joints), and one body's input (geometry, material, \
                 flanges, reduction) is expected here",
            ));
        }
        Self::from_value(path, value, "")
    }

    /// The body input `value`, found in `path` at the field `at` (empty for the whole file; an
    /// assembly's inline body is `assembly.bodies[1].flexible`): checked against the schema and
    /// read, every message naming its field below `at`.
    pub(crate) fn from_value(path: &Path, value: serde_json::Value, at: &str) -> Result<Self> {
        check_flange_names(path, &value).map_err(|e| below(at, e))?;
        check_against_schema(path, &value, at)?;
        let mut spec: Spec = serde_json::from_value(value).map_err(|e| {
            InputError::field(path, below_field(at, ""), format!("does not match the input format: {e}")).caused_by(e)
        })?;
        spec.check(path).map_err(|e| below(at, e))?;
        spec.keep_connected(path).map_err(|e| below(at, e))?;
        Ok(spec)
    }

    fn check(&self, path: &Path) -> Result<()> {
        self.check_mount(path)?;
        for (i, f) in self.flanges.iter().enumerate() {
            self.check_flange(path, i, f)?;
            self.check_node_selector(path, i, &f.nodes)?;
        }
        self.check_part(path)?;
        self.check_ranges(path)?;
        self.check_requests(path)?;
        self.check_boxes(path)
    }

    /// One "motion" flange, or none for a free-floating body.
    fn check_mount(&self, path: &Path) -> Result<()> {
        let mounts: Vec<usize> =
            self.flanges.iter().enumerate().filter(|(_, f)| f.role == Role::Motion).map(|(i, _)| i).collect();
        match mounts.len() {
            1 => {}
            0 => {
                // free-floating: the FMU integrates the rigid-body motion itself
                if self.stiffening() {
                    return Err(InputError::field(
                        path,
                        "scene.geometric_stiffening",
                        "geometric stiffening is supported for mounted bodies only (this body has no \"motion\" flange)",
                    ));
                }
            }
            _ => {
                return Err(InputError::field(
                    path,
                    format!("flanges[{}].role", mounts[1]),
                    format!(
                        "a second \"motion\" flange; only one mount is supported (flanges[{}] is the mount)",
                        mounts[0]
                    ),
                ));
            }
        }
        Ok(())
    }

    /// Flange `i`'s name is its own, and its weights fit its coupling.
    fn check_flange(&self, path: &Path, i: usize, f: &FlangeSpec) -> Result<()> {
        if let Some(j) = self.flanges[..i].iter().position(|g| g.name == f.name) {
            return Err(InputError::field(
                path,
                format!("flanges[{i}].name"),
                format!("\"{}\" is already the name of flanges[{j}]", f.name),
            ));
        }
        match (f.coupling, f.weights) {
            (Coupling::Rigid, Some(_)) => {
                return Err(InputError::field(
                    path,
                    format!("flanges[{i}].weights"),
                    "weights belong to a distributing coupling; this flange is rigid (add \"coupling\": \"distributing\", \
                     or remove weights)",
                ));
            }
            (Coupling::Distributing, Some(Weights::Area)) if self.geometry.matrices.is_some() => {
                return Err(InputError::field(
                    path,
                    format!("flanges[{i}].weights"),
                    "area weights need the part's element faces, and matrix input has no elements; use \"uniform\" \
                     weights, or give the mesh",
                ));
            }
            _ => {}
        }
        Ok(())
    }

    /// Flange `i`'s node selector names a box that exists and is not degenerate.
    fn check_node_selector(&self, path: &Path, i: usize, nodes: &NodeSelector) -> Result<()> {
        match nodes {
            NodeSelector::BoxFace { box_index, .. } if *box_index >= self.geometry.boxes.len() => {
                return Err(InputError::field(
                    path,
                    format!("flanges[{i}].nodes.box_face.box"),
                    format!(
                        "box {box_index} does not exist: geometry.boxes has {} boxes (indices from 0)",
                        self.geometry.boxes.len()
                    ),
                ));
            }
            NodeSelector::BoxFace { .. } if self.geometry.boxes.is_empty() => {
                return Err(InputError::field(
                    path,
                    format!("flanges[{i}].nodes.box_face"),
                    "box_face selects a face of geometry.boxes, and this part has none; use node_set, plane, box, sphere or cylinder",
                ));
            }
            NodeSelector::Plane { normal, .. } if normal.iter().map(|c| c * c).sum::<f64>() == 0.0 => {
                return Err(InputError::field(
                    path,
                    format!("flanges[{i}].nodes.plane.normal"),
                    "the normal is the zero vector",
                ));
            }
            NodeSelector::Cylinder { axis, .. } if axis.iter().map(|c| c * c).sum::<f64>() == 0.0 => {
                return Err(InputError::field(
                    path,
                    format!("flanges[{i}].nodes.cylinder.axis"),
                    "the axis is the zero vector",
                ));
            }
            NodeSelector::Box { min, max } if (0..3).any(|a| !(max[a] > min[a])) => {
                return Err(InputError::field(
                    path,
                    format!("flanges[{i}].nodes.box"),
                    format!("empty box: every coordinate of max {max:?} must exceed min {min:?}"),
                ));
            }
            _ => {}
        }
        Ok(())
    }

    /// The modes and the band requested are within what a build computes.
    fn check_requests(&self, path: &Path) -> Result<()> {
        if let Some(n) = self.reduction.modes
            && n > MAX_MODES
        {
            return Err(InputError::field(
                path,
                "reduction.modes",
                format!(
                    "{n} modes requested, at most {MAX_MODES} are supported: a reduced body for system simulation needs the \
                     modes of its scene's band (use reduction.max_frequency, or scene.band with scene.tolerance)"
                ),
            ));
        }
        if let Some([lo, hi]) = self.scene.as_ref().and_then(|s| s.band)
            && !(hi > lo)
        {
            return Err(InputError::field(
                path,
                "scene.band",
                format!("the band's upper limit {hi} Hz must exceed its lower limit {lo} Hz"),
            ));
        }
        Ok(())
    }

    /// Every box of the geometry has a volume and proportions a mesh can resolve.
    fn check_boxes(&self, path: &Path) -> Result<()> {
        for (i, b) in self.geometry.boxes.iter().enumerate() {
            for axis in 0..3 {
                if !(b.max[axis] > b.min[axis]) {
                    return Err(InputError::field(
                        path,
                        format!("geometry.boxes[{i}]"),
                        format!(
                            "degenerate box: max[{axis}] = {} must be greater than min[{axis}] = {}",
                            b.max[axis], b.min[axis]
                        ),
                    ));
                }
            }
            check_box_proportions(path, i, b, self.geometry.length_unit)?;
        }
        Ok(())
    }

    /// Materials and damping within the physical ranges of `ranges` (finite but absurd values
    /// build FMUs whose outputs are NaN).
    fn check_ranges(&self, path: &Path) -> Result<()> {
        let named = self.materials.iter().map(|(k, m)| (format!("materials.{k}"), *m));
        for (field, m) in self.material.map(|m| ("material".to_string(), m)).into_iter().chain(named) {
            for (name, v) in [("E", m.e), ("nu", m.nu), ("rho", m.rho)] {
                if let Some(problem) = v.and_then(|v| ranges::material_problem(name, v)) {
                    return Err(InputError::field(path, format!("{field}.{name}"), problem));
                }
            }
        }
        let d = &self.damping;
        let why = "heavier damping than any structure has, and the reduced equations would overflow to NaN";
        let bands = d
            .modal_bands
            .iter()
            .flatten()
            .enumerate()
            .map(|(i, b)| (format!("damping.modal_bands[{i}].ratio"), b.ratio));
        let ratios = d.modal_ratio.map(|r| ("damping.modal_ratio".to_string(), r)).into_iter().chain(bands);
        let checks = [
            ("damping.alpha".to_string(), d.alpha, ranges::ALPHA_MAX, " 1/s"),
            ("damping.beta".to_string(), d.beta, ranges::BETA_MAX, " s"),
        ]
        .into_iter()
        .chain(ratios.map(|(f, r)| (f, r, ranges::RATIO_MAX, " (1 is critical damping)")));
        for (field, v, max, unit) in checks {
            if !ranges::within(v, (0.0, max)) {
                return Err(InputError::field(path, field, format!("{v:e} is outside [0, {max:e}]{unit}: {why}")));
            }
        }
        check_experiment(path, self.experiment.as_ref())
    }

    /// The part's source and its material: boxes need a complete material, matrices none.
    fn check_part(&self, path: &Path) -> Result<()> {
        let g = &self.geometry;
        if g.boxes.is_empty() && g.mesh.is_none() && g.matrices.is_none() {
            return Err(InputError::field(path, "geometry", "give one of boxes, mesh or matrices"));
        }
        if !g.boxes.is_empty() {
            let m = self.material.unwrap_or_default();
            for (value, name) in [(m.e, "E"), (m.nu, "nu"), (m.rho, "rho")] {
                if value.is_none() {
                    return Err(InputError::field(
                        path,
                        if self.material.is_some() { format!("material.{name}") } else { "material".into() },
                        format!("the box mesh needs the material's {name} (E [Pa], nu, rho [kg/m^3])"),
                    ));
                }
            }
            if !self.materials.is_empty() {
                return Err(InputError::field(
                    path,
                    "materials",
                    "named materials apply to mesh files; the box mesh has one material: use material",
                ));
            }
        }
        if g.matrices.is_some() {
            if g.length_unit != LengthUnit::Metre {
                return Err(InputError::field(
                    path,
                    "geometry.length_unit",
                    format!(
                        "\"{}\" cannot apply to matrices: their stiffness, mass and node coordinates must be in SI units \
                         (N/m, kg, m); remove length_unit and export the matrices in SI",
                        g.length_unit.symbol()
                    ),
                ));
            }
            if self.material.is_some() || !self.materials.is_empty() {
                return Err(InputError::field(
                    path,
                    if self.material.is_some() { "material" } else { "materials" },
                    "a part given by its matrices has its material in them; remove the material",
                ));
            }
            if self.stiffening() {
                return Err(InputError::field(
                    path,
                    "scene.geometric_stiffening",
                    "geometric stiffening needs element stresses, so a mesh (geometry.boxes or geometry.mesh), not matrices",
                ));
            }
        }
        Ok(())
    }

    /// A file named in the input, relative to the input file's directory.
    pub fn resolve(input: &Path, name: &str) -> std::path::PathBuf {
        let p = Path::new(name);
        if p.is_absolute() { p.to_path_buf() } else { input.parent().unwrap_or(Path::new(".")).join(p) }
    }

    /// The file `name` of the input's `field`, resolved as `resolve` does, or why it cannot be
    /// read: the field, the path as resolved, and the folder relative paths start from (a path
    /// that is right from the shell's folder but not from the input's is the usual slip).
    pub fn readable_file(input: &Path, field: &str, name: &str) -> Result<std::path::PathBuf> {
        use std::os::unix::fs::OpenOptionsExt;
        let resolved = Self::resolve(input, name);
        use crate::file_read::{self, FileKind};
        let kind = if field == "geometry.mesh" { FileKind::Mesh } else { FileKind::Matrix };
        let problem = match std::fs::metadata(&resolved) {
            Ok(m) if m.is_dir() => "is a folder, not a file".to_string(),
            Ok(_) => match file_read::check(&resolved, kind, crate::size::Memory::of_this_machine().bytes) {
                // opened non-blocking: a FIFO that slipped past the check must not block here
                Ok(_) => match std::fs::OpenOptions::new().read(true).custom_flags(libc::O_NONBLOCK).open(&resolved) {
                    Ok(_) => return Ok(resolved),
                    Err(e) => format!("cannot be read: {e}"),
                },
                Err(refusal) => refusal.reason,
            },
            Err(e) => format!("cannot be read: {e}"),
        };
        let folder = input.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
        // the folder as the user finds it: absolute, where the working directory is known
        let shown = std::path::absolute(folder).unwrap_or_else(|_| folder.to_path_buf());
        let how = if Path::new(name).is_absolute() {
            "the path is absolute".to_string()
        } else if input == Path::new("<stdin>") {
            format!(
                "relative paths resolve from the working directory {} (the input came from standard input)",
                shown.display()
            )
        } else {
            format!("relative paths resolve from the input file's folder {}", shown.display())
        };
        Err(InputError::field(input, field, format!("\"{name}\" ({}) {problem}; {how}", resolved.display())))
    }

    /// Metres per unit of the geometry's lengths.
    pub fn length_scale(&self) -> f64 {
        self.geometry.length_unit.metres()
    }

    /// Drop the force flanges the scene does not connect: the FMU models only what the scene uses.
    fn keep_connected(&mut self, path: &Path) -> Result<()> {
        let Some(connected) = self.scene.as_ref().and_then(|s| s.connected.clone()) else {
            return Ok(());
        };
        for (i, name) in connected.iter().enumerate() {
            match self.flanges.iter().find(|f| &f.name == name) {
                None => {
                    return Err(InputError::field(
                        path,
                        format!("scene.connected[{i}]"),
                        format!(
                            "no flange is named \"{name}\" (flanges: {})",
                            self.flanges.iter().map(|f| f.name.as_str()).collect::<Vec<_>>().join(", ")
                        ),
                    ));
                }
                Some(f) if f.role == Role::Motion => {
                    return Err(InputError::field(
                        path,
                        format!("scene.connected[{i}]"),
                        format!("\"{name}\" is the mount; list force flanges only"),
                    ));
                }
                _ => {}
            }
        }
        self.flanges.retain(|f| f.role == Role::Motion || connected.contains(&f.name));
        Ok(())
    }

    /// The mount flange; None for a free-floating body.
    pub fn mount_index(&self) -> Option<usize> {
        self.flanges.iter().position(|f| f.role == Role::Motion)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const GOOD: &str = r#"{
      "name": "Beam",
      "geometry": { "boxes": [ { "min": [0,0,0], "max": [1,0.01,0.02], "elements": [10,1,1] } ] },
      "material": { "E": 2e11, "nu": 0.3, "rho": 7850 },
      "flanges": [
        { "name": "base", "role": "motion", "nodes": { "box_face": { "box": 0, "face": "-x" } } },
        { "name": "tip", "role": "force", "nodes": { "plane": { "point": [1,0,0], "normal": [1,0,0] } } }
      ],
      "reduction": { "modes": 4 }
    }"#;

    fn err(text: &str) -> String {
        Spec::from_str(Path::new("in.json"), text).unwrap_err().to_string()
    }

    /// The schema refuses the reserved flange names too, so editors flag them while the user types.
    #[test]
    fn the_schema_lists_the_reserved_names() {
        let schema: serde_json::Value = serde_json::from_str(SCHEMA).unwrap();
        let listed = &schema["properties"]["flanges"]["items"]["properties"]["name"]["not"]["enum"];
        let mut got: Vec<&str> = listed.as_array().unwrap().iter().map(|v| v.as_str().unwrap()).collect();
        got.sort_unstable();
        let mut want = variable_names::RESERVED.to_vec();
        want.sort_unstable();
        assert_eq!(got, want);
    }

    #[test]
    fn good_input_parses() {
        let s = Spec::from_str(Path::new("in.json"), GOOD).unwrap();
        assert_eq!(s.geometry.element, ElementKind::Hex20);
        assert_eq!(s.mount_index(), Some(0));
        assert_eq!(s.reduction.modes, Some(4));
    }

    #[test]
    fn the_length_unit_scales_the_selectors_and_not_directions() {
        let mm = GOOD.replace("\"elements\": [10,1,1] } ]", "\"elements\": [10,1,1] } ], \"length_unit\": \"mm\"");
        let s = Spec::from_str(Path::new("in.json"), &mm).unwrap();
        assert_eq!(s.geometry.length_unit, LengthUnit::Millimetre);
        assert_eq!(s.length_scale(), 1e-3);
        let plane = NodeSelector::Plane { point: [1000.0, 0.0, 0.0], normal: [1.0, 0.0, 0.0], tolerance: Some(2.0) };
        let NodeSelector::Plane { point, normal, tolerance } = plane.scaled(1e-3) else { unreachable!() };
        assert_eq!((point, normal, tolerance), ([1.0, 0.0, 0.0], [1.0, 0.0, 0.0], Some(2e-3)));
        // the inch and the foot exactly
        assert_eq!((LengthUnit::Inch.metres(), LengthUnit::Foot.metres()), (0.0254, 0.3048));
        let e = err(&GOOD.replace("\"elements\": [10,1,1] } ]", "\"elements\": [10,1,1] } ], \"length_unit\": \"km\""));
        assert!(e.contains("geometry.length_unit") && e.contains("\"km\"") && e.contains("\"mm\""), "{e}");
        let matrices = r#"{"name": "M", "reduction": {"modes": 1}, "flanges": [],
            "geometry": {"matrices": {"stiffness": "K", "mass": "M", "dofs": "d", "nodes": "n"}, "length_unit": "mm"}}"#;
        let e = err(matrices);
        assert!(e.contains("geometry.length_unit") && e.contains("SI"), "{e}");
    }

    #[test]
    fn an_unreadable_file_names_its_field_path_and_folder() {
        let dir = std::env::temp_dir().join(format!("fmu-builder-readable-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let input = dir.join("in.json");
        let e = Spec::readable_file(&input, "geometry.mesh", "meshes/part.inp").unwrap_err().to_string();
        let folder = std::path::absolute(&dir).unwrap();
        for part in [
            "in.json: geometry.mesh: \"meshes/part.inp\"",
            &dir.join("meshes/part.inp").display().to_string(),
            &format!("relative paths resolve from the input file's folder {}", folder.display()),
        ] {
            assert!(e.contains(part), "{part:?} not in {e}");
        }
        let e = Spec::readable_file(&input, "geometry.matrices.mass", ".").unwrap_err().to_string();
        assert!(e.contains("geometry.matrices.mass") && e.contains("is a folder"), "{e}");
        std::fs::write(dir.join("part.inp"), "").unwrap();
        assert_eq!(Spec::readable_file(&input, "geometry.mesh", "part.inp").unwrap(), dir.join("part.inp"));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn bad_inputs_name_the_field() {
        let e = err("{ \"name\": ");
        assert!(e.contains("in.json") && e.contains("line 1") && e.contains("not valid JSON"), "{e}");
        let e = err(&GOOD.replace("\"rho\": 7850", "\"rho\": 7850, \"colour\": 1"));
        assert!(e.contains("material") && e.contains("colour"), "{e}");
        let e = err(&GOOD.replace("\"E\": 2e11", "\"E\": 0"));
        assert!(e.contains("material.E"), "{e}");
        let e = err(&GOOD.replace("\"nu\": 0.3", "\"nu\": 0.5"));
        assert!(e.contains("material.nu"), "{e}");
        let e = err(&GOOD.replace("\"nu\": 0.3", "\"nu\": -1.2"));
        assert!(e.contains("material.nu"), "{e}");
        let e = err(&GOOD.replace("\"max\": [1,0.01,0.02]", "\"max\": [1,0.0,0.02]"));
        assert!(e.contains("geometry.boxes[0]") && e.contains("degenerate"), "{e}");
        let e = err(&GOOD.replace("\"box\": 0", "\"box\": 3"));
        assert!(e.contains("flanges[0].nodes.box_face.box"), "{e}");
        let e = err(&GOOD.replace("\"name\": \"tip\"", "\"name\": \"base\""));
        assert!(e.contains("flanges[1].name"), "{e}");
        let e = err(&GOOD.replace("\"role\": \"force\"", "\"role\": \"motion\""));
        assert!(e.contains("flanges[1].role"), "{e}");
        let e = err(&GOOD.replace("\"modes\": 4", "\"modes\": 4, \"max_frequency\": 10"));
        assert!(e.contains("reduction"), "{e}");
        let e = err(&GOOD.replace("\"face\": \"-x\"", "\"face\": \"left\""));
        assert!(e.contains("flanges[0].nodes"), "{e}");
    }
}
