//! The element catalogue: what each supported solid element is, independent of
//! how its matrices are computed (that is `model::fe`).
//!
//! Every kind equals the CalculiX/Abaqus element of `calculix_name()` in its
//! node order: corners first, then the midside nodes of `midside_edges()`. The
//! spec names the kinds in lowercase (`geometry.element`: "hex8", "hex20",
//! "hex20r", "tet4", "tet10"), mesh files by their CalculiX names.

use serde::Deserialize;
use std::fmt;

/// Largest node count of any supported element; sizes the stack buffers of
/// element loops so that they never allocate.
pub const MAX_NODES_PER_ELEMENT: usize = 20;

/// Supported solid element types, each equal to the CalculiX element of
/// `calculix_name()` (node order, shape functions and integration rules).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, Deserialize, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum ElementKind {
    /// 8-node trilinear hexahedron (CalculiX C3D8).
    Hex8,
    /// 20-node quadratic serendipity hexahedron (CalculiX C3D20).
    #[default]
    Hex20,
    /// 20-node serendipity hexahedron with reduced 2x2x2 integration
    /// (CalculiX C3D20R).
    Hex20R,
    /// 4-node linear tetrahedron (CalculiX C3D4).
    Tet4,
    /// 10-node quadratic tetrahedron (CalculiX C3D10).
    Tet10,
}

/// Natural coordinates of the C3D8 nodes: nodes 1-4 counterclockwise on the
/// face zeta = -1, nodes 5-8 above them on zeta = +1.
pub const HEX8_NATURAL_COORDS: [[i8; 3]; 8] =
    [[-1, -1, -1], [1, -1, -1], [1, 1, -1], [-1, 1, -1], [-1, -1, 1], [1, -1, 1], [1, 1, 1], [-1, 1, 1]];

/// Natural coordinates of the C3D20 nodes: corners as in C3D8, then midside
/// nodes of the bottom edges (1-2, 2-3, 3-4, 4-1), of the top edges (5-6, 6-7,
/// 7-8, 8-5) and of the vertical edges (1-5, 2-6, 3-7, 4-8).
pub const HEX20_NATURAL_COORDS: [[i8; 3]; 20] = [
    [-1, -1, -1],
    [1, -1, -1],
    [1, 1, -1],
    [-1, 1, -1],
    [-1, -1, 1],
    [1, -1, 1],
    [1, 1, 1],
    [-1, 1, 1],
    [0, -1, -1],
    [1, 0, -1],
    [0, 1, -1],
    [-1, 0, -1],
    [0, -1, 1],
    [1, 0, 1],
    [0, 1, 1],
    [-1, 0, 1],
    [-1, -1, 0],
    [1, -1, 0],
    [1, 1, 0],
    [-1, 1, 0],
];

/// Corner pairs of the C3D10 midside nodes 5..10: edges 1-2, 2-3, 3-1, 1-4,
/// 2-4, 3-4 (0-based here, positions 4..9).
pub const TET10_EDGES: [(usize, usize); 6] = [(0, 1), (1, 2), (2, 0), (0, 3), (1, 3), (2, 3)];

/// Corner pairs of the C3D20 midside nodes 9..20 (0-based positions 8..19).
pub const HEX20_EDGES: [(usize, usize); 12] =
    [(0, 1), (1, 2), (2, 3), (3, 0), (4, 5), (5, 6), (6, 7), (7, 4), (0, 4), (1, 5), (2, 6), (3, 7)];

impl ElementKind {
    /// Every kind, in declaration order.
    pub const ALL: [ElementKind; 5] =
        [ElementKind::Hex8, ElementKind::Hex20, ElementKind::Hex20R, ElementKind::Tet4, ElementKind::Tet10];

    /// Number of nodes of the element.
    pub const fn nodes_per_element(self) -> usize {
        match self {
            ElementKind::Hex8 => 8,
            ElementKind::Hex20 | ElementKind::Hex20R => 20,
            ElementKind::Tet4 => 4,
            ElementKind::Tet10 => 10,
        }
    }

    /// Number of corner (vertex) nodes; the remaining nodes are midside nodes.
    pub const fn corner_nodes(self) -> usize {
        match self {
            ElementKind::Tet4 | ElementKind::Tet10 => 4,
            ElementKind::Hex8 | ElementKind::Hex20 | ElementKind::Hex20R => 8,
        }
    }

    /// The faces as cycles of corner positions (connectivity order), outward or not.
    pub const fn corner_faces(self) -> &'static [&'static [usize]] {
        match self {
            ElementKind::Tet4 | ElementKind::Tet10 => &[&[0, 1, 2], &[0, 1, 3], &[1, 2, 3], &[0, 2, 3]],
            ElementKind::Hex8 | ElementKind::Hex20 | ElementKind::Hex20R => {
                &[&[0, 1, 2, 3], &[4, 5, 6, 7], &[0, 1, 5, 4], &[1, 2, 6, 5], &[2, 3, 7, 6], &[3, 0, 4, 7]]
            }
        }
    }

    /// For each midside node (in connectivity order, after the corners), the
    /// two 0-based corner positions of the edge it sits on. Empty for linear
    /// elements.
    pub const fn midside_edges(self) -> &'static [(usize, usize)] {
        match self {
            ElementKind::Tet4 | ElementKind::Hex8 => &[],
            ElementKind::Tet10 => &TET10_EDGES,
            ElementKind::Hex20 | ElementKind::Hex20R => &HEX20_EDGES,
        }
    }

    /// The name in the spec and in reports.
    pub const fn name(self) -> &'static str {
        match self {
            ElementKind::Hex8 => "hex8",
            ElementKind::Hex20 => "hex20",
            ElementKind::Hex20R => "hex20r",
            ElementKind::Tet4 => "tet4",
            ElementKind::Tet10 => "tet10",
        }
    }

    /// The CalculiX/Abaqus element type name.
    pub const fn calculix_name(self) -> &'static str {
        match self {
            ElementKind::Hex8 => "C3D8",
            ElementKind::Hex20 => "C3D20",
            ElementKind::Hex20R => "C3D20R",
            ElementKind::Tet4 => "C3D4",
            ElementKind::Tet10 => "C3D10",
        }
    }

    /// The kind whose `calculix_name()` is `name` (surrounding blanks ignored,
    /// case-insensitive, as CalculiX reads keywords and parameters).
    pub fn from_calculix_name(name: &str) -> Option<Self> {
        let name = name.trim();
        Self::ALL.into_iter().find(|k| k.calculix_name().eq_ignore_ascii_case(name))
    }

    /// Comma-separated CalculiX names of every kind, for error messages:
    /// tetrahedra first, then hexahedra, each by node count.
    pub fn supported_names() -> String {
        use ElementKind::*;
        [Tet4, Tet10, Hex8, Hex20, Hex20R].map(|k| k.calculix_name()).join(", ")
    }

    /// Natural coordinates (each -1, 0 or +1) of the nodes of the hexahedral
    /// kinds in C3D8/C3D20 order; `None` for tetrahedra, whose nodes do not
    /// sit on that lattice. The box mesher and the hexahedra's shape functions
    /// both use this table, so connectivity and shape functions can never
    /// disagree about the node order.
    pub const fn natural_node_coords(self) -> Option<&'static [[i8; 3]]> {
        match self {
            ElementKind::Hex8 => Some(&HEX8_NATURAL_COORDS),
            ElementKind::Hex20 | ElementKind::Hex20R => Some(&HEX20_NATURAL_COORDS),
            ElementKind::Tet4 | ElementKind::Tet10 => None,
        }
    }
}

impl fmt::Display for ElementKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip() {
        for kind in ElementKind::ALL {
            assert_eq!(ElementKind::from_calculix_name(kind.calculix_name()), Some(kind));
            let lower = kind.calculix_name().to_ascii_lowercase();
            assert_eq!(ElementKind::from_calculix_name(&lower), Some(kind));
            let quoted = format!("\"{}\"", kind.name());
            assert_eq!(serde_json::from_str::<ElementKind>(&quoted).unwrap(), kind);
            assert_eq!(kind.to_string(), kind.name());
        }
        let names = ElementKind::ALL.map(|k| (k.name(), k.calculix_name()));
        assert_eq!(
            names,
            [("hex8", "C3D8"), ("hex20", "C3D20"), ("hex20r", "C3D20R"), ("tet4", "C3D4"), ("tet10", "C3D10")]
        );
        assert_eq!(ElementKind::from_calculix_name(" c3d20r "), Some(ElementKind::Hex20R));
        assert_eq!(ElementKind::from_calculix_name("C3D8R"), None);
        assert!(serde_json::from_str::<ElementKind>("\"C3D8\"").is_err());
        assert_eq!(ElementKind::default(), ElementKind::Hex20);
        assert_eq!(ElementKind::supported_names(), "C3D4, C3D10, C3D8, C3D20, C3D20R");
    }

    #[test]
    fn node_counts_corners_and_edges_agree() {
        for kind in ElementKind::ALL {
            let n = kind.nodes_per_element();
            assert!(n <= MAX_NODES_PER_ELEMENT);
            assert_eq!(kind.corner_nodes() + kind.midside_edges().len(), n, "{kind}");
            if let Some(natural) = kind.natural_node_coords() {
                assert_eq!(natural.len(), n, "{kind}");
            }
            for &(a, b) in kind.midside_edges() {
                assert!(a < kind.corner_nodes() && b < kind.corner_nodes() && a != b);
            }
        }
    }

    /// Each hex20 midside node sits halfway between the corners of its edge.
    #[test]
    fn hex20_midside_edges_match_the_natural_coordinates() {
        let natural = ElementKind::Hex20.natural_node_coords().unwrap();
        assert_eq!(&natural[..8], &HEX8_NATURAL_COORDS);
        for (k, &(a, b)) in ElementKind::Hex20.midside_edges().iter().enumerate() {
            let m = natural[8 + k];
            for d in 0..3 {
                assert_eq!(2 * m[d], natural[a][d] + natural[b][d], "midside {}", 8 + k);
            }
        }
    }
}
