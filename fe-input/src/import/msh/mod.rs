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

mod ascii;
mod binary;
mod builder;

pub use ascii::parse_msh;
pub use builder::{HEX20_GMSH_TO_ABAQUS, TET10_GMSH_TO_ABAQUS};

use super::{ImportError, ImportedMesh};
use binary::{is_binary, parse_binary};
use std::fmt;
use std::path::Path;

/// Reads a Gmsh MSH 4.1 file, ASCII or binary.
pub fn read_msh(path: &Path) -> Result<ImportedMesh, ImportError> {
    use crate::file_read::{self, FileKind};
    let bytes = file_read::read(path, FileKind::Mesh, crate::size::Memory::of_this_machine().bytes)
        .map_err(|e| ImportError::new(path, 0, format!("cannot read the file: it {e}")).caused_by(e))?;
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

/// The tokens of a line as exactly `count` integers.
fn ints_of(path: &Path, loc: Loc, t: &[&str], count: usize, what: &str) -> Res<Vec<i64>> {
    if t.len() != count {
        return Err(error(path, loc, format!("{what}: expected {count} values, got {}", t.len())));
    }
    t.iter().map(|s| int_at(path, loc, s, what)).collect()
}

fn int_at(path: &Path, loc: Loc, s: &str, what: &str) -> Res<i64> {
    s.parse::<i64>().map_err(|_| error(path, loc, format!("malformed integer '{s}' in {what}")))
}

fn count_at(path: &Path, loc: Loc, v: i64, what: &str) -> Res<usize> {
    usize::try_from(v).map_err(|_| error(path, loc, format!("negative {what} {v}")))
}

/// A `$PhysicalNames` line `dim tag "name"` (ASCII in both encodings).
fn physical_name(path: &Path, loc: Loc, l: &str) -> Res<((i64, i64), String)> {
    let mut it = l.splitn(2, char::is_whitespace);
    let dim = int_at(path, loc, it.next().unwrap_or(""), "physical name dimension")?;
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

#[cfg(test)]
mod test_data {
    /// Unit cube as one hex8 in volume 1 ("body"), with a named physical
    /// surface on z = 0 ("fixed") and an unnamed physical surface (tag 3)
    /// on z = 1 whose nodes carry parametric coordinates.
    pub(super) const CUBE: &str = r#"$MeshFormat
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

    /// (name, ASCII export, binary export) of one Gmsh model each, written
    /// by `testdata/make_fixtures.py` (Gmsh 4.15.2).
    pub(super) const FIXTURES: [(&str, &[u8], &[u8]); 4] = [
        ("hex8", include_bytes!("testdata/hex8.msh"), include_bytes!("testdata/hex8.bin.msh")),
        ("hex20", include_bytes!("testdata/hex20.msh"), include_bytes!("testdata/hex20.bin.msh")),
        ("tet4", include_bytes!("testdata/tet4.msh"), include_bytes!("testdata/tet4.bin.msh")),
        ("tet10", include_bytes!("testdata/tet10.msh"), include_bytes!("testdata/tet10.bin.msh")),
    ];
}

#[cfg(test)]
mod tests {
    use super::test_data::FIXTURES;
    use super::*;
    use crate::element::ElementKind;

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
        let without_coordinates = |m: &ImportedMesh| ImportedMesh { nodes: Vec::new(), ..m.clone() };
        assert_eq!(without_coordinates(ascii), without_coordinates(binary), "{what}");
    }

    fn parse_fixture(name: &str, bytes: &[u8]) -> ImportedMesh {
        parse_msh_bytes(bytes, Path::new(name)).unwrap_or_else(|e| panic!("{e}"))
    }

    #[test]
    fn binary_fixtures_equal_their_ascii_twins() {
        for (name, ascii, binary) in FIXTURES {
            assert!(ascii.starts_with(b"$MeshFormat\n4.1 0 8\n"), "{name}");
            assert!(binary.starts_with(b"$MeshFormat\n4.1 1 8\n\x01\0\0\0\n"), "{name}");
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
                        assert!((m[d] - 0.5 * (p[d] + q[d])).abs() < 1e-9, "{name}: {ty} edge {i}-{j}");
                    }
                }
            }
            // every node set point is where its group says
            let on = |set: &str, pred: &dyn Fn([f64; 3]) -> bool| {
                let s = &b.node_sets[set];
                assert!(!s.is_empty(), "{name}: {set} is empty");
                for &n in s {
                    assert!(pred(b.nodes[n]), "{name}: node {n} of {set} at {:?}", b.nodes[n]);
                }
            };
            match name {
                "hex8" | "hex20" => {
                    let (ty, nn, bottom) =
                        if name == "hex8" { (ElementKind::Hex8, 12, 6) } else { (ElementKind::Hex20, 32, 13) };
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
                    let ty = if name == "tet4" { ElementKind::Tet4 } else { ElementKind::Tet10 };
                    assert!(b.num_elements() > 5, "{name}");
                    assert!(b.element_types.iter().all(|&t| t == ty), "{name}");
                    let names: Vec<&str> = b.node_sets.keys().map(String::as_str).collect();
                    assert_eq!(names, ["PHYSICAL_1D_3", "PHYSICAL_2D_3", "body", "fixed"], "{name}");
                    on("fixed", &|p| p[0] == 0.0);
                    on("PHYSICAL_2D_3", &|p| p[0] == 1.0);
                    on("PHYSICAL_1D_3", &|p| p[0] == 1.0 && p[1] == 0.0);
                    assert_eq!(b.node_sets["body"].len(), b.num_nodes(), "{name}");
                    assert_eq!(b.element_sets["body"], (0..b.num_elements()).collect::<Vec<_>>(), "{name}");
                }
            }
        }
    }

    #[test]
    fn read_msh_and_read_mesh_read_binary_files() {
        let (name, _, binary) = FIXTURES[1];
        let path = std::env::temp_dir().join(format!("fmu-builder-msh-test-{}-{name}.bin.msh", std::process::id()));
        std::fs::write(&path, binary).unwrap();
        let by_read_msh = read_msh(&path);
        let by_read_mesh = super::super::read_mesh(&path);
        std::fs::remove_file(&path).unwrap();
        let expected = parse_fixture(name, binary);
        assert_eq!(by_read_msh.unwrap(), expected);
        assert_eq!(by_read_mesh.unwrap(), expected);
    }
}
