//! FE models given as assembled matrices: stiffness, mass and (optionally)
//! damping exported from ANSYS, Abaqus or CalculiX, plus a DoF map that says
//! which node and direction each matrix row is, plus the node coordinates.
//!
//! # Matrix files (Matrix Market)
//!
//! Each matrix is a Matrix Market coordinate file:
//!
//! ```text
//! %%MatrixMarket matrix coordinate real symmetric
//! % any number of comment lines
//! 24 24 300
//! 1 1 4.9358974358974e+04
//! 1 2 1.6826923076923e+04
//! ...
//! ```
//!
//! The header is case-insensitive; the field must be `real` or `integer` and
//! the symmetry `general` or `symmetric`. Indices are 1-based. A `symmetric`
//! file stores one triangle, either one (an off-diagonal position given in
//! both triangles is refused: it would be counted twice). A `general` file
//! must be symmetric to `|a_ij - a_ji| <= 1e-10 max_k |a_kk|` and is then
//! replaced by the exactly symmetric `(A + A^T) / 2`. Duplicate entries are
//! summed, as assemblers mean them. Refused: `array` (dense) files, `complex`,
//! `pattern`, `hermitian` and `skew-symmetric` matrices, non-square sizes,
//! out-of-range indices, a number of entries other than announced, malformed
//! or non-finite numbers. Explicit zeros are dropped.
//!
//! CalculiX's own `.sti`/`.mas` files (`*FREQUENCY, SOLVER=MATRIXSTORAGE`) are
//! the upper triangle as `row column value` lines without header or size
//! line; prepending `%%MatrixMarket matrix coordinate real symmetric` and the
//! line `n n nnz` turns them into valid input.
//!
//! # DoF maps
//!
//! The format is detected from the content:
//!
//! * ANSYS `.mapping` (`HBMAT, ..., Mapping=YES` / APDL Math): a header line
//!   `Matrix Eqn   Node   DOF`, then one `eqn node label` line per row in any
//!   order, `eqn` the 1-based row, `label` `UX`, `UY` or `UZ`. The header may
//!   be missing.
//! * CalculiX `.dof` (`*FREQUENCY, SOLVER=MATRIXSTORAGE`): one `node.direction`
//!   per line (`12.3` = node 12, z); row i is line i.
//! * A two-column list `node direction` (whitespace or comma separated;
//!   direction `1`/`2`/`3`, `x`/`y`/`z` or `UX`/`UY`/`UZ`, case-insensitive);
//!   row i is data line i.
//!
//! In all three, blank lines and lines starting with `#` or `%` are ignored.
//! Rotational DoFs (`ROTX`..`ROTZ`, directions 4..6) are refused: only solid
//! models are supported. Every node of the map needs all three directions
//! exactly once.
//!
//! # Node files
//!
//! `.inp` (Abaqus/CalculiX, via [`crate::import::read_inp`]; a deck with only
//! `*NODE`/`*NSET` is fine) or `.msh` (Gmsh 4.1, via
//! [`crate::import::parse_msh`]; the `$Elements` section may be absent) give
//! coordinates and node sets. Any other extension is read as a table of
//! `id x y z` lines (comma and/or whitespace separated; lines starting with
//! `#`, `*` or `%` are comments). Nodes of the file that the DoF map does not
//! use are dropped.
//!
//! # Checks
//!
//! Matrix sizes equal the DoF map's row count; the diagonals of K and M are
//! positive; M is positive semi-definite (sparse Cholesky of M + 1e-8 diag M:
//! consistent masses integrated with reduced rules are singular); the rigid-body
//! residual of K (see [`rigid_body_residual`]) is at most
//! [`FREE_FREE_TOLERANCE`] for a part declared free-free.

mod checks;
mod dof_map;
mod matrix_market;
mod nodes;

pub use checks::{FREE_FREE_TOLERANCE, RIGID_BODY_MOTIONS, rigid_body_residual};
pub use dof_map::{DofMapFormat, DofRow, parse_dof_map, read_dof_map};
pub use matrix_market::{SYMMETRY_TOLERANCE, parse_matrix_market};
pub use nodes::parse_node_table;

use super::ImportError;
use checks::{check_free_free, check_mass_semidefinite, check_positive_diagonal};
use faer::sparse::SparseColMat;
use matrix_market::read_mm;
use nodes::read_nodes;
use std::collections::{BTreeMap, HashMap};
use std::path::Path;

const DIRECTIONS: [&str; 3] = ["x", "y", "z"];

/// A model read from assembled matrices. DoF `3 * node + direction`
/// (direction 0, 1, 2 = x, y, z) of every matrix is node `node` of `nodes`.
#[derive(Debug, Clone)]
pub struct MatrixModel {
    /// Coordinates of the nodes the DoF map uses, dense 0-based, in the order
    /// of the node file.
    pub nodes: Vec<[f64; 3]>,
    /// File ids of `nodes`.
    pub node_ids: Vec<u64>,
    /// Node sets of an `.inp`/`.msh` node file in the dense numbering (nodes
    /// not in the DoF map dropped; a set may end up empty). Empty for a plain
    /// node table.
    pub node_sets: BTreeMap<String, Vec<usize>>,
    /// Stiffness, `3 * nodes.len()` square, exactly symmetric.
    pub stiffness: SparseColMat<usize, f64>,
    /// Mass, same size, exactly symmetric and positive semi-definite.
    pub mass: SparseColMat<usize, f64>,
    /// Damping, same size, exactly symmetric.
    pub damping: Option<SparseColMat<usize, f64>>,
    /// [`rigid_body_residual`] of `stiffness`.
    pub rigid_body_residual: [f64; 6],
}

/// The files of a matrix model.
#[derive(Debug, Clone, Copy)]
pub struct MatrixFiles<'a> {
    pub stiffness: &'a Path,
    pub mass: &'a Path,
    pub damping: Option<&'a Path>,
    pub dof_map: &'a Path,
    pub nodes: &'a Path,
}

/// Reads and checks a matrix model; see the module documentation for the
/// formats. `free_free` says the part has no supports, so its stiffness must
/// not resist rigid-body motion.
pub fn read_matrix_model(files: &MatrixFiles, free_free: bool) -> Result<MatrixModel, ImportError> {
    let (_, rows) = read_dof_map(files.dof_map)?;
    let node_file = read_nodes(files.nodes)?;

    let mut file_index: HashMap<u64, usize> = HashMap::with_capacity(node_file.ids.len());
    for (k, &id) in node_file.ids.iter().enumerate() {
        file_index.insert(id, k);
    }
    // The first unknown node in file order is the one a reader finds first
    // (rows are in matrix order, which an ANSYS mapping need not follow).
    if let Some(r) = rows.iter().filter(|r| !file_index.contains_key(&r.node)).min_by_key(|r| r.line) {
        return Err(ImportError::new(
            files.dof_map,
            r.line,
            format!("node {} of the DoF map is not defined in the node file {}", r.node, files.nodes.display()),
        ));
    }
    let mut used = vec![false; node_file.ids.len()];
    let mut row_file_node = Vec::with_capacity(rows.len());
    for r in &rows {
        let f = file_index.get(&r.node).copied().unwrap_or(0);
        if let Some(u) = used.get_mut(f) {
            *u = true;
        }
        row_file_node.push(f);
    }
    // Node-file order keeps the dense numbering recognisable to the user
    // (and independent of how the exporter happened to order the rows).
    let mut dense = vec![usize::MAX; used.len()];
    let mut nodes = Vec::new();
    let mut node_ids = Vec::new();
    for (f, &u) in used.iter().enumerate() {
        if u {
            dense[f] = nodes.len();
            nodes.push(node_file.coords[f]);
            node_ids.push(node_file.ids[f]);
        }
    }
    let node_sets = node_file
        .sets
        .iter()
        .map(|(name, members)| {
            let mapped =
                members.iter().filter_map(|&f| dense.get(f).copied().filter(|&d| d != usize::MAX)).collect::<Vec<_>>();
            (name.clone(), mapped)
        })
        .collect::<BTreeMap<_, _>>();
    let perm: Vec<usize> = rows.iter().zip(&row_file_node).map(|(r, &f)| 3 * dense[f] + r.direction).collect();

    let label = |row: usize| match rows.get(row) {
        Some(r) => format!("row {} (node {} {})", row + 1, r.node, DIRECTIONS[r.direction]),
        None => format!("row {}", row + 1),
    };
    let map = (rows.len(), files.dof_map);
    let k = read_mm(files.stiffness, Some(map), &label)?;
    let m = read_mm(files.mass, Some(map), &label)?;
    let d = match files.damping {
        Some(p) => Some(read_mm(p, Some(map), &label)?),
        None => None,
    };
    check_positive_diagonal(&k, files.stiffness, "stiffness", &label)?;
    check_positive_diagonal(&m, files.mass, "mass", &label)?;

    let stiffness = k.to_sparse(&perm, files.stiffness)?;
    let mass = m.to_sparse(&perm, files.mass)?;
    let damping = match (&d, files.damping) {
        (Some(d), Some(p)) => Some(d.to_sparse(&perm, p)?),
        _ => None,
    };

    check_mass_semidefinite(&mass, files.mass)?;
    let rigid_body_residual = check_free_free(&stiffness, &nodes, &node_ids, free_free, files.stiffness)?;

    Ok(MatrixModel { nodes, node_ids, node_sets, stiffness, mass, damping, rigid_body_residual })
}

// ---------------------------------------------------------------------------
// Text helpers of the parsers

/// A number as exporters write it.
fn parse_f64(s: &str) -> Option<f64> {
    // Fortran exponents (1.0D3) are what some exporters write.
    if s.contains(['d', 'D']) { s.replace(['d', 'D'], "e").parse().ok() } else { s.parse().ok() }
}

/// At most 60 characters of a line, for messages.
fn clip(s: &str) -> String {
    if s.chars().count() > 60 { format!("{}...", s.chars().take(60).collect::<String>()) } else { s.to_string() }
}

/// The comma and/or whitespace separated fields of a line.
fn split_fields(t: &str) -> Vec<&str> {
    t.split(|c: char| c == ',' || c.is_whitespace()).filter(|s| !s.is_empty()).collect()
}

#[cfg(test)]
mod test_util {
    use super::ImportError;
    use faer::sparse::SparseColMat;
    use std::path::PathBuf;

    /// Asserts the error is on `line` of `file` and its message contains all `parts`.
    pub(super) fn check_err(e: ImportError, file: &str, line: usize, parts: &[&str]) {
        assert_eq!(e.line, line, "wrong line for: {e}");
        assert!(e.file.ends_with(file), "wrong file for: {e}");
        for p in parts {
            assert!(e.message.contains(p), "message lacks '{p}': {e}");
        }
    }

    pub(super) fn dense(m: &SparseColMat<usize, f64>) -> Vec<Vec<f64>> {
        let d = m.to_dense();
        (0..d.nrows()).map(|i| (0..d.ncols()).map(|j| d[(i, j)]).collect()).collect()
    }

    /// A scratch directory unique to the test.
    pub(super) fn scratch(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("matrices-test-{}-{name}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    /// The .dof CalculiX 2.20 writes for one C3D8 element (nodes 1..8) with
    /// `*FREQUENCY, SOLVER=MATRIXSTORAGE`: node-major, `%d.%d`, no header.
    pub(super) const CCX_DOF: &str = "1.1\n1.2\n1.3\n2.1\n2.2\n2.3\n3.1\n3.2\n3.3\n4.1\n4.2\n4.3\n5.1\n5.2\n5.3\n6.1\n6.2\n6.3\n7.1\n7.2\n7.3\n8.1\n8.2\n8.3\n";
}

#[cfg(test)]
mod tests {
    use super::test_util::{CCX_DOF, check_err, dense, scratch};
    use super::*;
    use std::path::PathBuf;

    /// Writes `m` (dense, row-major n x n) as Matrix Market: the upper
    /// triangle as 'symmetric' or everything as 'general'; `perm[r]` is the
    /// model DoF of file row r.
    fn write_mm(path: &Path, m: &[f64], n: usize, perm: &[usize], symmetric: bool) {
        let mut body = String::new();
        let mut count = 0;
        for r in 0..n {
            for c in 0..n {
                let v = m[perm[r] * n + perm[c]];
                if v != 0.0 && (!symmetric || r <= c) {
                    body += &format!("{} {} {:e}\n", r + 1, c + 1, v);
                    count += 1;
                }
            }
        }
        let kind = if symmetric { "symmetric" } else { "general" };
        std::fs::write(
            path,
            format!("%%MatrixMarket matrix coordinate real {kind}\n% written by the test\n{n} {n} {count}\n{body}"),
        )
        .unwrap();
    }

    /// One 2 cm eight-node cell (a slightly distorted hexahedron) at `base`
    /// with node ids 11, 21, ..., 81: coordinates, 24x24 stiffness and mass
    /// (row-major, node-major DoFs). The stiffness is that of steel bars of
    /// 1 cm^2 between every two nodes: like a solid element's, symmetric,
    /// positive semi-definite and free of the six rigid-body motions up to
    /// rounding, with full 3x3 node blocks. The mass is `m_ab delta_ij` with
    /// `m_ab = rho V (1 + delta_ab) / 72` (positive definite, total rho V).
    fn cell(base: [f64; 3]) -> (Vec<u64>, Vec<[f64; 3]>, Vec<f64>, Vec<f64>) {
        let unit = [
            [0.0, 0.0, 0.0],
            [1.1, 0.0, 0.05],
            [1.0, 0.9, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.1, 1.2],
            [1.0, 0.0, 1.0],
            [1.05, 1.0, 1.0],
            [0.0, 1.0, 1.0],
        ];
        let coords: Vec<[f64; 3]> = unit.iter().map(|p| [0, 1, 2].map(|d| base[d] + 0.02 * p[d])).collect();
        let ids = (1..=8).map(|k| 10 * k + 1).collect();
        let ea = 210e9 * 1e-4;
        let mut k = vec![0.0; 24 * 24];
        for a in 0..8 {
            for b in a + 1..8 {
                let d = [0, 1, 2].map(|i| coords[b][i] - coords[a][i]);
                let len = d.iter().map(|x| x * x).sum::<f64>().sqrt();
                let n = d.map(|x| x / len);
                for i in 0..3 {
                    for j in 0..3 {
                        // n_i n_j first: the same bits for (i, j) and (j, i).
                        let v = ea / len * (n[i] * n[j]);
                        k[(3 * a + i) * 24 + 3 * a + j] += v;
                        k[(3 * b + i) * 24 + 3 * b + j] += v;
                        k[(3 * a + i) * 24 + 3 * b + j] -= v;
                        k[(3 * b + i) * 24 + 3 * a + j] -= v;
                    }
                }
            }
        }
        let rho_v = 7850.0 * 0.02f64.powi(3);
        let mut m = vec![0.0; 24 * 24];
        for a in 0..8 {
            for b in 0..8 {
                let m_ab = rho_v * if a == b { 2.0 } else { 1.0 } / 72.0;
                for d in 0..3 {
                    m[(3 * a + d) * 24 + 3 * b + d] = m_ab;
                }
            }
        }
        (ids, coords, k, m)
    }

    /// A base point about the cell's size away from the origin.
    const NEAR: [f64; 3] = [0.003, -0.004, 0.001];

    struct CellFiles {
        dir: PathBuf,
        k: Vec<f64>,
        m: Vec<f64>,
        coords: Vec<[f64; 3]>,
        ids: Vec<u64>,
        /// perm[r] = model DoF of file row r
        perm: Vec<usize>,
    }

    /// Writes the cell with its rows in a scrambled order, an ANSYS
    /// mapping for it, and an .inp node file listing the nodes in reverse
    /// (plus one node the map does not use).
    fn cell_files(name: &str, base: [f64; 3]) -> CellFiles {
        let dir = scratch(name);
        let (ids, coords, k, m) = cell(base);
        let perm: Vec<usize> = (0..24).map(|r| (r * 7 + 5) % 24).collect();
        write_mm(&dir.join("k.mtx"), &k, 24, &perm, true);
        write_mm(&dir.join("m.mtx"), &m, 24, &perm, false);
        let damp: Vec<f64> = k.iter().zip(&m).map(|(k, m)| 1e-5 * k + 2.0 * m).collect();
        write_mm(&dir.join("d.mtx"), &damp, 24, &perm, true);
        let mut map = String::from("Matrix Eqn   Node   DOF\n");
        for (r, &p) in perm.iter().enumerate().rev() {
            map += &format!("{:>10} {:>6}    {}\n", r + 1, ids[p / 3], ["UX", "UY", "UZ"][p % 3]);
        }
        std::fs::write(dir.join("k.mapping"), map).unwrap();
        let mut inp = String::from("** nodes only\n*NODE, NSET=NALL\n999, 5., 5., 5.\n");
        for a in (0..8).rev() {
            inp += &format!("{}, {:e}, {:e}, {:e}\n", ids[a], coords[a][0], coords[a][1], coords[a][2]);
        }
        inp += &format!("*NSET, NSET=BOTTOM\n{}, {}, {}, {}, 999\n", ids[0], ids[1], ids[2], ids[3]);
        std::fs::write(dir.join("nodes.inp"), inp).unwrap();
        CellFiles { dir, k, m, coords, ids, perm }
    }

    impl CellFiles {
        fn files(&self) -> (PathBuf, PathBuf, PathBuf, PathBuf, PathBuf) {
            let d = &self.dir;
            (d.join("k.mtx"), d.join("m.mtx"), d.join("d.mtx"), d.join("k.mapping"), d.join("nodes.inp"))
        }
    }

    #[test]
    fn round_trip_and_rigid_body_residual() {
        let h = cell_files("roundtrip", NEAR);
        let (k, m, d, map, nodes) = h.files();
        let files = MatrixFiles { stiffness: &k, mass: &m, damping: Some(&d), dof_map: &map, nodes: &nodes };
        let model = read_matrix_model(&files, true).unwrap();
        // Dense numbering follows the node file, which lists the nodes in reverse.
        let rev: Vec<u64> = h.ids.iter().rev().copied().collect();
        assert_eq!(model.node_ids, rev);
        assert_eq!(model.nodes[0], h.coords[7]);
        assert_eq!(model.node_sets["BOTTOM"], vec![4, 5, 6, 7]);
        assert_eq!(model.node_sets["NALL"], (0..8).collect::<Vec<_>>());
        // model DoF of cell DoF e: node a -> dense 7 - a
        let dof = |e: usize| 3 * (7 - e / 3) + e % 3;
        let (ks, ms) = (dense(&model.stiffness), dense(&model.mass));
        let dmp = dense(model.damping.as_ref().unwrap());
        for a in 0..24 {
            for b in 0..24 {
                assert_eq!(ks[dof(a)][dof(b)], h.k[a * 24 + b], "K({a},{b})");
                let want_m = 0.5 * h.m[a * 24 + b] + 0.5 * h.m[b * 24 + a];
                assert_eq!(ms[dof(a)][dof(b)], want_m, "M({a},{b})");
                assert_eq!(dmp[dof(a)][dof(b)], 1e-5 * h.k[a * 24 + b] + 2.0 * h.m[a * 24 + b]);
            }
        }
        assert_eq!(model.stiffness.nrows(), 24);
        for (c, r) in model.rigid_body_residual.iter().enumerate() {
            assert!(*r < 1e-14, "{}: {r:e}", RIGID_BODY_MOTIONS[c]);
        }
        assert_eq!(rigid_body_residual(&model.stiffness, &model.nodes), model.rigid_body_residual);
        std::fs::remove_dir_all(&h.dir).ok();
    }

    /// 100 m from the origin a 2 cm cell's coordinates carry only ~1e-12 of
    /// its size, so its own stiffness is rigid-body free to that level only;
    /// still far inside the free-free tolerance.
    #[test]
    fn far_from_origin_is_still_free_free() {
        let h = cell_files("far", [100.0, -50.0, 20.0]);
        let (k, m, _, map, nodes) = h.files();
        let files = MatrixFiles { stiffness: &k, mass: &m, damping: None, dof_map: &map, nodes: &nodes };
        let model = read_matrix_model(&files, true).unwrap();
        for (c, r) in model.rigid_body_residual.iter().enumerate() {
            assert!(*r < 1e-10, "{}: {r:e}", RIGID_BODY_MOTIONS[c]);
        }
        std::fs::remove_dir_all(&h.dir).ok();
    }

    #[test]
    fn supported_stiffness_is_refused_when_free_free() {
        let h = cell_files("support", NEAR);
        let (k, m, _, map, nodes) = h.files();
        // A support spring at node 31 (cell node 2), direction y.
        let kmax = h.k.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        let mut ks = h.k.clone();
        ks[7 * 24 + 7] += 1e3 * kmax;
        write_mm(&k, &ks, 24, &h.perm, true);
        let files = MatrixFiles { stiffness: &k, mass: &m, damping: None, dof_map: &map, nodes: &nodes };
        let e = read_matrix_model(&files, true).unwrap_err();
        check_err(
            e,
            "k.mtx",
            0,
            &["translation y", "rotation about x", "rotation about z", "node 31 y", "supports", "free-free"],
        );
        // Not free-free: accepted, and the residual tells.
        let model = read_matrix_model(&files, false).unwrap();
        let r = model.rigid_body_residual;
        assert!(r[1] > 0.5, "{r:?}");
        assert!(r[0] < 1e-14 && r[2] < 1e-14 && r[4] < 1e-14, "{r:?}");
        assert!(r[3] > 0.1 && r[5] > 0.1, "{r:?}");
        std::fs::remove_dir_all(&h.dir).ok();
    }

    #[test]
    fn model_level_errors() {
        let h = cell_files("errors", NEAR);
        let (k, m, _, map, nodes) = h.files();
        let dir = &h.dir;
        let model = |k: &Path, m: &Path, map: &Path, nodes: &Path| {
            let files = MatrixFiles { stiffness: k, mass: m, damping: None, dof_map: map, nodes };
            read_matrix_model(&files, true)
        };

        // A node of the map missing from the node file.
        let few = dir.join("few.txt");
        std::fs::write(&few, "11 0 0 0\n21 1 0 0\n").unwrap();
        let e = model(&k, &m, &map, &few).unwrap_err();
        assert!(e.file.ends_with("k.mapping"), "{e}");
        assert!(e.message.contains("node 81 of the DoF map is not defined in the node file"), "{e}");
        assert_eq!(e.line, 2, "{e}"); // the mapping lists row 24 first

        // Matrix size differs from the map.
        let small = dir.join("small.mtx");
        std::fs::write(&small, "%%MatrixMarket matrix coordinate real symmetric\n%\n3 3 1\n1 1 1\n").unwrap();
        check_err(model(&k, &small, &map, &nodes).unwrap_err(), "small.mtx", 3, &["3 x 3", "has 24 rows", "k.mapping"]);
        let files = MatrixFiles { stiffness: &k, mass: &m, damping: Some(&small), dof_map: &map, nodes: &nodes };
        check_err(read_matrix_model(&files, true).unwrap_err(), "small.mtx", 3, &["has 24 rows"]);

        // Non-positive diagonal: named by node and direction.
        let mut ks = h.k.clone();
        ks[5 * 24 + 5] = -1.0; // cell node 1 (id 21), z
        let bad = dir.join("bad_k.mtx");
        write_mm(&bad, &ks, 24, &h.perm, true);
        let e = model(&bad, &m, &map, &nodes).unwrap_err();
        assert!(e.line > 3 && e.file.ends_with("bad_k.mtx"), "{e}");
        for part in ["stiffness diagonal entry of row", "(node 21 z) is -1e0", "positive"] {
            assert!(e.message.contains(part), "{e}");
        }

        // Mass with positive diagonal but indefinite.
        let mut ms = h.m.clone();
        // Far above the mass scale: the x/y block of node 11 becomes indefinite.
        ms[1] = 1.0;
        ms[24] = 1.0;
        let bad = dir.join("bad_m.mtx");
        write_mm(&bad, &ms, 24, &h.perm, true);
        check_err(model(&k, &bad, &map, &nodes).unwrap_err(), "bad_m.mtx", 0, &["mass matrix is indefinite"]);

        // A plain table node file and a CalculiX-style .dof map in another row order.
        let table = dir.join("nodes.csv");
        let mut t = String::from("# id, x, y, z\n");
        for (id, x) in h.ids.iter().zip(&h.coords) {
            t += &format!("{id}, {:e}, {:e}, {:e}\n", x[0], x[1], x[2]);
        }
        std::fs::write(&table, t).unwrap();
        let ccx = dir.join("k.dof");
        let mut s = String::new();
        for &p in &h.perm {
            s += &format!("{}.{}\n", h.ids[p / 3], p % 3 + 1);
        }
        std::fs::write(&ccx, s).unwrap();
        let md = model(&k, &m, &ccx, &table).unwrap();
        assert_eq!(md.node_ids, h.ids);
        assert!(md.node_sets.is_empty());
        assert!(md.damping.is_none());
        let ks = dense(&md.stiffness);
        assert_eq!(ks[5][7], h.k[5 * 24 + 7]);
        std::fs::remove_dir_all(&h.dir).ok();
    }

    /// Truncations and mutations of valid inputs must give errors, not panics.
    #[test]
    fn no_panics_on_damaged_input() {
        let texts = [
            "%%MatrixMarket matrix coordinate real general\n% c\n3 3 4\n1 1 2.0\n1 3 -1\n3 1 -1\n3 3 4e0\n",
            "%%MatrixMarket matrix coordinate integer symmetric\n3 3 3\n1 1 2\n3 1 -1\n3 3 4\n",
            "Matrix Eqn   Node   DOF\n     3      7    UZ\n     1      7    UX\n     2      7    UY\n",
            CCX_DOF,
            "# c\n7 1\n7, y\n7 UZ\n",
            "1, 0, 0, 0\n2 1.5 2e3 -1\n",
        ];
        let junk = ["", " ", "\n", "%", "0", "-", "9999999999999999999999", "é", ".", "nan", "\u{feff}"];
        for t in texts {
            let cuts: Vec<usize> = (0..=t.len()).filter(|&c| t.is_char_boundary(c)).collect();
            for &c in &cuts {
                for j in junk {
                    let s = format!("{}{j}{}", &t[..c], &t[c..]);
                    let p = Path::new("x");
                    let _ = parse_matrix_market(&s, p);
                    let _ = parse_dof_map(&s, p);
                    let _ = parse_node_table(&s, p);
                    let cut = &t[..c];
                    let _ = parse_matrix_market(cut, p);
                    let _ = parse_dof_map(cut, p);
                    let _ = parse_node_table(cut, p);
                }
            }
        }
    }
}
