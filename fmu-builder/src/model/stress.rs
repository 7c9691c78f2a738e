//! Nodal stresses of displacement fields on the mesh, at chosen nodes: every element's nodal
//! values (`fe::stress`), averaged over the elements that share the node (a plain mean, as
//! CalculiX averages its nodal stresses).

use crate::error::{BuildError, Result};
use crate::input::spec::{MAX_STRESS_POINTS, StressOutputs};
use crate::model::fe::stress::{element_nodal_stresses, von_mises};
use crate::model::part::Part;
use faer::MatRef;
use rayon::prelude::*;
use std::path::Path;

const NOT_WANTED: u32 = u32::MAX;

/// Stresses (xx, yy, zz, xy, yz, zx) at `nodes` of the fields `u` (3N x k, node-major rows):
/// nodes.len() x k vectors, node-major.
pub fn nodal_stresses(part: &Part, nodes: &[usize], u: MatRef<'_, f64>) -> Result<Vec<[f64; 6]>> {
    let mesh = &part.mesh;
    let k = u.ncols();
    let mut slot = vec![NOT_WANTED; mesh.n_nodes()];
    for (s, &n) in nodes.iter().enumerate() {
        slot[n] = s as u32;
    }
    let empty = || (vec![[0.0; 6]; nodes.len() * k], vec![0u32; nodes.len()]);
    // element by element on every thread, each summing into its own copy (no locks), then
    // the copies summed: a node's elements may lie in any thread's share
    let (sums, counts) = (0..mesh.n_elements())
        .into_par_iter()
        .with_min_len(256)
        .try_fold(empty, |(mut sums, mut counts), e| -> Result<_> {
            let conn = mesh.element(e);
            if conn.iter().all(|&n| slot[n] == NOT_WANTED) {
                return Ok((sums, counts));
            }
            let kind = mesh.kind(e);
            let mut buf = [[0.0; 3]; crate::input::element::MAX_NODES_PER_ELEMENT];
            let coords = mesh.element_coords(e, &mut buf);
            let ue: Vec<f64> =
                conn.iter().flat_map(|&n| (0..3).flat_map(move |i| (0..k).map(move |c| u[(3 * n + i, c)]))).collect();
            let mut out = vec![[0.0; 6]; conn.len() * k];
            let material = &part.materials[mesh.material[e]].elasticity;
            element_nodal_stresses(kind, coords, material, &ue, k, &mut out)
                .map_err(|err| part.element_error(e, err.to_string()).caused_by(err))?;
            for (a, &n) in conn.iter().enumerate() {
                let s = slot[n];
                if s == NOT_WANTED {
                    continue;
                }
                let s = s as usize;
                counts[s] += 1;
                for c in 0..k {
                    let (sum, add) = (&mut sums[s * k + c], out[a * k + c]);
                    for r in 0..6 {
                        sum[r] += add[r];
                    }
                }
            }
            Ok((sums, counts))
        })
        .try_reduce(empty, |(mut sums, mut counts), (other_sums, other_counts)| {
            for (a, b) in sums.iter_mut().zip(&other_sums) {
                for r in 0..6 {
                    a[r] += b[r];
                }
            }
            for (a, b) in counts.iter_mut().zip(&other_counts) {
                *a += b;
            }
            Ok((sums, counts))
        })?;
    Ok(sums
        .chunks(k.max(1))
        .zip(&counts)
        .flat_map(|(node, &count)| {
            let scale = if count > 0 { 1.0 / f64::from(count) } else { 0.0 };
            node.iter().map(move |s| s.map(|v| v * scale))
        })
        .take(nodes.len() * k)
        .collect())
}

/// Why a node is a recovery point.
#[derive(Debug, Clone, PartialEq)]
pub enum PointOrigin {
    NodeSet(String),
    /// The node nearest to this point (mesh coordinates).
    Nearest([f64; 3]),
    /// Rank (1 = highest) among the hot spots, the unit load case that ranks it, and its von
    /// Mises stress there relative to that case's peak.
    HotSpot {
        rank: usize,
        case: String,
        share: f64,
    },
}

/// A node where the FMU recovers stresses.
#[derive(Debug, Clone, PartialEq)]
pub struct RecoveryPoint {
    pub node: usize,
    pub origin: PointOrigin,
}

impl RecoveryPoint {
    /// Variable name stem: `stress.n<node id>` (the file's id, or the node's number from 1).
    pub fn name(&self, part: &Part) -> String {
        format!("stress.n{}", node_number(part, self.node))
    }

    /// Which node and why, for the variables' descriptions.
    pub fn description(&self, part: &Part) -> String {
        let p = part.mesh.nodes[self.node];
        let at = format!("node {} at ({:.6}, {:.6}, {:.6}) m", node_number(part, self.node), p[0], p[1], p[2]);
        match &self.origin {
            PointOrigin::NodeSet(set) => format!("{at}, of node set {set}"),
            PointOrigin::Nearest(q) => format!("{at}, nearest to ({}, {}, {})", q[0], q[1], q[2]),
            PointOrigin::HotSpot { rank, case, share } => {
                format!("{at}, hot spot {rank} (von Mises {:.0} % of the peak under {case})", 100.0 * share)
            }
        }
    }
}

/// The node's id in the mesh file, or its number from 1.
fn node_number(part: &Part, node: usize) -> u64 {
    part.node_ids.get(node).copied().unwrap_or(node as u64 + 1)
}

/// Which nodes belong to an element: only those carry a nodal stress.
fn element_nodes(part: &Part) -> Vec<bool> {
    let mut used = vec![false; part.mesh.n_nodes()];
    for e in 0..part.mesh.n_elements() {
        for &n in part.mesh.element(e) {
            used[n] = true;
        }
    }
    used
}

/// What the spec asks to recover: its named points, and how many hot spots to add.
#[derive(Debug, Clone, PartialEq)]
pub struct Recovery {
    pub points: Vec<RecoveryPoint>,
    pub hot_spots: usize,
}

/// The recovery points the spec names (node sets, nearest nodes), each node once, in the
/// order given; refused with the field when a set does not exist, the part has no elements, or
/// there are more than `MAX_STRESS_POINTS`.
pub fn requested_points(file: &Path, request: &StressOutputs, part: &Part) -> Result<Recovery> {
    let field = "outputs.stress";
    if !part.has_elements() {
        return Err(BuildError::input(
            file,
            field,
            "stresses are recovered from the mesh's elements, and this part is given by matrices (geometry.matrices) \
             without elements: give the mesh (geometry.mesh) or leave outputs.stress out",
        ));
    }
    let used = element_nodes(part);
    let mut points: Vec<RecoveryPoint> = Vec::new();
    let mut push = |node: usize, origin: PointOrigin| {
        if used[node] && !points.iter().any(|p| p.node == node) {
            points.push(RecoveryPoint { node, origin });
        }
    };
    for (i, set) in request.node_sets.iter().enumerate() {
        let Some(nodes) = part.node_set(set) else {
            let known: Vec<&str> = part.node_sets.keys().map(|k| k.as_str()).collect();
            return Err(BuildError::input(
                file,
                format!("{field}.node_sets[{i}]"),
                format!(
                    "there is no node set \"{set}\" ({})",
                    if known.is_empty() {
                        "the part has no node sets".to_string()
                    } else {
                        format!("node sets: {}", known.join(", "))
                    }
                ),
            ));
        };
        for &n in nodes {
            push(n, PointOrigin::NodeSet(set.clone()));
        }
    }
    for given in &request.points {
        // given in geometry.length_unit (and named so), the mesh is in metres
        let q = &given.map(|c| c * part.length_scale);
        let distance = |n: usize| {
            let p = part.mesh.nodes[n];
            (0..3).map(|a| (p[a] - q[a]) * (p[a] - q[a])).sum::<f64>()
        };
        let nearest =
            (0..part.mesh.n_nodes()).filter(|&n| used[n]).min_by(|&a, &b| distance(a).total_cmp(&distance(b)));
        if let Some(n) = nearest {
            push(n, PointOrigin::Nearest(*given));
        }
    }
    let total = points.len() + request.hot_spots;
    if total > MAX_STRESS_POINTS {
        return Err(BuildError::input(
            file,
            field,
            format!(
                "{} recovery points ({} from node sets and points, {} hot spots): at most {MAX_STRESS_POINTS} \
                 (seven outputs each); name smaller node sets",
                total,
                points.len(),
                request.hot_spots
            ),
        ));
    }
    Ok(Recovery { points, hot_spots: request.hot_spots })
}

/// The `count` nodes with the highest von Mises stress over the unit load cases `fields` (3N x
/// cases, named by `cases`), each case's stresses relative to its own peak (a unit force and a
/// unit acceleration are not comparable otherwise); nodes `excluded` (tied to flanges) and
/// nodes already `chosen` are passed over.
pub fn hot_spots(
    part: &Part,
    fields: MatRef<'_, f64>,
    cases: &[String],
    excluded: &[bool],
    chosen: &[RecoveryPoint],
    count: usize,
) -> Result<Vec<RecoveryPoint>> {
    assert_eq!(cases.len(), fields.ncols());
    let used = element_nodes(part);
    let candidates: Vec<usize> = (0..part.mesh.n_nodes()).filter(|&n| used[n] && !excluded[n]).collect();
    let k = fields.ncols();
    let stresses = nodal_stresses(part, &candidates, fields)?;
    let mises: Vec<f64> = stresses.iter().map(von_mises).collect();
    let peaks: Vec<f64> =
        (0..k).map(|c| (0..candidates.len()).map(|i| mises[i * k + c]).fold(0.0f64, f64::max)).collect();
    let mut scored: Vec<(f64, usize, usize)> = candidates
        .iter()
        .enumerate()
        .filter(|(_, n)| !chosen.iter().any(|p| p.node == **n))
        .map(|(i, &n)| {
            let (share, case) = (0..k)
                .filter(|&c| peaks[c] > 0.0)
                .map(|c| (mises[i * k + c] / peaks[c], c))
                .fold((0.0, 0), |best, x| if x.0 > best.0 { x } else { best });
            (share, case, n)
        })
        .collect();
    // highest first; ties by node number, so the choice does not depend on the threads' sums
    scored.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.2.cmp(&b.2)));
    Ok(scored
        .into_iter()
        .take(count)
        .enumerate()
        .map(|(r, (share, case, node))| RecoveryPoint {
            node,
            origin: PointOrigin::HotSpot { rank: r + 1, case: cases.get(case).cloned().unwrap_or_default(), share },
        })
        .collect())
}
