//! Gmsh MSH 4.1 ASCII importer.
//!
//! Reads `$MeshFormat`, `$PhysicalNames`, `$Entities`, `$Nodes` and
//! `$Elements`; other sections are skipped. 3D elements of Gmsh types 4
//! (tet4), 11 (tet10), 5 (hex8) and 17 (hex20) become C3D4, C3D10, C3D8 and
//! C3D20 with their nodes reordered to the CalculiX/Abaqus convention.
//! Lower-dimensional elements are only used for physical groups: every node
//! of an element whose entity belongs to a physical group (of any dimension)
//! is put in that group's node set, and 3D elements of a physical volume
//! also form an element set. Sets are named by the physical name, or
//! `PHYSICAL_<tag>` for unnamed groups (`PHYSICAL_<dim>D_<tag>` if the same
//! unnamed tag is used in several dimensions). Groups of different
//! dimensions sharing a name are merged.
//!
//! All nodes of the `$Nodes` section are imported (in file order), even
//! those not used by any 3D element.

use super::{ElementType, ImportError, ImportedMesh};
use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::path::Path;

/// Gmsh -> Abaqus/CalculiX node permutation for the 10-node tetrahedron:
/// `abaqus[k] = gmsh[TET10_GMSH_TO_ABAQUS[k]]`.
///
/// Gmsh documentation, "Node ordering" (Tetrahedron10): corners 0-3, then
/// edge nodes 4: 0-1, 5: 1-2, 6: 2-0, 7: 0-3, 8: 2-3, 9: 1-3.
/// Abaqus/CalculiX C3D10: corners 1-4, then 5: 1-2, 6: 2-3, 7: 3-1,
/// 8: 1-4, 9: 2-4, 10: 3-4, i.e. 0-based 4: 0-1, 5: 1-2, 6: 2-0, 7: 0-3,
/// 8: 1-3, 9: 2-3. Only the last two edge nodes are swapped.
pub const TET10_GMSH_TO_ABAQUS: [usize; 10] = [0, 1, 2, 3, 4, 5, 6, 7, 9, 8];

/// Gmsh -> Abaqus/CalculiX node permutation for the 20-node hexahedron:
/// `abaqus[k] = gmsh[HEX20_GMSH_TO_ABAQUS[k]]`.
///
/// Gmsh documentation, "Node ordering" (Hexahedron20 diagram): corners 0-7
/// as in Abaqus (0-3 bottom face, 4-7 top face), then edge nodes
/// 8: 0-1, 9: 0-3, 10: 0-4, 11: 1-2, 12: 1-5, 13: 2-3, 14: 2-6, 15: 3-7,
/// 16: 4-5, 17: 4-7, 18: 5-6, 19: 6-7.
/// Abaqus/CalculiX C3D20 (0-based): 8: 0-1, 9: 1-2, 10: 2-3, 11: 3-0,
/// 12: 4-5, 13: 5-6, 14: 6-7, 15: 7-4, 16: 0-4, 17: 1-5, 18: 2-6, 19: 3-7.
pub const HEX20_GMSH_TO_ABAQUS: [usize; 20] = [
    0, 1, 2, 3, 4, 5, 6, 7, // corners
    8, 11, 13, 9, // bottom face edges 0-1, 1-2, 2-3, 3-0
    16, 18, 19, 17, // top face edges 4-5, 5-6, 6-7, 7-4
    10, 12, 14, 15, // vertical edges 0-4, 1-5, 2-6, 3-7
];

/// Reads a Gmsh MSH 4.1 ASCII file.
pub fn read_msh(path: &Path) -> Result<ImportedMesh, ImportError> {
    let bytes = std::fs::read(path)
        .map_err(|e| ImportError::new(path, 0, format!("cannot read file: {e}")))?;
    // Lossy: a binary file is detected from its ASCII header and rejected.
    let text = String::from_utf8_lossy(&bytes);
    parse_msh(&text, path)
}

/// Gmsh element type -> (name, number of nodes, dimension), for the types
/// a file is likely to contain.
fn gmsh_type_info(t: i64) -> Option<(&'static str, usize, u8)> {
    Some(match t {
        1 => ("line2", 2, 1),
        2 => ("tri3", 3, 2),
        3 => ("quad4", 4, 2),
        4 => ("tet4", 4, 3),
        5 => ("hex8", 8, 3),
        6 => ("prism6", 6, 3),
        7 => ("pyramid5", 5, 3),
        8 => ("line3", 3, 1),
        9 => ("tri6", 6, 2),
        10 => ("quad9", 9, 2),
        11 => ("tet10", 10, 3),
        12 => ("hex27", 27, 3),
        13 => ("prism18", 18, 3),
        14 => ("pyramid14", 14, 3),
        15 => ("point", 1, 0),
        16 => ("quad8", 8, 2),
        17 => ("hex20", 20, 3),
        18 => ("prism15", 15, 3),
        19 => ("pyramid13", 13, 3),
        20 => ("tri9", 9, 2),
        21 => ("tri10", 10, 2),
        26 => ("line4", 4, 1),
        29 => ("tet20", 20, 3),
        _ => return None,
    })
}

fn supported_3d(t: i64) -> Option<(ElementType, &'static [usize])> {
    const TET4: [usize; 4] = [0, 1, 2, 3];
    const HEX8: [usize; 8] = [0, 1, 2, 3, 4, 5, 6, 7];
    match t {
        4 => Some((ElementType::C3D4, &TET4)),
        11 => Some((ElementType::C3D10, &TET10_GMSH_TO_ABAQUS)),
        5 => Some((ElementType::C3D8, &HEX8)),
        17 => Some((ElementType::C3D20, &HEX20_GMSH_TO_ABAQUS)),
        _ => None,
    }
}

type Res<T> = Result<T, ImportError>;

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
        let l = self.lines.get(self.pos).copied().ok_or_else(|| {
            self.err(
                self.last_line(),
                format!("unexpected end of file while reading {what}"),
            )
        })?;
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
        if t.len() != count {
            return Err(self.err(
                n,
                format!("{what}: expected {count} values, got {}", t.len()),
            ));
        }
        let v = t
            .iter()
            .map(|s| int(self.path, n, s, what))
            .collect::<Res<_>>()?;
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
    s.parse::<i64>()
        .map_err(|_| ImportError::new(path, line, format!("malformed integer '{s}' in {what}")))
}

fn count(path: &Path, line: usize, v: i64, what: &str) -> Res<usize> {
    usize::try_from(v).map_err(|_| ImportError::new(path, line, format!("negative {what} {v}")))
}

fn float(path: &Path, line: usize, s: &str, what: &str) -> Res<f64> {
    match s.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        _ => Err(ImportError::new(
            path,
            line,
            format!("malformed number '{s}' in {what}"),
        )),
    }
}

/// Parses the text of a MSH 4.1 ASCII file; `path` is used for messages.
pub fn parse_msh(text: &str, path: &Path) -> Result<ImportedMesh, ImportError> {
    let mut cur = Cursor {
        path,
        lines: text
            .lines()
            .enumerate()
            .map(|(i, l)| (i + 1, l.trim()))
            .filter(|(_, l)| !l.is_empty())
            .collect(),
        pos: 0,
    };

    let mut have_format = false;
    let mut physical_names: BTreeMap<(i64, i64), String> = BTreeMap::new();
    let mut have_entities = false;
    // (dim, entity tag) -> physical tags
    let mut entity_physicals: HashMap<(i64, i64), Vec<i64>> = HashMap::new();
    let mut mesh = ImportedMesh::default();
    let mut node_index: HashMap<u64, usize> = HashMap::new();
    let mut node_line: Vec<usize> = Vec::new();
    let mut have_nodes = false;
    let mut have_elements = false;
    // (dim, entity tag) -> nodes of its elements; 3D entity tag -> elements
    let mut entity_nodes: HashMap<(i64, i64), BTreeSet<usize>> = HashMap::new();
    let mut volume_elements: HashMap<i64, Vec<usize>> = HashMap::new();
    let mut element_line: HashMap<u64, usize> = HashMap::new();

    while cur.pos < cur.lines.len() {
        let (n, header) = cur.next("section")?;
        if !header.starts_with('$') {
            return Err(cur.err(
                n,
                format!("expected a section header ($Name), found '{header}'"),
            ));
        }
        let section = &header[1..];
        if !have_format && section != "MeshFormat" {
            return Err(cur.err(n, format!("expected $MeshFormat before ${section}")));
        }
        match section {
            "MeshFormat" => {
                let (n, t) = cur.tokens("$MeshFormat")?;
                if t.len() != 3 {
                    return Err(cur.err(n, "$MeshFormat: expected 'version file-type data-size'"));
                }
                if t[1] != "0" {
                    return Err(cur.err(n, "binary .msh not supported, save as ASCII"));
                }
                if t[0] != "4.1" {
                    return Err(cur.err(
                        n,
                        format!(
                            "MSH version {} not supported: only 4.1 ASCII (in Gmsh: Mesh.MshFileVersion = 4.1, or -format msh41)",
                            t[0]
                        ),
                    ));
                }
                cur.expect_end("MeshFormat")?;
                have_format = true;
            }
            "PhysicalNames" => {
                let (_, c) = cur.ints(1, "$PhysicalNames count")?;
                for _ in 0..count(path, n, c[0], "count")? {
                    let (n, l) = cur.next("physical name")?;
                    let mut it = l.splitn(2, char::is_whitespace);
                    let dim = int(path, n, it.next().unwrap_or(""), "physical name dimension")?;
                    let rest = it.next().unwrap_or("").trim_start();
                    let mut it = rest.splitn(2, char::is_whitespace);
                    let tag = int(path, n, it.next().unwrap_or(""), "physical name tag")?;
                    let name = it.next().unwrap_or("").trim();
                    let name = name
                        .strip_prefix('"')
                        .and_then(|s| s.strip_suffix('"'))
                        .ok_or_else(|| cur.err(n, "physical name: expected 'dim tag \"name\"'"))?;
                    physical_names.insert((dim, tag), name.to_string());
                }
                cur.expect_end("PhysicalNames")?;
            }
            "Entities" => {
                let (_, c) = cur.ints(4, "$Entities counts")?;
                for dim in 0..4i64 {
                    for _ in 0..count(path, n, c[dim as usize], "entity count")? {
                        let (n, t) = cur.tokens("entity")?;
                        // point: tag x y z nphys ...; others: tag bbox(6) nphys ...
                        let at = if dim == 0 { 4 } else { 7 };
                        let what = "entity";
                        let bad = || cur.err(n, format!("malformed {dim}D entity line"));
                        let tag = int(path, n, t.first().ok_or_else(bad)?, what)?;
                        let np = count(
                            path,
                            n,
                            int(path, n, t.get(at).ok_or_else(bad)?, what)?,
                            what,
                        )?;
                        let phys = t.get(at + 1..at + 1 + np).ok_or_else(bad)?;
                        let phys = phys
                            .iter()
                            .map(|s| int(path, n, s, what).map(i64::abs))
                            .collect::<Res<Vec<_>>>()?;
                        entity_physicals.insert((dim, tag), phys);
                    }
                }
                cur.expect_end("Entities")?;
                have_entities = true;
            }
            "PartitionedEntities" => {
                return Err(cur.err(n, "partitioned .msh files are not supported"));
            }
            "Nodes" => {
                if have_nodes {
                    return Err(cur.err(n, "more than one $Nodes section"));
                }
                have_nodes = true;
                let (hn, h) = cur.ints(4, "$Nodes header")?;
                let blocks = count(path, hn, h[0], "block count")?;
                let total = count(path, hn, h[1], "node count")?;
                for _ in 0..blocks {
                    let (bn, b) = cur.ints(
                        4,
                        "node block header (entityDim entityTag parametric numNodes)",
                    )?;
                    let dim = b[0];
                    let parametric = b[2] != 0;
                    let nb = count(path, bn, b[3], "node count")?;
                    let mut tags = Vec::with_capacity(nb.min(cur.lines.len()));
                    for _ in 0..nb {
                        let (n, t) = cur.ints(1, "node tag")?;
                        let tag = u64::try_from(t[0])
                            .map_err(|_| cur.err(n, format!("invalid node tag {}", t[0])))?;
                        if let Some(&first) = node_index.get(&tag) {
                            return Err(cur.err(
                                n,
                                format!(
                                    "duplicate node tag {tag} (first at line {})",
                                    node_line[first]
                                ),
                            ));
                        }
                        node_index.insert(tag, mesh.nodes.len() + tags.len());
                        node_line.push(n);
                        tags.push(tag);
                    }
                    let expect = if parametric {
                        3 + dim.max(0) as usize
                    } else {
                        3
                    };
                    for &tag in &tags {
                        let (n, t) = cur.tokens("node coordinates")?;
                        if t.len() != expect && t.len() != 3 {
                            return Err(cur.err(
                                n,
                                format!(
                                    "coordinates of node {tag}: expected {expect} values, got {}",
                                    t.len()
                                ),
                            ));
                        }
                        let mut x = [0.0; 3];
                        for d in 0..3 {
                            x[d] = float(path, n, t[d], &format!("coordinates of node {tag}"))?;
                        }
                        mesh.nodes.push(x);
                        mesh.node_ids.push(tag);
                    }
                }
                if mesh.nodes.len() != total {
                    return Err(cur.err(
                        hn,
                        format!(
                            "$Nodes header announces {total} nodes but the blocks contain {}",
                            mesh.nodes.len()
                        ),
                    ));
                }
                cur.expect_end("Nodes")?;
            }
            "Elements" => {
                if !have_nodes {
                    return Err(cur.err(n, "$Elements before $Nodes"));
                }
                if have_elements {
                    return Err(cur.err(n, "more than one $Elements section"));
                }
                have_elements = true;
                let (hn, h) = cur.ints(4, "$Elements header")?;
                let blocks = count(path, hn, h[0], "block count")?;
                let total = count(path, hn, h[1], "element count")?;
                let mut seen = 0usize;
                for _ in 0..blocks {
                    let (bn, b) = cur.ints(
                        4,
                        "element block header (entityDim entityTag elementType numElements)",
                    )?;
                    let (dim, etag, etype) = (b[0], b[1], b[2]);
                    let ne = count(path, bn, b[3], "element count")?;
                    let info = gmsh_type_info(etype);
                    let conv = if dim == 3 {
                        Some(supported_3d(etype).ok_or_else(|| {
                            cur.err(
                                bn,
                                format!(
                                    "unsupported 3D element type {etype}{} (supported: 4 tet4, 11 tet10, 5 hex8, 17 hex20)",
                                    info.map(|i| format!(" ({})", i.0)).unwrap_or_default()
                                ),
                            )
                        })?)
                    } else {
                        None
                    };
                    if let Some((name, _, tdim)) = info
                        && i64::from(tdim) != dim
                    {
                        return Err(cur.err(
                            bn,
                            format!("element type {etype} ({name}) in a {dim}D entity block"),
                        ));
                    }
                    let set = entity_nodes.entry((dim, etag)).or_default();
                    for _ in 0..ne {
                        let (n, t) = cur.tokens("element")?;
                        let tag = int(path, n, t[0], "element tag")?;
                        let tag = u64::try_from(tag)
                            .map_err(|_| cur.err(n, format!("invalid element tag {tag}")))?;
                        if let Some(first) = element_line.insert(tag, n) {
                            return Err(cur.err(
                                n,
                                format!("duplicate element tag {tag} (first at line {first})"),
                            ));
                        }
                        let nn = t.len() - 1;
                        if let Some((name, expect, _)) = info
                            && nn != expect
                        {
                            return Err(cur.err(
                                n,
                                format!("element {tag}: type {etype} ({name}) needs {expect} nodes, got {nn}"),
                            ));
                        }
                        if nn == 0 {
                            return Err(cur.err(n, format!("element {tag} has no nodes")));
                        }
                        let mut nodes = Vec::with_capacity(nn);
                        for s in &t[1..] {
                            let id = int(path, n, s, "element node tag")?;
                            let idx = u64::try_from(id)
                                .ok()
                                .and_then(|id| node_index.get(&id).copied())
                                .ok_or_else(|| {
                                    cur.err(
                                        n,
                                        format!("element {tag} references undefined node {id}"),
                                    )
                                })?;
                            nodes.push(idx);
                        }
                        set.extend(nodes.iter().copied());
                        if let Some((ty, perm)) = conv {
                            volume_elements
                                .entry(etag)
                                .or_default()
                                .push(mesh.connectivity.len());
                            mesh.connectivity
                                .push(perm.iter().map(|&k| nodes[k]).collect());
                            mesh.element_types.push(ty);
                            mesh.element_ids.push(tag);
                        }
                    }
                    seen += ne;
                }
                if seen != total {
                    return Err(cur.err(
                        hn,
                        format!("$Elements header announces {total} elements but the blocks contain {seen}"),
                    ));
                }
                cur.expect_end("Elements")?;
            }
            _ => {
                // Unknown / irrelevant section ($Comments, $NodeData, $Periodic, ...): skip.
                let end = format!("$End{section}");
                loop {
                    let (_, l) = cur.next(&end).map_err(|_| {
                        cur.err(n, format!("section ${section} is not terminated by {end}"))
                    })?;
                    if l == end {
                        break;
                    }
                }
            }
        }
    }
    if !have_format {
        return Err(ImportError::new(
            path,
            cur.last_line(),
            "not a Gmsh file: no $MeshFormat section",
        ));
    }
    if !have_nodes || !have_elements {
        return Err(ImportError::new(
            path,
            cur.last_line(),
            "missing $Nodes or $Elements section",
        ));
    }
    if !have_entities && !physical_names.is_empty() {
        return Err(ImportError::new(
            path,
            cur.last_line(),
            "$PhysicalNames present but no $Entities section: cannot map physical groups",
        ));
    }

    // Physical group (dim, tag) -> nodes / elements.
    let mut group_nodes: BTreeMap<(i64, i64), BTreeSet<usize>> = BTreeMap::new();
    let mut group_elements: BTreeMap<i64, BTreeSet<usize>> = BTreeMap::new();
    for key in physical_names.keys() {
        group_nodes.entry(*key).or_default();
        if key.0 == 3 {
            group_elements.entry(key.1).or_default();
        }
    }
    for (&(dim, etag), nodes) in &entity_nodes {
        for &p in entity_physicals
            .get(&(dim, etag))
            .map(Vec::as_slice)
            .unwrap_or(&[])
        {
            group_nodes
                .entry((dim, p))
                .or_default()
                .extend(nodes.iter().copied());
            if dim == 3 {
                let els = volume_elements.get(&etag).map(Vec::as_slice).unwrap_or(&[]);
                group_elements
                    .entry(p)
                    .or_default()
                    .extend(els.iter().copied());
            }
        }
    }
    let group_name = |dim: i64, tag: i64| -> String {
        if let Some(name) = physical_names.get(&(dim, tag)) {
            return name.clone();
        }
        let shared = group_nodes
            .keys()
            .any(|&(d, t)| t == tag && d != dim && !physical_names.contains_key(&(d, t)));
        if shared {
            format!("PHYSICAL_{dim}D_{tag}")
        } else {
            format!("PHYSICAL_{tag}")
        }
    };
    for (&(dim, tag), nodes) in &group_nodes {
        mesh.node_sets
            .entry(group_name(dim, tag))
            .or_default()
            .extend(nodes.iter().copied());
    }
    for (&tag, els) in &group_elements {
        mesh.element_sets
            .entry(group_name(3, tag))
            .or_default()
            .extend(els.iter().copied());
    }
    for v in mesh
        .node_sets
        .values_mut()
        .chain(mesh.element_sets.values_mut())
    {
        v.sort_unstable();
        v.dedup();
    }
    Ok(mesh)
}

#[cfg(test)]
mod tests {
    use super::super::test_util::assert_midsides_at_midpoints;
    use super::*;

    /// Unit cube as one hex8 in volume 1 ("body"), with a named physical
    /// surface on z = 0 ("fixed") and an unnamed physical surface (tag 3)
    /// on z = 1 whose nodes carry parametric coordinates.
    const CUBE: &str = r#"$MeshFormat
4.1 0 8
$EndMeshFormat
$PhysicalNames
2
2 1 "fixed"
3 2 "body"
$EndPhysicalNames
$Entities
0 0 2 1
1 0 0 0 1 1 0 1 1 0
2 0 0 1 1 1 1 1 3 0
1 0 0 0 1 1 1 1 2 2 1 2
$EndEntities
$Nodes
2 8 1 8
3 1 0 4
1
2
3
4
0 0 0
1 0 0
1 1 0
0 1 0

2 2 1 4
5
6
7
8
0 0 1 0 0
1 0 1 1 0
1 1 1 1 1
0 1 1 0 1
$EndNodes
$Comments
anything $here
$EndComments
$Elements
3 4 1 5
2 1 3 1
1 1 2 3 4
2 2 2 2
2 5 6 7
3 6 7 8
3 1 5 1
5 1 2 3 4 5 6 7 8
$EndElements
"#;

    #[test]
    fn unit_cube_hex8_with_physical_groups() {
        let m = parse_msh(CUBE, Path::new("cube.msh")).unwrap();
        assert_eq!(m.nodes.len(), 8);
        assert_eq!(m.nodes[6], [1.0, 1.0, 1.0]);
        assert_eq!(m.element_types, vec![ElementType::C3D8]);
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

    /// Builds a one-element .msh whose midside nodes are placed at the
    /// midpoints of the Gmsh edges (per the Gmsh "Node ordering" docs).
    fn single_element_msh(
        gmsh_type: i64,
        corners: &[[f64; 3]],
        gmsh_edges: &[(usize, usize)],
    ) -> String {
        let mut pts: Vec<[f64; 3]> = corners.to_vec();
        for &(a, b) in gmsh_edges {
            pts.push([0, 1, 2].map(|d| 0.5 * (corners[a][d] + corners[b][d])));
        }
        let n = pts.len();
        let mut s =
            format!("$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 {n} 1 {n}\n3 1 0 {n}\n");
        // Node tags in reverse order (tag != index + 1) to exercise the mapping.
        for k in 0..n {
            s += &format!("{}\n", 100 + n - k);
        }
        for p in &pts {
            s += &format!("{} {} {}\n", p[0], p[1], p[2]);
        }
        s += &format!("$EndNodes\n$Elements\n1 1 1 1\n3 1 {gmsh_type} 1\n7");
        for k in 0..n {
            s += &format!(" {}", 100 + n - k);
        }
        s + "\n$EndElements\n"
    }

    #[test]
    fn tet10_node_order_is_converted() {
        let corners = [
            [0.1, 0.0, 0.0],
            [2.0, 0.3, 0.0],
            [0.2, 3.0, 0.1],
            [0.3, 0.1, 5.0],
        ];
        // Gmsh Tetrahedron10: 4: 0-1, 5: 1-2, 6: 2-0, 7: 0-3, 8: 2-3, 9: 1-3
        let gmsh_edges = [(0, 1), (1, 2), (2, 0), (0, 3), (2, 3), (1, 3)];
        let m = parse_msh(
            &single_element_msh(11, &corners, &gmsh_edges),
            Path::new("t.msh"),
        )
        .unwrap();
        assert_eq!(m.element_types, vec![ElementType::C3D10]);
        assert_eq!(m.element_ids, vec![7]);
        assert_midsides_at_midpoints(&m);
    }

    #[test]
    fn hex20_node_order_is_converted() {
        let corners = [
            [0.0, 0.0, 0.0],
            [2.0, 0.0, 0.1],
            [2.2, 3.0, 0.0],
            [0.1, 3.1, 0.0],
            [0.0, 0.2, 4.0],
            [2.0, 0.0, 4.1],
            [2.1, 3.0, 4.0],
            [0.0, 3.0, 4.2],
        ];
        // Gmsh Hexahedron20: 8: 0-1, 9: 0-3, 10: 0-4, 11: 1-2, 12: 1-5, 13: 2-3,
        // 14: 2-6, 15: 3-7, 16: 4-5, 17: 4-7, 18: 5-6, 19: 6-7
        let gmsh_edges = [
            (0, 1),
            (0, 3),
            (0, 4),
            (1, 2),
            (1, 5),
            (2, 3),
            (2, 6),
            (3, 7),
            (4, 5),
            (4, 7),
            (5, 6),
            (6, 7),
        ];
        let m = parse_msh(
            &single_element_msh(17, &corners, &gmsh_edges),
            Path::new("h.msh"),
        )
        .unwrap();
        assert_eq!(m.element_types, vec![ElementType::C3D20]);
        assert_midsides_at_midpoints(&m);
        // corners unchanged
        for (&n, c) in m.connectivity[0].iter().zip(&corners) {
            assert_eq!(&m.nodes[n], c);
        }
    }

    fn check(text: &str, line: usize, parts: &[&str]) {
        let e = parse_msh(text, Path::new("bad.msh")).unwrap_err();
        assert_eq!(e.line, line, "wrong line for: {e}");
        for p in parts {
            assert!(e.message.contains(p), "message lacks '{p}': {e}");
        }
        assert!(
            e.to_string().starts_with(&format!("bad.msh:{line}: ")),
            "{e}"
        );
    }

    #[test]
    fn errors_have_lines() {
        check(
            "$MeshFormat\n4.1 1 8\n\u{1}\0\0\0\n$EndMeshFormat\n",
            2,
            &["binary .msh not supported, save as ASCII"],
        );
        check(
            "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n",
            2,
            &["version 2.2"],
        );
        check("$Nodes\n", 1, &["$MeshFormat"]);
        // line numbers refer to CUBE
        check(
            &CUBE.replace("3 6 7 8", "3 6 7 9"),
            46,
            &["element 3", "undefined node 9"],
        );
        check(
            &CUBE.replace("1 1 2 3 4\n2 2", "1 1 2 3\n2 2"),
            43,
            &["needs 4 nodes, got 3"],
        );
        check(
            &CUBE.replace("3 1 5 1", "3 1 6 1"),
            47,
            &["unsupported 3D element type 6 (prism6)"],
        );
        check(
            &CUBE.replace("1 1 0\n0 1 0", "1 x 0\n0 1 0"),
            24,
            &["malformed number 'x'"],
        );
        check(
            &CUBE.replace("\n4\n0 0 0", "\n3\n0 0 0"),
            21,
            &["duplicate node tag 3"],
        );
        check(
            &CUBE.replace("3 6 7 8", "1 6 7 8"),
            46,
            &["duplicate element tag 1"],
        );
        check(
            &CUBE.replace("$EndNodes\n", ""),
            36,
            &["expected $EndNodes"],
        );
    }
}
