//! The reader of ASCII MSH 4.1 files.

use super::builder::MeshBuilder;
use super::{Loc, Res, count_at, int_at, ints_of, physical_name};
use crate::import::{ImportError, ImportedMesh};
use std::path::Path;

/// Non-blank lines with their 1-based line numbers.
struct Cursor<'a> {
    path: &'a Path,
    lines: Vec<(usize, &'a str)>,
    pos: usize,
}

impl<'a> Cursor<'a> {
    fn err(&self, line: usize, msg: impl Into<String>) -> ImportError {
        ImportError::new(self.path, line, msg)
    }

    fn last_line(&self) -> usize {
        self.lines.last().map_or(0, |l| l.0)
    }

    fn next(&mut self, what: &str) -> Res<(usize, &'a str)> {
        let l = self
            .lines
            .get(self.pos)
            .copied()
            .ok_or_else(|| self.err(self.last_line(), format!("unexpected end of file while reading {what}")))?;
        self.pos += 1;
        Ok(l)
    }

    /// Next line split into whitespace-separated tokens.
    fn tokens(&mut self, what: &str) -> Res<(usize, Vec<&'a str>)> {
        let (n, l) = self.next(what)?;
        Ok((n, l.split_whitespace().collect()))
    }

    /// Next line as exactly `count` integers.
    fn ints(&mut self, count: usize, what: &str) -> Res<(usize, Vec<i64>)> {
        let (n, t) = self.tokens(what)?;
        let v = ints_of(self.path, Loc::Line(n), &t, count, what)?;
        Ok((n, v))
    }

    fn expect_end(&mut self, section: &str) -> Res<()> {
        let (n, l) = self.next(&format!("$End{section}"))?;
        if l != format!("$End{section}") {
            return Err(self.err(n, format!("expected $End{section}, found '{l}'")));
        }
        Ok(())
    }
}

fn int(path: &Path, line: usize, s: &str, what: &str) -> Res<i64> {
    int_at(path, Loc::Line(line), s, what)
}

fn count(path: &Path, line: usize, v: i64, what: &str) -> Res<usize> {
    count_at(path, Loc::Line(line), v, what)
}

fn float(path: &Path, line: usize, s: &str, what: &str) -> Res<f64> {
    match s.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        _ => Err(ImportError::new(path, line, format!("malformed number '{s}' in {what}"))),
    }
}

/// The sections of the file, each read from the line after its header (`n`, for messages).
impl Cursor<'_> {
    /// `$MeshFormat`: version 4.1, ASCII.
    fn mesh_format(&mut self) -> Res<()> {
        let (n, t) = self.tokens("$MeshFormat")?;
        if t.len() != 3 {
            return Err(self.err(n, "$MeshFormat: expected 'version file-type data-size'"));
        }
        if t[1] == "1" {
            return Err(self.err(
                n,
                "binary .msh not supported here, save as ASCII (binary MSH 4.1 is read from bytes, by read_msh / parse_msh_bytes)",
            ));
        }
        if t[1] != "0" {
            return Err(
                self.err(n, format!("$MeshFormat: file-type '{}' (expected 0 for ASCII or 1 for binary)", t[1]))
            );
        }
        if t[0] != "4.1" {
            return Err(self.err(
                n,
                format!(
                    "MSH version {} not supported: only 4.1, ASCII or binary (in Gmsh: Mesh.MshFileVersion = 4.1, or -format msh41)",
                    t[0]
                ),
            ));
        }
        self.expect_end("MeshFormat")?;
        Ok(())
    }

    /// `$PhysicalNames`: the names of the physical groups.
    fn physical_names(&mut self, n: usize, mb: &mut MeshBuilder<'_>) -> Res<()> {
        let (_, c) = self.ints(1, "$PhysicalNames count")?;
        for _ in 0..count(self.path, n, c[0], "count")? {
            let (n, l) = self.next("physical name")?;
            let (key, name) = physical_name(self.path, Loc::Line(n), l)?;
            mb.physical_names.insert(key, name);
        }
        self.expect_end("PhysicalNames")?;
        Ok(())
    }

    /// `$Entities`: the physical groups of every point, curve, surface and volume.
    fn entities(&mut self, n: usize, mb: &mut MeshBuilder<'_>) -> Res<()> {
        let (_, c) = self.ints(4, "$Entities counts")?;
        for dim in 0..4i64 {
            for _ in 0..count(self.path, n, c[dim as usize], "entity count")? {
                let (n, t) = self.tokens("entity")?;
                // point: tag x y z nphys ...; others: tag bbox(6) nphys ...
                let at = if dim == 0 { 4 } else { 7 };
                let what = "entity";
                let bad = || self.err(n, format!("malformed {dim}D entity line"));
                let tag = int(self.path, n, t.first().ok_or_else(bad)?, what)?;
                let np = count(self.path, n, int(self.path, n, t.get(at).ok_or_else(bad)?, what)?, what)?;
                let phys = t.get(at + 1..at + 1 + np).ok_or_else(bad)?;
                let phys = phys.iter().map(|s| int(self.path, n, s, what).map(i64::abs)).collect::<Res<Vec<_>>>()?;
                mb.entity_physicals.insert((dim, tag), phys);
            }
        }
        self.expect_end("Entities")?;
        mb.have_entities = true;
        Ok(())
    }

    /// `$Nodes`: blocks of node tags, then their coordinates.
    fn nodes(&mut self, n: usize, mb: &mut MeshBuilder<'_>) -> Res<()> {
        mb.begin_nodes(Loc::Line(n))?;
        let (hn, h) = self.ints(4, "$Nodes header")?;
        let blocks = count(self.path, hn, h[0], "block count")?;
        let total = count(self.path, hn, h[1], "node count")?;
        for _ in 0..blocks {
            let (bn, b) = self.ints(4, "node block header (entityDim entityTag parametric numNodes)")?;
            let dim = b[0];
            let parametric = b[2] != 0;
            let nb = count(self.path, bn, b[3], "node count")?;
            let mut tags = Vec::with_capacity(nb.min(self.lines.len()));
            for _ in 0..nb {
                let (n, t) = self.ints(1, "node tag")?;
                let tag = u64::try_from(t[0]).map_err(|_| self.err(n, format!("invalid node tag {}", t[0])))?;
                mb.node_tag(Loc::Line(n), tag)?;
                tags.push(tag);
            }
            let expect = if parametric { 3 + dim.max(0) as usize } else { 3 };
            for &tag in &tags {
                let (n, t) = self.tokens("node coordinates")?;
                if t.len() != expect && t.len() != 3 {
                    return Err(
                        self.err(n, format!("coordinates of node {tag}: expected {expect} values, got {}", t.len()))
                    );
                }
                let mut x = [0.0; 3];
                for d in 0..3 {
                    x[d] = float(self.path, n, t[d], &format!("coordinates of node {tag}"))?;
                }
                mb.push_node(tag, x);
            }
        }
        mb.end_nodes(Loc::Line(hn), total)?;
        self.expect_end("Nodes")?;
        Ok(())
    }

    /// `$Elements`: blocks of one element type, a line per element.
    fn elements(&mut self, n: usize, mb: &mut MeshBuilder<'_>) -> Res<()> {
        mb.begin_elements(Loc::Line(n))?;
        let (hn, h) = self.ints(4, "$Elements header")?;
        let blocks = count(self.path, hn, h[0], "block count")?;
        let total = count(self.path, hn, h[1], "element count")?;
        let mut seen = 0usize;
        for _ in 0..blocks {
            let (bn, b) = self.ints(4, "element block header (entityDim entityTag elementType numElements)")?;
            let ne = count(self.path, bn, b[3], "element count")?;
            let block = mb.element_block(Loc::Line(bn), b[0], b[1], b[2])?;
            for _ in 0..ne {
                let (n, t) = self.tokens("element")?;
                let tag = int(self.path, n, t[0], "element tag")?;
                let tag = u64::try_from(tag).map_err(|_| self.err(n, format!("invalid element tag {tag}")))?;
                mb.element_tag(Loc::Line(n), tag)?;
                let nn = t.len() - 1;
                if let Some((name, expect, _)) = block.info
                    && nn != expect
                {
                    return Err(self.err(
                        n,
                        format!("element {tag}: type {} ({name}) needs {expect} nodes, got {nn}", block.etype),
                    ));
                }
                if nn == 0 {
                    return Err(self.err(n, format!("element {tag} has no nodes")));
                }
                let mut nodes = Vec::with_capacity(nn);
                for s in &t[1..] {
                    let id = int(self.path, n, s, "element node tag")?;
                    nodes.push(mb.node_ref(Loc::Line(n), tag, id)?);
                }
                mb.push_element(&block, tag, nodes);
            }
            seen += ne;
        }
        mb.end_elements(Loc::Line(hn), total, seen)?;
        self.expect_end("Elements")?;
        Ok(())
    }

    /// A section the import does not need ($Comments, $NodeData, $Periodic, ...), up to its end.
    fn skip_section(&mut self, n: usize, section: &str) -> Res<()> {
        let end = format!("$End{section}");
        loop {
            let (_, l) =
                self.next(&end).map_err(|_| self.err(n, format!("section ${section} is not terminated by {end}")))?;
            if l == end {
                break;
            }
        }
        Ok(())
    }
}

/// Parses the text of a MSH 4.1 ASCII file; `path` is used for messages.
/// Binary files must be read as bytes: [`read_msh`](super::read_msh),
/// [`parse_msh_bytes`](super::parse_msh_bytes).
pub fn parse_msh(text: &str, path: &Path) -> Result<ImportedMesh, ImportError> {
    let mut cur = Cursor {
        path,
        lines: text.lines().enumerate().map(|(i, l)| (i + 1, l.trim())).filter(|(_, l)| !l.is_empty()).collect(),
        pos: 0,
    };

    let mut have_format = false;
    let mut mb = MeshBuilder::new(path);

    while cur.pos < cur.lines.len() {
        let (n, header) = cur.next("section")?;
        if !header.starts_with('$') {
            return Err(cur.err(n, format!("expected a section header ($Name), found '{header}'")));
        }
        let section = &header[1..];
        if !have_format && section != "MeshFormat" {
            return Err(cur.err(n, format!("expected $MeshFormat before ${section}")));
        }
        match section {
            "MeshFormat" => {
                cur.mesh_format()?;
                have_format = true;
            }
            "PhysicalNames" => cur.physical_names(n, &mut mb)?,
            "Entities" => cur.entities(n, &mut mb)?,
            "PartitionedEntities" => {
                return Err(cur.err(n, "partitioned .msh files are not supported"));
            }
            "Nodes" => cur.nodes(n, &mut mb)?,
            "Elements" => cur.elements(n, &mut mb)?,
            _ => cur.skip_section(n, section)?,
        }
    }
    if !have_format {
        return Err(ImportError::new(path, cur.last_line(), "not a Gmsh file: no $MeshFormat section"));
    }
    mb.finish(Loc::Line(cur.last_line()))
}

#[cfg(test)]
mod tests {
    use super::super::test_data::CUBE;
    use super::*;
    use crate::element::ElementKind;

    #[test]
    fn unit_cube_hex8_with_physical_groups() {
        let m = parse_msh(CUBE, Path::new("cube.msh")).unwrap();
        assert_eq!(m.nodes.len(), 8);
        assert_eq!(m.nodes[6], [1.0, 1.0, 1.0]);
        assert_eq!(m.element_types, vec![ElementKind::Hex8]);
        assert_eq!(m.element_ids, vec![5]);
        assert_eq!(m.connectivity, vec![(0..8).collect::<Vec<_>>()]);
        assert_eq!(m.node_sets["fixed"], vec![0, 1, 2, 3]);
        assert_eq!(m.node_sets["PHYSICAL_3"], vec![4, 5, 6, 7]);
        assert_eq!(m.node_sets["body"], (0..8).collect::<Vec<_>>());
        assert_eq!(m.node_sets.len(), 3);
        assert_eq!(m.element_sets.len(), 1);
        assert_eq!(m.element_sets["body"], vec![0]);
        assert!(m.materials.is_empty() && m.sections.is_empty());
    }

    fn check(text: &str, line: usize, parts: &[&str]) {
        let e = parse_msh(text, Path::new("bad.msh")).unwrap_err();
        assert_eq!(e.line, line, "wrong line for: {e}");
        for p in parts {
            assert!(e.message.contains(p), "message lacks '{p}': {e}");
        }
        assert!(e.to_string().starts_with(&format!("bad.msh:{line}: ")), "{e}");
    }

    #[test]
    fn errors_have_lines() {
        check(
            "$MeshFormat\n4.1 1 8\n\u{1}\0\0\0\n$EndMeshFormat\n",
            2,
            &["binary .msh not supported here, save as ASCII", "parse_msh_bytes"],
        );
        check("$MeshFormat\n2.2 0 8\n$EndMeshFormat\n", 2, &["version 2.2"]);
        check("$Nodes\n", 1, &["$MeshFormat"]);
        // line numbers refer to CUBE
        check(&CUBE.replace("3 6 7 8", "3 6 7 9"), 46, &["element 3", "undefined node 9"]);
        check(&CUBE.replace("1 1 2 3 4\n2 2", "1 1 2 3\n2 2"), 43, &["needs 4 nodes, got 3"]);
        check(&CUBE.replace("3 1 5 1", "3 1 6 1"), 47, &["unsupported 3D element type 6 (prism6)"]);
        check(&CUBE.replace("1 1 0\n0 1 0", "1 x 0\n0 1 0"), 24, &["malformed number 'x'"]);
        check(&CUBE.replace("\n4\n0 0 0", "\n3\n0 0 0"), 21, &["duplicate node tag 3"]);
        check(&CUBE.replace("3 6 7 8", "1 6 7 8"), 46, &["duplicate element tag 1"]);
        check(&CUBE.replace("$EndNodes\n", ""), 36, &["expected $EndNodes"]);
    }
}
