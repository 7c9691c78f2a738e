//! An assembly's build: every flexible body reduced once (bodies built from the same input share
//! one reduction), rigid bodies taken as given, the joints placed and checked by the runtime's
//! own equations (flanges that do not meet, joints that constrain the same motion twice, a first
//! step that does not converge), and one FMU written whose runtime solves all of it.

use super::reduce_spec;
use crate::error::{BuildError, InputError, Result};
use crate::input::assembly::{
    AssemblySpec, BodyKind, DriveFunction as InputFunction, DriveQuantity as InputQuantity, FlangeRef, JointType,
};
use crate::input::spec::Role;
use crate::output::binaries::PlatformBinary;
use crate::output::package;
use crate::output::report::Report;
use fmu_runtime::assembly::AssemblyError;
use fmu_runtime::assembly::description::{
    AssemblyDescription, BodyDescription, BodyModel, Drive, DriveFunction, DriveQuantity, ExternalFlange, FlangeRole,
    JointDescription, Side, SolverSettings,
};
use fmu_runtime::assembly::joint::JointKind;
use fmu_runtime::fmu::assembly::AssemblyFmu;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// What an assembly's build produced.
pub struct BuiltAssembly {
    pub spec: AssemblySpec,
    pub description: AssemblyDescription,
    /// Each flexible body's reduction report, by body name (bodies sharing a reduction repeat it).
    pub reports: Vec<(String, Report)>,
    /// The stop time and communication step of the FMU's DefaultExperiment.
    pub experiment: (f64, f64),
}

/// Reduce the bodies, check the assembly and write its FMU.
pub fn build_assembly(spec: AssemblySpec, output: &Path, binaries: &[PlatformBinary]) -> Result<BuiltAssembly> {
    let file = spec.file.clone();
    let (description, reports) = describe(&spec)?;
    let fmu = phases::phase("assembly: joints placed and checked", || check(&description, &file))?;
    let stop = spec.experiment.as_ref().and_then(|e| e.stop_time).unwrap_or(10.0);
    let step = spec.experiment.as_ref().and_then(|e| e.step_size).unwrap_or(description.solver.max_step);
    phases::phase("checks and packaging", || {
        package::write_assembly_fmu(&spec, &description, fmu.table(), &reports, (stop, step), output, binaries)
    })?;
    Ok(BuiltAssembly { spec, description, reports, experiment: (stop, step) })
}

fn field(file: &Path, field: String, message: impl Into<String>) -> BuildError {
    BuildError::Input(InputError::field(file, field, message))
}

/// The runtime's description of the assembly, with every flexible body reduced.
fn describe(spec: &AssemblySpec) -> Result<(AssemblyDescription, Vec<(String, Report)>)> {
    let file = &spec.file;
    let mut reduced_by_input: HashMap<String, (fmu_runtime::reduced::ReducedBody, Report)> = HashMap::new();
    let mut bodies = Vec::new();
    let mut reports = Vec::new();
    for (i, b) in spec.bodies.iter().enumerate() {
        let model = match &b.kind {
            BodyKind::Flexible { spec: body, file: body_file } => {
                // the same input (file and content) is reduced once
                let key = format!(
                    "{}\n{}",
                    body_file.as_deref().unwrap_or(file).display(),
                    serde_json::to_string(body).unwrap_or_default()
                );
                if !reduced_by_input.contains_key(&key) {
                    let source: PathBuf = body_file.clone().unwrap_or_else(|| file.clone());
                    let built = phases::phase(format!("body '{}': reduction", b.name), || {
                        reduce_spec((**body).clone(), &source)
                    })?;
                    reduced_by_input.insert(key.clone(), (built.reduced, built.report));
                }
                let (reduced, report) = &reduced_by_input[&key];
                reports.push((b.name.clone(), report.clone()));
                if reduced.rotation.is_none() {
                    return Err(field(
                        file,
                        format!("assembly.bodies[{i}].flexible"),
                        "the body's input declares a scene without rotation (scene.loads without \"rotation\"): a body \
                         of an assembly turns with its joints, so its input must keep the rotating-frame terms",
                    ));
                }
                BodyModel::Flexible(Box::new(reduced.clone()))
            }
            BodyKind::Rigid(r) => {
                let [xx, yy, zz, xy, yz, zx] = r.inertia;
                BodyModel::Rigid {
                    mass: r.mass,
                    centre: r.centre_of_mass,
                    inertia_at_centre: [xx, xy, zx, xy, yy, yz, zx, yz, zz],
                    flanges: r.flanges.iter().map(|f| (f.name.clone(), f.position)).collect(),
                }
            }
        };
        bodies.push(BodyDescription { name: b.name.clone(), position: b.position, rotation: b.rotation, model });
    }
    let mut description = AssemblyDescription {
        guid: String::new(),
        model_name: spec.name.clone(),
        gravity: spec.gravity,
        bodies,
        joints: Vec::new(),
        flanges: Vec::new(),
        solver: SolverSettings {
            spectral_radius: spec.solver.spectral_radius,
            tolerance: spec.solver.tolerance,
            max_iterations: spec.solver.max_iterations,
            max_step: spec
                .solver
                .max_step
                .unwrap_or_else(|| spec.experiment.as_ref().and_then(|e| e.step_size).unwrap_or(1e-3).min(1e-3)),
        },
    };
    add_joints(spec, &mut description)?;
    description.seal();
    Ok((description, reports))
}

/// The joints and external flanges of `spec`, the bodies of `description` placed.
fn add_joints(spec: &AssemblySpec, description: &mut AssemblyDescription) -> Result<()> {
    let file = &spec.file;
    for (k, j) in spec.joints.iter().enumerate() {
        let side = |s: usize| side_of(description, file, &j.between[s], &format!("assembly.joints[{k}].between[{s}]"));
        let (first, second) = (side(0)?, side(1)?);
        let kind = match j.joint_type {
            JointType::Weld => JointKind::Weld,
            JointType::Revolute => JointKind::Revolute,
            JointType::Prismatic => JointKind::Prismatic,
            JointType::Spherical => JointKind::Spherical,
            JointType::Universal => JointKind::Universal,
        };
        let axes = match (j.axis, j.axes) {
            (Some(a), _) => [a, [0.0; 3]],
            (None, Some(a)) => a,
            (None, None) => [[0.0; 3]; 2],
        };
        let drive = j.drive.map(|d| Drive {
            quantity: match d.quantity {
                InputQuantity::Angle | InputQuantity::Position => DriveQuantity::Motion,
                InputQuantity::Torque | InputQuantity::Force => DriveQuantity::Load,
            },
            function: match d.function {
                InputFunction::Input => DriveFunction::Input,
                InputFunction::Constant(v) => DriveFunction::Constant(v),
                InputFunction::SpinUp { speed, time } => DriveFunction::SpinUp { speed, time },
                InputFunction::Sine { amplitude, frequency, phase_rad: phase, offset } => {
                    DriveFunction::Sine { amplitude, frequency, phase, offset }
                }
            },
        });
        description.joints.push(JointDescription { name: j.name.clone(), kind, first, second, axes, drive });
    }
    for (k, f) in spec.flanges.iter().enumerate() {
        let Side::Body { body, marker } = side_of(description, file, &f.at, &format!("assembly.flanges[{k}].at"))?
        else {
            return Err(field(
                file,
                format!("assembly.flanges[{k}].at"),
                "an external flange is on a body, not the ground",
            ));
        };
        let role = if f.role == Role::Motion { FlangeRole::Motion } else { FlangeRole::Force };
        description.flanges.push(ExternalFlange { name: f.name.clone(), role, body, marker });
    }
    Ok(())
}

fn side_of(d: &AssemblyDescription, file: &Path, r: &FlangeRef, at: &str) -> Result<Side> {
    match r {
        FlangeRef::Ground => Ok(Side::Ground),
        FlangeRef::Body { body, flange } => {
            let names = d.bodies[*body].flange_names();
            let marker = names.iter().position(|n| n == flange).ok_or_else(|| {
                field(
                    file,
                    at.to_string(),
                    format!(
                        "body '{}' has no flange '{flange}' in its FMU (its flanges: {}); a force flange its scene \
                         does not connect (scene.connected) is left out",
                        d.bodies[*body].name,
                        names.join(", ")
                    ),
                )
            })?;
            Ok(Side::Body { body: *body, marker })
        }
    }
}

/// The runtime's own start and a few steps: joints that do not meet or constrain the same
/// motion twice, and mechanisms that lock, are refused here rather than in a host.
fn check(d: &AssemblyDescription, file: &Path) -> Result<AssemblyFmu> {
    let place = |e: &AssemblyError| match e {
        AssemblyError::Joint { joint, .. } | AssemblyError::Misassembled { joint, .. } => {
            format!("assembly.joints ('{joint}')")
        }
        AssemblyError::Redundant { .. } => "assembly.joints".to_string(),
        AssemblyError::Body { body, .. } => format!("assembly.bodies ('{body}')"),
        _ => "assembly".to_string(),
    };
    let fmu = AssemblyFmu::new(d).map_err(|e| field(file, place(&e), e.to_string()).caused_by(e))?;
    let mut trial = fmu.assembly().clone();
    trial.start_run(0.0).map_err(|e| field(file, place(&e), format!("at the start: {e}")).caused_by(e))?;
    for _ in 0..10 {
        trial
            .do_step(d.solver.max_step)
            .map_err(|e| field(file, place(&e), format!("in the first steps: {e}")).caused_by(e))?;
    }
    if trial.motion.pos.iter().chain(&trial.motion.vel).any(|x| !x.is_finite()) {
        return Err(BuildError::not_finite(format!("{}: the assembly's first steps are not finite", file.display())));
    }
    Ok(fmu)
}
