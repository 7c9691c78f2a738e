//! Fuzzing of the reduced-model loader (`ReducedBody::from_bytes`, `format::Container`) and of
//! the FMU built on what it accepts.
//!
//! Seeds: valid bodies (mounted, rotating with all stiffening terms, free-floating, one with
//! quasi-static modes). Each case decodes the seed's entries, mutates them (values set to NaN,
//! +-inf, +-1e308, 0, denormals, negatives; dimensions changed consistently or not; entries
//! removed, duplicated, renamed, added, of the other kind; texts emptied or odd), re-encodes the
//! container, then possibly mutates raw bytes (flips, 8-byte words, truncation, payload length)
//! and in nearly every case recomputes the CRC, so the content checks behind it are reached.
//!
//! Oracle: `from_bytes` never panics, crashes or hangs (each case runs in a child process:
//! proptest's `fork` and `timeout`, with a memory ceiling); an error is a sentence about the
//! reduced-model file, not a Debug dump; an accepted body is usable: instantiated through the FMI
//! entry points (Co-Simulation and Model Exchange), initialised, stepped and read, it never
//! panics (no "panic in the model" logged), every non-OK status comes with a logged message, and
//! nothing non-finite is returned with fmi2OK or fmi2Warning.
//!
//! Short mode (CI): `FUZZ_CASES` cases, default 96. Long mode (docs/FUZZING.md):
//! `FUZZ_CASES=20000 FUZZ_SEED=7 cargo test --release -p fmu-runtime --test fuzz_reduced_loader`.

use std::ffi::CString;

use fmi2::api;
use fmi2::types::fmi2Status::{fmi2OK, fmi2Warning};
use fmi2::types::*;
use fmi2::{Causality, Interface, Model, VarType};
use fmu_runtime::fmu::BodyFmu;
use fmu_runtime::format::{FORMAT_VERSION, MAGIC, RESOURCE_FILE};
use fmu_runtime::interface::VariableTable;
use fmu_runtime::reduced::{ReducedBody, free_two_mode_body, rotating_two_mode_body, two_mode_body};
use proptest::prelude::*;
use proptest::sample::select;
use test_support::fuzz::{self, limit_memory};
use test_support::logger::Log;
use test_support::scratch::{Scratch, file_uri};

// ---------------------------------------------------------------------------------------------
// seeds

fn seeds() -> Vec<Vec<u8>> {
    let mounted = two_mode_body();
    let rotating = rotating_two_mode_body();
    let free = free_two_mode_body();
    let mut split = two_mode_body();
    split.dynamic_cutoff = 100.0;
    split.modal_damping = vec![0.02, 0.05];
    [mounted, rotating, free, split].iter().map(ReducedBody::to_bytes).collect()
}

// ---------------------------------------------------------------------------------------------
// the container, decoded here independently of the crate (the layout of format.rs)

#[derive(Debug, Clone)]
enum Value {
    Array { dims: Vec<u64>, values: Vec<f64> },
    Text(Vec<u8>),
}

fn decode(bytes: &[u8]) -> Vec<(Vec<u8>, Value)> {
    let mut pos = 20;
    let u = |pos: &mut usize, n: usize| -> u64 {
        let mut w = [0u8; 8];
        w[..n].copy_from_slice(&bytes[*pos..*pos + n]);
        *pos += n;
        u64::from_le_bytes(w)
    };
    let count = u(&mut pos, 4);
    let mut out = Vec::new();
    for _ in 0..count {
        let len = u(&mut pos, 2) as usize;
        let name = bytes[pos..pos + len].to_vec();
        pos += len;
        let kind = u(&mut pos, 1);
        if kind == 0 {
            let rank = u(&mut pos, 1);
            let dims: Vec<u64> = (0..rank).map(|_| u(&mut pos, 8)).collect();
            let total: u64 = dims.iter().product();
            let values = (0..total).map(|_| f64::from_bits(u(&mut pos, 8))).collect();
            out.push((name, Value::Array { dims, values }));
        } else {
            let len = u(&mut pos, 8) as usize;
            out.push((name, Value::Text(bytes[pos..pos + len].to_vec())));
            pos += len;
        }
    }
    out
}

fn encode_payload(entries: &[(Vec<u8>, Value)]) -> Vec<u8> {
    let mut p = Vec::new();
    p.extend_from_slice(&(entries.len() as u32).to_le_bytes());
    for (name, v) in entries {
        p.extend_from_slice(&(name.len() as u16).to_le_bytes());
        p.extend_from_slice(name);
        match v {
            Value::Array { dims, values } => {
                p.push(0);
                p.push(dims.len() as u8);
                for d in dims {
                    p.extend_from_slice(&d.to_le_bytes());
                }
                for x in values {
                    p.extend_from_slice(&x.to_le_bytes());
                }
            }
            Value::Text(t) => {
                p.push(1);
                p.extend_from_slice(&(t.len() as u64).to_le_bytes());
                p.extend_from_slice(t);
            }
        }
    }
    p
}

fn frame(payload: &[u8], length: u64) -> Vec<u8> {
    let mut out = Vec::with_capacity(payload.len() + 24);
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&FORMAT_VERSION.to_le_bytes());
    out.extend_from_slice(&length.to_le_bytes());
    out.extend_from_slice(payload);
    out
}

fn seal(mut body: Vec<u8>) -> Vec<u8> {
    let crc = crc32fast::hash(&body);
    body.extend_from_slice(&crc.to_le_bytes());
    body
}

// ---------------------------------------------------------------------------------------------
// mutations

const VALUES: &[f64] = &[
    f64::NAN,
    f64::INFINITY,
    f64::NEG_INFINITY,
    1e308,
    -1e308,
    f64::MAX,
    0.0,
    -0.0,
    5e-324,
    2.2250738585072014e-308,
    -1.0,
    1.0,
    0.5,
    3.0,
    1e4,
    1e-300,
    1e300,
];

const NAMES: &[&str] = &[
    "omega",
    "flange.count",
    "flange.0.name",
    "flange.0.shapes",
    "flange.1.name",
    "free_floating",
    "rotation.G",
    "rotation.O",
    "stiffening",
    "stiffening.centrifugal",
    "stiffening.flange.0",
    "dynamic_cutoff",
    "damping.modal",
    "mass",
    "inertia",
    "guid",
    "mount.name",
    "",
    "\u{0}",
];

const TEXTS: &[&str] = &["", "{test}", "\u{0}", "base", "tip", "\u{e9}\u{e9}", "%s%n%s", "a\nb"];

const WORDS: &[u64] = &[
    0,
    1,
    2,
    3,
    0xff,
    0xffff,
    0xffff_ffff,
    0x1_0000_0000,
    0x1000_0000_0000_0000,
    0x7fff_ffff_ffff_ffff,
    u64::MAX,
    0x7ff8_0000_0000_0000,
    0x7ff0_0000_0000_0000,
];

#[derive(Debug, Clone)]
enum Edit {
    SetValue {
        entry: usize,
        index: usize,
        value: f64,
    },
    /// Every value of the entry.
    Fill {
        entry: usize,
        value: f64,
    },
    /// Change dimension `dim` to `to` and resize the values to match.
    Resize {
        entry: usize,
        dim: usize,
        to: u64,
    },
    /// Change a dimension without the values (the sizes disagree).
    Dims {
        entry: usize,
        dim: usize,
        to: u64,
    },
    Remove {
        entry: usize,
    },
    Duplicate {
        entry: usize,
    },
    Rename {
        entry: usize,
        to: &'static str,
    },
    ToText {
        entry: usize,
        text: &'static str,
    },
    ToScalar {
        entry: usize,
        value: f64,
    },
    Add {
        name: &'static str,
        value: f64,
    },
    /// Swap two values of an array (omega out of order, ...).
    Swap {
        entry: usize,
        a: usize,
        b: usize,
    },
}

#[derive(Debug, Clone)]
enum Raw {
    Flip {
        at: usize,
        mask: u8,
    },
    Word {
        at: usize,
        value: u64,
    },
    /// Cut the payload and state the cut length (a consistent, short file).
    CutPayload {
        per_mille: u16,
    },
    /// State a different payload length.
    Length {
        value: u64,
    },
    Truncate {
        per_mille: u16,
    },
}

fn edit() -> impl Strategy<Value = Edit> {
    let e = any::<usize>();
    prop_oneof![
        4 => (e, any::<usize>(), select(VALUES)).prop_map(|(entry, index, value)| Edit::SetValue { entry, index, value }),
        2 => (e, select(VALUES)).prop_map(|(entry, value)| Edit::Fill { entry, value }),
        2 => (e, 0..4usize, prop_oneof![0..6u64, Just(1000u64)]).prop_map(|(entry, dim, to)| Edit::Resize { entry, dim, to }),
        1 => (e, 0..4usize, select(WORDS)).prop_map(|(entry, dim, to)| Edit::Dims { entry, dim, to }),
        2 => e.prop_map(|entry| Edit::Remove { entry }),
        1 => e.prop_map(|entry| Edit::Duplicate { entry }),
        1 => (e, select(NAMES)).prop_map(|(entry, to)| Edit::Rename { entry, to }),
        1 => (e, select(TEXTS)).prop_map(|(entry, text)| Edit::ToText { entry, text }),
        1 => (e, select(VALUES)).prop_map(|(entry, value)| Edit::ToScalar { entry, value }),
        2 => (select(NAMES), select(VALUES)).prop_map(|(name, value)| Edit::Add { name, value }),
        1 => (e, any::<usize>(), any::<usize>()).prop_map(|(entry, a, b)| Edit::Swap { entry, a, b }),
    ]
}

fn raw() -> impl Strategy<Value = Raw> {
    prop_oneof![
        3 => (any::<usize>(), 1..=255u8).prop_map(|(at, mask)| Raw::Flip { at, mask }),
        3 => (any::<usize>(), select(WORDS)).prop_map(|(at, value)| Raw::Word { at, value }),
        1 => (0..1000u16).prop_map(|per_mille| Raw::CutPayload { per_mille }),
        1 => select(WORDS).prop_map(|value| Raw::Length { value }),
        1 => (0..1000u16).prop_map(|per_mille| Raw::Truncate { per_mille }),
    ]
}

#[derive(Debug, Clone)]
struct Case {
    seed: usize,
    edits: Vec<Edit>,
    raw: Vec<Raw>,
    /// Keep the CRC of the unmutated bytes (rarely: the checksum check itself).
    stale_crc: bool,
}

fn case() -> impl Strategy<Value = Case> {
    (0..4usize, prop::collection::vec(edit(), 0..4), prop::collection::vec(raw(), 0..2), prop::bool::weighted(0.05))
        .prop_map(|(seed, edits, raw, stale_crc)| Case { seed, edits, raw, stale_crc })
}

fn apply(entries: &mut Vec<(Vec<u8>, Value)>, e: &Edit) {
    let n = entries.len();
    if n == 0 {
        if let Edit::Add { name, value } = *e {
            entries.push((name.as_bytes().to_vec(), Value::Array { dims: vec![1], values: vec![value] }));
        }
        return;
    }
    match *e {
        Edit::SetValue { entry, index, value } => {
            if let Value::Array { values, .. } = &mut entries[entry % n].1
                && !values.is_empty()
            {
                let k = index % values.len();
                values[k] = value;
            }
        }
        Edit::Fill { entry, value } => {
            if let Value::Array { values, .. } = &mut entries[entry % n].1 {
                values.iter_mut().for_each(|v| *v = value);
            }
        }
        Edit::Resize { entry, dim, to } => {
            if let Value::Array { dims, values } = &mut entries[entry % n].1 {
                if dims.is_empty() {
                    dims.push(to);
                } else {
                    let d = dim % dims.len();
                    dims[d] = to;
                }
                let total: u64 = dims.iter().product();
                values.resize(total.min(1 << 20) as usize, 0.25);
            }
        }
        Edit::Dims { entry, dim, to } => {
            if let Value::Array { dims, .. } = &mut entries[entry % n].1
                && !dims.is_empty()
            {
                let d = dim % dims.len();
                dims[d] = to;
            }
        }
        Edit::Remove { entry } => {
            entries.remove(entry % n);
        }
        Edit::Duplicate { entry } => {
            let copy = entries[entry % n].clone();
            entries.push(copy);
        }
        Edit::Rename { entry, to } => entries[entry % n].0 = to.as_bytes().to_vec(),
        Edit::ToText { entry, text } => entries[entry % n].1 = Value::Text(text.as_bytes().to_vec()),
        Edit::ToScalar { entry, value } => entries[entry % n].1 = Value::Array { dims: vec![1], values: vec![value] },
        Edit::Add { name, value } => {
            entries.push((name.as_bytes().to_vec(), Value::Array { dims: vec![1], values: vec![value] }))
        }
        Edit::Swap { entry, a, b } => {
            if let Value::Array { values, .. } = &mut entries[entry % n].1
                && !values.is_empty()
            {
                let len = values.len();
                values.swap(a % len, b % len);
            }
        }
    }
}

/// The file bytes of a case.
fn build(seed: &[u8], c: &Case) -> Vec<u8> {
    let mut entries = decode(seed);
    for e in &c.edits {
        apply(&mut entries, e);
    }
    let payload = encode_payload(&entries);
    let mut length = payload.len() as u64;
    let mut body = frame(&payload, length);
    for r in &c.raw {
        match *r {
            Raw::Flip { at, mask } => {
                let len = body.len();
                body[at % len] ^= mask;
            }
            Raw::Word { at, value } => {
                let start = at % body.len();
                for (k, b) in value.to_le_bytes().into_iter().enumerate() {
                    if let Some(x) = body.get_mut(start + k) {
                        *x = b;
                    }
                }
            }
            Raw::CutPayload { per_mille } => {
                length = length * per_mille as u64 / 1000;
                body.truncate(20 + length as usize);
                body[12..20].copy_from_slice(&length.to_le_bytes());
            }
            Raw::Length { value } => body[12..20].copy_from_slice(&value.to_le_bytes()),
            Raw::Truncate { per_mille } => {
                let keep = body.len() * per_mille as usize / 1000;
                body.truncate(keep);
            }
        }
    }
    if c.stale_crc {
        let crc = crc32fast::hash(&frame(&payload, payload.len() as u64));
        body.extend_from_slice(&crc.to_le_bytes());
        body
    } else {
        seal(body)
    }
}

// ---------------------------------------------------------------------------------------------
// oracle

fn debug_dump(msg: &str) -> Option<&'static str> {
    ["Some(", "Ok(", "Err(", "{ at:", "{ name:", "{ stored:", "Malformed(", "Missing(", "Shape {", "Truncated {"]
        .into_iter()
        .find(|p| msg.contains(p))
}

/// Checks one FMI call: non-OK needs a logged message; no panic logged.
struct Host<'a> {
    log: &'a Log,
    violations: Vec<String>,
}

impl Host<'_> {
    fn check(&mut self, call: &str, status: fmi2Status, logged_before: usize) -> bool {
        let log = self.log.entries()[logged_before..].to_vec();
        if let Some(e) = log.iter().find(|e| e.text.contains("panic")) {
            self.violations.push(format!("{call}: panic in the model: {}", e.text));
        }
        if status != fmi2OK && !log.iter().any(|e| e.status != fmi2OK) {
            self.violations.push(format!("{call} returned {status:?} without a logged message"));
        }
        status == fmi2OK || status == fmi2Warning
    }

    fn finite(&mut self, call: &str, values: &[f64]) {
        if let Some(k) = values.iter().position(|v| !v.is_finite()) {
            self.violations.push(format!("{call} returned {} at index {k} with fmi2OK/fmi2Warning", values[k]));
        }
    }
}

/// Instantiates the accepted body through the FMI entry points and runs it a little.
fn exercise(body: &ReducedBody, bytes: &[u8], kind: fmi2Type) -> Vec<String> {
    let dir = Scratch::new("fuzz-loader");
    std::fs::write(dir.path().join(RESOURCE_FILE), bytes).unwrap();
    let uri = file_uri(dir.path());
    let Ok(guid) = CString::new(body.guid.clone()) else { return vec![] };
    let table = VariableTable::new(body);
    let reals: Vec<u32> = table
        .variables
        .iter()
        .filter(|v| v.var_type == VarType::Real && v.causality != Causality::Input)
        .map(|v| v.vr)
        .collect();
    let log = Box::<Log>::default();
    let cb = log.callbacks();
    let mut host = Host { log: &log, violations: Vec::new() };
    unsafe {
        let n = log.len();
        let c = api::fmi2Instantiate::<BodyFmu>(c"fuzz".as_ptr(), kind, guid.as_ptr(), uri.as_ptr(), &cb, 0, 1);
        if c.is_null() {
            if !log.entries()[n..].iter().any(|e| e.status != fmi2OK) {
                host.violations.push("fmi2Instantiate returned NULL without a logged message".into());
            }
            return host.violations;
        }
        let n = log.len();
        let s = api::fmi2SetupExperiment::<BodyFmu>(c, 0, 0.0, 0.0, 0, 0.0);
        let mut alive = host.check("fmi2SetupExperiment", s, n);
        for (name, f) in [
            ("fmi2EnterInitializationMode", api::fmi2EnterInitializationMode::<BodyFmu> as unsafe fn(_) -> _),
            ("fmi2ExitInitializationMode", api::fmi2ExitInitializationMode::<BodyFmu>),
        ] {
            if alive {
                let n = log.len();
                let s = f(c);
                alive = host.check(name, s, n);
            }
        }
        let mut values = vec![0.0; reals.len()];
        if alive {
            if kind == fmi2CoSimulation {
                let mut t = 0.0;
                for h in [1e-3, 1e-2, 1.0] {
                    let n = log.len();
                    let s = api::fmi2DoStep::<BodyFmu>(c, t, h, 1);
                    t += h;
                    if !host.check("fmi2DoStep", s, n) {
                        break;
                    }
                    let n = log.len();
                    let s = api::fmi2GetReal::<BodyFmu>(c, reals.as_ptr(), reals.len(), values.as_mut_ptr());
                    if host.check("fmi2GetReal", s, n) {
                        host.finite("fmi2GetReal", &values);
                    }
                }
            } else {
                let n = log.len();
                let s = api::fmi2EnterContinuousTimeMode::<BodyFmu>(c);
                if host.check("fmi2EnterContinuousTimeMode", s, n) {
                    let nx = BodyFmu::for_interface(body.clone(), Interface::ModelExchange).n_states();
                    let mut x = vec![0.0; nx];
                    let mut dx = vec![0.0; nx];
                    for name in ["fmi2GetContinuousStates", "fmi2GetDerivatives", "fmi2GetReal"] {
                        let n = log.len();
                        let (s, out) = match name {
                            "fmi2GetContinuousStates" => {
                                (api::fmi2GetContinuousStates::<BodyFmu>(c, x.as_mut_ptr(), nx), &x)
                            }
                            "fmi2GetDerivatives" => (api::fmi2GetDerivatives::<BodyFmu>(c, dx.as_mut_ptr(), nx), &dx),
                            _ => (
                                api::fmi2GetReal::<BodyFmu>(c, reals.as_ptr(), reals.len(), values.as_mut_ptr()),
                                &values,
                            ),
                        };
                        if host.check(name, s, n) {
                            let out = out.clone();
                            host.finite(name, &out);
                        }
                    }
                }
            }
        }
        api::fmi2FreeInstance::<BodyFmu>(c);
    }
    host.violations
}

// ---------------------------------------------------------------------------------------------

proptest! {
    #![proptest_config(fuzz::config(96))]

    #[test]
    fn reduced_model_loader(c in case()) {
        limit_memory();
        let seeds = seeds();
        let bytes = build(&seeds[c.seed], &c);
        let result = ReducedBody::from_bytes(&bytes);
        if std::env::var_os("FUZZ_VERBOSE").is_some() {
            eprintln!("fuzz case: {}", result.as_ref().map(|_| "accepted".to_string()).unwrap_or_else(|e| e.to_string()));
        }
        match result {
            Err(e) => {
                let msg = e.to_string();
                prop_assert!(msg.contains("reduced-model"), "the error does not say what is wrong with what: {}", msg);
                if let Some(dump) = debug_dump(&msg) {
                    return Err(TestCaseError::fail(format!("the error carries a Rust Debug dump ({dump}): {msg}")));
                }
            }
            Ok(body) => {
                for kind in [fmi2CoSimulation, fmi2ModelExchange] {
                    let v = exercise(&body, &bytes, kind);
                    prop_assert!(v.is_empty(), "accepted body, fmi2Type {}: {}", kind, v.join("; "));
                }
            }
        }
    }
}

/// The seeds load, and the decoder here reads what the crate writes.
#[test]
fn seeds_load_and_round_trip() {
    for (k, seed) in seeds().iter().enumerate() {
        let body = ReducedBody::from_bytes(seed).unwrap();
        let again = seal(frame(&encode_payload(&decode(seed)), (seed.len() - 24) as u64));
        assert_eq!(&again, seed, "seed {k}");
        for kind in [fmi2CoSimulation, fmi2ModelExchange] {
            assert_eq!(exercise(&body, seed, kind), Vec::<String>::new(), "seed {k}");
        }
    }
}
