//! Structured hexahedral meshing of a union of axis-aligned boxes.
//!
//! Each box gets a regular grid; boxes that touch share their interface
//! nodes. Interfaces must be conforming (no hanging nodes), boxes must not
//! overlap.
//!
//! Internally every box is described by a "lattice": along each axis the
//! element corner coordinates for hex8, or corners plus edge midpoints for
//! hex20 (two lattice intervals per element). For hex20 a lattice point is a
//! node only if at most one of its indices is odd (no face or body centres).

use crate::element::{ElementKind, MAX_NODES_PER_ELEMENT};
use std::collections::HashMap;

/// Axis-aligned box with the number of elements along each axis.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BoxRegion {
    pub min: [f64; 3],
    pub max: [f64; 3],
    pub divisions: [usize; 3],
}

/// A solid mesh, possibly of mixed element kinds and materials. `elements` is the flat
/// connectivity (CalculiX node order, positive Jacobian); element `e` owns
/// `elements[offsets[e]..offsets[e + 1]]`.
#[derive(Debug, Clone, PartialEq)]
pub struct Mesh {
    pub nodes: Vec<[f64; 3]>,
    pub elements: Vec<usize>,
    pub offsets: Vec<usize>,
    pub kinds: Vec<ElementKind>,
    /// Index of each element's material in the part's material table.
    pub material: Vec<usize>,
}

impl Mesh {
    /// An empty mesh (no nodes, no elements).
    pub fn empty() -> Self {
        Self { nodes: Vec::new(), elements: Vec::new(), offsets: vec![0], kinds: Vec::new(), material: Vec::new() }
    }

    /// Nodes without elements: a part given by its matrices.
    pub fn nodes_only(nodes: Vec<[f64; 3]>) -> Self {
        Self { nodes, ..Self::empty() }
    }

    /// Appends an element (its node count must be the kind's).
    pub fn push_element(&mut self, kind: ElementKind, nodes: &[usize], material: usize) {
        debug_assert_eq!(nodes.len(), kind.nodes_per_element());
        self.elements.extend_from_slice(nodes);
        self.offsets.push(self.elements.len());
        self.kinds.push(kind);
        self.material.push(material);
    }

    pub fn n_nodes(&self) -> usize {
        self.nodes.len()
    }

    pub fn n_elements(&self) -> usize {
        self.kinds.len()
    }

    pub fn kind(&self, i: usize) -> ElementKind {
        self.kinds[i]
    }

    /// The element kinds present, in first-use order (for reports).
    pub fn kind_names(&self) -> String {
        let mut seen: Vec<ElementKind> = Vec::new();
        for &k in &self.kinds {
            if !seen.contains(&k) {
                seen.push(k);
            }
        }
        seen.iter().map(|k| k.name()).collect::<Vec<_>>().join(", ")
    }

    /// The faces of the mesh's surface, each met by one element only: (element, face index into
    /// its kind's `corner_faces`), ascending (the same order run to run).
    pub fn boundary_faces(&self) -> Vec<(usize, usize)> {
        let mut count: HashMap<Vec<usize>, (usize, (usize, usize))> = HashMap::new();
        for e in 0..self.n_elements() {
            let conn = self.element(e);
            for (f, face) in self.kind(e).corner_faces().iter().enumerate() {
                let mut key: Vec<usize> = face.iter().map(|&i| conn[i]).collect();
                key.sort_unstable();
                count.entry(key).and_modify(|c| c.0 += 1).or_insert((1, (e, f)));
            }
        }
        let mut out: Vec<(usize, usize)> = count.into_values().filter(|c| c.0 == 1).map(|c| c.1).collect();
        out.sort_unstable();
        out
    }

    /// Node indices of element `i`. Panics if `i >= n_elements()` (a caller
    /// bug, not a user-input condition).
    pub fn element(&self, i: usize) -> &[usize] {
        &self.elements[self.offsets[i]..self.offsets[i + 1]]
    }

    /// Coordinates of the nodes of element `i`, written into a stack buffer
    /// so assembly loops need not allocate; returns the filled prefix.
    pub fn element_coords<'a>(&self, i: usize, buf: &'a mut [[f64; 3]; MAX_NODES_PER_ELEMENT]) -> &'a [[f64; 3]] {
        let conn = self.element(i);
        for (slot, &node) in buf.iter_mut().zip(conn) {
            *slot = self.nodes[node];
        }
        &buf[..conn.len()]
    }
}

/// What is wrong with a single box.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum BoxProblem {
    NonFinite,
    /// `min >= max` along the axis.
    NonPositiveExtent {
        min: f64,
        max: f64,
    },
    ZeroDivisions,
}

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MeshError {
    #[error("geometry has no boxes")]
    NoBoxes,
    /// Box `box_index` is unusable along `axis` (0 = x, 1 = y, 2 = z).
    #[error("box {box_index}: {}", box_problem(*.axis, .problem))]
    DegenerateBox { box_index: usize, axis: usize, problem: BoxProblem },
    /// The interiors of the two boxes intersect.
    #[error("boxes {first} and {second} overlap; boxes may only touch")]
    Overlap { first: usize, second: usize },
    /// A node of box `node_box` at `point` lies on the interface with box
    /// `other_box`, but `other_box` has no node there (hanging node).
    #[error(
        "boxes {node_box} and {other_box} touch with non-matching meshes: node of box {node_box} at ({}, {}, {}) has \
         no counterpart in box {other_box}; adjust the divisions so the grids coincide on the shared face",
        .point[0], .point[1], .point[2]
    )]
    NonConforming { node_box: usize, other_box: usize, point: [f64; 3] },
    /// Node or element count of the box does not fit in memory.
    #[error("box {box_index}: too many elements to mesh")]
    TooLarge { box_index: usize },
    /// The box mesher builds hexahedra only; tetrahedral meshes are imported.
    #[error("the box mesher cannot build {kind} elements (only hex8, hex20 and hex20r)")]
    UnsupportedElement { kind: ElementKind },
}

const AXIS_NAMES: [&str; 3] = ["x", "y", "z"];

fn box_problem(axis: usize, problem: &BoxProblem) -> String {
    let a = AXIS_NAMES.get(axis).copied().unwrap_or("?");
    match problem {
        BoxProblem::NonFinite => format!("{a} bounds are not finite numbers"),
        BoxProblem::NonPositiveExtent { min, max } => format!("{a} extent is empty (min {min} >= max {max})"),
        BoxProblem::ZeroDivisions => format!("number of elements along {a} must be at least 1"),
    }
}

/// Meshes the union of `boxes` with elements of `kind`, merging coincident
/// nodes of touching boxes.
pub fn mesh_boxes(boxes: &[BoxRegion], kind: ElementKind) -> Result<Mesh, MeshError> {
    if boxes.is_empty() {
        return Err(MeshError::NoBoxes);
    }
    let step = lattice_step(kind).ok_or(MeshError::UnsupportedElement { kind })?;
    for (i, b) in boxes.iter().enumerate() {
        validate_box(i, b)?;
        check_size(i, b, step)?;
    }
    let lattices: Vec<Lattice> = boxes.iter().map(|b| Lattice::new(b, step)).collect();
    // Relative to the smallest element edge: far below any node spacing, far
    // above rounding noise of the box coordinates.
    let min_edge = boxes
        .iter()
        .flat_map(|b| (0..3).map(move |a| (b.max[a] - b.min[a]) / b.divisions[a] as f64))
        .fold(f64::INFINITY, f64::min);
    let tol = 1e-6 * min_edge;

    for i in 0..boxes.len() {
        for j in i + 1..boxes.len() {
            check_pair(i, j, &lattices[i], &lattices[j], tol)?;
        }
    }

    let mut mesh = Mesh::empty();
    let mut interface_nodes = NodeHash::new(tol);
    for (box_index, lattice) in lattices.iter().enumerate() {
        add_box(&mut mesh, kind, box_index, lattice, &boxes[box_index], &mut interface_nodes)?;
    }
    Ok(mesh)
}

fn validate_box(box_index: usize, b: &BoxRegion) -> Result<(), MeshError> {
    for axis in 0..3 {
        let (min, max) = (b.min[axis], b.max[axis]);
        let problem = if !(min.is_finite() && max.is_finite()) {
            BoxProblem::NonFinite
        } else if min >= max {
            BoxProblem::NonPositiveExtent { min, max }
        } else if b.divisions[axis] == 0 {
            BoxProblem::ZeroDivisions
        } else {
            continue;
        };
        return Err(MeshError::DegenerateBox { box_index, axis, problem });
    }
    Ok(())
}

/// Upper bound on lattice points per box. Far beyond any mesh this tool can
/// solve, but it keeps the interface checks and index arithmetic bounded
/// before any memory is reserved.
const MAX_LATTICE_POINTS: usize = 1 << 31;

fn check_size(box_index: usize, b: &BoxRegion, step: usize) -> Result<(), MeshError> {
    let points = b.divisions.iter().try_fold(1usize, |acc, &d| {
        d.checked_mul(step).and_then(|m| m.checked_add(1)).and_then(|p| acc.checked_mul(p))
    });
    match points {
        Some(p) if p <= MAX_LATTICE_POINTS => Ok(()),
        _ => Err(MeshError::TooLarge { box_index }),
    }
}

/// Lattice intervals per element edge; `None` for kinds the box mesher
/// cannot build.
fn lattice_step(kind: ElementKind) -> Option<usize> {
    match kind {
        ElementKind::Hex8 => Some(1),
        ElementKind::Hex20 | ElementKind::Hex20R => Some(2),
        ElementKind::Tet4 | ElementKind::Tet10 => None,
    }
}

/// Regular lattice of one box.
struct Lattice {
    min: [f64; 3],
    max: [f64; 3],
    /// Lattice intervals per axis (`divisions * step`).
    intervals: [usize; 3],
    /// Whether odd lattice indices are edge midpoints (hex20).
    quadratic: bool,
}

impl Lattice {
    fn new(b: &BoxRegion, step: usize) -> Self {
        Lattice {
            min: b.min,
            max: b.max,
            // Sizes were checked by `check_size`; saturation is belt and braces.
            intervals: b.divisions.map(|d| d.saturating_mul(step)),
            quadratic: step == 2,
        }
    }

    fn coord(&self, axis: usize, i: usize) -> f64 {
        let m = self.intervals[axis];
        // The last point is set exactly so that touching boxes agree bit for
        // bit on their shared plane.
        if i == m { self.max[axis] } else { self.min[axis] + (self.max[axis] - self.min[axis]) * (i as f64 / m as f64) }
    }

    fn is_node(&self, idx: [usize; 3]) -> bool {
        !self.quadratic || idx.iter().filter(|&&i| i % 2 == 1).count() <= 1
    }

    /// Lattice index along `axis` whose coordinate is within `tol` of `x`.
    fn index_near(&self, axis: usize, x: f64, tol: f64) -> Option<usize> {
        let m = self.intervals[axis];
        let t = (x - self.min[axis]) / (self.max[axis] - self.min[axis]) * m as f64;
        if !(t > -1.0 && t < m as f64 + 1.0) {
            return None;
        }
        let i = (t.round().max(0.0) as usize).min(m);
        ((self.coord(axis, i) - x).abs() <= tol).then_some(i)
    }

    /// Lattice indices along `axis` with coordinates in `[lo - tol, hi + tol]`.
    fn indices_within(&self, axis: usize, lo: f64, hi: f64, tol: f64) -> Vec<usize> {
        let m = self.intervals[axis];
        let scale = m as f64 / (self.max[axis] - self.min[axis]);
        let first = ((lo - tol - self.min[axis]) * scale).floor().max(0.0) as usize;
        let last = (((hi + tol - self.min[axis]) * scale).ceil().max(0.0) as usize).min(m);
        (first..=last)
            .filter(|&i| {
                let x = self.coord(axis, i);
                x >= lo - tol && x <= hi + tol
            })
            .collect()
    }
}

/// Refuses overlapping boxes and, for touching boxes, any node of either box
/// on the contact region (face, edge or point) without a node of the other.
fn check_pair(i: usize, j: usize, a: &Lattice, b: &Lattice, tol: f64) -> Result<(), MeshError> {
    let mut lo = [0.0; 3];
    let mut hi = [0.0; 3];
    for axis in 0..3 {
        lo[axis] = a.min[axis].max(b.min[axis]);
        hi[axis] = a.max[axis].min(b.max[axis]);
        if hi[axis] - lo[axis] < -tol {
            return Ok(()); // separated along this axis
        }
    }
    if (0..3).all(|axis| hi[axis] - lo[axis] > tol) {
        return Err(MeshError::Overlap { first: i, second: j });
    }
    check_nodes_matched((i, a), (j, b), lo, hi, tol)?;
    check_nodes_matched((j, b), (i, a), lo, hi, tol)
}

/// Every node of `own` in the contact region `[lo, hi]` must coincide with a
/// node of `other`.
fn check_nodes_matched(
    (own_index, own): (usize, &Lattice),
    (other_index, other): (usize, &Lattice),
    lo: [f64; 3],
    hi: [f64; 3],
    tol: f64,
) -> Result<(), MeshError> {
    let candidates: [Vec<usize>; 3] = [0, 1, 2].map(|axis| own.indices_within(axis, lo[axis], hi[axis], tol));
    for &i in &candidates[0] {
        for &j in &candidates[1] {
            for &k in &candidates[2] {
                let idx = [i, j, k];
                if !own.is_node(idx) {
                    continue;
                }
                let point = [own.coord(0, i), own.coord(1, j), own.coord(2, k)];
                let matched = [0, 1, 2].map(|axis| other.index_near(axis, point[axis], tol));
                let coincides = match matched {
                    [Some(a), Some(b), Some(c)] => other.is_node([a, b, c]),
                    _ => false,
                };
                if !coincides {
                    return Err(MeshError::NonConforming { node_box: own_index, other_box: other_index, point });
                }
            }
        }
    }
    Ok(())
}

/// Spatial hash of nodes on box boundaries; only those can be shared, so
/// interior nodes never enter it. Cells are `tol` wide, so a node within
/// `tol` (per axis) of a stored one is found in one of the 27 cells around.
struct NodeHash {
    tol: f64,
    cells: HashMap<[i64; 3], usize>,
}

impl NodeHash {
    fn new(tol: f64) -> Self {
        NodeHash { tol, cells: HashMap::new() }
    }

    fn cell(&self, p: [f64; 3]) -> [i64; 3] {
        // `as` saturates, so absurd coordinates cannot panic.
        p.map(|x| (x / self.tol).floor() as i64)
    }

    fn find(&self, p: [f64; 3], nodes: &[[f64; 3]]) -> Option<usize> {
        let c = self.cell(p);
        for dz in -1..=1 {
            for dy in -1..=1 {
                for dx in -1..=1 {
                    let key = [c[0].saturating_add(dx), c[1].saturating_add(dy), c[2].saturating_add(dz)];
                    if let Some(&id) = self.cells.get(&key) {
                        let q = nodes[id];
                        if (0..3).all(|a| (q[a] - p[a]).abs() <= self.tol) {
                            return Some(id);
                        }
                    }
                }
            }
        }
        None
    }

    fn insert(&mut self, p: [f64; 3], id: usize) {
        let key = self.cell(p);
        self.cells.entry(key).or_insert(id);
    }
}

fn add_box(
    mesh: &mut Mesh,
    kind: ElementKind,
    box_index: usize,
    lattice: &Lattice,
    region: &BoxRegion,
    interface_nodes: &mut NodeHash,
) -> Result<(), MeshError> {
    let too_large = || MeshError::TooLarge { box_index };
    let [mx, my, mz] = lattice.intervals;
    let points = [mx, my, mz]
        .iter()
        .try_fold(1usize, |acc, &m| m.checked_add(1).and_then(|p| acc.checked_mul(p)))
        .ok_or_else(too_large)?;
    let npe = kind.nodes_per_element();
    let element_entries = region.divisions.iter().try_fold(npe, |acc, &d| acc.checked_mul(d)).ok_or_else(too_large)?;

    // Lattice point -> global node id (usize::MAX for face/body centres).
    let mut local = Vec::new();
    local.try_reserve_exact(points).map_err(|_| too_large())?;
    mesh.nodes.try_reserve(points).map_err(|_| too_large())?;
    mesh.elements.try_reserve(element_entries).map_err(|_| too_large())?;

    for k in 0..=mz {
        for j in 0..=my {
            for i in 0..=mx {
                let idx = [i, j, k];
                if !lattice.is_node(idx) {
                    local.push(usize::MAX);
                    continue;
                }
                let p = [lattice.coord(0, i), lattice.coord(1, j), lattice.coord(2, k)];
                let on_boundary = idx.iter().zip(lattice.intervals).any(|(&v, m)| v == 0 || v == m);
                let existing = if on_boundary { interface_nodes.find(p, &mesh.nodes) } else { None };
                let id = match existing {
                    Some(id) => id,
                    None => {
                        let id = mesh.nodes.len();
                        mesh.nodes.push(p);
                        if on_boundary {
                            interface_nodes.insert(p, id);
                        }
                        id
                    }
                };
                local.push(id);
            }
        }
    }

    let unsupported = MeshError::UnsupportedElement { kind };
    let step = lattice_step(kind).ok_or(unsupported.clone())?;
    let natural = kind.natural_node_coords().ok_or(unsupported)?;
    let [dx, dy, dz] = region.divisions;
    let flat = |i: usize, j: usize, k: usize| i + (mx + 1) * (j + (my + 1) * k);
    for ez in 0..dz {
        for ey in 0..dy {
            for ex in 0..dx {
                for c in natural {
                    // Natural coordinate -1 / 0 / +1 -> lattice offset within the
                    // element 0 / step/2 / step (0 only occurs for hex20 midsides).
                    let off = |e: usize, v: i8| {
                        e * step
                            + match v {
                                ..0 => 0,
                                0 => step / 2,
                                _ => step,
                            }
                    };
                    mesh.elements.push(local[flat(off(ex, c[0]), off(ey, c[1]), off(ez, c[2]))]);
                }
                mesh.offsets.push(mesh.elements.len());
                mesh.kinds.push(kind);
                mesh.material.push(0);
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cube(min: [f64; 3], max: [f64; 3], divisions: [usize; 3]) -> BoxRegion {
        BoxRegion { min, max, divisions }
    }

    /// Corner grid plus one midpoint per element edge.
    fn hex20_node_count(n: [usize; 3]) -> usize {
        let [x, y, z] = n;
        (x + 1) * (y + 1) * (z + 1) + x * (y + 1) * (z + 1) + (x + 1) * y * (z + 1) + (x + 1) * (y + 1) * z
    }

    /// Sum of element volumes. Fails unless every element is an axis-aligned
    /// brick with each node at `x0 + (xi + 1) h / 2` for its natural
    /// coordinates `xi` and all `h > 0`: an isoparametric map with a positive
    /// Jacobian.
    fn mesh_volume(mesh: &Mesh) -> f64 {
        let mut buf = [[0.0; 3]; MAX_NODES_PER_ELEMENT];
        (0..mesh.n_elements())
            .map(|e| {
                let kind = mesh.kind(e);
                let coords = mesh.element_coords(e, &mut buf);
                let natural = kind.natural_node_coords().expect("hexahedron");
                assert_eq!(coords.len(), natural.len());
                let (lo, hi) = (coords[0], coords[6]);
                let h = [0, 1, 2].map(|d| hi[d] - lo[d]);
                assert!(h.iter().all(|&h| h > 0.0), "element {e}: extents {h:?}");
                for (a, (p, xi)) in coords.iter().zip(natural).enumerate() {
                    for d in 0..3 {
                        let want = lo[d] + 0.5 * f64::from(xi[d] + 1) * h[d];
                        assert!((p[d] - want).abs() < 1e-12, "element {e} node {a}");
                    }
                }
                h.iter().product::<f64>()
            })
            .sum()
    }

    fn assert_elements_well_formed(mesh: &Mesh) {
        for e in 0..mesh.n_elements() {
            let conn = mesh.element(e);
            let mut sorted = conn.to_vec();
            sorted.sort_unstable();
            sorted.dedup();
            assert_eq!(sorted.len(), conn.len(), "element {e} repeats a node");
            assert!(conn.iter().all(|&n| n < mesh.n_nodes()));
        }
    }

    #[test]
    fn single_box_counts() {
        let n = [3, 2, 4];
        let b = cube([0.0, -1.0, 2.0], [1.5, 1.0, 3.0], n);
        let hex8 = mesh_boxes(&[b], ElementKind::Hex8).unwrap();
        assert_eq!(hex8.n_nodes(), 4 * 3 * 5);
        assert_eq!(hex8.n_elements(), 24);
        let hex20 = mesh_boxes(&[b], ElementKind::Hex20).unwrap();
        assert_eq!(hex20.n_nodes(), hex20_node_count(n));
        // Same count via the lattice: (2n+1)^3 minus face centres and body centres.
        let full: usize = n.iter().map(|&d| 2 * d + 1).product();
        let face_centres = n[0] * n[1] * (n[2] + 1) + n[1] * n[2] * (n[0] + 1) + n[2] * n[0] * (n[1] + 1);
        assert_eq!(hex20.n_nodes(), full - face_centres - n[0] * n[1] * n[2]);
        assert_eq!(hex20.n_elements(), 24);
        for mesh in [&hex8, &hex20] {
            assert_elements_well_formed(mesh);
            assert!((mesh_volume(mesh) - 3.0).abs() < 1e-12, "{}", mesh.kind(0));
        }
    }

    #[test]
    fn hex20_midside_nodes_sit_between_their_corners() {
        let mesh = mesh_boxes(&[cube([0.0; 3], [2.0, 1.0, 1.0], [2, 1, 1])], ElementKind::Hex20).unwrap();
        // (midside, corner a, corner b) in 0-based C3D20 numbering.
        let edges = [
            (8, 0, 1),
            (9, 1, 2),
            (10, 2, 3),
            (11, 3, 0),
            (12, 4, 5),
            (13, 5, 6),
            (14, 6, 7),
            (15, 7, 4),
            (16, 0, 4),
            (17, 1, 5),
            (18, 2, 6),
            (19, 3, 7),
        ];
        for e in 0..mesh.n_elements() {
            let c = mesh.element(e);
            for &(m, a, b) in &edges {
                let (pm, pa, pb) = (mesh.nodes[c[m]], mesh.nodes[c[a]], mesh.nodes[c[b]]);
                for axis in 0..3 {
                    assert!((pm[axis] - 0.5 * (pa[axis] + pb[axis])).abs() < 1e-12, "element {e} edge {m}");
                }
            }
        }
    }

    #[test]
    fn l_shape_shares_interface_nodes() {
        // Box 1 sits on top of the left half of box 0; shared face y = 1, x in [0, 1].
        let boxes = [cube([0.0; 3], [2.0, 1.0, 1.0], [2, 1, 1]), cube([0.0, 1.0, 0.0], [1.0, 2.0, 1.0], [1, 1, 1])];
        let hex8 = mesh_boxes(&boxes, ElementKind::Hex8).unwrap();
        assert_eq!(hex8.n_nodes(), 12 + 8 - 4);
        let hex20 = mesh_boxes(&boxes, ElementKind::Hex20).unwrap();
        assert_eq!(hex20.n_nodes(), hex20_node_count([2, 1, 1]) + hex20_node_count([1, 1, 1]) - 8);
        for mesh in [&hex8, &hex20] {
            assert_eq!(mesh.n_elements(), 3);
            assert_elements_well_formed(mesh);
            assert!((mesh_volume(mesh) - 3.0).abs() < 1e-12);
            // No two nodes coincide after merging.
            let mut keys: Vec<[i64; 3]> = mesh.nodes.iter().map(|p| p.map(|x| (x * 1e6).round() as i64)).collect();
            keys.sort_unstable();
            keys.dedup();
            assert_eq!(keys.len(), mesh.n_nodes());
        }
    }

    #[test]
    fn union_volume_of_three_boxes() {
        // A T-shape with refined but matching grids and a non-unit offset.
        let boxes = [
            cube([-1.0, 0.0, 0.0], [2.0, 0.5, 0.3], [6, 2, 2]),
            cube([0.0, 0.5, 0.0], [1.0, 2.0, 0.3], [2, 3, 2]),
            cube([0.0, 2.0, 0.0], [1.0, 2.5, 0.3], [2, 1, 2]),
        ];
        for kind in [ElementKind::Hex8, ElementKind::Hex20] {
            let mesh = mesh_boxes(&boxes, kind).unwrap();
            let volume = 3.0 * 0.5 * 0.3 + 1.5 * 0.3 + 0.5 * 0.3;
            assert!((mesh_volume(&mesh) - volume).abs() < 1e-12, "{kind}");
            assert_elements_well_formed(&mesh);
        }
    }

    #[test]
    fn hanging_nodes_are_refused() {
        let base = cube([0.0; 3], [1.0; 3], [1, 1, 1]);
        for kind in [ElementKind::Hex8, ElementKind::Hex20] {
            // Finer grid on one side of the shared face x = 1.
            let finer = cube([1.0, 0.0, 0.0], [2.0, 1.0, 1.0], [1, 2, 1]);
            match mesh_boxes(&[base, finer], kind) {
                Err(MeshError::NonConforming { node_box: 1, other_box: 0, point }) => {
                    assert!((point[0] - 1.0).abs() < 1e-12 && point[1] > 0.0 && point[1] < 1.0, "{point:?}");
                }
                other => panic!("{kind}: expected NonConforming, got {other:?}"),
            }
            // Shifted box: its corner lands inside the face of box 0.
            let shifted = cube([1.0, 0.5, 0.0], [2.0, 1.5, 1.0], [1, 1, 1]);
            let err = mesh_boxes(&[base, shifted], kind).unwrap_err();
            assert!(matches!(err, MeshError::NonConforming { .. }), "{kind}: {err}");
            assert!(err.to_string().contains("boxes 0 and 1") || err.to_string().contains("boxes 1 and 0"), "{err}");
        }
    }

    #[test]
    fn hex20_half_element_offset_is_refused() {
        // Every coordinate along y matches (0 1 2 vs 1 2 3 lattice), but box 0's
        // midside at y = 1 faces box 1's corner: only the node-type check sees it.
        let a = cube([0.0; 3], [1.0, 2.0, 1.0], [1, 1, 1]);
        let b = cube([1.0, 1.0, 0.0], [2.0, 3.0, 1.0], [1, 1, 1]);
        let err = mesh_boxes(&[a, b], ElementKind::Hex20).unwrap_err();
        assert!(matches!(err, MeshError::NonConforming { .. }), "{err}");
    }

    #[test]
    fn overlapping_boxes_are_refused() {
        let a = cube([0.0; 3], [1.0; 3], [2, 2, 2]);
        let b = cube([0.5, 0.5, 0.5], [1.5, 1.5, 1.5], [2, 2, 2]);
        let separate = cube([5.0; 3], [6.0; 3], [1, 1, 1]);
        let inner = cube([0.25; 3], [0.75; 3], [1, 1, 1]);
        assert_eq!(mesh_boxes(&[separate, a, b], ElementKind::Hex8), Err(MeshError::Overlap { first: 1, second: 2 }));
        assert_eq!(mesh_boxes(&[a, inner], ElementKind::Hex20), Err(MeshError::Overlap { first: 0, second: 1 }));
        // Disjoint boxes are fine and share nothing.
        let mesh = mesh_boxes(&[a, separate], ElementKind::Hex8).unwrap();
        assert_eq!(mesh.n_nodes(), 27 + 8);
    }

    #[test]
    fn degenerate_boxes_are_refused() {
        let good = cube([0.0; 3], [1.0; 3], [1, 1, 1]);
        let flat = cube([0.0; 3], [1.0, 0.0, 1.0], [1, 1, 1]);
        let no_div = cube([0.0; 3], [1.0; 3], [1, 1, 0]);
        let nan = cube([0.0, 0.0, f64::NAN], [1.0; 3], [1, 1, 1]);
        assert!(matches!(
            mesh_boxes(&[good, flat], ElementKind::Hex8),
            Err(MeshError::DegenerateBox { box_index: 1, axis: 1, problem: BoxProblem::NonPositiveExtent { .. } })
        ));
        assert!(matches!(
            mesh_boxes(&[no_div], ElementKind::Hex20),
            Err(MeshError::DegenerateBox { box_index: 0, axis: 2, problem: BoxProblem::ZeroDivisions })
        ));
        assert!(matches!(
            mesh_boxes(&[good, good, nan], ElementKind::Hex8),
            Err(MeshError::DegenerateBox { box_index: 2, axis: 2, problem: BoxProblem::NonFinite })
        ));
        assert_eq!(mesh_boxes(&[], ElementKind::Hex8), Err(MeshError::NoBoxes));
        let huge = cube([0.0; 3], [1.0; 3], [usize::MAX, 2, 2]);
        assert!(matches!(mesh_boxes(&[huge], ElementKind::Hex20), Err(MeshError::TooLarge { box_index: 0 })));
        // Large but not overflowing, touching another box: refused before the
        // interface check would enumerate its face.
        let big = cube([1.0, 0.0, 0.0], [2.0, 1.0, 1.0], [1, 1 << 20, 1 << 20]);
        assert!(matches!(mesh_boxes(&[good, big], ElementKind::Hex8), Err(MeshError::TooLarge { box_index: 1 })));
    }

    /// Tetrahedra come from imported meshes only; hex20r shares hex20's nodes.
    #[test]
    fn box_mesher_builds_hexahedra_only() {
        let good = cube([0.0; 3], [1.0; 3], [2, 1, 1]);
        for kind in [ElementKind::Tet4, ElementKind::Tet10] {
            let err = mesh_boxes(&[good], kind).unwrap_err();
            assert_eq!(err, MeshError::UnsupportedElement { kind });
            assert!(err.to_string().contains(kind.name()), "{err}");
        }
        let hex20 = mesh_boxes(&[good], ElementKind::Hex20).unwrap();
        let hex20r = mesh_boxes(&[good], ElementKind::Hex20R).unwrap();
        assert!(hex20r.kinds.iter().all(|&k| k == ElementKind::Hex20R));
        assert_eq!((hex20r.nodes, hex20r.elements), (hex20.nodes, hex20.elements));
    }

    #[test]
    fn merges_a_million_nodes_quickly() {
        // Two touching 50x50x200-element boxes: ~1.05 million nodes in total.
        let a = cube([0.0; 3], [1.0, 1.0, 2.0], [50, 50, 200]);
        let b = cube([1.0, 0.0, 0.0], [2.0, 1.0, 2.0], [50, 50, 200]);
        let start = std::time::Instant::now();
        let mesh = mesh_boxes(&[a, b], ElementKind::Hex8).unwrap();
        assert_eq!(mesh.n_nodes(), 2 * 51 * 51 * 201 - 51 * 201);
        assert!(start.elapsed().as_secs_f64() < 10.0, "took {:?}", start.elapsed());
    }
}
