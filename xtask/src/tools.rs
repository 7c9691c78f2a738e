//! The portable build's tools fetched where the machine has none, so that the README's first
//! command on a fresh machine links the FMU's runtime against glibc 2.17 by itself: zig from
//! PyPI's `ziglang` wheel, downloaded by the machine's own pip (its index, mirror, proxy and
//! certificates apply) and unpacked by Python's zipfile, and cargo-zigbuild from crates.io by
//! `cargo install`. Both go into `<target>/tools/` (nothing outside the workspace's target
//! folder; `cargo clean` removes them), at the versions tests/requirements.txt and tests/run.sh
//! pin. `FMU_RUNTIME_FETCH=off` leaves them out (an offline machine: the runtime is then linked
//! natively, with the warning that says how to get the tools).

use std::env;
use std::path::{Path, PathBuf};
use std::process::Command;

/// The `ziglang` wheel's version (tests/requirements.txt pins the same).
pub const ZIGLANG: &str = "0.17.1";
/// cargo-zigbuild's version (tests/run.sh installs the same).
pub const CARGO_ZIGBUILD: &str = "0.24.1";

/// Whether the tools may be fetched (`FMU_RUNTIME_FETCH`: `auto`, the default, or `off`).
pub fn fetch_allowed() -> Result<bool, String> {
    match env::var("FMU_RUNTIME_FETCH").unwrap_or_default().trim() {
        "" | "auto" | "1" => Ok(true),
        "off" | "0" => Ok(false),
        other => Err(format!("FMU_RUNTIME_FETCH is {other:?}: expected auto or off")),
    }
}

fn tools_dir(target: &Path) -> PathBuf {
    target.join("tools")
}

/// Where a fetched zig is.
pub fn local_zig(target: &Path) -> PathBuf {
    tools_dir(target).join(format!("ziglang-{ZIGLANG}")).join("ziglang").join(format!("zig{}", env::consts::EXE_SUFFIX))
}

/// Where a fetched cargo-zigbuild is.
pub fn local_cargo_zigbuild(target: &Path) -> PathBuf {
    tools_dir(target).join("bin").join(format!("cargo-zigbuild{}", env::consts::EXE_SUFFIX))
}

/// zig from PyPI into `<target>/tools/ziglang-VERSION/` with `python`'s pip; its path.
pub fn fetch_zig(target: &Path, python: &Path) -> Result<PathBuf, String> {
    let tools = tools_dir(target);
    let dir = tools.join(format!("ziglang-{ZIGLANG}"));
    let (download, partial) = (tools.join("download"), tools.join(format!("ziglang-{ZIGLANG}.part")));
    for d in [&download, &partial] {
        if d.exists() {
            std::fs::remove_dir_all(d).map_err(|e| format!("cannot remove {}: {e}", d.display()))?;
        }
    }
    eprintln!(
        "fetching zig {ZIGLANG} for the portable runtime: PyPI's ziglang wheel (about 100 MB) with {} -m pip, into {}",
        python.display(),
        dir.display()
    );
    let mut pip = Command::new(python);
    pip.args(["-m", "pip", "download", "--no-deps", "--only-binary=:all:", "--disable-pip-version-check"])
        .arg(format!("ziglang=={ZIGLANG}"))
        .arg("--dest")
        .arg(&download);
    run(&mut pip, "pip download ziglang")?;
    let wheel = std::fs::read_dir(&download)
        .map_err(|e| format!("cannot read {}: {e}", download.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .find(|p| p.extension().is_some_and(|x| x == "whl"))
        .ok_or_else(|| format!("pip left no ziglang wheel in {}", download.display()))?;
    // a wheel is a zip; Python's zipfile unpacks it wherever Python runs (no unzip needed)
    let mut unzip = Command::new(python);
    unzip
        .args(["-c", "import sys, zipfile; zipfile.ZipFile(sys.argv[1]).extractall(sys.argv[2])"])
        .arg(&wheel)
        .arg(&partial);
    run(&mut unzip, "unpacking the ziglang wheel")?;
    let zig = partial.join("ziglang").join(format!("zig{}", env::consts::EXE_SUFFIX));
    make_executable(&zig)?;
    // a whole folder or none: a fetch cut short leaves only the .part folder, removed next time
    if dir.exists() {
        std::fs::remove_dir_all(&dir).map_err(|e| format!("cannot remove {}: {e}", dir.display()))?;
    }
    std::fs::rename(&partial, &dir).map_err(|e| format!("cannot rename {}: {e}", partial.display()))?;
    std::fs::remove_dir_all(&download).map_err(|e| format!("cannot remove {}: {e}", download.display()))?;
    Ok(local_zig(target))
}

/// cargo-zigbuild from crates.io into `<target>/tools/bin/`; its path.
pub fn install_cargo_zigbuild(cargo: &Path, target: &Path) -> Result<PathBuf, String> {
    let root = tools_dir(target);
    eprintln!(
        "installing cargo-zigbuild {CARGO_ZIGBUILD} for the portable runtime from crates.io into {} (it compiles: about 3 minutes on 2 cores)",
        root.display()
    );
    let mut install = Command::new(cargo);
    install.args(["install", "--locked", "cargo-zigbuild", "--version", CARGO_ZIGBUILD, "--root"]).arg(&root);
    // the tools' own build must not take the workspace's target folder or flags
    for var in ["CARGO_TARGET_DIR", "RUSTFLAGS", "CARGO_ENCODED_RUSTFLAGS", "CARGO_BUILD_TARGET"] {
        install.env_remove(var);
    }
    // cargo advises adding an install root missing from the PATH to it: xtask calls the tool by
    // its path, so the advice would only mislead
    let bin = root.join("bin");
    let path = env::var_os("PATH").unwrap_or_default();
    if let Ok(joined) = env::join_paths(std::iter::once(bin).chain(env::split_paths(&path))) {
        install.env("PATH", joined);
    }
    run(&mut install, "cargo install cargo-zigbuild")?;
    Ok(local_cargo_zigbuild(target))
}

#[cfg(unix)]
fn make_executable(path: &Path) -> Result<(), String> {
    use std::os::unix::fs::PermissionsExt;
    let mut permissions =
        std::fs::metadata(path).map_err(|e| format!("the wheel has no {}: {e}", path.display()))?.permissions();
    permissions.set_mode(permissions.mode() | 0o755);
    std::fs::set_permissions(path, permissions).map_err(|e| format!("cannot make {} executable: {e}", path.display()))
}

#[cfg(not(unix))]
fn make_executable(path: &Path) -> Result<(), String> {
    if path.is_file() { Ok(()) } else { Err(format!("the wheel has no {}", path.display())) }
}

fn run(cmd: &mut Command, what: &str) -> Result<(), String> {
    let status = cmd.status().map_err(|e| format!("cannot run {what}: {e}"))?;
    if status.success() { Ok(()) } else { Err(format!("{what} failed ({status}); its output is above")) }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The versions fetched are the ones the test set-up installs: one zig, one cargo-zigbuild.
    #[test]
    fn the_pins_match_the_test_set_up() {
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).parent().unwrap();
        let requirements = std::fs::read_to_string(root.join("tests/requirements.txt")).unwrap();
        assert!(requirements.lines().any(|l| l.trim() == format!("ziglang=={ZIGLANG}")), "{requirements}");
        let run_sh = std::fs::read_to_string(root.join("tests/run.sh")).unwrap();
        assert!(run_sh.contains(&format!("cargo-zigbuild --version {CARGO_ZIGBUILD}")), "tests/run.sh");
    }
}
