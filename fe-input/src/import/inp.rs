//! Abaqus / CalculiX input deck (`.inp`) importer.
//!
//! Supported model data: `*NODE` (NSET=, SYSTEM=R), `*ELEMENT` (TYPE= one of
//! C3D4, C3D10, C3D8, C3D20, C3D20R; ELSET=; records continued on following
//! lines when a line ends with a comma), `*NSET` / `*ELSET` (ids, set names,
//! GENERATE), `*MATERIAL`, `*ELASTIC` (TYPE=ISO), `*DENSITY`,
//! `*SOLID SECTION` and `*INCLUDE, INPUT=` (relative to the including file).
//!
//! Analysis data (`*STEP` ... `*END STEP`, loads, boundary conditions,
//! output requests, ...) and material options that do not affect a linear
//! elastic model (expansion, conductivity, ...) are skipped. Any other
//! keyword is rejected, because it may change the model in a way this
//! importer cannot represent.
//!
//! Keyword and set/material names are case-insensitive and returned
//! upper-cased. References (element nodes, set members) are resolved after
//! the whole deck has been read, so nodes may follow the elements that use
//! them; a set name, however, must be defined before it is referenced.

use super::{ImportError, ImportedMaterial, ImportedMesh};
use crate::element::ElementKind;
use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::path::{Path, PathBuf};

const MAX_INCLUDE_DEPTH: usize = 16;

/// Keywords that are skipped together with their data lines (analysis
/// definitions, output requests, things that do not change the mesh or
/// the linear elastic material model).
const SKIPPED: &[&str] = &[
    "HEADING",
    "PREPRINT",
    "BOUNDARY",
    "CLOAD",
    "DLOAD",
    "DSLOAD",
    "NODE PRINT",
    "EL PRINT",
    "NODE FILE",
    "EL FILE",
    "NODE OUTPUT",
    "ELEMENT OUTPUT",
    "OUTPUT",
    "CONTACT PRINT",
    "STATIC",
    "FREQUENCY",
    "BUCKLE",
    "RIGID BODY",
    "AMPLITUDE",
    "SURFACE",
    "INITIAL CONDITIONS",
    "PHYSICAL CONSTANTS",
    "RESTART",
    "TEMPERATURE",
    "END STEP",
    // material options irrelevant to linear elastic stiffness and mass
    "EXPANSION",
    "CONDUCTIVITY",
    "SPECIFIC HEAT",
    "PLASTIC",
];

/// Material options: they do not end the current `*MATERIAL` block.
const MATERIAL_OPTIONS: &[&str] = &["ELASTIC", "DENSITY", "EXPANSION", "CONDUCTIVITY", "SPECIFIC HEAT", "PLASTIC"];

/// Whether an element type is a surface (plane, axisymmetric, shell, membrane) or line (truss,
/// beam) element of Abaqus/CalculiX: "surface", "line", or None for any other type. These are
/// what Gmsh writes beside the volume when "save all elements" is on.
fn lower_dimensional(name: &str) -> Option<&'static str> {
    let n = name.to_ascii_uppercase();
    let starts = |prefixes: &[&str]| prefixes.iter().any(|p| n.starts_with(p));
    // shells: S3, S3R, S4, S4R, S6, S8, S8R, S9R5 (and STRI3, STRI65 below)
    let shell = n.len() >= 2 && n.starts_with('S') && n.as_bytes()[1].is_ascii_digit();
    if shell || starts(&["CPS", "CPE", "CAX", "M3D", "STRI", "DC2D"]) {
        Some("surface")
    } else if starts(&["T2D", "T3D", "B21", "B22", "B23", "B31", "B32", "B33"]) {
        Some("line")
    } else {
        None
    }
}

/// Reads an Abaqus/CalculiX input deck.
pub fn read_inp(path: &Path) -> Result<ImportedMesh, ImportError> {
    let text = super::read_text(path)?;
    parse_inp(&text, path)
}

/// Parses the text of an input deck; `path` is used for error messages and
/// as the base directory of `*INCLUDE` files.
pub fn parse_inp(text: &str, path: &Path) -> Result<ImportedMesh, ImportError> {
    let mut files = vec![path.to_path_buf()];
    let mut lines = Vec::new();
    collect_lines(text, 0, &mut files, &mut lines, 0)?;
    Parser::new(files).run(&lines)
}

#[derive(Debug, Clone, Copy)]
struct Loc {
    file: usize,
    line: usize,
}

struct Line {
    loc: Loc,
    text: String,
}

fn is_keyword(text: &str) -> bool {
    text.starts_with('*') && !text.starts_with("**")
}

struct Keyword {
    name: String,
    params: Vec<(String, String)>,
    loc: Loc,
}

impl Keyword {
    fn parse(text: &str, loc: Loc) -> Keyword {
        let mut parts = text[1..].split(',');
        let name = normalize(parts.next().unwrap_or(""));
        let params = parts
            .map(str::trim)
            .filter(|p| !p.is_empty())
            .map(|p| match p.split_once('=') {
                Some((k, v)) => (normalize(k), v.trim().trim_matches('"').trim().to_string()),
                None => (normalize(p), String::new()),
            })
            .collect();
        Keyword { name, params, loc }
    }

    fn param(&self, key: &str) -> Option<&str> {
        self.params.iter().find(|(k, _)| k == key).map(|(_, v)| v.as_str())
    }
}

/// Upper-cases and collapses internal whitespace ("solid  section" ->
/// "SOLID SECTION").
fn normalize(s: &str) -> String {
    s.split_whitespace().collect::<Vec<_>>().join(" ").to_ascii_uppercase()
}

/// Collects the significant lines (no blanks, no `**` comments) of a file,
/// expanding `*INCLUDE` recursively.
fn collect_lines(
    text: &str,
    file: usize,
    files: &mut Vec<PathBuf>,
    out: &mut Vec<Line>,
    depth: usize,
) -> Result<(), ImportError> {
    for (i, raw) in text.lines().enumerate() {
        let t = raw.trim();
        if t.is_empty() || t.starts_with("**") {
            continue;
        }
        let loc = Loc { file, line: i + 1 };
        if is_keyword(t) {
            let kw = Keyword::parse(t, loc);
            if kw.name == "INCLUDE" {
                let err = |msg: String| ImportError::new(files[file].clone(), loc.line, msg);
                let input = match kw.param("INPUT") {
                    Some(v) if !v.is_empty() => v.to_string(),
                    _ => return Err(err("*INCLUDE requires an INPUT= parameter".into())),
                };
                if depth >= MAX_INCLUDE_DEPTH {
                    return Err(err(format!(
                        "*INCLUDE nested more than {MAX_INCLUDE_DEPTH} levels deep (recursive include?)"
                    )));
                }
                let target = Path::new(&input);
                let target = if target.is_absolute() {
                    target.to_path_buf()
                } else {
                    files[file].parent().unwrap_or(Path::new("")).join(target)
                };
                let sub = super::read_text(&target).map_err(|e| {
                    err(format!("cannot read included file {}: {}", target.display(), e.message)).caused_by(e)
                })?;
                files.push(target);
                let idx = files.len() - 1;
                collect_lines(&sub, idx, files, out, depth + 1)?;
                continue;
            }
        }
        out.push(Line { loc, text: t.to_string() });
    }
    Ok(())
}

struct PendingElement {
    id: u64,
    nodes: Vec<u64>,
    loc: Loc,
}

#[derive(Clone, Copy, PartialEq, Eq)]
enum SetKind {
    Node,
    Element,
}

impl SetKind {
    fn keyword(self) -> &'static str {
        match self {
            SetKind::Node => "NSET",
            SetKind::Element => "ELSET",
        }
    }
    fn what(self) -> &'static str {
        match self {
            SetKind::Node => "node",
            SetKind::Element => "element",
        }
    }
}

enum SetItem {
    Id(u64),
    Range(u64, u64, u64),
    Name(String),
}

/// Sets by name, their members as indices.
type Sets = BTreeMap<String, BTreeSet<usize>>;

struct SetOp {
    kind: SetKind,
    name: String,
    items: Vec<(SetItem, Loc)>,
}

struct Parser {
    files: Vec<PathBuf>,
    nodes: Vec<[f64; 3]>,
    node_ids: Vec<u64>,
    node_locs: Vec<Loc>,
    node_index: HashMap<u64, usize>,
    element_types: Vec<ElementKind>,
    elements: Vec<PendingElement>,
    element_index: HashMap<u64, usize>,
    set_ops: Vec<SetOp>,
    materials: Vec<ImportedMaterial>,
    material_locs: Vec<Loc>,
    elastic_seen: Vec<bool>,
    density_seen: Vec<bool>,
    sections: Vec<(String, String, Loc)>,
    /// Surface and line elements left out: count per type name, in the order met.
    skipped: Vec<(String, usize)>,
    /// Their ids: element sets may list them (Gmsh writes a set per physical group).
    skipped_ids: std::collections::HashSet<u64>,
}

type Res<T> = Result<T, ImportError>;

impl Parser {
    fn new(files: Vec<PathBuf>) -> Self {
        Parser {
            files,
            nodes: Vec::new(),
            node_ids: Vec::new(),
            node_locs: Vec::new(),
            node_index: HashMap::new(),
            element_types: Vec::new(),
            elements: Vec::new(),
            element_index: HashMap::new(),
            set_ops: Vec::new(),
            materials: Vec::new(),
            material_locs: Vec::new(),
            elastic_seen: Vec::new(),
            density_seen: Vec::new(),
            sections: Vec::new(),
            skipped: Vec::new(),
            skipped_ids: std::collections::HashSet::new(),
        }
    }

    fn err(&self, loc: Loc, msg: impl Into<String>) -> ImportError {
        ImportError::new(self.files[loc.file].clone(), loc.line, msg)
    }

    /// "file:line" of a location, for "first defined at" hints.
    fn where_(&self, loc: Loc) -> String {
        format!("{}:{}", self.files[loc.file].display(), loc.line)
    }

    fn run(mut self, lines: &[Line]) -> Res<ImportedMesh> {
        let mut i = 0;
        let mut current_material: Option<usize> = None;
        while i < lines.len() {
            let line = &lines[i];
            if !is_keyword(&line.text) {
                return Err(self.err(line.loc, "data line before the first keyword"));
            }
            let kw = Keyword::parse(&line.text, line.loc);
            let start = i + 1;
            let mut end = start;
            while end < lines.len() && !is_keyword(&lines[end].text) {
                end += 1;
            }
            let data = &lines[start..end];
            i = end;

            if kw.name != "MATERIAL" && !MATERIAL_OPTIONS.contains(&kw.name.as_str()) {
                current_material = None;
            }
            match kw.name.as_str() {
                "NODE" => self.node_block(&kw, data)?,
                "ELEMENT" => self.element_block(&kw, data)?,
                "NSET" => self.set_block(&kw, data, SetKind::Node)?,
                "ELSET" => self.set_block(&kw, data, SetKind::Element)?,
                "MATERIAL" => current_material = Some(self.material(&kw, data)?),
                "ELASTIC" => self.elastic(&kw, data, current_material)?,
                "DENSITY" => self.density(&kw, data, current_material)?,
                "SOLID SECTION" => self.solid_section(&kw)?,
                "STEP" => {
                    // Skip everything up to and including *END STEP.
                    while i < lines.len() {
                        let t = &lines[i].text;
                        i += 1;
                        if is_keyword(t) && Keyword::parse(t, lines[i - 1].loc).name == "END STEP" {
                            break;
                        }
                    }
                }
                name if SKIPPED.contains(&name) => {}
                "TRANSFORM" | "ORIENTATION" => {
                    return Err(self.err(
                        kw.loc,
                        format!(
                            "*{} is not supported: local coordinate systems cannot be honoured by the importer",
                            kw.name
                        ),
                    ));
                }
                "" => return Err(self.err(kw.loc, "empty keyword '*'")),
                _ => {
                    return Err(self.err(
                        kw.loc,
                        format!(
                            "unsupported keyword *{}: it may change the model in a way the importer cannot represent \
                             (supported: *NODE, *ELEMENT, *NSET, *ELSET, *MATERIAL, *ELASTIC, *DENSITY, \
                             *SOLID SECTION, *INCLUDE; analysis keywords and *STEP blocks are skipped)",
                            kw.name
                        ),
                    ));
                }
            }
        }
        self.finish()
    }

    /// The skipped elements in words: ("12 surface elements", "CPS6") or, with several kinds,
    /// ("14 surface and line elements", "CPS6: 12, T3D3: 2").
    fn skipped_summary(&self) -> Option<(String, String)> {
        let total: usize = self.skipped.iter().map(|(_, c)| c).sum();
        if self.skipped.is_empty() {
            return None;
        }
        let has = |d: &str| self.skipped.iter().any(|(n, _)| lower_dimensional(n) == Some(d));
        let kind = match (has("surface"), has("line")) {
            (true, true) => "surface and line",
            (false, true) => "line",
            _ => "surface",
        };
        let types = if self.skipped.len() == 1 {
            self.skipped[0].0.clone()
        } else {
            self.skipped.iter().map(|(n, c)| format!("{n}: {c}")).collect::<Vec<_>>().join(", ")
        };
        Some((format!("{total} {kind} element{}", if total == 1 { "" } else { "s" }), types))
    }

    fn check_params(&self, kw: &Keyword, allowed: &[&str]) -> Res<()> {
        for (k, v) in &kw.params {
            if !allowed.contains(&k.as_str()) {
                return Err(self.err(
                    kw.loc,
                    format!(
                        "*{}: unsupported parameter {} (supported: {})",
                        kw.name,
                        k,
                        if allowed.is_empty() { "none".to_string() } else { allowed.join(", ") }
                    ),
                ));
            }
            if v.is_empty() && k != "GENERATE" && k != "INTERNAL" && k != "UNSORTED" {
                return Err(self.err(kw.loc, format!("*{}: parameter {} needs a value", kw.name, k)));
            }
        }
        Ok(())
    }

    fn required<'k>(&self, kw: &'k Keyword, key: &str) -> Res<&'k str> {
        kw.param(key).ok_or_else(|| self.err(kw.loc, format!("*{} requires a {}= parameter", kw.name, key)))
    }

    fn parse_f64(&self, s: &str, loc: Loc, what: &str) -> Res<f64> {
        let t = s.trim();
        // Fortran-style exponents (1.0D3) are accepted.
        match t.replace(['d', 'D'], "e").parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(v),
            _ => Err(self.err(loc, format!("malformed number '{t}' for {what}"))),
        }
    }

    fn parse_id(&self, s: &str, loc: Loc, what: &str) -> Res<u64> {
        let t = s.trim();
        t.parse::<u64>().map_err(|_| self.err(loc, format!("malformed {what} '{t}' (expected a non-negative integer)")))
    }

    /// Splits a data line at commas; a trailing comma does not produce an
    /// empty field, an empty field elsewhere is an error.
    fn fields<'a>(&self, line: &'a Line) -> Res<Vec<&'a str>> {
        let mut f: Vec<&str> = line.text.split(',').map(str::trim).collect();
        while f.last().is_some_and(|s| s.is_empty()) {
            f.pop();
        }
        if f.iter().any(|s| s.is_empty()) {
            return Err(self.err(line.loc, "empty field in data line"));
        }
        Ok(f)
    }

    fn node_block(&mut self, kw: &Keyword, data: &[Line]) -> Res<()> {
        self.check_params(kw, &["NSET", "SYSTEM"])?;
        if let Some(sys) = kw.param("SYSTEM")
            && !sys.eq_ignore_ascii_case("R")
        {
            return Err(self.err(
                kw.loc,
                format!("*NODE, SYSTEM={sys} is not supported (only rectangular coordinates, SYSTEM=R)"),
            ));
        }
        let mut members = Vec::new();
        for line in data {
            let f = self.fields(line)?;
            if !(2..=4).contains(&f.len()) {
                return Err(self.err(
                    line.loc,
                    format!("*NODE data line needs a node id and up to 3 coordinates, got {} values", f.len()),
                ));
            }
            let id = self.parse_id(f[0], line.loc, "node id")?;
            let mut x = [0.0; 3];
            for (d, s) in f[1..].iter().enumerate() {
                x[d] = self.parse_f64(s, line.loc, &format!("coordinate {} of node {id}", d + 1))?;
            }
            if let Some(&first) = self.node_index.get(&id) {
                return Err(self.err(
                    line.loc,
                    format!("duplicate node id {id} (first defined at {})", self.where_(self.node_locs[first])),
                ));
            }
            self.node_index.insert(id, self.nodes.len());
            self.nodes.push(x);
            self.node_ids.push(id);
            self.node_locs.push(line.loc);
            members.push((SetItem::Id(id), line.loc));
        }
        if let Some(name) = kw.param("NSET") {
            self.set_ops.push(SetOp { kind: SetKind::Node, name: name.to_ascii_uppercase(), items: members });
        }
        Ok(())
    }

    fn element_block(&mut self, kw: &Keyword, data: &[Line]) -> Res<()> {
        self.check_params(kw, &["TYPE", "ELSET"])?;
        let tname = self.required(kw, "TYPE")?;
        if ElementKind::from_calculix_name(tname).is_none() && lower_dimensional(tname).is_some() {
            return self.skip_elements(kw, tname, data);
        }
        let ty = ElementKind::from_calculix_name(tname).ok_or_else(|| {
            self.err(
                kw.loc,
                format!(
                    "unsupported element type {} (supported: {})",
                    tname.to_ascii_uppercase(),
                    ElementKind::supported_names()
                ),
            )
        })?;
        let need = 1 + ty.nodes_per_element();
        let mut members = Vec::new();
        let mut k = 0;
        while k < data.len() {
            let first = &data[k];
            let mut tokens: Vec<(&str, Loc)> = self.fields(first)?.into_iter().map(|s| (s, first.loc)).collect();
            let mut last = first;
            k += 1;
            // Continuation: the previous line ends with a comma and the
            // record is not complete yet.
            while tokens.len() < need && last.text.ends_with(',') && k < data.len() {
                last = &data[k];
                tokens.extend(self.fields(last)?.into_iter().map(|s| (s, last.loc)));
                k += 1;
            }
            let Some(&(id_text, id_loc)) = tokens.first() else {
                return Err(self.err(first.loc, "empty element data line"));
            };
            let id = self.parse_id(id_text, id_loc, "element id")?;
            if tokens.len() != need {
                return Err(self.err(
                    first.loc,
                    format!(
                        "element {id}: type {} needs {} nodes, got {}",
                        ty.calculix_name(),
                        ty.nodes_per_element(),
                        tokens.len() - 1
                    ),
                ));
            }
            let mut nodes = Vec::with_capacity(ty.nodes_per_element());
            for &(s, loc) in &tokens[1..] {
                nodes.push(self.parse_id(s, loc, &format!("node id in element {id}"))?);
            }
            if let Some(&prev) = self.element_index.get(&id) {
                return Err(self.err(
                    first.loc,
                    format!("duplicate element id {id} (first defined at {})", self.where_(self.elements[prev].loc)),
                ));
            }
            self.element_index.insert(id, self.elements.len());
            self.elements.push(PendingElement { id, nodes, loc: first.loc });
            self.element_types.push(ty);
            members.push((SetItem::Id(id), first.loc));
        }
        if let Some(name) = kw.param("ELSET") {
            self.set_ops.push(SetOp { kind: SetKind::Element, name: name.to_ascii_uppercase(), items: members });
        }
        Ok(())
    }

    /// A block of surface or line elements (a Gmsh "save all elements" deck writes the
    /// boundary's triangles and the edges' lines beside the volume): they add no stiffness or
    /// mass to a solid model, so they are counted and left out, and their ids remembered for the
    /// element sets that list them. Without any volume element `finish` refuses the deck.
    fn skip_elements(&mut self, kw: &Keyword, tname: &str, data: &[Line]) -> Res<()> {
        let name = tname.to_ascii_uppercase();
        let mut count = 0;
        let mut continued = false;
        for line in data {
            // a record continues on the next line when its line ends with a comma (the node
            // count of a type the importer does not model is not known); the id is the first
            // field of the record's first line
            if !continued && let Some(first) = self.fields(line)?.first() {
                let id = self.parse_id(first, line.loc, "element id")?;
                self.skipped_ids.insert(id);
                count += 1;
            }
            continued = line.text.ends_with(',');
        }
        match self.skipped.iter_mut().find(|(n, _)| *n == name) {
            Some((_, c)) => *c += count,
            None => self.skipped.push((name, count)),
        }
        if let Some(set) = kw.param("ELSET") {
            // the set exists (a later *ELSET may name it), and holds no volume element
            self.set_ops.push(SetOp { kind: SetKind::Element, name: set.to_ascii_uppercase(), items: Vec::new() });
        }
        Ok(())
    }

    fn set_block(&mut self, kw: &Keyword, data: &[Line], kind: SetKind) -> Res<()> {
        let key = kind.keyword();
        self.check_params(kw, &[key, "GENERATE", "INTERNAL", "UNSORTED"])?;
        let name = self.required(kw, key)?.to_ascii_uppercase();
        let generate = kw.param("GENERATE").is_some();
        let mut items = Vec::new();
        for line in data {
            let f = self.fields(line)?;
            if generate {
                if !(2..=3).contains(&f.len()) {
                    return Err(self.err(
                        line.loc,
                        format!("*{key}, GENERATE expects 'start, end[, step]', got {} values", f.len()),
                    ));
                }
                let a = self.parse_id(f[0], line.loc, "GENERATE start")?;
                let b = self.parse_id(f[1], line.loc, "GENERATE end")?;
                let s = if f.len() == 3 { self.parse_id(f[2], line.loc, "GENERATE step")? } else { 1 };
                if s == 0 || b < a {
                    return Err(self.err(
                        line.loc,
                        format!("*{key}, GENERATE: invalid range {a}, {b}, {s} (need start <= end and step >= 1)"),
                    ));
                }
                items.push((SetItem::Range(a, b, s), line.loc));
            } else {
                for s in f {
                    let item = if let Ok(id) = s.parse::<u64>() {
                        SetItem::Id(id)
                    } else if s.starts_with(|c: char| c.is_ascii_alphabetic() || c == '_') {
                        SetItem::Name(s.to_ascii_uppercase())
                    } else {
                        return Err(self
                            .err(line.loc, format!("*{key} {name}: malformed {} id or set name '{s}'", kind.what())));
                    };
                    items.push((item, line.loc));
                }
            }
        }
        self.set_ops.push(SetOp { kind, name, items });
        Ok(())
    }

    fn material(&mut self, kw: &Keyword, data: &[Line]) -> Res<usize> {
        self.check_params(kw, &["NAME"])?;
        let name = self.required(kw, "NAME")?.to_ascii_uppercase();
        if let Some(line) = data.first() {
            return Err(self.err(line.loc, "unexpected data line after *MATERIAL"));
        }
        if let Some(i) = self.materials.iter().position(|m| m.name == name) {
            return Err(self.err(
                kw.loc,
                format!("duplicate material {name} (first defined at {})", self.where_(self.material_locs[i])),
            ));
        }
        self.materials.push(ImportedMaterial { name, ..Default::default() });
        self.material_locs.push(kw.loc);
        self.elastic_seen.push(false);
        self.density_seen.push(false);
        Ok(self.materials.len() - 1)
    }

    /// The single data line of a material option (temperature dependence,
    /// i.e. several lines, is rejected).
    fn single_data_line<'a>(&self, kw: &Keyword, data: &'a [Line], cur: Option<usize>) -> Res<(usize, &'a Line)> {
        let Some(m) = cur else {
            return Err(self.err(kw.loc, format!("*{} outside of a *MATERIAL definition", kw.name)));
        };
        match data {
            [] => Err(self.err(kw.loc, format!("*{} requires a data line", kw.name))),
            [line] => Ok((m, line)),
            [_, second, ..] => Err(self.err(
                second.loc,
                format!(
                    "temperature-dependent *{} ({} data lines) is not supported; give a single line",
                    kw.name,
                    data.len()
                ),
            )),
        }
    }

    fn elastic(&mut self, kw: &Keyword, data: &[Line], cur: Option<usize>) -> Res<()> {
        self.check_params(kw, &["TYPE"])?;
        if let Some(t) = kw.param("TYPE") {
            let t = normalize(t);
            if t != "ISO" && t != "ISOTROPIC" {
                return Err(self.err(kw.loc, format!("*ELASTIC, TYPE={t} is not supported (only TYPE=ISO)")));
            }
        }
        let (m, line) = self.single_data_line(kw, data, cur)?;
        if self.elastic_seen[m] {
            return Err(self.err(kw.loc, format!("material {} has more than one *ELASTIC", self.materials[m].name)));
        }
        let f = self.fields(line)?;
        if !(2..=3).contains(&f.len()) {
            return Err(self.err(line.loc, format!("*ELASTIC expects 'E, nu[, temperature]', got {} values", f.len())));
        }
        let e = self.parse_f64(f[0], line.loc, "Young's modulus")?;
        let nu = self.parse_f64(f[1], line.loc, "Poisson's ratio")?;
        if f.len() == 3 {
            self.parse_f64(f[2], line.loc, "temperature")?;
        }
        self.materials[m].e = Some(e);
        self.materials[m].nu = Some(nu);
        self.elastic_seen[m] = true;
        Ok(())
    }

    fn density(&mut self, kw: &Keyword, data: &[Line], cur: Option<usize>) -> Res<()> {
        self.check_params(kw, &[])?;
        let (m, line) = self.single_data_line(kw, data, cur)?;
        if self.density_seen[m] {
            return Err(self.err(kw.loc, format!("material {} has more than one *DENSITY", self.materials[m].name)));
        }
        let f = self.fields(line)?;
        if !(1..=2).contains(&f.len()) {
            return Err(self.err(line.loc, format!("*DENSITY expects 'rho[, temperature]', got {} values", f.len())));
        }
        let rho = self.parse_f64(f[0], line.loc, "density")?;
        if f.len() == 2 {
            self.parse_f64(f[1], line.loc, "temperature")?;
        }
        self.materials[m].rho = Some(rho);
        self.density_seen[m] = true;
        Ok(())
    }

    fn solid_section(&mut self, kw: &Keyword) -> Res<()> {
        // Data lines (optional thickness for plane elements) are ignored.
        self.check_params(kw, &["ELSET", "MATERIAL", "CONTROLS"])?;
        let elset = self.required(kw, "ELSET")?.to_ascii_uppercase();
        let material = self.required(kw, "MATERIAL")?.to_ascii_uppercase();
        self.sections.push((elset, material, kw.loc));
        Ok(())
    }

    fn finish(self) -> Res<ImportedMesh> {
        let notes = self.skipped_notes()?;
        let connectivity = self.connectivity()?;
        let (node_sets, element_sets) = self.sets()?;
        let sections = self.sections(&element_sets)?;
        Ok(ImportedMesh {
            nodes: self.nodes,
            node_ids: self.node_ids,
            element_types: self.element_types,
            connectivity,
            element_ids: self.elements.iter().map(|e| e.id).collect(),
            node_sets: node_sets.into_iter().map(|(k, v)| (k, v.into_iter().collect())).collect(),
            element_sets: element_sets.into_iter().map(|(k, v)| (k, v.into_iter().collect())).collect(),
            materials: self.materials,
            sections,
            notes,
        })
    }

    /// A note on the surface and line elements skipped; an error where nothing else is left.
    fn skipped_notes(&self) -> Res<Vec<String>> {
        let file = self.files[0].display().to_string();
        Ok(match self.skipped_summary() {
            Some((what, types)) if self.elements.is_empty() => {
                return Err(ImportError::new(
                    &self.files[0],
                    0,
                    format!(
                        "no volume elements, only {what} ({types}): the builder needs the solid's volume elements \
                         (supported: {}); export only volume elements (Gmsh: mesh in 3D, uncheck 'save all elements' \
                         / use physical groups of the volume)",
                        ElementKind::supported_names()
                    ),
                ));
            }
            Some((what, types)) => vec![format!(
                "skipped {what} ({types}) of {file}: export only volume elements (Gmsh: uncheck 'save all elements' \
                 / use physical groups of the volume)"
            )],
            None => Vec::new(),
        })
    }

    /// Every element's nodes as indices into the node list.
    fn connectivity(&self) -> Res<Vec<Vec<usize>>> {
        let mut connectivity = Vec::with_capacity(self.elements.len());
        for e in &self.elements {
            let conn = e
                .nodes
                .iter()
                .map(|id| {
                    self.node_index
                        .get(id)
                        .copied()
                        .ok_or_else(|| self.err(e.loc, format!("element {} references undefined node {id}", e.id)))
                })
                .collect::<Res<Vec<usize>>>()?;
            connectivity.push(conn);
        }
        Ok(connectivity)
    }

    /// The node and element sets, by name: `*NSET` and `*ELSET` resolved in file order.
    fn sets(&self) -> Res<(Sets, Sets)> {
        let mut node_sets: BTreeMap<String, BTreeSet<usize>> = BTreeMap::new();
        let mut element_sets: BTreeMap<String, BTreeSet<usize>> = BTreeMap::new();
        for op in &self.set_ops {
            let (sets, index) = match op.kind {
                SetKind::Node => (&mut node_sets, &self.node_index),
                SetKind::Element => (&mut element_sets, &self.element_index),
            };
            let members = self.set_members(op, sets, index)?;
            sets.entry(op.name.clone()).or_default().extend(members);
        }
        Ok((node_sets, element_sets))
    }

    /// The members of one `*NSET` or `*ELSET`: ids, generated ranges and the sets named before.
    fn set_members(&self, op: &SetOp, sets: &Sets, index: &HashMap<u64, usize>) -> Res<BTreeSet<usize>> {
        let mut members = BTreeSet::new();
        let lookup = |id: u64, loc: Loc| {
            index.get(&id).copied().ok_or_else(|| {
                self.err(loc, format!("*{} {}: {} {id} is not defined", op.kind.keyword(), op.name, op.kind.what()))
            })
        };
        // skipped surface and line elements leave the sets that list them
        let skipped = |id: u64| op.kind == SetKind::Element && self.skipped_ids.contains(&id);
        for (item, loc) in &op.items {
            match item {
                SetItem::Id(id) if skipped(*id) => {}
                SetItem::Id(id) => {
                    members.insert(lookup(*id, *loc)?);
                }
                SetItem::Range(a, b, s) => {
                    let mut id = *a;
                    while id <= *b {
                        if !skipped(id) {
                            members.insert(lookup(id, *loc)?);
                        }
                        id = match id.checked_add(*s) {
                            Some(v) => v,
                            None => break,
                        };
                    }
                }
                SetItem::Name(n) => match sets.get(n) {
                    Some(s) => members.extend(s.iter().copied()),
                    None => {
                        return Err(self.err(
                            *loc,
                            format!(
                                "*{} {}: references undefined {} set {n}",
                                op.kind.keyword(),
                                op.name,
                                op.kind.what()
                            ),
                        ));
                    }
                },
            }
        }
        Ok(members)
    }

    /// The `*SOLID SECTION`s, their element sets and materials defined.
    fn sections(&self, element_sets: &Sets) -> Res<Vec<(String, String)>> {
        let mut sections = Vec::with_capacity(self.sections.len());
        for (elset, material, loc) in &self.sections {
            if !element_sets.contains_key(elset) {
                return Err(self.err(*loc, format!("*SOLID SECTION: element set {elset} is not defined")));
            }
            if !self.materials.iter().any(|m| &m.name == material) {
                return Err(self.err(*loc, format!("*SOLID SECTION: material {material} is not defined")));
            }
            sections.push((elset.clone(), material.clone()));
        }
        Ok(sections)
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_util::assert_midsides_at_midpoints;
    use super::*;

    /// Grid nodes for two unit cubes side by side along x, spacing 0.5:
    /// id(i, j, k) = 1 + i + 5 j + 15 k, i in 0..5, j, k in 0..3.
    fn grid_nodes() -> String {
        let mut s = String::new();
        for k in 0..3 {
            for j in 0..3 {
                for i in 0..5 {
                    let id = 1 + i + 5 * j + 15 * k;
                    s += &format!("{id}, {}, {}, {}\n", 0.5 * i as f64, 0.5 * j as f64, 0.5 * k as f64);
                }
            }
        }
        s
    }

    fn two_hex20_deck() -> String {
        format!(
            "*Heading
 two C3D20 elements
** a comment line

*Node, nset=Nall
{}
*element, Type=c3d20, ELSET=Eone
** element 1: corners then midsides, continued after 16 numbers
1, 1, 3, 13, 11, 31, 33, 43, 41, 2, 8, 12, 6, 32, 38, 42,
36, 16, 18, 28, 26
*ELEMENT, TYPE=C3D20R, ELSET=ETWO
2, 3, 5, 15, 13, 33, 35, 45, 43, 4, 10, 14, 8, 34, 40, 44,
   38, 18, 20, 30, 28
*nset, nset=Fix, generate
1, 41, 5
*NSET,NSET=both
fix, 45
*Elset, Elset = AllEl
eone, ETWO
*MATERIAL, NAME=steel
*ELASTIC
210000., 0.3
*Density
7.85e-9
*Solid Section, elset=ALLEL, material=STEEL

*STEP
*STATIC
*BOUNDARY
FIX, 1, 3
*CLOAD
45, 1, 100.
*NODE FILE
U
*END STEP
",
            grid_nodes()
        )
    }

    #[test]
    fn parses_two_element_c3d20_deck() {
        let m = parse_inp(&two_hex20_deck(), Path::new("deck.inp")).unwrap();
        assert_eq!(m.nodes.len(), 45);
        assert_eq!(m.node_ids[44], 45);
        assert_eq!(m.nodes[44], [2.0, 1.0, 1.0]);
        assert_eq!(m.element_types, vec![ElementKind::Hex20, ElementKind::Hex20R]);
        assert_eq!(m.element_ids, vec![1, 2]);
        assert_eq!(m.connectivity[0].len(), 20);
        assert_eq!(m.connectivity[0][15], 35); // node id 36
        assert_eq!(m.connectivity[0][19], 25); // node id 26
        assert_eq!(m.connectivity[1][19], 27); // node id 28
        assert_midsides_at_midpoints(&m);

        let fix: Vec<usize> = (0..9).map(|n| n * 5).collect();
        assert_eq!(m.node_sets["FIX"], fix);
        let mut both = fix.clone();
        both.push(44);
        assert_eq!(m.node_sets["BOTH"], both);
        assert_eq!(m.node_sets["NALL"].len(), 45);
        assert_eq!(m.element_sets["EONE"], vec![0]);
        assert_eq!(m.element_sets["ETWO"], vec![1]);
        assert_eq!(m.element_sets["ALLEL"], vec![0, 1]);
        assert_eq!(
            m.materials,
            vec![ImportedMaterial { name: "STEEL".into(), e: Some(210000.0), nu: Some(0.3), rho: Some(7.85e-9) }]
        );
        assert_eq!(m.sections, vec![("ALLEL".to_string(), "STEEL".to_string())]);
    }

    #[test]
    fn include_is_relative_to_including_file() {
        let dir = std::env::temp_dir().join(format!("inp-include-test-{}", std::process::id()));
        std::fs::create_dir_all(dir.join("sub")).unwrap();
        std::fs::write(dir.join("sub/nodes.inp"), "*NODE\n1,0,0,0\n2,1,0,0\n3,0,1,0\n4,0,0,1\n").unwrap();
        std::fs::write(dir.join("sub/bad.inp"), "*NODE\n1,0,0,0\n\n1,1,0,0\n").unwrap();
        std::fs::write(dir.join("main.inp"), "*INCLUDE, INPUT=sub/nodes.inp\n*ELEMENT, TYPE=C3D4\n1, 1, 2, 3, 4\n")
            .unwrap();
        std::fs::write(dir.join("bad.inp"), "**\n*INCLUDE, INPUT=sub/bad.inp\n").unwrap();
        std::fs::write(dir.join("missing.inp"), "**\n**\n*INCLUDE, INPUT=nope.inp\n").unwrap();
        let m = read_inp(&dir.join("main.inp")).unwrap();
        assert_eq!(m.connectivity, vec![vec![0, 1, 2, 3]]);

        let e = read_inp(&dir.join("bad.inp")).unwrap_err();
        assert_eq!((e.file.clone(), e.line), (dir.join("sub/bad.inp"), 4), "{e}");
        let e = read_inp(&dir.join("missing.inp")).unwrap_err();
        assert_eq!((e.file.clone(), e.line), (dir.join("missing.inp"), 3), "{e}");
        assert!(e.message.contains("nope.inp"), "{e}");
        std::fs::remove_dir_all(&dir).ok();
    }

    const TET: &str = "*NODE\n1, 0, 0, 0\n2, 1, 0, 0\n3, 0, 1, 0\n4, 0, 0, 1\n";

    fn err(text: &str) -> ImportError {
        parse_inp(text, Path::new("bad.inp")).unwrap_err()
    }

    /// Asserts the error is on `line` and its message contains all `parts`.
    fn check(text: &str, line: usize, parts: &[&str]) {
        let e = err(text);
        assert_eq!(e.line, line, "wrong line for: {e}");
        for p in parts {
            assert!(e.message.contains(p), "message lacks '{p}': {e}");
        }
        assert!(e.to_string().starts_with(&format!("bad.inp:{line}: ")), "{e}");
    }

    #[test]
    fn error_unknown_element_type() {
        check(
            &format!("{TET}** wedge\n*ELEMENT, TYPE=C3D15\n1, 1, 2, 3, 4\n"),
            7,
            &["unsupported element type C3D15", "C3D4, C3D10, C3D8, C3D20, C3D20R"],
        );
    }

    /// Gmsh's "save all elements" writes the boundary's triangles and the edges' lines beside
    /// the volume: they are left out with a note, and the element sets listing them lose them.
    #[test]
    fn surface_and_line_elements_are_skipped_beside_volume_elements() {
        let deck = format!(
            "{TET}*ELEMENT, type=CPS6, ELSET=Surface1\n7, 1, 2, 3, 1, 2, 3\n8, 1, 2, 4, 1, 2, 4\n\
             *ELEMENT, type=T3D2, ELSET=Line1\n9, 1, 2\n\
             *ELEMENT, type=C3D4, ELSET=Volume1\n1, 1, 2, 3, 4\n\
             *ELSET, ELSET=Physical\n7, 8, 1\n*ELSET, ELSET=Edges\n9\n"
        );
        let m = parse_inp(&deck, Path::new("saveall.inp")).unwrap();
        assert_eq!(m.element_types, vec![ElementKind::Tet4]);
        assert_eq!(m.element_sets["PHYSICAL"], vec![0]);
        assert!(m.element_sets["EDGES"].is_empty() && m.element_sets["SURFACE1"].is_empty());
        assert_eq!(
            m.notes,
            vec![
                "skipped 3 surface and line elements (CPS6: 2, T3D2: 1) of saveall.inp: export only volume elements \
                 (Gmsh: uncheck 'save all elements' / use physical groups of the volume)"
            ]
        );
        let one = parse_inp(
            &format!("{TET}*ELEMENT, TYPE=C3D4\n1, 1, 2, 3, 4\n*ELEMENT, TYPE=S4R\n2, 1, 2, 3, 4\n"),
            Path::new("a.inp"),
        );
        assert!(one.unwrap().notes[0].starts_with("skipped 1 surface element (S4R) of a.inp: "));
    }

    #[test]
    fn a_deck_of_surface_elements_only_is_refused_with_the_way_out() {
        // the whole file is meant (line 0)
        let e = err(&format!("{TET}** shell\n*ELEMENT, TYPE=S4R\n1, 1, 2, 3, 4\n*ELEMENT, TYPE=T3D2\n2, 1, 2\n"));
        assert_eq!(e.line, 0, "{e}");
        for part in
            ["no volume elements, only 2 surface and line elements (S4R: 1, T3D2: 1)", "C3D4", "save all elements"]
        {
            assert!(e.to_string().starts_with("bad.inp: ") && e.message.contains(part), "{e}");
        }
    }

    #[test]
    fn error_missing_node() {
        check(
            &format!("{TET}*ELEMENT, TYPE=C3D4\n1, 1, 2, 3, 4\n2, 1, 2, 3, 9\n"),
            8,
            &["element 2", "undefined node 9"],
        );
    }

    #[test]
    fn error_duplicate_node() {
        check(&format!("{TET}\n*NODE\n5, 1, 1, 1\n2, 1, 1, 1\n"), 9, &["duplicate node id 2", "bad.inp:3"]);
    }

    #[test]
    fn error_duplicate_element() {
        check(
            &format!("{TET}*ELEMENT, TYPE=C3D4\n1, 1, 2, 3, 4\n*ELEMENT, TYPE=C3D4\n1, 4, 3, 2, 1\n"),
            9,
            &["duplicate element id 1", "bad.inp:7"],
        );
    }

    #[test]
    fn error_set_references_undefined_set() {
        check(&format!("{TET}*NSET, NSET=A\n1, 2\n*NSET, NSET=B\nA,\nC\n"), 10, &["undefined node set C"]);
    }

    #[test]
    fn error_set_references_undefined_id() {
        check(&format!("{TET}*NSET, NSET=A\n1, 2\n3, 7\n"), 8, &["node 7 is not defined"]);
        check(&format!("{TET}*NSET, NSET=A, GENERATE\n1, 5\n"), 7, &["node 5 is not defined"]);
        check(
            &format!("{TET}*ELEMENT, TYPE=C3D4\n1, 1, 2, 3, 4\n*ELSET, ELSET=E\n1,\n2\n"),
            10,
            &["element 2 is not defined"],
        );
    }

    #[test]
    fn error_malformed_numbers() {
        check("*NODE\n1, 0, 0, 0\n2, 1.0.0, 0, 0\n", 3, &["malformed number '1.0.0'"]);
        check("*NODE\n1, 0, 0, 0\nx2, 1, 0, 0\n", 3, &["malformed node id 'x2'"]);
        check(&format!("{TET}*ELEMENT, TYPE=C3D4\n1, 1, 2, 3.5, 4\n"), 7, &["malformed node id in element 1 '3.5'"]);
        check("*MATERIAL, NAME=M\n*ELASTIC\n2e5, abc\n", 3, &["malformed number 'abc'"]);
    }

    #[test]
    fn error_wrong_node_count() {
        check(&format!("{TET}*ELEMENT, TYPE=C3D10\n1, 1, 2, 3, 4\n"), 7, &["C3D10 needs 10 nodes, got 4"]);
        check(&format!("{TET}*ELEMENT, TYPE=C3D4\n,\n"), 7, &["empty element data line"]);
        // C3D20 record continued over two lines but one node short
        check(
            &format!("{TET}*ELEMENT, TYPE=C3D20\n\n7, 1, 2, 3, 4, 1, 2, 3, 4, 1, 2, 3, 4, 1, 2, 3,\n4, 1, 2, 3\n"),
            8,
            &["element 7", "C3D20 needs 20 nodes, got 19"],
        );
    }

    #[test]
    fn error_unsupported_keywords_and_options() {
        check(&format!("{TET}*TRANSFORM, NSET=A\n1,0,0,0,1,0\n"), 6, &["*TRANSFORM"]);
        check("*HEADING\nx\n*EQUATION\n2\n1,1,1.,2,1,-1.\n", 3, &["unsupported keyword *EQUATION"]);
        check("*MATERIAL, NAME=M\n*ELASTIC, TYPE=ORTHO\n1,2,3,4,5,6,7,8,9\n", 2, &["TYPE=ORTHO", "ISO"]);
        check("*MATERIAL, NAME=M\n*ELASTIC\n2e5, 0.3, 20\n1e5, 0.3, 500\n", 4, &["temperature-dependent"]);
        check("*NODE, SYSTEM=C\n1, 1, 0, 0\n", 1, &["SYSTEM=C"]);
        check("*ELASTIC\n2e5, 0.3\n", 1, &["outside of a *MATERIAL"]);
        check(
            &format!("{TET}*ELEMENT, TYPE=C3D4, ELSET=E\n1,1,2,3,4\n*SOLID SECTION, ELSET=E, MATERIAL=X\n"),
            8,
            &["material X is not defined"],
        );
        check("*MATERIAL, NAME=M\n*SOLID SECTION, ELSET=E, MATERIAL=M\n", 2, &["element set E is not defined"]);
    }

    #[test]
    fn step_blocks_and_analysis_keywords_are_skipped() {
        let deck = format!(
            "{TET}*BOUNDARY\n1, 1, 3\n*ELEMENT, TYPE=C3D4\n1, 1, 2, 3, 4\n*STEP, NLGEOM\n*FREQUENCY\n10\n\
             *EQUATION\nthis would be an error outside a step\n*END STEP\n*STEP\n*STATIC\n*END STEP\n"
        );
        let m = parse_inp(&deck, Path::new("ok.inp")).unwrap();
        assert_eq!(m.connectivity.len(), 1);
        assert!(m.materials.is_empty());
    }
}
