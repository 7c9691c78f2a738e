//! The meshed, flanged part as an Abaqus/CalculiX input deck (model data only: nodes, elements,
//! node sets, material), so the same mesh can be analysed by CalculiX for reference results.
//! Each flange gets its slave set `<NAME>` plus a reference node (set `<NAME>_REF`) and a
//! rotation node (set `<NAME>_ROT`) at its reference point, ready for `*RIGID BODY`; a
//! distributing flange's node weights follow its sets as comment lines.

use crate::error::{BuildError, Result};
use crate::input::element::ElementKind;
use crate::model::flange::{Flange, FlangeCoupling};
use crate::model::part::Part;
use std::fmt::Write as _;
use std::path::Path;

/// A real in at most 20 characters (CalculiX reads fixed 20-character fields): the shortest
/// representation that reads back exactly, or the most digits that fit.
fn real(x: f64) -> String {
    let shortest = format!("{x:e}");
    if shortest.len() <= 20 {
        return shortest;
    }
    (1..=16).rev().map(|p| format!("{x:.p$e}")).find(|s| s.len() <= 20).unwrap_or(shortest)
}

pub fn abaqus_deck(part: &Part, flanges: &[Flange]) -> String {
    let mesh = &part.mesh;
    let mut s = String::new();
    let _ = writeln!(s, "** written by fmu-builder: model data of the flanged mesh (SI units)");
    let _ = writeln!(s, "*NODE, NSET=NALL");
    for (i, p) in mesh.nodes.iter().enumerate() {
        let _ = writeln!(s, "{}, {}, {}, {}", i + 1, real(p[0]), real(p[1]), real(p[2]));
    }
    let n = mesh.nodes.len();
    for (k, f) in flanges.iter().enumerate() {
        let p = f.reference;
        for extra in 0..2 {
            let _ = writeln!(s, "{}, {}, {}, {}", n + 1 + 2 * k + extra, real(p[0]), real(p[1]), real(p[2]));
        }
    }
    // one *ELEMENT block per (kind, material): CalculiX wants one type per block, and the
    // material's element set is the union of its blocks
    let mut groups: Vec<(ElementKind, usize)> = Vec::new();
    for e in 0..mesh.n_elements() {
        let key = (mesh.kind(e), mesh.material[e]);
        if !groups.contains(&key) {
            groups.push(key);
        }
    }
    for &(kind, material) in &groups {
        let _ = writeln!(s, "*ELEMENT, TYPE={}, ELSET=M{}", kind.calculix_name(), material + 1);
        for e in (0..mesh.n_elements()).filter(|&e| (mesh.kind(e), mesh.material[e]) == (kind, material)) {
            let nodes: Vec<String> = mesh.element(e).iter().map(|i| (i + 1).to_string()).collect();
            // at most 16 entries on a data line: continue the rest on the next line
            let (first, rest) = nodes.split_at(nodes.len().min(15));
            let _ = write!(s, "{}, {}", e + 1, first.join(", "));
            if !rest.is_empty() {
                let _ = write!(s, ",\n{}", rest.join(", "));
            }
            s.push('\n');
        }
    }
    let _ = writeln!(s, "*ELSET, ELSET=EALL");
    let mut used: Vec<usize> = groups.iter().map(|g| g.1).collect();
    used.sort_unstable();
    used.dedup();
    let _ = writeln!(s, "{}", used.iter().map(|m| format!("M{}", m + 1)).collect::<Vec<_>>().join(", "));
    for (k, f) in flanges.iter().enumerate() {
        let name = f.name.to_uppercase();
        let _ = writeln!(s, "*NSET, NSET={name}");
        for chunk in f.slaves.chunks(8) {
            let ids: Vec<String> = chunk.iter().map(|i| (i + 1).to_string()).collect();
            let _ = writeln!(s, "{}", ids.join(", "));
        }
        let _ = writeln!(s, "*NSET, NSET={name}_REF\n{}", n + 1 + 2 * k);
        let _ = writeln!(s, "*NSET, NSET={name}_ROT\n{}", n + 2 + 2 * k);
        // a distributing flange's weights as comment lines (`**W node, weight`): CalculiX 2.20
        // has no one keyword for its whole coupling (`*DISTRIBUTING COUPLING` ties translations
        // only, `*COUPLING` + `*DISTRIBUTING` spreads loads with its own weights), so the deck
        // carries the data and the analysis picks what it needs
        if let FlangeCoupling::Distributing { weights } = &f.coupling {
            let _ = writeln!(s, "** distributing coupling of {name} (node, weight):");
            for (&node, &w) in f.slaves.iter().zip(weights) {
                let _ = writeln!(s, "**W {}, {}", node + 1, real(w));
            }
        }
    }
    for m in used {
        let mat = &part.materials[m];
        let _ = writeln!(
            s,
            "*MATERIAL, NAME=MAT{}\n*ELASTIC\n{}, {}\n*DENSITY\n{}",
            m + 1,
            real(mat.elasticity.e),
            real(mat.elasticity.nu),
            real(mat.rho)
        );
        let _ = writeln!(s, "*SOLID SECTION, ELSET=M{}, MATERIAL=MAT{}", m + 1, m + 1);
    }
    s
}

/// Writes one file an export made; the caller's, so that the output stage puts it in place
/// (a temporary file and a checked rename).
pub type WriteFile<'a> = &'a dyn Fn(&Path, &[u8]) -> Result<()>;

pub fn write_abaqus_deck(path: &Path, part: &Part, flanges: &[Flange], write: WriteFile) -> Result<()> {
    if !part.has_elements() {
        return Err(BuildError::file(
            path,
            "--export-inp needs a part with elements (this one is given by its matrices)",
        ));
    }
    write(path, abaqus_deck(part, flanges).as_bytes())
}

fn matrix_market(a: &faer::sparse::SparseColMat<usize, f64>, what: &str) -> String {
    let n = a.ncols();
    let mut entries = Vec::new();
    for j in 0..n {
        for (&i, &v) in a.row_idx_of_col_raw(j).iter().zip(a.val_of_col(j)) {
            if i >= j {
                entries.push((i, j, v));
            }
        }
    }
    let mut s = String::new();
    let _ = writeln!(s, "%%MatrixMarket matrix coordinate real symmetric\n% fmu-builder: {what}, SI units");
    let _ = writeln!(s, "{} {} {}", a.nrows(), n, entries.len());
    for (i, j, v) in entries {
        // shortest representation that reads back bit-exactly
        let _ = writeln!(s, "{} {} {v:e}", i + 1, j + 1);
    }
    s
}

/// The part's free-free matrices as users export them from an FE code: K.mtx, M.mtx (Matrix
/// Market, symmetric), dofs.txt (node id and direction of each row) and nodes.txt (id x y z),
/// with node ids 1..N in the part's node order. Reading them back as `geometry.matrices` gives
/// the very model the mesh gives.
pub fn write_free_free_matrices(dir: &Path, part: &Part, write_file: WriteFile) -> Result<()> {
    if !part.has_elements() {
        return Err(BuildError::file(
            dir,
            "--export-free-free needs a part with elements (this one is given by its matrices)",
        ));
    }
    std::fs::create_dir_all(dir).map_err(|e| BuildError::io(dir, e))?;
    let free = crate::model::assembly::uncoupled(&part.mesh, &part.materials, &|e, m| part.element_error(e, m))?;
    let write = |name: &str, text: String| write_file(&dir.join(name), text.as_bytes());
    write("K.mtx", matrix_market(&free.stiffness, "free-free stiffness [N/m]"))?;
    write("M.mtx", matrix_market(&free.mass, "free-free mass [kg]"))?;
    let mut dofs = String::from("# row of K.mtx and M.mtx: node direction\n");
    let mut nodes = String::from("# id x y z [m]\n");
    for (i, p) in part.mesh.nodes.iter().enumerate() {
        for d in 1..=3 {
            let _ = writeln!(dofs, "{} {d}", i + 1);
        }
        let _ = writeln!(nodes, "{} {:e} {:e} {:e}", i + 1, p[0], p[1], p[2]);
    }
    write("dofs.txt", dofs)?;
    write("nodes.txt", nodes)
}

/// The mounted body's matrices (mount held) in Matrix Market coordinate format, with the DoF of
/// each flange load: K.mtx, M.mtx (symmetric, lower triangle), and flange_dofs.txt (0-based row
/// of each unit flange load, 6 per force flange: u_x..z, theta_x..z).
pub fn write_matrix_market(
    dir: &Path,
    model: &crate::model::rigid_coupling::Assembled,
    write: WriteFile,
) -> Result<()> {
    std::fs::create_dir_all(dir).map_err(|e| BuildError::io(dir, e))?;
    let nc = model.dofs.n_clamped();
    for (name, a) in [("K.mtx", &model.stiffness), ("M.mtx", &model.mass)] {
        let b = crate::linalg::sparse::block(a, 0..nc, 0..nc)?;
        write(&dir.join(name), matrix_market(&b, &format!("{name} of the mounted body (mount held)")).as_bytes())?;
    }
    let d = &model.dofs;
    let mut s = String::from(
        "# 0-based DoF of each unit flange load: 6 per force flange (u_x u_y u_z theta_x theta_y theta_z)\n",
    );
    for (k, first) in d.flange_first.iter().enumerate() {
        if Some(k) != d.mount {
            for i in 0..6 {
                let _ = writeln!(s, "{}", first + i);
            }
        }
    }
    write(&dir.join("flange_dofs.txt"), s.as_bytes())
}

#[cfg(test)]
mod tests {
    #[test]
    fn reals_fit_calculix_fields_and_read_back() {
        for x in [0.0, -5.000000000000001e-3, 0.994, 1.006, 2.1e11, 0.2804878048780488, 1.0000000000000002] {
            let s = super::real(x);
            assert!(s.len() <= 20, "{s}");
            let back: f64 = s.parse().unwrap();
            assert!((back - x).abs() <= 1e-14 * x.abs(), "{s}");
        }
        assert_eq!(super::real(0.994), "9.94e-1");
        // what does not fit keeps as many digits as fit
        let s = super::real(-1.2345678901234567e-123);
        assert!(s.len() <= 20 && (s.parse::<f64>().unwrap() / -1.2345678901234567e-123 - 1.0).abs() < 1e-11, "{s}");
    }
}
