//! Matrix Market coordinate files (see the format notes of the parent
//! module).

use super::{clip, parse_f64};
use crate::file_read::FileKind;
use crate::import::{ImportError, read_text_of_kind};
use faer::sparse::{SparseColMat, Triplet};
use std::path::Path;

/// Allowed asymmetry of a `general` matrix, relative to its largest diagonal
/// magnitude. Exporters write 13-17 significant digits, so a symmetric
/// assembled matrix differs from its transpose by far less than this.
pub const SYMMETRY_TOLERANCE: f64 = 1e-10;

/// One stored entry, file numbering, 0-based. `u32` indices keep the parse
/// of a 10^7-entry file a third smaller; sizes beyond that are refused.
#[derive(Debug, Clone, Copy)]
pub(super) struct Entry {
    pub(super) i: u32,
    pub(super) j: u32,
    pub(super) v: f64,
    pub(super) line: usize,
}

/// A parsed, exactly symmetric matrix in file numbering: the upper triangle
/// (i <= j), duplicates summed.
pub(super) struct SymMatrix {
    pub(super) n: usize,
    pub(super) upper: Vec<Entry>,
}

impl SymMatrix {
    /// The full matrix with row/column r moved to perm[r] (a permutation of
    /// 0..n). Explicit zeros are dropped.
    pub(super) fn to_sparse(&self, perm: &[usize], path: &Path) -> Result<SparseColMat<usize, f64>, ImportError> {
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
            ImportError::new(
                path,
                0,
                format!("cannot build the sparse matrix: {}", fe_linalg::faer_error::creation(&e)),
            )
            .caused_by(e)
        })
    }
}

/// Parses a Matrix Market coordinate file into the full, exactly symmetric
/// matrix in file numbering (see the module documentation for what is
/// accepted).
pub fn parse_matrix_market(text: &str, path: &Path) -> Result<SparseColMat<usize, f64>, ImportError> {
    let m = parse_mm(text, path, None, &|r| format!("row {}", r + 1))?;
    let identity: Vec<usize> = (0..m.n).collect();
    m.to_sparse(&identity, path)
}

pub(super) fn read_mm(
    path: &Path,
    expect: Option<(usize, &Path)>,
    label: &dyn Fn(usize) -> String,
) -> Result<SymMatrix, ImportError> {
    parse_mm(&read_text_of_kind(path, FileKind::Matrix)?, path, expect, label)
}

/// The next line that is neither blank nor a `%` comment; `last` follows
/// the lines consumed, for messages about a file that ends early.
fn next_data<'a>(lines: &mut impl Iterator<Item = (usize, &'a str)>, last: &mut usize) -> Option<(usize, &'a str)> {
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
    let Header { integer, symmetric } = header(first, path)?;
    let mut last = 1;
    let Some((size_line, size_text)) = next_data(&mut lines, &mut last) else {
        return Err(err(last, "missing size line 'rows columns entries' after the header".into()));
    };
    let (n, nnz) = size(size_line, size_text, expect, path)?;
    let entries =
        entries(&mut lines, &mut last, Size { n, nnz, line: size_line, text_len: text.len() }, integer, path)?;
    let merged = merge_duplicates(entries, path)?;
    let upper = if symmetric { stored_triangle(&merged, path)? } else { symmetrised(&merged, label, path)? };
    Ok(SymMatrix { n, upper })
}

/// What the header line declares of the entries: integer (else real) values, one triangle
/// stored (else both).
struct Header {
    integer: bool,
    symmetric: bool,
}

/// The header line `%%MatrixMarket matrix coordinate real|integer general|symmetric`.
fn header(first: &str, path: &Path) -> Result<Header, ImportError> {
    let err = |line: usize, msg: String| ImportError::new(path, line, msg);
    let head: Vec<&str> = first.split_whitespace().collect();
    if !head.first().is_some_and(|t| t.eq_ignore_ascii_case("%%MatrixMarket")) {
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
    let (object, format) = (head[1].to_ascii_lowercase(), head[2].to_ascii_lowercase());
    if object != "matrix" {
        return Err(err(1, format!("Matrix Market object '{}' is not supported: expected 'matrix'", head[1])));
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
            return Err(err(1, format!("unknown Matrix Market format '{}': expected 'coordinate'", head[2])));
        }
    }
    Ok(Header { integer: integer_field(&head, path)?, symmetric: symmetric_storage(&head, path)? })
}

/// The header's field: `integer` (true) or `real` (false).
fn integer_field(head: &[&str], path: &Path) -> Result<bool, ImportError> {
    let err = |line: usize, msg: String| ImportError::new(path, line, msg);
    let field = head[3].to_ascii_lowercase();
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
            return Err(err(1, format!("unknown Matrix Market field '{}': expected 'real' or 'integer'", head[3])));
        }
    };
    Ok(integer)
}

/// The header's symmetry: `symmetric` (true) or `general` (false).
fn symmetric_storage(head: &[&str], path: &Path) -> Result<bool, ImportError> {
    let err = |line: usize, msg: String| ImportError::new(path, line, msg);
    let symmetry = head[4].to_ascii_lowercase();
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
                format!("unknown Matrix Market symmetry '{}': expected 'general' or 'symmetric'", head[4]),
            ));
        }
    };

    Ok(symmetric)
}

/// The size line `rows columns entries`: the matrix's size and its entry count.
fn size(
    size_line: usize,
    size_text: &str,
    expect: Option<(usize, &Path)>,
    path: &Path,
) -> Result<(usize, usize), ImportError> {
    let err = |line: usize, msg: String| ImportError::new(path, line, msg);
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
            err(size_line, format!("malformed size '{s}' on the size line: expected a non-negative integer"))
        })?;
    }
    let [n, cols, nnz] = dims;
    if n != cols {
        return Err(err(size_line, format!("matrix is {n} x {cols}: stiffness, mass and damping must be square")));
    }
    if n > u32::MAX as usize {
        return Err(err(size_line, format!("matrix size {n} is too large (at most {})", u32::MAX)));
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
    Ok((n, nnz))
}

/// What the size line announced, and the file's length (which bounds a lying size line).
struct Size {
    n: usize,
    nnz: usize,
    line: usize,
    text_len: usize,
}

/// The entries after the size line, as many as it announced.
fn entries<'a>(
    lines: &mut impl Iterator<Item = (usize, &'a str)>,
    last: &mut usize,
    size: Size,
    integer: bool,
    path: &Path,
) -> Result<Vec<Entry>, ImportError> {
    let err = |line: usize, msg: String| ImportError::new(path, line, msg);
    let Size { n, nnz, line: size_line, text_len } = size;
    // Each entry needs at least 6 bytes, which bounds a lying size line.
    let mut entries = Vec::with_capacity(nnz.min(text_len / 6 + 1));
    while let Some((k, t)) = next_data(lines, last) {
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
        entries.push(entry(k, t, n, integer, path)?);
    }
    if entries.len() != nnz {
        return Err(err(
            size_line,
            format!("the size line announces {nnz} entries but the file contains {}", entries.len()),
        ));
    }
    Ok(entries)
}

/// One entry line `row column value` (line `k`) of an `n` x `n` matrix.
fn entry(k: usize, t: &str, n: usize, integer: bool, path: &Path) -> Result<Entry, ImportError> {
    let err = |line: usize, msg: String| ImportError::new(path, line, msg);
    let mut it = t.split_whitespace();
    let (Some(si), Some(sj), Some(sv), None) = (it.next(), it.next(), it.next(), it.next()) else {
        return Err(err(
            k,
            format!("entry '{}' has {} values, expected 'row column value'", clip(t), t.split_whitespace().count()),
        ));
    };
    let index = |s: &str, what: &str| -> Result<u32, ImportError> {
        match s.parse::<usize>() {
            Ok(v) if (1..=n).contains(&v) => Ok((v - 1) as u32),
            Ok(v) => {
                Err(err(k, format!("{what} index {v} out of range: the matrix is {n} x {n} and indices are 1-based")))
            }
            Err(_) => Err(err(k, format!("malformed {what} index '{s}': expected a positive integer"))),
        }
    };
    let i = index(si, "row")?;
    let j = index(sj, "column")?;
    let v = if integer {
        sv.parse::<i64>()
            .map(|v| v as f64)
            .map_err(|_| err(k, format!("malformed value '{sv}': the header declares 'integer' entries")))?
    } else {
        parse_f64(sv).ok_or_else(|| err(k, format!("malformed number '{sv}': expected a real value")))?
    };
    if !v.is_finite() {
        return Err(err(k, format!("value '{sv}' is not finite (NaN or infinity)")));
    }
    Ok(Entry { i, j, v, line: k })
}

/// The entries sorted by position, duplicates summed.
fn merge_duplicates(mut entries: Vec<Entry>, path: &Path) -> Result<Vec<Entry>, ImportError> {
    let err = |line: usize, msg: String| ImportError::new(path, line, msg);
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
    Ok(merged)
}

/// The entry at (i, j) of the sorted, merged entries.
fn find(merged: &[Entry], i: u32, j: u32) -> Option<Entry> {
    merged.binary_search_by_key(&(i, j), |e| (e.i, e.j)).ok().map(|p| merged[p])
}

/// The upper triangle of a `symmetric` file, which stores one triangle, either one.
fn stored_triangle(merged: &[Entry], path: &Path) -> Result<Vec<Entry>, ImportError> {
    let err = |line: usize, msg: String| ImportError::new(path, line, msg);
    let mut upper = Vec::with_capacity(merged.len());
    for e in merged {
        if e.i > e.j
            && let Some(m) = find(merged, e.j, e.i)
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
    Ok(upper)
}

/// The upper triangle of a `general` file: each entry and its mirror averaged, refused where
/// they differ beyond the tolerance.
fn symmetrised(merged: &[Entry], label: &dyn Fn(usize) -> String, path: &Path) -> Result<Vec<Entry>, ImportError> {
    let err = |line: usize, msg: String| ImportError::new(path, line, msg);
    let mut upper = Vec::with_capacity(merged.len());
    let max_diag = merged.iter().filter(|e| e.i == e.j).fold(0.0f64, |m, e| m.max(e.v.abs()));
    let tol = SYMMETRY_TOLERANCE * max_diag;
    // (difference, entry, value of the mirror, line of the mirror)
    let mut worst: Option<(f64, Entry, f64, Option<usize>)> = None;
    for e in merged {
        if e.i == e.j {
            upper.push(*e);
            continue;
        }
        let mirror = find(merged, e.j, e.i);
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
        upper.push(Entry { i, j, v: 0.5 * e.v + 0.5 * mv, line: e.line });
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
    Ok(upper)
}

#[cfg(test)]
mod tests {
    use super::super::test_util::{check_err, dense};
    use super::*;

    const P: &str = "k.mtx";

    fn mm(text: &str) -> Result<SparseColMat<usize, f64>, ImportError> {
        parse_matrix_market(text, Path::new(P))
    }

    fn mm_err(text: &str, line: usize, parts: &[&str]) {
        check_err(mm(text).unwrap_err(), P, line, parts);
    }

    #[test]
    fn symmetric_file_either_triangle() {
        let upper = "%%MatrixMarket matrix coordinate real symmetric\n% comment\n%\n3 3 4\n1 1 2.0\n1 3 -1\n2 2 3e0\n3 3 4.0D0\n";
        let lower = "%%matrixmarket MATRIX Coordinate REAL Symmetric\n3 3 4\n1 1 2.0\n3 1 -1\n2 2 3e0\n\n3 3 4\n";
        let want = vec![vec![2.0, 0.0, -1.0], vec![0.0, 3.0, 0.0], vec![-1.0, 0.0, 4.0]];
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
        assert_eq!(dense(&mm(t).unwrap()), vec![vec![3.0, 0.75], vec![0.75, 4.0]]);
        let g = "%%MatrixMarket matrix coordinate real general\n2 2 5\n1 2 1\n2 1 0.5\n1 2 -0.5\n1 1 1\n2 2 1\n";
        assert_eq!(dense(&mm(g).unwrap()), vec![vec![1.0, 0.5], vec![0.5, 1.0]]);
    }

    #[test]
    fn matrix_market_errors() {
        let h = "%%MatrixMarket matrix coordinate real symmetric\n";
        mm_err("", 0, &["empty file"]);
        mm_err("%%MatrixMarket matrix array real general\n2 2\n1\n2\n3\n4\n", 1, &["'array'", "coordinate"]);
        mm_err("%%MatrixMarket matrix coordinate complex general\n1 1 1\n1 1 1 0\n", 1, &["'complex'", "real"]);
        mm_err("%%MatrixMarket matrix coordinate pattern symmetric\n1 1 1\n1 1\n", 1, &["'pattern'"]);
        mm_err("%%MatrixMarket matrix coordinate real hermitian\n1 1 1\n1 1 1\n", 1, &["'hermitian'"]);
        mm_err("%%MatrixMarket matrix coordinate real skew-symmetric\n1 1 0\n", 1, &["'skew-symmetric'"]);
        mm_err("%%MatrixMarket matrix coordinate real\n1 1 0\n", 1, &["incomplete"]);
        mm_err("1 1 4.9e4\n1 2 1.6e4\n", 1, &["not a Matrix Market file", "CalculiX"]);
        mm_err(&format!("{h}% c\n2 3 1\n1 1 1\n"), 3, &["2 x 3", "square"]);
        mm_err(&format!("{h}2 2\n"), 2, &["rows columns entries"]);
        mm_err(&format!("{h}2 2 x\n"), 2, &["malformed size 'x'"]);
        mm_err(&format!("{h}2 2 2\n1 1 1\n3 1 1\n"), 4, &["row index 3 out of range", "2 x 2"]);
        mm_err(&format!("{h}2 2 2\n1 1 1\n1 0 1\n"), 4, &["column index 0 out of range", "1-based"]);
        mm_err(&format!("{h}2 2 2\n1 1 1\n1.5 1 1\n"), 4, &["malformed row index '1.5'"]);
        mm_err(&format!("{h}2 2 3\n1 1 1\n2 2 1\n"), 2, &["announces 3 entries", "contains 2"]);
        mm_err(&format!("{h}2 2 1\n1 1 1\n%\n2 2 1\n"), 5, &["more entries than the 1 announced", "line 2"]);
        mm_err(&format!("{h}2 2 2\n1 1 1\n2 2 1.0.0\n"), 4, &["malformed number '1.0.0'"]);
        mm_err(&format!("{h}2 2 2\n1 1 1\n2 2 NaN\n"), 4, &["not finite"]);
        mm_err(&format!("{h}2 2 2\n1 1 inf\n2 2 1\n"), 3, &["not finite"]);
        mm_err(&format!("{h}2 2 2\n1 1 1e999\n2 2 1\n"), 3, &["not finite"]);
        mm_err(&format!("{h}2 2 2\n1 1 1\n2 2 1 0\n"), 4, &["4 values", "row column value"]);
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
            &["not symmetric", "A(2, 3) = 5e-9", "A(3, 2) = 0 (no entry)", "1e-10 x max|diagonal| = 1.000e-9"],
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
}
