//! Mesh importers: Abaqus/CalculiX input decks (`.inp`) and Gmsh MSH 4.1
//! files, ASCII or binary (`.msh`).
//!
//! Both importers produce an [`ImportedMesh`] with dense, 0-based node and
//! element numbering, element connectivity in the CalculiX/Abaqus node order
//! of the element kind (see [`crate::element`]), named node/element sets and (for `.inp`) materials
//! and solid sections. Every error carries the file and line it refers to.

use crate::element::ElementKind;
use crate::error::Cause;
use crate::file_read::FileKind;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

#[cfg(test)]
mod bracket_example;
pub mod inp;
pub mod matrices;
pub mod msh;

pub use inp::{parse_inp, read_inp};
pub use msh::{parse_msh, read_msh};

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
    /// Kind of each element.
    pub element_types: Vec<ElementKind>,
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
    /// What the importer left out and the user should know (surface and line elements of a
    /// deck written with Gmsh's "save all elements"), one sentence each.
    pub notes: Vec<String>,
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
        self.materials.iter().find(|m| m.name.eq_ignore_ascii_case(name))
    }
}

/// An import error located in a file. `line` is 1-based; 0 means the error
/// concerns the file as a whole (e.g. it cannot be read).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{}{}: {message}", .file.display(), line_suffix(*.line))]
pub struct ImportError {
    pub file: PathBuf,
    pub line: usize,
    pub message: String,
    /// The error the message was made from (the system's, a library's), if any.
    #[source]
    pub cause: Option<Cause>,
}

impl ImportError {
    pub fn new(file: impl Into<PathBuf>, line: usize, message: impl Into<String>) -> Self {
        ImportError { file: file.into(), line, message: message.into(), cause: None }
    }
    /// `self` keeping `cause`, the error its message was made from, as its source.
    pub fn caused_by(self, cause: impl std::error::Error + Send + Sync + 'static) -> Self {
        ImportError { cause: Some(Cause::new(cause)), ..self }
    }
}

fn line_suffix(line: usize) -> String {
    if line > 0 { format!(":{line}") } else { String::new() }
}

/// Reads a mesh, choosing the importer from the file extension
/// (`.inp` -> [`read_inp`], `.msh` -> [`read_msh`]; case-insensitive).
pub fn read_mesh(path: &Path) -> Result<ImportedMesh, ImportError> {
    let ext = path.extension().and_then(|e| e.to_str()).map(|e| e.to_ascii_lowercase());
    match ext.as_deref() {
        Some("inp") => read_inp(path),
        Some("msh") => read_msh(path),
        _ => Err(ImportError::new(path, 0, "unknown mesh file extension (expected .inp or .msh)")),
    }
}

/// Reads a file as text (invalid UTF-8 is replaced, which only matters in
/// comments). Errors are reported against the file itself (line 0).
pub(crate) fn read_text(path: &Path) -> Result<String, ImportError> {
    read_text_of_kind(path, FileKind::Mesh)
}

/// `read_text` with the size limit of `kind` (matrices may be larger than meshes).
pub(crate) fn read_text_of_kind(path: &Path, kind: FileKind) -> Result<String, ImportError> {
    crate::file_read::read_text(path, kind, crate::size::Memory::of_this_machine().bytes)
        .map_err(|e| ImportError::new(path, 0, format!("cannot read the file: it {e}")).caused_by(e))
}

#[cfg(test)]
pub(crate) mod test_util {
    use super::ImportedMesh;

    /// Asserts that every midside node of every element lies at the midpoint
    /// of the two corners its position implies in the Abaqus/CalculiX order.
    pub fn assert_midsides_at_midpoints(mesh: &ImportedMesh) {
        for (e, (ty, conn)) in mesh.element_types.iter().zip(&mesh.connectivity).enumerate() {
            assert_eq!(conn.len(), ty.nodes_per_element());
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
