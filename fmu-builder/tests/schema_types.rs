//! The input's JSON schema (what editors check while the user types) and the builder's own types
//! and limits (what the build accepts) must say the same: a field the schema offers that the
//! types refuse, a limit the schema allows that the builder refuses (once `reduction.modes <=
//! 2000` in the schema against 1000 in the builder), or an enum value one side lacks, leaves a
//! user with an input that validates and fails, or the reverse.
//!
//! Base inputs below use every field of the schema (checked: a field they miss fails the test).
//! For every field with a numeric or length bound, the value at the bound (or just inside an
//! exclusive one) and just beyond it are put to both the schema and the builder's input check
//! (`Spec::from_str`, all that `fmu-builder` checks before meshing, or `AssemblySpec::from_str`
//! for an assembly), and their verdicts must agree; for every enum, every value and one that is
//! not. An assembly's inline body is the body input's own form (the schema's `"$ref": "#"`), its
//! fields covered by the body documents: the walks below stop there.

use fmu_builder::input::assembly::{AssemblySpec, json::AssemblyFile};
use fmu_builder::input::ranges;
use fmu_builder::input::spec::{MAX_MODES, SCHEMA, Spec};
use serde_json::{Value, json};
use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// Inputs that together use every property of the schema, each valid on its own (the first one
/// path of each kind in a document is the one varied: the other occurrences may have neighbours,
/// a second flange's role, that make a value wrong for reasons beyond the field itself).
fn base_documents() -> Vec<Value> {
    let boxes = json!({
        "$schema": "../schemas/fmu-builder-input.schema.json",
        "name": "Beam",
        "description": "every field of boxes, flanges, scene, outputs",
        "geometry": {
            "element": "hex20",
            "boxes": [{"min": [0.0, 0.0, 0.0], "max": [1.0, 0.01, 0.02], "elements": [10, 1, 1]}],
            "length_unit": "m"
        },
        "material": {"E": 2e11, "nu": 0.3, "rho": 7850.0},
        "damping": {"alpha": 1.0, "beta": 1e-3, "modal_ratio": 0.01},
        "flanges": [
            {"name": "base", "role": "motion", "coupling": "rigid", "reference_point": [0.0, 0.0, 0.0],
             "nodes": {"box_face": {"box": 0, "face": "-x"}}},
            {"name": "tip", "role": "force", "coupling": "distributing", "weights": "area",
             "nodes": {"plane": {"point": [1.0, 0.0, 0.0], "normal": [1.0, 0.0, 0.0], "tolerance": 1e-6}}},
            {"name": "s", "role": "force", "nodes": {"sphere": {"center": [0.5, 0.0, 0.0], "radius": 0.001}}},
            {"name": "c", "role": "force",
             "nodes": {"cylinder": {"point": [0.3, 0.0, 0.0], "axis": [1.0, 0.0, 0.0], "radius": 0.001, "length": 0.01}}},
            {"name": "b", "role": "force", "nodes": {"box": {"min": [0.7, -1.0, -1.0], "max": [0.71, 1.0, 1.0]}}},
            {"name": "n", "role": "force", "nodes": {"node_set": "SET"}}
        ],
        "scene": {"loads": ["gravity"], "geometric_stiffening": false, "band": [0.0, 100.0], "tolerance": 1e-3,
                  "connected": ["tip", "s", "c", "b", "n"]},
        "reduction": {"method": "craig_bampton", "modes": 4, "dynamic_cutoff": 1000.0},
        "outputs": {"stress": {"node_sets": ["SET"], "points": [[0.5, 0.0, 0.0]], "hot_spots": 1}},
        "experiment": {"stop_time": 1.0, "tolerance": 1e-6}
    });
    let mesh = json!({
        "name": "Bracket",
        "geometry": {"mesh": "part.inp", "length_unit": "mm"},
        "materials": {"STEEL": {"E": 2e11, "nu": 0.3, "rho": 7850.0}},
        "damping": {"modal_bands": [{"below": 100.0, "ratio": 0.02}]},
        "flanges": [{"name": "base", "role": "motion", "nodes": {"node_set": "BASE"}}],
        "reduction": {"method": "modal", "max_frequency": 500.0},
        "experiment": {"step_size": 1e-3}
    });
    let krylov = json!({
        "name": "K",
        "geometry": {"boxes": [{"min": [0.0, 0.0, 0.0], "max": [1.0, 0.01, 0.02], "elements": [10, 1, 1]}]},
        "material": {"E": 2e11, "nu": 0.3, "rho": 7850.0},
        "flanges": [{"name": "base", "role": "motion", "nodes": {"box_face": {"box": 0, "face": "-x"}}}],
        "reduction": {"method": "krylov", "expansion_points": [0.0, 100.0], "moments": 2,
                      "real_expansion_points": [10.0]}
    });
    let petsc = json!({
        "name": "P",
        "geometry": {"matrices": {"stiffness": "K.mtx", "mass": "M.mtx", "damping": "D.mtx", "dofs": "dofs.txt",
                                  "nodes": "nodes.txt", "free_free": true}},
        "flanges": [{"name": "base", "role": "motion", "nodes": {"node_set": "BASE"}}],
        "reduction": {"modes": 2, "backend": {"kind": "petsc", "ranks": 2, "launcher": "mpirun", "python": "python3",
                      "host": "127.0.0.1", "job_folder": "jobs", "partitioner": "ptscotch", "connect_timeout": 30.0}}
    });
    let mut docs = vec![boxes, mesh, krylov, petsc];
    docs.extend(assembly_documents());
    docs
}

/// A rigid body's mass properties with the flanges `names`.
fn rigid(names: &[&str]) -> Value {
    let flanges: Vec<Value> = names.iter().map(|n| json!({"name": n, "position": [0.0, 0.0, 0.0]})).collect();
    json!({"mass": 1.0, "centre_of_mass": [0.1, 0.0, 0.0], "inertia": [1.0, 1.0, 1.0, 0.0, 0.0, 0.0], "flanges": flanges})
}

/// Assemblies that together use every field of the assembly form. Where a document's first joint
/// or first external flange takes another value of its enum, the counts of degrees of freedom
/// leave room for it (each enum value builds in one of them, the others are refused by both for
/// the form, not the count).
fn assembly_documents() -> Vec<Value> {
    let link = json!({
        "name": "Link",
        "geometry": {"element": "hex8", "boxes": [{"min": [0.0, 0.0, 0.0], "max": [1.0, 0.01, 0.02], "elements": [10, 1, 1]}]},
        "material": {"E": 2e11, "nu": 0.3, "rho": 7850.0},
        "flanges": [
            {"name": "base", "role": "motion", "nodes": {"box_face": {"box": 0, "face": "-x"}}},
            {"name": "tip", "role": "force", "nodes": {"box_face": {"box": 0, "face": "+x"}}}
        ],
        "reduction": {"modes": 2}
    });
    // a flexible link hinged to the ground, a rigid crank on a ball joint at its tip, and a free
    // rigid body the host holds (a force and a motion flange at the same place)
    let full = json!({
        "$schema": "../schemas/fmu-builder-input.schema.json",
        "name": "Arm",
        "description": "every field of the assembly form but the drives",
        "assembly": {
            "gravity": [0.0, 0.0, -9.81],
            "bodies": [
                {"name": "upper", "flexible": link, "position": [0.0, 0.0, 0.0], "rotation": {"axis": [0.0, 1.0, 0.0], "angle": 45.0}},
                {"name": "crank", "rigid": rigid(&["centre", "pin"]), "position": [0.7, 0.0, -0.7]},
                {"name": "free", "rigid": rigid(&["f"])}
            ],
            "joints": [
                {"name": "pivot", "type": "revolute", "between": ["ground", "upper.base"], "axis": [0.0, 1.0, 0.0]},
                {"name": "elbow", "type": "spherical", "between": ["upper.tip", "crank.centre"]},
                {"name": "cardan", "type": "universal", "between": ["crank.pin", "ground"], "axes": [[0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]}
            ],
            "flanges": [{"name": "load", "role": "force", "at": "free.f"}, {"name": "mount", "role": "motion", "at": "free.f"}],
            "solver": {"spectral_radius": 0.8, "tolerance": 1e-9, "max_iterations": 12, "max_step": 0.0005}
        },
        "experiment": {"stop_time": 2.0, "tolerance": 1e-6}
    });
    let mut docs = vec![full];
    // a chain of rigid bodies each held to the ground by one joint: `joints` the first joint of
    // each document (every type first once), then one per drive quantity and function
    let chain = |first: Value, more: &[Value]| {
        let joints: Vec<Value> = std::iter::once(&first)
            .chain(more)
            .enumerate()
            .map(|(i, j)| {
                let mut j = j.clone();
                j["name"] = json!(format!("j{i}"));
                j["between"] = json!(["ground", format!("b{i}.f")]);
                j
            })
            .collect();
        let bodies: Vec<Value> =
            (0..joints.len()).map(|i| json!({"name": format!("b{i}"), "rigid": rigid(&["f"])})).collect();
        json!({"name": "Chain", "assembly": {"bodies": bodies, "joints": joints}})
    };
    for first in [
        json!({"type": "weld"}),
        json!({"type": "prismatic", "axis": [1.0, 0.0, 0.0]}),
        json!({"type": "spherical"}),
        json!({"type": "universal", "axes": [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]}),
    ] {
        docs.push(chain(first, &[]));
    }
    let functions = [
        json!({"constant": 0.5}),
        json!({"spin_up": {"speed": 6.5, "time": 1.0}}),
        json!({"sine": {"amplitude": 0.1, "frequency": 2.0, "phase": 90.0, "offset": 0.01}}),
        json!("input"),
    ];
    let mut driven = Vec::new();
    for (quantity, kind) in
        [("angle", "revolute"), ("torque", "revolute"), ("position", "prismatic"), ("force", "prismatic")]
    {
        for f in &functions {
            driven.push(json!({"type": kind, "axis": [0.0, 0.0, 1.0], "drive": {quantity: f}}));
        }
    }
    docs.push(chain(driven[0].clone(), &driven[1..]));
    // the first external flange a motion flange: a body the host holds, and nothing else
    docs.push(json!({"name": "Held", "assembly": {"bodies": [{"name": "b0", "rigid": rigid(&["f"])}],
                                                  "flanges": [{"name": "mount", "role": "motion", "at": "b0.f"}]},
                     "experiment": {"step_size": 1e-3}}));
    docs
}

fn schema() -> Value {
    serde_json::from_str(SCHEMA).expect("the embedded schema is JSON")
}

/// The builder's verdict: Ok, or its message.
fn builder(doc: &Value) -> Result<(), String> {
    let text = doc.to_string();
    if doc.get("assembly").is_some() {
        AssemblySpec::from_str(Path::new("in.json"), &text).map(|_| ()).map_err(|e| e.to_string())
    } else {
        Spec::from_str(Path::new("in.json"), &text).map(|_| ()).map_err(|e| e.to_string())
    }
}

/// Whether `s` offers the whole input's schema (`"$ref": "#"`, an assembly's inline body): the
/// body documents cover its fields.
fn is_whole_input(s: &Value) -> bool {
    s.get("$ref").and_then(Value::as_str) == Some("#")
        || s.get("oneOf").and_then(Value::as_array).is_some_and(|alts| alts.iter().any(is_whole_input))
}

fn resolve<'a>(root: &'a Value, s: &'a Value) -> &'a Value {
    match s.get("$ref").and_then(Value::as_str) {
        Some(r) => root.pointer(&r[1..]).unwrap_or_else(|| panic!("dangling $ref {r}")),
        None => s,
    }
}

/// The schema of `key` inside an object whose schema is `s`: its `properties`, those of a
/// `oneOf`/`anyOf` alternative, or `additionalProperties`.
fn child<'a>(root: &'a Value, s: &'a Value, key: &str) -> Option<&'a Value> {
    let s = resolve(root, s);
    if let Some(p) = s.get("properties").and_then(|p| p.get(key)) {
        return Some(p);
    }
    for alternatives in ["oneOf", "anyOf"] {
        for alt in s.get(alternatives).and_then(Value::as_array).into_iter().flatten() {
            if let Some(p) = child(root, alt, key) {
                return Some(p);
            }
        }
    }
    s.get("additionalProperties").filter(|a| a.is_object())
}

/// A keyword of a property schema, on the property or where its `$ref` leads.
fn keyword<'a>(root: &'a Value, s: &'a Value, key: &str) -> Option<&'a Value> {
    s.get(key).or_else(|| resolve(root, s).get(key))
}

/// Every property path of the schema: `flanges[].nodes.plane.tolerance`, `materials.*.E`.
fn schema_paths(root: &Value, s: &Value, path: &str, out: &mut BTreeSet<String>) {
    if is_whole_input(s) && !path.is_empty() {
        return;
    }
    let s = resolve(root, s);
    let join = |k: &str| if path.is_empty() { k.to_string() } else { format!("{path}.{k}") };
    for (k, p) in s.get("properties").and_then(Value::as_object).into_iter().flatten() {
        out.insert(join(k));
        schema_paths(root, p, &join(k), out);
    }
    for alternatives in ["oneOf", "anyOf"] {
        for alt in s.get(alternatives).and_then(Value::as_array).into_iter().flatten() {
            schema_paths(root, alt, path, out);
        }
    }
    if let Some(a) = s.get("additionalProperties").filter(|a| a.is_object()) {
        out.insert(join("*"));
        schema_paths(root, a, &join("*"), out);
    }
    if let Some(items) = s.get("items") {
        schema_paths(root, items, &format!("{path}[]"), out);
    }
}

/// A place in a document: its JSON pointer, its dotted field (as the builder names it), its
/// path in the schema's terms, and its schema.
struct Location<'a> {
    pointer: String,
    field: String,
    generic: String,
    schema: &'a Value,
}

/// Every value in `doc` with its schema, first occurrences of each generic path only.
fn locations<'a>(root: &'a Value, doc: &Value) -> Vec<Location<'a>> {
    fn walk<'a>(
        root: &'a Value,
        v: &Value,
        s: &'a Value,
        at: (&str, &str, &str),
        seen: &mut BTreeSet<String>,
        out: &mut Vec<Location<'a>>,
    ) {
        let (pointer, field, generic) = at;
        if !generic.is_empty() && seen.insert(generic.to_string()) {
            out.push(Location { pointer: pointer.into(), field: field.into(), generic: generic.into(), schema: s });
        }
        if !generic.is_empty() && is_whole_input(s) {
            return;
        }
        match v {
            Value::Object(map) => {
                let additional = resolve(root, s).get("properties").is_none();
                for (k, x) in map {
                    let sub = child(root, s, k).unwrap_or_else(|| panic!("{generic}.{k} is not in the schema"));
                    let g = if additional && resolve(root, s).get("additionalProperties").is_some() { "*" } else { k };
                    let dot = |p: &str, k: &str| if p.is_empty() { k.to_string() } else { format!("{p}.{k}") };
                    walk(root, x, sub, (&format!("{pointer}/{k}"), &dot(field, k), &dot(generic, g)), seen, out);
                }
            }
            Value::Array(items) => {
                // every item (the second flange is the first with a plane), each generic path
                // recorded where it first occurs
                if let Some(item) = keyword(root, s, "items") {
                    for (i, x) in items.iter().enumerate() {
                        let (p, f, g) = (format!("{pointer}/{i}"), format!("{field}[{i}]"), format!("{generic}[]"));
                        walk(root, x, item, (&p, &f, &g), seen, out);
                    }
                }
            }
            _ => {}
        }
    }
    let mut out = Vec::new();
    walk(root, doc, root, ("", "", ""), &mut BTreeSet::new(), &mut out);
    out
}

fn with(doc: &Value, pointer: &str, value: Value) -> Value {
    let mut d = doc.clone();
    *d.pointer_mut(pointer).unwrap() = value;
    d
}

/// The values at and just beyond each bound of a numeric or string schema: (value, inside?).
fn probes(root: &Value, s: &Value) -> Vec<(Value, bool, String)> {
    let kw = |k: &str| keyword(root, s, k).and_then(Value::as_f64);
    let integer = keyword(root, s, "type").and_then(Value::as_str) == Some("integer");
    let num = |x: f64| if integer { json!(x as i64) } else { json!(x) };
    // the nearest value beyond a bound: the next integer, or the next double
    let up = |x: f64| if integer { x + 1.0 } else { x.next_up() };
    let down = |x: f64| if integer { x - 1.0 } else { x.next_down() };
    let mut out = Vec::new();
    if let Some(m) = kw("minimum") {
        out.push((num(m), true, format!("minimum {m}")));
        out.push((num(down(m)), false, format!("just below the minimum {m}")));
    }
    if let Some(m) = kw("maximum") {
        out.push((num(m), true, format!("maximum {m}")));
        out.push((num(up(m)), false, format!("just above the maximum {m}")));
    }
    if let Some(m) = kw("exclusiveMinimum") {
        out.push((num(m), false, format!("exclusive minimum {m}")));
        out.push((num(up(m)), true, format!("just above the exclusive minimum {m}")));
    }
    if let Some(m) = kw("exclusiveMaximum") {
        out.push((num(m), false, format!("exclusive maximum {m}")));
        out.push((num(down(m)), true, format!("just below the exclusive maximum {m}")));
    }
    let text = |n: f64| json!("a".repeat(n as usize));
    if let Some(n) = kw("minLength").filter(|&n| n > 0.0) {
        out.push((text(n), true, format!("minLength {n}")));
        out.push((text(n - 1.0), false, format!("below minLength {n}")));
    }
    if let Some(n) = kw("maxLength") {
        out.push((text(n), true, format!("maxLength {n}")));
        out.push((text(n + 1.0), false, format!("above maxLength {n}")));
    }
    out
}

#[test]
fn the_base_documents_use_every_field_and_the_types_take_them() {
    let root = schema();
    let validator = jsonschema::validator_for(&root).unwrap();
    let mut declared = BTreeSet::new();
    schema_paths(&root, &root, "", &mut declared);
    let mut used = BTreeSet::new();
    for doc in base_documents() {
        let problems: Vec<String> =
            validator.iter_errors(&doc).map(|e| format!("{}: {e}", e.instance_path())).collect();
        assert!(problems.is_empty(), "a base document is invalid for the schema: {problems:?}");
        builder(&doc).unwrap_or_else(|e| panic!("the builder refuses a base document: {e}"));
        // the serde types alone (deny_unknown_fields, no schema in front of them) take every name
        let written = if doc.get("assembly").is_some() {
            let file: AssemblyFile =
                serde_json::from_value(doc.clone()).unwrap_or_else(|e| panic!("the types refuse: {e}"));
            serde_json::to_value(&file).unwrap()
        } else {
            let spec: Spec = serde_json::from_value(doc.clone()).unwrap_or_else(|e| panic!("the types refuse: {e}"));
            serde_json::to_value(&spec).unwrap()
        };
        used.extend(locations(&root, &doc).into_iter().map(|l| l.generic));
        // ... and every field the types write back is one the schema knows
        let mut back = Vec::new();
        fn keys(v: &Value, path: &str, out: &mut Vec<String>) {
            match v {
                Value::Object(m) => {
                    for (k, x) in m.iter().filter(|(_, x)| !x.is_null()) {
                        let p = if path.is_empty() { k.clone() } else { format!("{path}.{k}") };
                        out.push(p.clone());
                        keys(x, &p, out);
                    }
                }
                Value::Array(a) => a.iter().for_each(|x| keys(x, &format!("{path}[]"), out)),
                _ => {}
            }
        }
        keys(&written, "", &mut back);
        // (an inline body's own fields are a body input's, written back by `Spec`)
        for k in back.into_iter().filter(|k| !k.contains(".flexible.")) {
            let generic = k.replace("materials.STEEL", "materials.*");
            assert!(declared.contains(&generic), "the types have a field {generic} the schema does not declare");
        }
    }
    let missing: Vec<&String> = declared.difference(&used).collect();
    assert!(
        missing.is_empty(),
        "schema fields no base document uses (add them, so their limits are tested): {missing:?}"
    );
}

/// Fields whose real limit is a count in the same input (a box index below the number of
/// boxes), which a schema cannot state: the schema holds an outer limit (so 1e300 or 2^64 is
/// refused with the field named before any parsing), and at it the builder refuses with the field
/// named too.
const BOUND_BY_THE_INPUT: &[&str] = &["flanges[0].nodes.box_face.box"];

#[test]
fn every_bound_of_the_schema_is_the_builders() {
    let root = schema();
    let validator = jsonschema::validator_for(&root).unwrap();
    let mut tested = 0;
    let mut disagreements = Vec::new();
    for doc in base_documents() {
        for at in locations(&root, &doc) {
            for (value, inside, what) in probes(&root, at.schema) {
                let d = with(&doc, &at.pointer, value.clone());
                let by_schema = validator.is_valid(&d);
                let by_builder = builder(&d);
                tested += 1;
                match (inside, by_schema, &by_builder) {
                    (true, true, Ok(())) => {}
                    // the schema's bound is an outer one; the builder's is the input's own count
                    (true, true, Err(m))
                        if BOUND_BY_THE_INPUT.contains(&at.field.as_str()) && m.contains(&at.field) => {}
                    // refused by both, and the builder says which field
                    (false, false, Err(m)) if m.contains(&at.field) => {}
                    _ => disagreements.push(format!(
                        "{} = {value} ({what}): schema {}, builder {}",
                        at.field,
                        if by_schema { "accepts" } else { "refuses" },
                        match &by_builder {
                            Ok(()) => "accepts".to_string(),
                            Err(m) => format!("refuses: {m}"),
                        }
                    )),
                }
            }
        }
    }
    assert!(disagreements.is_empty(), "schema and builder disagree:\n{}", disagreements.join("\n"));
    // the fields with bounds (E, nu, rho twice, alpha, beta, ratios, modes, elements, ...)
    assert!(tested > 60, "only {tested} probes");
}

#[test]
fn every_enum_value_is_taken_by_both_or_refused_by_both() {
    let root = schema();
    let validator = jsonschema::validator_for(&root).unwrap();
    let mut accepted: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    let mut offered: BTreeMap<String, Vec<String>> = BTreeMap::new();
    let mut disagreements = Vec::new();
    for doc in base_documents() {
        for at in locations(&root, &doc) {
            let Some(values) = keyword(&root, at.schema, "enum").and_then(Value::as_array) else { continue };
            offered.insert(at.generic.clone(), values.iter().map(|v| v.to_string()).collect());
            for v in values {
                let d = with(&doc, &at.pointer, v.clone());
                let (by_schema, by_builder) = (validator.is_valid(&d), builder(&d));
                if by_schema != by_builder.is_ok() {
                    disagreements.push(format!("{} = {v}: schema {by_schema}, builder {by_builder:?}", at.field));
                }
                if by_builder.is_ok() {
                    accepted.entry(at.generic.clone()).or_default().insert(v.to_string());
                }
            }
            // a value not in the list: refused, naming the field and what it accepts
            let d = with(&doc, &at.pointer, json!("no-such-value"));
            assert!(!validator.is_valid(&d));
            let m = builder(&d).expect_err("an unknown enum value is refused");
            let first = values[0].to_string();
            assert!(m.contains(&at.field) && m.contains(&first), "{}: {m}", at.field);
        }
    }
    assert!(disagreements.is_empty(), "schema and builder disagree:\n{}", disagreements.join("\n"));
    for (path, values) in &offered {
        let taken = accepted.get(path).cloned().unwrap_or_default();
        let never: Vec<&String> = values.iter().filter(|v| !taken.contains(*v)).collect();
        assert!(never.is_empty(), "{path}: no base document builds with {never:?}");
    }
    for path in [
        "geometry.length_unit",
        "geometry.element",
        "flanges[].role",
        "reduction.method",
        "scene.loads[]",
        "assembly.joints[].type",
        "assembly.flanges[].role",
    ] {
        assert!(offered.contains_key(path), "{path} was not tested");
    }
}

/// The builder's named limits are the schema's: a constant changed on one side only fails here
/// even where the probes above would not reach it (a limit the schema does not state at all).
#[test]
fn the_builders_constants_are_the_schemas_bounds() {
    let root = schema();
    let at = |pointer: &str| root.pointer(pointer).unwrap_or_else(|| panic!("no {pointer} in the schema"));
    let inclusive = |pointer: &str, (lo, hi): (f64, f64)| {
        let p = at(pointer);
        assert_eq!(p["minimum"].as_f64(), Some(lo), "{pointer}: minimum");
        assert_eq!(p["maximum"].as_f64(), Some(hi), "{pointer}: maximum");
    };
    for m in ["/properties/material/properties", "/$defs/material/properties"] {
        inclusive(&format!("{m}/E"), ranges::E_RANGE);
        inclusive(&format!("{m}/nu"), ranges::NU_RANGE);
        inclusive(&format!("{m}/rho"), ranges::RHO_RANGE);
    }
    let damping = "/properties/damping/properties";
    inclusive(&format!("{damping}/alpha"), (0.0, ranges::ALPHA_MAX));
    inclusive(&format!("{damping}/beta"), (0.0, ranges::BETA_MAX));
    inclusive(&format!("{damping}/modal_ratio"), (0.0, ranges::RATIO_MAX));
    inclusive(&format!("{damping}/modal_bands/items/properties/ratio"), (0.0, ranges::RATIO_MAX));
    inclusive("/properties/reduction/properties/modes", (0.0, MAX_MODES as f64));
    let units: Vec<&str> = at("/properties/geometry/properties/length_unit/enum")
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_str().unwrap())
        .collect();
    let known: Vec<&str> = fmu_builder::input::spec::LengthUnit::ALL.iter().map(|u| u.symbol()).collect();
    assert_eq!(units, known);
}
