//! Node files: an `.inp` or `.msh` mesh (nodes and node sets), or a table
//! of `id x y z` lines.

use super::{DIRECTIONS, clip, parse_f64, split_fields};
use crate::file_read::FileKind;
use crate::import::{ImportError, parse_msh, read_mesh, read_text_of_kind};
use std::collections::{BTreeMap, HashMap};
use std::path::Path;

#[derive(Debug)]
pub(super) struct NodeFile {
    pub(super) ids: Vec<u64>,
    pub(super) coords: Vec<[f64; 3]>,
    /// Sets in file indices.
    pub(super) sets: BTreeMap<String, Vec<usize>>,
}

pub(super) fn read_nodes(path: &Path) -> Result<NodeFile, ImportError> {
    let ext = path.extension().and_then(|e| e.to_str()).map(|e| e.to_ascii_lowercase());
    let mesh = match ext.as_deref() {
        Some("inp") => read_mesh(path)?,
        Some("msh") => {
            let mut text = read_text_of_kind(path, FileKind::Matrix)?;
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
            parse_msh(&text, path)?
        }
        _ => {
            let (ids, coords) = parse_node_table(&read_text_of_kind(path, FileKind::Matrix)?, path)?;
            return Ok(NodeFile { ids, coords, sets: BTreeMap::new() });
        }
    };
    if mesh.nodes.is_empty() {
        return Err(ImportError::new(path, 0, "the node file defines no nodes"));
    }
    Ok(NodeFile { ids: mesh.node_ids, coords: mesh.nodes, sets: mesh.node_sets })
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
        let id = f[0]
            .parse::<u64>()
            .map_err(|_| err(line, format!("malformed node id '{}': expected a non-negative integer", f[0])))?;
        let mut x = [0.0; 3];
        for d in 0..3 {
            let s = f[d + 1];
            x[d] = match parse_f64(s) {
                Some(v) if v.is_finite() => v,
                Some(_) => {
                    return Err(err(line, format!("coordinate {} of node {id} is not finite: '{s}'", DIRECTIONS[d])));
                }
                None => {
                    return Err(err(
                        line,
                        format!("malformed coordinate {} of node {id}: '{s}', expected a number", DIRECTIONS[d]),
                    ));
                }
            };
        }
        if let Some(first) = first_line.insert(id, line) {
            return Err(err(line, format!("duplicate node id {id} (first defined on line {first})")));
        }
        ids.push(id);
        coords.push(x);
    }
    if ids.is_empty() {
        return Err(err(0, "the node file defines no nodes (expected 'id x y z' lines)".into()));
    }
    Ok((ids, coords))
}

#[cfg(test)]
mod tests {
    use super::super::test_util::{check_err, scratch};
    use super::*;

    #[test]
    fn node_table() {
        let t = "# id x y z\n* from a deck\n% or so\n\n10, 0.0, 1.0, 2.0\n 20 1e-3 -2.5D1 3\n30,4 5, 6\n";
        let (ids, x) = parse_node_table(t, Path::new("n.txt")).unwrap();
        assert_eq!(ids, vec![10, 20, 30]);
        assert_eq!(x, vec![[0.0, 1.0, 2.0], [1e-3, -25.0, 3.0], [4.0, 5.0, 6.0]]);
        let e = |t: &str| parse_node_table(t, Path::new("n.txt")).unwrap_err();
        check_err(e("1 0 0 0\n\n1 1 1 1\n"), "n.txt", 3, &["duplicate node id 1 (first defined on line 1)"]);
        check_err(e("1 0 0 0\n2 0 0\n"), "n.txt", 2, &["found 3 values", "id x y z"]);
        check_err(e("1 0 0 0\n2 0 a 0\n"), "n.txt", 2, &["malformed coordinate y of node 2: 'a'"]);
        check_err(e("1 0 0 0\n2 0 0 nan\n"), "n.txt", 2, &["coordinate z of node 2 is not finite"]);
        check_err(e("-1 0 0 0\n"), "n.txt", 1, &["malformed node id '-1'"]);
        check_err(e("# nothing\n"), "n.txt", 0, &["no nodes"]);
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
}
