//! Hands the builder the FMU's linux64 runtime to embed (`RUNTIME_SO` in src/output/package.rs
//! includes `$OUT_DIR/fmu_runtime.so`). It builds nothing and runs no program: the runtime cdylib
//! is built once, in the workspace's own target folder, by `cargo xtask runtime` (xtask/: linked
//! by zig against glibc 2.17 where zig and cargo-zigbuild are found, see docs/PLATFORMS.md),
//! which places it at `<target>/fmu-runtime/libfmu_runtime.so` with a record beside it
//! (`runtime.info`, fmu-builder/build/runtime_stamp.rs). `cargo xtask build` and `cargo xtask run`
//! run it before building the builder, as tests/run.sh does before its first cargo build.
//!
//! The runtime taken is the first of:
//!
//! - `FMU_RUNTIME_SO`: a prebuilt one, embedded as it is ("prebuilt, FMU_RUNTIME_SO");
//! - `fmu-runtime/` in the target folder of this build (the first folder above `OUT_DIR` with
//!   cargo's CACHEDIR.TAG: `CARGO_TARGET_DIR` and `build.target-dir` included);
//! - `fmu-runtime/` in the workspace's `target/` (where this build's target folder is another:
//!   `CARGO_TARGET_DIR` or `--target-dir` set for this build only).
//!
//! None there is an error that names `cargo xtask runtime`. The file must be a 64-bit ELF shared
//! object exporting `fmi2Instantiate`. In a source tree, the runtime of the target folder must
//! also have been built from the sources now there: the record's hash of them
//! (`runtime_stamp::INPUTS`: fmu-runtime/, fmi2/, the workspace manifest, Cargo.lock and the cargo
//! configuration) is recomputed, and cargo reruns this script whenever one of them changes, so
//! a runtime older than its sources is refused with the command that rebuilds it rather than
//! embedded silently. `FMU_RUNTIME_PORTABLE=require` (CI) refuses a natively linked one.
//!
//! The builder's `--version` says which kind of linux64 binary it embeds (`FMU_RUNTIME_LINUX64`)
//! and, for a native one, the newest glibc it needs (`FMU_RUNTIME_NATIVE_GLIBC`, empty for a
//! portable or prebuilt one), so that the builder can warn on every FMU it packages.

use std::env;
use std::path::{Path, PathBuf};

#[path = "build/runtime_stamp.rs"]
mod runtime_stamp;

use runtime_stamp::{COMMAND, DIR, INFO, INPUTS, Record, SO};

/// The kind of a runtime given by `FMU_RUNTIME_SO`.
const PREBUILT: &str = "prebuilt, FMU_RUNTIME_SO";
/// What every runtime must export (the builder checks all 44 fmi2 functions of binaries handed to
/// it; one here tells a runtime from any other shared object).
const EXPORT: &str = "fmi2Instantiate";

/// The runtime to embed: its bytes, kind and native glibc.
struct Runtime {
    bytes: Vec<u8>,
    kind: String,
    native_glibc: String,
}

fn main() {
    match runtime() {
        Ok(runtime) => embed(&runtime),
        // cargo prints it as an error and fails the build
        Err(e) => println!("cargo::error={}", e.replace('\n', " ")),
    }
}

fn embed(runtime: &Runtime) {
    let out_dir = PathBuf::from(env::var("OUT_DIR").expect("cargo sets OUT_DIR"));
    let dest = out_dir.join("fmu_runtime.so");
    // an unchanged binary keeps its file time: the builder is not recompiled for nothing
    if std::fs::read(&dest).ok().as_deref() != Some(runtime.bytes.as_slice()) {
        std::fs::write(&dest, &runtime.bytes).unwrap_or_else(|e| panic!("cannot write {}: {e}", dest.display()));
    }
    println!("cargo:rustc-env=FMU_RUNTIME_LINUX64={}", runtime.kind);
    println!("cargo:rustc-env=FMU_RUNTIME_NATIVE_GLIBC={}", runtime.native_glibc);
}

fn runtime() -> Result<Runtime, String> {
    println!("cargo:rerun-if-env-changed=FMU_RUNTIME_SO");
    println!("cargo:rerun-if-env-changed=FMU_RUNTIME_PORTABLE");
    if let Some(prebuilt) = env::var_os("FMU_RUNTIME_SO") {
        let so = PathBuf::from(prebuilt);
        println!("cargo:rerun-if-changed={}", so.display());
        let bytes = std::fs::read(&so).map_err(|e| {
            format!(
                "cannot read FMU_RUNTIME_SO={} ({e}): name an existing runtime binary, or unset FMU_RUNTIME_SO to \
                 embed the one `{COMMAND}` builds",
                so.display()
            )
        })?;
        check_runtime(&bytes, &so, "FMU_RUNTIME_SO")?;
        return Ok(Runtime { bytes, kind: PREBUILT.to_string(), native_glibc: String::new() });
    }
    let manifest_dir = PathBuf::from(env::var("CARGO_MANIFEST_DIR").expect("cargo sets CARGO_MANIFEST_DIR"));
    let workspace = manifest_dir.parent().unwrap_or(&manifest_dir).to_path_buf();
    let out_dir = PathBuf::from(env::var("OUT_DIR").expect("cargo sets OUT_DIR"));
    let mut candidates: Vec<PathBuf> =
        out_dir.ancestors().filter(|dir| dir.join("CACHEDIR.TAG").is_file()).map(|dir| dir.join(DIR)).collect();
    candidates.push(workspace.join("target").join(DIR));
    candidates.dedup();
    let Some(dir) = candidates.iter().find(|dir| dir.join(SO).is_file()) else {
        let looked: Vec<String> = candidates.iter().map(|d| d.join(SO).display().to_string()).collect();
        return Err(format!(
            "no fmu-runtime binary to embed (looked for {}): build it first with `{COMMAND}` in the workspace \
             (or `cargo xtask build`, which builds the runtime and then the builder), or name a prebuilt one with FMU_RUNTIME_SO",
            looked.join(", ")
        ));
    };
    let so = dir.join(SO);
    let info = dir.join(INFO);
    println!("cargo:rerun-if-changed={}", so.display());
    println!("cargo:rerun-if-changed={}", info.display());
    let bytes = std::fs::read(&so)
        .map_err(|e| format!("cannot read {} ({e}): rebuild the runtime with `{COMMAND}`", so.display()))?;
    check_runtime(&bytes, &so, "the runtime")?;
    let text = std::fs::read_to_string(&info)
        .map_err(|e| format!("cannot read {} ({e}): rebuild the runtime with `{COMMAND}`", info.display()))?;
    let record =
        Record::parse(&text).map_err(|e| format!("{}: {e}: rebuild the runtime with `{COMMAND}`", info.display()))?;
    if record.binary != runtime_stamp::hash_bytes(&bytes) {
        return Err(format!(
            "{} is not the binary {} describes (replaced by hand?): rebuild the runtime with `{COMMAND}`",
            so.display(),
            info.display()
        ));
    }
    check_sources(&workspace, &record, &so)?;
    if record.kind.starts_with("native") && env::var("FMU_RUNTIME_PORTABLE").is_ok_and(|m| m.trim() == "require") {
        return Err(format!(
            "FMU_RUNTIME_PORTABLE=require, but {} is linked natively ({}): set up zig and cargo-zigbuild \
             (bash tests/run.sh --setup-only) and run `{COMMAND}`",
            so.display(),
            record.kind
        ));
    }
    Ok(Runtime { bytes, kind: record.kind, native_glibc: record.native_glibc })
}

/// Ok when `bytes` (of `path`) are a runtime binary.
fn check_runtime(bytes: &[u8], path: &Path, what: &str) -> Result<(), String> {
    runtime_stamp::check_elf_exports(bytes, EXPORT).map_err(|why| {
        format!(
            "{what} {} is no fmu-runtime binary: {why} (a 64-bit ELF shared object exporting {EXPORT} is needed)",
            path.display()
        )
    })
}

/// In a source tree (fmu-runtime/ and fmi2/ beside this crate): the runtime was built from the
/// sources now there. A packaged builder, without them, takes the runtime as it is.
fn check_sources(workspace: &Path, record: &Record, so: &Path) -> Result<(), String> {
    if !(workspace.join("fmu-runtime/src").is_dir() && workspace.join("fmi2/src").is_dir()) {
        return Ok(());
    }
    for input in INPUTS {
        let path = workspace.join(input);
        // a path that does not exist would make cargo rerun this script on every build
        if path.exists() {
            println!("cargo:rerun-if-changed={}", path.display());
        }
    }
    let now = runtime_stamp::hash_inputs(workspace)?;
    if record.sources != now {
        return Err(format!(
            "{} is stale: it was built from other sources than those now in {} ({}), so the builder would embed an \
             outdated FMU binary: rebuild it with `{COMMAND}`",
            so.display(),
            workspace.display(),
            INPUTS.join(", ")
        ));
    }
    Ok(())
}
