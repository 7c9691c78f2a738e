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
//! `.inp` (Abaqus/CalculiX, via [`crate::input::import::read_inp`]; a deck with only
//! `*NODE`/`*NSET` is fine) or `.msh` (Gmsh 4.1, via
//! [`crate::input::import::parse_msh`]; the `$Elements` section may be absent) give
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

use super::{ImportError, read_text};
use faer::sparse::{SparseColMat, Triplet};
use faer::{Mat, Side};
use std::collections::{BTreeMap, HashMap};
use std::path::Path;

/// Largest rigid-body residual a free-free stiffness may have.
pub const FREE_FREE_TOLERANCE: f64 = 1e-6;

/// Allowed asymmetry of a `general` matrix, relative to its largest diagonal
/// magnitude. Exporters write 13-17 significant digits, so a symmetric
/// assembled matrix differs from its transpose by far less than this.
pub const SYMMETRY_TOLERANCE: f64 = 1e-10;

/// Names of the six rigid-body motions in the order of
/// [`rigid_body_residual`].
pub const RIGID_BODY_MOTIONS: [&str; 6] = [
    "translation x",
    "translation y",
    "translation z",
    "rotation about x",
    "rotation about y",
    "rotation about z",
];

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

/// Which DoF map format a file was read as.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DofMapFormat {
    /// ANSYS `.mapping`: `eqn node label` rows.
    AnsysMapping,
    /// CalculiX `.dof`: `node.direction` per line.
    CalculixDof,
    /// Two columns `node direction`.
    NodeDirection,
}

/// One matrix row of a DoF map.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct DofRow {
    /// Node id as in the node file.
    pub node: u64,
    /// 0, 1, 2 = x, y, z.
    pub direction: usize,
    /// 1-based line of the DoF map file that defines the row.
    pub line: usize,
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
    if let Some(r) = rows
        .iter()
        .filter(|r| !file_index.contains_key(&r.node))
        .min_by_key(|r| r.line)
    {
        return Err(ImportError::new(
            files.dof_map,
            r.line,
            format!(
                "node {} of the DoF map is not defined in the node file {}",
                r.node,
                files.nodes.display()
            ),
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
            let mapped = members
                .iter()
                .filter_map(|&f| dense.get(f).copied().filter(|&d| d != usize::MAX))
                .collect::<Vec<_>>();
            (name.clone(), mapped)
        })
        .collect::<BTreeMap<_, _>>();
    let perm: Vec<usize> = rows
        .iter()
        .zip(&row_file_node)
        .map(|(r, &f)| 3 * dense[f] + r.direction)
        .collect();

    let label = |row: usize| match rows.get(row) {
        Some(r) => format!(
            "row {} (node {} {})",
            row + 1,
            r.node,
            DIRECTIONS[r.direction]
        ),
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

    // A consistent mass may be singular (CalculiX integrates C3D4, C3D10 and C3D20R masses with
    // their stiffness rules: rank 1, 4 and 8 per element), so the check is for indefiniteness:
    // M + 1e-8 diag(M) must factor. A singular semidefinite M passes, a negative eigenvalue
    // beyond round-off does not.
    let lifted = {
        let mut t: Vec<faer::sparse::Triplet<usize, usize, f64>> = Vec::with_capacity(mass.val().len() + mass.nrows());
        for j in 0..mass.ncols() {
            for (&i, &v) in mass.row_idx_of_col_raw(j).iter().zip(mass.val_of_col(j)) {
                t.push(faer::sparse::Triplet::new(i, j, v));
                if i == j {
                    t.push(faer::sparse::Triplet::new(i, j, 1e-8 * v));
                }
            }
        }
        SparseColMat::try_new_from_triplets(mass.nrows(), mass.ncols(), &t)
            .map_err(|e| ImportError::new(files.mass, 0, format!("mass matrix: {e:?}")))?
    };
    if let Err(e) = lifted.sp_cholesky(Side::Lower) {
        let why = match e {
            faer::sparse::linalg::LltError::Numeric(_) => {
                "its Cholesky factorisation meets a non-positive pivot".to_string()
            }
            faer::sparse::linalg::LltError::Generic(g) => {
                format!("the factorisation failed ({g:?})")
            }
        };
        return Err(ImportError::new(
            files.mass,
            0,
            format!(
                "mass matrix is indefinite (not positive semi-definite): {why}. Check that the mass matrix \
                 belongs to the same model and DoF order as the stiffness and the DoF map"
            ),
        ));
    }

    let check = rigid_body_check(&stiffness, &nodes);
    let rigid_body_residual = check.map(|(r, _)| r);
    if free_free {
        let resisted: Vec<usize> = (0..6)
            .filter(|&c| {
                rigid_body_residual[c] > FREE_FREE_TOLERANCE || rigid_body_residual[c].is_nan()
            })
            .collect();
        if let Some(&worst) = resisted
            .iter()
            .max_by(|&&a, &&b| rigid_body_residual[a].total_cmp(&rigid_body_residual[b]))
        {
            let list = resisted
                .iter()
                .map(|&c| {
                    format!(
                        "{} (residual {:.2e})",
                        RIGID_BODY_MOTIONS[c], rigid_body_residual[c]
                    )
                })
                .collect::<Vec<_>>()
                .join(", ");
            let dof = check[worst].1;
            let node = node_ids.get(dof / 3).copied().unwrap_or(0);
            return Err(ImportError::new(
                files.stiffness,
                0,
                format!(
                    "the stiffness matrix resists rigid-body {list}, above the free-free tolerance \
                     {FREE_FREE_TOLERANCE:e}; the largest reaction to the {} is at node {node} {}. \
                     The stiffness seems to carry supports (boundary conditions, springs to ground) \
                     while the input says the part is free-free: export the stiffness of the \
                     unsupported part, or do not declare it free-free",
                    RIGID_BODY_MOTIONS[worst],
                    DIRECTIONS[dof % 3]
                ),
            ));
        }
    }

    Ok(MatrixModel {
        nodes,
        node_ids,
        node_sets,
        stiffness,
        mass,
        damping,
        rigid_body_residual,
    })
}

/// How far the stiffness `k` (DoF `3 * node + direction`) is from being free
/// of the six rigid-body fields about the centroid of `nodes`: for each field
/// `r` (translations x, y, z, then small rotations about x, y, z) the value
/// `||K r||_inf / (max_ij |K_ij| * ||r||_inf)`.
///
/// The max-norm is used because a support acts on a few DoFs: its reaction
/// shows in the max-norm at full size whatever the model size, where a
/// 2-norm would dilute it by the square root of the node count. Dividing by
/// `max |K_ij| ||r||_inf` bounds the value by the nonzeros per row for any
/// field and makes it independent of units and of the field's scale, so the
/// rotations (scaled by the largest distance from the centroid) compare
/// directly with the translations. `K r` is summed in double-double, so for
/// a free stiffness the value is the rounding of the stored entries
/// (~1e-16 per digit-exact entry, ~1e-13 for the 14 digits CalculiX writes),
/// and a support spring `s` at the farthest node gives about
/// `s / max |K_ij|`.
///
/// Returns NaN for all six when `k` is not `3 nodes.len()` square; a field
/// that vanishes (rotations of a single node or about the axis of collinear
/// nodes) or an all-zero `k` gives 0.
pub fn rigid_body_residual(k: &SparseColMat<usize, f64>, nodes: &[[f64; 3]]) -> [f64; 6] {
    rigid_body_check(k, nodes).map(|(r, _)| r)
}

/// [`rigid_body_residual`] with, per field, the DoF of the largest reaction.
fn rigid_body_check(k: &SparseColMat<usize, f64>, nodes: &[[f64; 3]]) -> [(f64, usize); 6] {
    let n = 3 * nodes.len();
    if k.nrows() != n || k.ncols() != n {
        return [(f64::NAN, 0); 6];
    }
    if n == 0 {
        return [(0.0, 0); 6];
    }
    // mul_compensated walks col_ptr ranges, which is only right for compact
    // storage; a caller's matrix with per-column counts is rebuilt first.
    let compact;
    let k = if k.symbolic().col_nnz().is_some() {
        let mut trip = Vec::new();
        for j in 0..n {
            for (&i, &v) in k.row_idx_of_col_raw(j).iter().zip(k.val_of_col(j)) {
                trip.push(Triplet::new(i, j, v));
            }
        }
        match SparseColMat::try_new_from_triplets(n, n, &trip) {
            Ok(m) => {
                compact = m;
                &compact
            }
            Err(_) => return [(f64::NAN, 0); 6],
        }
    } else {
        k
    };
    let mut kmax = 0.0f64;
    for j in 0..n {
        for &v in k.val_of_col(j) {
            kmax = kmax.max(v.abs());
        }
    }

    let count = nodes.len() as f64;
    let mut c = [0.0; 3];
    for p in nodes {
        for d in 0..3 {
            c[d] += p[d] / count;
        }
    }
    let size = nodes
        .iter()
        .map(|p| ((p[0] - c[0]).powi(2) + (p[1] - c[1]).powi(2) + (p[2] - c[2]).powi(2)).sqrt())
        .fold(0.0, f64::max);
    let scale = if size > 0.0 { 1.0 / size } else { 0.0 };
    let mut r = Mat::<f64>::zeros(n, 6);
    for (a, p) in nodes.iter().enumerate() {
        let x = [0, 1, 2].map(|d| (p[d] - c[d]) * scale);
        for t in 0..3 {
            r[(3 * a + t, t)] = 1.0;
        }
        // omega x (p - c) for omega = e_x, e_y, e_z.
        r[(3 * a + 1, 3)] = -x[2];
        r[(3 * a + 2, 3)] = x[1];
        r[(3 * a, 4)] = x[2];
        r[(3 * a + 2, 4)] = -x[0];
        r[(3 * a, 5)] = -x[1];
        r[(3 * a + 1, 5)] = x[0];
    }
    let kr = crate::linalg::sparse::mul_compensated(None, 1.0, k, r.as_ref());
    let mut out = [(0.0, 0); 6];
    for (col, o) in out.iter_mut().enumerate() {
        let mut rmax = 0.0f64;
        let mut num = 0.0f64;
        let mut arg = 0;
        for i in 0..n {
            rmax = rmax.max(r[(i, col)].abs());
            let v = kr[(i, col)].abs();
            if v > num || v.is_nan() {
                num = v;
                arg = i;
            }
        }
        let den = kmax * rmax;
        *o = (
            if den > 0.0 {
                num / den
            } else if num.is_nan() {
                f64::NAN
            } else {
                0.0
            },
            arg,
        );
    }
    out
}

// ---------------------------------------------------------------------------
// Matrix Market

/// One stored entry, file numbering, 0-based. `u32` indices keep the parse
/// of a 10^7-entry file a third smaller; sizes beyond that are refused.
#[derive(Debug, Clone, Copy)]
struct Entry {
    i: u32,
    j: u32,
    v: f64,
    line: usize,
}

/// A parsed, exactly symmetric matrix in file numbering: the upper triangle
/// (i <= j), duplicates summed.
struct SymMatrix {
    n: usize,
    upper: Vec<Entry>,
}

impl SymMatrix {
    /// The full matrix with row/column r moved to perm[r] (a permutation of
    /// 0..n). Explicit zeros are dropped.
    fn to_sparse(
        &self,
        perm: &[usize],
        path: &Path,
    ) -> Result<SparseColMat<usize, f64>, ImportError> {
        let mut trip = Vec::with_capacity(2 * self.upper.len());
        for e in &self.upper {
            if e.v == 0.0 {
                continue;
            }
            let (a, b) = match (perm.get(e.i as usize), perm.get(e.j as usize)) {
                (Some(&a), Some(&b)) => (a, b),
                _ => return Err(ImportError::new(path, e.line, "entry outside the DoF map")),
            };
            trip.push(Triplet::new(a, b, e.v));
            if a != b {
                trip.push(Triplet::new(b, a, e.v));
            }
        }
        SparseColMat::try_new_from_triplets(self.n, self.n, &trip).map_err(|e| {
            ImportError::new(path, 0, format!("cannot build the sparse matrix: {e:?}"))
        })
    }
}

/// Parses a Matrix Market coordinate file into the full, exactly symmetric
/// matrix in file numbering (see the module documentation for what is
/// accepted).
pub fn parse_matrix_market(
    text: &str,
    path: &Path,
) -> Result<SparseColMat<usize, f64>, ImportError> {
    let m = parse_mm(text, path, None, &|r| format!("row {}", r + 1))?;
    let identity: Vec<usize> = (0..m.n).collect();
    m.to_sparse(&identity, path)
}

fn read_mm(
    path: &Path,
    expect: Option<(usize, &Path)>,
    label: &dyn Fn(usize) -> String,
) -> Result<SymMatrix, ImportError> {
    parse_mm(&read_text(path)?, path, expect, label)
}

fn parse_f64(s: &str) -> Option<f64> {
    // Fortran exponents (1.0D3) are what some exporters write.
    if s.contains(['d', 'D']) {
        s.replace(['d', 'D'], "e").parse().ok()
    } else {
        s.parse().ok()
    }
}

/// The next line that is neither blank nor a `%` comment; `last` follows
/// the lines consumed, for messages about a file that ends early.
fn next_data<'a>(
    lines: &mut impl Iterator<Item = (usize, &'a str)>,
    last: &mut usize,
) -> Option<(usize, &'a str)> {
    for (k, t) in lines.by_ref() {
        *last = k;
        if !(t.is_empty() || t.starts_with('%')) {
            return Some((k, t));
        }
    }
    None
}

/// Parses a Matrix Market file. `expect` = (rows of the DoF map, its file);
/// `label` names a row in messages.
fn parse_mm(
    text: &str,
    path: &Path,
    expect: Option<(usize, &Path)>,
    label: &dyn Fn(usize) -> String,
) -> Result<SymMatrix, ImportError> {
    let err = |line: usize, msg: String| ImportError::new(path, line, msg);
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut lines = text.lines().enumerate().map(|(k, l)| (k + 1, l.trim()));
    let Some((_, first)) = lines.next() else {
        return Err(err(
            0,
            "empty file: expected a Matrix Market header '%%MatrixMarket matrix coordinate real symmetric'".into(),
        ));
    };
    let head: Vec<&str> = first.split_whitespace().collect();
    if !head
        .first()
        .is_some_and(|t| t.eq_ignore_ascii_case("%%MatrixMarket"))
    {
        let looks_like_triplet = head.len() == 3
            && head[0].parse::<u64>().is_ok()
            && head[1].parse::<u64>().is_ok()
            && parse_f64(head[2]).is_some();
        let hint = if looks_like_triplet {
            " (this looks like a headerless 'row column value' list such as CalculiX's .sti/.mas: prepend \
             '%%MatrixMarket matrix coordinate real symmetric' and a size line 'n n entries')"
        } else {
            ""
        };
        return Err(err(
            1,
            format!(
                "not a Matrix Market file: found '{}', expected a header '%%MatrixMarket matrix coordinate \
                 real general|symmetric'{hint}",
                clip(first)
            ),
        ));
    }
    if head.len() != 5 {
        return Err(err(
            1,
            format!(
                "incomplete Matrix Market header '{}': expected '%%MatrixMarket matrix coordinate \
                 real|integer general|symmetric'",
                clip(first)
            ),
        ));
    }
    let (object, format, field, symmetry) = (
        head[1].to_ascii_lowercase(),
        head[2].to_ascii_lowercase(),
        head[3].to_ascii_lowercase(),
        head[4].to_ascii_lowercase(),
    );
    if object != "matrix" {
        return Err(err(
            1,
            format!(
                "Matrix Market object '{}' is not supported: expected 'matrix'",
                head[1]
            ),
        ));
    }
    match format.as_str() {
        "coordinate" => {}
        "array" => {
            return Err(err(
                1,
                "Matrix Market 'array' (dense) format is not supported: expected 'coordinate' (sparse \
                 'row column value' entries)"
                    .into(),
            ));
        }
        _ => {
            return Err(err(
                1,
                format!(
                    "unknown Matrix Market format '{}': expected 'coordinate'",
                    head[2]
                ),
            ));
        }
    }
    let integer = match field.as_str() {
        "real" => false,
        "integer" => true,
        "complex" | "pattern" => {
            return Err(err(
                1,
                format!(
                    "Matrix Market field '{}' is not supported: stiffness, mass and damping must be \
                     'real' (or 'integer')",
                    head[3]
                ),
            ));
        }
        _ => {
            return Err(err(
                1,
                format!(
                    "unknown Matrix Market field '{}': expected 'real' or 'integer'",
                    head[3]
                ),
            ));
        }
    };
    let symmetric = match symmetry.as_str() {
        "general" => false,
        "symmetric" => true,
        "hermitian" | "skew-symmetric" => {
            return Err(err(
                1,
                format!(
                    "Matrix Market symmetry '{}' is not supported: stiffness, mass and damping must be \
                     'symmetric' or 'general' (and then symmetric in value)",
                    head[4]
                ),
            ));
        }
        _ => {
            return Err(err(
                1,
                format!(
                    "unknown Matrix Market symmetry '{}': expected 'general' or 'symmetric'",
                    head[4]
                ),
            ));
        }
    };

    let mut last = 1;
    let Some((size_line, size_text)) = next_data(&mut lines, &mut last) else {
        return Err(err(
            last,
            "missing size line 'rows columns entries' after the header".into(),
        ));
    };
    let size: Vec<&str> = size_text.split_whitespace().collect();
    if size.len() != 3 {
        return Err(err(
            size_line,
            format!(
                "size line '{}' has {} values, expected 'rows columns entries' (3 integers)",
                clip(size_text),
                size.len()
            ),
        ));
    }
    let mut dims = [0usize; 3];
    for (d, s) in dims.iter_mut().zip(&size) {
        *d = s.parse().map_err(|_| {
            err(
                size_line,
                format!("malformed size '{s}' on the size line: expected a non-negative integer"),
            )
        })?;
    }
    let [n, cols, nnz] = dims;
    if n != cols {
        return Err(err(
            size_line,
            format!("matrix is {n} x {cols}: stiffness, mass and damping must be square"),
        ));
    }
    if n > u32::MAX as usize {
        return Err(err(
            size_line,
            format!("matrix size {n} is too large (at most {})", u32::MAX),
        ));
    }
    if let Some((rows, map)) = expect
        && n != rows
    {
        return Err(err(
            size_line,
            format!(
                "matrix is {n} x {n}, but the DoF map {} has {rows} rows: the matrix and the map must \
                 come from the same export",
                map.display()
            ),
        ));
    }

    // Each entry needs at least 6 bytes, which bounds a lying size line.
    let mut entries = Vec::with_capacity(nnz.min(text.len() / 6 + 1));
    while let Some((k, t)) = next_data(&mut lines, &mut last) {
        if entries.len() == nnz {
            return Err(err(
                k,
                format!(
                    "more entries than the {nnz} announced on the size line (line {size_line}): the file \
                     holds at least {}",
                    nnz + 1
                ),
            ));
        }
        let mut it = t.split_whitespace();
        let (Some(si), Some(sj), Some(sv), None) = (it.next(), it.next(), it.next(), it.next())
        else {
            return Err(err(
                k,
                format!(
                    "entry '{}' has {} values, expected 'row column value'",
                    clip(t),
                    t.split_whitespace().count()
                ),
            ));
        };
        let index = |s: &str, what: &str| -> Result<u32, ImportError> {
            match s.parse::<usize>() {
                Ok(v) if (1..=n).contains(&v) => Ok((v - 1) as u32),
                Ok(v) => Err(err(
                    k,
                    format!(
                        "{what} index {v} out of range: the matrix is {n} x {n} and indices are 1-based"
                    ),
                )),
                Err(_) => Err(err(
                    k,
                    format!("malformed {what} index '{s}': expected a positive integer"),
                )),
            }
        };
        let i = index(si, "row")?;
        let j = index(sj, "column")?;
        let v = if integer {
            sv.parse::<i64>().map(|v| v as f64).map_err(|_| {
                err(
                    k,
                    format!("malformed value '{sv}': the header declares 'integer' entries"),
                )
            })?
        } else {
            parse_f64(sv)
                .ok_or_else(|| err(k, format!("malformed number '{sv}': expected a real value")))?
        };
        if !v.is_finite() {
            return Err(err(
                k,
                format!("value '{sv}' is not finite (NaN or infinity)"),
            ));
        }
        entries.push(Entry { i, j, v, line: k });
    }
    if entries.len() != nnz {
        return Err(err(
            size_line,
            format!(
                "the size line announces {nnz} entries but the file contains {}",
                entries.len()
            ),
        ));
    }

    // Stable sort: the first line of a run of duplicates stays first, so
    // messages point at the entry a reader finds first.
    entries.sort_by_key(|e| (e.i, e.j));
    let mut merged: Vec<Entry> = Vec::with_capacity(entries.len());
    for e in entries {
        match merged.last_mut() {
            Some(m) if m.i == e.i && m.j == e.j => {
                m.v += e.v;
                if !m.v.is_finite() {
                    return Err(err(e.line, "the sum of duplicate entries overflows".into()));
                }
            }
            _ => merged.push(e),
        }
    }
    let find = |i: u32, j: u32| {
        merged
            .binary_search_by_key(&(i, j), |e| (e.i, e.j))
            .ok()
            .map(|p| merged[p])
    };

    let mut upper = Vec::with_capacity(merged.len());
    if symmetric {
        for e in &merged {
            if e.i > e.j
                && let Some(m) = find(e.j, e.i)
            {
                let (a, b) = if e.line > m.line { (e, &m) } else { (&m, e) };
                return Err(err(
                    a.line,
                    format!(
                        "entry ({}, {}) mirrors the entry ({}, {}) on line {}: a 'symmetric' file stores one \
                         triangle only, so this position would be counted twice (declare the file \
                         'general' if it holds both triangles)",
                        a.i + 1,
                        a.j + 1,
                        b.i + 1,
                        b.j + 1,
                        b.line
                    ),
                ));
            }
            let (i, j) = (e.i.min(e.j), e.i.max(e.j));
            upper.push(Entry { i, j, ..*e });
        }
    } else {
        let max_diag = merged
            .iter()
            .filter(|e| e.i == e.j)
            .fold(0.0f64, |m, e| m.max(e.v.abs()));
        let tol = SYMMETRY_TOLERANCE * max_diag;
        // (difference, entry, value of the mirror, line of the mirror)
        let mut worst: Option<(f64, Entry, f64, Option<usize>)> = None;
        for e in &merged {
            if e.i == e.j {
                upper.push(*e);
                continue;
            }
            let mirror = find(e.j, e.i);
            if e.i > e.j && mirror.is_some() {
                continue; // handled with its mirror
            }
            let mv = mirror.map_or(0.0, |m| m.v);
            let diff = (e.v - mv).abs();
            if diff > tol && worst.as_ref().is_none_or(|w| diff > w.0) {
                worst = Some((diff, *e, mv, mirror.map(|m| m.line)));
            }
            let (i, j) = (e.i.min(e.j), e.i.max(e.j));
            // Halves first: the sum of two large values may overflow.
            upper.push(Entry {
                i,
                j,
                v: 0.5 * e.v + 0.5 * mv,
                line: e.line,
            });
        }
        if let Some((diff, e, mv, mline)) = worst {
            let mirror = match mline {
                Some(l) => format!("{mv:e} (line {l})"),
                None => "0 (no entry)".to_string(),
            };
            return Err(err(
                e.line,
                format!(
                    "matrix declared 'general' is not symmetric: A({}, {}) = {:e} but A({}, {}) = {mirror}; \
                     |difference| {diff:.3e} exceeds {SYMMETRY_TOLERANCE:e} x max|diagonal| = {tol:.3e} \
                     ({} / {}). Stiffness, mass and damping of a linear elastic model are symmetric: \
                     check the export",
                    e.i + 1,
                    e.j + 1,
                    e.v,
                    e.j + 1,
                    e.i + 1,
                    label(e.i as usize),
                    label(e.j as usize)
                ),
            ));
        }
        upper.sort_by_key(|e| (e.i, e.j));
    }
    Ok(SymMatrix { n, upper })
}

/// Refuses a non-positive (or missing) diagonal entry.
fn check_positive_diagonal(
    m: &SymMatrix,
    path: &Path,
    what: &str,
    label: &dyn Fn(usize) -> String,
) -> Result<(), ImportError> {
    let mut diag: Vec<Option<(f64, usize)>> = vec![None; m.n];
    for e in m.upper.iter().filter(|e| e.i == e.j) {
        if let Some(d) = diag.get_mut(e.i as usize) {
            *d = Some((e.v, e.line));
        }
    }
    for (r, d) in diag.iter().enumerate() {
        match *d {
            Some((v, _)) if v > 0.0 => {}
            Some((v, line)) => {
                return Err(ImportError::new(
                    path,
                    line,
                    format!(
                        "{what} diagonal entry of {} is {v:e}, expected a positive value: every DoF of a \
                         solid has positive {what}",
                        label(r)
                    ),
                ));
            }
            None => {
                return Err(ImportError::new(
                    path,
                    0,
                    format!(
                        "{what} matrix has no diagonal entry for {}, expected a positive value: every DoF \
                         of a solid has positive {what}",
                        label(r)
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// At most 60 characters of a line, for messages.
fn clip(s: &str) -> String {
    if s.chars().count() > 60 {
        format!("{}...", s.chars().take(60).collect::<String>())
    } else {
        s.to_string()
    }
}

// ---------------------------------------------------------------------------
// DoF maps

/// Reads a DoF map; see [`parse_dof_map`].
pub fn read_dof_map(path: &Path) -> Result<(DofMapFormat, Vec<DofRow>), ImportError> {
    parse_dof_map(&read_text(path)?, path)
}

enum Direction {
    Translation(usize),
    Rotation,
    Unknown,
}

fn direction(tok: &str) -> Direction {
    match tok.to_ascii_lowercase().as_str() {
        "1" | "x" | "ux" => Direction::Translation(0),
        "2" | "y" | "uy" => Direction::Translation(1),
        "3" | "z" | "uz" => Direction::Translation(2),
        "4" | "5" | "6" | "rotx" | "roty" | "rotz" | "rx" | "ry" | "rz" | "urx" | "ury" | "urz" => {
            Direction::Rotation
        }
        _ => Direction::Unknown,
    }
}

fn split_fields(t: &str) -> Vec<&str> {
    t.split(|c: char| c == ',' || c.is_whitespace())
        .filter(|s| !s.is_empty())
        .collect()
}

/// Parses a DoF map (format detected from the content, see the module
/// documentation) into one [`DofRow`] per matrix row, in row order. Checks
/// that no (node, direction) repeats, that no row is missing and that every
/// node has all three directions.
pub fn parse_dof_map(text: &str, path: &Path) -> Result<(DofMapFormat, Vec<DofRow>), ImportError> {
    let err = |line: usize, msg: String| ImportError::new(path, line, msg);
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let data: Vec<(usize, &str)> = text
        .lines()
        .enumerate()
        .map(|(k, l)| (k + 1, l.trim()))
        .filter(|(_, t)| !(t.is_empty() || t.starts_with('#') || t.starts_with('%')))
        .collect();
    let Some(&(first_line, first)) = data.first() else {
        return Err(err(0, "the DoF map lists no rows".into()));
    };
    let first_fields = split_fields(first);
    let (format, body) = if first_fields
        .first()
        .is_some_and(|t| t.eq_ignore_ascii_case("matrix"))
    {
        (DofMapFormat::AnsysMapping, &data[1..])
    } else {
        match first_fields.len() {
            1 if first.contains('.') => (DofMapFormat::CalculixDof, &data[..]),
            2 => (DofMapFormat::NodeDirection, &data[..]),
            3 => (DofMapFormat::AnsysMapping, &data[..]),
            _ => {
                return Err(err(
                    first_line,
                    format!(
                        "unrecognised DoF map line '{}': expected an ANSYS mapping (header 'Matrix Eqn Node \
                         DOF', then 'eqn node label'), a CalculiX .dof ('node.direction' per line) or a \
                         two-column list 'node direction'",
                        clip(first)
                    ),
                ));
            }
        }
    };
    if body.is_empty() {
        return Err(err(0, "the DoF map lists no rows".into()));
    }

    let node_id = |s: &str, line: usize| {
        s.parse::<u64>().map_err(|_| {
            err(
                line,
                format!("malformed node id '{s}': expected a non-negative integer"),
            )
        })
    };
    let dir = |tok: &str, node: u64, line: usize, expected: &str| match direction(tok) {
        Direction::Translation(d) => Ok(d),
        Direction::Rotation => Err(err(
            line,
            format!(
                "node {node}: rotational DoF '{tok}': only solid models (three translations per node) \
                 are supported; beam and shell models carry rotations the import cannot represent"
            ),
        )),
        Direction::Unknown => Err(err(
            line,
            format!("node {node}: unsupported direction '{tok}', expected {expected}"),
        )),
    };

    // Rows in file order, with their 0-based matrix row.
    let mut listed: Vec<(usize, DofRow)> = Vec::with_capacity(body.len());
    match format {
        DofMapFormat::CalculixDof => {
            for (r, &(line, t)) in body.iter().enumerate() {
                let Some((ns, ds)) = t
                    .split_once('.')
                    .filter(|_| !t.contains(char::is_whitespace))
                else {
                    return Err(err(
                        line,
                        format!(
                            "found '{}', expected 'node.direction' like the first line (CalculiX .dof)",
                            clip(t)
                        ),
                    ));
                };
                let node = node_id(ns, line)?;
                let d = dir(ds, node, line, "1, 2 or 3")?;
                listed.push((
                    r,
                    DofRow {
                        node,
                        direction: d,
                        line,
                    },
                ));
            }
        }
        DofMapFormat::NodeDirection => {
            for (r, &(line, t)) in body.iter().enumerate() {
                let f = split_fields(t);
                if f.len() != 2 {
                    return Err(err(
                        line,
                        format!(
                            "found {} values in '{}', expected 'node direction'",
                            f.len(),
                            clip(t)
                        ),
                    ));
                }
                let node = node_id(f[0], line)?;
                let d = dir(f[1], node, line, "1, 2, 3, x, y, z or UX, UY, UZ")?;
                listed.push((
                    r,
                    DofRow {
                        node,
                        direction: d,
                        line,
                    },
                ));
            }
        }
        DofMapFormat::AnsysMapping => {
            let mut eqn_line: HashMap<usize, usize> = HashMap::with_capacity(body.len());
            let mut max_eqn = (0, 0);
            for &(line, t) in body {
                let f = split_fields(t);
                if f.len() != 3 {
                    return Err(err(
                        line,
                        format!(
                            "found {} values in '{}', expected 'eqn node label' (ANSYS mapping)",
                            f.len(),
                            clip(t)
                        ),
                    ));
                }
                let eqn = match f[0].parse::<usize>() {
                    Ok(e) if e >= 1 => e,
                    _ => {
                        return Err(err(
                            line,
                            format!(
                                "malformed equation number '{}': expected a positive integer",
                                f[0]
                            ),
                        ));
                    }
                };
                if let Some(first) = eqn_line.insert(eqn, line) {
                    return Err(err(
                        line,
                        format!("equation {eqn} is listed twice (first on line {first})"),
                    ));
                }
                if eqn > max_eqn.0 {
                    max_eqn = (eqn, line);
                }
                let node = node_id(f[1], line)?;
                let d = dir(f[2], node, line, "UX, UY or UZ")?;
                listed.push((
                    eqn - 1,
                    DofRow {
                        node,
                        direction: d,
                        line,
                    },
                ));
            }
            if max_eqn.0 > body.len() {
                // The equation numbers are distinct, so at most body.len()
                // of the first body.len() + 5 are present: the scan is short.
                let missing: Vec<String> = (1..=max_eqn.0)
                    .filter(|e| !eqn_line.contains_key(e))
                    .take(5)
                    .map(|e| e.to_string())
                    .collect();
                return Err(err(
                    0,
                    format!(
                        "the map lists {} rows but equation numbers go up to {} (line {}): rows {}{} have \
                         no entry",
                        body.len(),
                        max_eqn.0,
                        max_eqn.1,
                        missing.join(", "),
                        if max_eqn.0 - body.len() > missing.len() {
                            ", ..."
                        } else {
                            ""
                        }
                    ),
                ));
            }
        }
    }

    let mut seen: HashMap<(u64, usize), usize> = HashMap::with_capacity(listed.len());
    // Per node: first line and the line of each direction, in order of first
    // appearance so the reported node is the first incomplete one in the file.
    let mut per_node: HashMap<u64, usize> = HashMap::new();
    let mut nodes: Vec<(u64, usize, [Option<usize>; 3])> = Vec::new();
    for (_, row) in &listed {
        if let Some(first) = seen.insert((row.node, row.direction), row.line) {
            return Err(err(
                row.line,
                format!(
                    "node {} direction {} is listed twice (first on line {first}): each DoF must be one \
                     matrix row",
                    row.node, DIRECTIONS[row.direction]
                ),
            ));
        }
        let k = *per_node.entry(row.node).or_insert_with(|| {
            nodes.push((row.node, row.line, [None; 3]));
            nodes.len() - 1
        });
        nodes[k].2[row.direction] = Some(row.line);
    }
    for (node, line, dirs) in &nodes {
        let missing: Vec<&str> = (0..3)
            .filter(|&d| dirs[d].is_none())
            .map(|d| DIRECTIONS[d])
            .collect();
        if !missing.is_empty() {
            let present: Vec<&str> = (0..3)
                .filter(|&d| dirs[d].is_some())
                .map(|d| DIRECTIONS[d])
                .collect();
            return Err(err(
                *line,
                format!(
                    "node {node} has rows for {} but none for {}: only solid models with all three \
                     translations at every node are supported. CalculiX and ANSYS leave DoFs fixed by \
                     boundary conditions out of the exported matrices: export them from the model \
                     without *BOUNDARY / D constraints",
                    present.join(", "),
                    missing.join(", ")
                ),
            ));
        }
    }

    let mut rows = vec![None; listed.len()];
    for (r, row) in listed {
        if let Some(slot) = rows.get_mut(r) {
            *slot = Some(row);
        }
    }
    let rows: Option<Vec<DofRow>> = rows.into_iter().collect();
    match rows {
        Some(rows) => Ok((format, rows)),
        None => Err(err(0, "the DoF map does not cover every matrix row".into())),
    }
}

// ---------------------------------------------------------------------------
// Node files

#[derive(Debug)]
struct NodeFile {
    ids: Vec<u64>,
    coords: Vec<[f64; 3]>,
    /// Sets in file indices.
    sets: BTreeMap<String, Vec<usize>>,
}

fn read_nodes(path: &Path) -> Result<NodeFile, ImportError> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase());
    let mesh = match ext.as_deref() {
        Some("inp") => super::read_mesh(path)?,
        Some("msh") => {
            let mut text = read_text(path)?;
            // The .msh reader insists on an $Elements section; a node-only
            // export gets an empty one appended, past every real line, so
            // line numbers in messages stay right.
            let has = |s: &str| text.lines().any(|l| l.trim() == s);
            if has("$Nodes") && !has("$Elements") {
                if !text.ends_with('\n') {
                    text.push('\n');
                }
                text.push_str("$Elements\n0 0 0 0\n$EndElements\n");
            }
            super::parse_msh(&text, path)?
        }
        _ => {
            let (ids, coords) = parse_node_table(&read_text(path)?, path)?;
            return Ok(NodeFile {
                ids,
                coords,
                sets: BTreeMap::new(),
            });
        }
    };
    if mesh.nodes.is_empty() {
        return Err(ImportError::new(path, 0, "the node file defines no nodes"));
    }
    Ok(NodeFile {
        ids: mesh.node_ids,
        coords: mesh.nodes,
        sets: mesh.node_sets,
    })
}

/// Parses a node table: `id x y z` per line, comma and/or whitespace
/// separated; blank lines and lines starting with `#`, `*` or `%` are
/// skipped. Returns ids and coordinates in file order.
pub fn parse_node_table(text: &str, path: &Path) -> Result<(Vec<u64>, Vec<[f64; 3]>), ImportError> {
    let err = |line: usize, msg: String| ImportError::new(path, line, msg);
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut ids = Vec::new();
    let mut coords = Vec::new();
    let mut first_line: HashMap<u64, usize> = HashMap::new();
    for (k, raw) in text.lines().enumerate() {
        let line = k + 1;
        let t = raw.trim();
        if t.is_empty() || t.starts_with(['#', '*', '%']) {
            continue;
        }
        let f = split_fields(t);
        if f.len() != 4 {
            return Err(err(
                line,
                format!(
                    "found {} values in '{}', expected 'id x y z' (comment lines start with #, * or %)",
                    f.len(),
                    clip(t)
                ),
            ));
        }
        let id = f[0].parse::<u64>().map_err(|_| {
            err(
                line,
                format!(
                    "malformed node id '{}': expected a non-negative integer",
                    f[0]
                ),
            )
        })?;
        let mut x = [0.0; 3];
        for d in 0..3 {
            let s = f[d + 1];
            x[d] = match parse_f64(s) {
                Some(v) if v.is_finite() => v,
                Some(_) => {
                    return Err(err(
                        line,
                        format!(
                            "coordinate {} of node {id} is not finite: '{s}'",
                            DIRECTIONS[d]
                        ),
                    ));
                }
                None => {
                    return Err(err(
                        line,
                        format!(
                            "malformed coordinate {} of node {id}: '{s}', expected a number",
                            DIRECTIONS[d]
                        ),
                    ));
                }
            };
        }
        if let Some(first) = first_line.insert(id, line) {
            return Err(err(
                line,
                format!("duplicate node id {id} (first defined on line {first})"),
            ));
        }
        ids.push(id);
        coords.push(x);
    }
    if ids.is_empty() {
        return Err(err(
            0,
            "the node file defines no nodes (expected 'id x y z' lines)".into(),
        ));
    }
    Ok((ids, coords))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    const P: &str = "k.mtx";

    fn mm(text: &str) -> Result<SparseColMat<usize, f64>, ImportError> {
        parse_matrix_market(text, Path::new(P))
    }

    /// Asserts the error is on `line` of `file` and its message contains all `parts`.
    fn check_err(e: ImportError, file: &str, line: usize, parts: &[&str]) {
        assert_eq!(e.line, line, "wrong line for: {e}");
        assert!(e.file.ends_with(file), "wrong file for: {e}");
        for p in parts {
            assert!(e.message.contains(p), "message lacks '{p}': {e}");
        }
    }

    fn mm_err(text: &str, line: usize, parts: &[&str]) {
        check_err(mm(text).unwrap_err(), P, line, parts);
    }

    fn dense(m: &SparseColMat<usize, f64>) -> Vec<Vec<f64>> {
        let d = m.to_dense();
        (0..d.nrows())
            .map(|i| (0..d.ncols()).map(|j| d[(i, j)]).collect())
            .collect()
    }

    #[test]
    fn symmetric_file_either_triangle() {
        let upper = "%%MatrixMarket matrix coordinate real symmetric\n% comment\n%\n3 3 4\n1 1 2.0\n1 3 -1\n2 2 3e0\n3 3 4.0D0\n";
        let lower = "%%matrixmarket MATRIX Coordinate REAL Symmetric\n3 3 4\n1 1 2.0\n3 1 -1\n2 2 3e0\n\n3 3 4\n";
        let want = vec![
            vec![2.0, 0.0, -1.0],
            vec![0.0, 3.0, 0.0],
            vec![-1.0, 0.0, 4.0],
        ];
        assert_eq!(dense(&mm(upper).unwrap()), want);
        assert_eq!(dense(&mm(lower).unwrap()), want);
        // Mixed triangles without a mirrored pair are harmless.
        let mixed = "%%MatrixMarket matrix coordinate integer symmetric\n3 3 5\n1 1 2\n3 1 -1\n2 2 3\n2 3 5\n3 3 4\n";
        assert_eq!(dense(&mm(mixed).unwrap())[1][2], 5.0);
        assert_eq!(dense(&mm(mixed).unwrap())[2][1], 5.0);
    }

    #[test]
    fn general_file_is_symmetrised_exactly() {
        let t = "%%MatrixMarket matrix coordinate real general\n2 2 4\n1 1 1e6\n1 2 0.30000000000000004\n2 1 0.3\n2 2 1e6\n";
        let m = mm(t).unwrap();
        let d = dense(&m);
        assert_eq!(d[0][1], d[1][0]);
        assert_eq!(d[0][1], 0.5 * 0.30000000000000004 + 0.5 * 0.3);
    }

    #[test]
    fn duplicates_are_summed() {
        let t = "%%MatrixMarket matrix coordinate real symmetric\n2 2 5\n1 1 1\n2 1 0.5\n1 1 2\n2 2 4\n2 1 0.25\n";
        assert_eq!(
            dense(&mm(t).unwrap()),
            vec![vec![3.0, 0.75], vec![0.75, 4.0]]
        );
        let g = "%%MatrixMarket matrix coordinate real general\n2 2 5\n1 2 1\n2 1 0.5\n1 2 -0.5\n1 1 1\n2 2 1\n";
        assert_eq!(dense(&mm(g).unwrap()), vec![vec![1.0, 0.5], vec![0.5, 1.0]]);
    }

    #[test]
    fn matrix_market_errors() {
        let h = "%%MatrixMarket matrix coordinate real symmetric\n";
        mm_err("", 0, &["empty file"]);
        mm_err(
            "%%MatrixMarket matrix array real general\n2 2\n1\n2\n3\n4\n",
            1,
            &["'array'", "coordinate"],
        );
        mm_err(
            "%%MatrixMarket matrix coordinate complex general\n1 1 1\n1 1 1 0\n",
            1,
            &["'complex'", "real"],
        );
        mm_err(
            "%%MatrixMarket matrix coordinate pattern symmetric\n1 1 1\n1 1\n",
            1,
            &["'pattern'"],
        );
        mm_err(
            "%%MatrixMarket matrix coordinate real hermitian\n1 1 1\n1 1 1\n",
            1,
            &["'hermitian'"],
        );
        mm_err(
            "%%MatrixMarket matrix coordinate real skew-symmetric\n1 1 0\n",
            1,
            &["'skew-symmetric'"],
        );
        mm_err(
            "%%MatrixMarket matrix coordinate real\n1 1 0\n",
            1,
            &["incomplete"],
        );
        mm_err(
            "1 1 4.9e4\n1 2 1.6e4\n",
            1,
            &["not a Matrix Market file", "CalculiX"],
        );
        mm_err(&format!("{h}% c\n2 3 1\n1 1 1\n"), 3, &["2 x 3", "square"]);
        mm_err(&format!("{h}2 2\n"), 2, &["rows columns entries"]);
        mm_err(&format!("{h}2 2 x\n"), 2, &["malformed size 'x'"]);
        mm_err(
            &format!("{h}2 2 2\n1 1 1\n3 1 1\n"),
            4,
            &["row index 3 out of range", "2 x 2"],
        );
        mm_err(
            &format!("{h}2 2 2\n1 1 1\n1 0 1\n"),
            4,
            &["column index 0 out of range", "1-based"],
        );
        mm_err(
            &format!("{h}2 2 2\n1 1 1\n1.5 1 1\n"),
            4,
            &["malformed row index '1.5'"],
        );
        mm_err(
            &format!("{h}2 2 3\n1 1 1\n2 2 1\n"),
            2,
            &["announces 3 entries", "contains 2"],
        );
        mm_err(
            &format!("{h}2 2 1\n1 1 1\n%\n2 2 1\n"),
            5,
            &["more entries than the 1 announced", "line 2"],
        );
        mm_err(
            &format!("{h}2 2 2\n1 1 1\n2 2 1.0.0\n"),
            4,
            &["malformed number '1.0.0'"],
        );
        mm_err(&format!("{h}2 2 2\n1 1 1\n2 2 NaN\n"), 4, &["not finite"]);
        mm_err(&format!("{h}2 2 2\n1 1 inf\n2 2 1\n"), 3, &["not finite"]);
        mm_err(&format!("{h}2 2 2\n1 1 1e999\n2 2 1\n"), 3, &["not finite"]);
        mm_err(
            &format!("{h}2 2 2\n1 1 1\n2 2 1 0\n"),
            4,
            &["4 values", "row column value"],
        );
        mm_err(
            "%%MatrixMarket matrix coordinate integer general\n1 1 1\n1 1 1.5\n",
            3,
            &["malformed value '1.5'", "integer"],
        );
        mm_err(
            &format!("{h}2 2 4\n1 1 1\n2 1 0.5\n2 2 1\n1 2 0.5\n"),
            6,
            &["mirrors the entry (2, 1) on line 4", "one triangle"],
        );
        // Worst asymmetric pair reported, on the line of one of its entries.
        mm_err(
            "%%MatrixMarket matrix coordinate real general\n3 3 6\n1 1 10\n2 2 10\n3 3 10\n1 2 1\n2 1 1.00000000001\n2 3 5e-9\n",
            8,
            &[
                "not symmetric",
                "A(2, 3) = 5e-9",
                "A(3, 2) = 0 (no entry)",
                "1e-10 x max|diagonal| = 1.000e-9",
            ],
        );
        mm_err(
            "%%MatrixMarket matrix coordinate real general\n2 2 4\n1 1 10\n2 2 10\n2 1 1\n1 2 2\n",
            6,
            &["not symmetric", "A(1, 2) = 2e0", "A(2, 1) = 1e0 (line 5)"],
        );
    }

    #[test]
    fn tolerated_asymmetry_is_relative_to_the_diagonal() {
        let t = "%%MatrixMarket matrix coordinate real general\n2 2 4\n1 1 1e10\n2 2 1\n1 2 0.5\n2 1 0.5000001\n";
        assert!(mm(t).is_ok());
    }

    const DP: &str = "map.txt";

    fn dof(text: &str) -> Result<(DofMapFormat, Vec<DofRow>), ImportError> {
        parse_dof_map(text, Path::new(DP))
    }

    fn dof_err(text: &str, line: usize, parts: &[&str]) {
        check_err(dof(text).unwrap_err(), DP, line, parts);
    }

    fn pairs(rows: &[DofRow]) -> Vec<(u64, usize)> {
        rows.iter().map(|r| (r.node, r.direction)).collect()
    }

    #[test]
    fn dof_map_formats() {
        let ansys = "Matrix Eqn   Node   DOF\n     3      7    UZ\n     1      7    UX\n     2      7    uy\n     6      2    UZ\n     4      2    UX\n     5      2    UY\n";
        let (f, rows) = dof(ansys).unwrap();
        assert_eq!(f, DofMapFormat::AnsysMapping);
        assert_eq!(
            pairs(&rows),
            vec![(7, 0), (7, 1), (7, 2), (2, 0), (2, 1), (2, 2)]
        );
        assert_eq!(rows[0].line, 3);

        let (f, rows) = dof("7.1\n7.2\n7.3\n2.1\n2.2\n2.3\n").unwrap();
        assert_eq!(f, DofMapFormat::CalculixDof);
        assert_eq!(
            pairs(&rows),
            vec![(7, 0), (7, 1), (7, 2), (2, 0), (2, 1), (2, 2)]
        );

        let plain = "# node direction\n7 1\n7, y\n\n% z last\n7 UZ\n2 X\n2\t2\n2 uz\n";
        let (f, rows) = dof(plain).unwrap();
        assert_eq!(f, DofMapFormat::NodeDirection);
        assert_eq!(
            pairs(&rows),
            vec![(7, 0), (7, 1), (7, 2), (2, 0), (2, 1), (2, 2)]
        );
        assert_eq!(rows[2].line, 6);
    }

    /// The .dof CalculiX 2.20 writes for one C3D8 element (nodes 1..8) with
    /// `*FREQUENCY, SOLVER=MATRIXSTORAGE`: node-major, `%d.%d`, no header.
    const CCX_DOF: &str = "1.1\n1.2\n1.3\n2.1\n2.2\n2.3\n3.1\n3.2\n3.3\n4.1\n4.2\n4.3\n5.1\n5.2\n5.3\n6.1\n6.2\n6.3\n7.1\n7.2\n7.3\n8.1\n8.2\n8.3\n";

    /// The same deck with `*BOUNDARY` on 101,1,3 and 4,2,2 (node 1 renamed
    /// 101): CalculiX leaves the fixed DoFs out.
    const CCX_DOF_WITH_BC: &str = "2.1\n2.2\n2.3\n3.1\n3.2\n3.3\n4.1\n4.3\n5.1\n5.2\n5.3\n6.1\n6.2\n6.3\n7.1\n7.2\n7.3\n8.1\n8.2\n8.3\n";

    #[test]
    fn calculix_matrixstorage_dof() {
        let (f, rows) = dof(CCX_DOF).unwrap();
        assert_eq!(f, DofMapFormat::CalculixDof);
        assert_eq!(rows.len(), 24);
        for (r, row) in rows.iter().enumerate() {
            assert_eq!(
                (row.node, row.direction, row.line),
                (r as u64 / 3 + 1, r % 3, r + 1)
            );
        }
        dof_err(
            CCX_DOF_WITH_BC,
            7,
            &[
                "node 4 has rows for x, z but none for y",
                "boundary conditions",
            ],
        );
    }

    #[test]
    fn dof_map_errors() {
        dof_err("", 0, &["no rows"]);
        dof_err("# only comments\n", 0, &["no rows"]);
        dof_err(
            "Matrix Eqn Node DOF\n1 1 UX\n2 1 UY\n3 1 ROTX\n",
            4,
            &["rotational DoF 'ROTX'", "solid"],
        );
        dof_err("1.1\n1.2\n1.4\n", 3, &["rotational DoF '4'"]);
        dof_err("1 x\n1 y\n1 rotz\n", 3, &["rotational DoF 'rotz'"]);
        dof_err(
            "Matrix Eqn Node DOF\n1 1 UX\n2 1 UY\n3 1 TEMP\n",
            4,
            &["unsupported direction 'TEMP'", "UX, UY or UZ"],
        );
        dof_err("1 x\n1 w\n", 2, &["unsupported direction 'w'"]);
        dof_err(
            "1.1\n1.2\n1.3\n1.2\n",
            4,
            &["node 1 direction y is listed twice (first on line 2)"],
        );
        dof_err(
            "1 1\n1 2\n1 3\n2 1\n2 2\n2 x\n",
            6,
            &["node 2 direction x is listed twice (first on line 4)"],
        );
        dof_err(
            "Matrix Eqn Node DOF\n1 1 UX\n2 1 UY\n2 1 UZ\n",
            4,
            &["equation 2 is listed twice (first on line 3)"],
        );
        dof_err(
            "Matrix Eqn Node DOF\n1 1 UX\n2 1 UY\n5 1 UZ\n",
            0,
            &["3 rows", "up to 5 (line 4)", "rows 3, 4 have no entry"],
        );
        dof_err(
            "Matrix Eqn Node DOF\n0 1 UX\n",
            2,
            &["malformed equation number '0'"],
        );
        dof_err("1.1\n1.2\n1 3\n", 3, &["expected 'node.direction'"]);
        dof_err("1.1\n1.2\nx.3\n", 3, &["malformed node id 'x'"]);
        dof_err("1 1\n1 2 3\n", 2, &["found 3 values", "node direction"]);
        dof_err("1 2 3 4\n", 1, &["unrecognised DoF map line"]);
        dof_err(
            "5 x\n5 z\n6 x\n6 y\n6 z\n",
            1,
            &["node 5 has rows for x, z but none for y"],
        );
    }

    #[test]
    fn node_table() {
        let t = "# id x y z\n* from a deck\n% or so\n\n10, 0.0, 1.0, 2.0\n 20 1e-3 -2.5D1 3\n30,4 5, 6\n";
        let (ids, x) = parse_node_table(t, Path::new("n.txt")).unwrap();
        assert_eq!(ids, vec![10, 20, 30]);
        assert_eq!(
            x,
            vec![[0.0, 1.0, 2.0], [1e-3, -25.0, 3.0], [4.0, 5.0, 6.0]]
        );
        let e = |t: &str| parse_node_table(t, Path::new("n.txt")).unwrap_err();
        check_err(
            e("1 0 0 0\n\n1 1 1 1\n"),
            "n.txt",
            3,
            &["duplicate node id 1 (first defined on line 1)"],
        );
        check_err(
            e("1 0 0 0\n2 0 0\n"),
            "n.txt",
            2,
            &["found 3 values", "id x y z"],
        );
        check_err(
            e("1 0 0 0\n2 0 a 0\n"),
            "n.txt",
            2,
            &["malformed coordinate y of node 2: 'a'"],
        );
        check_err(
            e("1 0 0 0\n2 0 0 nan\n"),
            "n.txt",
            2,
            &["coordinate z of node 2 is not finite"],
        );
        check_err(e("-1 0 0 0\n"), "n.txt", 1, &["malformed node id '-1'"]);
        check_err(e("# nothing\n"), "n.txt", 0, &["no nodes"]);
    }

    /// A scratch directory unique to the test.
    fn scratch(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("matrices-test-{}-{name}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

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
        let coords: Vec<[f64; 3]> = unit
            .iter()
            .map(|p| [0, 1, 2].map(|d| base[d] + 0.02 * p[d]))
            .collect();
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
            map += &format!(
                "{:>10} {:>6}    {}\n",
                r + 1,
                ids[p / 3],
                ["UX", "UY", "UZ"][p % 3]
            );
        }
        std::fs::write(dir.join("k.mapping"), map).unwrap();
        let mut inp = String::from("** nodes only\n*NODE, NSET=NALL\n999, 5., 5., 5.\n");
        for a in (0..8).rev() {
            inp += &format!(
                "{}, {:e}, {:e}, {:e}\n",
                ids[a], coords[a][0], coords[a][1], coords[a][2]
            );
        }
        inp += &format!(
            "*NSET, NSET=BOTTOM\n{}, {}, {}, {}, 999\n",
            ids[0], ids[1], ids[2], ids[3]
        );
        std::fs::write(dir.join("nodes.inp"), inp).unwrap();
        CellFiles {
            dir,
            k,
            m,
            coords,
            ids,
            perm,
        }
    }

    impl CellFiles {
        fn files(&self) -> (PathBuf, PathBuf, PathBuf, PathBuf, PathBuf) {
            let d = &self.dir;
            (
                d.join("k.mtx"),
                d.join("m.mtx"),
                d.join("d.mtx"),
                d.join("k.mapping"),
                d.join("nodes.inp"),
            )
        }
    }

    #[test]
    fn round_trip_and_rigid_body_residual() {
        let h = cell_files("roundtrip", NEAR);
        let (k, m, d, map, nodes) = h.files();
        let files = MatrixFiles {
            stiffness: &k,
            mass: &m,
            damping: Some(&d),
            dof_map: &map,
            nodes: &nodes,
        };
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
                assert_eq!(
                    dmp[dof(a)][dof(b)],
                    1e-5 * h.k[a * 24 + b] + 2.0 * h.m[a * 24 + b]
                );
            }
        }
        assert_eq!(model.stiffness.nrows(), 24);
        for (c, r) in model.rigid_body_residual.iter().enumerate() {
            assert!(*r < 1e-14, "{}: {r:e}", RIGID_BODY_MOTIONS[c]);
        }
        assert_eq!(
            rigid_body_residual(&model.stiffness, &model.nodes),
            model.rigid_body_residual
        );
        std::fs::remove_dir_all(&h.dir).ok();
    }

    /// 100 m from the origin a 2 cm cell's coordinates carry only ~1e-12 of
    /// its size, so its own stiffness is rigid-body free to that level only;
    /// still far inside the free-free tolerance.
    #[test]
    fn far_from_origin_is_still_free_free() {
        let h = cell_files("far", [100.0, -50.0, 20.0]);
        let (k, m, _, map, nodes) = h.files();
        let files = MatrixFiles {
            stiffness: &k,
            mass: &m,
            damping: None,
            dof_map: &map,
            nodes: &nodes,
        };
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
        let files = MatrixFiles {
            stiffness: &k,
            mass: &m,
            damping: None,
            dof_map: &map,
            nodes: &nodes,
        };
        let e = read_matrix_model(&files, true).unwrap_err();
        check_err(
            e,
            "k.mtx",
            0,
            &[
                "translation y",
                "rotation about x",
                "rotation about z",
                "node 31 y",
                "supports",
                "free-free",
            ],
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
            let files = MatrixFiles {
                stiffness: k,
                mass: m,
                damping: None,
                dof_map: map,
                nodes,
            };
            read_matrix_model(&files, true)
        };

        // A node of the map missing from the node file.
        let few = dir.join("few.txt");
        std::fs::write(&few, "11 0 0 0\n21 1 0 0\n").unwrap();
        let e = model(&k, &m, &map, &few).unwrap_err();
        assert!(e.file.ends_with("k.mapping"), "{e}");
        assert!(
            e.message
                .contains("node 81 of the DoF map is not defined in the node file"),
            "{e}"
        );
        assert_eq!(e.line, 2, "{e}"); // the mapping lists row 24 first

        // Matrix size differs from the map.
        let small = dir.join("small.mtx");
        std::fs::write(
            &small,
            "%%MatrixMarket matrix coordinate real symmetric\n%\n3 3 1\n1 1 1\n",
        )
        .unwrap();
        check_err(
            model(&k, &small, &map, &nodes).unwrap_err(),
            "small.mtx",
            3,
            &["3 x 3", "has 24 rows", "k.mapping"],
        );
        let files = MatrixFiles {
            stiffness: &k,
            mass: &m,
            damping: Some(&small),
            dof_map: &map,
            nodes: &nodes,
        };
        check_err(
            read_matrix_model(&files, true).unwrap_err(),
            "small.mtx",
            3,
            &["has 24 rows"],
        );

        // Non-positive diagonal: named by node and direction.
        let mut ks = h.k.clone();
        ks[5 * 24 + 5] = -1.0; // cell node 1 (id 21), z
        let bad = dir.join("bad_k.mtx");
        write_mm(&bad, &ks, 24, &h.perm, true);
        let e = model(&bad, &m, &map, &nodes).unwrap_err();
        assert!(e.line > 3 && e.file.ends_with("bad_k.mtx"), "{e}");
        for part in [
            "stiffness diagonal entry of row",
            "(node 21 z) is -1e0",
            "positive",
        ] {
            assert!(e.message.contains(part), "{e}");
        }

        // Mass with positive diagonal but indefinite.
        let mut ms = h.m.clone();
        // Far above the mass scale: the x/y block of node 11 becomes indefinite.
        ms[1] = 1.0;
        ms[24] = 1.0;
        let bad = dir.join("bad_m.mtx");
        write_mm(&bad, &ms, 24, &h.perm, true);
        check_err(
            model(&k, &bad, &map, &nodes).unwrap_err(),
            "bad_m.mtx",
            0,
            &["mass matrix is indefinite"],
        );

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

    #[test]
    fn msh_node_file_without_elements() {
        let dir = scratch("msh");
        let msh = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 2 1 2\n3 1 0 2\n5\n9\n0 0 0\n1 2 3\n$EndNodes\n";
        std::fs::write(dir.join("n.msh"), msh).unwrap();
        let nf = read_nodes(&dir.join("n.msh")).unwrap();
        assert_eq!(nf.ids, vec![5, 9]);
        assert_eq!(nf.coords[1], [1.0, 2.0, 3.0]);
        let with_empty = format!("{msh}$Elements\n0 0 0 0\n$EndElements\n");
        std::fs::write(dir.join("e.msh"), with_empty).unwrap();
        assert_eq!(read_nodes(&dir.join("e.msh")).unwrap().ids, vec![5, 9]);
        // Errors still carry the real line numbers.
        std::fs::write(dir.join("bad.msh"), msh.replace("1 2 3", "1 x 3")).unwrap();
        let e = read_nodes(&dir.join("bad.msh")).unwrap_err();
        assert_eq!(e.line, 10, "{e}");
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn rigid_body_residual_edge_cases() {
        let k = SparseColMat::<usize, f64>::try_new_from_triplets(3, 3, &[Triplet::new(0, 0, 1.0)])
            .unwrap();
        assert!(
            rigid_body_residual(&k, &[[0.0; 3], [1.0; 3]])
                .iter()
                .all(|r| r.is_nan())
        );
        // One node: rotations vanish; a spring on x resists translation x only.
        assert_eq!(
            rigid_body_residual(&k, &[[1.0, 2.0, 3.0]]),
            [1.0, 0.0, 0.0, 0.0, 0.0, 0.0]
        );
        let zero = SparseColMat::<usize, f64>::try_new_from_triplets(3, 3, &[]).unwrap();
        assert_eq!(rigid_body_residual(&zero, &[[1.0, 2.0, 3.0]]), [0.0; 6]);
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
        let junk = [
            "",
            " ",
            "\n",
            "%",
            "0",
            "-",
            "9999999999999999999999",
            "é",
            ".",
            "nan",
            "\u{feff}",
        ];
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
