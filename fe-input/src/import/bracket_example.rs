//! Checks of the Gmsh-generated bracket example (`examples/bracket/`): the
//! `.msh` (MSH 4.1) and `.inp` (Abaqus) exports of one tet10 mesh must be
//! read by the importers as the same mesh, with the bolt-hole node sets on
//! the hole cylinders and the CAD volume.
//!
//! Geometry (metres, see `examples/bracket/bracket.geo`): base plate
//! `[0, 0.080] x [0, 0.040] x [0, 0.006]`, upright `[0, 0.006] x [0, 0.040] x
//! [0, 0.060]`, inner fillet of radius 0.004 along `x = z = 0.006`, holes of
//! radius 0.00425: BOLT_BASE on the axis through (0.055, 0.020, 0) along z,
//! BOLT_ARM on the axis through (0, 0.020, 0.040) along x.
//!
//! Gmsh places the midside nodes on the CAD geometry, so the element edges on
//! the hole cylinders and on the fillet are curved; all other edges are
//! straight.

use super::test_util::assert_midsides_at_midpoints;
use super::{ImportedMesh, read_mesh};
use crate::element::ElementKind;
use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::f64::consts::PI;
use std::path::PathBuf;

const HOLE_R: f64 = 0.00425;
const FILLET_R: f64 = 0.004;
/// Gmsh writes `.msh` coordinates with `%.16g` but `.inp` coordinates with
/// `%.14g` (14 significant digits): for coordinates below 0.1 m the two
/// differ by up to 5e-16 m.
const COORD_TOL: f64 = 1e-15;
/// Distance tolerance for "lies on a CAD surface" (observed: ~1e-17).
const ON_SURFACE_TOL: f64 = 1e-12;

/// CAD volume: union of the plates + fillet material - two holes.
fn cad_volume() -> f64 {
    0.080 * 0.040 * 0.006 + 0.006 * 0.040 * 0.054 + (1.0 - PI / 4.0) * FILLET_R * FILLET_R * 0.040
        - 2.0 * PI * HOLE_R * HOLE_R * 0.006
}

fn example(file: &str) -> PathBuf {
    PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../examples/bracket/")).join(file)
}

fn load(file: &str) -> ImportedMesh {
    let path = example(file);
    read_mesh(&path).unwrap_or_else(|e| panic!("cannot import {}: {e}", path.display()))
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn det3(a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> f64 {
    a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) + a[2] * (b[0] * c[1] - b[1] * c[0])
}

/// Distance of `p` from the base hole axis (through (0.055, 0.020, z), along z).
fn r_base(p: [f64; 3]) -> f64 {
    (p[0] - 0.055).hypot(p[1] - 0.020)
}

/// Distance of `p` from the upright hole axis (through (x, 0.020, 0.040), along x).
fn r_arm(p: [f64; 3]) -> f64 {
    (p[1] - 0.020).hypot(p[2] - 0.040)
}

fn on_base_hole(p: [f64; 3]) -> bool {
    (r_base(p) - HOLE_R).abs() < ON_SURFACE_TOL && (-1e-12..=0.006 + 1e-12).contains(&p[2])
}

fn on_arm_hole(p: [f64; 3]) -> bool {
    (r_arm(p) - HOLE_R).abs() < ON_SURFACE_TOL && (-1e-12..=0.006 + 1e-12).contains(&p[0])
}

/// On the fillet: the quarter cylinder of radius 0.004 around the axis
/// through (0.010, y, 0.010) along y, between x = 0.006 and z = 0.006.
fn on_fillet(p: [f64; 3]) -> bool {
    ((p[0] - 0.010).hypot(p[2] - 0.010) - FILLET_R).abs() < ON_SURFACE_TOL
        && p[0] <= 0.010 + 1e-12
        && p[2] <= 0.010 + 1e-12
}

/// Node ids of each element in connectivity order.
fn element_id_tuples(mesh: &ImportedMesh) -> Vec<Vec<u64>> {
    mesh.connectivity.iter().map(|c| c.iter().map(|&i| mesh.node_ids[i]).collect()).collect()
}

/// Sorted node ids of an element -> its node ids in connectivity order.
fn elements_by_node_set(mesh: &ImportedMesh) -> BTreeMap<Vec<u64>, Vec<u64>> {
    let mut map = BTreeMap::new();
    for ids in element_id_tuples(mesh) {
        let mut key = ids.clone();
        key.sort_unstable();
        assert!(map.insert(key, ids).is_none(), "two elements on the same nodes");
    }
    map
}

fn node_set_ids(mesh: &ImportedMesh, name: &str) -> BTreeSet<u64> {
    mesh.node_sets
        .get(name)
        .unwrap_or_else(|| panic!("node set {name} missing (have {:?})", mesh.node_sets.keys().collect::<Vec<_>>()))
        .iter()
        .map(|&i| mesh.node_ids[i])
        .collect()
}

/// Gradients of the 10 C3D10 shape functions with respect to the volume
/// coordinates (L1..L4) at `l`; corners `L_i (2 L_i - 1)`, midsides
/// `4 L_a L_b` on the edges 1-2, 2-3, 3-1, 1-4, 2-4, 3-4.
fn tet10_dn_dl(l: [f64; 4]) -> [[f64; 4]; 10] {
    let mut d = [[0.0; 4]; 10];
    for i in 0..4 {
        d[i][i] = 4.0 * l[i] - 1.0;
    }
    for (k, &(a, b)) in ElementKind::Tet10.midside_edges().iter().enumerate() {
        d[4 + k][a] = 4.0 * l[b];
        d[4 + k][b] = 4.0 * l[a];
    }
    d
}

/// Jacobian determinant of the isoparametric tet10 map at volume
/// coordinates `l` (reference coordinates xi_j = L_{j+1}).
fn tet10_det_j(x: &[[f64; 3]], l: [f64; 4]) -> f64 {
    let d = tet10_dn_dl(l);
    let mut cols = [[0.0; 3]; 3]; // cols[j] = dx/dxi_j
    for (n, xn) in x.iter().enumerate() {
        for (j, col) in cols.iter_mut().enumerate() {
            let g = d[n][j + 1] - d[n][0];
            for r in 0..3 {
                col[r] += g * xn[r];
            }
        }
    }
    det3(cols[0], cols[1], cols[2])
}

/// Volume of an isoparametric (possibly curved) tet10: det J is a cubic in
/// the reference coordinates, integrated exactly by the 5-point degree-3
/// rule (centroid weight -4/5, (1/2, 1/6, 1/6, 1/6) weights 9/20, times the
/// reference volume 1/6). Also returns the smallest det J at the corners and
/// the quadrature points, relative to the corner-tet det J.
fn tet10_volume(x: &[[f64; 3]]) -> (f64, f64) {
    let lin = det3(sub(x[1], x[0]), sub(x[2], x[0]), sub(x[3], x[0]));
    let mut v = -0.8 / 6.0 * tet10_det_j(x, [0.25; 4]);
    let mut min_ratio = tet10_det_j(x, [0.25; 4]) / lin;
    for i in 0..4 {
        let mut q = [1.0 / 6.0; 4];
        q[i] = 0.5;
        let dj = tet10_det_j(x, q);
        v += 0.45 / 6.0 * dj;
        min_ratio = min_ratio.min(dj / lin);
        let mut c = [0.0; 4];
        c[i] = 1.0;
        min_ratio = min_ratio.min(tet10_det_j(x, c) / lin);
    }
    (v, min_ratio)
}

/// Volume between a circular arc of radius `r` split into `n` segments over
/// the angle `phi` and (a) its chords, (b) the parabolas through the end and
/// arc-midpoint nodes (curved quadratic edges), per unit length of the
/// cylinder.
fn arc_defects(r: f64, n: usize, phi: f64) -> (f64, f64) {
    let th = phi / n as f64;
    let circ = 0.5 * r * r * (th - th.sin());
    let parab = 2.0 / 3.0 * (2.0 * r * (0.5 * th).sin()) * (r * (1.0 - (0.5 * th).cos()));
    (n as f64 * circ, n as f64 * (circ - parab))
}

#[test]
fn bracket_msh_and_inp_describe_the_same_tet10_mesh() {
    let msh = load("bracket.msh");
    let inp = load("bracket.inp");

    // Element types.
    for (name, m) in [("msh", &msh), ("inp", &inp)] {
        assert!(m.num_elements() > 0, "{name}: no elements");
        assert!(m.element_types.iter().all(|&t| t == ElementKind::Tet10), "{name}: not all elements are C3D10");
    }
    assert_eq!(msh.num_elements(), inp.num_elements());
    assert!((2000..=6000).contains(&msh.num_nodes()), "{} nodes", msh.num_nodes());

    // Nodes: same ids, same coordinates (to the .inp print precision).
    assert_eq!(msh.num_nodes(), inp.num_nodes());
    let inp_index: HashMap<u64, usize> = inp.node_ids.iter().enumerate().map(|(i, &id)| (id, i)).collect();
    assert_eq!(inp_index.len(), inp.num_nodes());
    let mut max_diff: f64 = 0.0;
    for (i, id) in msh.node_ids.iter().enumerate() {
        let j = *inp_index.get(id).unwrap_or_else(|| panic!("node {id} of the .msh is not in the .inp"));
        for d in 0..3 {
            max_diff = max_diff.max((msh.nodes[i][d] - inp.nodes[j][d]).abs());
        }
    }
    assert!(max_diff <= COORD_TOL, "node coordinates differ by {max_diff}");

    // Elements: same node-id tuples in the same (CalculiX) node order.
    let by_nodes_msh = elements_by_node_set(&msh);
    let by_nodes_inp = elements_by_node_set(&inp);
    assert!(by_nodes_msh == by_nodes_inp, "element connectivities differ between .msh and .inp");
    // Gmsh writes the same element tags to both files.
    let msh_elements: BTreeMap<u64, Vec<u64>> = msh.element_ids.iter().copied().zip(element_id_tuples(&msh)).collect();
    let inp_elements: BTreeMap<u64, Vec<u64>> = inp.element_ids.iter().copied().zip(element_id_tuples(&inp)).collect();
    assert!(msh_elements == inp_elements, "element ids differ");

    // Every node is used by an element.
    let used: BTreeSet<usize> = msh.connectivity.iter().flatten().copied().collect();
    assert_eq!(used.len(), msh.num_nodes());

    // Node sets: the .msh importer keeps the physical names as written (upper
    // case in bracket.geo), the .inp importer upper-cases.
    for name in ["BOLT_BASE", "BOLT_ARM", "BRACKET"] {
        assert_eq!(node_set_ids(&msh, name), node_set_ids(&inp, name), "node set {name} differs");
    }
    assert_eq!(node_set_ids(&msh, "BRACKET").len(), msh.num_nodes());
    for (name, on_hole, other) in [
        ("BOLT_BASE", on_base_hole as fn([f64; 3]) -> bool, on_arm_hole as fn([f64; 3]) -> bool),
        ("BOLT_ARM", on_arm_hole, on_base_hole),
    ] {
        let set = &msh.node_sets[name];
        assert!(set.len() > 50, "{name}: {} nodes", set.len());
        for &n in set {
            let p = msh.nodes[n];
            assert!(on_hole(p), "{name}: node {} at {p:?} is not on its hole", msh.node_ids[n]);
            assert!(!other(p));
        }
        // Conversely, every node on the hole cylinder is in the set.
        let on: Vec<usize> = (0..msh.num_nodes()).filter(|&n| on_hole(msh.nodes[n])).collect();
        assert_eq!(&on, set, "{name}: set differs from the nodes on the cylinder");
    }

    // Midside nodes: at the edge midpoint, except on the curved CAD faces
    // (hole cylinders, fillet), where the corners and the midside node lie on
    // the same cylinder.
    let on_curved: [fn([f64; 3]) -> bool; 3] = [on_base_hole, on_arm_hole, on_fillet];
    let mut curved_edges = 0;
    let mut straight_only =
        ImportedMesh { nodes: msh.nodes.clone(), node_ids: msh.node_ids.clone(), ..Default::default() };
    for (ty, conn) in msh.element_types.iter().zip(&msh.connectivity) {
        let mut curved = false;
        for (k, &(a, b)) in ty.midside_edges().iter().enumerate() {
            let m = msh.nodes[conn[4 + k]];
            let (pa, pb) = (msh.nodes[conn[a]], msh.nodes[conn[b]]);
            let dev = (0..3).map(|d| (m[d] - 0.5 * (pa[d] + pb[d])).abs()).fold(0.0, f64::max);
            if dev > 1e-12 {
                curved = true;
                curved_edges += 1;
                assert!(
                    on_curved.iter().any(|f| f(pa) && f(pb) && f(m)),
                    "curved edge {:?} not on a hole or the fillet",
                    [pa, m, pb]
                );
            }
        }
        if !curved {
            straight_only.element_types.push(*ty);
            straight_only.connectivity.push(conn.clone());
        }
    }
    assert!(curved_edges > 0);
    assert!(straight_only.num_elements() > msh.num_elements() / 2);
    assert_midsides_at_midpoints(&straight_only);

    // Volume. The corner tets (straight-sided tet10) replace each arc by its
    // chords; the curved tet10 by parabolas through the arc midpoints. Both
    // only add material (the chords/parabolas lie inside the hole and fillet
    // circles). On the plate faces the holes have 11 segments, the fillet 2
    // (size fields in bracket.geo); the estimates below are the per-length
    // arc defects times the cylinder lengths.
    let (hole_chords, hole_parabolas) = arc_defects(HOLE_R, 11, 2.0 * PI);
    let (fillet_chords, fillet_parabolas) = arc_defects(FILLET_R, 2, PI / 2.0);
    let est_chords = 2.0 * 0.006 * hole_chords + 0.040 * fillet_chords; // 8.65e-8 m^3 (0.27 %)
    let est_parabolas = 2.0 * 0.006 * hole_parabolas + 0.040 * fillet_parabolas; // 5.4e-10 m^3 (1.7e-5)
    let cad = cad_volume();
    let mut v_corner = 0.0;
    let mut v_iso = 0.0;
    let mut min_ratio = f64::INFINITY;
    for conn in &msh.connectivity {
        let x: Vec<[f64; 3]> = conn.iter().map(|&n| msh.nodes[n]).collect();
        v_corner += det3(sub(x[1], x[0]), sub(x[2], x[0]), sub(x[3], x[0])) / 6.0;
        let (v, r) = tet10_volume(&x);
        v_iso += v;
        min_ratio = min_ratio.min(r);
    }
    // Positive orientation and no badly distorted curved element (Gmsh
    // reports a worst distortion of 0.56).
    assert!(min_ratio > 0.5, "min det J ratio {min_ratio}");
    let ex_corner = v_corner - cad;
    let ex_iso = v_iso - cad;
    assert!(
        ex_corner > 0.5 * est_chords && ex_corner < 1.1 * est_chords,
        "corner-tet volume {v_corner} vs CAD {cad}: excess {ex_corner}, chord estimate {est_chords}"
    );
    assert!(
        ex_iso > 0.0 && ex_iso < 1.5 * est_parabolas,
        "tet10 volume {v_iso} vs CAD {cad}: excess {ex_iso}, parabola estimate {est_parabolas}"
    );

    eprintln!(
        "bracket: {} nodes ({} DoF), {} C3D10; BOLT_BASE {} nodes, BOLT_ARM {} nodes; \
         {curved_edges} curved edge occurrences; max .msh/.inp coordinate difference {max_diff:.2e}; \
         min det J ratio {min_ratio:.3}; CAD volume {cad:.7e}, corner tets {v_corner:.7e} ({:+.3e}), \
         tet10 {v_iso:.7e} ({:+.3e})",
        msh.num_nodes(),
        3 * msh.num_nodes(),
        msh.num_elements(),
        msh.node_sets["BOLT_BASE"].len(),
        msh.node_sets["BOLT_ARM"].len(),
        ex_corner / cad,
        ex_iso / cad,
    );
}
