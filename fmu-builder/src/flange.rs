//! Flanges: a six-DoF master node at a reference point, tied rigidly to slave nodes (RBE2; paper
//! eq. 3): xi_j = u + theta x (x_j - r_c). Here the slaves are selected on the mesh and checked;
//! the coupling itself enters at assembly (`assembly::rigid_coupling`).

use crate::error::{BuildError, Result};
use crate::mesh::Mesh;
use crate::spec::{NodeSelector, Role, Spec};
use std::path::Path;

#[derive(Debug, Clone)]
pub struct Flange {
    pub name: String,
    pub role: Role,
    /// Master node position (undeformed), world = body axes [m].
    pub reference: [f64; 3],
    /// Mesh node indices tied to the master, ascending.
    pub slaves: Vec<usize>,
}

/// Bounding-box diagonal of the mesh: the length scale for geometric tolerances.
pub fn model_size(mesh: &Mesh) -> f64 {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for p in &mesh.nodes {
        for a in 0..3 {
            lo[a] = lo[a].min(p[a]);
            hi[a] = hi[a].max(p[a]);
        }
    }
    (0..3).map(|a| (hi[a] - lo[a]).powi(2)).sum::<f64>().sqrt()
}

fn select(spec: &Spec, selector: &NodeSelector, mesh: &Mesh, size: f64) -> Vec<usize> {
    let tol_default = 1e-6 * size;
    match selector {
        NodeSelector::BoxFace { box_index, face } => {
            let b = &spec.geometry.boxes[*box_index];
            let (axis, upper) = face.axis_side();
            let level = if upper { b.max[axis] } else { b.min[axis] };
            (0..mesh.nodes.len())
                .filter(|&i| {
                    let p = mesh.nodes[i];
                    (p[axis] - level).abs() <= tol_default
                        && (0..3).filter(|&a| a != axis).all(|a| {
                            p[a] >= b.min[a] - tol_default && p[a] <= b.max[a] + tol_default
                        })
                })
                .collect()
        }
        NodeSelector::Plane { point, normal, tolerance } => {
            let len = normal.iter().map(|c| c * c).sum::<f64>().sqrt();
            let n = normal.map(|c| c / len);
            let tol = tolerance.unwrap_or(tol_default);
            (0..mesh.nodes.len())
                .filter(|&i| {
                    let p = mesh.nodes[i];
                    ((p[0] - point[0]) * n[0] + (p[1] - point[1]) * n[1] + (p[2] - point[2]) * n[2]).abs() <= tol
                })
                .collect()
        }
    }
}

/// Ratio of the second to the first principal extent of a point set: ~0 for collinear points.
fn planarity(points: &[[f64; 3]]) -> f64 {
    let n = points.len() as f64;
    let mut c = [0.0; 3];
    for p in points {
        for a in 0..3 {
            c[a] += p[a] / n;
        }
    }
    let mut s = nalgebra::Matrix3::<f64>::zeros();
    for p in points {
        let d = nalgebra::Vector3::new(p[0] - c[0], p[1] - c[1], p[2] - c[2]);
        s += d * d.transpose();
    }
    let mut ev: Vec<f64> = s.symmetric_eigenvalues().iter().copied().collect();
    ev.sort_by(|a, b| b.total_cmp(a));
    if ev[0] <= 0.0 { 0.0 } else { (ev[1].max(0.0) / ev[0]).sqrt() }
}

pub fn select_flanges(spec: &Spec, file: &Path, mesh: &Mesh) -> Result<Vec<Flange>> {
    let size = model_size(mesh);
    let mut owner: Vec<Option<usize>> = vec![None; mesh.nodes.len()];
    let mut flanges = Vec::with_capacity(spec.flanges.len());
    for (k, fs) in spec.flanges.iter().enumerate() {
        let field = format!("flanges[{k}].nodes");
        let slaves = select(spec, &fs.nodes, mesh, size);
        if slaves.is_empty() {
            return Err(BuildError::input(
                file,
                field,
                format!("flange \"{}\" selects no node of the mesh (check the face or plane and its tolerance)", fs.name),
            ));
        }
        let points: Vec<[f64; 3]> = slaves.iter().map(|&i| mesh.nodes[i]).collect();
        if slaves.len() < 3 || planarity(&points) < 1e-8 {
            return Err(BuildError::input(
                file,
                field,
                format!(
                    "flange \"{}\" selects {} node(s) on a line; a rigid flange needs at least three non-collinear nodes",
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
                        "flange \"{}\" shares the node at ({}, {}, {}) with flange \"{}\"; a node can be tied to one flange only",
                        fs.name, p[0], p[1], p[2], spec.flanges[other].name
                    ),
                ));
            }
            owner[s] = Some(k);
        }
        let reference = fs.reference_point.unwrap_or_else(|| {
            let n = points.len() as f64;
            let mut c = [0.0; 3];
            for p in &points {
                for a in 0..3 {
                    c[a] += p[a] / n;
                }
            }
            c
        });
        flanges.push(Flange { name: fs.name.clone(), role: fs.role, reference, slaves });
    }
    Ok(flanges)
}
