//! The builder's layout, checked on its sources: a stage uses only the stages before it (input,
//! model, reduce, ffrf, output, then the driver `pipeline`; `error`, `linalg`, `profile`,
//! `out_of_memory` and `progress` serve all), and no module imports a module that imports it back. docs/ARCHITECTURE.md describes the stages.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// Top-level modules and their place in the data flow.
const STAGES: [(&str, usize); 11] = [
    ("error", 0),
    ("linalg", 0),
    ("profile", 0),
    ("out_of_memory", 0),
    ("progress", 0),
    ("input", 1),
    ("model", 2),
    ("reduce", 3),
    ("ffrf", 4),
    ("output", 5),
    ("pipeline", 6),
];

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).expect("readable source directory") {
        let path = entry.expect("directory entry").path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// `input/import/mod.rs` -> [input, import]; `model/flange.rs` -> [model, flange].
fn module_of(relative: &Path) -> Vec<String> {
    let mut parts: Vec<String> = relative.with_extension("").iter().map(|c| c.to_string_lossy().into_owned()).collect();
    if parts.last().is_some_and(|p| p == "mod") {
        parts.pop();
    }
    parts
}

/// Parses one path after `crate::` (or inside a `{...}` group) starting at `i`, pushing every
/// complete path onto `out`; returns the index after it.
fn parse_path(s: &[u8], mut i: usize, prefix: &mut Vec<String>, out: &mut Vec<Vec<String>>) -> usize {
    let depth = prefix.len();
    loop {
        while i < s.len() && s[i].is_ascii_whitespace() {
            i += 1;
        }
        if i < s.len() && (s[i].is_ascii_alphabetic() || s[i] == b'_') {
            let start = i;
            while i < s.len() && (s[i].is_ascii_alphanumeric() || s[i] == b'_') {
                i += 1;
            }
            prefix.push(String::from_utf8_lossy(&s[start..i]).into_owned());
            if s[i..].starts_with(b"::") {
                i += 2;
                continue;
            }
            out.push(prefix.clone());
        } else if i < s.len() && s[i] == b'{' {
            i += 1;
            loop {
                while i < s.len() && (s[i].is_ascii_whitespace() || s[i] == b',') {
                    i += 1;
                }
                if i >= s.len() || s[i] == b'}' {
                    prefix.truncate(depth);
                    return i + 1;
                }
                let before = i;
                i = parse_path(s, i, prefix, out);
                if i == before {
                    // not a path (e.g. `*`): skip the character
                    i += 1;
                }
            }
        }
        prefix.truncate(depth);
        return i;
    }
}

/// Every module path a source names after `crate::`, groups expanded, comments ignored.
fn crate_paths(text: &str) -> Vec<Vec<String>> {
    let code: String = text.lines().map(|l| l.split("//").next().unwrap_or("")).collect::<Vec<_>>().join("\n");
    let s = code.as_bytes();
    let mut out = Vec::new();
    let mut from = 0;
    while let Some(k) = code[from..].find("crate::") {
        let start = from + k + "crate::".len();
        parse_path(s, start, &mut Vec::new(), &mut out);
        from = start;
    }
    out
}

/// Import edges between source files (relative paths), from `crate::` paths.
fn import_edges() -> (Vec<String>, BTreeSet<(String, String)>) {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    let modules: BTreeMap<Vec<String>, String> = files
        .iter()
        .map(|f| {
            let rel = f.strip_prefix(&src).unwrap();
            (module_of(rel), rel.to_string_lossy().into_owned())
        })
        .collect();
    let mut edges = BTreeSet::new();
    for f in &files {
        let rel = f.strip_prefix(&src).unwrap().to_string_lossy().into_owned();
        if rel == "lib.rs" || rel == "main.rs" {
            continue;
        }
        let text = std::fs::read_to_string(f).unwrap();
        for path in crate_paths(&text) {
            let target = (1..=path.len()).rev().find_map(|k| modules.get(&path[..k]));
            if let Some(target) = target.filter(|t| **t != rel) {
                edges.insert((rel.clone(), target.clone()));
            }
        }
    }
    (modules.into_values().collect(), edges)
}

fn stage_of(file: &str) -> usize {
    let top = file.split('/').next().unwrap().trim_end_matches(".rs");
    STAGES.iter().find(|(name, _)| *name == top).unwrap_or_else(|| panic!("{file}: not in a stage of STAGES")).1
}

#[test]
fn the_path_parser_expands_groups() {
    let paths = crate_paths("use crate::a::{self, b::{C, d}, E};\nlet x = crate::f::g(); // crate::comment");
    let expected: Vec<Vec<&str>> =
        vec![vec!["a", "self"], vec!["a", "b", "C"], vec!["a", "b", "d"], vec!["a", "E"], vec!["f", "g"]];
    assert_eq!(paths.len(), expected.len(), "{paths:?}");
    for (p, e) in paths.iter().zip(&expected) {
        assert_eq!(p, e);
    }
}

#[test]
fn no_stage_imports_from_a_later_stage() {
    let (files, edges) = import_edges();
    // the check must see the whole crate, not pass on an empty scan
    assert!(files.len() > 50 && edges.len() > 100, "{} files, {} edges", files.len(), edges.len());
    let upstream: Vec<String> = edges
        .iter()
        .filter(|(from, to)| stage_of(to) > stage_of(from))
        .map(|(from, to)| format!("{from} -> {to}"))
        .collect();
    assert!(upstream.is_empty(), "imports from a later stage:\n{}", upstream.join("\n"));
}

#[test]
fn no_circle_of_imports() {
    let (_, edges) = import_edges();
    let mut graph: BTreeMap<&str, Vec<&str>> = BTreeMap::new();
    for (from, to) in &edges {
        graph.entry(from).or_default().push(to);
    }
    // depth-first search; a module met again while on the stack closes a circle
    fn visit<'a>(
        node: &'a str,
        graph: &BTreeMap<&'a str, Vec<&'a str>>,
        stack: &mut Vec<&'a str>,
        done: &mut BTreeSet<&'a str>,
        circles: &mut Vec<String>,
    ) {
        if let Some(at) = stack.iter().position(|n| *n == node) {
            let mut circle = stack[at..].to_vec();
            circle.push(node);
            circles.push(circle.join(" -> "));
            return;
        }
        if !done.insert(node) {
            return;
        }
        stack.push(node);
        for next in graph.get(node).into_iter().flatten() {
            visit(next, graph, stack, done, circles);
        }
        stack.pop();
    }
    let mut circles = Vec::new();
    let mut done = BTreeSet::new();
    for node in graph.keys() {
        visit(node, &graph, &mut Vec::new(), &mut done, &mut circles);
    }
    assert!(circles.is_empty(), "circles of imports:\n{}", circles.join("\n"));
}
