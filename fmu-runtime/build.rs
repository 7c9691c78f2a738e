//! The runtime's build identity: the package version and a hash of the sources the binary is
//! compiled from (this crate's and the `fmi2` layer's). The builder links this crate as a
//! library and so knows the identity of its own runtime; it packages a runtime binary built on
//! another platform (`--platform-binary`) only when that binary carries the same identity,
//! because the reduced-model file and the variable table it writes are those of its own
//! runtime source. Line endings are normalised so that a Windows checkout (CRLF) of the same
//! commit hashes the same; std only: the runtime takes no new dependency for this.

use std::path::{Path, PathBuf};

fn main() {
    let manifest = PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").expect("cargo sets CARGO_MANIFEST_DIR"));
    let out_dir = PathBuf::from(std::env::var("OUT_DIR").expect("cargo sets OUT_DIR"));
    let roots = [("fmu-runtime/src", manifest.join("src")), ("fmi2/src", manifest.join("../fmi2/src"))];
    let mut files = Vec::new();
    for (name, dir) in &roots {
        println!("cargo:rerun-if-changed={}", dir.display());
        collect_sources(dir, name, &mut files);
    }
    // file names with forward slashes, sorted: the same on every platform and file system
    files.sort();
    let mut hash = Fnv1a64::new();
    for (name, path) in &files {
        let text = std::fs::read(path).unwrap_or_else(|e| panic!("cannot read {}: {e}", path.display()));
        hash.update(name.as_bytes());
        hash.update(&[0]);
        hash.update(&normalise_line_endings(&text));
        hash.update(&[0]);
    }
    let id = format!("{}+src.{:016x}", std::env::var("CARGO_PKG_VERSION").unwrap_or_default(), hash.finish());
    let code = format!(
        "/// This runtime's build identity: version and source hash (see build.rs).\n\
         pub const BUILD_ID: &str = \"{id}\";\n"
    );
    std::fs::write(out_dir.join("build_id.rs"), code).expect("cannot write build_id.rs into OUT_DIR");
}

/// Every `.rs` file below `dir`, named `prefix/relative/path.rs`.
fn collect_sources(dir: &Path, prefix: &str, out: &mut Vec<(String, PathBuf)>) {
    let entries = std::fs::read_dir(dir).unwrap_or_else(|e| panic!("cannot list {}: {e}", dir.display()));
    for entry in entries {
        let path = entry.unwrap_or_else(|e| panic!("cannot list {}: {e}", dir.display())).path();
        let Some(file_name) = path.file_name().and_then(|n| n.to_str()).map(str::to_owned) else { continue };
        let name = format!("{prefix}/{file_name}");
        if path.is_dir() {
            collect_sources(&path, &name, out);
        } else if file_name.ends_with(".rs") {
            out.push((name, path));
        }
    }
}

/// CRLF -> LF.
fn normalise_line_endings(text: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(text.len());
    for (i, &b) in text.iter().enumerate() {
        if !(b == b'\r' && text.get(i + 1) == Some(&b'\n')) {
            out.push(b);
        }
    }
    out
}

/// 64-bit FNV-1a: tells one source tree from another (a consistency check between builds of
/// this project, not a defence against forgery).
struct Fnv1a64(u64);

impl Fnv1a64 {
    fn new() -> Self {
        Self(0xcbf2_9ce4_8422_2325)
    }
    fn update(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 ^= u64::from(b);
            self.0 = self.0.wrapping_mul(0x0000_0100_0000_01b3);
        }
    }
    fn finish(&self) -> u64 {
        self.0
    }
}
