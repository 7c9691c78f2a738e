//! Builds the runtime cdylib (the FMU's linux64 binary) and hands its path to the builder, which
//! embeds it: `cargo build -p fmu-builder` alone would compile fmu-runtime only as an rlib, and
//! an installed builder must not look for a .so in a source tree. The nested cargo uses its own
//! target directory so it never waits on the outer build's lock.
//!
//! The binary must load on every Linux an FMU's user may have, not only on the build machine:
//! linked against this machine's glibc it asks for the newest symbol versions it uses
//! (`pthread_key_create@GLIBC_2.34` on glibc 2.34+), and RHEL/Rocky 8, Ubuntu 20.04 and
//! Debian 11 refuse to load it. So where zig and cargo-zigbuild are found, the runtime is
//! linked by zig against glibc 2.17's symbol versions (`x86_64-unknown-linux-gnu.2.17`),
//! otherwise natively with a warning. Environment (each change rebuilds the runtime):
//!
//! - `FMU_RUNTIME_SO`: take this prebuilt runtime instead of building one;
//! - `FMU_RUNTIME_PORTABLE`: `auto` (default: portable when the tools are found), `require`
//!   (fail without them: CI), `off` (native);
//! - `FMU_RUNTIME_ZIG`: the zig executable (else `zig` on the PATH, else the `ziglang` package
//!   of tests/.venv's Python or of `python3`);
//! - `FMU_RUNTIME_CARGO_ZIGBUILD`: the cargo-zigbuild executable (else on the PATH or in
//!   `$CARGO_HOME/bin`).
//!
//! The builder's `--version` says which kind of linux64 binary it embeds
//! (`FMU_RUNTIME_LINUX64`) and, for a native one, the newest glibc it needs
//! (`FMU_RUNTIME_NATIVE_GLIBC`, empty for a portable or prebuilt one), so that the builder can
//! warn on every FMU it packages.
//!
//! The tools usually appear after the first build: the README's first command builds the
//! builder, its second (`bash tests/run.sh`) then installs ziglang into tests/.venv and
//! cargo-zigbuild into `$CARGO_HOME/bin`. So this script asks cargo to rerun it when anything it
//! looked at changes: the environment it reads and every path it probed, found or not. Cargo
//! takes a path that does not exist as changed on every build (and would rebuild the builder each
//! time), so a missing path is watched through its nearest existing folder, at most up to a
//! bound set per probe (the PATH folder itself, the Python's site-packages, `$CARGO_HOME/bin`,
//! the repository's tests/): a file appearing there changes that folder. Cargo scans a watched
//! folder recursively; the largest is the Python's site-packages (some 50 000 files, 0.5 s
//! per cargo command measured), watched only while no zig is found.

use std::env;
use std::path::{Path, PathBuf};
use std::process::Command;

/// The oldest glibc the portable binary loads on: Rust's own minimum for
/// x86_64-unknown-linux-gnu (RHEL/CentOS 7); every distribution since carries these versions.
const GLIBC_BASELINE: &str = "2.17";
/// The only host whose runtime is the FMU's linux64 binary.
const LINUX64: &str = "x86_64-unknown-linux-gnu";

fn main() {
    let manifest_dir = PathBuf::from(env::var("CARGO_MANIFEST_DIR").expect("cargo sets CARGO_MANIFEST_DIR"));
    let runtime = manifest_dir.join("../fmu-runtime");
    let out_dir = PathBuf::from(env::var("OUT_DIR").expect("cargo sets OUT_DIR"));
    println!("cargo:rerun-if-changed={}", runtime.join("src").display());
    println!("cargo:rerun-if-changed={}", runtime.join("Cargo.toml").display());
    println!("cargo:rerun-if-changed={}", runtime.join("build.rs").display());
    // the generic FMI layer the runtime links
    let fmi2 = manifest_dir.join("../fmi2");
    println!("cargo:rerun-if-changed={}", fmi2.join("src").display());
    println!("cargo:rerun-if-changed={}", fmi2.join("Cargo.toml").display());
    // what this script reads, and what decides where the Pythons it runs import ziglang from
    for var in [
        "FMU_RUNTIME_SO",
        "FMU_RUNTIME_PORTABLE",
        "FMU_RUNTIME_ZIG",
        "FMU_RUNTIME_CARGO_ZIGBUILD",
        "PATH",
        "CARGO_HOME",
        "HOME",
        "PYTHONPATH",
        "PYTHONHOME",
        "PYTHONUSERBASE",
        "PYTHONNOUSERSITE",
    ] {
        println!("cargo:rerun-if-env-changed={var}");
    }

    let (so, kind) = if let Ok(prebuilt) = env::var("FMU_RUNTIME_SO") {
        (PathBuf::from(prebuilt), "prebuilt, FMU_RUNTIME_SO".to_string())
    } else {
        build_runtime(&manifest_dir, &runtime.join("Cargo.toml"), &out_dir.join("runtime-target"))
    };
    let dest = out_dir.join("fmu_runtime.so");
    let bytes = std::fs::read(&so).unwrap_or_else(|e| panic!("cannot read {}: {e}", so.display()));
    // an unchanged binary keeps its file time: the builder is not recompiled for nothing
    if std::fs::read(&dest).ok().as_deref() != Some(bytes.as_slice()) {
        std::fs::write(&dest, &bytes).unwrap_or_else(|e| panic!("cannot write {}: {e}", dest.display()));
    }
    println!("cargo:rustc-env=FMU_RUNTIME_LINUX64={kind}");
    // a native binary needs the build machine's glibc: name the version, for the builder's warning
    let native_glibc =
        if kind.starts_with("native") { newest_glibc(&bytes).unwrap_or_default() } else { String::new() };
    println!("cargo:rustc-env=FMU_RUNTIME_NATIVE_GLIBC={native_glibc}");
}

/// The newest `GLIBC_x.y[.z]` symbol version named in a shared library (the names of its version
/// needs are plain strings in its dynamic string table), e.g. "2.34".
fn newest_glibc(so: &[u8]) -> Option<String> {
    const TAG: &[u8] = b"GLIBC_";
    let mut newest: Option<Vec<u32>> = None;
    let mut i = 0;
    while let Some(pos) = so[i..].windows(TAG.len()).position(|w| w == TAG) {
        let start = i + pos + TAG.len();
        let end = start + so[start..].iter().take_while(|b| b.is_ascii_digit() || **b == b'.').count();
        let parts: Option<Vec<u32>> =
            std::str::from_utf8(&so[start..end]).ok().and_then(|v| v.split('.').map(|p| p.parse().ok()).collect());
        if let Some(parts) = parts.filter(|p| p.len() >= 2)
            && newest.as_ref().is_none_or(|n| parts > *n)
        {
            newest = Some(parts);
        }
        i = end.max(start);
    }
    newest.map(|v| v.iter().map(u32::to_string).collect::<Vec<_>>().join("."))
}

/// Ask cargo to rerun this script when `path` changes, or, while it does not exist, when it may
/// have appeared: its nearest existing folder not above `bound` is watched instead (a missing
/// path itself would make every build rerun the script and rebuild the builder). Nothing where
/// even `bound` does not exist.
fn watch(path: &Path, bound: &Path) {
    let mut p = path;
    loop {
        if p.exists() {
            println!("cargo:rerun-if-changed={}", p.display());
            return;
        }
        if p == bound {
            return;
        }
        match p.parent() {
            Some(parent) if parent.starts_with(bound) => p = parent,
            _ => return,
        }
    }
}

#[derive(Clone, Copy, PartialEq)]
enum Portable {
    Auto,
    Require,
    Off,
}

fn portable_mode() -> Portable {
    match env::var("FMU_RUNTIME_PORTABLE").unwrap_or_default().trim() {
        "" | "auto" => Portable::Auto,
        "require" | "1" => Portable::Require,
        "off" | "0" => Portable::Off,
        other => panic!("FMU_RUNTIME_PORTABLE is {other:?}: expected auto, require or off"),
    }
}

/// The runtime built portable where possible; its path and what kind it is.
fn build_runtime(manifest_dir: &Path, manifest: &Path, target_dir: &Path) -> (PathBuf, String) {
    let mode = portable_mode();
    let host = env::var("HOST").unwrap_or_default();
    let why_native = if mode == Portable::Off {
        "FMU_RUNTIME_PORTABLE=off".to_string()
    } else if host != LINUX64 {
        format!("the portable build is made on {LINUX64} hosts only, this is {host}")
    } else {
        match zig_toolchain(manifest_dir) {
            Ok(tools) => match build_portable(&tools, manifest, target_dir) {
                Ok(so) => {
                    let kind =
                        format!("portable, glibc {GLIBC_BASELINE} or newer, linked by zig {}", tools.zig_version);
                    return (so, kind);
                }
                Err(e) => format!("the portable build with zig failed: {e}"),
            },
            Err(e) => e,
        }
    };
    if mode == Portable::Require {
        panic!("FMU_RUNTIME_PORTABLE=require, but the runtime cannot be built portable: {why_native}");
    }
    if mode == Portable::Auto {
        println!(
            "cargo:warning=fmu-runtime is linked natively, so the FMUs' linux64 binary needs this machine's glibc or newer ({why_native}). \
             For one that loads on glibc {GLIBC_BASELINE}+ (RHEL/Rocky 8, Ubuntu 20.04, Debian 11): pip install ziglang (or zig on the PATH) and \
             cargo install --locked cargo-zigbuild (bash tests/run.sh --setup-only sets up both), then build again: the build notices them"
        );
    }
    (build_native(manifest, target_dir), "native, glibc of the build machine or newer".to_string())
}

/// The nested cargo's command, without the flags meant for the outer build.
fn nested(program: &Path) -> Command {
    let mut cmd = Command::new(program);
    // flags meant for the outer build (coverage, sanitizers, a cross target) must not leak into
    // the FMU binary
    for var in
        ["RUSTFLAGS", "CARGO_ENCODED_RUSTFLAGS", "CARGO_BUILD_TARGET", "CARGO_TARGET_DIR", "CARGO_BUILD_RUSTFLAGS"]
    {
        cmd.env_remove(var);
    }
    // `cargo clippy` runs the workspace through clippy-driver: the FMU binary is compiled by
    // rustc, and linted where the runtime crate itself is linted
    cmd.env_remove("RUSTC_WORKSPACE_WRAPPER").env_remove("CLIPPY_ARGS");
    cmd
}

fn build_native(manifest: &Path, target_dir: &Path) -> PathBuf {
    let cargo = PathBuf::from(env::var("CARGO").unwrap_or_else(|_| "cargo".into()));
    let status = nested(&cargo)
        .args(["build", "--release", "--lib", "--manifest-path"])
        .arg(manifest)
        .arg("--target-dir")
        .arg(target_dir)
        .status()
        .expect("cannot run cargo to build fmu-runtime");
    if !status.success() {
        panic!("building the fmu-runtime cdylib failed");
    }
    target_dir.join("release/libfmu_runtime.so")
}

struct ZigToolchain {
    zig: PathBuf,
    zig_version: String,
    cargo_zigbuild: PathBuf,
}

fn build_portable(tools: &ZigToolchain, manifest: &Path, target_dir: &Path) -> Result<PathBuf, String> {
    let target = format!("{LINUX64}.{GLIBC_BASELINE}");
    let output = nested(&tools.cargo_zigbuild)
        .args(["zigbuild", "--release", "--lib", "--target", &target, "--manifest-path"])
        .arg(manifest)
        .arg("--target-dir")
        .arg(target_dir)
        .env("CARGO_ZIGBUILD_ZIG_PATH", &tools.zig)
        // cargo-zigbuild's linker wrappers go with the build, not into the user's cache
        .env("CARGO_ZIGBUILD_CACHE_DIR", target_dir.join("cargo-zigbuild"))
        .output()
        .map_err(|e| format!("cannot run {}: {e}", tools.cargo_zigbuild.display()))?;
    if !output.status.success() {
        let stderr = String::from_utf8_lossy(&output.stderr);
        let tail: Vec<&str> = stderr.lines().rev().take(15).collect();
        return Err(tail.into_iter().rev().collect::<Vec<_>>().join("\n"));
    }
    Ok(target_dir.join(LINUX64).join("release/libfmu_runtime.so"))
}

/// zig and cargo-zigbuild, or why they were not found (everything that was tried).
fn zig_toolchain(manifest_dir: &Path) -> Result<ZigToolchain, String> {
    let (zig, zig_version) = find_zig(manifest_dir)?;
    let cargo_zigbuild = find_cargo_zigbuild()?;
    Ok(ZigToolchain { zig, zig_version, cargo_zigbuild })
}

fn find_zig(manifest_dir: &Path) -> Result<(PathBuf, String), String> {
    if let Some(zig) = env::var_os("FMU_RUNTIME_ZIG") {
        let zig = PathBuf::from(zig);
        watch(&zig, zig.parent().unwrap_or(&zig));
        let version =
            zig_version(&zig).ok_or_else(|| format!("FMU_RUNTIME_ZIG={}: `zig version` fails", zig.display()))?;
        return Ok((zig, version));
    }
    let mut tried = Vec::new();
    if let Some(zig) = on_path("zig") {
        if let Some(version) = zig_version(&zig) {
            return Ok((zig, version));
        }
        tried.push(format!("{} (`zig version` fails)", zig.display()));
    } else {
        tried.push("zig on the PATH".to_string());
    }
    // the virtual environment tests/run.sh creates, then the Python on the PATH
    let tests = manifest_dir.join("../tests");
    let venv = tests.join(".venv/bin/python");
    // the repository's tests/ bounds the watch: before run.sh, tests/ gains .venv
    watch(&venv, &tests);
    let venv = Some(venv).filter(|p| p.is_file());
    // the Python on the PATH only where the virtual environment has no zig: probed lazily
    for python in venv.into_iter().map(Some).chain(std::iter::once_with(|| on_path("python3"))).flatten() {
        match ziglang_zig(&python) {
            Some(zig) => {
                if let Some(version) = zig_version(&zig) {
                    return Ok((zig, version));
                }
                tried.push(format!("{} (`zig version` fails)", zig.display()));
            }
            None => tried.push(format!("the ziglang package of {}", python.display())),
        }
    }
    Err(format!("no zig found (tried {})", tried.join(", ")))
}

/// Where `python` installs packages (lines "install DIR") and its `ziglang` package if it has
/// one ("found DIR").
const ZIGLANG_PROBE: &str = "\
import os, site, sysconfig
paths = sysconfig.get_paths()
dirs = {paths['purelib'], paths['platlib']}
if site.ENABLE_USER_SITE:
    dirs.add(site.getusersitepackages())
for d in sorted(dirs):
    print('install', d)
try:
    import ziglang
except ImportError:
    pass
else:
    print('found', os.path.dirname(ziglang.__file__))
";

/// The zig executable inside the `ziglang` package of `python`, if it has one. Watches it, or,
/// without one, the folders pip would install it into.
fn ziglang_zig(python: &Path) -> Option<PathBuf> {
    watch(python, python.parent().unwrap_or(python));
    let output = Command::new(python).args(["-c", ZIGLANG_PROBE]).output().ok().filter(|o| o.status.success())?;
    let stdout = String::from_utf8(output.stdout).ok()?;
    let zig_name = format!("zig{}", env::consts::EXE_SUFFIX);
    let mut zig = None;
    for line in stdout.lines() {
        if let Some(dir) = line.strip_prefix("found ") {
            let dir = PathBuf::from(dir);
            let z = dir.join(&zig_name);
            watch(&z, dir.parent().unwrap_or(&dir));
            zig = Some(z).filter(|z| z.is_file());
        }
    }
    if zig.is_none() {
        for line in stdout.lines() {
            if let Some(dir) = line.strip_prefix("install ") {
                let dir = Path::new(dir);
                watch(&dir.join("ziglang").join(&zig_name), dir);
            }
        }
    }
    zig
}

fn zig_version(zig: &Path) -> Option<String> {
    let output = Command::new(zig).arg("version").output().ok().filter(|o| o.status.success())?;
    Some(String::from_utf8_lossy(&output.stdout).trim().to_string())
}

fn find_cargo_zigbuild() -> Result<PathBuf, String> {
    if let Some(path) = env::var_os("FMU_RUNTIME_CARGO_ZIGBUILD") {
        let path = PathBuf::from(path);
        watch(&path, path.parent().unwrap_or(&path));
        return if path.is_file() {
            Ok(path)
        } else {
            Err(format!("FMU_RUNTIME_CARGO_ZIGBUILD={}: no such file", path.display()))
        };
    }
    let name = format!("cargo-zigbuild{}", env::consts::EXE_SUFFIX);
    // where `cargo install` puts it, as cargo itself finds subcommands
    let cargo_home = env::var_os("CARGO_HOME")
        .map(PathBuf::from)
        .or_else(|| env::var_os("HOME").map(|h| Path::new(&h).join(".cargo")));
    on_path(&name)
        .or_else(|| {
            let bin = cargo_home?.join("bin");
            let path = bin.join(&name);
            // `cargo install` adds the file to $CARGO_HOME/bin
            watch(&path, &bin);
            Some(path).filter(|p| p.is_file())
        })
        .ok_or_else(|| "no cargo-zigbuild found on the PATH or in $CARGO_HOME/bin".to_string())
}

/// The first `name` in the PATH's folders. Watches each folder looked into (a folder the PATH
/// names but that does not exist is not: its nearest existing folder may be the home folder,
/// which cargo would scan whole).
fn on_path(name: &str) -> Option<PathBuf> {
    let path = env::var_os("PATH")?;
    env::split_paths(&path).map(|dir| (dir.join(name), dir)).find_map(|(p, dir)| {
        watch(&p, &dir);
        Some(p).filter(|p| p.is_file())
    })
}
