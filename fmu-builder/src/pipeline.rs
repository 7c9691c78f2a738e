//! The whole job, stage after stage: spec -> mesh -> flanges -> assembly -> reduction ->
//! invariants -> report. Each stage's output is a plain value; this file only wires them;
//! `package` turns the result into the FMU.

use crate::assembly::{self, Assembled};
use crate::error::{BuildError, Result};
use crate::fe::{ElementKind, Elasticity};
use crate::ffrf;
use crate::flange::{self, Flange};
use crate::mesh::{self, BoxRegion, Mesh, MeshError};
use crate::reduce::{self, Basis, ModeCount};
use crate::report::{self, FlangeReport, Report};
use crate::spec::{Element, Role, Spec};
use fmu_runtime::reduced::{FlangeShapes, ReducedBody};
use std::hash::{Hash, Hasher};
use std::path::Path;

pub struct Built {
    pub spec: Spec,
    pub mesh: Mesh,
    pub flanges: Vec<Flange>,
    pub model: Assembled,
    pub basis: Basis,
    pub reduced: ReducedBody,
    pub report: Report,
}

pub fn mesh_of(spec: &Spec, file: &Path) -> Result<Mesh> {
    let kind = match spec.geometry.element {
        Element::Hex20 => ElementKind::Hex20,
        Element::Hex8 => ElementKind::Hex8,
    };
    let boxes: Vec<BoxRegion> = spec
        .geometry
        .boxes
        .iter()
        .map(|b| BoxRegion { min: b.min, max: b.max, divisions: b.elements })
        .collect();
    mesh::mesh_boxes(&boxes, kind).map_err(|e| {
        let field = match &e {
            MeshError::DegenerateBox { box_index, .. } | MeshError::TooLarge { box_index } => {
                format!("geometry.boxes[{box_index}]")
            }
            MeshError::Overlap { second, .. } => format!("geometry.boxes[{second}]"),
            MeshError::NonConforming { node_box, .. } => format!("geometry.boxes[{node_box}]"),
            _ => "geometry.boxes".to_string(),
        };
        BuildError::input(file, field, e.to_string())
    })
}

fn guid_of(bytes: &[u8]) -> String {
    let mut h1 = std::collections::hash_map::DefaultHasher::new();
    bytes.hash(&mut h1);
    let a = h1.finish();
    let mut h2 = std::collections::hash_map::DefaultHasher::new();
    (a, bytes.len(), "fmu-builder").hash(&mut h2);
    let b = h2.finish();
    format!(
        "{{{:08x}-{:04x}-{:04x}-{:04x}-{:012x}}}",
        a >> 32,
        (a >> 16) & 0xffff,
        a & 0xffff,
        b >> 48,
        b & 0xffff_ffff_ffff
    )
}

/// Read, mesh, couple, assemble and reduce: everything but writing the FMU.
pub fn reduce_spec(spec: Spec, file: &Path) -> Result<Built> {
    let mesh = mesh_of(&spec, file)?;
    let flanges = flange::select_flanges(&spec, file, &mesh)?;
    let mount = spec.mount_index();
    let origin = flanges[mount].reference;
    let material = Elasticity { e: spec.material.e, nu: spec.material.nu };
    let model = assembly::assemble(&mesh, &flanges, material, spec.material.rho, origin)?;
    let modes = match (spec.reduction.modes, spec.reduction.max_frequency) {
        (Some(n), _) => ModeCount::Count(n),
        (None, Some(f)) => ModeCount::Below(f),
        (None, None) => ModeCount::Count(0),
    };
    let basis = reduce::craig_bampton(&model, modes)?;
    let inv = ffrf::invariants(&model, &mesh.nodes, &flanges, origin, &basis);
    let props = model.mass_properties;
    for a in 0..3 {
        if (inv.rigid_mass[a] - props.mass).abs() > 1e-9 * props.mass {
            return Err(BuildError::Numerical(format!(
                "internal check failed: rigid translation mass {} differs from the mesh mass {}",
                inv.rigid_mass[a], props.mass
            )));
        }
    }
    let force: Vec<usize> = (0..flanges.len()).filter(|&k| flanges[k].role == Role::Force).collect();
    let mut reduced = ReducedBody {
        guid: String::new(),
        model_name: spec.name.clone(),
        mount: flanges[mount].name.clone(),
        omega: basis.omega.clone(),
        alpha: spec.damping.alpha,
        beta: spec.damping.beta,
        mass: props.mass,
        first_moment: props.first_moment,
        inertia: props.inertia,
        c_t: inv.c_t,
        c_r: inv.c_r,
        flanges: force
            .iter()
            .map(|&k| FlangeShapes {
                name: flanges[k].name.clone(),
                position: [0, 1, 2].map(|a| flanges[k].reference[a] - origin[a]),
                shapes: inv.flange_shapes[k].clone(),
            })
            .collect(),
    };
    reduced.guid = guid_of(&reduced.to_bytes());

    let force_dofs: Vec<(String, usize)> =
        force.iter().map(|&k| (flanges[k].name.clone(), model.dofs.flange_first[k])).collect();
    let accuracy = report::accuracy(&model, &basis, &force_dofs, basis.omega.len())?;
    let report = Report {
        model_name: spec.name.clone(),
        guid: reduced.guid.clone(),
        element: mesh.kind.name().to_string(),
        nodes: mesh.n_nodes(),
        elements: mesh.n_elements(),
        dofs_constrained: model.dofs.n_dofs,
        mass: props.mass,
        volume: props.volume,
        center_of_mass: props.first_moment.map(|m| m / props.mass),
        inertia_about_origin: props.inertia,
        method: "Craig-Bampton".into(),
        fixed_interface_modes: basis.n_normal,
        constraint_modes: 6 * force.len(),
        order: basis.omega.len(),
        flanges: flanges
            .iter()
            .map(|f| FlangeReport {
                name: f.name.clone(),
                role: match f.role {
                    Role::Motion => "motion".into(),
                    Role::Force => "force".into(),
                },
                reference_point: f.reference,
                slave_nodes: f.slaves.len(),
            })
            .collect(),
        accuracy,
    };
    Ok(Built { spec, mesh, flanges, model, basis, reduced, report })
}

