//! The mesh of a MSH 4.1 file, independent of its encoding: Gmsh element
//! types, their conversion to the CalculiX node order, and the node and
//! element sets of the physical groups.

use super::{Loc, Res, error};
use crate::element::ElementKind;
use crate::import::{ImportError, ImportedMesh};
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

/// The mesh a MSH 4.1 file defines, independent of its encoding: the ASCII
/// and the binary reader feed it in file order and it makes the checks
/// that do not depend on the encoding, so both give the same
/// [`ImportedMesh`] and the same messages.
pub(super) struct MeshBuilder<'p> {
    path: &'p Path,
    pub(super) physical_names: BTreeMap<(i64, i64), String>,
    pub(super) have_entities: bool,
    /// (dim, entity tag) -> physical tags
    pub(super) entity_physicals: HashMap<(i64, i64), Vec<i64>>,
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
pub(super) struct ElementBlock {
    dim: i64,
    etag: i64,
    pub(super) etype: i64,
    /// (name, number of nodes, dimension) if the type is known.
    pub(super) info: Option<(&'static str, usize, u8)>,
    /// Element type and Gmsh -> CalculiX node permutation of a 3D block.
    conv: Option<(ElementKind, &'static [usize])>,
}

impl<'p> MeshBuilder<'p> {
    pub(super) fn new(path: &'p Path) -> Self {
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

    pub(super) fn err(&self, loc: Loc, msg: impl Into<String>) -> ImportError {
        error(self.path, loc, msg)
    }

    pub(super) fn begin_nodes(&mut self, loc: Loc) -> Res<()> {
        if self.have_nodes {
            return Err(self.err(loc, "more than one $Nodes section"));
        }
        self.have_nodes = true;
        Ok(())
    }

    /// Registers the tag of the next node; its coordinates follow (after
    /// the other tags of its block) with [`Self::push_node`].
    pub(super) fn node_tag(&mut self, loc: Loc, tag: u64) -> Res<()> {
        if let Some(&first) = self.node_index.get(&tag) {
            let first = self.node_loc.get(first).copied().unwrap_or(loc);
            return Err(self.err(loc, format!("duplicate node tag {tag} (first at {first})")));
        }
        self.node_index.insert(tag, self.node_loc.len());
        self.node_loc.push(loc);
        Ok(())
    }

    pub(super) fn push_node(&mut self, tag: u64, x: [f64; 3]) {
        self.mesh.nodes.push(x);
        self.mesh.node_ids.push(tag);
    }

    pub(super) fn end_nodes(&self, header: Loc, total: usize) -> Res<()> {
        if self.mesh.nodes.len() != total {
            return Err(self.err(
                header,
                format!("$Nodes header announces {total} nodes but the blocks contain {}", self.mesh.nodes.len()),
            ));
        }
        Ok(())
    }

    pub(super) fn begin_elements(&mut self, loc: Loc) -> Res<()> {
        if !self.have_nodes {
            return Err(self.err(loc, "$Elements before $Nodes"));
        }
        if self.have_elements {
            return Err(self.err(loc, "more than one $Elements section"));
        }
        self.have_elements = true;
        Ok(())
    }

    pub(super) fn element_block(&mut self, loc: Loc, dim: i64, etag: i64, etype: i64) -> Res<ElementBlock> {
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
            return Err(self.err(loc, format!("element type {etype} ({name}) in a {dim}D entity block")));
        }
        // An empty block of a physical entity still makes its (empty) set.
        self.entity_nodes.entry((dim, etag)).or_default();
        Ok(ElementBlock { dim, etag, etype, info, conv })
    }

    pub(super) fn element_tag(&mut self, loc: Loc, tag: u64) -> Res<()> {
        if let Some(first) = self.element_loc.insert(tag, loc) {
            return Err(self.err(loc, format!("duplicate element tag {tag} (first at {first})")));
        }
        Ok(())
    }

    /// Index of node `id` referenced by element `element`.
    pub(super) fn node_ref<T: Copy + fmt::Display>(&self, loc: Loc, element: u64, id: T) -> Res<usize>
    where
        u64: TryFrom<T>,
    {
        u64::try_from(id)
            .ok()
            .and_then(|id| self.node_index.get(&id).copied())
            .ok_or_else(|| self.err(loc, format!("element {element} references undefined node {id}")))
    }

    /// Adds an element of `block`; `nodes` (indices, Gmsh order) has the
    /// node count of the block's type whenever the type is known.
    pub(super) fn push_element(&mut self, block: &ElementBlock, tag: u64, nodes: Vec<usize>) {
        self.entity_nodes.entry((block.dim, block.etag)).or_default().extend(nodes.iter().copied());
        if let Some((ty, perm)) = block.conv {
            self.volume_elements.entry(block.etag).or_default().push(self.mesh.connectivity.len());
            // A 3D block has a known type, so `nodes` has `perm.len()` entries.
            self.mesh.connectivity.push(perm.iter().map(|&k| nodes[k]).collect());
            self.mesh.element_types.push(ty);
            self.mesh.element_ids.push(tag);
        }
    }

    pub(super) fn end_elements(&self, header: Loc, total: usize, seen: usize) -> Res<()> {
        if seen != total {
            return Err(
                self.err(header, format!("$Elements header announces {total} elements but the blocks contain {seen}"))
            );
        }
        Ok(())
    }

    /// Final checks and the node/element sets of the physical groups;
    /// `end` locates errors about the file as a whole.
    pub(super) fn finish(self, end: Loc) -> Res<ImportedMesh> {
        if !self.have_nodes || !self.have_elements {
            return Err(self.err(end, "missing $Nodes or $Elements section"));
        }
        if !self.have_entities && !self.physical_names.is_empty() {
            return Err(self.err(end, "$PhysicalNames present but no $Entities section: cannot map physical groups"));
        }
        let MeshBuilder { physical_names, entity_physicals, mut mesh, entity_nodes, volume_elements, .. } = self;

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
            for &p in entity_physicals.get(&(dim, etag)).map(Vec::as_slice).unwrap_or(&[]) {
                group_nodes.entry((dim, p)).or_default().extend(nodes.iter().copied());
                if dim == 3 {
                    let els = volume_elements.get(&etag).map(Vec::as_slice).unwrap_or(&[]);
                    group_elements.entry(p).or_default().extend(els.iter().copied());
                }
            }
        }
        let group_name = |dim: i64, tag: i64| -> String {
            if let Some(name) = physical_names.get(&(dim, tag)) {
                return name.clone();
            }
            let shared =
                group_nodes.keys().any(|&(d, t)| t == tag && d != dim && !physical_names.contains_key(&(d, t)));
            if shared { format!("PHYSICAL_{dim}D_{tag}") } else { format!("PHYSICAL_{tag}") }
        };
        for (&(dim, tag), nodes) in &group_nodes {
            mesh.node_sets.entry(group_name(dim, tag)).or_default().extend(nodes.iter().copied());
        }
        for (&tag, els) in &group_elements {
            mesh.element_sets.entry(group_name(3, tag)).or_default().extend(els.iter().copied());
        }
        for v in mesh.node_sets.values_mut().chain(mesh.element_sets.values_mut()) {
            v.sort_unstable();
            v.dedup();
        }
        Ok(mesh)
    }
}

#[cfg(test)]
mod tests {
    use super::super::parse_msh;
    use super::*;
    use crate::import::test_util::assert_midsides_at_midpoints;

    /// Builds a one-element .msh whose midside nodes are placed at the
    /// midpoints of the Gmsh edges (per the Gmsh "Node ordering" docs).
    fn single_element_msh(gmsh_type: i64, corners: &[[f64; 3]], gmsh_edges: &[(usize, usize)]) -> String {
        let mut pts: Vec<[f64; 3]> = corners.to_vec();
        for &(a, b) in gmsh_edges {
            pts.push([0, 1, 2].map(|d| 0.5 * (corners[a][d] + corners[b][d])));
        }
        let n = pts.len();
        let mut s = format!("$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 {n} 1 {n}\n3 1 0 {n}\n");
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
        let corners = [[0.1, 0.0, 0.0], [2.0, 0.3, 0.0], [0.2, 3.0, 0.1], [0.3, 0.1, 5.0]];
        // Gmsh Tetrahedron10: 4: 0-1, 5: 1-2, 6: 2-0, 7: 0-3, 8: 2-3, 9: 1-3
        let gmsh_edges = [(0, 1), (1, 2), (2, 0), (0, 3), (2, 3), (1, 3)];
        let m = parse_msh(&single_element_msh(11, &corners, &gmsh_edges), Path::new("t.msh")).unwrap();
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
        let gmsh_edges =
            [(0, 1), (0, 3), (0, 4), (1, 2), (1, 5), (2, 3), (2, 6), (3, 7), (4, 5), (4, 7), (5, 6), (6, 7)];
        let m = parse_msh(&single_element_msh(17, &corners, &gmsh_edges), Path::new("h.msh")).unwrap();
        assert_eq!(m.element_types, vec![ElementKind::Hex20]);
        assert_midsides_at_midpoints(&m);
        // corners unchanged
        for (&n, c) in m.connectivity[0].iter().zip(&corners) {
            assert_eq!(&m.nodes[n], c);
        }
    }
}
