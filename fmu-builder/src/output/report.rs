//! The report of a build: what was built (part, mass properties, flanges, method and order) and
//! what the reduction costs in accuracy. Written into the FMU's documentation as JSON.

use crate::error::Result;
use crate::input::spec::{Role, Spec, Weights};
use crate::linalg::sparse::{SpdSolve, SpdSolver};
use crate::model::flange::{Flange, FlangeCoupling};
use crate::model::part::Part;
use crate::model::rigid_coupling::Assembled;
use crate::output::plausibility::{self, SceneReport};
use crate::output::verdict::{self, Verdict};
use crate::reduce::accuracy::Accuracy;
use crate::reduce::basis::Basis;
use crate::reduce::experiment::plan;
use fmu_runtime::reduced::ReducedBody;
use serde::Serialize;

/// modelDescription.xml's DefaultExperiment (start 0).
#[derive(Debug, Clone, Copy, Serialize, PartialEq)]
pub struct ExperimentReport {
    pub stop_time: f64,
    pub step_size: f64,
    pub tolerance: f64,
}

#[derive(Debug, Clone, Serialize)]
pub struct FlangeReport {
    pub name: String,
    pub role: String,
    pub reference_point: [f64; 3],
    pub slave_nodes: usize,
    /// "rigid", or "distributing, uniform weights" / "distributing, area weights".
    pub coupling: String,
}

fn rigid() -> String {
    "rigid".into()
}

/// A stress recovery point and its static stresses under the unit load cases.
#[derive(Debug, Clone, Serialize)]
pub struct StressPointReport {
    /// Variable name stem of its outputs.
    pub name: String,
    /// Which node and why.
    pub description: String,
    /// Node position in the mesh's coordinates [m].
    pub position: [f64; 3],
    pub unit_cases: Vec<UnitCaseStress>,
}

/// Static stress at a recovery point under one unit load case (xx, yy, zz, xy, yz, zx in the
/// body frame, and von Mises) [Pa per unit load].
#[derive(Debug, Clone, Serialize)]
pub struct UnitCaseStress {
    pub case: String,
    pub stress: [f64; 6],
    pub von_mises: f64,
}

/// The back-end of the reduction: in this process, or PETSc across MPI ranks with its rows'
/// distribution, the MUMPS factor's size (all ranks), its phases' times and each rank's peak
/// resident memory (so far: the products and packaging after it add little).
#[derive(Debug, Clone, Default, Serialize)]
pub struct BackendReport {
    pub kind: String,
    #[serde(skip_serializing_if = "is_zero")]
    pub ranks: usize,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub rows_per_rank: Vec<usize>,
    #[serde(skip_serializing_if = "is_zero_f64")]
    pub factor_entries: f64,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub load_seconds: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub partition_seconds: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub factor_seconds: Option<f64>,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub peak_mib_per_rank: Vec<f64>,
}

fn is_zero(n: &usize) -> bool {
    *n == 0
}

fn is_zero_f64(x: &f64) -> bool {
    *x == 0.0
}

impl BackendReport {
    /// What of it goes into the FMU: the kind alone. The rank count, the times, the memory and
    /// the factor's size say where and how the build ran, not what it made (MUMPS's factor
    /// changes with the partition: 4.83e7 to 5.04e7 entries in five 2-rank builds), and FMUs of
    /// one input must not differ by them; `--report` and `--timings` keep them.
    pub fn packaged(&self) -> BackendReport {
        BackendReport { kind: self.kind.clone(), ..Default::default() }
    }
}

/// The report of `solver`'s back-end.
pub fn backend_of(solver: &SpdSolver) -> Result<BackendReport> {
    Ok(match solver.session() {
        None => BackendReport {
            kind: "in_process".into(),
            ranks: 1,
            rows_per_rank: vec![solver.n()],
            factor_entries: solver.factor_entries() as f64,
            ..Default::default()
        },
        Some(session) => {
            let s = &session.started;
            BackendReport {
                kind: "petsc".into(),
                ranks: s.ranks,
                rows_per_rank: s.rows_per_rank.clone(),
                factor_entries: s.factor_entries,
                load_seconds: Some(s.load_seconds),
                partition_seconds: Some(s.partition_seconds),
                factor_seconds: Some(s.factor_seconds),
                peak_mib_per_rank: session.peak_memory()?,
            }
        }
    })
}

#[derive(Debug, Clone, Serialize)]
pub struct Report {
    pub model_name: String,
    /// The builder that wrote the FMU (`fmu-builder <version>`).
    pub tool: String,
    /// The damping the FMU applies, in words (Rayleigh and modal, as the input gives them).
    pub damping: String,
    pub guid: String,
    pub element: String,
    /// What the part was read from (boxes, a mesh file, matrices).
    pub source: String,
    /// For matrix input: |K r| / (|K| |r|) of the six rigid-body motions (tx, ty, tz, rx, ry, rz).
    pub rigid_body_residual: Option<[f64; 6]>,
    pub nodes: usize,
    pub elements: usize,
    /// DoFs after flange coupling (each flange's slave nodes tied to its reference point's six).
    pub dofs_constrained: usize,
    pub mass: f64,
    pub volume: Option<f64>,
    /// Centre of mass in the body frame (origin at the mount's reference point) [m].
    pub center_of_mass: [f64; 3],
    pub inertia_about_origin: [f64; 9],
    pub method: String,
    pub fixed_interface_modes: usize,
    pub constraint_modes: usize,
    pub order: usize,
    /// Modes that are states in Model Exchange (at or below the cutoff); the rest are
    /// quasi-static there.
    pub dynamic_modes: usize,
    /// Quasi-static modes that settle slower than the cutoff through their damping: first-order
    /// states in Model Exchange (q only, its rate from damping without inertia).
    pub relaxing_modes: usize,
    /// The cutoff between dynamic and quasi-static modes [Hz]; None: every mode dynamic.
    pub dynamic_cutoff_hz: Option<f64>,
    /// How the cutoff was chosen.
    pub dynamic_cutoff_rule: String,
    /// The scene's own cutoff [Hz] (its band, the input's, the highest normal mode) before the
    /// limit of what a host resolves; None: every mode.
    pub scene_cutoff_hz: Option<f64>,
    /// The fastest dynamic mode a host resolves at the default experiment's output interval
    /// (and a 1 s run's 1 ms) [Hz].
    pub host_cutoff_hz: f64,
    /// The FMU's DefaultExperiment, and why its step.
    pub default_experiment: ExperimentReport,
    pub default_step_rule: String,
    /// The longest step at which explicit Euler carries the Model Exchange states [s] (0: none,
    /// a dynamic mode is undamped), and the frequency of the mode that limits it [Hz].
    pub explicit_euler_step: f64,
    pub explicit_euler_mode_hz: Option<f64>,
    /// Dynamic modes without any damping: a host's error in them grows with every period.
    pub undamped_dynamic_modes: usize,
    pub flanges: Vec<FlangeReport>,
    /// Stress recovery points (outputs.stress), in the order of the FMU's variables.
    pub stress_points: Vec<StressPointReport>,
    /// Where the reduction's linear algebra ran.
    pub backend: BackendReport,
    /// What the scene lets the FMU model and which inputs it refuses.
    pub scene: SceneReport,
    /// Probable unit slips and implausible results (the build stands).
    pub warnings: Vec<String>,
    /// How many of `warnings`, first, the build said as it read the part (the summary does not
    /// say them again).
    #[serde(skip)]
    pub said_early: usize,
    /// Pictures for the documentation (caption, SVG): not in report.json.
    #[serde(skip)]
    pub pictures: Vec<(String, String)>,
    pub accuracy: Accuracy,
    /// How far the FMU can be trusted: the valid range and the errors within it.
    pub verdict: Verdict,
}

impl Report {
    /// The report as the FMU carries it: without what varies from run to run on the same input
    /// (the back-end's times, memory and factor size).
    pub fn as_packaged(&self) -> Report {
        Report { backend: self.backend.packaged(), ..self.clone() }
    }
}

/// Components below 1e-12 of the vector's size are round-off of a symmetric part's zeros:
/// reported as 0 (not -0.000000 or 6.4e-17).
fn without_round_off(v: [f64; 3]) -> [f64; 3] {
    let size = v.iter().fold(0.0f64, |a, x| a.max(x.abs()));
    v.map(|x| if x.abs() <= 1e-12 * size { 0.0 } else { x })
}

/// The damping the FMU applies (its parameters damping.alpha and damping.beta start at the
/// Rayleigh values; the modal ratios are fixed in the FMU).
fn damping_applied(spec: &Spec) -> String {
    let d = &spec.damping;
    let mut parts = Vec::new();
    if d.alpha != 0.0 || d.beta != 0.0 {
        parts.push(format!(
            "Rayleigh alpha = {:e} 1/s, beta = {:e} s (parameters damping.alpha, damping.beta)",
            d.alpha, d.beta
        ));
    }
    if let Some(z) = d.modal_ratio {
        parts.push(format!("modal damping ratio {z} in every mode"));
    }
    if let Some(bands) = &d.modal_bands {
        let b: Vec<String> = bands.iter().map(|b| format!("{} below {} Hz", b.ratio, b.below)).collect();
        parts.push(format!("modal damping ratios {}", b.join(", ")));
    }
    if spec.geometry.matrices.as_ref().is_some_and(|m| m.damping.is_some()) {
        parts.push("the input's damping matrix, projected on the basis (its diagonal)".to_string());
    }
    if parts.is_empty() { "none (undamped)".to_string() } else { parts.join("; ") }
}

/// The build's report: what was built and what its reduction costs.
#[allow(clippy::too_many_arguments)]
pub fn report_of(
    spec: &Spec,
    part: &Part,
    flanges: &[Flange],
    model: &Assembled,
    basis: &Basis,
    reduced: &ReducedBody,
    method: &str,
    static_shapes: usize,
    accuracy: Accuracy,
) -> Report {
    let props = model.mass_properties;
    let host = plan(spec, basis, reduced);
    let euler = reduced.explicit_euler_limit(reduced.alpha, reduced.beta);
    let mount = flanges.iter().find(|f| f.role == Role::Motion).map(|f| f.name.as_str());
    let mut report = Report {
        model_name: spec.name.clone(),
        tool: format!("fmu-builder {}", env!("CARGO_PKG_VERSION")),
        damping: damping_applied(spec),
        guid: reduced.guid.clone(),
        element: part.element_description(),
        source: part.source.clone(),
        rigid_body_residual: part.rigid_body_residual,
        nodes: part.mesh.n_nodes(),
        elements: part.mesh.n_elements(),
        dofs_constrained: model.dofs.n_dofs,
        mass: props.mass,
        volume: props.volume,
        center_of_mass: without_round_off(props.first_moment.map(|m| m / props.mass)),
        inertia_about_origin: props.inertia,
        method: method.into(),
        fixed_interface_modes: basis.n_normal,
        constraint_modes: static_shapes,
        order: basis.omega.len(),
        dynamic_modes: reduced.n_dynamic(),
        relaxing_modes: reduced.n_relaxing(),
        dynamic_cutoff_hz: reduced
            .dynamic_cutoff
            .is_finite()
            .then(|| reduced.dynamic_cutoff / (2.0 * std::f64::consts::PI)),
        dynamic_cutoff_rule: host.rule.clone(),
        scene_cutoff_hz: host.scene_cutoff.is_finite().then(|| host.scene_cutoff / (2.0 * std::f64::consts::PI)),
        host_cutoff_hz: host.host_cutoff / (2.0 * std::f64::consts::PI),
        default_experiment: ExperimentReport { stop_time: host.stop, step_size: host.step, tolerance: host.tolerance },
        default_step_rule: host.step_rule.clone(),
        explicit_euler_step: euler.0,
        explicit_euler_mode_hz: euler.1.map(|j| reduced.omega[j] / (2.0 * std::f64::consts::PI)),
        undamped_dynamic_modes: reduced.n_undamped_dynamic(reduced.alpha, reduced.beta),
        flanges: flanges
            .iter()
            .map(|f| FlangeReport {
                name: f.name.clone(),
                role: if f.role == Role::Motion { "motion" } else { "force" }.into(),
                reference_point: f.reference,
                slave_nodes: f.slaves.len(),
                coupling: match &f.coupling {
                    FlangeCoupling::Rigid => rigid(),
                    FlangeCoupling::Distributing { .. } => {
                        let area = spec.flanges.iter().any(|s| s.name == f.name && s.weights == Some(Weights::Area));
                        format!("distributing, {} weights", if area { "area" } else { "uniform" })
                    }
                },
            })
            .collect(),
        stress_points: Vec::new(),
        backend: BackendReport::default(),
        scene: plausibility::scene(spec, mount),
        warnings: Vec::new(),
        said_early: 0,
        pictures: Vec::new(),
        verdict: verdict::of(&accuracy, spec.scene.as_ref().and_then(|s| s.tolerance)),
        accuracy,
    };
    let mass = (!part.from_matrices).then_some(props.mass);
    let early = plausibility::early_warnings(part, mass, spec.reduction.max_frequency);
    report.said_early = early.len();
    report.warnings = plausibility::warnings(early, part, report.accuracy.full_hz.first().copied(), mount.is_some());
    report
}
