//! A free-floating body (no motion flange): the FMU integrates the rigid-body motion itself.
//! The body frame sits at the centre of mass with mean axes (elastic shapes M-orthogonal to the
//! rigid-body fields), the basis is free-interface elastic modes plus inertia-relief attachment
//! shapes of the flanges, and the report compares against the full model's free-free modes and
//! inertia-relief flange compliance.

use super::body::{Coupled, Measured, Run, Support, internal_check};
use super::prepare::Prepared;
use super::stress::{Recovered, unit_case_names};
use crate::error::Result;
use crate::ffrf::invariants::{self, Invariants};
use crate::linalg::eigen::Deflation;
use crate::linalg::sparse::SpdSolver;
use crate::model::rigid_coupling;
use crate::reduce::accuracy::{enforce, free_free_accuracy};
use crate::reduce::basis::{self, Basis};
use crate::reduce::free_body::{rigid_deflation, shifted_stiffness};
use faer::{Mat, MatRef};
use fmu_runtime::reduced::Stiffening;
use std::borrow::Cow;
use std::path::Path;

/// What a free body's phases share once K + s M is factored.
pub(super) struct FreeFloating {
    /// The shift s of the factored K + s M.
    shift: f64,
    /// The six rigid-body fields about the centre of mass, M-orthonormal: deflated from the
    /// eigen-solves, projected out of the attachment shapes.
    rigid: Deflation,
}

impl Support for FreeFloating {
    fn couple(p: Prepared) -> Result<Coupled> {
        let mut model = phases::phase("coupling of the flanges", || {
            rigid_coupling::rigid_coupling(&p.free, &p.part.mesh.nodes, &p.flanges, [0.0; 3])
        })?;
        drop(p.free);
        let (origin, props) = model.mass_properties.about_centre_of_mass();
        model.mass_properties = props;
        let (spec, file, part, flanges, modes) = (p.spec, p.file, p.part, p.flanges, p.modes);
        Ok(Coupled { spec, file, part, flanges, model, origin, mount: None, modes })
    }

    /// Where the factorisation fails tells the user where the mesh has its mechanism.
    fn factor(body: &Coupled) -> Result<(SpdSolver<'_>, Self)> {
        let model = &body.model;
        let (k_shifted, shift) = shifted_stiffness(&model.stiffness, &model.mass)?;
        let backend = body.spec.reduction.backend.backend(body.file.parent().unwrap_or(Path::new("")));
        let describe = |d| model.dofs.describe(d, &body.flanges, &|n| body.part.node_label(n));
        let solver = SpdSolver::on(&backend, Cow::Owned(k_shifted), "K + s M of the free body", &describe)?;
        let fields = invariants::rigid_fields(model, &body.part.mesh.nodes, &body.flanges, body.origin);
        let rigid = rigid_deflation(&model.mass, fields)?;
        Ok((solver, FreeFloating { shift, rigid }))
    }

    fn basis(&mut self, body: &Coupled, solver: &SpdSolver) -> Result<(Basis, String)> {
        let basis = phases::phase("reduction basis", || {
            basis::free_free(&body.model, solver, self.shift, &self.rigid, body.modes)
        })?;
        Ok((basis, "free-interface modes + inertia-relief attachment shapes".to_string()))
    }

    /// Mean axes: the elastic shapes carry no momentum.
    fn check_invariants(&self, body: &Coupled, inv: &Invariants) -> Result<()> {
        let props = body.model.mass_properties;
        let scale = props.mass.sqrt() * (1.0 + props.inertia[0].abs().sqrt());
        let drift = inv.c_t.iter().chain(&inv.c_r).fold(0.0f64, |m, v| m.max(v.abs()));
        if drift > 1e-8 * scale {
            return Err(internal_check(format!("the elastic basis carries rigid-body momentum ({drift:e})")));
        }
        Ok(())
    }

    fn stiffening(&self, _: &Coupled, _: &SpdSolver, _: MatRef<'_, f64>) -> Result<Option<Stiffening>> {
        Ok(None)
    }

    /// Unit flange loads with inertia relief: what deforms a free body.
    fn unit_cases(&self, body: &Coupled, solver: &SpdSolver) -> (Mat<f64>, Vec<String>) {
        let unit = basis::flange_unit_loads(&body.model);
        let statics = basis::inertia_relief_solve(solver, &body.model.mass, self.shift, &self.rigid, &unit);
        let names = unit_case_names(&body.flanges, &body.force_flanges(), &[]);
        (body.on_mesh(statics.as_ref()), names)
    }

    fn measure(self, run: &Run<'_>, _: &Recovered) -> Result<Measured> {
        let accuracy = phases::phase("accuracy comparison with the full model", || {
            free_free_accuracy(&run.body.model, run.solver, self.shift, &self.rigid, run.basis)
        })?;
        enforce(&accuracy)?;
        Ok(Measured { accuracy, band_rule: None })
    }
}
