//! Gmsh MSH 4.1 importer (ASCII and binary).
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
//!
//! # Binary files
//!
//! A binary file (`$MeshFormat` line `4.1 1 8`) is read as bytes, as laid
//! out in the Gmsh reference manual ("MSH file format") and written by
//! Gmsh's `GModelIO_MSH4.cpp`: the `$MeshFormat` line is followed by the
//! int 1 as an endianness check; section header and footer lines and the
//! whole `$PhysicalNames` section are ASCII; the bodies of `$Entities`,
//! `$Nodes` and `$Elements` are raw little-endian numbers with the layout of
//! the ASCII sections: `int` = i32, `size_t` = u64 (data-size 8 is
//! required), `double` = f64. Files written on a big-endian machine
//! (byte-swapped check int) are refused, and so are element blocks of a
//! type missing from the importer's table of Gmsh types (up to order 2,
//! plus a few order-3 ones; the node count is needed to read a binary
//! block, where the ASCII reader can skip any lower-dimensional type).
//! Both encodings of one mesh give the same [`ImportedMesh`] (ASCII
//! coordinates carry 16 significant digits, the binary ones all bits).
//! Errors in binary files have `line` 0 and start with the 0-based byte
//! offset they refer to (`byte N: ...`).

use super::{ImportError, ImportedMesh};
use crate::input::element::ElementKind;
use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::fmt;
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

/// Reads a Gmsh MSH 4.1 file, ASCII or binary.
pub fn read_msh(path: &Path) -> Result<ImportedMesh, ImportError> {
    let bytes = std::fs::read(path)
        .map_err(|e| ImportError::new(path, 0, format!("cannot read file: {e}")))?;
    parse_msh_bytes(&bytes, path)
}

/// Parses the contents of a MSH 4.1 file, ASCII or binary (as announced by
/// the file-type in `$MeshFormat`); `path` is used for messages.
pub fn parse_msh_bytes(bytes: &[u8], path: &Path) -> Result<ImportedMesh, ImportError> {
    if is_binary(bytes) {
        parse_binary(bytes, path)
    } else {
        // Lossy: invalid UTF-8 can only matter in physical names and comments.
        parse_msh(&String::from_utf8_lossy(bytes), path)
    }
}

/// Whether the file starts with a `$MeshFormat` section of file-type 1.
/// Anything else goes to the ASCII reader, which reports what is wrong.
fn is_binary(bytes: &[u8]) -> bool {
    let mut r = Bin {
        path: Path::new(""),
        b: bytes,
        pos: 0,
    };
    matches!(r.line(), Some((_, l)) if l == b"$MeshFormat")
        && r.line().is_some_and(|(_, l)| {
            let t = ascii_tokens(l);
            t.len() == 3 && t.get(1) == Some(&&b"1"[..])
        })
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

fn supported_3d(t: i64) -> Option<(ElementKind, &'static [usize])> {
    const TET4: [usize; 4] = [0, 1, 2, 3];
    const HEX8: [usize; 8] = [0, 1, 2, 3, 4, 5, 6, 7];
    match t {
        4 => Some((ElementKind::Tet4, &TET4)),
        11 => Some((ElementKind::Tet10, &TET10_GMSH_TO_ABAQUS)),
        5 => Some((ElementKind::Hex8, &HEX8)),
        17 => Some((ElementKind::Hex20, &HEX20_GMSH_TO_ABAQUS)),
        _ => None,
    }
}

type Res<T> = Result<T, ImportError>;

/// Where an error is: a 1-based line of an ASCII file, or a 0-based byte
/// offset of a binary file.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Loc {
    Line(usize),
    Byte(usize),
}

impl fmt::Display for Loc {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Loc::Line(n) => write!(f, "line {n}"),
            Loc::Byte(b) => write!(f, "byte {b}"),
        }
    }
}

/// An error at `loc`: ASCII files report the line in [`ImportError::line`],
/// binary files (line 0) the byte offset at the start of the message.
fn error(path: &Path, loc: Loc, msg: impl Into<String>) -> ImportError {
    match loc {
        Loc::Line(n) => ImportError::new(path, n, msg),
        Loc::Byte(b) => ImportError::new(path, 0, format!("byte {b}: {}", msg.into())),
    }
}

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

/// The tokens of a line as exactly `count` integers.
fn ints_of(path: &Path, loc: Loc, t: &[&str], count: usize, what: &str) -> Res<Vec<i64>> {
    if t.len() != count {
        return Err(error(
            path,
            loc,
            format!("{what}: expected {count} values, got {}", t.len()),
        ));
    }
    t.iter().map(|s| int_at(path, loc, s, what)).collect()
}

fn int_at(path: &Path, loc: Loc, s: &str, what: &str) -> Res<i64> {
    s.parse::<i64>()
        .map_err(|_| error(path, loc, format!("malformed integer '{s}' in {what}")))
}

fn int(path: &Path, line: usize, s: &str, what: &str) -> Res<i64> {
    int_at(path, Loc::Line(line), s, what)
}

fn count_at(path: &Path, loc: Loc, v: i64, what: &str) -> Res<usize> {
    usize::try_from(v).map_err(|_| error(path, loc, format!("negative {what} {v}")))
}

fn count(path: &Path, line: usize, v: i64, what: &str) -> Res<usize> {
    count_at(path, Loc::Line(line), v, what)
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

/// A `$PhysicalNames` line `dim tag "name"` (ASCII in both encodings).
fn physical_name(path: &Path, loc: Loc, l: &str) -> Res<((i64, i64), String)> {
    let mut it = l.splitn(2, char::is_whitespace);
    let dim = int_at(
        path,
        loc,
        it.next().unwrap_or(""),
        "physical name dimension",
    )?;
    let rest = it.next().unwrap_or("").trim_start();
    let mut it = rest.splitn(2, char::is_whitespace);
    let tag = int_at(path, loc, it.next().unwrap_or(""), "physical name tag")?;
    let name = it.next().unwrap_or("").trim();
    let name = name
        .strip_prefix('"')
        .and_then(|s| s.strip_suffix('"'))
        .ok_or_else(|| error(path, loc, "physical name: expected 'dim tag \"name\"'"))?;
    Ok(((dim, tag), name.to_string()))
}

/// The mesh a MSH 4.1 file defines, independent of its encoding: the ASCII
/// and the binary reader feed it in file order and it makes the checks
/// that do not depend on the encoding, so both give the same
/// [`ImportedMesh`] and the same messages.
struct MeshBuilder<'p> {
    path: &'p Path,
    physical_names: BTreeMap<(i64, i64), String>,
    have_entities: bool,
    /// (dim, entity tag) -> physical tags
    entity_physicals: HashMap<(i64, i64), Vec<i64>>,
    mesh: ImportedMesh,
    node_index: HashMap<u64, usize>,
    /// Where each node tag was read, by node index.
    node_loc: Vec<Loc>,
    have_nodes: bool,
    have_elements: bool,
    /// (dim, entity tag) -> nodes of its elements
    entity_nodes: HashMap<(i64, i64), BTreeSet<usize>>,
    /// 3D entity tag -> element indices
    volume_elements: HashMap<i64, Vec<usize>>,
    /// Where each element tag was read.
    element_loc: HashMap<u64, Loc>,
}

/// A checked element block header.
struct ElementBlock {
    dim: i64,
    etag: i64,
    etype: i64,
    /// (name, number of nodes, dimension) if the type is known.
    info: Option<(&'static str, usize, u8)>,
    /// Element type and Gmsh -> CalculiX node permutation of a 3D block.
    conv: Option<(ElementKind, &'static [usize])>,
}

impl<'p> MeshBuilder<'p> {
    fn new(path: &'p Path) -> Self {
        MeshBuilder {
            path,
            physical_names: BTreeMap::new(),
            have_entities: false,
            entity_physicals: HashMap::new(),
            mesh: ImportedMesh::default(),
            node_index: HashMap::new(),
            node_loc: Vec::new(),
            have_nodes: false,
            have_elements: false,
            entity_nodes: HashMap::new(),
            volume_elements: HashMap::new(),
            element_loc: HashMap::new(),
        }
    }

    fn err(&self, loc: Loc, msg: impl Into<String>) -> ImportError {
        error(self.path, loc, msg)
    }

    fn begin_nodes(&mut self, loc: Loc) -> Res<()> {
        if self.have_nodes {
            return Err(self.err(loc, "more than one $Nodes section"));
        }
        self.have_nodes = true;
        Ok(())
    }

    /// Registers the tag of the next node; its coordinates follow (after
    /// the other tags of its block) with [`Self::push_node`].
    fn node_tag(&mut self, loc: Loc, tag: u64) -> Res<()> {
        if let Some(&first) = self.node_index.get(&tag) {
            let first = self.node_loc.get(first).copied().unwrap_or(loc);
            return Err(self.err(loc, format!("duplicate node tag {tag} (first at {first})")));
        }
        self.node_index.insert(tag, self.node_loc.len());
        self.node_loc.push(loc);
        Ok(())
    }

    fn push_node(&mut self, tag: u64, x: [f64; 3]) {
        self.mesh.nodes.push(x);
        self.mesh.node_ids.push(tag);
    }

    fn end_nodes(&self, header: Loc, total: usize) -> Res<()> {
        if self.mesh.nodes.len() != total {
            return Err(self.err(
                header,
                format!(
                    "$Nodes header announces {total} nodes but the blocks contain {}",
                    self.mesh.nodes.len()
                ),
            ));
        }
        Ok(())
    }

    fn begin_elements(&mut self, loc: Loc) -> Res<()> {
        if !self.have_nodes {
            return Err(self.err(loc, "$Elements before $Nodes"));
        }
        if self.have_elements {
            return Err(self.err(loc, "more than one $Elements section"));
        }
        self.have_elements = true;
        Ok(())
    }

    fn element_block(&mut self, loc: Loc, dim: i64, etag: i64, etype: i64) -> Res<ElementBlock> {
        let info = gmsh_type_info(etype);
        let conv = if dim == 3 {
            Some(supported_3d(etype).ok_or_else(|| {
                self.err(
                    loc,
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
            return Err(self.err(
                loc,
                format!("element type {etype} ({name}) in a {dim}D entity block"),
            ));
        }
        // An empty block of a physical entity still makes its (empty) set.
        self.entity_nodes.entry((dim, etag)).or_default();
        Ok(ElementBlock {
            dim,
            etag,
            etype,
            info,
            conv,
        })
    }

    fn element_tag(&mut self, loc: Loc, tag: u64) -> Res<()> {
        if let Some(first) = self.element_loc.insert(tag, loc) {
            return Err(self.err(
                loc,
                format!("duplicate element tag {tag} (first at {first})"),
            ));
        }
        Ok(())
    }

    /// Index of node `id` referenced by element `element`.
    fn node_ref<T: Copy + fmt::Display>(&self, loc: Loc, element: u64, id: T) -> Res<usize>
    where
        u64: TryFrom<T>,
    {
        u64::try_from(id)
            .ok()
            .and_then(|id| self.node_index.get(&id).copied())
            .ok_or_else(|| {
                self.err(
                    loc,
                    format!("element {element} references undefined node {id}"),
                )
            })
    }

    /// Adds an element of `block`; `nodes` (indices, Gmsh order) has the
    /// node count of the block's type whenever the type is known.
    fn push_element(&mut self, block: &ElementBlock, tag: u64, nodes: Vec<usize>) {
        self.entity_nodes
            .entry((block.dim, block.etag))
            .or_default()
            .extend(nodes.iter().copied());
        if let Some((ty, perm)) = block.conv {
            self.volume_elements
                .entry(block.etag)
                .or_default()
                .push(self.mesh.connectivity.len());
            // A 3D block has a known type, so `nodes` has `perm.len()` entries.
            self.mesh
                .connectivity
                .push(perm.iter().map(|&k| nodes[k]).collect());
            self.mesh.element_types.push(ty);
            self.mesh.element_ids.push(tag);
        }
    }

    fn end_elements(&self, header: Loc, total: usize, seen: usize) -> Res<()> {
        if seen != total {
            return Err(self.err(
                header,
                format!(
                    "$Elements header announces {total} elements but the blocks contain {seen}"
                ),
            ));
        }
        Ok(())
    }

    /// Final checks and the node/element sets of the physical groups;
    /// `end` locates errors about the file as a whole.
    fn finish(self, end: Loc) -> Res<ImportedMesh> {
        if !self.have_nodes || !self.have_elements {
            return Err(self.err(end, "missing $Nodes or $Elements section"));
        }
        if !self.have_entities && !self.physical_names.is_empty() {
            return Err(self.err(
                end,
                "$PhysicalNames present but no $Entities section: cannot map physical groups",
            ));
        }
        let MeshBuilder {
            physical_names,
            entity_physicals,
            mut mesh,
            entity_nodes,
            volume_elements,
            ..
        } = self;

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
}

/// Parses the text of a MSH 4.1 ASCII file; `path` is used for messages.
/// Binary files must be read as bytes: [`read_msh`], [`parse_msh_bytes`].
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
    let mut mb = MeshBuilder::new(path);

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
                if t[1] == "1" {
                    return Err(cur.err(
                        n,
                        "binary .msh not supported here, save as ASCII (binary MSH 4.1 is read from bytes, by read_msh / parse_msh_bytes)",
                    ));
                }
                if t[1] != "0" {
                    return Err(cur.err(
                        n,
                        format!(
                            "$MeshFormat: file-type '{}' (expected 0 for ASCII or 1 for binary)",
                            t[1]
                        ),
                    ));
                }
                if t[0] != "4.1" {
                    return Err(cur.err(
                        n,
                        format!(
                            "MSH version {} not supported: only 4.1, ASCII or binary (in Gmsh: Mesh.MshFileVersion = 4.1, or -format msh41)",
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
                    let (key, name) = physical_name(path, Loc::Line(n), l)?;
                    mb.physical_names.insert(key, name);
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
                        mb.entity_physicals.insert((dim, tag), phys);
                    }
                }
                cur.expect_end("Entities")?;
                mb.have_entities = true;
            }
            "PartitionedEntities" => {
                return Err(cur.err(n, "partitioned .msh files are not supported"));
            }
            "Nodes" => {
                mb.begin_nodes(Loc::Line(n))?;
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
                        mb.node_tag(Loc::Line(n), tag)?;
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
                        mb.push_node(tag, x);
                    }
                }
                mb.end_nodes(Loc::Line(hn), total)?;
                cur.expect_end("Nodes")?;
            }
            "Elements" => {
                mb.begin_elements(Loc::Line(n))?;
                let (hn, h) = cur.ints(4, "$Elements header")?;
                let blocks = count(path, hn, h[0], "block count")?;
                let total = count(path, hn, h[1], "element count")?;
                let mut seen = 0usize;
                for _ in 0..blocks {
                    let (bn, b) = cur.ints(
                        4,
                        "element block header (entityDim entityTag elementType numElements)",
                    )?;
                    let ne = count(path, bn, b[3], "element count")?;
                    let block = mb.element_block(Loc::Line(bn), b[0], b[1], b[2])?;
                    for _ in 0..ne {
                        let (n, t) = cur.tokens("element")?;
                        let tag = int(path, n, t[0], "element tag")?;
                        let tag = u64::try_from(tag)
                            .map_err(|_| cur.err(n, format!("invalid element tag {tag}")))?;
                        mb.element_tag(Loc::Line(n), tag)?;
                        let nn = t.len() - 1;
                        if let Some((name, expect, _)) = block.info
                            && nn != expect
                        {
                            return Err(cur.err(
                                n,
                                format!(
                                    "element {tag}: type {} ({name}) needs {expect} nodes, got {nn}",
                                    block.etype
                                ),
                            ));
                        }
                        if nn == 0 {
                            return Err(cur.err(n, format!("element {tag} has no nodes")));
                        }
                        let mut nodes = Vec::with_capacity(nn);
                        for s in &t[1..] {
                            let id = int(path, n, s, "element node tag")?;
                            nodes.push(mb.node_ref(Loc::Line(n), tag, id)?);
                        }
                        mb.push_element(&block, tag, nodes);
                    }
                    seen += ne;
                }
                mb.end_elements(Loc::Line(hn), total, seen)?;
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
    mb.finish(Loc::Line(cur.last_line()))
}

/// ASCII-whitespace separated tokens of a line of bytes.
fn ascii_tokens(l: &[u8]) -> Vec<&[u8]> {
    l.split(|c| c.is_ascii_whitespace())
        .filter(|t| !t.is_empty())
        .collect()
}

/// A line of a binary file for a message: lossy UTF-8, escaped, at most
/// 40 characters.
fn shown(l: &[u8]) -> String {
    let s = String::from_utf8_lossy(l);
    let mut out: String = s.chars().take(40).flat_map(char::escape_debug).collect();
    if s.chars().nth(40).is_some() {
        out.push_str("...");
    }
    out
}

/// Cursor over the bytes of a binary MSH file. Every read is bounds
/// checked; running out of bytes is an "unexpected end of file" error.
struct Bin<'a> {
    path: &'a Path,
    b: &'a [u8],
    pos: usize,
}

impl<'a> Bin<'a> {
    fn err(&self, at: usize, msg: impl Into<String>) -> ImportError {
        error(self.path, Loc::Byte(at), msg)
    }

    fn eof(&self, section: &str, what: &str) -> ImportError {
        self.err(
            self.pos,
            format!(
                "unexpected end of file in ${section}: expected {what}, {} bytes left",
                self.b.len().saturating_sub(self.pos)
            ),
        )
    }

    /// The next `n` bytes (`what`, in `$section`).
    fn take(&mut self, n: usize, section: &str, what: &str) -> Res<&'a [u8]> {
        let b = self.b;
        match self.pos.checked_add(n).and_then(|end| b.get(self.pos..end)) {
            Some(s) => {
                self.pos += n;
                Ok(s)
            }
            None => Err(self.eof(section, &format!("{what} ({n} bytes)"))),
        }
    }

    fn array<const N: usize>(&mut self, section: &str, what: &str) -> Res<[u8; N]> {
        let at = self.pos;
        let s = self.take(N, section, what)?;
        <[u8; N]>::try_from(s).map_err(|_| self.err(at, format!("cannot read {what}")))
    }

    /// An `int` (i32).
    fn int(&mut self, section: &str, what: &str) -> Res<i32> {
        Ok(i32::from_le_bytes(self.array(section, what)?))
    }

    /// A `size_t` (u64, data-size 8).
    fn size(&mut self, section: &str, what: &str) -> Res<u64> {
        Ok(u64::from_le_bytes(self.array(section, what)?))
    }

    /// A `double` (f64).
    fn double(&mut self, section: &str, what: &str) -> Res<f64> {
        Ok(f64::from_le_bytes(self.array(section, what)?))
    }

    /// A `size_t` count.
    fn count(&mut self, section: &str, what: &str) -> Res<usize> {
        let at = self.pos;
        let v = self.size(section, what)?;
        usize::try_from(v).map_err(|_| self.err(at, format!("{what} {v} is too large")))
    }

    /// Skips `count` values of `width` bytes.
    fn skip(&mut self, count: usize, width: usize, section: &str, what: &str) -> Res<()> {
        match count.checked_mul(width) {
            Some(n) => self.take(n, section, what).map(|_| ()),
            None => Err(self.eof(section, &format!("{count} {what}"))),
        }
    }

    /// Skips ASCII whitespace, then returns the offset and the bytes (right
    /// trimmed) of the line up to the next `\n`, which is consumed; `None`
    /// at the end of the file.
    fn line(&mut self) -> Option<(usize, &'a [u8])> {
        let b = self.b;
        let rest = b.get(self.pos..)?;
        let Some(skip) = rest.iter().position(|c| !c.is_ascii_whitespace()) else {
            self.pos = b.len();
            return None;
        };
        let start = self.pos + skip;
        let rest = b.get(start..)?;
        let len = rest.iter().position(|&c| c == b'\n').unwrap_or(rest.len());
        self.pos = start + len + usize::from(len < rest.len());
        Some((start, rest.get(..len)?.trim_ascii_end()))
    }

    /// The next line, which must exist, in `$section`.
    fn ascii_line(&mut self, section: &str, what: &str) -> Res<(usize, &'a [u8])> {
        self.line().ok_or_else(|| self.eof(section, what))
    }

    /// Expects the line `$End<section>`.
    fn expect_end(&mut self, section: &str) -> Res<()> {
        let end = format!("$End{section}");
        let (at, l) = self.ascii_line(section, &end)?;
        if l != end.as_bytes() {
            return Err(self.err(at, format!("expected {end}, found '{}'", shown(l))));
        }
        Ok(())
    }

    /// Skips an unknown section (started at `at`) up to the line
    /// `$End<section>`.
    fn skip_section(&mut self, section: &str, at: usize) -> Res<()> {
        let end = format!("$End{section}");
        let pat = end.as_bytes();
        let b = self.b;
        let mut from = self.pos;
        while let Some(i) = b
            .get(from..)
            .and_then(|rest| rest.windows(pat.len()).position(|w| w == pat))
        {
            let start = from + i;
            let stop = start + pat.len();
            let line_start = start
                .checked_sub(1)
                .and_then(|p| b.get(p))
                .is_none_or(|c| c.is_ascii_whitespace());
            let line_end = b.get(stop).is_none_or(|c| c.is_ascii_whitespace());
            if line_start && line_end {
                self.pos = stop;
                return Ok(());
            }
            from = start + 1;
        }
        Err(self.err(at, format!("section ${section} is not terminated by {end}")))
    }
}

/// Parses a binary MSH 4.1 file (see the module documentation).
fn parse_binary(bytes: &[u8], path: &Path) -> Res<ImportedMesh> {
    let mut r = Bin {
        path,
        b: bytes,
        pos: 0,
    };
    let mut mb = MeshBuilder::new(path);
    let mut have_format = false;
    while let Some((at, header)) = r.line() {
        let Some(section) = header.strip_prefix(b"$") else {
            return Err(r.err(
                at,
                format!(
                    "expected a section header ($Name), found '{}'",
                    shown(header)
                ),
            ));
        };
        let section = String::from_utf8_lossy(section).into_owned();
        if !have_format && section != "MeshFormat" {
            return Err(r.err(at, format!("expected $MeshFormat before ${section}")));
        }
        match section.as_str() {
            "MeshFormat" => {
                binary_mesh_format(&mut r)?;
                have_format = true;
            }
            "PhysicalNames" => {
                const S: &str = "PhysicalNames";
                let (at, l) = r.ascii_line(S, "the number of physical names")?;
                let t = String::from_utf8_lossy(l);
                let t: Vec<&str> = t.split_whitespace().collect();
                let c = ints_of(path, Loc::Byte(at), &t, 1, "$PhysicalNames count")?;
                for _ in 0..count_at(path, Loc::Byte(at), c[0], "count")? {
                    let (at, l) = r.ascii_line(S, "a physical name line")?;
                    let (key, name) =
                        physical_name(path, Loc::Byte(at), &String::from_utf8_lossy(l))?;
                    mb.physical_names.insert(key, name);
                }
                r.expect_end(S)?;
            }
            "Entities" => {
                const S: &str = "Entities";
                let mut counts = [0usize; 4];
                for (dim, c) in counts.iter_mut().enumerate() {
                    *c = r.count(S, &format!("the number of {dim}D entities"))?;
                }
                for (dim, &c) in (0i64..).zip(&counts) {
                    for _ in 0..c {
                        let tag = r.int(S, &format!("{dim}D entity tag"))?;
                        // point: x y z; others: bounding box
                        r.skip(if dim == 0 { 3 } else { 6 }, 8, S, "entity coordinates")?;
                        let np = r.count(S, "the number of physical tags of an entity")?;
                        let mut phys = Vec::new();
                        for _ in 0..np {
                            phys.push(i64::from(r.int(S, "physical tag")?).abs());
                        }
                        if dim > 0 {
                            let nb = r.count(S, "the number of bounding entities")?;
                            r.skip(nb, 4, S, "bounding entity tags")?;
                        }
                        mb.entity_physicals.insert((dim, i64::from(tag)), phys);
                    }
                }
                r.expect_end(S)?;
                mb.have_entities = true;
            }
            "PartitionedEntities" => {
                return Err(r.err(at, "partitioned .msh files are not supported"));
            }
            "Nodes" => {
                const S: &str = "Nodes";
                mb.begin_nodes(Loc::Byte(at))?;
                let header = Loc::Byte(r.pos);
                let blocks = r.count(S, "the number of node blocks")?;
                let total = r.count(S, "the number of nodes")?;
                r.skip(2, 8, S, "the min/max node tags")?;
                for _ in 0..blocks {
                    let bat = r.pos;
                    let dim = r.int(S, "node block entity dimension")?;
                    r.int(S, "node block entity tag")?;
                    let parametric = r.int(S, "node block parametric flag")? != 0;
                    let nb = r.count(S, "the number of nodes in a block")?;
                    if !(0..=3).contains(&dim) {
                        return Err(
                            r.err(bat, format!("invalid node block entity dimension {dim}"))
                        );
                    }
                    // parametric coordinates: u (curves), u v (surfaces), u v w (volumes)
                    let extra = if parametric { dim as usize } else { 0 };
                    let mut tags = Vec::with_capacity(nb.min(r.b.len() / 8));
                    for _ in 0..nb {
                        let at = r.pos;
                        let tag = r.size(S, "node tag")?;
                        mb.node_tag(Loc::Byte(at), tag)?;
                        tags.push(tag);
                    }
                    for &tag in &tags {
                        let at = r.pos;
                        let mut x = [0.0; 3];
                        for v in &mut x {
                            *v = r.double(S, "node coordinate")?;
                        }
                        if let Some(v) = x.iter().find(|v| !v.is_finite()) {
                            return Err(r.err(
                                at,
                                format!("coordinates of node {tag}: {v} is not a finite number"),
                            ));
                        }
                        r.skip(extra, 8, S, "parametric node coordinates")?;
                        mb.push_node(tag, x);
                    }
                }
                mb.end_nodes(header, total)?;
                r.expect_end(S)?;
            }
            "Elements" => {
                const S: &str = "Elements";
                mb.begin_elements(Loc::Byte(at))?;
                let header = Loc::Byte(r.pos);
                let blocks = r.count(S, "the number of element blocks")?;
                let total = r.count(S, "the number of elements")?;
                r.skip(2, 8, S, "the min/max element tags")?;
                let mut seen = 0usize;
                for _ in 0..blocks {
                    let bat = Loc::Byte(r.pos);
                    let dim = r.int(S, "element block entity dimension")?;
                    let etag = r.int(S, "element block entity tag")?;
                    let etype = r.int(S, "element block element type")?;
                    let ne = r.count(S, "the number of elements in a block")?;
                    let block =
                        mb.element_block(bat, i64::from(dim), i64::from(etag), i64::from(etype))?;
                    let Some((_, nn, _)) = block.info else {
                        return Err(mb.err(
                            bat,
                            format!(
                                "unknown element type {etype} in a {dim}D block: its node count is needed to read a binary file"
                            ),
                        ));
                    };
                    for _ in 0..ne {
                        let at = r.pos;
                        let tag = r.size(S, "element tag")?;
                        mb.element_tag(Loc::Byte(at), tag)?;
                        let mut nodes = Vec::with_capacity(nn);
                        for _ in 0..nn {
                            let at = r.pos;
                            let id = r.size(S, "element node tag")?;
                            nodes.push(mb.node_ref(Loc::Byte(at), tag, id)?);
                        }
                        mb.push_element(&block, tag, nodes);
                    }
                    seen = seen.saturating_add(ne);
                }
                mb.end_elements(header, total, seen)?;
                r.expect_end(S)?;
            }
            _ => r.skip_section(&section, at)?,
        }
    }
    mb.finish(Loc::Byte(bytes.len()))
}

/// The rest of a binary file's `$MeshFormat` section, after its header.
fn binary_mesh_format(r: &mut Bin) -> Res<()> {
    const S: &str = "MeshFormat";
    let (at, l) = r.ascii_line(S, "'version file-type data-size'")?;
    let t = ascii_tokens(l);
    let text = |i: usize| {
        t.get(i)
            .map(|s| String::from_utf8_lossy(s))
            .unwrap_or_default()
    };
    if t.len() != 3 {
        return Err(r.err(at, "$MeshFormat: expected 'version file-type data-size'"));
    }
    if text(1) != "1" {
        return Err(r.err(
            at,
            format!("$MeshFormat: file-type {} in a binary file", text(1)),
        ));
    }
    if text(0) != "4.1" {
        return Err(r.err(
            at,
            format!(
                "MSH version {} not supported: only 4.1, ASCII or binary (in Gmsh: Mesh.MshFileVersion = 4.1, or -format msh41)",
                text(0)
            ),
        ));
    }
    if text(2) != "8" {
        return Err(r.err(
            at,
            format!(
                "binary .msh with data-size {} not supported: only 8 (8-byte size_t, as written by 64-bit Gmsh)",
                text(2)
            ),
        ));
    }
    let at = r.pos;
    let one: [u8; 4] = r.array(S, "the endianness check (binary int 1)")?;
    if one != 1i32.to_le_bytes() {
        return Err(r.err(
            at,
            if one == 1i32.to_be_bytes() {
                "byte-swapped binary .msh (written on a big-endian machine) not supported: the endianness check int is 1 in big-endian byte order; save as ASCII".to_string()
            } else {
                format!(
                    "endianness check: expected the binary int 1, found bytes {one:02x?}"
                )
            },
        ));
    }
    r.expect_end(S)
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
        assert_eq!(m.element_types, vec![ElementKind::Tet10]);
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
        assert_eq!(m.element_types, vec![ElementKind::Hex20]);
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
            &[
                "binary .msh not supported here, save as ASCII",
                "parse_msh_bytes",
            ],
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

    // ------------------------------------------------------------------
    // Binary MSH 4.1

    /// (name, ASCII export, binary export) of one Gmsh model each, written
    /// by `testdata/make_fixtures.py` (Gmsh 4.15.2).
    const FIXTURES: [(&str, &[u8], &[u8]); 4] = [
        (
            "hex8",
            include_bytes!("testdata/hex8.msh"),
            include_bytes!("testdata/hex8.bin.msh"),
        ),
        (
            "hex20",
            include_bytes!("testdata/hex20.msh"),
            include_bytes!("testdata/hex20.bin.msh"),
        ),
        (
            "tet4",
            include_bytes!("testdata/tet4.msh"),
            include_bytes!("testdata/tet4.bin.msh"),
        ),
        (
            "tet10",
            include_bytes!("testdata/tet10.msh"),
            include_bytes!("testdata/tet10.bin.msh"),
        ),
    ];

    /// Asserts that two imports describe the same mesh: everything equal,
    /// coordinates within 1e-15 relative (ASCII has 16 significant digits,
    /// binary all bits of the same doubles).
    fn assert_same_mesh(ascii: &ImportedMesh, binary: &ImportedMesh, what: &str) {
        assert_eq!(ascii.nodes.len(), binary.nodes.len(), "{what}: node count");
        for (i, (a, b)) in ascii.nodes.iter().zip(&binary.nodes).enumerate() {
            for d in 0..3 {
                assert!(
                    (a[d] - b[d]).abs() <= 1e-15 * a[d].abs().max(b[d].abs()),
                    "{what}: node {i}, coordinate {d}: {} vs {}",
                    a[d],
                    b[d]
                );
            }
        }
        let without_coordinates = |m: &ImportedMesh| ImportedMesh {
            nodes: Vec::new(),
            ..m.clone()
        };
        assert_eq!(
            without_coordinates(ascii),
            without_coordinates(binary),
            "{what}"
        );
    }

    fn parse_fixture(name: &str, bytes: &[u8]) -> ImportedMesh {
        parse_msh_bytes(bytes, Path::new(name)).unwrap_or_else(|e| panic!("{e}"))
    }

    #[test]
    fn binary_fixtures_equal_their_ascii_twins() {
        for (name, ascii, binary) in FIXTURES {
            assert!(ascii.starts_with(b"$MeshFormat\n4.1 0 8\n"), "{name}");
            assert!(
                binary.starts_with(b"$MeshFormat\n4.1 1 8\n\x01\0\0\0\n"),
                "{name}"
            );
            let a = parse_fixture(name, ascii);
            let b = parse_fixture(name, binary);
            assert_same_mesh(&a, &b, name);
            assert!(!b.connectivity.is_empty(), "{name}");
            // Midside nodes at the midpoints of their CalculiX edges (Gmsh
            // places them through the curve parametrisation: ~1e-12 off).
            for (ty, conn) in b.element_types.iter().zip(&b.connectivity) {
                for (k, &(i, j)) in ty.midside_edges().iter().enumerate() {
                    let m = b.nodes[conn[ty.corner_nodes() + k]];
                    let (p, q) = (b.nodes[conn[i]], b.nodes[conn[j]]);
                    for d in 0..3 {
                        assert!(
                            (m[d] - 0.5 * (p[d] + q[d])).abs() < 1e-9,
                            "{name}: {ty} edge {i}-{j}"
                        );
                    }
                }
            }
            // every node set point is where its group says
            let on = |set: &str, pred: &dyn Fn([f64; 3]) -> bool| {
                let s = &b.node_sets[set];
                assert!(!s.is_empty(), "{name}: {set} is empty");
                for &n in s {
                    assert!(
                        pred(b.nodes[n]),
                        "{name}: node {n} of {set} at {:?}",
                        b.nodes[n]
                    );
                }
            };
            match name {
                "hex8" | "hex20" => {
                    let (ty, nn, bottom) = if name == "hex8" {
                        (ElementKind::Hex8, 12, 6)
                    } else {
                        (ElementKind::Hex20, 32, 13)
                    };
                    assert_eq!(b.element_types, vec![ty; 2], "{name}");
                    assert_eq!(b.num_nodes(), nn, "{name}");
                    assert_eq!(b.node_sets.len(), 2, "{name}");
                    assert_eq!(b.node_sets["block"], (0..nn).collect::<Vec<_>>(), "{name}");
                    assert_eq!(b.node_sets["bottom"].len(), bottom, "{name}");
                    on("bottom", &|p| p[2] == 0.0);
                    assert_eq!(b.element_sets.len(), 1, "{name}");
                    assert_eq!(b.element_sets["block"], vec![0, 1], "{name}");
                }
                _ => {
                    let ty = if name == "tet4" {
                        ElementKind::Tet4
                    } else {
                        ElementKind::Tet10
                    };
                    assert!(b.num_elements() > 5, "{name}");
                    assert!(b.element_types.iter().all(|&t| t == ty), "{name}");
                    let names: Vec<&str> = b.node_sets.keys().map(String::as_str).collect();
                    assert_eq!(
                        names,
                        ["PHYSICAL_1D_3", "PHYSICAL_2D_3", "body", "fixed"],
                        "{name}"
                    );
                    on("fixed", &|p| p[0] == 0.0);
                    on("PHYSICAL_2D_3", &|p| p[0] == 1.0);
                    on("PHYSICAL_1D_3", &|p| p[0] == 1.0 && p[1] == 0.0);
                    assert_eq!(b.node_sets["body"].len(), b.num_nodes(), "{name}");
                    assert_eq!(
                        b.element_sets["body"],
                        (0..b.num_elements()).collect::<Vec<_>>(),
                        "{name}"
                    );
                }
            }
        }
    }

    #[test]
    fn read_msh_and_read_mesh_read_binary_files() {
        let (name, _, binary) = FIXTURES[1];
        let path = std::env::temp_dir().join(format!(
            "fmu-builder-msh-test-{}-{name}.bin.msh",
            std::process::id()
        ));
        std::fs::write(&path, binary).unwrap();
        let by_read_msh = read_msh(&path);
        let by_read_mesh = super::super::read_mesh(&path);
        std::fs::remove_file(&path).unwrap();
        let expected = parse_fixture(name, binary);
        assert_eq!(by_read_msh.unwrap(), expected);
        assert_eq!(by_read_mesh.unwrap(), expected);
    }

    /// Builds binary files by hand.
    #[derive(Default)]
    struct W {
        b: Vec<u8>,
        /// Offset recorded by [`W::mark`].
        mark: usize,
    }

    impl W {
        fn s(&mut self, s: &str) -> &mut Self {
            self.b.extend_from_slice(s.as_bytes());
            self
        }
        fn raw(&mut self, b: &[u8]) -> &mut Self {
            self.b.extend_from_slice(b);
            self
        }
        fn i(&mut self, v: i32) -> &mut Self {
            self.raw(&v.to_le_bytes())
        }
        fn z(&mut self, v: u64) -> &mut Self {
            self.raw(&v.to_le_bytes())
        }
        fn d(&mut self, v: f64) -> &mut Self {
            self.raw(&v.to_le_bytes())
        }
        fn ds(&mut self, v: &[f64]) -> &mut Self {
            for &x in v {
                self.d(x);
            }
            self
        }
        fn mark(&mut self) -> &mut Self {
            self.mark = self.b.len();
            self
        }
    }

    /// Defects [`cube_bin`] can build in.
    #[derive(Debug, Clone, Copy, PartialEq, Eq)]
    enum Defect {
        None,
        DuplicateNodeTag,
        NodeCount,
        NanCoordinate,
        UndefinedNode,
        UnknownType,
        Prism,
    }

    /// [`CUBE`] as a binary file, plus an unknown section with binary
    /// content; returns the file and the offset of the defect.
    fn cube_bin(defect: Defect) -> (Vec<u8>, usize) {
        let is = |d: Defect| defect == d;
        let mut w = W::default();
        w.s("$MeshFormat\n4.1 1 8\n").i(1).s("\n$EndMeshFormat\n");
        w.s("$PhysicalNames\n2\n2 1 \"fixed\"\n3 2 \"body\"\n$EndPhysicalNames\n");
        w.s("$Entities\n").z(0).z(0).z(2).z(1);
        for (tag, bbox, phys) in [
            (1, [0., 0., 0., 1., 1., 0.], 1),
            (2, [0., 0., 1., 1., 1., 1.], 3),
        ] {
            w.i(tag);
            w.ds(&bbox);
            w.z(1).i(phys).z(0);
        }
        w.i(1);
        w.ds(&[0., 0., 0., 1., 1., 1.]);
        w.z(1).i(2).z(2).i(1).i(-2);
        w.s("\n$EndEntities\n");

        w.s("$Nodes\n");
        if is(Defect::NodeCount) {
            w.mark();
        }
        w.z(2)
            .z(if is(Defect::NodeCount) { 9 } else { 8 })
            .z(1)
            .z(8);
        w.i(3).i(1).i(0).z(4);
        for tag in 1..=4 {
            if tag == 4 && is(Defect::DuplicateNodeTag) {
                w.mark().z(3);
            } else {
                w.z(tag);
            }
        }
        for (k, p) in [[0., 0., 0.], [1., 0., 0.], [1., 1., 0.], [0., 1., 0.]]
            .into_iter()
            .enumerate()
        {
            if k == 2 && is(Defect::NanCoordinate) {
                w.mark().d(p[0]).d(f64::NAN).d(p[2]);
            } else {
                w.ds(&p);
            }
        }
        // surface 2, parametric: x y z u v
        w.i(2).i(2).i(1).z(4);
        for tag in 5..=8 {
            w.z(tag);
        }
        for p in [
            [0., 0., 1., 0., 0.],
            [1., 0., 1., 1., 0.],
            [1., 1., 1., 1., 1.],
            [0., 1., 1., 0., 1.],
        ] {
            w.ds(&p);
        }
        w.s("\n$EndNodes\n$Comments\nanything $here\n$EndComments\n");
        // Binary junk with a newline, a '$' and a look-alike end marker.
        w.s("$Junk\n")
            .raw(&[0, b'\n', b'$', 0xff, 0xfe])
            .s("\n$EndJunkX\n");
        w.z(u64::MAX).s("\n$EndJunk\n");

        w.s("$Elements\n").z(3).z(4).z(1).z(5);
        w.i(2).i(1).i(3).z(1);
        w.z(1).z(1).z(2).z(3).z(4);
        if is(Defect::UnknownType) {
            w.mark();
        }
        w.i(2)
            .i(2)
            .i(if is(Defect::UnknownType) { 99 } else { 2 })
            .z(2);
        w.z(2).z(5).z(6).z(7);
        w.z(3).z(6).z(7);
        if is(Defect::UndefinedNode) {
            w.mark().z(9);
        } else {
            w.z(8);
        }
        if is(Defect::Prism) {
            w.mark();
        }
        w.i(3).i(1).i(if is(Defect::Prism) { 6 } else { 5 }).z(1);
        w.z(5);
        for n in 1..=8 {
            w.z(n);
        }
        w.s("\n$EndElements\n");
        (w.b, w.mark)
    }

    #[test]
    fn hand_made_binary_cube_equals_the_ascii_cube() {
        let (bin, _) = cube_bin(Defect::None);
        let ascii = parse_msh(CUBE, Path::new("cube.msh")).unwrap();
        assert_eq!(parse_msh_bytes(&bin, Path::new("cube.msh")).unwrap(), ascii);
        // and the ASCII text through the bytes entry point
        assert_eq!(
            parse_msh_bytes(CUBE.as_bytes(), Path::new("cube.msh")).unwrap(),
            ascii
        );
    }

    /// Parses a defective binary file; the error must name the byte.
    fn check_bin(bytes: &[u8], byte: usize, parts: &[&str]) {
        let e = parse_msh_bytes(bytes, Path::new("bad.msh")).unwrap_err();
        assert_eq!(e.line, 0, "{e}");
        assert!(
            e.to_string()
                .starts_with(&format!("bad.msh: byte {byte}: ")),
            "wrong location: {e}"
        );
        for p in parts {
            assert!(e.message.contains(p), "message lacks '{p}': {e}");
        }
    }

    #[test]
    fn binary_errors_name_the_byte() {
        let (_, first_tag3) = {
            // offset of node tag 3 in the intact file: 8 bytes before tag 4
            let (_, dup) = cube_bin(Defect::DuplicateNodeTag);
            ((), dup - 8)
        };
        let cases = [
            (
                Defect::DuplicateNodeTag,
                vec![format!("duplicate node tag 3 (first at byte {first_tag3})")],
            ),
            (
                Defect::NodeCount,
                vec!["announces 9 nodes but the blocks contain 8".to_string()],
            ),
            (
                Defect::NanCoordinate,
                vec!["coordinates of node 3: NaN is not a finite number".to_string()],
            ),
            (
                Defect::UndefinedNode,
                vec!["element 3 references undefined node 9".to_string()],
            ),
            (
                Defect::UnknownType,
                vec!["unknown element type 99 in a 2D block".to_string()],
            ),
            (
                Defect::Prism,
                vec!["unsupported 3D element type 6 (prism6)".to_string()],
            ),
        ];
        for (defect, parts) in cases {
            let (bin, at) = cube_bin(defect);
            let parts: Vec<&str> = parts.iter().map(String::as_str).collect();
            check_bin(&bin, at, &parts);
        }

        let (good, _) = cube_bin(Defect::None);
        let replaced = |from: &[u8], to: &[u8]| -> Vec<u8> {
            let i = good
                .windows(from.len())
                .position(|w| w == from)
                .expect("pattern in the file");
            [&good[..i], to, &good[i + from.len()..]].concat()
        };
        // $MeshFormat: version, data size, endianness check
        check_bin(
            &replaced(b"4.1 1 8", b"4.1 1 4"),
            12,
            &["data-size 4 not supported", "only 8"],
        );
        check_bin(&replaced(b"4.1 1 8", b"2.2 1 8"), 12, &["version 2.2"]);
        check_bin(
            &replaced(b"8\n\x01\0\0\0", b"8\n\0\0\0\x01"),
            20,
            &["byte-swapped", "big-endian"],
        );
        check_bin(
            &replaced(b"8\n\x01\0\0\0", b"8\n\x02\0\0\0"),
            20,
            &["endianness check", "[02, 00, 00, 00]"],
        );
        // section footers
        let at = good.windows(10).position(|w| w == b"$EndNodes\n").unwrap();
        check_bin(
            &replaced(b"$EndNodes\n", b"$EndNodez\n"),
            at,
            &["expected $EndNodes, found '$EndNodez'"],
        );
        let at = good.windows(6).position(|w| w == b"$Junk\n").unwrap();
        check_bin(
            &replaced(b"$EndJunk\n", b"$EndJunq\n"),
            at,
            &["section $Junk is not terminated by $EndJunk"],
        );
        // the ASCII text entry point refuses binary content clearly
        let text = String::from_utf8_lossy(&good);
        let e = parse_msh(&text, Path::new("bad.msh")).unwrap_err();
        assert_eq!(e.line, 2);
        assert!(e.message.contains("read_msh / parse_msh_bytes"), "{e}");
    }

    #[test]
    fn truncated_binary_files_are_errors_not_panics() {
        let (cube, _) = cube_bin(Defect::None);
        let files = FIXTURES
            .iter()
            .map(|&(name, _, bin)| (name, bin))
            .chain([("cube", &cube[..])]);
        for (name, bin) in files {
            let path = Path::new("cut.msh");
            let full = parse_msh_bytes(bin, path).unwrap();
            for len in 0..bin.len() - 1 {
                if let Ok(m) = parse_msh_bytes(&bin[..len], path) {
                    panic!(
                        "{name}: the first {len} of {} bytes parse ({} nodes)",
                        bin.len(),
                        m.num_nodes()
                    );
                }
            }
            // Only the final newline missing: the file is complete.
            assert_eq!(parse_msh_bytes(&bin[..bin.len() - 1], path).unwrap(), full);
        }

        // Cuts inside the binary sections name the section and the byte.
        let (_, _, bin) = FIXTURES[3];
        for (section, into, what) in [
            ("Entities", 3, "the number of 0D entities"),
            // header: 4 size_t; block header: 3 int + 1 size_t; then tags
            ("Nodes", 32 + 20 + 3, "node tag"),
            ("Elements", 32 + 20 + 8 + 3, "element node tag"),
        ] {
            let header = format!("${section}\n");
            let start = bin
                .windows(header.len())
                .position(|w| w == header.as_bytes())
                .unwrap()
                + header.len();
            let cut = start + into;
            let e = parse_msh_bytes(&bin[..cut], Path::new("cut.msh")).unwrap_err();
            assert_eq!(e.line, 0);
            let msg = e.to_string();
            assert!(
                msg.starts_with("cut.msh: byte ")
                    && msg.contains(&format!(
                        "unexpected end of file in ${section}: expected {what}"
                    )),
                "{msg}"
            );
        }
    }
}
