//! Stress recovery for a build: the stress modes of the chosen nodes (their nodal stresses per
//! basis vector, what the FMU multiplies by q), the hot spots among the unit load cases' static
//! stresses, and each point's static stresses under those cases for the report.

use crate::error::{BuildError, Result};
use crate::ffrf::inertia::LoadCase;
use crate::model::flange::Flange;
use crate::model::part::Part;
use crate::model::stress::{Recovery, RecoveryPoint, hot_spots, nodal_stresses};
use crate::output::report::{StressPointReport, UnitCaseStress};
use faer::MatRef;
use fmu_runtime::reduced::StressPoint;
use std::path::Path;

/// Unit load cases as static fields on the mesh (3N x cases) with their names.
pub struct UnitCases<'a> {
    pub fields: MatRef<'a, f64>,
    pub names: Vec<String>,
}

/// Names of the unit flange loads (six per force flange, f_x .. t_z) and the scene's inertial
/// cases, in the order of their static fields.
pub fn unit_case_names(flanges: &[Flange], force: &[usize], cases: &[LoadCase]) -> Vec<String> {
    let axis = ["x", "y", "z"];
    let mut names: Vec<String> = force
        .iter()
        .flat_map(|&k| {
            (0..6).map(move |i| {
                if i < 3 {
                    format!("1 N force {} at flange {}", axis[i], flanges[k].name)
                } else {
                    format!("1 N.m torque {} at flange {}", axis[i - 3], flanges[k].name)
                }
            })
        })
        .collect();
    names.extend(cases.iter().map(|case| match case {
        LoadCase::Translation(a) => format!("1 m/s2 mount acceleration {} (or gravity -{})", axis[*a], axis[*a]),
        LoadCase::Euler(a) => format!("1 rad/s2 angular acceleration about {}", axis[*a]),
        LoadCase::Centrifugal(a, b) => format!("centrifugal load of w{} w{} = 1 (rad/s)^2", axis[*a], axis[*b]),
    }));
    names
}

/// What stress recovery adds to a build.
pub struct Recovered {
    /// The FMU's recovery points with their stress modes.
    pub points: Vec<StressPoint>,
    pub report: Vec<StressPointReport>,
    /// The points' mesh nodes, in the same order.
    pub nodes: Vec<usize>,
}

impl Recovered {
    pub fn none() -> Self {
        Self { points: Vec::new(), report: Vec::new(), nodes: Vec::new() }
    }
}

/// The recovery points' stress modes (6 x r per point, body frame = mesh axes) and their
/// report, hot spots chosen among the unit cases' static stresses.
pub fn recover(
    file: &Path,
    part: &Part,
    flanges: &[Flange],
    origin: [f64; 3],
    recovery: Recovery,
    phi_mesh: MatRef<'_, f64>,
    unit: &UnitCases<'_>,
) -> Result<Recovered> {
    phases::phase("stress recovery", || {
        let mut points = recovery.points;
        if recovery.hot_spots > 0 {
            points.extend(hot_spots_of(file, part, flanges, unit, &points, recovery.hot_spots)?);
        }
        phases::note(|| format!("{} points, {} unit load cases", points.len(), unit.names.len()));
        let nodes: Vec<usize> = points.iter().map(|p| p.node).collect();
        let r = phi_mesh.ncols();
        let modes = nodal_stresses(part, &nodes, phi_mesh)?;
        let k = unit.fields.ncols();
        let statics = nodal_stresses(part, &nodes, unit.fields)?;
        let mut stress_points = Vec::with_capacity(points.len());
        let mut report = Vec::with_capacity(points.len());
        for (i, point) in points.iter().enumerate() {
            let x = part.mesh.nodes[point.node];
            let mut rows = vec![0.0; 6 * r];
            for j in 0..r {
                for c in 0..6 {
                    rows[c * r + j] = modes[i * r + j][c];
                }
            }
            stress_points.push(StressPoint {
                name: point.name(part),
                description: point.description(part),
                position: [0, 1, 2].map(|a| x[a] - origin[a]),
                modes: rows,
            });
            report.push(point_report(part, point, &statics[i * k..(i + 1) * k], &unit.names));
        }
        Ok(Recovered { points: stress_points, report, nodes })
    })
}

/// The `count` nodes of highest von Mises stress over the unit cases, flange-tied nodes left
/// out (their stresses are the idealised tie's).
fn hot_spots_of(
    file: &Path,
    part: &Part,
    flanges: &[Flange],
    unit: &UnitCases<'_>,
    chosen: &[RecoveryPoint],
    count: usize,
) -> Result<Vec<RecoveryPoint>> {
    if unit.names.is_empty() {
        return Err(BuildError::input(
            file,
            "outputs.stress.hot_spots",
            "hot spots are found under the unit load cases, and this body has none (no force flange, no scene \
             loads): add a force flange or declare scene.loads, or name the nodes (node_sets, points)",
        ));
    }
    let mut tied = vec![false; part.mesh.n_nodes()];
    for f in flanges {
        for &n in &f.slaves {
            tied[n] = true;
        }
    }
    hot_spots(part, unit.fields, &unit.names, &tied, chosen, count)
}

/// A point's static stresses under each unit case, for the report.
fn point_report(part: &Part, point: &RecoveryPoint, statics: &[[f64; 6]], cases: &[String]) -> StressPointReport {
    StressPointReport {
        name: point.name(part),
        description: point.description(part),
        position: part.mesh.nodes[point.node],
        unit_cases: statics
            .iter()
            .zip(cases)
            .map(|(&stress, case)| UnitCaseStress {
                case: case.clone(),
                stress,
                von_mises: crate::model::fe::stress::von_mises(&stress),
            })
            .collect(),
    }
}
