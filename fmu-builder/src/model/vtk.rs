//! The meshed part as a legacy VTK file (ASCII unstructured grid) that ParaView and VTK read:
//! the elements, one 0/1 field per flange marking its slave nodes, and displacement fields
//! (the reduced basis' shapes, named with their frequencies) to look at mode shapes with
//! ParaView's "Warp By Vector".
//!
//! VTK's quadratic cells take CalculiX's node order as it is: corners, then the midside nodes of
//! the edges in the same order (VTK_QUADRATIC_TETRA 24, VTK_QUADRATIC_HEXAHEDRON 25); C3D20R is
//! a quadratic hexahedron too.

use crate::error::{BuildError, Result};
use crate::input::element::ElementKind;
use crate::model::flange::Flange;
use crate::model::part::Part;
use faer::MatRef;
use std::fmt::Write as _;
use std::path::Path;

fn cell_type(kind: ElementKind) -> u8 {
    match kind {
        ElementKind::Tet4 => 10,
        ElementKind::Tet10 => 24,
        ElementKind::Hex8 => 12,
        ElementKind::Hex20 | ElementKind::Hex20R => 25,
    }
}

/// Name VTK accepts for a data array: no white space.
fn array_name(name: &str) -> String {
    name.chars().map(|c| if c.is_whitespace() { '_' } else { c }).collect()
}

/// The file's text, titled `title`: the mesh, the flanges' slave sets and the `fields` (3N x k
/// mesh displacement fields, node-major rows) named by `names`.
pub fn vtk(title: &str, part: &Part, flanges: &[Flange], fields: MatRef<'_, f64>, names: &[String]) -> String {
    let mesh = &part.mesh;
    let n = mesh.n_nodes();
    let mut s = String::new();
    let _ = writeln!(
        s,
        "# vtk DataFile Version 3.0\n{} (fmu-builder)\nASCII\nDATASET UNSTRUCTURED_GRID",
        title.replace(['\n', '\r'], " ")
    );
    let _ = writeln!(s, "POINTS {n} double");
    for p in &mesh.nodes {
        let _ = writeln!(s, "{:e} {:e} {:e}", p[0], p[1], p[2]);
    }
    let ne = mesh.n_elements();
    let size: usize = (0..ne).map(|e| mesh.element(e).len() + 1).sum();
    let _ = writeln!(s, "CELLS {ne} {size}");
    for e in 0..ne {
        let conn = mesh.element(e);
        let _ = write!(s, "{}", conn.len());
        for i in conn {
            let _ = write!(s, " {i}");
        }
        s.push('\n');
    }
    let _ = writeln!(s, "CELL_TYPES {ne}");
    for e in 0..ne {
        let _ = writeln!(s, "{}", cell_type(mesh.kind(e)));
    }
    let _ = writeln!(s, "POINT_DATA {n}");
    for f in flanges {
        let mut mark = vec![0u8; n];
        for &i in &f.slaves {
            mark[i] = 1;
        }
        let _ = writeln!(s, "SCALARS flange_{} int 1\nLOOKUP_TABLE default", array_name(&f.name));
        for m in mark {
            let _ = writeln!(s, "{m}");
        }
    }
    for (j, name) in names.iter().enumerate() {
        let _ = writeln!(s, "VECTORS {} double", array_name(name));
        for i in 0..n {
            let _ = writeln!(s, "{:e} {:e} {:e}", fields[(3 * i, j)], fields[(3 * i + 1, j)], fields[(3 * i + 2, j)]);
        }
    }
    s
}

pub fn write_vtk(
    path: &Path,
    title: &str,
    part: &Part,
    flanges: &[Flange],
    fields: MatRef<'_, f64>,
    names: &[String],
    write: crate::model::export::WriteFile,
) -> Result<()> {
    if !part.has_elements() {
        return Err(BuildError::file(
            path,
            "--export-vtk needs a part with elements (this one is given by its matrices)",
        ));
    }
    write(path, vtk(title, part, flanges, fields, names).as_bytes())
}
