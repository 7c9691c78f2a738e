//! DoF maps: which node and direction each matrix row is (see the formats
//! of the parent module).

use super::{DIRECTIONS, clip, split_fields};
use crate::file_read::FileKind;
use crate::import::{ImportError, read_text_of_kind};
use std::collections::HashMap;
use std::path::Path;

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

/// Reads a DoF map; see [`parse_dof_map`].
pub fn read_dof_map(path: &Path) -> Result<(DofMapFormat, Vec<DofRow>), ImportError> {
    parse_dof_map(&read_text_of_kind(path, FileKind::Matrix)?, path)
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
        "4" | "5" | "6" | "rotx" | "roty" | "rotz" | "rx" | "ry" | "rz" | "urx" | "ury" | "urz" => Direction::Rotation,
        _ => Direction::Unknown,
    }
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
    let (format, body) = detect_format(&data, first_line, first, path)?;
    if body.is_empty() {
        return Err(err(0, "the DoF map lists no rows".into()));
    }
    let rows = RowReader { path };
    // Rows in file order, with their 0-based matrix row.
    let listed = match format {
        DofMapFormat::CalculixDof => rows.calculix_dof(body)?,
        DofMapFormat::NodeDirection => rows.node_direction(body)?,
        DofMapFormat::AnsysMapping => rows.ansys_mapping(body)?,
    };
    check_every_dof_once(&listed, path)?;
    in_row_order(format, listed, path)
}

/// A line that is neither blank nor a comment, with its 1-based number.
type DataLine<'a> = (usize, &'a str);

/// The format the first data line shows, and the data lines that list rows (after the ANSYS
/// header, if any).
fn detect_format<'d, 'a>(
    data: &'d [DataLine<'a>],
    first_line: usize,
    first: &str,
    path: &Path,
) -> Result<(DofMapFormat, &'d [DataLine<'a>]), ImportError> {
    let err = |line: usize, msg: String| ImportError::new(path, line, msg);
    let first_fields = split_fields(first);
    let (format, body) = if first_fields.first().is_some_and(|t| t.eq_ignore_ascii_case("matrix")) {
        (DofMapFormat::AnsysMapping, &data[1..])
    } else {
        match first_fields.len() {
            1 if first.contains('.') => (DofMapFormat::CalculixDof, data),
            2 => (DofMapFormat::NodeDirection, data),
            3 => (DofMapFormat::AnsysMapping, data),
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
    Ok((format, body))
}

/// Reads the rows of each format.
struct RowReader<'p> {
    path: &'p Path,
}

impl RowReader<'_> {
    fn err(&self, line: usize, msg: String) -> ImportError {
        ImportError::new(self.path, line, msg)
    }

    fn node_id(&self, s: &str, line: usize) -> Result<u64, ImportError> {
        s.parse::<u64>()
            .map_err(|_| self.err(line, format!("malformed node id '{s}': expected a non-negative integer")))
    }

    fn direction(&self, tok: &str, node: u64, line: usize, expected: &str) -> Result<usize, ImportError> {
        match direction(tok) {
            Direction::Translation(d) => Ok(d),
            Direction::Rotation => Err(self.err(
                line,
                format!(
                    "node {node}: rotational DoF '{tok}': only solid models (three translations per node) \
                     are supported; beam and shell models carry rotations the import cannot represent"
                ),
            )),
            Direction::Unknown => {
                Err(self.err(line, format!("node {node}: unsupported direction '{tok}', expected {expected}")))
            }
        }
    }

    /// CalculiX `.dof`: `node.direction` per line, in row order.
    fn calculix_dof(&self, body: &[(usize, &str)]) -> Result<Vec<(usize, DofRow)>, ImportError> {
        let mut listed: Vec<(usize, DofRow)> = Vec::with_capacity(body.len());
        for (r, &(line, t)) in body.iter().enumerate() {
            let Some((ns, ds)) = t.split_once('.').filter(|_| !t.contains(char::is_whitespace)) else {
                return Err(self.err(
                    line,
                    format!("found '{}', expected 'node.direction' like the first line (CalculiX .dof)", clip(t)),
                ));
            };
            let node = self.node_id(ns, line)?;
            let d = self.direction(ds, node, line, "1, 2 or 3")?;
            listed.push((r, DofRow { node, direction: d, line }));
        }
        Ok(listed)
    }

    /// Two columns `node direction`, in row order.
    fn node_direction(&self, body: &[(usize, &str)]) -> Result<Vec<(usize, DofRow)>, ImportError> {
        let mut listed: Vec<(usize, DofRow)> = Vec::with_capacity(body.len());
        for (r, &(line, t)) in body.iter().enumerate() {
            let f = split_fields(t);
            if f.len() != 2 {
                return Err(
                    self.err(line, format!("found {} values in '{}', expected 'node direction'", f.len(), clip(t)))
                );
            }
            let node = self.node_id(f[0], line)?;
            let d = self.direction(f[1], node, line, "1, 2, 3, x, y, z or UX, UY, UZ")?;
            listed.push((r, DofRow { node, direction: d, line }));
        }
        Ok(listed)
    }

    /// ANSYS `.mapping`: `eqn node label` rows in any order, every equation number listed once.
    fn ansys_mapping(&self, body: &[(usize, &str)]) -> Result<Vec<(usize, DofRow)>, ImportError> {
        let mut listed: Vec<(usize, DofRow)> = Vec::with_capacity(body.len());
        let mut eqn_line: HashMap<usize, usize> = HashMap::with_capacity(body.len());
        let mut max_eqn = (0, 0);
        for &(line, t) in body {
            let f = split_fields(t);
            if f.len() != 3 {
                return Err(self.err(
                    line,
                    format!("found {} values in '{}', expected 'eqn node label' (ANSYS mapping)", f.len(), clip(t)),
                ));
            }
            let eqn = match f[0].parse::<usize>() {
                Ok(e) if e >= 1 => e,
                _ => {
                    return Err(
                        self.err(line, format!("malformed equation number '{}': expected a positive integer", f[0]))
                    );
                }
            };
            if let Some(first) = eqn_line.insert(eqn, line) {
                return Err(self.err(line, format!("equation {eqn} is listed twice (first on line {first})")));
            }
            if eqn > max_eqn.0 {
                max_eqn = (eqn, line);
            }
            let node = self.node_id(f[1], line)?;
            let d = self.direction(f[2], node, line, "UX, UY or UZ")?;
            listed.push((eqn - 1, DofRow { node, direction: d, line }));
        }
        if max_eqn.0 > body.len() {
            // The equation numbers are distinct, so at most body.len()
            // of the first body.len() + 5 are present: the scan is short.
            let missing: Vec<String> =
                (1..=max_eqn.0).filter(|e| !eqn_line.contains_key(e)).take(5).map(|e| e.to_string()).collect();
            return Err(self.err(
                0,
                format!(
                    "the map lists {} rows but equation numbers go up to {} (line {}): rows {}{} have \
                     no entry",
                    body.len(),
                    max_eqn.0,
                    max_eqn.1,
                    missing.join(", "),
                    if max_eqn.0 - body.len() > missing.len() { ", ..." } else { "" }
                ),
            ));
        }
        Ok(listed)
    }
}

/// No (node, direction) twice, and all three directions at every node.
fn check_every_dof_once(listed: &[(usize, DofRow)], path: &Path) -> Result<(), ImportError> {
    let err = |line: usize, msg: String| ImportError::new(path, line, msg);
    let mut seen: HashMap<(u64, usize), usize> = HashMap::with_capacity(listed.len());
    // Per node: first line and the line of each direction, in order of first
    // appearance so the reported node is the first incomplete one in the file.
    let mut per_node: HashMap<u64, usize> = HashMap::new();
    let mut nodes: Vec<(u64, usize, [Option<usize>; 3])> = Vec::new();
    for (_, row) in listed {
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
        let missing: Vec<&str> = (0..3).filter(|&d| dirs[d].is_none()).map(|d| DIRECTIONS[d]).collect();
        if !missing.is_empty() {
            let present: Vec<&str> = (0..3).filter(|&d| dirs[d].is_some()).map(|d| DIRECTIONS[d]).collect();
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
    Ok(())
}

/// The rows in matrix order, every row covered.
fn in_row_order(
    format: DofMapFormat,
    listed: Vec<(usize, DofRow)>,
    path: &Path,
) -> Result<(DofMapFormat, Vec<DofRow>), ImportError> {
    let err = |line: usize, msg: String| ImportError::new(path, line, msg);
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

#[cfg(test)]
mod tests {
    use super::super::test_util::{CCX_DOF, check_err};
    use super::*;

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
        assert_eq!(pairs(&rows), vec![(7, 0), (7, 1), (7, 2), (2, 0), (2, 1), (2, 2)]);
        assert_eq!(rows[0].line, 3);

        let (f, rows) = dof("7.1\n7.2\n7.3\n2.1\n2.2\n2.3\n").unwrap();
        assert_eq!(f, DofMapFormat::CalculixDof);
        assert_eq!(pairs(&rows), vec![(7, 0), (7, 1), (7, 2), (2, 0), (2, 1), (2, 2)]);

        let plain = "# node direction\n7 1\n7, y\n\n% z last\n7 UZ\n2 X\n2\t2\n2 uz\n";
        let (f, rows) = dof(plain).unwrap();
        assert_eq!(f, DofMapFormat::NodeDirection);
        assert_eq!(pairs(&rows), vec![(7, 0), (7, 1), (7, 2), (2, 0), (2, 1), (2, 2)]);
        assert_eq!(rows[2].line, 6);
    }

    /// The same deck with `*BOUNDARY` on 101,1,3 and 4,2,2 (node 1 renamed
    /// 101): CalculiX leaves the fixed DoFs out.
    const CCX_DOF_WITH_BC: &str =
        "2.1\n2.2\n2.3\n3.1\n3.2\n3.3\n4.1\n4.3\n5.1\n5.2\n5.3\n6.1\n6.2\n6.3\n7.1\n7.2\n7.3\n8.1\n8.2\n8.3\n";

    #[test]
    fn calculix_matrixstorage_dof() {
        let (f, rows) = dof(CCX_DOF).unwrap();
        assert_eq!(f, DofMapFormat::CalculixDof);
        assert_eq!(rows.len(), 24);
        for (r, row) in rows.iter().enumerate() {
            assert_eq!((row.node, row.direction, row.line), (r as u64 / 3 + 1, r % 3, r + 1));
        }
        dof_err(CCX_DOF_WITH_BC, 7, &["node 4 has rows for x, z but none for y", "boundary conditions"]);
    }

    #[test]
    fn dof_map_errors() {
        dof_err("", 0, &["no rows"]);
        dof_err("# only comments\n", 0, &["no rows"]);
        dof_err("Matrix Eqn Node DOF\n1 1 UX\n2 1 UY\n3 1 ROTX\n", 4, &["rotational DoF 'ROTX'", "solid"]);
        dof_err("1.1\n1.2\n1.4\n", 3, &["rotational DoF '4'"]);
        dof_err("1 x\n1 y\n1 rotz\n", 3, &["rotational DoF 'rotz'"]);
        dof_err(
            "Matrix Eqn Node DOF\n1 1 UX\n2 1 UY\n3 1 TEMP\n",
            4,
            &["unsupported direction 'TEMP'", "UX, UY or UZ"],
        );
        dof_err("1 x\n1 w\n", 2, &["unsupported direction 'w'"]);
        dof_err("1.1\n1.2\n1.3\n1.2\n", 4, &["node 1 direction y is listed twice (first on line 2)"]);
        dof_err("1 1\n1 2\n1 3\n2 1\n2 2\n2 x\n", 6, &["node 2 direction x is listed twice (first on line 4)"]);
        dof_err("Matrix Eqn Node DOF\n1 1 UX\n2 1 UY\n2 1 UZ\n", 4, &["equation 2 is listed twice (first on line 3)"]);
        dof_err(
            "Matrix Eqn Node DOF\n1 1 UX\n2 1 UY\n5 1 UZ\n",
            0,
            &["3 rows", "up to 5 (line 4)", "rows 3, 4 have no entry"],
        );
        dof_err("Matrix Eqn Node DOF\n0 1 UX\n", 2, &["malformed equation number '0'"]);
        dof_err("1.1\n1.2\n1 3\n", 3, &["expected 'node.direction'"]);
        dof_err("1.1\n1.2\nx.3\n", 3, &["malformed node id 'x'"]);
        dof_err("1 1\n1 2 3\n", 2, &["found 3 values", "node direction"]);
        dof_err("1 2 3 4\n", 1, &["unrecognised DoF map line"]);
        dof_err("5 x\n5 z\n6 x\n6 y\n6 z\n", 1, &["node 5 has rows for x, z but none for y"]);
    }
}
