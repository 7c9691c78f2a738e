//! Mesh importers: Abaqus/CalculiX input decks (`.inp`) and Gmsh MSH 4.1
//! files, ASCII or binary (`.msh`).
//!
//! Both importers produce an [`ImportedMesh`] with dense, 0-based node and
//! element numbering, element connectivity in the CalculiX/Abaqus node order
//! of the element type, named node/element sets and (for `.inp`) materials
//! and solid sections. Every error carries the file and line it refers to.

use std::collections::BTreeMap;
use std::fmt;
use std::path::{Path, PathBuf};

#[cfg(test)]
mod bracket_example;
pub mod inp;
pub mod matrices;
pub mod msh;

pub use inp::{parse_inp, read_inp};
pub use msh::{parse_msh, read_msh};

/// Supported solid element types (CalculiX/Abaqus names).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum ElementType {
    /// 4-node linear tetrahedron.
    C3D4,
    /// 10-node quadratic tetrahedron.
    C3D10,
    /// 8-node linear hexahedron.
    C3D8,
    /// 20-node quadratic hexahedron.
    C3D20,
    /// 20-node quadratic hexahedron, reduced integration.
    C3D20R,
}

/// Corner pairs of the C3D10 midside nodes 5..10 (0-based positions 4..9).
const C3D10_EDGES: [(usize, usize); 6] = [(0, 1), (1, 2), (2, 0), (0, 3), (1, 3), (2, 3)];

/// Corner pairs of the C3D20 midside nodes 9..20 (0-based positions 8..19).
const C3D20_EDGES: [(usize, usize); 12] = [
    (0, 1),
    (1, 2),
    (2, 3),
    (3, 0),
    (4, 5),
    (5, 6),
    (6, 7),
    (7, 4),
    (0, 4),
    (1, 5),
    (2, 6),
    (3, 7),
];

impl ElementType {
    /// All supported types.
    pub const ALL: [ElementType; 5] = [
        ElementType::C3D4,
        ElementType::C3D10,
        ElementType::C3D8,
        ElementType::C3D20,
        ElementType::C3D20R,
    ];

    /// Number of nodes of the element.
    pub fn nodes(self) -> usize {
        match self {
            ElementType::C3D4 => 4,
            ElementType::C3D10 => 10,
            ElementType::C3D8 => 8,
            ElementType::C3D20 | ElementType::C3D20R => 20,
        }
    }

    /// Number of corner (vertex) nodes; the remaining nodes are midside nodes.
    pub fn corner_nodes(self) -> usize {
        match self {
            ElementType::C3D4 | ElementType::C3D10 => 4,
            ElementType::C3D8 | ElementType::C3D20 | ElementType::C3D20R => 8,
        }
    }

    /// For each midside node (in connectivity order, after the corners), the
    /// two 0-based corner positions of the edge it sits on. Empty for linear
    /// elements.
    pub fn midside_edges(self) -> &'static [(usize, usize)] {
        match self {
            ElementType::C3D4 | ElementType::C3D8 => &[],
            ElementType::C3D10 => &C3D10_EDGES,
            ElementType::C3D20 | ElementType::C3D20R => &C3D20_EDGES,
        }
    }

    /// Parses an Abaqus element type name (case-insensitive).
    pub fn from_abaqus_name(name: &str) -> Option<Self> {
        let name = name.trim();
        Self::ALL
            .into_iter()
            .find(|t| t.abaqus_name().eq_ignore_ascii_case(name))
    }

    /// The Abaqus/CalculiX name of the type.
    pub fn abaqus_name(self) -> &'static str {
        match self {
            ElementType::C3D4 => "C3D4",
            ElementType::C3D10 => "C3D10",
            ElementType::C3D8 => "C3D8",
            ElementType::C3D20 => "C3D20",
            ElementType::C3D20R => "C3D20R",
        }
    }

    /// Comma-separated list of the supported type names (for error messages).
    pub fn supported_names() -> String {
        Self::ALL.map(|t| t.abaqus_name()).join(", ")
    }
}

impl fmt::Display for ElementType {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.abaqus_name())
    }
}

/// A material as read from the mesh file (only what a linear elastic
/// isotropic model needs). Missing properties are `None`.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ImportedMaterial {
    pub name: String,
    pub e: Option<f64>,
    pub nu: Option<f64>,
    pub rho: Option<f64>,
}

/// An imported solid mesh.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ImportedMesh {
    /// Node coordinates, dense and 0-based (file order).
    pub nodes: Vec<[f64; 3]>,
    /// File id (label / tag) of each node, same order as `nodes`.
    pub node_ids: Vec<u64>,
    /// Type of each element.
    pub element_types: Vec<ElementType>,
    /// 0-based node indices of each element, in the CalculiX/Abaqus node
    /// order of its type.
    pub connectivity: Vec<Vec<usize>>,
    /// File id of each element, same order as `connectivity`.
    pub element_ids: Vec<u64>,
    /// Node sets: name -> sorted, de-duplicated 0-based node indices.
    /// `.inp` names are upper-cased; `.msh` names are the physical names
    /// as written (or `PHYSICAL_<tag>` for unnamed groups).
    pub node_sets: BTreeMap<String, Vec<usize>>,
    /// Element sets: name -> sorted, de-duplicated 0-based element indices.
    pub element_sets: BTreeMap<String, Vec<usize>>,
    pub materials: Vec<ImportedMaterial>,
    /// Solid sections as (element set name, material name), both upper-cased.
    pub sections: Vec<(String, String)>,
}

impl ImportedMesh {
    pub fn num_nodes(&self) -> usize {
        self.nodes.len()
    }

    pub fn num_elements(&self) -> usize {
        self.connectivity.len()
    }

    /// Looks up a material by (case-insensitive) name.
    pub fn material(&self, name: &str) -> Option<&ImportedMaterial> {
        self.materials
            .iter()
            .find(|m| m.name.eq_ignore_ascii_case(name))
    }
}

/// An import error located in a file. `line` is 1-based; 0 means the error
/// concerns the file as a whole (e.g. it cannot be read).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ImportError {
    pub file: PathBuf,
    pub line: usize,
    pub message: String,
}

impl ImportError {
    pub fn new(file: impl Into<PathBuf>, line: usize, message: impl Into<String>) -> Self {
        ImportError {
            file: file.into(),
            line,
            message: message.into(),
        }
    }
}

impl fmt::Display for ImportError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.line > 0 {
            write!(f, "{}:{}: {}", self.file.display(), self.line, self.message)
        } else {
            write!(f, "{}: {}", self.file.display(), self.message)
        }
    }
}

impl std::error::Error for ImportError {}

/// Reads a mesh, choosing the importer from the file extension
/// (`.inp` -> [`read_inp`], `.msh` -> [`read_msh`]; case-insensitive).
pub fn read_mesh(path: &Path) -> Result<ImportedMesh, ImportError> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase());
    match ext.as_deref() {
        Some("inp") => read_inp(path),
        Some("msh") => read_msh(path),
        _ => Err(ImportError::new(
            path,
            0,
            "unknown mesh file extension (expected .inp or .msh)",
        )),
    }
}

/// Reads a file as text (invalid UTF-8 is replaced, which only matters in
/// comments). Errors are reported against the file itself (line 0).
pub(crate) fn read_text(path: &Path) -> Result<String, ImportError> {
    let bytes = std::fs::read(path)
        .map_err(|e| ImportError::new(path, 0, format!("cannot read file: {e}")))?;
    Ok(match String::from_utf8(bytes) {
        Ok(s) => s,
        Err(e) => String::from_utf8_lossy(e.as_bytes()).into_owned(),
    })
}

#[cfg(test)]
pub(crate) mod test_util {
    use super::ImportedMesh;

    /// Asserts that every midside node of every element lies at the midpoint
    /// of the two corners its position implies in the Abaqus/CalculiX order.
    pub fn assert_midsides_at_midpoints(mesh: &ImportedMesh) {
        for (e, (ty, conn)) in mesh
            .element_types
            .iter()
            .zip(&mesh.connectivity)
            .enumerate()
        {
            assert_eq!(conn.len(), ty.nodes());
            for (k, &(a, b)) in ty.midside_edges().iter().enumerate() {
                let m = mesh.nodes[conn[ty.corner_nodes() + k]];
                let pa = mesh.nodes[conn[a]];
                let pb = mesh.nodes[conn[b]];
                for d in 0..3 {
                    assert!(
                        (m[d] - 0.5 * (pa[d] + pb[d])).abs() < 1e-12,
                        "element {e} ({ty}): midside position {} is not between corners {a} and {b}",
                        ty.corner_nodes() + k
                    );
                }
            }
        }
    }
}
