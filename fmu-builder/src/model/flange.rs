//! Flanges: a six-DoF master node at a reference point, tied to slave nodes rigidly (RBE2; paper
//! eq. 3: xi_j = u + theta x (x_j - r_c)) or by a distributing coupling (RBE3, `distributing`).
//! Here the slaves are selected on the mesh and checked, and a distributing flange's weights
//! found; the coupling itself enters at assembly (`rigid_coupling`).

use crate::error::{BuildError, Refusal, Result};
use crate::input::mesh::Mesh;
use crate::input::spec::{Coupling, NodeSelector, Role, Spec, Weights};
use crate::model::distributing;
use crate::model::part::Part;
use nalgebra::{Matrix3, Vector3};
use std::path::Path;

#[derive(Debug, Clone)]
pub struct Flange {
    pub name: String,
    pub role: Role,
    /// Master node position (undeformed), world = body axes [m].
    pub reference: [f64; 3],
    /// Mesh node indices tied to the master, ascending.
    pub slaves: Vec<usize>,
    pub coupling: FlangeCoupling,
}

#[derive(Debug, Clone, PartialEq)]
pub enum FlangeCoupling {
    Rigid,
    /// The weight of each slave (same order), positive.
    Distributing {
        weights: Vec<f64>,
    },
}

fn bounds(mesh: &Mesh) -> ([f64; 3], [f64; 3]) {
    bounds_of(&mesh.nodes)
}

fn bounds_of(points: &[[f64; 3]]) -> ([f64; 3], [f64; 3]) {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for p in points {
        for a in 0..3 {
            lo[a] = lo[a].min(p[a]);
            hi[a] = hi[a].max(p[a]);
        }
    }
    (lo, hi)
}

/// Bounding-box diagonal of the mesh: the length scale for geometric tolerances.
pub fn model_size(mesh: &Mesh) -> f64 {
    let (lo, hi) = bounds(mesh);
    (Vector3::from(hi) - Vector3::from(lo)).norm()
}

/// The slave nodes a selector names; Err(message) when a named node set or box does not exist.
fn select(selector: &NodeSelector, part: &Part, size: f64) -> std::result::Result<Vec<usize>, Refusal> {
    let mesh = &part.mesh;
    let tol_default = 1e-6 * size;
    let within = |keep: &dyn Fn(Vector3<f64>) -> bool| {
        (0..mesh.nodes.len()).filter(|&i| keep(Vector3::from(mesh.nodes[i]))).collect::<Vec<_>>()
    };
    Ok(match selector {
        NodeSelector::NodeSet(name) => match part.node_set(name) {
            Some(nodes) => nodes.to_vec(),
            None => {
                let known: Vec<&str> = part.node_sets.keys().map(|k| k.as_str()).collect();
                return Err(Refusal::from(format!(
                    "there is no node set \"{name}\" ({})",
                    if known.is_empty() {
                        "the part has no node sets".to_string()
                    } else {
                        format!("node sets: {}", known.join(", "))
                    }
                )));
            }
        },
        NodeSelector::Box { min, max } => {
            within(&|p| (0..3).all(|a| p[a] >= min[a] - tol_default && p[a] <= max[a] + tol_default))
        }
        NodeSelector::Sphere { center, radius } => {
            within(&|p| (p - Vector3::from(*center)).norm() <= radius + tol_default)
        }
        NodeSelector::Cylinder { point, axis, radius, length } => {
            let n = Vector3::from(*axis).normalize();
            within(&|p| {
                let d = p - Vector3::from(*point);
                let along = d.dot(&n);
                (d - n * along).norm() <= radius + tol_default
                    && length.is_none_or(|l| along.abs() <= 0.5 * l + tol_default)
            })
        }
        NodeSelector::BoxFace { box_index, face } => {
            let Some(b) = part.boxes.get(*box_index) else {
                return Err(Refusal::from(format!(
                    "there is no box {box_index}: the part has {} box(es)",
                    part.boxes.len()
                )));
            };
            let (axis, upper) = face.axis_side();
            let level = if upper { b.max[axis] } else { b.min[axis] };
            within(&|p| {
                (p[axis] - level).abs() <= tol_default
                    && (0..3)
                        .filter(|&a| a != axis)
                        .all(|a| p[a] >= b.min[a] - tol_default && p[a] <= b.max[a] + tol_default)
            })
        }
        NodeSelector::Plane { point, normal, tolerance } => {
            let n = Vector3::from(*normal).normalize();
            let tol = tolerance.unwrap_or(tol_default);
            within(&|p| (p - Vector3::from(*point)).dot(&n).abs() <= tol)
        }
    })
}

fn centroid(points: &[[f64; 3]]) -> Vector3<f64> {
    points.iter().fold(Vector3::zeros(), |c, p| c + Vector3::from(*p) / points.len() as f64)
}

/// Ratio of the second to the first principal extent of a point set: ~0 for collinear points.
fn planarity(points: &[[f64; 3]]) -> f64 {
    let c = centroid(points);
    let mut s = Matrix3::<f64>::zeros();
    for p in points {
        let d = Vector3::from(*p) - c;
        s += d * d.transpose();
    }
    // a 3 x 3 of finite coordinates: QR converges in a few sweeps; the limit only guards a hang
    let Some(evd) = s.try_symmetric_eigen(f64::EPSILON, 1000) else {
        return 0.0;
    };
    let mut ev: Vec<f64> = evd.eigenvalues.iter().copied().collect();
    ev.sort_by(|a, b| b.total_cmp(a));
    if ev[0] <= 0.0 { 0.0 } else { (ev[1].max(0.0) / ev[0]).sqrt() }
}

/// A reference point this many part sizes from its flange's nodes is a unit slip or a typo: the
/// rigid tie's lever arms scale the flange's stiffness and inertia terms by its square (1e6 at
/// this distance), the most a reduction checked to 1e-8 can take.
const MAX_LEVER_IN_SIZES: f64 = 1e3;

pub fn select_flanges(spec: &Spec, file: &Path, part: &Part) -> Result<Vec<Flange>> {
    let mesh = &part.mesh;
    let size = model_size(mesh);
    let mut owner: Vec<Option<usize>> = vec![None; mesh.nodes.len()];
    let mut flanges = Vec::with_capacity(spec.flanges.len());
    // every selector failure states where the part is: a selector in millimetres on a part in
    // metres (or the other way round) shows at once
    // ... in the unit the selectors are given in (geometry.length_unit)
    let (unit, scale) = (spec.geometry.length_unit.symbol(), part.length_scale);
    let (lo, hi) = bounds(mesh);
    let spans = format!("the part spans {:?} to {:?} [{unit}]", lo.map(|c| c / scale), hi.map(|c| c / scale));
    for (k, fs) in spec.flanges.iter().enumerate() {
        let field = format!("flanges[{k}].nodes");
        let slaves = select(&fs.nodes.scaled(scale), part, size)
            .map_err(|m| BuildError::input(file, format!("{field}.node_set"), format!("{m}; {spans}")))?;
        if slaves.is_empty() {
            return Err(BuildError::input(
                file,
                field,
                format!(
                    "flange \"{}\" selects no node of the part (check the set, face, plane, box, sphere or cylinder and its size, \
                     in {unit}; {spans})",
                    fs.name
                ),
            ));
        }
        let points: Vec<[f64; 3]> = slaves.iter().map(|&i| mesh.nodes[i]).collect();
        if slaves.len() < 3 || planarity(&points) < 1e-8 {
            let (plo, phi) = bounds_of(&points);
            return Err(BuildError::input(
                file,
                field,
                format!(
                    "flange \"{}\" selects {} node(s) on a line (from {plo:?} to {phi:?}); a rigid flange needs at least three \
                     non-collinear nodes: widen the selector (in {unit}; {spans})",
                    fs.name,
                    slaves.len()
                ),
            ));
        }
        for &s in &slaves {
            if let Some(other) = owner[s] {
                let p = mesh.nodes[s];
                return Err(BuildError::input(
                    file,
                    field,
                    format!(
                        "flange \"{}\" shares the node at ({}, {}, {}) with flange \"{}\"; a node can be tied to one flange only: \
                         narrow one of the selectors ({spans})",
                        fs.name, p[0], p[1], p[2], spec.flanges[other].name
                    ),
                ));
            }
            owner[s] = Some(k);
        }
        let reference = fs.reference_point.map(|r| r.map(|c| c * scale)).unwrap_or_else(|| centroid(&points).into());
        let lever = (Vector3::from(reference) - centroid(&points)).norm();
        if !(lever <= MAX_LEVER_IN_SIZES * size) {
            return Err(BuildError::input(
                file,
                format!("flanges[{k}].reference_point"),
                format!(
                    "the reference point {reference:?} lies {lever:.3e} m from the flange's nodes, more than {MAX_LEVER_IN_SIZES:.0e} \
                     times the part's size ({size:.3e} m): the rigid lever to it swamps the part's own stiffness and mass in \
                     double precision; put it at the joint the flange stands for (in {unit}; {spans})"
                ),
            ));
        }
        let (slaves, coupling) = match fs.coupling {
            Coupling::Rigid => (slaves, FlangeCoupling::Rigid),
            Coupling::Distributing => {
                distributing_weights(file, k, fs.name.as_str(), fs.weights, part, slaves, reference)?
            }
        };
        flanges.push(Flange { name: fs.name.clone(), role: fs.role, reference, slaves, coupling });
    }
    Ok(flanges)
}

/// A distributing flange's weights (nodes without weight leave the flange: nothing ties them),
/// checked to define the reference point's rotation.
fn distributing_weights(
    file: &Path,
    k: usize,
    name: &str,
    weights: Option<Weights>,
    part: &Part,
    slaves: Vec<usize>,
    reference: [f64; 3],
) -> Result<(Vec<usize>, FlangeCoupling)> {
    let mesh = &part.mesh;
    let w = match weights.unwrap_or_default() {
        Weights::Uniform => vec![1.0; slaves.len()],
        Weights::Area => distributing::tributary_areas(mesh, &slaves),
    };
    let (slaves, w): (Vec<usize>, Vec<f64>) = slaves.into_iter().zip(w).filter(|(_, w)| *w > 0.0).unzip();
    if slaves.is_empty() {
        return Err(BuildError::input(
            file,
            format!("flanges[{k}].weights"),
            format!(
                "flange \"{name}\" has area weights, but no face of the part's surface has all its nodes in the flange \
                 (a node set or selector of surface nodes is needed, corners and midsides); use \"uniform\" weights"
            ),
        ));
    }
    let points: Vec<[f64; 3]> = slaves.iter().map(|&i| mesh.nodes[i]).collect();
    match distributing::constraint(&points, &w, reference) {
        Ok(_) => Ok((slaves, FlangeCoupling::Distributing { weights: w })),
        Err(why) => Err(BuildError::input(
            file,
            format!("flanges[{k}].coupling"),
            format!(
                "flange \"{name}\"'s {} weighted nodes {}: a distributing coupling takes the reference point's rotation \
                 from how its nodes move about their centroid, which nodes on a line leave undefined; select nodes \
                 spread over a surface, or use \"coupling\": \"rigid\"",
                points.len(),
                match why {
                    distributing::Refusal::Collinear => "lie on a line",
                    distributing::Refusal::NoWeight => "have no weight",
                }
            ),
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::BTreeMap;

    /// A 4 x 2 x 2 hex8 box [0, 4] x [0, 2] x [0, 2] with a node set of its x = 4 face.
    fn part() -> (Spec, Part) {
        let spec = Spec::from_str(
            Path::new("in.json"),
            r#"{"name": "P", "geometry": {"element": "hex8", "boxes": [{"min": [0,0,0], "max": [4,2,2], "elements": [4,2,2]}]},
                "material": {"E": 1e9, "nu": 0.3, "rho": 1000}, "flanges": [], "reduction": {"modes": 2}}"#,
        )
        .unwrap();
        let mut p = crate::model::part::part_of(&spec, Path::new("in.json")).unwrap();
        let tip: Vec<usize> = (0..p.mesh.n_nodes()).filter(|&i| p.mesh.nodes[i][0] == 4.0).collect();
        p.node_sets = BTreeMap::from([("TIP".to_string(), tip)]);
        (spec, p)
    }

    fn selected(part: &Part, json: &str) -> std::result::Result<Vec<[f64; 3]>, String> {
        let selector: NodeSelector = serde_json::from_str(json).unwrap();
        select(&selector, part, model_size(&part.mesh))
            .map(|s| s.iter().map(|&i| part.mesh.nodes[i]).collect())
            .map_err(|e| e.reason)
    }

    #[test]
    fn every_selector_picks_what_it_says() {
        let (_, part) = part();
        // 3 x 3 nodes on the face x = 4, however it is named
        for json in [
            r#"{"node_set": "tip"}"#,
            r#"{"plane": {"point": [4, 0, 0], "normal": [2, 0, 0]}}"#,
            r#"{"box": {"min": [3.5, -1, -1], "max": [5, 3, 3]}}"#,
        ] {
            let nodes = selected(&part, json).unwrap();
            assert_eq!(nodes.len(), 9, "{json}");
            assert!(nodes.iter().all(|p| p[0] == 4.0), "{json}");
        }
        // the sphere of radius 1 around the face centre: the centre and its 4 edge neighbours
        let nodes = selected(&part, r#"{"sphere": {"center": [4, 1, 1], "radius": 1}}"#).unwrap();
        assert_eq!(nodes.len(), 6, "{nodes:?}"); // plus the node one step inside, at (3, 1, 1)
        // the cylinder around the x axis through (., 1, 1), radius 1: 5 nodes per cross-section
        let nodes = selected(&part, r#"{"cylinder": {"point": [0, 1, 1], "axis": [1, 0, 0], "radius": 1}}"#).unwrap();
        assert_eq!(nodes.len(), 5 * 5);
        // with a length, only the cross-sections within length/2 of the point
        let nodes =
            selected(&part, r#"{"cylinder": {"point": [4, 1, 1], "axis": [-1, 0, 0], "radius": 1, "length": 1}}"#)
                .unwrap();
        assert_eq!(nodes.len(), 5);
        let e = selected(&part, r#"{"node_set": "ROOT"}"#).unwrap_err();
        assert!(e.contains("ROOT") && e.contains("TIP"), "{e}");
    }
}
