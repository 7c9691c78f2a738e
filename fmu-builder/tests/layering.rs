//! The builder's layout. The stages below the builder's own are crates, so Cargo keeps them
//! below: `petsc-backend`, then `fe-linalg`, then `fe-input`, each depending only on those before
//! it (checked here on the manifests; a planted import upward fails to compile, as each crate's
//! `compile_fail` doc test shows). Within the fmu-builder crate, where Cargo cannot see it, this
//! checks on the sources: a stage uses only the stages before it (model, reduce, ffrf, output,
//! then the driver `pipeline` and the command-line `job`; `error`, `profile` and `progress`
//! serve all), no module imports a module that imports it back, every top-level module has a
//! stage, and the binary only parses its arguments and runs a job. The runtime's model layer (mechanics)
//! knows nothing of FMI or C; only its adapter does. docs/ARCHITECTURE.md describes the stages.
//!
//! Paths are read from the code with comments, strings and character literals removed, and
//! resolved from `crate::`, `self::` and `super::` (any depth) to the file they name.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// Top-level modules and their place in the data flow.
const STAGES: [(&str, usize); 9] = [
    ("error", 0),
    ("profile", 0),
    ("progress", 0),
    ("model", 2),
    ("reduce", 3),
    ("ffrf", 4),
    ("output", 5),
    ("pipeline", 6),
    ("job", 7),
];

/// What the binary may name of the library: the job it runs, the types of its options, the
/// --version text and its allocator. Anything else would be library work in main.rs.
const BINARY_USES: [&str; 4] = ["job", "input::spec", "output::package", "out_of_memory"];

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
    if parts.last().is_some_and(|p| p == "mod" || p == "lib") {
        parts.pop();
    }
    parts
}

/// The code with comments (line, nested block), string literals (plain, byte, raw with any
/// number of #) and character literals replaced by spaces, so that nothing inside them reads as
/// a path. Lifetimes (`'a`) stay.
fn code_only(text: &str) -> String {
    let s: Vec<char> = text.chars().collect();
    let mut out = String::with_capacity(text.len());
    let mut i = 0;
    let blank = |out: &mut String, c: char| out.push(if c == '\n' { '\n' } else { ' ' });
    while i < s.len() {
        let next = s.get(i + 1).copied();
        if s[i] == '/' && next == Some('/') {
            while i < s.len() && s[i] != '\n' {
                i += 1;
            }
        } else if s[i] == '/' && next == Some('*') {
            let mut depth = 0;
            while i < s.len() {
                if s[i] == '/' && s.get(i + 1) == Some(&'*') {
                    depth += 1;
                    i += 2;
                } else if s[i] == '*' && s.get(i + 1) == Some(&'/') {
                    depth -= 1;
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    blank(&mut out, s[i]);
                    i += 1;
                }
            }
        } else if let Some(end) = raw_string_end(&s, i) {
            s[i..end].iter().for_each(|&c| blank(&mut out, c));
            i = end;
        } else if s[i] == '"' || (s[i] == 'b' && next == Some('"') && !ident_before(&s, i)) {
            i += if s[i] == 'b' { 2 } else { 1 };
            while i < s.len() && s[i] != '"' {
                i += if s[i] == '\\' { 2 } else { 1 };
            }
            i += 1;
            out.push_str("\"\"");
        } else if s[i] == '\''
            && let Some(end) = char_literal_end(&s, i)
        {
            i = end;
            out.push_str("' '");
        } else {
            out.push(s[i]);
            i += 1;
        }
    }
    out
}

fn ident_before(s: &[char], i: usize) -> bool {
    i > 0 && (s[i - 1].is_alphanumeric() || s[i - 1] == '_')
}

/// The end of a raw string r"..", r#".."#, br#".."# starting at `i`, if one starts there.
fn raw_string_end(s: &[char], i: usize) -> Option<usize> {
    if ident_before(s, i) {
        return None;
    }
    let mut k = i;
    if s.get(k) == Some(&'b') {
        k += 1;
    }
    if s.get(k) != Some(&'r') {
        return None;
    }
    k += 1;
    let hashes = s[k..].iter().take_while(|&&c| c == '#').count();
    k += hashes;
    if s.get(k) != Some(&'"') {
        return None;
    }
    k += 1;
    while k < s.len() {
        if s[k] == '"' && s[k + 1..].iter().take(hashes).filter(|&&c| c == '#').count() == hashes {
            return Some(k + 1 + hashes);
        }
        k += 1;
    }
    Some(s.len())
}

/// The end of a character literal at `i` ('x', '\n', '\u{..}', '"'); None for a lifetime.
fn char_literal_end(s: &[char], i: usize) -> Option<usize> {
    if s.get(i + 1) == Some(&'\\') {
        let close = s[i + 2..].iter().position(|&c| c == '\'')?;
        return Some(i + 2 + close + 1);
    }
    (s.get(i + 2) == Some(&'\'')).then_some(i + 3)
}

/// Parses one path (or a `{...}` group of paths) at `i`, pushing every complete path onto
/// `out`; returns the index after it.
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
            let mut j = i;
            while j < s.len() && s[j].is_ascii_whitespace() {
                j += 1;
            }
            if s[j..].starts_with(b"::") {
                i = j + 2;
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

/// Every path the code names from `root` (`crate`, `self`, `super`, a crate name), groups
/// expanded, as written (with its leading `root`).
fn paths_from(code: &str, root: &str) -> Vec<Vec<String>> {
    let s = code.as_bytes();
    let needle = format!("{root}::");
    let mut out = Vec::new();
    let mut from = 0;
    while let Some(k) = code[from..].find(&needle) {
        let at = from + k;
        from = at + needle.len();
        // `xsuper::` or `a::super::` are not paths from `root` here (a chain is read from its start)
        let before = code[..at].trim_end();
        if at > 0 && (s[at - 1].is_ascii_alphanumeric() || s[at - 1] == b'_' || before.ends_with("::")) {
            continue;
        }
        let mut prefix = vec![root.to_string()];
        parse_path(s, from, &mut prefix, &mut out);
    }
    out
}

/// The module a path names, from the module `here` it is written in: `crate::a::b` is [a, b],
/// `super::x` is here's parent's x, `self::y` here's y; `super::super::` climbs twice.
fn resolve(here: &[String], path: &[String]) -> Option<Vec<String>> {
    let (mut base, mut rest): (Vec<String>, &[String]) = match path.first()?.as_str() {
        "crate" => (Vec::new(), &path[1..]),
        "self" => (here.to_vec(), &path[1..]),
        "super" => (here.to_vec(), path),
        _ => return None,
    };
    while rest.first().is_some_and(|p| p == "super") {
        base.pop()?;
        rest = &rest[1..];
    }
    base.extend(rest.iter().filter(|p| *p != "self").cloned());
    Some(base)
}

/// Every module path a file's code names, resolved from its module.
fn named_modules(code: &str, here: &[String]) -> Vec<Vec<String>> {
    let mut paths = paths_from(code, "crate");
    paths.extend(paths_from(code, "super"));
    paths.extend(paths_from(code, "self"));
    paths.iter().filter_map(|p| resolve(here, p)).collect()
}

struct Crate {
    /// module path -> file (relative to src)
    modules: BTreeMap<Vec<String>, String>,
    /// import edges between files
    edges: BTreeSet<(String, String)>,
}

fn scan(src: &Path, skip: &[&str]) -> Crate {
    let mut files = Vec::new();
    rust_files(src, &mut files);
    let rel = |f: &PathBuf| f.strip_prefix(src).unwrap().to_string_lossy().into_owned();
    let modules: BTreeMap<Vec<String>, String> =
        files.iter().map(|f| (module_of(Path::new(&rel(f))), rel(f))).collect();
    let mut edges = BTreeSet::new();
    for f in &files {
        let from = rel(f);
        if skip.contains(&from.as_str()) {
            continue;
        }
        let code = code_only(&std::fs::read_to_string(f).unwrap());
        for path in named_modules(&code, &module_of(Path::new(&from))) {
            let target = (1..=path.len()).rev().find_map(|k| modules.get(&path[..k]));
            if let Some(target) = target.filter(|t| **t != from) {
                edges.insert((from.clone(), target.clone()));
            }
        }
    }
    Crate { modules, edges }
}

fn builder() -> Crate {
    scan(&Path::new(env!("CARGO_MANIFEST_DIR")).join("src"), &["lib.rs", "main.rs"])
}

fn stage_of(file: &str) -> usize {
    let top = file.split('/').next().unwrap().trim_end_matches(".rs");
    STAGES.iter().find(|(name, _)| *name == top).unwrap_or_else(|| panic!("{file}: not in a stage of STAGES")).1
}

/// Circles in a graph of import edges, each as "a -> b -> a".
fn circles(edges: &BTreeSet<(String, String)>) -> Vec<String> {
    let mut graph: BTreeMap<&str, Vec<&str>> = BTreeMap::new();
    for (from, to) in edges {
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
    let mut found = Vec::new();
    let mut done = BTreeSet::new();
    for node in graph.keys() {
        visit(node, &graph, &mut Vec::new(), &mut done, &mut found);
    }
    found
}

fn later_stage_imports(edges: &BTreeSet<(String, String)>) -> Vec<String> {
    edges
        .iter()
        .filter(|(from, to)| stage_of(to) > stage_of(from))
        .map(|(from, to)| format!("{from} -> {to}"))
        .collect()
}

fn strings(list: &[&str]) -> Vec<String> {
    list.iter().map(|s| s.to_string()).collect()
}

#[test]
fn the_path_parser_expands_groups_and_skips_comments_and_strings() {
    let text = "use crate::a::{self, b::{C, d}, E};\nlet x = crate::f::g(); // crate::comment\n\
                let s = \"// not a comment\"; use crate::h;\nlet t = r#\"crate::in_raw\"#; /* crate::block */ \
                let c = '\"'; use crate::i; fn f<'a>(x: &'a str) { crate::j::k(x) }";
    let paths = paths_from(&code_only(text), "crate");
    let expected: Vec<Vec<&str>> = vec![
        vec!["crate", "a", "self"],
        vec!["crate", "a", "b", "C"],
        vec!["crate", "a", "b", "d"],
        vec!["crate", "a", "E"],
        vec!["crate", "f", "g"],
        vec!["crate", "h"],
        vec!["crate", "i"],
        vec!["crate", "j", "k"],
    ];
    assert_eq!(paths.len(), expected.len(), "{paths:?}");
    for (p, e) in paths.iter().zip(&expected) {
        assert_eq!(p, e);
    }
}

#[test]
fn super_and_self_paths_resolve_from_the_module_they_are_written_in() {
    let here = strings(&["input", "import", "msh"]);
    let code = code_only("use super::super::spec::Spec; use super::inp; use self::ascii::x; use crate::model::part;");
    let mut found = named_modules(&code, &here);
    found.sort();
    let mut expected = [
        vec!["input", "spec", "Spec"],
        vec!["input", "import", "inp"],
        vec!["input", "import", "msh", "ascii", "x"],
        vec!["model", "part"],
    ];
    expected.sort();
    assert_eq!(found.len(), expected.len(), "{found:?}");
    for (f, e) in found.iter().zip(&expected) {
        assert_eq!(f, &strings(e));
    }
    // above the crate root is no module
    assert_eq!(resolve(&strings(&["input"]), &strings(&["super", "super", "x"])), None);
}

/// The planted imports the check must catch: a later stage named through `super::super`, an
/// import right after a string holding `//`, a circle built with `super::`.
#[test]
fn planted_imports_are_caught() {
    let dir = std::env::temp_dir().join(format!("layering-planted-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    for (file, text) in [
        ("model/mod.rs", "pub mod part;"),
        ("model/part.rs", "fn f() { let s = \"http://x\"; crate::reduce::basis::g(); }"),
        ("model/flange.rs", "use super::super::reduce::basis;"),
        ("reduce/mod.rs", "pub mod basis; pub mod order;"),
        ("reduce/basis.rs", "use super::order::x;"),
        ("reduce/order.rs", "use super::basis::y;"),
    ] {
        let path = dir.join(file);
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(path, text).unwrap();
    }
    let planted = scan(&dir, &[]);
    let mut upstream = later_stage_imports(&planted.edges);
    upstream.sort();
    assert_eq!(upstream, ["model/flange.rs -> reduce/basis.rs", "model/part.rs -> reduce/basis.rs"]);
    let found = circles(&planted.edges);
    assert_eq!(found.len(), 1, "{found:?}");
    assert!(found[0].contains("reduce/basis.rs") && found[0].contains("reduce/order.rs"), "{found:?}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The workspace's crates in the order of the data flow: a crate may depend on those before it
/// only. `fmi2` and `fmu-runtime` (the FMU's side) come before the builder, which shares the
/// runtime's reduced-body format; `test-support` serves the tests and the bench; `xtask` builds
/// the runtime and names no crate.
const CRATE_ORDER: [&str; 10] = [
    "phases",
    "fmi2",
    "fmu-runtime",
    "petsc-backend",
    "fe-linalg",
    "fe-input",
    "fmu-builder",
    "test-support",
    "bench",
    "xtask",
];

/// The workspace crates a manifest's `[dependencies]` name by path (dev-dependencies are the
/// tests', which may use anything).
fn path_dependencies(manifest: &str) -> Vec<String> {
    let mut in_dependencies = false;
    let mut found = Vec::new();
    for line in manifest.lines().map(str::trim) {
        if line.starts_with('[') {
            in_dependencies = line == "[dependencies]";
        } else if in_dependencies && line.contains("path = \"../") {
            found.push(line.split(['=', ' ']).next().unwrap_or_default().to_string());
        }
    }
    found
}

#[test]
fn the_crates_depend_only_on_the_crates_before_them() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let mut upward = Vec::new();
    let mut edges = 0;
    for (at, name) in CRATE_ORDER.iter().enumerate() {
        let manifest = std::fs::read_to_string(root.join(name).join("Cargo.toml")).unwrap();
        for dependency in path_dependencies(&manifest) {
            edges += 1;
            match CRATE_ORDER.iter().position(|c| *c == dependency) {
                Some(d) if d < at => {}
                _ => upward.push(format!("{name} -> {dependency}")),
            }
        }
    }
    let workspace = std::fs::read_to_string(root.join("Cargo.toml")).unwrap();
    let members = workspace.lines().find(|l| l.starts_with("members")).expect("the workspace's members");
    let mut listed: Vec<&str> = members.split('"').skip(1).step_by(2).collect();
    listed.sort();
    let mut ordered = CRATE_ORDER.to_vec();
    ordered.sort();
    assert_eq!(listed, ordered, "every workspace member has its place in CRATE_ORDER");
    // the check must read the manifests, not pass on none
    assert!(edges >= 10, "{edges} path dependencies read");
    assert!(upward.is_empty(), "crates depending on a later stage (or one not in CRATE_ORDER):\n{}", upward.join("\n"));
    assert_eq!(
        path_dependencies(
            "[dependencies]\nfe-input = { path = \"../fe-input\" }\n[dev-dependencies]\nx = { path = \"../x\" }"
        ),
        ["fe-input"]
    );
}

#[test]
fn every_top_level_module_has_a_stage() {
    let lib = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("src/lib.rs")).unwrap();
    let declared: BTreeSet<String> = code_only(&lib)
        .split(';')
        .filter_map(|item| {
            let words: Vec<&str> = item.split_whitespace().collect();
            let at = words.iter().position(|w| *w == "mod")?;
            (at + 2 == words.len()).then(|| words[at + 1].to_string())
        })
        .collect();
    let staged: BTreeSet<String> = STAGES.iter().map(|(m, _)| m.to_string()).collect();
    assert_eq!(declared, staged, "lib.rs's modules and STAGES differ");
}

#[test]
fn no_stage_imports_from_a_later_stage() {
    let c = builder();
    // the check must see the whole crate, not pass on an empty scan
    assert!(c.modules.len() > 50 && c.edges.len() > 100, "{} files, {} edges", c.modules.len(), c.edges.len());
    let upstream = later_stage_imports(&c.edges);
    assert!(upstream.is_empty(), "imports from a later stage:\n{}", upstream.join("\n"));
}

#[test]
fn no_circle_of_imports() {
    let found = circles(&builder().edges);
    assert!(found.is_empty(), "circles of imports:\n{}", found.join("\n"));
}

#[test]
fn the_binary_only_parses_its_arguments_and_runs_a_job() {
    let main = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("src/main.rs")).unwrap();
    let named = paths_from(&code_only(&main), "fmu_builder");
    assert!(named.iter().any(|p| p[1] == "job"), "main.rs runs no job: {named:?}");
    let library_work: Vec<String> = named
        .iter()
        .map(|p| p[1..].join("::"))
        .filter(|p| !BINARY_USES.iter().any(|allowed| p.starts_with(allowed)))
        .collect();
    assert!(library_work.is_empty(), "main.rs names library work beyond its job: {library_work:?}");
}

/// The runtime: a model layer that knows mechanics and nothing of FMI or C, and its adapter
/// (`fmu`, `interface`, `lib.rs`) that knows FMI. No model file names `fmi2`, `extern "C"`,
/// `std::ffi` or libc, or imports the adapter.
#[test]
fn the_runtime_model_layer_knows_nothing_of_fmi() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("../fmu-runtime/src");
    let adapter = |file: &str| {
        file == "lib.rs"
            || ["interface", "fmu"].iter().any(|m| file == format!("{m}.rs") || file.starts_with(&format!("{m}/")))
    };
    let runtime = scan(&src, &[]);
    assert!(runtime.modules.len() > 10, "{} runtime files", runtime.modules.len());
    let mut found = Vec::new();
    for file in runtime.modules.values().filter(|f| !adapter(f)) {
        let code = code_only(&std::fs::read_to_string(src.join(file)).unwrap());
        for word in ["fmi2::", "fmi2 ::", "extern \"\"", "std::ffi", "libc::"] {
            if code.contains(word) {
                found.push(format!("{file} names {word}"));
            }
        }
    }
    for (from, to) in &runtime.edges {
        if !adapter(from) && adapter(to) {
            found.push(format!("{from} imports the adapter {to}"));
        }
    }
    assert!(found.is_empty(), "the runtime's model layer reaches into FMI:\n{}", found.join("\n"));
    let circles = circles(&runtime.edges);
    assert!(circles.is_empty(), "circles of imports in the runtime:\n{}", circles.join("\n"));
}
