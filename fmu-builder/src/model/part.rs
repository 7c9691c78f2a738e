//! The part as the input describes it, whatever its source: boxes meshed here, a mesh file
//! (Abaqus/CalculiX `.inp`, Gmsh `.msh`) or assembled matrices. Resolves every element's
//! material (the input's `materials` over `material` over the mesh file) and keeps the node sets
//! flanges may name. Everything downstream sees one `Part`.

use crate::error::{BuildError, Result};
use crate::input::element::ElementKind;
use crate::input::import::{self, ImportError, ImportedMesh};
use crate::input::mesh::{self, BoxRegion, Mesh, MeshError};
use crate::input::ranges;
use crate::input::size::{self, Memory};
use crate::input::spec::{MaterialSpec, Spec};
use crate::linalg::faer_error;
use crate::model::assembly::{self, SolidMaterial, Uncoupled};
use crate::model::fe::Elasticity;
use faer::sparse::{SparseColMat, Triplet};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

pub struct Part {
    pub mesh: Mesh,
    /// The boxes a built-in mesh was generated from (empty for mesh files and matrices): the
    /// regions `box_face` selectors refer to.
    pub boxes: Vec<BoxRegion>,
    pub materials: Vec<SolidMaterial>,
    /// Named node sets (mesh-file or node-file names), as dense node indices.
    pub node_sets: BTreeMap<String, Vec<usize>>,
    /// The user's free-free matrices, when the part is given by them.
    pub matrices: Option<Uncoupled>,
    /// Relative rigid-body residuals |K r| of given matrices (translation x, y, z, rotation x, y, z).
    pub rigid_body_residual: Option<[f64; 6]>,
    /// What the part was read from, for reports.
    pub source: String,
    pub from_matrices: bool,
    /// The file the nodes and elements come from (the mesh or node file; the input file for
    /// boxes): messages about an element or node name it.
    pub origin: PathBuf,
    /// File ids of the nodes and elements (empty for boxes: they have none).
    pub node_ids: Vec<u64>,
    pub element_ids: Vec<u64>,
    /// Metres per unit of the input's lengths (`geometry.length_unit`): the mesh is in metres,
    /// and the flange selectors and stress points, given in the input's unit, are scaled by it.
    pub length_scale: f64,
    /// What the import left out, said as warnings (surface elements of a "save all" deck).
    pub notes: Vec<String>,
}

impl From<ImportError> for BuildError {
    fn from(e: ImportError) -> Self {
        let field = if e.line > 0 { format!("line {}", e.line) } else { String::new() };
        BuildError::input(&e.file, field, e.message)
    }
}

impl Part {
    /// Element kinds of the mesh, or "matrices".
    pub fn element_description(&self) -> String {
        if self.from_matrices { "matrices".into() } else { self.mesh.kind_names() }
    }

    /// Case-insensitive node-set lookup.
    pub fn node_set(&self, name: &str) -> Option<&[usize]> {
        self.node_sets.iter().find(|(k, _)| k.eq_ignore_ascii_case(name)).map(|(_, v)| v.as_slice())
    }

    /// The free-free model: the user's matrices, or assembled from the mesh.
    pub fn free_free(&mut self) -> Result<Uncoupled> {
        match self.matrices.take() {
            Some(m) => Ok(m),
            None => assembly::uncoupled(&self.mesh, &self.materials, &|e, m| self.element_error(e, m)),
        }
    }

    /// Element `e` as the user knows it: its id in the mesh file, or its box and grid position.
    pub fn element_label(&self, e: usize) -> String {
        if let Some(id) = self.element_ids.get(e) {
            return format!("element {id} of {}", self.origin.display());
        }
        let mut first = 0usize;
        for (i, b) in self.boxes.iter().enumerate() {
            let count = b.divisions.iter().product::<usize>();
            if e < first + count {
                let local = e - first;
                let [nx, ny, _] = b.divisions;
                let at = [local % nx, (local / nx) % ny, local / (nx * ny)];
                return format!("element {at:?} (x, y, z from 0) of geometry.boxes[{i}]");
            }
            first += count;
        }
        format!("element {e}")
    }

    /// Node `n` as the user knows it: its id in the file, or its coordinates.
    pub fn node_label(&self, n: usize) -> String {
        let p = self.mesh.nodes[n];
        match self.node_ids.get(n) {
            Some(id) => format!("node {id} at ({}, {}, {})", p[0], p[1], p[2]),
            None => format!("node at ({}, {}, {})", p[0], p[1], p[2]),
        }
    }

    /// An element the FE formulation refuses (inverted, degenerate), named for the user.
    pub fn element_error(&self, e: usize, message: String) -> BuildError {
        let hint = if self.boxes.is_empty() {
            "fix its node order or coordinates in the mesh file (CalculiX node order, positive volume)"
        } else {
            "the box is too thin or too long for its element count: give geometry.boxes elements closer to the box's proportions"
        };
        let field = if self.element_ids.is_empty() { "geometry.boxes".to_string() } else { String::new() };
        BuildError::input(&self.origin, field, format!("{}: {message}; {hint}", self.element_label(e)))
    }

    /// Whether the part has elements (stresses, a deck to export).
    pub fn has_elements(&self) -> bool {
        self.mesh.n_elements() > 0
    }
}

pub fn part_of(spec: &Spec, file: &Path) -> Result<Part> {
    if let Some(name) = &spec.geometry.mesh {
        return mesh_file_part(spec, file, &Spec::readable_file(file, "geometry.mesh", name)?);
    }
    if let Some(m) = &spec.geometry.matrices {
        return matrix_part(spec, file, m);
    }
    box_part(spec, file)
}

fn box_part(spec: &Spec, file: &Path) -> Result<Part> {
    let kind = spec.geometry.element;
    let counts: Vec<[usize; 3]> = spec.geometry.boxes.iter().map(|b| b.elements).collect();
    size::check_boxes(file, &counts, kind, Memory::of_this_machine())?;
    // the boxes in metres (given in geometry.length_unit)
    let scale = spec.length_scale();
    let boxes: Vec<BoxRegion> = spec
        .geometry
        .boxes
        .iter()
        .map(|b| BoxRegion { min: b.min.map(|c| c * scale), max: b.max.map(|c| c * scale), divisions: b.elements })
        .collect();
    let mesh = mesh::mesh_boxes(&boxes, kind).map_err(|e| {
        let field = match &e {
            MeshError::DegenerateBox { box_index, .. } | MeshError::TooLarge { box_index } => {
                format!("geometry.boxes[{box_index}]")
            }
            MeshError::Overlap { second, .. } => format!("geometry.boxes[{second}]"),
            MeshError::NonConforming { node_box, .. } => format!("geometry.boxes[{node_box}]"),
            MeshError::UnsupportedElement { .. } => "geometry.element".to_string(),
            _ => "geometry.boxes".to_string(),
        };
        BuildError::input(file, field, e.to_string()).caused_by(e)
    })?;
    let m = spec.material.unwrap_or_default();
    let (Some(e), Some(nu), Some(rho)) = (m.e, m.nu, m.rho) else {
        return Err(BuildError::input(file, "material", "the box mesh needs E, nu and rho"));
    };
    Ok(Part {
        mesh,
        boxes,
        materials: vec![SolidMaterial { name: "material".into(), elasticity: Elasticity { e, nu }, rho }],
        node_sets: BTreeMap::new(),
        matrices: None,
        rigid_body_residual: None,
        source: format!("{} boxes", spec.geometry.boxes.len()),
        from_matrices: false,
        origin: file.to_path_buf(),
        node_ids: Vec::new(),
        element_ids: Vec::new(),
        length_scale: scale,
        notes: Vec::new(),
    })
}

/// Nodes referenced by no element carry no stiffness (a singular model): they are dropped.
/// Returns the kept coordinates and each file node's new index.
fn compact(imported: &ImportedMesh) -> (Vec<[f64; 3]>, Vec<Option<usize>>) {
    let mut used = vec![false; imported.nodes.len()];
    for &n in imported.connectivity.iter().flatten() {
        used[n] = true;
    }
    let mut nodes = Vec::new();
    let new_index = used
        .iter()
        .zip(&imported.nodes)
        .map(|(&u, p)| {
            u.then(|| {
                nodes.push(*p);
                nodes.len() - 1
            })
        })
        .collect();
    (nodes, new_index)
}

fn mesh_file_part(spec: &Spec, file: &Path, mesh_path: &Path) -> Result<Part> {
    let imported = import::read_mesh(mesh_path)?;
    if imported.connectivity.is_empty() {
        return Err(BuildError::input(
            mesh_path,
            "",
            format!("no solid elements (supported: {})", ElementKind::supported_names()),
        ));
    }
    check_imported_size(file, mesh_path, &imported.nodes, &imported.element_types, None, Memory::of_this_machine())?;
    check_materials_defined(spec, file, mesh_path, &imported)?;
    let section_of = section_materials(mesh_path, &imported)?;
    let (materials, element_material) = element_materials(spec, file, mesh_path, &imported, &section_of)?;
    let (mut nodes, new_index) = compact(&imported);
    // the mesh file's coordinates are in geometry.length_unit: metres from here on
    let scale = spec.length_scale();
    if scale != 1.0 {
        for p in &mut nodes {
            *p = p.map(|c| c * scale);
        }
    }
    let kept_ids: Vec<u64> =
        imported.node_ids.iter().zip(&new_index).filter(|(_, k)| k.is_some()).map(|(id, _)| *id).collect();
    let mut mesh = Mesh::nodes_only(nodes);
    let mut conn = Vec::with_capacity(20);
    for (e, c) in imported.connectivity.iter().enumerate() {
        conn.clear();
        conn.extend(c.iter().map(|&n| new_index[n].unwrap_or(0)));
        mesh.push_element(imported.element_types[e], &conn, element_material[e]);
    }
    let node_sets = imported
        .node_sets
        .iter()
        .map(|(name, members)| (name.clone(), members.iter().filter_map(|&n| new_index[n]).collect()))
        .collect();
    Ok(Part {
        // as the input names it: an absolute path of the machine that built it says nothing
        source: format!("{} ({} elements)", spec.geometry.mesh.as_deref().unwrap_or("mesh"), mesh.n_elements()),
        mesh,
        boxes: Vec::new(),
        materials,
        node_sets,
        matrices: None,
        rigid_body_residual: None,
        from_matrices: false,
        origin: mesh_path.to_path_buf(),
        node_ids: kept_ids,
        element_ids: imported.element_ids.clone(),
        length_scale: scale,
        notes: imported.notes.clone(),
    })
}

/// Every material the input names is one the mesh file defines.
fn check_materials_defined(spec: &Spec, file: &Path, mesh_path: &Path, imported: &ImportedMesh) -> Result<()> {
    for name in spec.materials.keys() {
        if imported.material(name).is_none() {
            let known: Vec<&str> = imported.materials.iter().map(|m| m.name.as_str()).collect();
            return Err(BuildError::input(
                file,
                format!("materials.{name}"),
                format!(
                    "{} defines no material \"{name}\" (its materials: {})",
                    mesh_path.display(),
                    if known.is_empty() { "none".to_string() } else { known.join(", ") }
                ),
            ));
        }
    }
    Ok(())
}

/// Every element's material name of its *SOLID SECTION (the first section naming it).
fn section_materials<'m>(mesh_path: &Path, imported: &'m ImportedMesh) -> Result<Vec<Option<&'m str>>> {
    let mut section_of: Vec<Option<&str>> = vec![None; imported.connectivity.len()];
    for (elset, material) in &imported.sections {
        let Some(members) = imported.element_sets.get(elset) else {
            return Err(BuildError::input(
                mesh_path,
                "",
                format!("*SOLID SECTION names element set {elset}, which is not defined"),
            ));
        };
        if imported.material(material).is_none() {
            return Err(BuildError::input(
                mesh_path,
                "",
                format!("*SOLID SECTION, ELSET={elset} names material {material}, which is not defined"),
            ));
        }
        for &e in members {
            section_of[e].get_or_insert(material.as_str());
        }
    }
    Ok(section_of)
}

/// The distinct materials of the elements' sections, and every element's index into them.
fn element_materials(
    spec: &Spec,
    file: &Path,
    mesh_path: &Path,
    imported: &ImportedMesh,
    section_of: &[Option<&str>],
) -> Result<(Vec<SolidMaterial>, Vec<usize>)> {
    let mut materials: Vec<SolidMaterial> = Vec::new();
    let mut index_of: BTreeMap<Option<String>, usize> = BTreeMap::new();
    let mut element_material = Vec::with_capacity(section_of.len());
    for (e, section) in section_of.iter().enumerate() {
        let key = section.map(|s| s.to_uppercase());
        if let Some(&i) = index_of.get(&key) {
            element_material.push(i);
            continue;
        }
        let m = resolve_material(spec, file, mesh_path, imported, *section, imported.element_ids[e])?;
        index_of.insert(key, materials.len());
        element_material.push(materials.len());
        materials.push(m);
    }
    Ok((materials, element_material))
}

/// A mesh or matrix file's model against the machine's memory, before assembly and factoring
/// (the readers' own allocations are bounded by the file's size). The factor fill is estimated
/// on a lattice of the part's bounding box.
fn check_imported_size(
    file: &Path,
    source: &Path,
    nodes: &[[f64; 3]],
    kinds: &[ElementKind],
    stiffness_nonzeros: Option<f64>,
    memory: Memory,
) -> Result<()> {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for p in nodes {
        for a in 0..3 {
            lo[a] = lo[a].min(p[a]);
            hi[a] = hi[a].max(p[a]);
        }
    }
    let n = nodes.len() as f64;
    let mut per_kind: Vec<(ElementKind, f64)> = Vec::new();
    for &k in kinds {
        match per_kind.iter_mut().find(|(kind, _)| *kind == k) {
            Some((_, c)) => *c += 1.0,
            None => per_kind.push((k, 1.0)),
        }
    }
    let fill = size::nested_dissection_fill(size::lattice_of(n, [0, 1, 2].map(|a| hi[a] - lo[a])));
    let estimate = size::SizeEstimate::new(n, &per_kind, stiffness_nonzeros, fill);
    estimate.fits(memory).map_err(|m| {
        let field = if stiffness_nonzeros.is_some() { "geometry.matrices" } else { "geometry.mesh" };
        BuildError::input(file, field, format!("{}: {m} (coarsen the mesh)", source.display()))
    })
}

/// The material of the elements of one section (None: elements in no section): the mesh file's
/// properties, overridden by the input's `material`, overridden by `materials[name]`.
fn resolve_material(
    spec: &Spec,
    file: &Path,
    mesh_path: &Path,
    imported: &ImportedMesh,
    section: Option<&str>,
    element_id: u64,
) -> Result<SolidMaterial> {
    let from_file = section.and_then(|s| imported.material(s));
    let global = spec.material.unwrap_or_default();
    let named: MaterialSpec = section
        .and_then(|s| spec.materials.iter().find(|(k, _)| k.eq_ignore_ascii_case(s)).map(|(_, v)| *v))
        .unwrap_or_default();
    let pick = |f: Option<f64>, g: Option<f64>, n: Option<f64>| n.or(g).or(f);
    let e = pick(from_file.and_then(|m| m.e), global.e, named.e);
    let nu = pick(from_file.and_then(|m| m.nu), global.nu, named.nu);
    let rho = pick(from_file.and_then(|m| m.rho), global.rho, named.rho);
    let what = match section {
        Some(s) => format!("material {s} (*SOLID SECTION of element {element_id} in {})", mesh_path.display()),
        None => format!("element {element_id} of {} (in no *SOLID SECTION)", mesh_path.display()),
    };
    let missing = |prop: &str| {
        BuildError::input(
            file,
            match section {
                Some(s) => format!("materials.{s}.{prop}"),
                None => format!("material.{prop}"),
            },
            format!("{what} has no {prop}: neither the mesh file nor the input gives it"),
        )
    };
    let e = e.ok_or_else(|| missing("E"))?;
    let nu = nu.ok_or_else(|| missing("nu"))?;
    let rho = rho.ok_or_else(|| missing("rho"))?;
    for (prop, v) in [("E", e), ("nu", nu), ("rho", rho)] {
        if let Some(problem) = ranges::material_problem(prop, v) {
            // the input's checks ran already: a value out of range here comes from the file
            return Err(BuildError::input(
                mesh_path,
                "",
                format!("{what}: {problem}; override it with material.{prop} in {}", file.display()),
            ));
        }
    }
    Ok(SolidMaterial { name: section.unwrap_or("material").to_string(), elasticity: Elasticity { e, nu }, rho })
}

fn matrix_part(_spec: &Spec, file: &Path, m: &crate::input::spec::MatrixSpec) -> Result<Part> {
    let path = |field: &str, name: &str| Spec::readable_file(file, &format!("geometry.matrices.{field}"), name);
    let (k, mm, dofs, nodes) =
        (path("stiffness", &m.stiffness)?, path("mass", &m.mass)?, path("dofs", &m.dofs)?, path("nodes", &m.nodes)?);
    let d = m.damping.as_deref().map(|name| path("damping", name)).transpose()?;
    let nodes_path = nodes.clone();
    let files = import::matrices::MatrixFiles {
        stiffness: &k,
        mass: &mm,
        damping: d.as_deref(),
        dof_map: &dofs,
        nodes: &nodes,
    };
    let model = import::matrices::read_matrix_model(&files, m.free_free)?;
    let nonzeros = model.stiffness.val().len() as f64;
    check_imported_size(file, &k, &model.nodes, &[], Some(nonzeros), Memory::of_this_machine())?;
    let nodal_mass = nodal_mass(&model.mass, &mm)?;
    let mesh = Mesh::nodes_only(model.nodes);
    Ok(Part {
        source: format!("matrices {} and {}", k.display(), mm.display()),
        mesh,
        boxes: Vec::new(),
        materials: Vec::new(),
        node_sets: model.node_sets,
        matrices: Some(Uncoupled {
            stiffness: model.stiffness,
            mass: model.mass,
            damping: model.damping,
            nodal_mass,
            volume: None,
        }),
        rigid_body_residual: Some(model.rigid_body_residual),
        from_matrices: true,
        origin: nodes_path,
        node_ids: model.node_ids,
        element_ids: Vec::new(),
        // matrices are SI (the input check refuses another length unit for them)
        length_scale: 1.0,
        notes: Vec::new(),
    })
}

/// The scalar nodal mass m_ab of a mass matrix of the form m_ab delta_ij (every solid-element
/// mass, consistent or lumped). The floating-frame invariants (cross products per node pair)
/// need that form; a matrix coupling directions is refused.
fn nodal_mass(mass: &SparseColMat<usize, f64>, file: &Path) -> Result<SparseColMat<usize, f64>> {
    let n = mass.nrows() / 3;
    let scale = mass.val().iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let tol = 1e-10 * scale;
    let mut blocks: std::collections::HashMap<(usize, usize), [[f64; 3]; 3]> = std::collections::HashMap::new();
    for col in 0..mass.ncols() {
        for (&row, &v) in mass.row_idx_of_col_raw(col).iter().zip(mass.val_of_col(col)) {
            blocks.entry((row / 3, col / 3)).or_insert([[0.0; 3]; 3])[row % 3][col % 3] += v;
        }
    }
    let dir = ["x", "y", "z"];
    let mut trip = Vec::with_capacity(blocks.len());
    let mut keys: Vec<_> = blocks.keys().copied().collect();
    keys.sort_unstable();
    for (a, b) in keys {
        let m = blocks[&(a, b)];
        for i in 0..3 {
            for j in 0..3 {
                let off = if i == j { (m[i][i] - m[0][0]).abs() } else { m[i][j].abs() };
                if off > tol {
                    return Err(BuildError::input(
                        file,
                        "",
                        format!(
                            "the mass matrix is not of the form m_ab delta_ij: between DoFs {}{} and {}{} (dense DoF order) \
                             it has {:e} where {:e} is expected; only solid (translational) models are supported",
                            a,
                            dir[i],
                            b,
                            dir[j],
                            m[i][j],
                            if i == j { m[0][0] } else { 0.0 }
                        ),
                    ));
                }
            }
        }
        trip.push(Triplet::new(a, b, m[0][0]));
    }
    SparseColMat::try_new_from_triplets(n, n, &trip)
        .map_err(|e| BuildError::numerical(format!("nodal mass: {}", faer_error::creation(&e))).caused_by(e))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spec(text: &str) -> Spec {
        Spec::from_str(Path::new("in.json"), text).unwrap()
    }

    const DECK: &str = "*NODE\n1,0,0,0\n2,1,0,0\n3,0,1,0\n4,0,0,1\n5,1,1,1\n99,5,5,5\n\
        *ELEMENT, TYPE=C3D4, ELSET=A\n1,1,2,3,4\n*ELEMENT, TYPE=C3D4, ELSET=B\n2,2,3,4,5\n\
        *NSET, NSET=FACE\n1,2,3,99\n\
        *MATERIAL, NAME=Steel\n*ELASTIC\n2e11, 0.3\n*DENSITY\n7800\n*SOLID SECTION, ELSET=A, MATERIAL=STEEL\n";

    fn part(dir: &Path, json_extra: &str) -> Result<Part> {
        std::fs::write(dir.join("m.inp"), DECK).unwrap();
        let text = format!(
            r#"{{"name": "P", "geometry": {{"mesh": "m.inp"}}, {json_extra}
              "flanges": [{{"name": "base", "role": "motion", "nodes": {{"node_set": "face"}}}}], "reduction": {{"modes": 2}}}}"#
        );
        let file = dir.join("in.json");
        part_of(&spec(&text), &file)
    }

    #[test]
    fn materials_resolve_file_then_material_then_materials() {
        let dir = std::env::temp_dir().join(format!("fmu-part-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        // element 2 is in no section: without an input material it has none
        let e = part(&dir, "").err().unwrap().to_string();
        assert!(e.contains("material.E") && e.contains("element 2") && e.contains("m.inp"), "{e}");
        let p = part(&dir, r#""material": {"E": 1e9, "nu": 0.25, "rho": 1000},"#).unwrap();
        let a = &p.materials[p.mesh.material[0]];
        let b = &p.materials[p.mesh.material[1]];
        // the input's material overrides the file's STEEL property by property
        assert_eq!((a.elasticity.e, a.elasticity.nu, a.rho), (1e9, 0.25, 1000.0));
        assert_eq!((b.elasticity.e, b.rho), (1e9, 1000.0));
        let p =
            part(&dir, r#""material": {"E": 1e9, "nu": 0.25, "rho": 1000}, "materials": {"steel": {"rho": 7000}},"#)
                .unwrap();
        let a = &p.materials[p.mesh.material[0]];
        assert_eq!((a.elasticity.e, a.rho), (1e9, 7000.0));
        // what the input leaves open comes from the file
        let p = part(&dir, r#""material": {"nu": 0.2, "E": 3e9, "rho": 10}, "materials": {"STEEL": {"nu": 0.1}},"#)
            .unwrap();
        let a = &p.materials[p.mesh.material[0]];
        assert_eq!((a.elasticity.e, a.elasticity.nu), (3e9, 0.1));
        let e = part(&dir, r#""material": {"E": 1e9, "nu": 0.25, "rho": 1000}, "materials": {"alu": {"E": 7e10}},"#)
            .err()
            .unwrap()
            .to_string();
        assert!(e.contains("materials.alu") && e.contains("STEEL"), "{e}");
        // node 99 is in no element: dropped, and dropped from its set
        let p = part(&dir, r#""material": {"E": 1e9, "nu": 0.25, "rho": 1000},"#).unwrap();
        assert_eq!(p.mesh.n_nodes(), 5);
        assert_eq!(p.node_set("Face").unwrap(), &[0, 1, 2]);
        std::fs::remove_dir_all(&dir).ok();
    }

    /// The schema keeps tetrahedra out of `geometry.element`; should one get through, the box
    /// mesher refuses it with its own message, against that field.
    #[test]
    fn tet_boxes_are_refused() {
        let text = r#"{"name": "P", "geometry": {"element": "ELEMENT", "boxes": [{"min": [0,0,0], "max": [1,1,1], "elements": [1,1,1]}]},
            "material": {"E": 1e9, "nu": 0.25, "rho": 1000},
            "flanges": [{"name": "base", "role": "motion", "nodes": {"box_face": {"box": 0, "face": "-x"}}}], "reduction": {"modes": 2}}"#;
        let e = Spec::from_str(Path::new("in.json"), &text.replace("ELEMENT", "tet4")).unwrap_err().to_string();
        assert!(e.contains("geometry.element"), "{e}");
        let mut s = spec(&text.replace("ELEMENT", "hex8"));
        assert_eq!(s.geometry.element, ElementKind::Hex8);
        for kind in [ElementKind::Tet4, ElementKind::Tet10] {
            s.geometry.element = kind;
            let e = part_of(&s, Path::new("in.json")).err().unwrap().to_string();
            assert!(e.contains("geometry.element") && e.contains(&format!("cannot build {kind} elements")), "{e}");
        }
    }

    /// A mesh file's model is held against the memory before assembly, named by its field.
    #[test]
    fn an_imported_mesh_too_large_for_the_memory_is_refused() {
        let nodes: Vec<[f64; 3]> = (0..1000).map(|i| [i as f64, (i % 10) as f64, (i % 100) as f64]).collect();
        let kinds = vec![ElementKind::Tet10; 500];
        let small = Memory { bytes: 1e6, source: "a test's 1 MB" };
        let e = check_imported_size(Path::new("in.json"), Path::new("big.msh"), &nodes, &kinds, None, small)
            .unwrap_err()
            .to_string();
        assert!(e.contains("in.json: geometry.mesh") && e.contains("big.msh") && e.contains("coarsen"), "{e}");
        let large = Memory { bytes: 1e10, source: "a test's 10 GB" };
        check_imported_size(Path::new("in.json"), Path::new("big.msh"), &nodes, &kinds, None, large).unwrap();
    }

    #[test]
    fn nodal_mass_needs_the_isotropic_form() {
        let iso = [
            (0, 0, 2.0),
            (1, 1, 2.0),
            (2, 2, 2.0),
            (0, 3, 0.5),
            (3, 0, 0.5),
            (1, 4, 0.5),
            (4, 1, 0.5),
            (2, 5, 0.5),
            (5, 2, 0.5),
            (3, 3, 1.0),
            (4, 4, 1.0),
            (5, 5, 1.0),
        ];
        let trip: Vec<_> = iso.iter().map(|&(i, j, v)| Triplet::new(i, j, v)).collect();
        let m = SparseColMat::try_new_from_triplets(6, 6, &trip).unwrap();
        let nodal = nodal_mass(&m, Path::new("M.mtx")).unwrap();
        assert_eq!(nodal.val_of_col(0), &[2.0, 0.5]);
        let mut coupled = trip.clone();
        coupled.push(Triplet::new(0, 1, 0.1));
        coupled.push(Triplet::new(1, 0, 0.1));
        let m = SparseColMat::try_new_from_triplets(6, 6, &coupled).unwrap();
        let e = nodal_mass(&m, Path::new("M.mtx")).err().unwrap().to_string();
        assert!(e.contains("M.mtx") && e.contains("m_ab delta_ij"), "{e}");
    }
}
