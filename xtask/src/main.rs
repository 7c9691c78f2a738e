//! The workspace's tasks, run as `cargo xtask ...` (an alias in .cargo/config.toml). The FMU's
//! linux64 binary is the fmu-runtime cdylib, which fmu-builder embeds; this builds it once, in the
//! workspace's own target folder, and places it where fmu-builder/build.rs takes it from
//! (`<target>/fmu-runtime/libfmu_runtime.so`, with `runtime.info` beside it:
//! fmu-builder/build/runtime_stamp.rs). See `usage()` for the commands.
//!
//! The binary must load on every Linux an FMU's user may have, not only on the build machine:
//! linked against this machine's glibc it asks for the newest symbol versions it uses
//! (`pthread_key_create@GLIBC_2.34` on glibc 2.34+), and RHEL/Rocky 8, Ubuntu 20.04 and Debian 11
//! refuse to load it. So where zig and cargo-zigbuild are found, the runtime is linked by zig
//! against glibc 2.17's symbol versions (`cargo zigbuild --target x86_64-unknown-linux-gnu.2.17`),
//! otherwise natively with a warning. Environment:
//!
//! - `FMU_RUNTIME_PORTABLE`: `auto` (default: portable when the tools are found), `require` (fail
//!   without them: CI), `off` (native);
//! - `FMU_RUNTIME_ZIG`: the zig executable (else `zig` on the PATH, else the `ziglang` package of
//!   tests/.venv's Python or of `python3`);
//! - `FMU_RUNTIME_CARGO_ZIGBUILD`: the cargo-zigbuild executable (else on the PATH or in
//!   `$CARGO_HOME/bin`);
//! - `FMU_RUNTIME_FETCH`: `auto` (default: tools not found are fetched into `<target>/tools/`,
//!   zig from PyPI with the machine's pip and cargo-zigbuild from crates.io, see `tools.rs`) or
//!   `off`.
//!
//! The tools are looked for on every run: the README's first command on a fresh machine fetches
//! them, and one set up later (`bash tests/run.sh --setup-only`) is found the same way.

use std::env;
use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode};

#[path = "../../fmu-builder/build/runtime_stamp.rs"]
mod runtime_stamp;
mod tools;

use runtime_stamp::Record;

/// The oldest glibc the portable binary loads on: Rust's own minimum for
/// x86_64-unknown-linux-gnu (RHEL/CentOS 7); every distribution since carries these versions.
const GLIBC_BASELINE: &str = "2.17";
/// The only host whose runtime is the FMU's linux64 binary.
const LINUX64: &str = "x86_64-unknown-linux-gnu";
const IS_LINUX64: bool = cfg!(all(target_arch = "x86_64", target_os = "linux", target_env = "gnu"));
/// The profile of the runtime the builder embeds: the FMU's binary is always the optimised one.
const DEFAULT_PROFILE: &str = "release";

fn usage() -> &'static str {
    "cargo xtask <command>

  runtime [--release | --profile P]   build the FMU's linux64 runtime (the fmu-runtime cdylib) once,
                                      portable (zig, glibc 2.17) where zig and cargo-zigbuild are found,
                                      into <target>/fmu-runtime/, where fmu-builder's build takes it from
                                      (profile: release unless --profile says otherwise)
  build                               runtime, then `cargo build --release -p fmu-builder`
  run [--] ARGS                       build, then run target/release/fmu-builder ARGS

Environment: FMU_RUNTIME_PORTABLE=auto|require|off, FMU_RUNTIME_ZIG, FMU_RUNTIME_CARGO_ZIGBUILD,
FMU_RUNTIME_FETCH=auto|off (docs/PLATFORMS.md)."
}

fn main() -> ExitCode {
    let args: Vec<OsString> = env::args_os().skip(1).collect();
    match run(&args) {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

fn run(args: &[OsString]) -> Result<ExitCode, String> {
    let ws = Workspace::find()?;
    let command = args.first().and_then(|a| a.to_str()).unwrap_or_default();
    let rest = args.get(1..).unwrap_or_default();
    match command {
        "runtime" => {
            let profile = runtime_profile(rest)?;
            ws.runtime(&profile)?;
        }
        "build" => {
            if let Some(extra) = rest.first() {
                return Err(format!("`cargo xtask build` takes no arguments, got {extra:?}\n\n{}", usage()));
            }
            ws.build()?;
        }
        "run" => {
            ws.build()?;
            let args = if rest.first().is_some_and(|a| a == "--") { &rest[1..] } else { rest };
            let builder = ws.target.join("release").join(format!("fmu-builder{}", env::consts::EXE_SUFFIX));
            let status = Command::new(&builder)
                .args(args)
                .status()
                .map_err(|e| format!("cannot run {}: {e}", builder.display()))?;
            return Ok(status.code().and_then(|c| u8::try_from(c).ok()).map_or(ExitCode::FAILURE, ExitCode::from));
        }
        "help" | "-h" | "--help" => println!("{}", usage()),
        "" => return Err(format!("no command given\n\n{}", usage())),
        other => return Err(format!("unknown command {other:?}\n\n{}", usage())),
    }
    Ok(ExitCode::SUCCESS)
}

/// The cargo profile `runtime`'s options ask for.
fn runtime_profile(args: &[OsString]) -> Result<String, String> {
    let mut profile = DEFAULT_PROFILE.to_string();
    let mut args = args.iter().map(|a| a.to_string_lossy().into_owned());
    while let Some(arg) = args.next() {
        match arg.as_str() {
            "--release" => profile = "release".to_string(),
            "--profile" => profile = args.next().ok_or("--profile needs a profile name")?,
            _ => match arg.strip_prefix("--profile=") {
                Some(p) => profile = p.to_string(),
                None => return Err(format!("unknown option {arg:?} of `cargo xtask runtime`\n\n{}", usage())),
            },
        }
    }
    Ok(profile)
}

/// The workspace root and its target folder, as cargo sees them (`CARGO_TARGET_DIR` and
/// `build.target-dir` included).
struct Workspace {
    root: PathBuf,
    target: PathBuf,
    cargo: PathBuf,
}

impl Workspace {
    fn find() -> Result<Self, String> {
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).parent().ok_or("xtask has no parent folder")?.to_path_buf();
        let cargo = env::var_os("CARGO").map_or_else(|| PathBuf::from("cargo"), PathBuf::from);
        let output = Command::new(&cargo)
            .args(["metadata", "--format-version", "1", "--no-deps"])
            .current_dir(&root)
            .output()
            .map_err(|e| format!("cannot run {} metadata: {e}", cargo.display()))?;
        if !output.status.success() {
            return Err(format!("cargo metadata failed: {}", String::from_utf8_lossy(&output.stderr).trim()));
        }
        let json = String::from_utf8_lossy(&output.stdout);
        let target = json_string(&json, "target_directory").ok_or("cargo metadata names no target_directory")?;
        Ok(Self { root, target: PathBuf::from(target), cargo })
    }

    /// A cargo command run in the workspace root.
    fn cargo(&self) -> Command {
        let mut cmd = Command::new(&self.cargo);
        cmd.current_dir(&self.root);
        cmd
    }

    /// The runtime, then the release builder, which embeds it.
    fn build(&self) -> Result<(), String> {
        self.runtime(DEFAULT_PROFILE)?;
        let mut cmd = self.cargo();
        cmd.args(["build", "--release", "-p", "fmu-builder"]);
        if env::var_os("FMU_RUNTIME_SO").is_some() {
            eprintln!("note: FMU_RUNTIME_SO is ignored: `cargo xtask build` embeds the runtime it has just built");
            cmd.env_remove("FMU_RUNTIME_SO");
        }
        run_status(&mut cmd, "cargo build --release -p fmu-builder")
    }

    /// Builds the runtime, portable where possible, and places it with its record where
    /// fmu-builder/build.rs looks.
    fn runtime(&self, profile: &str) -> Result<(), String> {
        // before the build: a source changed during it makes the record stale, never wrongly current
        let sources = runtime_stamp::hash_inputs(&self.root)?;
        let mode = portable_mode()?;
        let why_native = if mode == Portable::Off {
            "FMU_RUNTIME_PORTABLE=off".to_string()
        } else if !IS_LINUX64 {
            format!(
                "the portable build is made on {LINUX64} hosts only, this is {}-{}",
                env::consts::ARCH,
                env::consts::OS
            )
        } else {
            match self.toolchain() {
                Ok(tools) => match self.build_portable(&tools, profile) {
                    Ok(so) => {
                        let kind =
                            format!("portable, glibc {GLIBC_BASELINE} or newer, linked by zig {}", tools.zig_version);
                        return self.place(&so, kind, profile, sources);
                    }
                    Err(e) => format!("the portable build with zig failed: {e}"),
                },
                Err(e) => e,
            }
        };
        if mode == Portable::Require {
            return Err(format!(
                "FMU_RUNTIME_PORTABLE=require, but the runtime cannot be built portable: {why_native}"
            ));
        }
        if mode == Portable::Auto {
            eprintln!(
                "warning: fmu-runtime is linked natively, so the FMUs' linux64 binary needs this machine's glibc or newer ({why_native}). \
                 For one that loads on glibc {GLIBC_BASELINE}+ (RHEL/Rocky 8, Ubuntu 20.04, Debian 11): let `cargo xtask runtime` fetch zig and \
                 cargo-zigbuild (FMU_RUNTIME_FETCH=auto, with pip and network), or install them (pip install ziglang=={}, \
                 cargo install --locked cargo-zigbuild --version {}; bash tests/run.sh --setup-only sets up both), then run `cargo xtask runtime` \
                 (or `cargo xtask build`) again: it finds them",
                tools::ZIGLANG,
                tools::CARGO_ZIGBUILD
            );
        }
        let so = self.build_native(profile)?;
        self.place(&so, "native, glibc of the build machine or newer".to_string(), profile, sources)
    }

    /// zig and cargo-zigbuild as found, else fetched into `<target>/tools/` ([`tools`]) unless
    /// FMU_RUNTIME_FETCH=off; or why not (everything that was tried).
    fn toolchain(&self) -> Result<ZigToolchain, String> {
        let found = (find_zig(&self.root, &self.target), find_cargo_zigbuild(&self.target));
        if let (Ok((zig, zig_version)), Ok(cargo_zigbuild)) = found {
            return Ok(ZigToolchain { zig, zig_version, cargo_zigbuild });
        }
        let missing =
            [found.0.as_ref().err(), found.1.as_ref().err()].into_iter().flatten().cloned().collect::<Vec<_>>();
        if !tools::fetch_allowed()? {
            return Err(format!("{} (FMU_RUNTIME_FETCH=off: not fetched)", missing.join("; ")));
        }
        // a tool the environment names is the one wanted: its failure is said, not worked around
        let named = (found.0.is_err() && env::var_os("FMU_RUNTIME_ZIG").is_some())
            || (found.1.is_err() && env::var_os("FMU_RUNTIME_CARGO_ZIGBUILD").is_some());
        if named {
            return Err(missing.join("; "));
        }
        let fetched = (|| {
            let (zig, zig_version) = match found.0 {
                Ok(z) => z,
                Err(_) => {
                    let python = self.python().ok_or("no python3 on the PATH to fetch zig with")?;
                    let zig = tools::fetch_zig(&self.target, &python)?;
                    let version = zig_version(&zig).ok_or_else(|| format!("{}: `zig version` fails", zig.display()))?;
                    (zig, version)
                }
            };
            let cargo_zigbuild = match found.1 {
                Ok(c) => c,
                Err(_) => tools::install_cargo_zigbuild(&self.cargo, &self.target)?,
            };
            Ok::<_, String>(ZigToolchain { zig, zig_version, cargo_zigbuild })
        })();
        fetched.map_err(|e| format!("{}; fetching them failed: {e}", missing.join("; ")))
    }

    /// The Python whose pip fetches zig: tests/.venv's, else python3 on the PATH.
    fn python(&self) -> Option<PathBuf> {
        Some(self.root.join("tests/.venv/bin/python")).filter(|p| p.is_file()).or_else(|| on_path("python3"))
    }

    /// A cargo command building the runtime's library: the FMU binary is built the same whatever
    /// the environment sets for the workspace's other builds (coverage, sanitizers, a CPU or
    /// cross target must not reach it).
    fn runtime_command(&self, program: &Path, subcommand: &str, profile: &str) -> Command {
        let mut cmd = Command::new(program);
        cmd.current_dir(&self.root).args([subcommand, "--profile", profile, "-p", "fmu-runtime", "--lib"]);
        for var in ["RUSTFLAGS", "CARGO_ENCODED_RUSTFLAGS", "CARGO_BUILD_RUSTFLAGS", "CARGO_BUILD_TARGET"] {
            cmd.env_remove(var);
        }
        cmd
    }

    fn build_native(&self, profile: &str) -> Result<PathBuf, String> {
        run_status(&mut self.runtime_command(&self.cargo, "build", profile), "cargo build -p fmu-runtime")?;
        let name = format!("{}fmu_runtime{}", env::consts::DLL_PREFIX, env::consts::DLL_SUFFIX);
        Ok(self.target.join(profile_dir(profile)).join(name))
    }

    fn build_portable(&self, tools: &ZigToolchain, profile: &str) -> Result<PathBuf, String> {
        let target = format!("{LINUX64}.{GLIBC_BASELINE}");
        let mut cmd = self.runtime_command(&tools.cargo_zigbuild, "zigbuild", profile);
        cmd.args(["--target", &target])
            .env("CARGO_ZIGBUILD_ZIG_PATH", &tools.zig)
            // cargo-zigbuild's linker wrappers go with the build, not into the user's cache
            .env("CARGO_ZIGBUILD_CACHE_DIR", self.target.join("cargo-zigbuild"));
        run_status(&mut cmd, &format!("{} zigbuild", tools.cargo_zigbuild.display()))?;
        Ok(self.target.join(LINUX64).join(profile_dir(profile)).join("libfmu_runtime.so"))
    }

    /// Copies the built runtime to `<target>/fmu-runtime/` with its record. A file that would not
    /// change is not written (its time stays, and the builder is not recompiled for nothing); the
    /// record goes first when the binary changes, so that no old record ever describes a new
    /// binary.
    fn place(&self, so: &Path, kind: String, profile: &str, sources: String) -> Result<(), String> {
        let bytes = std::fs::read(so).map_err(|e| format!("cannot read the built runtime {}: {e}", so.display()))?;
        runtime_stamp::check_elf_exports(&bytes, "fmi2Instantiate")
            .map_err(|why| format!("the built runtime {} is not what it should be: {why}", so.display()))?;
        let native_glibc = if kind.starts_with("native") {
            runtime_stamp::newest_glibc(&bytes).unwrap_or_default()
        } else {
            String::new()
        };
        let record = Record {
            kind,
            native_glibc,
            profile: profile.to_string(),
            sources,
            binary: runtime_stamp::hash_bytes(&bytes),
        };
        let dir = self.target.join(runtime_stamp::DIR);
        std::fs::create_dir_all(&dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
        let (dest, info) = (dir.join(runtime_stamp::SO), dir.join(runtime_stamp::INFO));
        if std::fs::read(&dest).ok().as_deref() != Some(bytes.as_slice()) {
            if info.exists() {
                std::fs::remove_file(&info).map_err(|e| format!("cannot remove {}: {e}", info.display()))?;
            }
            write_atomically(&dest, &bytes)?;
        }
        let text = record.to_text();
        if std::fs::read_to_string(&info).ok().as_deref() != Some(text.as_str()) {
            write_atomically(&info, text.as_bytes())?;
        }
        eprintln!("fmu-runtime ({}, profile {profile}): {}", record.kind, dest.display());
        Ok(())
    }
}

/// `path` written through a temporary file beside it: a reader sees the old file or the new one.
fn write_atomically(path: &Path, bytes: &[u8]) -> Result<(), String> {
    let tmp = path.with_extension("tmp");
    std::fs::write(&tmp, bytes).map_err(|e| format!("cannot write {}: {e}", tmp.display()))?;
    std::fs::rename(&tmp, path).map_err(|e| format!("cannot rename {} to {}: {e}", tmp.display(), path.display()))
}

/// The folder of the target directory a cargo profile writes to.
fn profile_dir(profile: &str) -> &str {
    match profile {
        "dev" | "test" => "debug",
        "bench" => "release",
        other => other,
    }
}

fn run_status(cmd: &mut Command, what: &str) -> Result<(), String> {
    let status = cmd.status().map_err(|e| format!("cannot run {what}: {e}"))?;
    if status.success() { Ok(()) } else { Err(format!("{what} failed ({status}); its output is above")) }
}

/// The string value of the first `"key":"..."` in cargo's JSON.
fn json_string(json: &str, key: &str) -> Option<String> {
    let start = json.find(&format!("\"{key}\":\""))? + key.len() + 4;
    let mut out = String::new();
    let mut chars = json[start..].chars();
    loop {
        match chars.next()? {
            '"' => return Some(out),
            '\\' => match chars.next()? {
                'n' => out.push('\n'),
                't' => out.push('\t'),
                'u' => {
                    let hex: String = chars.by_ref().take(4).collect();
                    out.push(char::from_u32(u32::from_str_radix(&hex, 16).ok()?)?);
                }
                c => out.push(c),
            },
            c => out.push(c),
        }
    }
}

#[derive(Clone, Copy, PartialEq, Debug)]
enum Portable {
    Auto,
    Require,
    Off,
}

fn portable_mode() -> Result<Portable, String> {
    match env::var("FMU_RUNTIME_PORTABLE").unwrap_or_default().trim() {
        "" | "auto" => Ok(Portable::Auto),
        "require" | "1" => Ok(Portable::Require),
        "off" | "0" => Ok(Portable::Off),
        other => Err(format!("FMU_RUNTIME_PORTABLE is {other:?}: expected auto, require or off")),
    }
}

struct ZigToolchain {
    zig: PathBuf,
    zig_version: String,
    cargo_zigbuild: PathBuf,
}

/// zig, or why none was found (everything that was tried): FMU_RUNTIME_ZIG, the PATH, the
/// ziglang package of tests/.venv's Python or of python3, one fetched into `<target>/tools/`.
fn find_zig(root: &Path, target: &Path) -> Result<(PathBuf, String), String> {
    if let Some(zig) = env::var_os("FMU_RUNTIME_ZIG") {
        let zig = PathBuf::from(zig);
        let version =
            zig_version(&zig).ok_or_else(|| format!("FMU_RUNTIME_ZIG={}: `zig version` fails", zig.display()))?;
        return Ok((zig, version));
    }
    let mut tried = Vec::new();
    let zig_name = format!("zig{}", env::consts::EXE_SUFFIX);
    match on_path(&zig_name) {
        Some(zig) => match zig_version(&zig) {
            Some(version) => return Ok((zig, version)),
            None => tried.push(format!("{} (`zig version` fails)", zig.display())),
        },
        None => tried.push("zig on the PATH".to_string()),
    }
    // the virtual environment tests/run.sh creates, then the Python on the PATH
    let venv = Some(root.join("tests/.venv/bin/python")).filter(|p| p.is_file());
    for python in venv.into_iter().chain(on_path("python3")) {
        match ziglang_zig(&python, &zig_name) {
            Some(zig) => match zig_version(&zig) {
                Some(version) => return Ok((zig, version)),
                None => tried.push(format!("{} (`zig version` fails)", zig.display())),
            },
            None => tried.push(format!("the ziglang package of {}", python.display())),
        }
    }
    let fetched = tools::local_zig(target);
    if let Some(version) = zig_version(&fetched) {
        return Ok((fetched, version));
    }
    tried.push(fetched.display().to_string());
    Err(format!("no zig found (tried {})", tried.join(", ")))
}

/// The zig executable inside the `ziglang` package of `python`, if it has one.
fn ziglang_zig(python: &Path, zig_name: &str) -> Option<PathBuf> {
    let output = Command::new(python)
        .args(["-c", "import os, ziglang; print(os.path.dirname(ziglang.__file__))"])
        .output()
        .ok()
        .filter(|o| o.status.success())?;
    let dir = String::from_utf8(output.stdout).ok()?;
    Some(Path::new(dir.trim()).join(zig_name)).filter(|z| z.is_file())
}

fn zig_version(zig: &Path) -> Option<String> {
    let output = Command::new(zig).arg("version").output().ok().filter(|o| o.status.success())?;
    Some(String::from_utf8_lossy(&output.stdout).trim().to_string())
}

fn find_cargo_zigbuild(target: &Path) -> Result<PathBuf, String> {
    if let Some(path) = env::var_os("FMU_RUNTIME_CARGO_ZIGBUILD") {
        let path = PathBuf::from(path);
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
    let fetched = tools::local_cargo_zigbuild(target);
    on_path(&name)
        .or_else(|| Some(cargo_home?.join("bin").join(&name)).filter(|p| p.is_file()))
        .or_else(|| Some(fetched.clone()).filter(|p| p.is_file()))
        .ok_or_else(|| format!("no cargo-zigbuild found on the PATH, in $CARGO_HOME/bin or at {}", fetched.display()))
}

/// The first `name` in the PATH's folders.
fn on_path(name: &str) -> Option<PathBuf> {
    let path = env::var_os("PATH")?;
    env::split_paths(&path).map(|dir| dir.join(name)).find(|p| p.is_file())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn json_strings_are_read_with_their_escapes() {
        let json = r#"{"packages":[],"target_directory":"/a \"b\"\\c\u00e9","version":1}"#;
        assert_eq!(json_string(json, "target_directory").as_deref(), Some("/a \"b\"\\cé"));
        assert_eq!(json_string(json, "workspace_root"), None);
    }

    #[test]
    fn the_record_reads_back_what_it_wrote() {
        let record = Record {
            kind: "native, glibc of the build machine or newer".to_string(),
            native_glibc: "2.34".to_string(),
            profile: "release".to_string(),
            sources: "fnv1a64:0123456789abcdef".to_string(),
            binary: runtime_stamp::hash_bytes(b"x"),
        };
        assert_eq!(Record::parse(&record.to_text()), Ok(record));
        assert!(Record::parse("kind=x\n").unwrap_err().contains("native_glibc"));
    }

    #[test]
    fn the_source_hash_follows_the_runtimes_inputs() {
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).parent().unwrap();
        let files: Vec<String> = runtime_stamp::input_files(root).unwrap().into_iter().map(|(n, _)| n).collect();
        for expected in ["Cargo.lock", "fmi2/src/lib.rs", "fmu-runtime/src/lib.rs", "fmu-runtime/build.rs"] {
            assert!(files.iter().any(|f| f == expected), "{expected} missing from {files:?}");
        }
        assert!(!files.iter().any(|f| f.starts_with("fmu-builder/")), "{files:?}");
        assert_eq!(runtime_stamp::hash_inputs(root).unwrap(), runtime_stamp::hash_inputs(root).unwrap());
    }

    #[test]
    fn glibc_versions_and_elf_exports_are_read_from_the_bytes() {
        assert_eq!(runtime_stamp::newest_glibc(b"GLIBC_2.2.5\0GLIBC_2.34\0GLIBC_2.17\0").as_deref(), Some("2.34"));
        assert_eq!(runtime_stamp::newest_glibc(b"no versions"), None);
        assert_eq!(runtime_stamp::check_elf_exports(b"MZ....", "f").unwrap_err(), "it is not an ELF file");
        // this test binary is an ELF (a position-independent executable is of type ET_DYN too)
        // that exports no fmi2 function
        let me = std::fs::read(env::current_exe().unwrap()).unwrap();
        if IS_LINUX64 {
            let e = runtime_stamp::check_elf_exports(&me, "fmi2Instantiate").unwrap_err();
            assert!(e.contains("does not export fmi2Instantiate") || e.contains("shared object"), "{e}");
        }
    }

    #[test]
    fn profiles_map_to_their_folders() {
        assert_eq!(profile_dir("release"), "release");
        assert_eq!(profile_dir("dev"), "debug");
        assert_eq!(profile_dir("fast"), "fast");
        assert_eq!(runtime_profile(&[]).unwrap(), "release");
        assert_eq!(runtime_profile(&["--profile".into(), "dev".into()]).unwrap(), "dev");
        assert!(runtime_profile(&["--debug".into()]).is_err());
    }
}
