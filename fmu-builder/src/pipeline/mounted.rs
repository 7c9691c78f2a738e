//! A body held at its mount flange: the mount's DoFs are held, the mounted stiffness factored,
//! and the basis is the reduction method's (Craig-Bampton, modal, Krylov), optionally cut to the
//! scene's tolerance; its accuracy is measured against the full mounted model's modes, static
//! compliance and flange transfer functions.

use super::body::{Coupled, Measured, Run, Support, internal_check};
use super::prepare::Prepared;
use super::stress::{Recovered, unit_case_names};
use crate::error::Result;
use crate::ffrf::inertia::LoadCase;
use crate::ffrf::invariants::Invariants;
use crate::ffrf::prestress::Prestress;
use crate::ffrf::scene_loads::{self, case_name};
use crate::input::spec::{Method, SceneLoad};
use crate::linalg::eigen::Eigenpairs;
use crate::linalg::sparse::{self, SpdSolve, SpdSolver};
use crate::model::rigid_coupling;
use crate::model::stress::nodal_stresses;
use crate::reduce::accuracy::{self, Accuracy};
use crate::reduce::band_response::{self, Known};
use crate::reduce::basis::{self, Basis, ModeCount};
use crate::reduce::compared_band::{DEFAULT_CUT, compared_band};
use crate::reduce::frf::{self, ComparisonDamping, StressProbe};
use crate::reduce::order_selection::choose_order;
use faer::{Mat, MatRef};
use fmu_runtime::reduced::Stiffening;
use std::borrow::Cow;
use std::path::Path;

/// What a mounted body's phases share once its stiffness is factored.
pub(super) struct Mounted {
    /// The scene's unit inertial load cases and their static shapes (mounted DoFs, in the
    /// basis).
    cases: Vec<LoadCase>,
    load_shapes: Option<Mat<f64>>,
    /// The same cases' loads, kept only for the order selection, which needs them unsolved.
    inertial_loads: Option<Mat<f64>>,
    /// The static response to unit force-flange loads: Craig-Bampton's held solves and
    /// constraint modes, and the compliance comparison, all from this one refined solve.
    flange_shapes: Mat<f64>,
    /// The full model's modes where the basis' eigen-solve found them (Craig-Bampton with a
    /// mode count): the accuracy comparison then needs no eigen-solve of its own.
    whole: Option<Eigenpairs>,
}

impl Support for Mounted {
    fn couple(p: Prepared) -> Result<Coupled> {
        let Some(mount) = p.spec.mount_index() else {
            return Err(internal_check("a mounted body without a mount flange".into()));
        };
        let origin = p.flanges[mount].reference;
        let mut model = phases::phase("coupling of the flanges", || {
            rigid_coupling::rigid_coupling(&p.free, &p.part.mesh.nodes, &p.flanges, origin)
        })?;
        drop(p.free);
        // the mount is held: its rows of K take part in nothing after this, and the model keeps
        // the mounted body's stiffness once, the factor's refinement borrowing it
        let nc = model.dofs.n_clamped();
        model.stiffness = sparse::block(&model.stiffness, 0..nc, 0..nc)?;
        let (spec, file, part, flanges, modes) = (p.spec, p.file, p.part, p.flanges, p.modes);
        Ok(Coupled { spec, file, part, flanges, model, origin, mount: Some(mount), modes })
    }

    /// One factor serves every solve of the build: the mounted body's statics and modes, the
    /// Craig-Bampton shapes with the flanges held (`held::HeldSolver`), the accuracy comparison.
    fn factor(body: &Coupled) -> Result<(SpdSolver<'_>, Self)> {
        let backend = body.spec.reduction.backend.backend(body.file.parent().unwrap_or(Path::new("")));
        let describe = |d| body.model.dofs.describe(d, &body.flanges, &|n| body.part.node_label(n));
        let matrix = Cow::Borrowed(&body.model.stiffness);
        let solver = SpdSolver::on(&backend, matrix, "the stiffness of the mounted body", &describe)?;
        let cases = scene_loads::declared_cases(&body.spec);
        let (nodes, flanges) = (&body.part.mesh.nodes, &body.flanges);
        let loads = scene_loads::inertial_loads(&body.model, nodes, flanges, body.origin, &cases);
        let selects_order = body.spec.scene.as_ref().is_some_and(|s| s.tolerance.is_some());
        let inertial_loads = if selects_order { loads.clone() } else { None };
        let load_shapes = loads.map(|mut u| {
            solver.solve_refined(u.as_mut());
            u
        });
        let flange_shapes = phases::phase("flange static shapes", || {
            let mut g = basis::flange_unit_loads(&body.model);
            phases::note(|| format!("{} unit loads", g.ncols()));
            solver.solve_refined(g.as_mut());
            g
        });
        Ok((solver, Mounted { cases, load_shapes, inertial_loads, flange_shapes, whole: None }))
    }

    fn basis(&mut self, body: &Coupled, solver: &SpdSolver) -> Result<(Basis, String)> {
        let (basis, method) = phases::phase("reduction basis", || self.method_basis(body, solver))?;
        let basis = match body.spec.scene.as_ref().and_then(|s| s.tolerance) {
            Some(tol) if !body.model.dofs.flange_first.is_empty() => phases::phase("order selection", || {
                choose_order(&body.spec, &body.model, solver, self.inertial_loads.as_ref(), basis, tol)
            })?,
            _ => basis,
        };
        self.inertial_loads = None;
        Ok((basis, method))
    }

    fn check_invariants(&self, body: &Coupled, inv: &Invariants) -> Result<()> {
        let mass = body.model.mass_properties.mass;
        for a in 0..3 {
            if (inv.rigid_mass[a] - mass).abs() > 1e-9 * mass {
                let found = inv.rigid_mass[a];
                return Err(internal_check(format!(
                    "rigid translation mass {found} differs from the mesh mass {mass}"
                )));
            }
        }
        Ok(())
    }

    fn stiffening(&self, body: &Coupled, solver: &SpdSolver, phi_mesh: MatRef<'_, f64>) -> Result<Option<Stiffening>> {
        let spec = &body.spec;
        if !spec.stiffening() {
            return Ok(None);
        }
        let prestress = Prestress {
            mesh: &body.part.mesh,
            materials: &body.part.materials,
            flanges: &body.flanges,
            model: &body.model,
            solver,
            origin: body.origin,
            cases: &self.cases,
            load_shapes: self.load_shapes.as_ref(),
            phi_mesh,
        };
        let translates = spec.declares(SceneLoad::Gravity) || spec.declares(SceneLoad::Acceleration);
        Ok(Some(phases::phase("geometric stiffening", || prestress.terms(spec.rotates(), translates))?))
    }

    /// The flange shapes' unit loads, then the scene's inertial cases.
    fn unit_cases(&self, body: &Coupled, _solver: &SpdSolver) -> (Mat<f64>, Vec<String>) {
        let statics = match &self.load_shapes {
            Some(shapes) => concat_columns(&self.flange_shapes, shapes),
            None => self.flange_shapes.clone(),
        };
        let names = unit_case_names(&body.flanges, &body.force_flanges(), &self.cases);
        (body.on_mesh(statics.as_ref()), names)
    }

    fn measure(self, run: &Run<'_>, recovered: &Recovered) -> Result<Measured> {
        let body = run.body;
        let force_dofs: Vec<(String, usize)> = body
            .force_flanges()
            .into_iter()
            .map(|k| (body.flanges[k].name.clone(), body.model.dofs.flange_first[k]))
            .collect();
        let (mut accuracy, full_modes) = phases::phase("accuracy comparison with the full model", || {
            let n_full = run.basis.omega.len().max(10);
            accuracy::accuracy(&body.model, run.solver, &self.flange_shapes, run.basis, &force_dofs, n_full, self.whole)
        })?;
        accuracy::enforce(&accuracy)?;
        let mut band_rule = None;
        if !force_dofs.is_empty() {
            let known = Known { modes: Some(&full_modes), static_response: Some(&self.flange_shapes) };
            let (response, rule) = frequency_response(run, &accuracy, recovered, known)?;
            accuracy.frequency_response = Some(response);
            band_rule = Some(rule);
        }
        drop(full_modes);
        if let Some(shapes) = &self.load_shapes {
            inertial_responses(&mut accuracy, &self.cases, shapes, &force_dofs);
        }
        Ok(Measured { accuracy, band_rule })
    }
}

impl Mounted {
    /// The basis of the input's method (before any order selection) and its name in the report.
    fn method_basis(&mut self, body: &Coupled, solver: &SpdSolver) -> Result<(Basis, String)> {
        let (model, shapes, r) = (&body.model, self.load_shapes.as_ref(), &body.spec.reduction);
        Ok(match r.method {
            Method::CraigBampton => {
                // the accuracy comparison's full modes, as many as the basis will have columns (at
                // least ten): Craig-Bampton with a mode count finds them in the same space
                let whole_modes = match body.modes {
                    ModeCount::Count(c) => {
                        Some((c + basis::flange_unit_loads_count(model) + shapes.map_or(0, |s| s.ncols())).max(10))
                    }
                    ModeCount::Below(_) => None,
                };
                let (basis, full) =
                    basis::craig_bampton(model, solver, &self.flange_shapes, body.modes, shapes, whole_modes)?;
                self.whole = full;
                (basis, "Craig-Bampton".to_string())
            }
            Method::Modal => {
                (basis::modal(model, solver, body.modes, shapes)?, "modal with residual flexibility".to_string())
            }
            Method::Krylov => {
                let points = r.expansion_points.clone().unwrap_or_default();
                let moments = r.moments.unwrap_or(2);
                let real = r.real_expansion_points.clone().unwrap_or_default();
                let name = format!(
                    "second-order Krylov, {moments} block moments at s = 0, 2 pi i {points:?} Hz, {real:?} 1/s"
                );
                (basis::krylov(model, solver, &points, &real, moments, shapes)?, name)
            }
        })
    }
}

/// The flange transfer functions of the full and the reduced model compared over the scene's
/// band, or by default over the range the model claims (`compared_band`), at every size, as it
/// costs a few block solves (2.3 s of a 25 s build at 2.5e5 DoFs); the recovery points' stress
/// responses too (full: the full model's response on the mesh, its nodal stresses at the points).
fn frequency_response(
    run: &Run<'_>,
    accuracy: &Accuracy,
    recovered: &Recovered,
    known: Known<'_>,
) -> Result<(frf::FrequencyResponse, String)> {
    let (body, spec) = (run.body, &run.body.spec);
    let (band, rule, named) = compared_band(spec, run.basis, &accuracy.full_hz);
    let damping = ComparisonDamping::new(spec.damping.alpha, spec.damping.beta);
    let stresses_of = |x: MatRef<'_, f64>| nodal_stresses(&body.part, &recovered.nodes, body.on_mesh(x).as_ref());
    let probe = (!recovered.nodes.is_empty()).then(|| StressProbe {
        full: &stresses_of,
        modes: run.reduced.stress_points.iter().map(|p| p.modes.as_slice()).collect(),
    });
    let cut = if named { band_response::CUT } else { DEFAULT_CUT };
    let response = phases::phase("frequency-response comparison", || {
        let (full_hz, compliance) = (&accuracy.full_hz, &accuracy.compliance_full);
        frf::compare(&body.model, run.solver, run.basis, damping, band, full_hz, compliance, probe.as_ref(), known, cut)
    })?;
    Ok((response, rule))
}

/// The full model's flange response to each of the scene's unit inertial cases, in the report.
fn inertial_responses(accuracy: &mut Accuracy, cases: &[LoadCase], shapes: &Mat<f64>, force_dofs: &[(String, usize)]) {
    for (c, case) in cases.iter().enumerate() {
        accuracy.inertial_cases.push(case_name(*case));
        let response = force_dofs.iter().flat_map(|(_, first)| (0..6).map(move |i| shapes[(first + i, c)])).collect();
        accuracy.inertial_flange_response_full.push(response);
    }
}

/// [a b]: the columns of `a`, then those of `b` (same rows).
fn concat_columns(a: &Mat<f64>, b: &Mat<f64>) -> Mat<f64> {
    let mut out = Mat::<f64>::zeros(a.nrows(), a.ncols() + b.ncols());
    out.as_mut().subcols_mut(0, a.ncols()).copy_from(a);
    out.as_mut().subcols_mut(a.ncols(), b.ncols()).copy_from(b);
    out
}
