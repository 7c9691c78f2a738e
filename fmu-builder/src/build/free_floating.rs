//! A free-floating body (no motion flange): the FMU integrates the rigid-body motion itself.
//! The body frame sits at the centre of mass with mean axes (elastic shapes M-orthogonal to the
//! rigid-body fields), the basis is free-interface elastic modes plus inertia-relief attachment
//! shapes of the flanges, and the report compares against the full model's free-free modes and
//! inertia-relief flange compliance.

use super::Built;
use super::stress::{self, Recovered, UnitCases, unit_case_names};
use crate::error::{BuildError, Result};
use crate::ffrf::inertia;
use crate::ffrf::invariants;
use crate::input::spec::{Role, Spec};
use crate::linalg::eigen::Deflation;
use crate::linalg::sparse::{Sparse, SpdSolver, mul_new};
use crate::model::assembly::{MassProperties, Uncoupled};
use crate::model::flange::Flange;
use crate::model::part::Part;
use crate::model::rigid_coupling::{self, Assembled};
use crate::model::stress::Recovery;
use crate::output::fmu::guid::guid;
use crate::output::report::report_of;
use crate::profile;
use crate::reduce::accuracy::{enforce, free_free_accuracy};
use crate::reduce::basis::{self, ModeCount};
use crate::reduce::damping::{modal_damping, with_user_damping};
use faer::Side;
use fmu_runtime::reduced::{FlangeShapes, ReducedBody, RotationTerms};
use std::path::Path;

/// Mass properties about the centre of mass, from those about the mesh origin.
fn about_centre_of_mass(p: MassProperties) -> ([f64; 3], MassProperties) {
    let c = p.first_moment.map(|m| m / p.mass);
    let c2 = c[0] * c[0] + c[1] * c[1] + c[2] * c[2];
    let mut inertia = p.inertia;
    for i in 0..3 {
        for j in 0..3 {
            inertia[3 * i + j] -= p.mass * (if i == j { c2 } else { 0.0 } - c[i] * c[j]);
        }
    }
    (c, MassProperties { mass: p.mass, first_moment: [0.0; 3], inertia, volume: p.volume })
}

/// K + s M with s well below the lowest elastic eigenvalue (1e-9 of the largest diagonal ratio):
/// definite for a free body, and a shift that small leaves the elastic spectrum's order intact.
fn shifted(k: &Sparse, m: &Sparse) -> Result<(Sparse, f64)> {
    let n = k.nrows();
    let diag = |a: &Sparse, j: usize| -> f64 {
        a.row_idx_of_col_raw(j).iter().zip(a.val_of_col(j)).filter(|(i, _)| **i == j).map(|(_, v)| *v).sum()
    };
    let ratio = (0..n).map(|j| diag(k, j) / diag(m, j).max(f64::MIN_POSITIVE)).fold(0.0f64, f64::max);
    let s = 1e-9 * ratio;
    let sum = crate::linalg::sparse::add_scaled(k, s, m)?;
    Ok((sum, s))
}

/// The six rigid-body fields about the centre of mass, M-orthonormalised.
fn rigid_deflation(model: &Assembled, nodes: &[[f64; 3]], flanges: &[Flange], origin: [f64; 3]) -> Result<Deflation> {
    let r = invariants::rigid_fields(model, nodes, flanges, origin);
    let mr = mul_new(&model.mass, r.as_ref());
    let gram = r.transpose() * &mr;
    let l = gram
        .llt(Side::Lower)
        .map_err(|e| BuildError::Numerical(format!("the rigid-body mass matrix is singular ({e}): the part has no mass in some direction; check material.rho")))?
        .L()
        .to_owned();
    // Y = R L^-T
    let mut yt = r.transpose().to_owned();
    faer::linalg::triangular_solve::solve_lower_triangular_in_place(l.as_ref(), yt.as_mut(), faer::Par::Seq);
    let vectors = yt.transpose().to_owned();
    let m_vectors = mul_new(&model.mass, vectors.as_ref());
    Ok(Deflation { vectors, m_vectors })
}

pub fn reduce(
    spec: Spec,
    file: &Path,
    part: Part,
    free: Uncoupled,
    flanges: Vec<Flange>,
    modes: ModeCount,
    recovery: Option<Recovery>,
) -> Result<Built> {
    let mesh = &part.mesh;
    let mut model = profile::phase("coupling of the flanges", || {
        rigid_coupling::rigid_coupling(&free, &mesh.nodes, &flanges, [0.0; 3])
    })?;
    drop(free);
    let (origin, props) = about_centre_of_mass(model.mass_properties);
    model.mass_properties = props;
    let (k_shifted, shift) = shifted(&model.stiffness, &model.mass)?;
    // where it fails tells the user where the mesh has its mechanism
    let backend = spec.reduction.backend.backend(file.parent().unwrap_or(Path::new("")));
    let solver = SpdSolver::on(&backend, std::borrow::Cow::Owned(k_shifted), "K + s M of the free body", &|d| {
        model.dofs.describe(d, &flanges, &|n| part.node_label(n))
    })?;
    let rigid = rigid_deflation(&model, &mesh.nodes, &flanges, origin)?;
    let basis = profile::phase("reduction basis", || basis::free_free(&model, &solver, shift, &rigid, modes))?;
    solver.health()?;
    let inv = profile::phase("invariants", || invariants::invariants(&model, &mesh.nodes, &flanges, origin, &basis));
    // mean axes: the elastic shapes carry no momentum
    let scale = props.mass.sqrt() * (1.0 + props.inertia[0].abs().sqrt());
    let drift = inv.c_t.iter().chain(&inv.c_r).fold(0.0f64, |m, v| m.max(v.abs()));
    if drift > 1e-8 * scale {
        return Err(BuildError::Numerical(format!(
            "internal check failed: the elastic basis carries rigid-body momentum ({drift:e})"
        )));
    }
    let phi_mesh = inertia::expand(&model, &mesh.nodes, &flanges, basis.phi.as_ref());
    let rot = profile::phase("rotation invariants", || {
        inertia::rotation_invariants(&model, &mesh.nodes, origin, phi_mesh.as_ref())
    });
    let recovered = match recovery {
        Some(recovery) => {
            // unit flange loads with inertia relief: what deforms a free body
            let unit = basis::flange_unit_loads(&model);
            let statics = basis::inertia_relief_solve(&solver, &model.mass, shift, &rigid, &unit);
            let fields = inertia::expand(&model, &mesh.nodes, &flanges, statics.as_ref());
            let force: Vec<usize> = (0..flanges.len()).filter(|&k| flanges[k].role == Role::Force).collect();
            let unit = UnitCases { fields: fields.as_ref(), names: unit_case_names(&flanges, &force, &[]) };
            stress::recover(file, &part, &flanges, origin, recovery, phi_mesh.as_ref(), &unit)?
        }
        None => Recovered::none(),
    };
    let r = basis.omega.len();
    let mut reduced = ReducedBody {
        guid: String::new(),
        model_name: spec.name.clone(),
        mount: String::new(),
        omega: basis.omega.clone(),
        alpha: spec.damping.alpha,
        beta: spec.damping.beta,
        modal_damping: with_user_damping(modal_damping(&spec, &basis.omega), &model, &basis)?,
        mass: props.mass,
        first_moment: [0.0; 3],
        inertia: props.inertia,
        c_t: vec![0.0; 3 * r],
        c_r: vec![0.0; 3 * r],
        flanges: flanges
            .iter()
            .enumerate()
            .filter(|(_, f)| f.role == Role::Force)
            .map(|(k, f)| FlangeShapes {
                name: f.name.clone(),
                position: [0, 1, 2].map(|a| f.reference[a] - origin[a]),
                shapes: inv.flange_shapes[k].clone(),
            })
            .collect(),
        stress_points: recovered.points,
        rotation: Some(RotationTerms { g: rot.g, o_mat: rot.o_mat, o_vec: rot.o_vec }),
        stiffening: None,
        free_floating: true,
        // set from the plan below, which reads the body's frequencies and damping
        dynamic_cutoff: f64::INFINITY,
    };
    reduced.dynamic_cutoff = crate::reduce::experiment::plan(&spec, &basis, &reduced).cutoff;
    reduced.guid = guid(&reduced);
    let accuracy = profile::phase("accuracy comparison with the full model", || {
        free_free_accuracy(&model, &solver, shift, &rigid, &basis)
    })?;
    enforce(&accuracy)?;
    solver.health()?;
    let backend_report = crate::output::report::backend_of(&solver)?;
    let statics = basis.omega.len() - basis.n_normal;
    let mut report = report_of(
        &spec,
        &part,
        &flanges,
        &model,
        &basis,
        &reduced,
        "free-interface modes + inertia-relief attachment shapes",
        statics,
        accuracy,
    );
    report.stress_points = recovered.report;
    report.backend = backend_report;
    report.pictures = crate::output::mesh_view::pictures(&part, &flanges, phi_mesh.as_ref(), &basis.omega);
    Ok(Built { spec, part, flanges, model, basis, reduced, report, profile: Vec::new() })
}
