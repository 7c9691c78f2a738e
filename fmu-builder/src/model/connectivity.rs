//! Whether the part hangs together, checked before anything is factored. A second box that
//! does not touch the first, a region of a mesh file no element joins to the rest, or a piece
//! held by no flange makes the stiffness singular; the Cholesky factorisation would then report
//! a pivot index of a permuted matrix. Here the pieces are found on the element-node graph (the
//! stiffness pattern for matrices), joined through the flanges' rigid ties, and an unheld piece
//! is named by its size, some of its nodes and its bounding box.

use crate::error::{BuildError, Result};
use crate::input::spec::Role;
use crate::model::flange::Flange;
use crate::model::part::Part;
use std::path::Path;

/// Union-find over the nodes, with path halving.
struct Pieces {
    parent: Vec<usize>,
}

impl Pieces {
    fn new(n: usize) -> Self {
        Pieces { parent: (0..n).collect() }
    }
    fn root(&mut self, mut a: usize) -> usize {
        while self.parent[a] != a {
            self.parent[a] = self.parent[self.parent[a]];
            a = self.parent[a];
        }
        a
    }
    fn join(&mut self, a: usize, b: usize) {
        let (ra, rb) = (self.root(a), self.root(b));
        if ra != rb {
            self.parent[ra.max(rb)] = ra.min(rb);
        }
    }
}

/// The pieces of the part joined by its elements (or its stiffness's couplings) and by the
/// flanges' rigid ties: the piece (root) of every node.
fn pieces(part: &Part, flanges: &[Flange]) -> Vec<usize> {
    let n = part.mesh.n_nodes();
    let mut p = Pieces::new(n);
    for e in 0..part.mesh.n_elements() {
        let nodes = part.mesh.element(e);
        for &b in &nodes[1..] {
            p.join(nodes[0], b);
        }
    }
    if let Some(m) = &part.matrices {
        let k = &m.stiffness;
        for j in 0..k.ncols() {
            for (&i, &v) in k.row_idx_of_col_raw(j).iter().zip(k.val_of_col(j)) {
                if v != 0.0 && i / 3 < n && j / 3 < n {
                    p.join(i / 3, j / 3);
                }
            }
        }
    }
    for f in flanges {
        for &s in &f.slaves[1..] {
            p.join(f.slaves[0], s);
        }
    }
    (0..n).map(|a| p.root(a)).collect()
}

/// What the user sees of a piece: its node count, a few nodes and its bounding box.
fn describe(part: &Part, piece: &[usize], root: usize) -> (usize, String) {
    let members: Vec<usize> = (0..piece.len()).filter(|&a| piece[a] == root).collect();
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for &a in &members {
        for d in 0..3 {
            lo[d] = lo[d].min(part.mesh.nodes[a][d]);
            hi[d] = hi[d].max(part.mesh.nodes[a][d]);
        }
    }
    let some: Vec<String> = members.iter().take(3).map(|&a| part.node_label(a)).collect();
    let text = format!(
        "{} node(s) (e.g. {}{}) spanning {lo:?} to {hi:?}",
        members.len(),
        some.join(", "),
        if members.len() > 3 { ", ..." } else { "" }
    );
    (members.len(), text)
}

/// The part must be one piece held by the mount (mounted body) or one piece (free body),
/// counting flanges as rigid ties. The error names the field to change.
pub fn check_connected(file: &Path, part: &Part, flanges: &[Flange]) -> Result<()> {
    if part.mesh.n_nodes() == 0 {
        return Ok(());
    }
    let piece = pieces(part, flanges);
    let mut roots: Vec<usize> = piece.clone();
    roots.sort_unstable();
    roots.dedup();
    if roots.len() == 1 {
        return Ok(());
    }
    let field = if !part.boxes.is_empty() {
        "geometry.boxes"
    } else if part.from_matrices {
        "geometry.matrices"
    } else {
        "geometry.mesh"
    };
    let flange_names = |root: usize| -> String {
        let names: Vec<&str> = flanges.iter().filter(|f| piece[f.slaves[0]] == root).map(|f| f.name.as_str()).collect();
        if names.is_empty() { "no flange".to_string() } else { format!("flange(s) {}", names.join(", ")) }
    };
    let how = if part.boxes.is_empty() {
        "join it to the rest (shared nodes) in the mesh, or remove it"
    } else {
        "make the boxes touch with matching nodes on the shared face, or remove the box"
    };
    let mount = flanges.iter().find(|f| f.role == Role::Motion);
    let loose = match mount {
        Some(m) => roots.iter().copied().find(|&r| r != piece[m.slaves[0]]),
        // free body: every piece but the largest is a separate body
        None => {
            let size = |r: usize| piece.iter().filter(|&&p| p == r).count();
            let largest = roots.iter().copied().max_by_key(|&r| size(r)).unwrap_or(roots[0]);
            roots.iter().copied().find(|&r| r != largest)
        }
    };
    let Some(loose) = loose else { return Ok(()) };
    let (_, what) = describe(part, &piece, loose);
    let message = match mount {
        Some(m) => format!(
            "the part falls into {} pieces, and one of them is not held by the mount \"{}\": {what}, tied to {}. \
             Unheld, it would move freely (a singular stiffness); {how}, or tie it to the mount with a flange",
            roots.len(),
            m.name,
            flange_names(loose)
        ),
        None => format!(
            "the part falls into {} pieces that no element or flange joins, so they are separate bodies: one is {what}, \
             tied to {}; a free-floating FMU is one body: {how}",
            roots.len(),
            flange_names(loose)
        ),
    };
    Err(BuildError::input(file, field, message))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::input::spec::Spec;
    use crate::model::{flange, part};

    fn check(boxes: &str, flanges: &str) -> Result<()> {
        let text = format!(
            r#"{{"name": "P", "geometry": {{"element": "hex8", "boxes": [{boxes}]}},
                "material": {{"E": 1e9, "nu": 0.3, "rho": 1000}}, "flanges": [{flanges}], "reduction": {{"modes": 1}}}}"#
        );
        let file = Path::new("in.json");
        let spec = Spec::from_str(file, &text).unwrap();
        let part = part::part_of(&spec, file).unwrap();
        let flanges = flange::select_flanges(&spec, file, &part).unwrap();
        check_connected(file, &part, &flanges)
    }

    const A: &str = r#"{"min": [0,0,0], "max": [1,1,1], "elements": [1,1,1]}"#;
    const B: &str = r#"{"min": [2,0,0], "max": [3,1,1], "elements": [1,1,1]}"#;
    const MOUNT: &str = r#"{"name": "base", "role": "motion", "nodes": {"box_face": {"box": 0, "face": "-x"}}}"#;

    #[test]
    fn a_piece_the_mount_does_not_hold_is_named_and_a_flange_can_join_it() {
        check(A, MOUNT).unwrap();
        let e = check(&format!("{A}, {B}"), MOUNT).unwrap_err().to_string();
        assert!(e.contains("geometry.boxes") && e.contains("\"base\"") && e.contains("[2.0, 0.0, 0.0]"), "{e}");
        // a force flange alone does not hold the second box
        let tip = r#"{"name": "tip", "role": "force", "nodes": {"box_face": {"box": 1, "face": "+x"}}}"#;
        let e = check(&format!("{A}, {B}"), &format!("{MOUNT}, {tip}")).unwrap_err().to_string();
        assert!(e.contains("flange(s) tip"), "{e}");
        // a flange tying both boxes' facing faces joins them rigidly
        let bridge =
            r#"{"name": "bridge", "role": "force", "nodes": {"box": {"min": [0.9, -1, -1], "max": [2.1, 2, 2]}}}"#;
        check(&format!("{A}, {B}"), &format!("{MOUNT}, {bridge}")).unwrap();
        // a free body of two pieces is two bodies
        let e = check(&format!("{A}, {B}"), "").unwrap_err().to_string();
        assert!(e.contains("separate bodies"), "{e}");
    }
}
