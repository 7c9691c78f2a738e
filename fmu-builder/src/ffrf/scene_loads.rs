//! The scene's unit inertial load cases on a mounted body: which the scene declares, their
//! loads on the mounted DoFs, and their names in the report.

use crate::ffrf::inertia::{self, LoadCase};
use crate::input::spec::{SceneLoad, Spec};
use crate::model::flange::Flange;
use crate::model::rigid_coupling::Assembled;
use faer::Mat;

/// Gravity or acceleration: the three translations; rotation: angular accelerations and the
/// centrifugal cases.
pub fn declared_cases(spec: &Spec) -> Vec<LoadCase> {
    let mut cases = Vec::new();
    if spec.declares(SceneLoad::Gravity) || spec.declares(SceneLoad::Acceleration) {
        cases.extend(LoadCase::translations());
    }
    if spec.declares(SceneLoad::Rotation) {
        cases.extend(LoadCase::rotations());
    }
    cases
}

/// The cases' loads restricted to the mounted DoFs (n_clamped x cases), or None without cases.
pub fn inertial_loads(
    model: &Assembled,
    nodes: &[[f64; 3]],
    flanges: &[Flange],
    origin: [f64; 3],
    cases: &[LoadCase],
) -> Option<Mat<f64>> {
    if cases.is_empty() {
        return None;
    }
    let mut f = Mat::<f64>::zeros(3 * nodes.len(), cases.len());
    for (c, case) in cases.iter().enumerate() {
        f.as_mut().col_mut(c).copy_from(inertia::inertial_load(model, nodes, origin, *case).col(0));
    }
    Some(inertia::restrict(model, nodes, flanges, f.as_ref()))
}

/// The case as the report's accuracy section names it ("translation x", "centrifugal xy").
pub fn case_name(case: LoadCase) -> String {
    let axis = ["x", "y", "z"];
    match case {
        LoadCase::Translation(a) => format!("translation {}", axis[a]),
        LoadCase::Euler(a) => format!("angular acceleration {}", axis[a]),
        LoadCase::Centrifugal(a, b) => format!("centrifugal {}{}", axis[a], axis[b]),
    }
}
