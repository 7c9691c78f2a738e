//! The meshed, flanged part as an Abaqus/CalculiX input deck (model data only: nodes, elements,
//! node sets, material), so the same mesh can be analysed by CalculiX for reference results.
//! Each flange gets its slave set `<NAME>` plus a reference node (set `<NAME>_REF`) and a
//! rotation node (set `<NAME>_ROT`) at its reference point, ready for `*RIGID BODY`.

use crate::error::{BuildError, Result};
use crate::fe::ElementKind;
use crate::flange::Flange;
use crate::mesh::Mesh;
use crate::spec::Material;
use std::fmt::Write as _;
use std::path::Path;

pub fn abaqus_deck(mesh: &Mesh, flanges: &[Flange], material: &Material) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "** written by fmu-builder: model data of the flanged mesh (SI units)");
    let _ = writeln!(s, "*NODE, NSET=NALL");
    for (i, p) in mesh.nodes.iter().enumerate() {
        let _ = writeln!(s, "{}, {:.17e}, {:.17e}, {:.17e}", i + 1, p[0], p[1], p[2]);
    }
    let n = mesh.nodes.len();
    for (k, f) in flanges.iter().enumerate() {
        let p = f.reference;
        for extra in 0..2 {
            let _ = writeln!(s, "{}, {:.17e}, {:.17e}, {:.17e}", n + 1 + 2 * k + extra, p[0], p[1], p[2]);
        }
    }
    let ty = match mesh.kind {
        ElementKind::Hex8 => "C3D8",
        ElementKind::Hex20 => "C3D20",
    };
    let _ = writeln!(s, "*ELEMENT, TYPE={ty}, ELSET=EALL");
    for e in 0..mesh.n_elements() {
        let nodes: Vec<String> = mesh.element(e).iter().map(|i| (i + 1).to_string()).collect();
        // at most 16 entries on a data line: continue the rest on the next line
        let (first, rest) = nodes.split_at(nodes.len().min(15));
        let _ = write!(s, "{}, {}", e + 1, first.join(", "));
        if !rest.is_empty() {
            let _ = write!(s, ",\n{}", rest.join(", "));
        }
        s.push('\n');
    }
    for (k, f) in flanges.iter().enumerate() {
        let name = f.name.to_uppercase();
        let _ = writeln!(s, "*NSET, NSET={name}");
        for chunk in f.slaves.chunks(8) {
            let ids: Vec<String> = chunk.iter().map(|i| (i + 1).to_string()).collect();
            let _ = writeln!(s, "{}", ids.join(", "));
        }
        let _ = writeln!(s, "*NSET, NSET={name}_REF\n{}", n + 1 + 2 * k);
        let _ = writeln!(s, "*NSET, NSET={name}_ROT\n{}", n + 2 + 2 * k);
    }
    let _ = writeln!(s, "*MATERIAL, NAME=MAT\n*ELASTIC\n{:.17e}, {:.17e}\n*DENSITY\n{:.17e}", material.e, material.nu, material.rho);
    let _ = writeln!(s, "*SOLID SECTION, ELSET=EALL, MATERIAL=MAT");
    s
}

pub fn write_abaqus_deck(path: &Path, mesh: &Mesh, flanges: &[Flange], material: &Material) -> Result<()> {
    std::fs::write(path, abaqus_deck(mesh, flanges, material)).map_err(|e| BuildError::io(path, e))
}
