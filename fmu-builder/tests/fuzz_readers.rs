//! Fuzzing of the builder's readers: the JSON input (`Spec::from_file`), Abaqus/CalculiX `.inp`
//! (`read_inp`), Gmsh `.msh` 4.1 ASCII and binary (`read_msh`), Matrix Market with its DoF map
//! and node table (`read_matrix_model`, and `parse_matrix_market` on its own).
//!
//! Inputs are valid seeds (the bundled examples, the importer's Gmsh test meshes, a deck and
//! matrices generated here from a small box part) with a few mutations each: hostile tokens in
//! place of numbers and words (NaN, inf, 1e308, -1, 2^64, empty, NUL, ...), lines deleted,
//! duplicated (a section twice), swapped or inserted (section headers, huge counts), truncation,
//! bit flips and, in binary files, 4- and 8-byte words overwritten after each section header
//! (where the counts and tags are). Shrinking removes mutations, so a failure prints the seed and
//! the few mutations that cause it.
//!
//! Oracle: no panic, no crash (every case runs in a child process: proptest's `fork`, with a
//! memory ceiling, so an allocation sized by a hostile count aborts the child and is counted), no
//! hang (proptest's `timeout`), every error names the file and is a sentence, not a Rust Debug
//! dump (`Foo { field: ... }`, `Some(..)`), and every accepted mesh is consistent (indices in
//! range, one id per node and element, node counts of the element types).
//!
//! Short mode (CI, part of `cargo test`): `FUZZ_CASES` cases per target, default 64, a few seconds
//! each. Long mode (docs/FUZZING.md):
//! `FUZZ_CASES=20000 FUZZ_SEED=7 cargo test --release -p fmu-builder --test fuzz_readers`.
//! `FUZZ_TIMEOUT_MS` (default 20000) is the per-case time limit, `FUZZ_MEMORY_MB` (default 3072)
//! the child's address-space ceiling.

use std::path::{Path, PathBuf};

use fmu_builder::input::import::matrices::{MatrixFiles, parse_matrix_market, read_matrix_model};
use fmu_builder::input::import::{ImportedMesh, read_inp, read_msh};
use fmu_builder::input::spec::Spec;
use proptest::prelude::*;
use proptest::sample::select;
use test_support::fuzz::{self, env_u64, limit_memory};
use test_support::scratch::Scratch;

// ---------------------------------------------------------------------------------------------
// mutations

/// Tokens put in place of a number or word.
const HOSTILE: &[&str] = &[
    "NaN",
    "nan",
    "-nan",
    "inf",
    "-inf",
    "Infinity",
    "1e308",
    "-1e308",
    "1e309",
    "-1e309",
    "4.9e-324",
    "2.2250738585072014e-308",
    "0",
    "-0",
    "-1",
    "-2147483649",
    "2147483647",
    "2147483648",
    "4294967295",
    "4294967296",
    "9223372036854775807",
    "18446744073709551615",
    "18446744073709551616",
    "1e19",
    "99999999999999999999999999999",
    "1000000000",
    "1.5",
    "0x10",
    "",
    "\u{0}",
    "\u{feff}",
    "\u{e9}",
    "*",
    "$",
    "\"",
    "[]",
    "{}",
    "null",
    "true",
    "-",
    "1,2",
];

/// Lines inserted: section headers and ends of every format, huge and negative counts.
const LINES: &[&str] = &[
    "$MeshFormat",
    "4.1 0 8",
    "4.1 1 8",
    "$EndMeshFormat",
    "$Nodes",
    "$EndNodes",
    "$Elements",
    "$EndElements",
    "$Entities",
    "$EndEntities",
    "$PhysicalNames",
    "$EndPhysicalNames",
    "1 18446744073709551615 1 18446744073709551615",
    "1 1000000000000 1 1000000000000",
    "3 1 0 1000000000000",
    "3 1 4 4294967296",
    "2147483647 2147483647 2147483647 2147483647",
    "-1 -1 -1 -1",
    "*NODE",
    "*NODE, NSET=ALL",
    "*ELEMENT, TYPE=C3D20, ELSET=E",
    "*ELEMENT, TYPE=C3D4",
    "*ELEMENT, TYPE=C3D10",
    "*NSET, NSET=BIG, GENERATE",
    "1, 18446744073709551615, 1",
    "1, 1000000000000, 1",
    "1000000000000, 1, -1",
    "1, 10, 0",
    "*ELSET, ELSET=E, GENERATE",
    "*MATERIAL, NAME=STEEL",
    "*ELASTIC",
    "nan, nan",
    "*DENSITY",
    "*SOLID SECTION, ELSET=E, MATERIAL=STEEL",
    "*INCLUDE, INPUT=missing.inp",
    "*INCLUDE, INPUT=case.inp",
    "*STEP",
    "*END STEP",
    "1, 1e308, -1e308, nan",
    "%%MatrixMarket matrix coordinate real symmetric",
    "%%MatrixMarket matrix coordinate real general",
    "%%MatrixMarket matrix array real general",
    "1000000000 1000000000 1",
    "4294967296 4294967296 1",
    "3 3 18446744073709551615",
    "2000000000 2000000000 2000000000",
    "1 1 nan",
    "1 1 1e308",
    "4294967296 1 1",
    "1 UX",
    "1 1",
    "1.7",
    "18446744073709551615 x",
    "1 0 0 0",
    "",
    "{",
    "}",
];

/// Words written over binary data (after a section header): counts, tags, f64 bit patterns.
const WORDS: &[u64] = &[
    0,
    1,
    2,
    3,
    4,
    11,
    17,
    0x7fff_ffff,
    0x8000_0000,
    0xffff_ffff,
    0x1_0000_0000,
    0x100_0000_0000,
    0x7fff_ffff_ffff_ffff,
    0x8000_0000_0000_0000,
    u64::MAX,
    u64::MAX - 1,
    0x7ff8_0000_0000_0000, // NaN
    0x7ff0_0000_0000_0000, // +inf
    0xfff0_0000_0000_0000, // -inf
    0x7fe1_ccf3_85eb_c8a0, // 1e308
    0x0000_0000_0000_0001, // smallest denormal
];

#[derive(Debug, Clone)]
enum Mutation {
    /// Replace the `at`-th token (modulo their number).
    Token {
        at: usize,
        with: &'static str,
    },
    /// Replace the `at`-th numeric token.
    Number {
        at: usize,
        with: &'static str,
    },
    DeleteLines {
        at: usize,
        len: usize,
    },
    /// Lines `at..at+len` written twice: a duplicated record or section.
    DuplicateLines {
        at: usize,
        len: usize,
    },
    SwapLines {
        a: usize,
        b: usize,
    },
    InsertLine {
        at: usize,
        line: &'static str,
    },
    /// Keep the first `per_mille` thousandths of the bytes.
    Truncate {
        per_mille: u16,
    },
    FlipByte {
        at: usize,
        mask: u8,
    },
    /// Overwrite `width` (4 or 8) bytes `4 * slot` bytes after the end of the `anchor`-th line
    /// starting with `$` (binary Gmsh: the counts and tags of a section body).
    Word {
        anchor: usize,
        slot: u8,
        width: u8,
        value: u64,
    },
}

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        3 => (any::<usize>(), select(HOSTILE)).prop_map(|(at, with)| Mutation::Token { at, with }),
        4 => (any::<usize>(), select(HOSTILE)).prop_map(|(at, with)| Mutation::Number { at, with }),
        1 => (any::<usize>(), 1..4usize).prop_map(|(at, len)| Mutation::DeleteLines { at, len }),
        2 => (any::<usize>(), 1..40usize).prop_map(|(at, len)| Mutation::DuplicateLines { at, len }),
        1 => (any::<usize>(), any::<usize>()).prop_map(|(a, b)| Mutation::SwapLines { a, b }),
        2 => (any::<usize>(), select(LINES)).prop_map(|(at, line)| Mutation::InsertLine { at, line }),
        1 => (0..1000u16).prop_map(|per_mille| Mutation::Truncate { per_mille }),
        1 => (any::<usize>(), 1..=255u8).prop_map(|(at, mask)| Mutation::FlipByte { at, mask }),
        3 => (any::<usize>(), 0..24u8, prop_oneof![Just(4u8), Just(8u8)], select(WORDS))
            .prop_map(|(anchor, slot, width, value)| Mutation::Word { anchor, slot, width, value }),
    ]
}

fn mutations() -> impl Strategy<Value = Vec<Mutation>> {
    prop::collection::vec(mutation(), 1..4)
}

fn is_separator(b: u8) -> bool {
    matches!(b, b' ' | b'\t' | b'\r' | b'\n' | b',' | b'=' | b'[' | b']' | b'{' | b'}' | b':')
}

/// Byte ranges of the tokens (maximal runs of non-separators).
fn tokens(bytes: &[u8]) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut start = None;
    for (i, &b) in bytes.iter().enumerate() {
        match (start, is_separator(b)) {
            (None, false) => start = Some(i),
            (Some(s), true) => {
                out.push((s, i));
                start = None;
            }
            _ => {}
        }
    }
    if let Some(s) = start {
        out.push((s, bytes.len()));
    }
    out
}

fn is_number(token: &[u8]) -> bool {
    let t = token.strip_prefix(b"\"").unwrap_or(token);
    t.first().is_some_and(|c| c.is_ascii_digit() || *c == b'-' || *c == b'+' || *c == b'.')
}

/// Line ranges (without their '\n').
fn lines(bytes: &[u8]) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut s = 0;
    for (i, &b) in bytes.iter().enumerate() {
        if b == b'\n' {
            out.push((s, i));
            s = i + 1;
        }
    }
    if s < bytes.len() {
        out.push((s, bytes.len()));
    }
    out
}

fn splice(bytes: &mut Vec<u8>, range: (usize, usize), with: &[u8]) {
    bytes.splice(range.0..range.1, with.iter().copied());
}

fn apply(bytes: &mut Vec<u8>, m: &Mutation) {
    if bytes.is_empty() {
        return;
    }
    match *m {
        Mutation::Token { at, with } => {
            let t = tokens(bytes);
            if !t.is_empty() {
                splice(bytes, t[at % t.len()], with.as_bytes());
            }
        }
        Mutation::Number { at, with } => {
            let t: Vec<_> = tokens(bytes).into_iter().filter(|&(a, b)| is_number(&bytes[a..b])).collect();
            if !t.is_empty() {
                splice(bytes, t[at % t.len()], with.as_bytes());
            }
        }
        Mutation::DeleteLines { at, len } => {
            let l = lines(bytes);
            let first = at % l.len();
            let last = (first + len - 1).min(l.len() - 1);
            let end = if last + 1 < l.len() { l[last + 1].0 } else { bytes.len() };
            bytes.drain(l[first].0..end);
        }
        Mutation::DuplicateLines { at, len } => {
            let l = lines(bytes);
            let first = at % l.len();
            let last = (first + len - 1).min(l.len() - 1);
            let end = if last + 1 < l.len() { l[last + 1].0 } else { bytes.len() };
            let mut copy = bytes[l[first].0..end].to_vec();
            if copy.last() != Some(&b'\n') {
                copy.push(b'\n');
            }
            bytes.splice(end..end, copy);
        }
        Mutation::SwapLines { a, b } => {
            let l = lines(bytes);
            let (a, b) = (l[a % l.len()], l[b % l.len()]);
            let (first, second) = if a.0 <= b.0 { (a, b) } else { (b, a) };
            if first != second {
                let s1 = bytes[first.0..first.1].to_vec();
                let s2 = bytes[second.0..second.1].to_vec();
                splice(bytes, second, &s1);
                splice(bytes, first, &s2);
            }
        }
        Mutation::InsertLine { at, line } => {
            let l = lines(bytes);
            let pos = l[at % l.len()].0;
            let mut text = line.as_bytes().to_vec();
            text.push(b'\n');
            bytes.splice(pos..pos, text);
        }
        Mutation::Truncate { per_mille } => {
            let keep = bytes.len() * per_mille as usize / 1000;
            bytes.truncate(keep);
        }
        Mutation::FlipByte { at, mask } => {
            let n = bytes.len();
            bytes[at % n] ^= mask;
        }
        Mutation::Word { anchor, slot, width, value } => {
            let anchors: Vec<usize> = lines(bytes)
                .into_iter()
                .filter(|&(a, b)| b > a && bytes[a] == b'$')
                .map(|(_, b)| b + 1)
                .filter(|&p| p < bytes.len())
                .collect();
            if anchors.is_empty() {
                return;
            }
            let pos = anchors[anchor % anchors.len()] + 4 * slot as usize;
            let w = value.to_le_bytes();
            for (k, &b) in w[..width as usize].iter().enumerate() {
                if let Some(x) = bytes.get_mut(pos + k) {
                    *x = b;
                }
            }
        }
    }
}

fn mutate(seed: &[u8], ms: &[Mutation]) -> Vec<u8> {
    let mut bytes = seed.to_vec();
    for m in ms {
        apply(&mut bytes, m);
    }
    bytes
}

// ---------------------------------------------------------------------------------------------
// oracle

/// A Rust Debug dump in a message: `Name { field: ...`, `Some(`, `Ok(`, `Err(`.
fn debug_dump(msg: &str) -> Option<String> {
    for pat in ["Some(", "Ok(", "Err(", "ParseIntError", "ParseFloatError", "Utf8Error", "Os { code"] {
        if msg.contains(pat) {
            return Some(pat.to_string());
        }
    }
    // `Ident { ident:` (a struct dump; JSON quotes its keys, so it does not look like this)
    let b = msg.as_bytes();
    let mut i = 0;
    while let Some(off) = msg[i..].find(" { ") {
        let brace = i + off;
        let before = &msg[..brace];
        let ident_before =
            before.chars().next_back().is_some_and(|c| c.is_alphanumeric() || c == '_') && !before.ends_with(' ');
        let after = &msg[brace + 3..];
        let field: String = after.chars().take_while(|c| c.is_ascii_alphanumeric() || *c == '_').collect();
        if ident_before && !field.is_empty() && after[field.len()..].starts_with(": ") {
            return Some(msg[brace.saturating_sub(20)..(brace + 3 + field.len() + 2).min(b.len())].to_string());
        }
        i = brace + 3;
    }
    None
}

fn check_error(msg: &str, file: &Path) -> Result<(), TestCaseError> {
    let name = file.file_name().unwrap().to_string_lossy();
    prop_assert!(!msg.trim().is_empty(), "empty error message");
    prop_assert!(msg.contains(&*name), "the error does not name the file {name}: {msg}");
    if let Some(dump) = debug_dump(msg) {
        return Err(TestCaseError::fail(format!("the error carries a Rust Debug dump ({dump}): {msg}")));
    }
    Ok(())
}

fn check_mesh(m: &ImportedMesh) -> Result<(), TestCaseError> {
    let n = m.nodes.len();
    prop_assert_eq!(m.node_ids.len(), n, "one id per node");
    prop_assert_eq!(m.element_ids.len(), m.connectivity.len(), "one id per element");
    prop_assert_eq!(m.element_types.len(), m.connectivity.len(), "one type per element");
    for (e, (kind, conn)) in m.element_types.iter().zip(&m.connectivity).enumerate() {
        prop_assert_eq!(conn.len(), kind.nodes_per_element(), "element {} has the node count of its type", e);
        prop_assert!(conn.iter().all(|&k| k < n), "element {} refers to a node beyond the {} read", e, n);
    }
    for (name, set) in &m.node_sets {
        prop_assert!(set.iter().all(|&k| k < n), "node set {} refers to a node beyond the {} read", name, n);
    }
    for (name, set) in &m.element_sets {
        prop_assert!(
            set.iter().all(|&k| k < m.connectivity.len()),
            "element set {} refers to an element beyond those read",
            name
        );
    }
    Ok(())
}

// ---------------------------------------------------------------------------------------------
// seeds

fn examples() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples")
}

const SPEC_SEEDS: &[&str] =
    &["beam.json", "l-beam.json", "t-square.json", "bracket/bracket.json", "bracket/bracket-inp.json"];

/// A matrices spec (not among the examples).
const MATRIX_SPEC: &str = r#"{
  "name": "Matrices",
  "geometry": { "matrices": { "stiffness": "K.mtx", "mass": "M.mtx", "dofs": "dofs.txt", "nodes": "nodes.txt", "free_free": true } },
  "damping": { "modal_bands": [ { "below": 100, "ratio": 0.01 }, { "below": 1e308, "ratio": 0.02 } ] },
  "flanges": [
    { "name": "base", "role": "motion", "nodes": { "plane": { "point": [0, 0, 0], "normal": [1, 0, 0], "tolerance": 1e-6 } } },
    { "name": "tip", "role": "force", "nodes": { "cylinder": { "point": [1, 0, 0], "axis": [1, 0, 0], "radius": 0.1, "length": 0.01 } }, "reference_point": [1, 0, 0] }
  ],
  "scene": { "loads": ["gravity", "rotation"], "band": [0, 150], "tolerance": 0.01 },
  "reduction": { "method": "krylov", "expansion_points": [20, 140], "moments": 2, "dynamic_cutoff": 1000 }
}"#;

/// A deck with what the reader knows: mixed element types, continuation lines, sets with
/// GENERATE, materials, a section, skipped analysis steps.
const INP_SEED: &str = "*HEADING
fuzz seed
*NODE, NSET=ALL
1, 0.0, 0.0, 0.0
2, 1.0, 0.0, 0.0
3, 0.0, 1.0, 0.0
4, 0.0, 0.0, 1.0
5, 0.5, 0.0, 0.0
6, 0.5, 0.5, 0.0
7, 0.0, 0.5, 0.0
8, 0.0, 0.0, 0.5
9, 0.5, 0.0, 0.5
10, 0.0, 0.5, 0.5
11, 1.0, 1.0, 1.0
*ELEMENT, TYPE=C3D10, ELSET=TETS
1, 1, 2, 3, 4, 5, 6, 7, 8,
9, 10
*ELEMENT, TYPE=C3D4, ELSET=TETS
2, 2, 3, 4, 11
*NSET, NSET=BASE, GENERATE
1, 4, 1
*NSET, NSET=TIP
11, BASE
*ELSET, ELSET=ALLE, GENERATE
1, 2
*MATERIAL, NAME=STEEL
*ELASTIC
2.1e11, 0.3
*DENSITY
7850.
*EXPANSION
1.2e-5
*SOLID SECTION, ELSET=ALLE, MATERIAL=STEEL
*STEP
*STATIC
*BOUNDARY
BASE, 1, 3
*CLOAD
11, 3, 1.0
*END STEP
";

const MSH_SEEDS: &[(&str, &[u8])] = &[
    ("tet4.msh", include_bytes!("../../fe-input/src/import/msh/testdata/tet4.msh")),
    ("tet10.msh", include_bytes!("../../fe-input/src/import/msh/testdata/tet10.msh")),
    ("hex8.msh", include_bytes!("../../fe-input/src/import/msh/testdata/hex8.msh")),
    ("hex20.msh", include_bytes!("../../fe-input/src/import/msh/testdata/hex20.msh")),
    ("tet4.bin.msh", include_bytes!("../../fe-input/src/import/msh/testdata/tet4.bin.msh")),
    ("tet10.bin.msh", include_bytes!("../../fe-input/src/import/msh/testdata/tet10.bin.msh")),
    ("hex8.bin.msh", include_bytes!("../../fe-input/src/import/msh/testdata/hex8.bin.msh")),
    ("hex20.bin.msh", include_bytes!("../../fe-input/src/import/msh/testdata/hex20.bin.msh")),
];

/// A small box part's deck and free-free matrices, generated by the builder itself (so the seeds
/// follow the writers), once per process.
struct Generated {
    decks: Vec<String>,
    /// K.mtx, M.mtx, dofs.txt, nodes.txt
    matrices: Vec<(String, Vec<u8>)>,
}

fn generated() -> &'static Generated {
    static CELL: std::sync::OnceLock<Generated> = std::sync::OnceLock::new();
    CELL.get_or_init(|| {
        let scratch = Scratch::new("fuzz-readers-seeds");
        let dir = scratch.path();
        let mut decks = Vec::new();
        let mut matrices = Vec::new();
        for (element, elements) in [("hex8", "[2, 1, 1]"), ("hex20", "[1, 1, 1]")] {
            let json = format!(
                r#"{{"name": "Seed", "geometry": {{"element": "{element}", "boxes": [{{"min": [0, 0, 0], "max": [1, 0.2, 0.1], "elements": {elements}}}]}},
                 "material": {{"E": 2e11, "nu": 0.3, "rho": 7850}},
                 "flanges": [{{"name": "base", "role": "motion", "nodes": {{"box_face": {{"box": 0, "face": "-x"}}}}}}],
                 "reduction": {{"modes": 2}}}}"#
            );
            let file = dir.join(format!("{element}.json"));
            std::fs::write(&file, &json).unwrap();
            let spec = Spec::from_file(&file).unwrap();
            let part = fmu_builder::model::part::part_of(&spec, &file).unwrap();
            decks.push(fmu_builder::model::export::abaqus_deck(&part, &[]));
            if element == "hex8" {
                let out = dir.join("matrices");
                fmu_builder::model::export::write_free_free_matrices(&out, &part, &|p, b| {
                    std::fs::write(p, b).map_err(|e| fmu_builder::error::BuildError::io(p, e))
                })
                .unwrap();
                for name in ["K.mtx", "M.mtx", "dofs.txt", "nodes.txt"] {
                    matrices.push((name.to_string(), std::fs::read(out.join(name)).unwrap()));
                }
            }
        }
        Generated { decks, matrices }
    })
}

// ---------------------------------------------------------------------------------------------
// targets

proptest! {
    #![proptest_config(fuzz::config(64))]

    /// The JSON input: the examples and a matrices spec, read from a file.
    #[test]
    fn spec_reader(seed in 0..SPEC_SEEDS.len() + 1, ms in mutations()) {
        limit_memory();
        let text = match SPEC_SEEDS.get(seed) {
            Some(name) => std::fs::read(examples().join(name)).unwrap(),
            None => MATRIX_SPEC.as_bytes().to_vec(),
        };
        let scratch = Scratch::new("fuzz-readers-spec");
        let dir = scratch.path();
        let file = dir.join("case.json");
        std::fs::write(&file, mutate(&text, &ms)).unwrap();
        if let Err(e) = Spec::from_file(&file) {
            check_error(&e.to_string(), &file)?;
        }
    }

    /// Abaqus/CalculiX decks: the hand-written seed, the builder's own export of a hex8 and a
    /// hex20 box, and the bracket's Gmsh export (long runs only: 0.5 MB a case).
    #[test]
    fn inp_reader(seed in 0..4usize, ms in mutations()) {
        limit_memory();
        let g = generated();
        let long = env_u64("FUZZ_CASES", 64) > 1000;
        let text: Vec<u8> = match seed {
            0 => INP_SEED.as_bytes().to_vec(),
            1 | 2 => g.decks[seed - 1].as_bytes().to_vec(),
            _ if long => std::fs::read(examples().join("bracket/bracket.inp")).unwrap(),
            _ => g.decks[0].as_bytes().to_vec(),
        };
        let scratch = Scratch::new("fuzz-readers-inp");
        let dir = scratch.path();
        let file = dir.join("case.inp");
        std::fs::write(&file, mutate(&text, &ms)).unwrap();
        match read_inp(&file) {
            Ok(mesh) => check_mesh(&mesh)?,
            Err(e) => check_error(&e.to_string(), &file)?,
        }
    }

    /// Gmsh MSH 4.1: the importer's test meshes, ASCII and binary, tet4 to hex20.
    #[test]
    fn msh_reader(seed in 0..MSH_SEEDS.len(), ms in mutations()) {
        limit_memory();
        let (name, bytes) = MSH_SEEDS[seed];
        let scratch = Scratch::new("fuzz-readers-msh");
        let dir = scratch.path();
        let file = dir.join(name);
        std::fs::write(&file, mutate(bytes, &ms)).unwrap();
        match read_msh(&file) {
            Ok(mesh) => check_mesh(&mesh)?,
            Err(e) => check_error(&e.to_string(), &file)?,
        }
    }

    /// Matrix Market files on their own (K and M of a hex8 box).
    #[test]
    fn matrix_market_reader(seed in 0..2usize, ms in mutations()) {
        limit_memory();
        let (name, bytes) = &generated().matrices[seed];
        let text = String::from_utf8_lossy(&mutate(bytes, &ms)).into_owned();
        let file = Path::new("fuzz").join(name);
        match parse_matrix_market(&text, &file) {
            Ok(m) => prop_assert_eq!(m.nrows(), m.ncols()),
            Err(e) => check_error(&e.to_string(), &file)?,
        }
    }

    /// A whole matrix model (K, M, DoF map, node table), one or two files mutated: sizes, the
    /// DoF map against the nodes, the positive diagonals, M's Cholesky, the free-free check.
    #[test]
    fn matrix_model_reader(which in prop::collection::vec((0..4usize, mutations()), 1..3)) {
        limit_memory();
        let g = generated();
        let scratch = Scratch::new("fuzz-readers-matrices");
        let dir = scratch.path();
        let mut files: Vec<(PathBuf, Vec<u8>)> =
            g.matrices.iter().map(|(n, b)| (dir.join(n), b.clone())).collect();
        for (k, ms) in &which {
            files[*k].1 = mutate(&files[*k].1, ms);
        }
        for (path, bytes) in &files {
            std::fs::write(path, bytes).unwrap();
        }
        let spec = MatrixFiles {
            stiffness: &files[0].0,
            mass: &files[1].0,
            damping: None,
            dof_map: &files[2].0,
            nodes: &files[3].0,
        };
        if let Err(e) = read_matrix_model(&spec, true) {
            let msg = e.to_string();
            prop_assert!(
                files.iter().any(|(p, _)| msg.contains(&*p.file_name().unwrap().to_string_lossy())),
                "the error names none of the files: {}", msg
            );
            if let Some(dump) = debug_dump(&msg) {
                return Err(TestCaseError::fail(format!("the error carries a Rust Debug dump ({dump}): {msg}")));
            }
        }
    }
}

/// The seeds themselves are valid: the mutations start from inputs the readers accept.
#[test]
fn seeds_are_accepted() {
    let scratch = Scratch::new("fuzz-readers-check");
    let dir = scratch.path();
    for name in SPEC_SEEDS {
        Spec::from_file(&examples().join(name)).unwrap();
    }
    let file = dir.join("m.json");
    std::fs::write(&file, MATRIX_SPEC).unwrap();
    Spec::from_file(&file).unwrap();
    let g = generated();
    for (k, deck) in std::iter::once(INP_SEED.to_string()).chain(g.decks.iter().cloned()).enumerate() {
        let file = dir.join(format!("d{k}.inp"));
        std::fs::write(&file, deck).unwrap();
        let mesh = read_inp(&file).unwrap();
        assert!(mesh.num_elements() > 0);
    }
    for (name, bytes) in MSH_SEEDS {
        let file = dir.join(name);
        std::fs::write(&file, bytes).unwrap();
        assert!(read_msh(&file).unwrap().num_elements() > 0);
    }
    let paths: Vec<PathBuf> = g.matrices.iter().map(|(n, _)| dir.join(n)).collect();
    for ((_, bytes), p) in g.matrices.iter().zip(&paths) {
        std::fs::write(p, bytes).unwrap();
    }
    let files =
        MatrixFiles { stiffness: &paths[0], mass: &paths[1], damping: None, dof_map: &paths[2], nodes: &paths[3] };
    read_matrix_model(&files, true).unwrap();
    // the oracle itself
    assert!(debug_dump("x.inp:3: ParseIntError { kind: InvalidDigit }").is_some());
    assert!(debug_dump("cannot build the sparse matrix: OutOfBounds { row: 3, col: 4 }").is_some());
    assert!(debug_dump("a.json: flanges[0].nodes: {\"box\": 0} is not valid").is_none());
    assert!(debug_dump("x.msh: line 3: expected 4 numbers { got 2 }").is_none());
}
