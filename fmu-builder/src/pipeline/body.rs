//! The reduction of a body whose flanges are coupled, phase after phase. How the body is held
//! (`Support`: at a mount flange, or free-floating) decides what is factored, which basis it
//! gets, how its invariants are checked and what its accuracy is measured against; the phases
//! between are the same for every body, and written once here.

use super::built::Built;
use super::prepare::Prepared;
use super::stress::{self, Recovered, UnitCases};
use crate::error::{BuildError, Result};
use crate::ffrf::inertia;
use crate::ffrf::invariants::{self, Invariants};
use crate::input::spec::{Role, Spec};
use crate::linalg::sparse::SpdSolver;
use crate::model::flange::Flange;
use crate::model::part::Part;
use crate::model::rigid_coupling::Assembled;
use crate::model::stress::Recovery;
use crate::output::fmu::guid::guid;
use crate::output::report::{Report, backend_of, report_of};
use crate::reduce::accuracy::Accuracy;
use crate::reduce::basis::{Basis, ModeCount};
use crate::reduce::damping::{modal_damping, with_user_damping};
use faer::{Mat, MatRef};
use fmu_runtime::reduced::{FlangeShapes, ReducedBody, RotationTerms, Stiffening};
use std::path::PathBuf;

/// A body whose flanges are tied to their six-DoF masters: what every later phase reads.
pub(super) struct Coupled {
    pub spec: Spec,
    pub file: PathBuf,
    pub part: Part,
    pub flanges: Vec<Flange>,
    pub model: Assembled,
    /// The body frame's origin in mesh coordinates: the mount's reference point, or the centre
    /// of mass of a free-floating body (whose mass properties are then about it).
    pub origin: [f64; 3],
    /// The mount flange; None for a free-floating body.
    pub mount: Option<usize>,
    pub modes: ModeCount,
}

impl Coupled {
    /// The force flanges, by their index among all flanges.
    pub fn force_flanges(&self) -> Vec<usize> {
        (0..self.flanges.len()).filter(|&k| self.flanges[k].role == Role::Force).collect()
    }

    /// Shapes on the coupled DoFs as fields on the mesh's nodes (3N x columns).
    pub fn on_mesh(&self, x: MatRef<'_, f64>) -> Mat<f64> {
        inertia::expand(&self.model, &self.part.mesh.nodes, &self.flanges, x)
    }
}

/// The accuracy figures of a reduction, and the rule that chose the band its transfer functions
/// were compared over (None where none were compared).
pub(super) struct Measured {
    pub accuracy: Accuracy,
    pub band_rule: Option<String>,
}

/// How a body is held, as a strategy of the one pipeline in `reduce`.
pub(super) trait Support: Sized {
    /// Tie the flanges to their masters.
    fn couple(prepared: Prepared) -> Result<Coupled>;
    /// Factor the matrix every solve of the build uses, and compute what the strategy keeps
    /// between phases.
    fn factor(body: &Coupled) -> Result<(SpdSolver<'_>, Self)>;
    /// The reduction basis and the name of its method.
    fn basis(&mut self, body: &Coupled, solver: &SpdSolver) -> Result<(Basis, String)>;
    /// An internal consistency check of the invariants against the FE model.
    fn check_invariants(&self, body: &Coupled, inv: &Invariants) -> Result<()>;
    /// The geometric stiffening terms, where the scene asks for them.
    fn stiffening(&self, body: &Coupled, solver: &SpdSolver, phi_mesh: MatRef<'_, f64>) -> Result<Option<Stiffening>>;
    /// The static fields (on the mesh) of the unit load cases that deform the body, and their
    /// names: the hot-spot search and the stress report read them.
    fn unit_cases(&self, body: &Coupled, solver: &SpdSolver) -> (Mat<f64>, Vec<String>);
    /// The reduced body measured against the full model.
    fn measure(self, run: &Run<'_>, recovered: &Recovered) -> Result<Measured>;
}

/// What the last phases read: the coupled body, its solver, basis and reduced body.
pub(super) struct Run<'a> {
    pub body: &'a Coupled,
    pub solver: &'a SpdSolver<'a>,
    pub basis: &'a Basis,
    pub reduced: &'a ReducedBody,
}

/// Couple, factor, reduce, measure and report, for a body held as `S` holds it.
pub(super) fn reduce<S: Support>(mut prepared: Prepared) -> Result<Built> {
    let recovery = prepared.recovery.take();
    let body = S::couple(prepared)?;
    let (basis, reduced, report) = {
        let (solver, support) = S::factor(&body)?;
        reduce_coupled(&body, &solver, support, recovery)?
    };
    let Coupled { spec, part, flanges, model, .. } = body;
    Ok(Built { spec, part, flanges, model, basis, reduced, report })
}

fn reduce_coupled<S: Support>(
    body: &Coupled,
    solver: &SpdSolver,
    mut support: S,
    recovery: Option<Recovery>,
) -> Result<(Basis, ReducedBody, Report)> {
    let (basis, method) = support.basis(body, solver)?;
    solver.health()?;
    let inv = phases::phase("invariants", || {
        invariants::invariants(&body.model, &body.part.mesh.nodes, &body.flanges, body.origin, &basis)
    });
    support.check_invariants(body, &inv)?;
    let phi_mesh = body.on_mesh(basis.phi.as_ref());
    let rotation = rotation_terms(body, phi_mesh.as_ref());
    let stiffening = support.stiffening(body, solver, phi_mesh.as_ref())?;
    let recovered = match recovery {
        Some(recovery) => {
            let (fields, names) = support.unit_cases(body, solver);
            let unit = UnitCases { fields: fields.as_ref(), names };
            let (file, part, flanges) = (&body.file, &body.part, &body.flanges);
            stress::recover(file, part, flanges, body.origin, recovery, phi_mesh.as_ref(), &unit)?
        }
        None => Recovered::none(),
    };
    let reduced = reduced_body(body, &basis, &inv, rotation, stiffening, &recovered)?;
    let run = Run { body, solver, basis: &basis, reduced: &reduced };
    let measured = support.measure(&run, &recovered)?;
    solver.health()?;
    let report = report(&run, &method, measured, recovered, phi_mesh.as_ref())?;
    Ok((basis, reduced, report))
}

/// The rotating-frame invariants, for a body whose frame may rotate: every free-floating body,
/// and a mounted one whose scene declares rotation.
fn rotation_terms(body: &Coupled, phi_mesh: MatRef<'_, f64>) -> Option<RotationTerms> {
    if body.mount.is_some() && !body.spec.rotates() {
        return None;
    }
    Some(phases::phase("rotation invariants", || {
        let r = inertia::rotation_invariants(&body.model, &body.part.mesh.nodes, body.origin, phi_mesh);
        RotationTerms { g: r.g, o_mat: r.o_mat, o_vec: r.o_vec }
    }))
}

/// The reduced body the FMU carries. A free-floating body's frame has mean axes: its elastic
/// shapes carry no momentum, so their inertia coupling terms are zero by construction.
fn reduced_body(
    body: &Coupled,
    basis: &Basis,
    inv: &Invariants,
    rotation: Option<RotationTerms>,
    stiffening: Option<Stiffening>,
    recovered: &Recovered,
) -> Result<ReducedBody> {
    let (spec, flanges, props) = (&body.spec, &body.flanges, body.model.mass_properties);
    let r = basis.omega.len();
    let free_floating = body.mount.is_none();
    let (c_t, c_r) =
        if free_floating { (vec![0.0; 3 * r], vec![0.0; 3 * r]) } else { (inv.c_t.clone(), inv.c_r.clone()) };
    let mut reduced = ReducedBody {
        guid: String::new(),
        model_name: spec.name.clone(),
        mount: body.mount.map_or(String::new(), |m| flanges[m].name.clone()),
        omega: basis.omega.clone(),
        alpha: spec.damping.alpha,
        beta: spec.damping.beta,
        modal_damping: with_user_damping(modal_damping(spec, &basis.omega), &body.model, basis)?,
        mass: props.mass,
        first_moment: props.first_moment,
        inertia: props.inertia,
        c_t,
        c_r,
        flanges: flange_shapes(body, inv),
        stress_points: recovered.points.clone(),
        rotation,
        stiffening,
        free_floating,
        // set from the plan below, which reads the body's frequencies and damping
        dynamic_cutoff: f64::INFINITY,
    };
    reduced.dynamic_cutoff = crate::reduce::experiment::plan(spec, basis, &reduced).cutoff;
    reduced.guid = guid(&reduced);
    Ok(reduced)
}

/// The force flanges' positions in the body frame and their shapes.
fn flange_shapes(body: &Coupled, inv: &Invariants) -> Vec<FlangeShapes> {
    let flanges = &body.flanges;
    body.force_flanges()
        .into_iter()
        .map(|k| FlangeShapes {
            name: flanges[k].name.clone(),
            position: [0, 1, 2].map(|a| flanges[k].reference[a] - body.origin[a]),
            shapes: inv.flange_shapes[k].clone(),
        })
        .collect()
}

/// The report of the build: the model, the basis, the accuracy figures, the stress points,
/// the back-end and the pictures of the shapes.
fn report(
    run: &Run<'_>,
    method: &str,
    measured: Measured,
    recovered: Recovered,
    phi_mesh: MatRef<'_, f64>,
) -> Result<Report> {
    let (body, basis) = (run.body, run.basis);
    let backend = backend_of(run.solver)?;
    let statics = basis.omega.len() - basis.n_normal;
    let (spec, part, flanges) = (&body.spec, &body.part, &body.flanges);
    let mut report =
        report_of(spec, part, flanges, &body.model, basis, run.reduced, method, statics, measured.accuracy);
    report.verdict.band_rule = measured.band_rule;
    report.stress_points = recovered.report;
    report.backend = backend;
    report.pictures = crate::output::mesh_view::pictures(part, flanges, phi_mesh, &basis.omega);
    Ok(report)
}

/// An internal check that failed: the build stops rather than write a wrong FMU.
pub(super) fn internal_check(what: String) -> BuildError {
    BuildError::internal(format!("internal check failed: {what}"))
}
